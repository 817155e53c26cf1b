//! The board twin: the RP2350 image's board code ([`crate::board`]) on a
//! model of the RP2350's PIO blocks and GPIOs ([`pio`]) wired pin by pin to
//! the reference chip model ([`chip`]).
//!
//! [`Twin`] is the hardware layer ([`Hal`]): it boots the PIO blocks as
//! the image does, from the same programs and register values
//! ([`crate::programs`], [`crate::pioregs`]), and each call the board code
//! makes costs the CPU some cycles, during which the state machines and
//! the chip run. The cost is fixed ([`Twin::cpu_cycles`]), plus random
//! gaps when asked ([`Twin::with_gaps`]), so that FIFO limits are met for
//! real.

pub mod chip;
pub mod pio;
#[cfg(test)]
mod tests;

use crate::bus_cycle::BusTiming;
use crate::dma::{self, DmaRegs, Rings};
use crate::hal::{Counter, Hal};
use crate::pins;
use crate::pioregs::{self, block, fdebug, START_COUNTERS, STOP_COUNTERS};
use crate::programs::{self, Loaded};
use crate::ring::RING_WORDS;
use chip::ChipSide;
use pio::{Func, World};
use ppmc_core::emu::{Board as Model, ModelConfig};
use ppmc_core::protocol::Straps;
use std::format;
use std::string::String;

/// The RP2350's system clock in the twin, as embassy-rp sets it up.
pub const SYSCLK_HZ: u32 = 150_000_000;

/// Cycles one hardware-layer call costs the CPU by default: a PAC
/// register access and the loop around it.
pub const CPU_CYCLES: u64 = 12;

/// Cycles a reading of the bridge's clock costs the RP2350 image
/// (`Hal::cycles`: the cycle counter, extended): some 6.
pub const CLOCK_CYCLES: u64 = 6;

/// Cycles setting the clock right costs (`Hal::resync`: interrupts off,
/// the cycle counter, the 1 MHz timer's two words, the clock's 64-bit
/// arithmetic): some 64.
pub const RESYNC_CYCLES: u64 = 64;

/// How often the board code looked into the POUT counter's DMA ring, and
/// how full it found it: the capture's margin.
#[derive(Debug, Clone, Copy, Default)]
pub struct Drains {
    /// The most words the ring held when the board code looked.
    pub fullest: usize,
    /// The longest time between two looks that found words, in cycles.
    pub longest_gap: u64,
    last: Option<u64>,
}

impl Drains {
    fn look(&mut self, cycle: u64, level: usize) {
        self.fullest = self.fullest.max(level);
        if let Some(last) = self.last {
            if level > 0 {
                self.longest_gap = self.longest_gap.max(cycle - last);
            }
        }
        self.last = Some(cycle);
    }
}

/// The twin's hardware: the RP2350's PIO and GPIOs, the board around it.
#[derive(Debug)]
pub struct Twin {
    pub world: World,
    pub chip: ChipSide,
    layout: [Loaded; 3],
    /// The self-test generator, as loaded in PIO0.
    gen: Loaded,
    /// Cycles each call costs.
    pub cpu_cycles: u64,
    /// Random extra cycles per call: (state, at most).
    gaps: Option<(u64, u64)>,
    /// How the board code drained the POUT counter's ring.
    pub drains: Drains,
    /// The counters' DMA rings, as the image programs and reads them
    /// ([`crate::dma`]), in [`Counter::ALL`] order.
    rings: Rings,
    /// Clock readings not yet paid for: the world runs them off at the next
    /// call that spends.
    owed: core::cell::Cell<u64>,
    /// The system clock cycle the twin has simulated up to, for a thread
    /// that tells the host how far a long request has got (`ppmc-twin`'s
    /// WORKING messages): the twin runs slower than real time.
    pub progress: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// Cycles a pass of [`Hal::idle`]'s loop takes (read the pins and the
    /// capture FIFOs' levels, compare): how late after a change it returns.
    pub idle_step: u64,
    /// The reads of the last [`Hal::read_pins_grid`].
    grid: std::vec::Vec<(u64, u16)>,
}

impl Twin {
    /// The twin with a chip of `straps` and `cfg`, booted as the RP2350
    /// image boots: programs loaded, state machines configured, pins set
    /// (levels before directions), the buffers enabled.
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Twin, String> {
        let model = Model::new(straps, cfg).map_err(|e| format!("{e}"))?;
        let mut t = Twin {
            world: World::new(),
            chip: ChipSide::new(model, SYSCLK_HZ),
            layout: programs::layout(),
            gen: programs::relocate(programs::test_gen(), programs::test_gen_origin()),
            cpu_cycles: CPU_CYCLES,
            gaps: None,
            idle_step: 2 * CPU_CYCLES,
            progress: Default::default(),
            owed: core::cell::Cell::new(0),
            grid: std::vec::Vec::new(),
            drains: Drains::default(),
            rings: Rings::new(Counter::ALL.map(|c| dma::counter_channel(c, ring_addr(c.index())))),
        };
        t.boot().map_err(|e| format!("{e:?}"))?;
        Ok(t)
    }

    /// Adds a random gap of up to `max` cycles to every call (seeded).
    pub fn with_gaps(mut self, seed: u64, max: u64) -> Twin {
        self.gaps = Some((seed | 1, max));
        self
    }

    fn boot(&mut self) -> Result<(), std::boxed::Box<dyn core::fmt::Debug>> {
        let w = &mut self.world;
        for (b, p) in self.layout.iter().enumerate() {
            w.blocks[b]
                .set_gpiobase(block::GPIOBASE[b])
                .map_err(|e| std::boxed::Box::new(e) as _)?;
            w.blocks[b]
                .load(p.words(), 0)
                .map_err(|e| std::boxed::Box::new(e) as _)?;
        }
        // The generator after the bus player in PIO0, stopped, TEST_GEN
        // given to PIO0 and undriven (SM1's direction 0) until the self-test.
        w.blocks[0]
            .load(self.gen.words(), programs::test_gen_origin())
            .map_err(|e| std::boxed::Box::new(e) as _)?;
        w.blocks[0]
            .configure(pioregs::TEST_GEN_SM, &pioregs::test_gen(&self.gen))
            .map_err(|e| std::boxed::Box::new(e) as _)?;
        w.blocks[0].force_pins(1 << pins::TEST_GEN, 0, 0);
        w.func[pins::TEST_GEN as usize] = Func::Pio(0);
        // A DMA channel a counter, into its ring in RAM, started as the
        // image starts them.
        for c in Counter::ALL {
            w.dma.add_ram(ring_addr(c.index()), RING_WORDS);
        }
        self.rings.start(&mut TwinDma(w));
        // SIO outputs: levels first, then directions (issue 28): the chip's
        // inputs released, RESET* high, the buffers off until all is set.
        let mut sio_pins: u64 = 1 << pins::RESET | 1 << pins::CAPTURE_OE | 1 << pins::DRIVE_EN;
        for g in pins::INPUTS {
            sio_pins |= 1 << g;
        }
        let released: u64 = sio_pins & !(1 << pins::DRIVE_EN) & !(1 << pins::CAPTURE_OE);
        w.sio_out = released | 1 << pins::CAPTURE_OE;
        for g in 0..48 {
            if sio_pins >> g & 1 == 1 {
                w.func[g] = Func::Sio;
            }
        }
        w.sio_oe = sio_pins;
        // The bus player: idle levels, then directions, then the config.
        let player = pioregs::bus_player(&self.layout[0]);
        w.blocks[0]
            .configure(0, &player)
            .map_err(|e| std::boxed::Box::new(e) as _)?;
        let bus_mask: u64 = (1 << pins::BUS_COUNT) - 1;
        let idle = u64::from(crate::bus_cycle::IDLE >> 8) << pins::A0;
        w.blocks[0].force_pins(bus_mask, idle, 0);
        w.blocks[0].force_pins(bus_mask, idle, bus_mask);
        for g in 0..pins::BUS_COUNT {
            w.func[g as usize] = Func::Pio(0);
        }
        w.write_ctrl(0, 1);
        // The buffers: the chip's outputs in, then the bridge's out.
        w.sio_out &= !(1 << pins::CAPTURE_OE);
        w.sio_out |= 1 << pins::DRIVE_EN;
        let chip = &mut self.chip;
        w.cpu_wrote(chip);
        w.run_until(w.cycle + 4, chip);
        Ok(())
    }

    /// Runs the hardware to `cycle`, and says how far it got to whoever
    /// watches [`Twin::progress`].
    fn run_to(&mut self, cycle: u64) {
        self.world.run_until(cycle, &mut self.chip);
        self.progress
            .store(self.world.cycle, std::sync::atomic::Ordering::Relaxed);
    }

    /// Spends `n` CPU cycles (plus a gap, if any): the hardware runs.
    fn spend(&mut self, n: u64) {
        let mut n = n + self.owed.take();
        if let Some((s, max)) = self.gaps.as_mut() {
            *s ^= *s << 13;
            *s ^= *s >> 7;
            *s ^= *s << 17;
            if *max > 0 {
                n += *s % (*max + 1);
            }
        }
        let until = self.world.cycle + n;
        self.run_to(until);
    }

    /// Stops the bus player, as a stuck state machine would (a test of the
    /// board code's deadlines).
    pub fn stop_bus_player(&mut self) {
        self.world.write_ctrl(0, 0);
    }
}

/// Where the twin puts ring `i` in its RAM: aligned to a ring's size.
fn ring_addr(i: usize) -> u32 {
    pio::RAM + (i * RING_WORDS * 4) as u32
}

/// The address of word `i` (taken round the ring) of ring `channel`.
fn ring_slot(channel: usize, i: usize) -> u32 {
    ring_addr(channel) + 4 * (i % RING_WORDS) as u32
}

/// The twin's DMA block as the board code reaches it.
struct TwinDma<'a>(&'a mut World);

impl DmaRegs for TwinDma<'_> {
    fn read(&mut self, offset: usize) -> u32 {
        self.0.dma.read(offset)
    }

    fn write(&mut self, offset: usize, value: u32) {
        let w = &mut *self.0;
        w.dma.write(offset, value, &w.blocks);
    }

    fn ring_word(&mut self, channel: usize, i: usize) -> u32 {
        self.0.dma.ram_word(ring_slot(channel, i)).unwrap_or(0)
    }

    fn set_ring_word(&mut self, channel: usize, i: usize, value: u32) {
        self.0.dma.set_ram_word(ring_slot(channel, i), value);
    }
}

impl Hal for Twin {
    fn sysclk_hz(&self) -> u32 {
        SYSCLK_HZ
    }

    fn cycles(&self) -> u64 {
        // The reading costs its cycles; it says the time at its end.
        let owed = self.owed.get() + CLOCK_CYCLES;
        self.owed.set(owed);
        self.world.cycle + owed
    }

    fn resync(&mut self) {
        self.spend(RESYNC_CYCLES);
    }

    fn bus_tx_full(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].tx_full(0)
    }

    fn bus_push(&mut self, word: u32) -> u64 {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].txf_write(0, word);
        self.world.cycle
    }

    fn bus_tx_empty(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].tx_empty(0)
    }

    fn bus_pull(&mut self) -> Option<u32> {
        self.spend(self.cpu_cycles);
        let b = &mut self.world.blocks[block::BUS];
        (b.rx_level(0) > 0).then(|| b.rxf_read(0)).flatten()
    }

    fn capture_pull(&mut self, c: Counter) -> Option<u32> {
        self.spend(self.cpu_cycles);
        let i = c.index();
        let cycle = self.world.cycle;
        let d = &mut TwinDma(&mut self.world);
        if c == Counter::Pout {
            self.drains.look(cycle, self.rings.level(d, i));
        }
        self.rings.pull(d, i)
    }

    fn capture_peek(&mut self, c: Counter, k: usize) -> Option<u32> {
        self.spend(self.cpu_cycles);
        self.rings.peek(&mut TwinDma(&mut self.world), c.index(), k)
    }

    fn capture_level(&mut self) -> usize {
        self.spend(self.cpu_cycles);
        self.rings.fullest(&mut TwinDma(&mut self.world))
    }

    fn capture_stalled(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        let mut stalled = self.rings.take_lost(&mut TwinDma(&mut self.world));
        for b in [block::POUT, block::PINS] {
            let mask = pioregs::COUNTERS[b] << fdebug::RXSTALL;
            stalled |= self.world.blocks[b].fdebug() & mask != 0;
            self.world.blocks[b].clear_fdebug(mask);
        }
        stalled
    }

    fn start_counters(&mut self) -> u64 {
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(block::POUT, STOP_COUNTERS);
        let pads = self.world.pads();
        let level = |g: u32| pads >> g & 1 == 1;
        let pout = pioregs::pout_counter(&self.layout[1], level(pins::POUT));
        let others = pioregs::pin_counters(
            &self.layout[2],
            [pins::INT, pins::HOLD, pins::AUX].map(level),
        );
        for (b, s, regs) in [
            (block::POUT, 0, pout),
            (block::PINS, 0, others[0]),
            (block::PINS, 1, others[1]),
            (block::PINS, 2, others[2]),
        ] {
            // FJOIN_RX flipped and back: the FIFOs flushed.
            let blk = &mut self.world.blocks[b];
            blk.write_shiftctrl(s, regs.shiftctrl ^ 1 << pioregs::shiftctrl::FJOIN_RX);
            blk.write_shiftctrl(s, regs.shiftctrl);
            // Refused configurations are a bug of ours: the tests catch it.
            self.world.blocks[b]
                .configure(s, &regs)
                .unwrap_or_else(|e| panic!("the counters' configuration: {e:?}"));
        }
        for b in [block::POUT, block::PINS] {
            // Internal state cleared, as the image does; then the stalls.
            self.world.write_ctrl(b, pioregs::restart_counters(b));
            self.world.blocks[b].clear_fdebug(pioregs::COUNTERS[b] << fdebug::RXSTALL);
        }
        // What the rings held is from before: read from where each DMA
        // channel writes next, set before the counters start, as the image
        // does.
        let d = &mut TwinDma(&mut self.world);
        self.rings.clear_dreq_counts(d);
        self.rings.restart_readers(d);
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(block::POUT, START_COUNTERS);
        self.world.cycle
    }

    fn gen_connect(&mut self, on: bool) {
        let g = pioregs::TEST_GEN_SM;
        self.spend(self.cpu_cycles);
        let pulled = pins::SELF_TEST_PULLED.iter().fold(0u64, |m, g| m | 1 << g);
        if on {
            // As the image: the pull-ups first, then the buffers off.
            self.world.pull_up |= pulled;
            self.world.cpu_wrote(&mut self.chip);
            self.spend(self.cpu_cycles);
            self.world.sio_out |= 1 << pins::CAPTURE_OE;
            self.world.cpu_wrote(&mut self.chip);
            self.spend(self.cpu_cycles);
            let seen = self.world.seen();
            self.world.blocks[0].exec(g, pioregs::force_set(false, 0), seen);
            self.world.blocks[0].exec(g, pioregs::force_set(true, 1), seen);
        } else {
            let seen = self.world.seen();
            self.world.blocks[0].exec(g, pioregs::force_set(true, 0), seen);
            self.world.cpu_wrote(&mut self.chip);
            self.spend(self.cpu_cycles);
            self.world.sio_out &= !(1 << pins::CAPTURE_OE);
            self.world.cpu_wrote(&mut self.chip);
            self.spend(self.cpu_cycles);
            self.world.pull_up &= !pulled;
        }
        self.world.cpu_wrote(&mut self.chip);
    }

    fn gen_start(&mut self, words: [u32; 3]) -> u64 {
        let g = pioregs::TEST_GEN_SM;
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(0, pioregs::TEST_GEN_STOP);
        let regs = pioregs::test_gen(&self.gen);
        // FJOIN flipped and back: the FIFOs flushed, as the image does.
        let blk = &mut self.world.blocks[0];
        blk.write_shiftctrl(g, regs.shiftctrl ^ 1 << pioregs::shiftctrl::FJOIN_RX);
        blk.write_shiftctrl(g, regs.shiftctrl);
        self.world.blocks[0]
            .configure(g, &regs)
            .unwrap_or_else(|e| panic!("the generator's configuration: {e:?}"));
        for w in words {
            self.spend(self.cpu_cycles);
            self.world.blocks[0].txf_write(g, w);
        }
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(0, pioregs::TEST_GEN_RUN);
        self.world.cycle
    }

    fn gen_stop(&mut self) {
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(0, pioregs::TEST_GEN_STOP);
    }

    fn set_input(&mut self, i: usize, high: bool) {
        self.spend(self.cpu_cycles);
        let g = pins::INPUTS[i];
        self.world.sio_out = (self.world.sio_out & !(1 << g)) | u64::from(high) << g;
        self.world.cpu_wrote(&mut self.chip);
    }

    fn set_reset(&mut self, high: bool) {
        self.spend(self.cpu_cycles);
        let g = pins::RESET;
        self.world.sio_out = (self.world.sio_out & !(1 << g)) | u64::from(high) << g;
        self.world.cpu_wrote(&mut self.chip);
    }

    fn read_high_pins(&mut self) -> u16 {
        self.spend(self.cpu_cycles);
        (self.world.pads() >> 32) as u16
    }

    fn read_pins_grid(&mut self, t0: u64, step: u64, slack: u64, n: usize) {
        // A spin on the clock, then the read, as the image's loop.
        let mut grid = core::mem::take(&mut self.grid);
        grid.clear();
        let mut t = t0;
        for _ in 0..n {
            let mut seen = self.cycles();
            while seen < t {
                seen = self.cycles();
            }
            let at = if seen > t + slack { seen } else { t };
            grid.push((at, self.read_high_pins()));
            t = at + step;
        }
        self.grid = grid;
    }

    fn grid_read(&self, k: usize) -> (u64, u16) {
        self.grid.get(k).copied().unwrap_or_default()
    }

    fn idle(&mut self, until: u64) -> u64 {
        // The CPU's loop looks every `idle_step` cycles: it sees the next
        // thing the outside does (a POUT edge, a pin change) on its first
        // pass after, and the pass before saw nothing yet. Or it is `until`.
        use pio::Outside;
        self.spend(0);
        let now = self.world.cycle;
        let step = self.idle_step.max(1);
        let next = self.chip.next_change(now).unwrap_or(u64::MAX);
        let seen = now.saturating_add(next.saturating_sub(now).div_ceil(step).saturating_mul(step));
        let to = until.min(seen).max(now + 1);
        if self.world.blocks[0].sm[pioregs::TEST_GEN_SM].enabled {
            // The self-test generator's edges are the PIO's, not the
            // chip's: the loop sees them as a ring's word, pass by pass.
            let mut at = now;
            while at < to {
                let next = (at + step).min(to);
                self.run_to(next);
                if self.rings.hold_words(&mut TwinDma(&mut self.world)) {
                    return at;
                }
                at = next;
            }
            return to;
        }
        self.run_to(to);
        if to == seen {
            to - step
        } else {
            to
        }
    }
}

/// The capture's margin at the chip's fastest pulse rate, measured on the
/// twin ([`capture_margin`]).
#[derive(Debug, Clone, Copy)]
pub struct CaptureMargin {
    pub sysclk_hz: u32,
    pub pulses: u64,
    /// The move's pulse interval at its top speed.
    pub interval_ns: u64,
    /// Words the POUT counter's DMA ring holds, and the most it held when
    /// the board code looked.
    pub depth: usize,
    pub fullest: usize,
    /// The longest time between two looks that found words.
    pub longest_gap_ns: u64,
    pub lost: bool,
}

impl CaptureMargin {
    /// How many times over the ring could have held what came between two
    /// looks: its depth in pulse intervals, over the longest gap.
    pub fn margin(&self) -> f64 {
        (self.depth as u64 * self.interval_ns) as f64 / self.longest_gap_ns.max(1) as f64
    }
}

/// Runs a 5,000-pulse move in POUT mode at RH = 12 on a chip at SysClk
/// 40 MHz (CSEL high): 10.4 us a pulse, 96 kpps, the fastest under the
/// speed limit of 40 kpps x SysClk / 16 = 100 kpps (Section 3-2), while
/// the board code waits for BUSY = 0 as a scenario does; and says how the
/// board code kept up with the POUT counter's ring.
pub fn capture_margin() -> Result<CaptureMargin, String> {
    use ppmc_core::bus::{Bus, Op};
    use ppmc_core::protocol::Status;
    use ppmc_core::time::Duration;
    let (straps, mut ops) = fastest_move();
    let mut b = board(straps, ModelConfig::default())?;
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: Status::BUSY,
        timeout: Duration::from_millis(5),
    });
    ops.push(Op::AwaitStatus {
        mask: Status::BUSY,
        value: 0,
        timeout: Duration::from_secs(2),
    });
    for op in &ops {
        b.run(*op);
    }
    let pulses = b.record().last_move_pulses().count;
    let hw = b.hal();
    let tclock = straps
        .tclock(ppmc_core::protocol::ClockSource::Internal)
        .ok_or("no internal clock")?;
    Ok(CaptureMargin {
        sysclk_hz: SYSCLK_HZ,
        pulses,
        interval_ns: straps.pulse_interval(12, tclock).as_nanos(),
        depth: RING_WORDS,
        fullest: hw.drains.fullest,
        longest_gap_ns: hw.drains.longest_gap * 1_000_000_000 / u64::from(SYSCLK_HZ),
        lost: b.capture_lost(),
    })
}

/// [`capture_margin`]'s chip (SysClk 40 MHz) and ops, up to the move's
/// last byte: a reset, an initialization (RL 100, RH 12, PA 100), 100 ms,
/// 5,000 pulses with accel/decel in POUT mode.
pub fn fastest_move() -> (Straps, std::vec::Vec<ppmc_core::bus::Op>) {
    use ppmc_core::time::Duration;
    let straps = Straps {
        sysclk_hz: 40_000_000,
        ..Straps::default()
    };
    (
        straps,
        init_and_move(12, Duration::from_millis(100), 0xC3, 5_000),
    )
}

/// Ops: a reset; an initialization (4-phase, RL 100, RH `rh`, PA 100);
/// `settle`; the accel/decel move `command` (0x43 CW, 0xC3 in POUT mode)
/// of `steps` pulses, up to its last byte. Every write waits for IBF = 0,
/// at most 10 ms.
pub fn init_and_move(
    rh: u8,
    settle: ppmc_core::time::Duration,
    command: u8,
    steps: u32,
) -> std::vec::Vec<ppmc_core::bus::Op> {
    use ppmc_core::bus::Op;
    use ppmc_core::time::Duration;
    let wait = Some(Duration::from_millis(10));
    let n = steps - 1;
    let mut ops = std::vec![
        Op::Reset,
        Op::WriteCommand {
            byte: 0x02,
            wait_ibf: wait
        }
    ];
    for byte in [100, rh, 100, 0] {
        ops.push(Op::WriteData {
            byte,
            wait_ibf: wait,
        });
    }
    ops.push(Op::Delay(settle));
    ops.push(Op::WriteCommand {
        byte: command,
        wait_ibf: wait,
    });
    for byte in [n as u8, (n >> 8) as u8, (n >> 16) as u8] {
        ops.push(Op::WriteData {
            byte,
            wait_ibf: wait,
        });
    }
    ops
}

/// The board code on the twin: what `firmware/run-twin` serves.
pub type TwinBoard = crate::board::Board<Twin>;

/// The board code on a fresh twin with the default bus timing.
pub fn board(straps: Straps, cfg: ModelConfig) -> Result<TwinBoard, String> {
    Ok(crate::board::Board::new(
        Twin::new(straps, cfg)?,
        BusTiming::DEFAULT,
        straps,
    ))
}
