//! The RP2350's DMA block as the board code uses it (RP2350 datasheet,
//! 12.6), register by register, so that the image's own code that
//! programs, reads and re-arms the capture's channels ([`crate::dma`])
//! runs on the twin as on the chip:
//!
//! - READ_ADDR and WRITE_ADDR are live: written while the channel runs,
//!   the next transfer uses the new address (12.6.2);
//! - TRANS_COUNT read is the transfers left; written, it is the count the
//!   next trigger loads (12.6.2.2); mode 1 (TRIGGER_SELF) triggers the
//!   channel again when its count runs out, mode 15 (ENDLESS) never counts;
//! - a trigger (a write to CTRL_TRIG other than 0, with EN in the value
//!   written) starts a channel that is not BUSY; a BUSY channel, a disabled
//!   one, and one with an error flag set ignore it (12.6.3, 12.6.7.1);
//! - each transfer spends one of the channel's DREQ credits: a push into
//!   the RX FIFO its TREQ_SEL names is one more, at most 63 (12.6.4.2);
//!   writing DBG_CTDREQ clears them and starts the handshake afresh, which
//!   the twin takes to count the words the FIFO holds then (the datasheet
//!   says only "re-initiate DREQ handshake"); a channel with none moves
//!   nothing;
//! - one word a cycle a channel: read from a PIO RX FIFO (an empty one
//!   reads 0: the channel and the FIFO out of step), written to RAM, the
//!   write address wrapped at 2^RING_SIZE bytes when RING_SEL is set;
//! - a bus error (an address that is no PIO RX FIFO, or no RAM the twin
//!   has; or one a test injects) halts the channel: READ_ERROR or
//!   WRITE_ERROR set, BUSY low, no more transfers, until software writes 1
//!   to the flag (12.6.7);
//! - CHAN_ABORT ends a channel's sequence (its count cleared, BUSY low)
//!   at once: the model has no transfer in flight between cycles (a word
//!   is read and written in the cycle it is issued), so the bit, which
//!   on the chip reads 1 until those finish (12.6.8.3), reads 0 again;
//!   and, erratum RP2350-E5, a channel aborted with EN still set
//!   triggers itself again (TRIGGER_SELF) as the abort completes.
//!
//! What the board code does not use (the other aliases, chaining to
//! another channel, interrupts, sniffing, byte or halfword transfers,
//! incrementing reads) is refused with a panic, not modelled
//! approximately.

use super::block::Block;
use crate::dma::{ctrl, pio_rx_dreq, pio_rxf, reg, trans_count};
use std::vec::Vec;

/// Channels of the RP2350's DMA.
pub const CHANNELS: usize = 16;

/// Where the twin's RAM is, for the rings (any address the RP2350's SRAM
/// has would do).
pub const RAM: u32 = 0x2000_0000;

/// The PIO RX FIFO DREQ `dreq` is, if it is one (12.6.4.1).
fn rx_dreq(dreq: u32) -> Option<(usize, usize)> {
    (0..3)
        .flat_map(|b| (0..4).map(move |s| (b, s)))
        .find(|&(b, s)| u32::from(pio_rx_dreq(b, s)) == dreq)
}

/// A bus error a test makes a channel's next transfer meet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusError {
    Read,
    Write,
}

/// CTRL's bits software writes and reads back (EN through SNIFF_EN).
const CTRL_RW: u32 = 0x03ff_ffff;

/// One channel.
#[derive(Debug, Clone, Default)]
pub struct Channel {
    pub read_addr: u32,
    pub write_addr: u32,
    /// TRANS_COUNT as last written: the mode and the count a trigger loads.
    reload: u32,
    /// The transfers left in this sequence.
    count: u32,
    /// CTRL's read-write bits.
    ctrl: u32,
    pub busy: bool,
    read_error: bool,
    write_error: bool,
    /// DREQ credits (DBG_CTDREQ).
    credit: u32,
    /// The pushes of its DREQ's FIFO counted so far.
    pushes_seen: u64,
    /// A bus error its next transfer meets.
    inject: Option<BusError>,
    /// The RX FIFO (block, state machine) its TREQ_SEL names, if one.
    paced_by: Option<(usize, usize)>,
    /// The RX FIFO (block, state machine) READ_ADDR is, if one.
    source: Option<(usize, usize)>,
}

impl Channel {
    fn mode(&self) -> u32 {
        self.reload >> trans_count::MODE
    }

    fn ctrl_read(&self) -> u32 {
        let mut v = self.ctrl;
        if self.busy {
            v |= ctrl::BUSY;
        }
        if self.write_error {
            v |= ctrl::WRITE_ERROR;
        }
        if self.read_error {
            v |= ctrl::READ_ERROR;
        }
        if self.write_error || self.read_error {
            v |= ctrl::AHB_ERROR;
        }
        v
    }

    /// A trigger: ignored by a busy, a disabled, or an erring channel.
    fn trigger(&mut self) {
        if self.busy || self.ctrl & ctrl::EN == 0 || self.read_error || self.write_error {
            return;
        }
        self.count = self.reload & trans_count::COUNT;
        self.busy = true;
    }

    fn write_ctrl(&mut self, value: u32) {
        self.ctrl = value & CTRL_RW;
        self.paced_by = rx_dreq(self.ctrl >> ctrl::TREQ_SEL & 0x3f);
        if value & ctrl::READ_ERROR != 0 {
            self.read_error = false;
        }
        if value & ctrl::WRITE_ERROR != 0 {
            self.write_error = false;
        }
    }
}

/// The DMA block and the RAM its channels write.
#[derive(Debug, Clone)]
pub struct Dma {
    pub ch: [Channel; CHANNELS],
    /// RAM regions: (address, words).
    ram: Vec<(u32, Vec<u32>)>,
    /// The channels a cycle may change: those paced by a FIFO.
    active: Vec<usize>,
}

impl Default for Dma {
    fn default() -> Self {
        Dma::new()
    }
}

impl Dma {
    pub fn new() -> Dma {
        Dma {
            ch: core::array::from_fn(|_| Channel::default()),
            ram: Vec::new(),
            active: Vec::new(),
        }
    }

    /// Adds `words` of RAM at `addr` (word-aligned), zeroed.
    pub fn add_ram(&mut self, addr: u32, words: usize) {
        self.ram.push((addr, std::vec![0; words]));
    }

    fn ram_slot(&mut self, addr: u32) -> Option<&mut u32> {
        if addr & 3 != 0 {
            return None;
        }
        self.ram.iter_mut().find_map(|(base, words)| {
            let i = addr.checked_sub(*base)? as usize / 4;
            words.get_mut(i)
        })
    }

    /// The RAM word at `addr`.
    pub fn ram_word(&mut self, addr: u32) -> Option<u32> {
        self.ram_slot(addr).map(|w| *w)
    }

    /// Writes the RAM word at `addr` (the CPU's write).
    pub fn set_ram_word(&mut self, addr: u32, value: u32) {
        if let Some(w) = self.ram_slot(addr) {
            *w = value;
        }
    }

    /// The next transfer of channel `n` meets a bus error.
    pub fn inject(&mut self, n: usize, e: BusError) {
        self.ch[n].inject = Some(e);
    }

    /// A register read by the CPU.
    pub fn read(&self, offset: usize) -> u32 {
        if offset == reg::CHAN_ABORT {
            // Every abort is complete (above).
            return 0;
        }
        if offset >= reg::DBG_CTDREQ {
            let (n, r) = Self::split(offset - reg::DBG_CTDREQ);
            assert_eq!(r, 0, "DMA debug register {offset:#x} is not modelled");
            return self.ch[n].credit;
        }
        let (n, r) = Self::split(offset);
        let c = &self.ch[n];
        match r {
            reg::READ_ADDR => c.read_addr,
            reg::WRITE_ADDR => c.write_addr,
            reg::TRANS_COUNT => c.reload & !trans_count::COUNT | c.count,
            reg::CTRL_TRIG | reg::AL1_CTRL => c.ctrl_read(),
            _ => panic!("DMA register {offset:#x} is not modelled"),
        }
    }

    /// A register write by the CPU.
    pub fn write(&mut self, offset: usize, value: u32, blocks: &[Block; 3]) {
        self.write_reg(offset, value, blocks);
        self.active = (0..CHANNELS)
            .filter(|&n| self.ch[n].paced_by.is_some())
            .collect();
    }

    fn write_reg(&mut self, offset: usize, value: u32, blocks: &[Block; 3]) {
        if offset == reg::CHAN_ABORT {
            for n in (0..CHANNELS).filter(|n| value >> n & 1 == 1) {
                let c = &mut self.ch[n];
                c.busy = false;
                c.count = 0;
                // RP2350-E5: the abort completes the sequence, and a
                // channel still enabled triggers itself again.
                if c.ctrl & ctrl::EN != 0 && c.mode() == trans_count::TRIGGER_SELF {
                    c.trigger();
                }
            }
            return;
        }
        if offset >= reg::DBG_CTDREQ {
            let (n, r) = Self::split(offset - reg::DBG_CTDREQ);
            assert_eq!(r, 0, "DMA debug register {offset:#x} is not modelled");
            // The handshake afresh: the FIFO's words are the credits.
            let pushes = self.pushes(n, blocks);
            let c = &mut self.ch[n];
            c.credit = c
                .paced_by
                .map_or(0, |(b, s)| blocks[b].rx_level(s).min(63) as u32);
            c.pushes_seen = pushes;
            return;
        }
        let (n, r) = Self::split(offset);
        let c = &mut self.ch[n];
        match r {
            reg::READ_ADDR => {
                c.read_addr = value;
                c.source = (0..3)
                    .flat_map(|b| (0..4).map(move |s| (b, s)))
                    .find(|&(b, s)| pio_rxf(b, s) == value);
            }
            reg::WRITE_ADDR => c.write_addr = value,
            reg::TRANS_COUNT => c.reload = value,
            reg::AL1_CTRL => c.write_ctrl(value),
            reg::CTRL_TRIG => {
                c.write_ctrl(value);
                Self::check_ctrl(n, c.ctrl);
                if value != 0 {
                    c.trigger();
                }
            }
            _ => panic!("DMA register {offset:#x} is not modelled"),
        }
    }

    fn split(offset: usize) -> (usize, usize) {
        let n = offset / reg::CH_STRIDE;
        assert!(n < CHANNELS, "DMA register {offset:#x} is not modelled");
        (n, offset % reg::CH_STRIDE)
    }

    /// Refuses what the model does not do.
    fn check_ctrl(n: usize, c: u32) {
        if c & ctrl::EN == 0 {
            return;
        }
        let chain = (c >> ctrl::CHAIN_TO & 0xf) as usize;
        assert_eq!(
            chain, n,
            "channel {n}: chaining to another channel is not modelled"
        );
        assert_eq!(
            c >> 2 & 3,
            2,
            "channel {n}: only word transfers are modelled"
        );
        assert_eq!(
            c & ctrl::INCR_READ,
            0,
            "channel {n}: incrementing reads are not modelled"
        );
        assert!(
            rx_dreq(c >> ctrl::TREQ_SEL & 0x3f).is_some(),
            "channel {n}: only PIO RX DREQs are modelled"
        );
    }

    /// The pushes into the RX FIFO channel `n`'s DREQ names.
    fn pushes(&self, n: usize, blocks: &[Block; 3]) -> u64 {
        match self.ch[n].paced_by {
            Some((b, s)) => blocks[b].sm[s].pushed,
            None => 0,
        }
    }

    /// Whether a cycle could change anything: a transfer to make, or a
    /// DREQ not yet counted.
    pub fn quiet(&self, blocks: &[Block; 3]) -> bool {
        self.active.iter().all(|&n| {
            let c = &self.ch[n];
            self.pushes(n, blocks) == c.pushes_seen
                && !(c.busy && c.ctrl & ctrl::EN != 0 && c.credit > 0)
        })
    }

    /// One system clock cycle: DREQ credits counted, then each channel
    /// that may moves one word.
    pub fn step(&mut self, blocks: &mut [Block; 3]) {
        for k in 0..self.active.len() {
            let n = self.active[k];
            let pushes = self.pushes(n, blocks);
            let c = &mut self.ch[n];
            let new = pushes.saturating_sub(c.pushes_seen);
            c.pushes_seen = pushes;
            c.credit = (c.credit + new.min(63) as u32).min(63);
            if !(c.busy && c.ctrl & ctrl::EN != 0 && c.credit > 0) {
                continue;
            }
            c.credit -= 1;
            self.transfer(n, blocks);
        }
    }

    fn transfer(&mut self, n: usize, blocks: &mut [Block; 3]) {
        let (write_addr, inject, source) = {
            let c = &mut self.ch[n];
            (c.write_addr, c.inject.take(), c.source)
        };
        let word = match (inject, source) {
            (Some(BusError::Read), _) | (None | Some(BusError::Write), None) => None,
            // An empty FIFO reads 0 (and sets its FDEBUG.RXUNDER).
            (_, Some((b, s))) => Some(blocks[b].rxf_read(s).unwrap_or(0)),
        };
        let Some(word) = word else {
            let c = &mut self.ch[n];
            c.read_error = true;
            c.busy = false;
            return;
        };
        let written = inject != Some(BusError::Write)
            && self.ram_slot(write_addr).map(|w| *w = word).is_some();
        let c = &mut self.ch[n];
        if !written {
            c.write_error = true;
            c.busy = false;
            return;
        }
        if c.ctrl & ctrl::INCR_WRITE != 0 {
            let next = write_addr.wrapping_add(4);
            let ring = c.ctrl >> ctrl::RING_SIZE & 0xf;
            c.write_addr = if c.ctrl & ctrl::RING_SEL != 0 && ring != 0 {
                let mask = (1u32 << ring) - 1;
                write_addr & !mask | next & mask
            } else {
                next
            };
        }
        match c.mode() {
            0xf => {}
            mode => {
                c.count = c.count.saturating_sub(1);
                if c.count == 0 {
                    c.busy = false;
                    if mode == trans_count::TRIGGER_SELF {
                        c.trigger();
                    }
                }
            }
        }
    }
}
