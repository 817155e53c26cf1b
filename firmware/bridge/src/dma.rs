//! The capture's DMA channels, register by register (RP2350 datasheet,
//! 12.6): each moves its edge counter's words from the counter's RX FIFO
//! into a ring ([`crate::ring`]), for ever. [`Rings`] programs them, tells
//! the CPU where each writes next, reads the rings, and re-arms a channel
//! that stopped.
//!
//! The same code runs on the RP2350 (the image's `hw.rs` reads and writes
//! the DMA block's registers) and on the board twin (`twin::pio::Dma`, a
//! model of the same registers), through [`DmaRegs`].

use crate::hal::Counter;
use crate::pioregs;
use crate::ring::{Lapped, Reader, CANARY, RING_BITS, RING_WORDS};

/// Offsets in the DMA block (12.6.10).
pub mod reg {
    /// Channel `n`'s registers start at `n * CH_STRIDE`.
    pub const CH_STRIDE: usize = 0x40;
    /// Alias 0: the address the channel reads next.
    pub const READ_ADDR: usize = 0x00;
    /// Alias 0: the address the channel writes next (live).
    pub const WRITE_ADDR: usize = 0x04;
    /// Alias 0: read, the transfers left; written, the count the next
    /// trigger loads (and, bits 31:28, the mode).
    pub const TRANS_COUNT: usize = 0x08;
    /// Alias 0's trigger register: CTRL, and a trigger.
    pub const CTRL_TRIG: usize = 0x0c;
    /// Alias 1: CTRL, without a trigger.
    pub const AL1_CTRL: usize = 0x10;
    /// Write 1s: those channels abort; reads 1 until each is safe.
    pub const CHAN_ABORT: usize = 0x464;
    /// Channel `n`'s DREQ counter, at `DBG_CTDREQ + n * CH_STRIDE`: a
    /// write clears it.
    pub const DBG_CTDREQ: usize = 0x800;

    /// Register `r` of channel `n`.
    pub const fn ch(n: usize, r: usize) -> usize {
        n * CH_STRIDE + r
    }
}

/// CTRL's fields on the RP2350 (12.6.10, CH0_CTRL_TRIG; BUSY and the error
/// flags moved from the RP2040's places).
pub mod ctrl {
    pub const EN: u32 = 1 << 0;
    /// DATA_SIZE, bits 3:2: 2 is a word.
    pub const DATA_SIZE_WORD: u32 = 2 << 2;
    pub const INCR_READ: u32 = 1 << 4;
    pub const INCR_WRITE: u32 = 1 << 6;
    /// RING_SIZE, bits 11:8: log2 of the bytes the address wraps at.
    pub const RING_SIZE: u32 = 8;
    /// The write address wraps, not the read address.
    pub const RING_SEL: u32 = 1 << 12;
    /// CHAIN_TO, bits 16:13: the channel's own index chains to none.
    pub const CHAIN_TO: u32 = 13;
    /// TREQ_SEL, bits 22:17: the DREQ that paces it.
    pub const TREQ_SEL: u32 = 17;
    pub const IRQ_QUIET: u32 = 1 << 23;
    /// Read only: the channel runs a transfer sequence.
    pub const BUSY: u32 = 1 << 26;
    /// Write 1 to clear: a bus error on a write.
    pub const WRITE_ERROR: u32 = 1 << 29;
    /// Write 1 to clear: a bus error on a read.
    pub const READ_ERROR: u32 = 1 << 30;
    /// Read only: READ_ERROR or WRITE_ERROR.
    pub const AHB_ERROR: u32 = 1 << 31;
}

/// TRANS_COUNT's fields on the RP2350 (12.6.2.2).
pub mod trans_count {
    /// COUNT, bits 27:0.
    pub const COUNT: u32 = 0x0fff_ffff;
    /// MODE, bits 31:28.
    pub const MODE: u32 = 28;
    /// Mode 1: the channel triggers itself when its count runs out.
    pub const TRIGGER_SELF: u32 = 1;
}

/// The address of the RX FIFO register (RXF0..3) of state machine `s` of
/// PIO block `b`: block `b` at `0x5020_0000 + b * 0x10_0000` (2.2, the
/// address map), RXFn at 0x20 + 4n (11.7).
pub const fn pio_rxf(b: usize, s: usize) -> u32 {
    0x5020_0000 + b as u32 * 0x10_0000 + 0x20 + 4 * s as u32
}

/// The DREQ of the RX FIFO of state machine `s` of PIO block `b`
/// (12.6.4.1): PIO0's RX0-3 are 4-7, PIO1's 12-15, PIO2's 20-23.
pub const fn pio_rx_dreq(b: usize, s: usize) -> u8 {
    (b * 8 + 4 + s) as u8
}

/// Counter `c`'s channel, its ring at `ring`: channel `c.index()`, from
/// the counter's RX FIFO.
pub fn counter_channel(c: Counter, ring: u32) -> RingChannel {
    let (b, s) = pioregs::counter_sm(c);
    RingChannel {
        channel: c.index(),
        fifo: pio_rxf(b, s),
        ring,
        dreq: pio_rx_dreq(b, s),
    }
}

/// The DMA block's registers and the rings' memory, as the board code
/// reaches them: the RP2350's own, or the twin's model of them.
pub trait DmaRegs {
    /// The register at `offset` ([`reg`]) of the DMA block.
    fn read(&mut self, offset: usize) -> u32;
    /// Writes the register at `offset` of the DMA block.
    fn write(&mut self, offset: usize, value: u32);
    /// Word `i` of channel `channel`'s ring, as the DMA left it.
    fn ring_word(&mut self, channel: usize, i: usize) -> u32;
    /// Writes word `i` of channel `channel`'s ring (the CPU's [`CANARY`]).
    fn set_ring_word(&mut self, channel: usize, i: usize, value: u32);
}

/// Reads of CHAN_ABORT, then of BUSY, a re-arm waits at most: the datasheet
/// says "generally only a few cycles" (12.6.8.3).
pub const REARM_POLLS: usize = 1_000;

/// A channel that did not stop when aborted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stuck;

/// One counter's channel: which, and what it moves where.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RingChannel {
    /// The DMA channel.
    pub channel: usize,
    /// The address of the counter's RX FIFO (its RXF register).
    pub fifo: u32,
    /// The address of the ring, aligned to its size.
    pub ring: u32,
    /// The RX FIFO's DREQ (12.6.4.1).
    pub dreq: u8,
}

impl RingChannel {
    /// CTRL as the channel runs: words from the FIFO (the read address
    /// fixed) into the ring (the write address wrapped at its size),
    /// paced by the FIFO's DREQ, chained to none, no interrupt, enabled.
    pub const fn ctrl(&self) -> u32 {
        ctrl::DATA_SIZE_WORD
            | ctrl::INCR_WRITE
            | (RING_BITS as u32) << ctrl::RING_SIZE
            | ctrl::RING_SEL
            | (self.channel as u32) << ctrl::CHAIN_TO
            | (self.dreq as u32) << ctrl::TREQ_SEL
            | ctrl::IRQ_QUIET
            | ctrl::EN
    }

    /// TRANS_COUNT as written: a ring's worth of transfers, the channel
    /// triggering itself at the end of each, so that the count says where
    /// the next word goes.
    pub const fn trans_count() -> u32 {
        trans_count::TRIGGER_SELF << trans_count::MODE | RING_WORDS as u32
    }

    fn reg(&self, r: usize) -> usize {
        reg::ch(self.channel, r)
    }

    /// Programs the channel and triggers it (the write of CTRL_TRIG).
    pub fn program(&self, d: &mut impl DmaRegs) {
        d.write(self.reg(reg::READ_ADDR), self.fifo);
        d.write(self.reg(reg::WRITE_ADDR), self.ring);
        d.write(self.reg(reg::TRANS_COUNT), Self::trans_count());
        d.write(self.reg(reg::CTRL_TRIG), self.ctrl());
    }

    /// Where the channel writes next, as an index into its ring, from its
    /// transfer count ([`crate::ring`] says why not from WRITE_ADDR).
    pub fn write_index(&self, d: &mut impl DmaRegs) -> usize {
        let left = (d.read(self.reg(reg::TRANS_COUNT)) & trans_count::COUNT) as usize;
        (RING_WORDS - left.min(RING_WORDS)) % RING_WORDS
    }

    /// Stops the channel and starts it afresh at its ring's start, as the
    /// datasheet has it for a channel in an unknown state (12.6.8.3, with
    /// erratum RP2350-E5) and after a bus error (12.6.7.2): EN cleared
    /// first (without a trigger: alias 1's CTRL), so that the abort's
    /// completion cannot trigger it again; CHAN_ABORT, polled until its bit
    /// is clear; BUSY polled low (its transfers in flight flushed); 1
    /// written to both error flags; its DREQ handshake started afresh
    /// (DBG_CTDREQ: a faulting read was suppressed but took its credit,
    /// 12.6.7.3 and 12.6.4.2, so the count no longer matches what the FIFO
    /// holds); then programmed and triggered. Only
    /// this channel is touched: the others run on where they are (a
    /// trigger would not restart a running channel, and its WRITE_ADDR is
    /// live, 12.6.3 and 12.6.2). `Err` if the channel did not stop within
    /// [`REARM_POLLS`] reads; it is left stopped, not reprogrammed.
    pub fn rearm(&self, d: &mut impl DmaRegs) -> Result<(), Stuck> {
        let stopped = self.ctrl() & !ctrl::EN;
        d.write(self.reg(reg::AL1_CTRL), stopped);
        d.write(reg::CHAN_ABORT, 1 << self.channel);
        let aborted = (0..REARM_POLLS).any(|_| d.read(reg::CHAN_ABORT) >> self.channel & 1 == 0);
        let idle =
            aborted && (0..REARM_POLLS).any(|_| d.read(self.reg(reg::CTRL_TRIG)) & ctrl::BUSY == 0);
        if !idle {
            return Err(Stuck);
        }
        d.write(
            self.reg(reg::AL1_CTRL),
            stopped | ctrl::READ_ERROR | ctrl::WRITE_ERROR,
        );
        d.write(self.reg(reg::DBG_CTDREQ), 0);
        self.program(d);
        Ok(())
    }

    /// Whether the channel moves nothing more: a bus error halted it, or
    /// it is not enabled.
    pub fn halted(&self, d: &mut impl DmaRegs) -> bool {
        let c = d.read(self.reg(reg::CTRL_TRIG));
        c & ctrl::AHB_ERROR != 0 || c & ctrl::EN == 0
    }
}

/// The four rings: their channels, and the CPU's side of each.
#[derive(Debug, Clone)]
pub struct Rings {
    pub channels: [RingChannel; 4],
    readers: [Reader; 4],
    /// A ring was lapped, or a channel re-armed, since the last look.
    lost: bool,
}

impl Rings {
    pub const fn new(channels: [RingChannel; 4]) -> Rings {
        Rings {
            channels,
            readers: [Reader::new(); 4],
            lost: false,
        }
    }

    /// Starts every channel (at boot): each waits for its DREQ, so the
    /// counters need not run.
    pub fn start(&mut self, d: &mut impl DmaRegs) {
        for c in &self.channels {
            c.program(d);
        }
    }

    /// Reader `i` from where its channel writes next, with [`CANARY`] where
    /// it wrote last ([`Reader::at`]).
    pub fn restart_reader(&mut self, d: &mut impl DmaRegs, i: usize) {
        let ch = self.channels[i];
        let write = ch.write_index(d);
        d.set_ring_word(ch.channel, Reader::canary_slot(write), CANARY);
        self.readers[i] = Reader::at(write);
    }

    /// Every reader restarted, and nothing lost: what the rings held is
    /// from before (the counters' start).
    pub fn restart_readers(&mut self, d: &mut impl DmaRegs) {
        for i in 0..self.readers.len() {
            self.restart_reader(d, i);
        }
        self.lost = false;
    }

    /// Each channel's DREQ count cleared (DBG_CTDREQ), for counters whose
    /// FIFOs are empty and stay so until they start: the handshake starts
    /// afresh with them (12.6.4.2).
    pub fn clear_dreq_counts(&self, d: &mut impl DmaRegs) {
        for c in &self.channels {
            d.write(reg::ch(c.channel, reg::DBG_CTDREQ), 0);
        }
    }

    /// Words ring `i` holds that the CPU has not read.
    pub fn level(&self, d: &mut impl DmaRegs, i: usize) -> usize {
        self.readers[i].level(self.channels[i].write_index(d))
    }

    /// The `k`-th word (from 0) of ring `i` the CPU has not read, if the
    /// DMA wrote it, left unread. A ring lapped meanwhile is told by the
    /// next [`Rings::pull`] or [`Rings::take_lost`], which read it afresh.
    pub fn peek(&self, d: &mut impl DmaRegs, i: usize, k: usize) -> Option<u32> {
        let ch = self.channels[i];
        (k < self.level(d, i)).then(|| d.ring_word(ch.channel, self.readers[i].at_offset(k)))
    }

    /// Whether any ring holds words the CPU has not read (at the first
    /// that does: an idle loop asks on every pass).
    pub fn hold_words(&self, d: &mut impl DmaRegs) -> bool {
        (0..self.readers.len()).any(|i| self.level(d, i) > 0)
    }

    /// The fullest ring's words not read.
    pub fn fullest(&self, d: &mut impl DmaRegs) -> usize {
        (0..self.readers.len())
            .map(|i| self.level(d, i))
            .max()
            .unwrap_or(0)
    }

    /// The next word of ring `i`, if the DMA wrote one the CPU has not
    /// read; a lapped ring is read afresh from where the DMA writes, and
    /// the loss told by the next [`Rings::take_lost`].
    pub fn pull(&mut self, d: &mut impl DmaRegs, i: usize) -> Option<u32> {
        let ch = self.channels[i];
        let write = ch.write_index(d);
        match self.readers[i].next(|k| d.ring_word(ch.channel, k), write) {
            Ok(w) => w,
            Err(Lapped) => {
                self.lost = true;
                self.restart_reader(d, i);
                None
            }
        }
    }

    /// Whether the capture lost words since the last look: a ring the DMA
    /// came round on, or a channel that stopped. A stopped channel is
    /// re-armed here ([`RingChannel::rearm`]), alone, and its ring read
    /// afresh; what it had not moved is lost. One that does not stop is
    /// tried again at the next look, and lost again (its ring read afresh
    /// each time, so that nothing stale is read meanwhile).
    pub fn take_lost(&mut self, d: &mut impl DmaRegs) -> bool {
        let mut halted = false;
        for i in 0..self.channels.len() {
            let ch = self.channels[i];
            if ch.halted(d) {
                halted = true;
                // Stopped or not, the channel's count no longer says where
                // its ring was written: read it afresh, so that no word of
                // a lap ago passes for a new one.
                let _ = ch.rearm(d);
                self.restart_reader(d, i);
            }
        }
        core::mem::take(&mut self.lost) || halted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // CTRL_TRIG's and TRANS_COUNT's fields against rp-pac's RP2350
    // registers (generated from the RP2350's SVD): written independently
    // of this file.
    #[test]
    fn the_fields_are_where_the_rp2350s_svd_puts_them() {
        use rp_pac::dma::regs::{ChTransCount, CtrlTrig};
        use rp_pac::dma::vals::{DataSize, TransCountMode, TreqSel};
        let ch = RingChannel {
            channel: 2,
            fifo: 0,
            ring: 0,
            dreq: 21,
        };
        let mut want = CtrlTrig(0);
        want.set_en(true);
        want.set_data_size(DataSize::SIZE_WORD);
        want.set_incr_write(true);
        want.set_ring_size(RING_BITS);
        want.set_ring_sel(true);
        want.set_chain_to(2);
        want.set_treq_sel(TreqSel::from_bits(21));
        want.set_irq_quiet(true);
        assert_eq!(ch.ctrl(), want.0);
        for (bit, field) in [
            (ctrl::BUSY, CtrlTrig(ctrl::BUSY).busy()),
            (ctrl::READ_ERROR, CtrlTrig(ctrl::READ_ERROR).read_error()),
            (ctrl::WRITE_ERROR, CtrlTrig(ctrl::WRITE_ERROR).write_error()),
            (ctrl::AHB_ERROR, CtrlTrig(ctrl::AHB_ERROR).ahb_error()),
            (ctrl::INCR_READ, CtrlTrig(ctrl::INCR_READ).incr_read()),
        ] {
            assert!(field, "{bit:#x}");
        }
        let mut tc = ChTransCount(0);
        tc.set_mode(TransCountMode::TRIGGER_SELF);
        tc.set_count(RING_WORDS as u32);
        assert_eq!(RingChannel::trans_count(), tc.0);
    }

    #[test]
    fn the_fifos_and_dreqs_are_where_the_rp2350s_svd_and_datasheet_put_them() {
        use rp_pac::dma::vals::TreqSel;
        let pio = [rp_pac::PIO0, rp_pac::PIO1, rp_pac::PIO2];
        for (b, block) in pio.iter().enumerate() {
            for s in 0..4 {
                assert_eq!(block.rxf(s).as_ptr() as u32, pio_rxf(b, s));
            }
        }
        assert_eq!(pio_rx_dreq(1, 0), TreqSel::PIO1_RX0.to_bits());
        assert_eq!(pio_rx_dreq(2, 2), TreqSel::PIO2_RX2.to_bits());
        assert_eq!(pio_rx_dreq(0, 3), TreqSel::PIO0_RX3.to_bits());
    }

    #[test]
    fn the_registers_are_where_the_rp2350s_svd_puts_them() {
        let dma = rp_pac::DMA;
        let base = dma.as_ptr() as usize;
        let at = |p: *mut u32| p as usize - base;
        assert_eq!(
            at(dma.ch(3).read_addr().as_ptr()),
            reg::ch(3, reg::READ_ADDR)
        );
        assert_eq!(
            at(dma.ch(3).write_addr().as_ptr()),
            reg::ch(3, reg::WRITE_ADDR)
        );
        assert_eq!(
            at(dma.ch(3).trans_count().as_ptr() as *mut u32),
            reg::ch(3, reg::TRANS_COUNT)
        );
        assert_eq!(
            at(dma.ch(3).ctrl_trig().as_ptr() as *mut u32),
            reg::ch(3, reg::CTRL_TRIG)
        );
        assert_eq!(at(dma.ch(3).al1_ctrl().as_ptr()), reg::ch(3, reg::AL1_CTRL));
        assert_eq!(at(dma.chan_abort().as_ptr() as *mut u32), reg::CHAN_ABORT);
        assert_eq!(
            at(dma.ch(3).dbg_ctdreq().as_ptr() as *mut u32),
            reg::ch(3, reg::DBG_CTDREQ)
        );
    }
}
