//! The RP2350's side of the bridge's hardware layer ([`Hal`]): the PIO
//! blocks written register by register from `ppmc_bridge_fw::pioregs`
//! (the values the board twin runs), GPIOs through the SIO, and the clock
//! from the cycle counter and the always-running timer
//! (`ppmc_bridge_fw::clock`).
//!
//! The PIO state machines are configured through the PAC, not embassy-rp's
//! `Config`: embassy-rp 0.10 writes the JMP pin unrelative to GPIOBASE
//! (embassy-rs/embassy#5498), which would have the edge counters of PIO1
//! and PIO2 watch GPIO 16-20. embassy-rp still claims the pins (FUNCSEL,
//! input enable) and owns the blocks.

use core::cell::{RefCell, UnsafeCell};
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::DWT;
use embassy_rp::pac;
use embassy_rp::pac::pio::regs::{
    Ctrl, Fdebug, SmClkdiv, SmExecctrl, SmInstr, SmPinctrl, SmShiftctrl,
};
use ppmc_bridge_fw::clock::Clock;
use ppmc_bridge_fw::dma::{self, DmaRegs, Rings};
use ppmc_bridge_fw::hal::{Counter, Hal};
use ppmc_bridge_fw::limits::GRID_SAMPLES;
use ppmc_bridge_fw::pins;
use ppmc_bridge_fw::pioregs::{self, fdebug, shiftctrl, SmRegs, START_COUNTERS, STOP_COUNTERS};
use ppmc_bridge_fw::programs::Loaded;
use ppmc_bridge_fw::ring::RING_WORDS;

/// The three PIO blocks, by index.
fn pio(b: usize) -> pac::pio::Pio {
    match b {
        0 => pac::PIO0,
        1 => pac::PIO1,
        _ => pac::PIO2,
    }
}

/// Loads `p` at address `origin` of block `b` (already relocated there)
/// and sets the block's GPIOBASE. Each block holds one program at 0, and
/// PIO0 the self-test's generator after it (`ppmc_bridge_fw::programs`),
/// so nothing else is there.
pub fn load(b: usize, p: &Loaded, origin: u8) {
    let block = pio(b);
    for (i, w) in p.words().iter().enumerate() {
        block
            .instr_mem(usize::from(origin) + i)
            .write_value(pac::pio::regs::InstrMem(u32::from(*w)));
    }
    block
        .gpiobase()
        .write_value(pac::pio::regs::Gpiobase(pioregs::block::GPIOBASE[b]));
}

/// Writes the registers of state machine `s` of block `b`, then forces its
/// start instructions. The state machine must be disabled.
pub fn configure(b: usize, s: usize, regs: &SmRegs) {
    let sm = pio(b).sm(s);
    sm.clkdiv().write_value(SmClkdiv(regs.clkdiv));
    sm.execctrl().write_value(SmExecctrl(regs.execctrl));
    // FJOIN flipped, then as wanted: both FIFOs flushed.
    sm.shiftctrl()
        .write_value(SmShiftctrl(regs.shiftctrl ^ 1 << shiftctrl::FJOIN_RX));
    sm.shiftctrl().write_value(SmShiftctrl(regs.shiftctrl));
    sm.pinctrl().write_value(SmPinctrl(regs.pinctrl));
    for w in regs.start_instructions() {
        sm.instr().write_value(SmInstr(u32::from(w)));
    }
}

/// Sets the levels, then the directions, of `mask` (GPIO 0-12) on PIO0
/// SM0 with forced `set` instructions, five pins at a time.
pub fn bus_pins(levels: u32, dirs: u32, mask: u32) {
    let sm = pio(0).sm(0);
    let saved = sm.pinctrl().read();
    for (value, pindirs) in [(levels, false), (dirs, true)] {
        let mut g = 0;
        while g < 13 {
            let n = (13 - g).min(5);
            let chunk = (value >> g) & ((1 << n) - 1);
            let m = (mask >> g) & ((1 << n) - 1);
            if m != 0 {
                sm.pinctrl().write_value(SmPinctrl(
                    g << pioregs::pinctrl::SET_BASE | n << pioregs::pinctrl::SET_COUNT,
                ));
                // set pins / set pindirs, data = the chunk.
                let dest = if pindirs { 0b100 } else { 0b000 };
                sm.instr()
                    .write_value(SmInstr(0b111 << 13 | dest << 5 | chunk));
            }
            g += n;
        }
    }
    sm.pinctrl().write_value(saved);
}

/// A ring a DMA channel writes a counter's words into
/// (`ppmc_bridge_fw::ring`), aligned to its size as `RING_SIZE` needs.
#[repr(C, align(1024))]
struct Ring(UnsafeCell<[u32; RING_WORDS]>);

// SAFETY: the DMA writes a ring and only core 1's board code reads it,
// with volatile reads of whole words (`Rp2350::word`).
unsafe impl Sync for Ring {}

const _: () = assert!(core::mem::align_of::<Ring>() == RING_WORDS * 4);

static RINGS: [Ring; 4] = [const { Ring(UnsafeCell::new([0; RING_WORDS])) }; 4];

/// The reads of a run of pin samples (`Hal::read_pins_grid`): each its
/// cycle from the run's start and the levels of GPIO 32-47. A static, not
/// the heap, whose every byte `ppmc_bridge_fw::limits` has counted.
struct Grid(UnsafeCell<[(u32, u16); GRID_SAMPLES]>);

// SAFETY: only core 1's board code reads and writes it, one call at a
// time.
unsafe impl Sync for Grid {}

static GRID: Grid = Grid(UnsafeCell::new([(0, 0); GRID_SAMPLES]));

/// The DMA block's registers and the rings, as the board code reaches them
/// (`ppmc_bridge_fw::dma`, which the board twin runs too): channels 0-3,
/// one a counter in `Counter::ALL` order; main.rs claims them from
/// embassy-rp so that nothing else takes them.
struct RpDma;

impl DmaRegs for RpDma {
    fn read(&mut self, offset: usize) -> u32 {
        // SAFETY: `offset` is one of `ppmc_bridge_fw::dma::reg`'s, inside
        // the DMA block; a register is read whole.
        unsafe {
            core::ptr::read_volatile((pac::DMA.as_ptr() as *mut u8).add(offset) as *const u32)
        }
    }

    fn write(&mut self, offset: usize, value: u32) {
        // SAFETY: as `read`; only this module writes channels 0-3.
        unsafe {
            core::ptr::write_volatile(
                (pac::DMA.as_ptr() as *mut u8).add(offset) as *mut u32,
                value,
            )
        }
    }

    fn ring_word(&mut self, channel: usize, i: usize) -> u32 {
        let ring = RINGS[channel].0.get() as *const u32;
        // SAFETY: `i % RING_WORDS` is inside the ring, and a whole aligned
        // word is read at once, whatever the DMA does.
        unsafe { core::ptr::read_volatile(ring.add(i % RING_WORDS)) }
    }

    fn set_ring_word(&mut self, channel: usize, i: usize, value: u32) {
        let ring = RINGS[channel].0.get() as *mut u32;
        // SAFETY: inside the ring; the board code writes only the slot the
        // DMA wrote last (the canary), not the one it writes next.
        unsafe { core::ptr::write_volatile(ring.add(i % RING_WORDS), value) }
    }
}

/// The four rings' channels, each from its counter's RX FIFO into its ring
/// (`ppmc_bridge_fw::dma::counter_channel`).
fn rings() -> Rings {
    Rings::new(Counter::ALL.map(|c| dma::counter_channel(c, RINGS[c.index()].0.get() as u32)))
}

/// Starts the four DMA channels (at boot), each moving its counter's RX
/// FIFO into its ring for ever, paced by the FIFO's DREQ
/// (`ppmc_bridge_fw::dma::Rings::start`). The counters need not run: a
/// channel waits for its DREQ.
pub fn start_rings() {
    rings().start(&mut RpDma);
}

/// The RP2350's PIO, SIO and clock as the board code's hardware layer.
pub struct Rp2350 {
    sysclk_hz: u32,
    clock: RefCell<Clock>,
    counters: [Loaded; 2],
    /// The self-test generator, as loaded in PIO0.
    gen: Loaded,
    /// Core 0's heartbeat as last seen, and when (cycles).
    beat: (u32, u64),
    /// The counters' rings: their channels, and the CPU's side of each.
    rings: Rings,
    /// The cycle the last run of pin samples counted from (`GRID`).
    grid_base: u64,
}

/// Core 0's heartbeat: it counts up every 100 ms while core 0's executor
/// runs (`main.rs`); core 1 feeds the watchdog only while it moves.
pub static HEARTBEAT: AtomicU32 = AtomicU32::new(0);

impl core::fmt::Debug for Rp2350 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Rp2350")
            .field("sysclk_hz", &self.sysclk_hz)
            .finish_non_exhaustive()
    }
}

fn now_us() -> u64 {
    embassy_time::Instant::now().as_micros()
}

/// The watchdog's period: the board code feeds it from every loop
/// (`Hal::keepalive`), so only a loop that stopped lets it fire.
pub const WATCHDOG_MS: u64 = 1_000;
// LOAD holds 24 bits of microseconds.
const _: () = assert!(WATCHDOG_MS * 1_000 <= 0xFF_FFFF);

impl Rp2350 {
    /// Reads the cycle counter and the timer together and sets the clock
    /// by them (`ppmc_bridge_fw::clock`). Out of line: [`Hal::cycles`]
    /// needs it once in seven seconds.
    #[cold]
    #[inline(never)]
    fn update(&self) -> u64 {
        self.update_pair().0
    }

    /// [`Rp2350::update`], and the cycle counter's reading it was set at.
    #[cold]
    #[inline(never)]
    fn update_pair(&self) -> (u64, u32) {
        let (fine, us) = cortex_m::interrupt::free(|_| (DWT::cycle_count(), now_us()));
        (self.clock.borrow_mut().update(fine, us), fine)
    }

    /// The hardware layer, with the cycle counter running (`start`) and
    /// the counters' programs (PIO1's and PIO2's) loaded.
    pub fn new(sysclk_hz: u32, pout: Loaded, pins_: Loaded, gen: Loaded) -> Rp2350 {
        Rp2350 {
            sysclk_hz,
            clock: RefCell::new(Clock::new(sysclk_hz, DWT::cycle_count(), now_us(), 0)),
            counters: [pout, pins_],
            gen,
            beat: (HEARTBEAT.load(Ordering::Relaxed), 0),
            rings: rings(),
            grid_base: 0,
        }
    }

    /// The cycle of the register write just before the call: the clock
    /// now, less the cycles since. The counters' start and the
    /// generator's are stamped alike, so that what the self-test measures
    /// between them is the capture's, not a difference in stamping.
    #[inline(always)]
    fn stamp(&self) -> u64 {
        let after = DWT::cycle_count();
        let now = self.cycles();
        now - u64::from(DWT::cycle_count().wrapping_sub(after))
    }

    /// Pull-ups on the capture inputs the self-test leaves undriven (DIR,
    /// HOLD, AUX*, S1..S5, AUXO0..3) while the 74LVC245s' outputs are
    /// off, so that they hold still (RP2350-E9: a floating input pad
    /// drifts; a pull-up still holds it); off again after.
    fn hold_undriven(on: bool) {
        for g in pins::SELF_TEST_PULLED {
            pac::PADS_BANK0.gpio(g as usize).modify(|w| {
                w.set_pue(on);
                w.set_pde(false);
            });
        }
    }

    fn sio_set(g: u32, high: bool) {
        let bank = (g / 32) as usize;
        let bit = 1 << (g % 32);
        if high {
            pac::SIO.gpio_out(bank).value_set().write_value(bit);
        } else {
            pac::SIO.gpio_out(bank).value_clr().write_value(bit);
        }
    }
}

impl Hal for Rp2350 {
    fn sysclk_hz(&self) -> u32 {
        self.sysclk_hz
    }

    // Inlined, as the bus ops' hot loops read the clock at every pass:
    // out of line it cost 49 cycles a call (its registers saved and
    // restored) on the image on rp2350-emu, where ten calls made half of
    // a status wait's pass.
    #[inline(always)]
    fn cycles(&self) -> u64 {
        if let Some(c) = self.clock.borrow().extend(DWT::cycle_count()) {
            return c;
        }
        self.update()
    }

    #[inline(always)]
    fn fine(&self) -> u32 {
        DWT::cycle_count()
    }

    #[inline(always)]
    fn clock_pair(&self) -> (u64, u32) {
        let fine = DWT::cycle_count();
        match self.clock.borrow().extend(fine) {
            Some(c) => (c, fine),
            None => self.update_pair(),
        }
    }

    fn resync(&mut self) {
        self.update();
    }

    #[inline]
    fn bus_tx_full(&mut self) -> bool {
        pio(0).fstat().read().txfull() & 1 != 0
    }

    #[inline]
    fn bus_push(&mut self, word: u32) -> u64 {
        pio(0).txf(0).write_value(word);
        self.stamp()
    }

    #[inline(always)]
    fn bus_push_fine(&mut self, word: u32) -> u32 {
        pio(0).txf(0).write_value(word);
        DWT::cycle_count()
    }

    #[inline]
    fn bus_tx_empty(&mut self) -> bool {
        pio(0).fstat().read().txempty() & 1 != 0
    }

    #[inline]
    fn bus_pull(&mut self) -> Option<u32> {
        (pio(0).fstat().read().rxempty() & 1 == 0).then(|| pio(0).rxf(0).read())
    }

    fn capture_pull(&mut self, c: Counter) -> Option<u32> {
        self.rings.pull(&mut RpDma, c.index())
    }

    fn capture_peek(&mut self, c: Counter, k: usize) -> Option<u32> {
        self.rings.peek(&mut RpDma, c.index(), k)
    }

    fn capture_level(&mut self) -> usize {
        self.rings.fullest(&mut RpDma)
    }

    fn capture_stalled(&mut self) -> bool {
        // A ring the DMA came round on, or a channel that stopped (a bus
        // error halts one: re-armed, the capture lost), or (should the DMA
        // ever fall behind) a counter that stalled on its full FIFO.
        let lost = self.rings.take_lost(&mut RpDma);
        let pout = 1 << fdebug::RXSTALL;
        let others = 0b0111 << fdebug::RXSTALL;
        let stalled =
            lost || pio(1).fdebug().read().0 & pout != 0 || pio(2).fdebug().read().0 & others != 0;
        pio(1).fdebug().write_value(Fdebug(pout));
        pio(2).fdebug().write_value(Fdebug(others));
        stalled
    }

    fn start_counters(&mut self) -> u64 {
        pio(1).ctrl().write_value(Ctrl(STOP_COUNTERS));
        // Stopped, the counters push nothing more; the DMA takes what is
        // in their FIFOs within some cycles (bounded: a channel a bus error
        // halted never would). Flushing a FIFO the DMA still counts on
        // would put channel and FIFO out of step (datasheet 12.6.4.2).
        let pout_sm = 1u32;
        let others = 0b0111u32;
        for _ in 0..1_000 {
            let empty1 = pio(1).fstat().read().rxempty() as u32 & pout_sm == pout_sm;
            let empty2 = pio(2).fstat().read().rxempty() as u32 & others == others;
            if empty1 && empty2 {
                break;
            }
        }
        let high = |g: u32| pac::SIO.gpio_in((g / 32) as usize).read() >> (g % 32) & 1 == 1;
        let pout = pioregs::pout_counter(&self.counters[0], high(pins::POUT));
        let others = pioregs::pin_counters(
            &self.counters[1],
            [pins::INT, pins::HOLD, pins::AUX].map(high),
        );
        configure(1, 0, &pout);
        for (s, regs) in others.iter().enumerate() {
            configure(2, s, regs);
        }
        // Restart the state machines' internal state (ISR, delay), stopped.
        pio(1)
            .ctrl()
            .write_value(Ctrl(1 << pioregs::ctrl::SM_RESTART));
        pio(2)
            .ctrl()
            .write_value(Ctrl(0b0111 << pioregs::ctrl::SM_RESTART));
        pio(1).fdebug().write_value(Fdebug(1 << fdebug::RXSTALL));
        pio(2)
            .fdebug()
            .write_value(Fdebug(0b0111 << fdebug::RXSTALL));
        // Each channel's DREQ count cleared (the FIFOs are empty): the
        // handshake starts afresh with the counters. What the rings held
        // is from before: read from where each DMA channel writes next,
        // before the first edge can come.
        self.rings.clear_dreq_counts(&mut RpDma);
        self.rings.restart_readers(&mut RpDma);
        cortex_m::interrupt::free(|_| {
            pio(1).ctrl().write_value(Ctrl(START_COUNTERS));
            self.stamp()
        })
    }

    fn gen_connect(&mut self, on: bool) {
        let sm = pio(0).sm(pioregs::TEST_GEN_SM);
        let force = |w: u16| sm.instr().write_value(SmInstr(u32::from(w)));
        if on {
            // The chip's outputs off the capture inputs first, then
            // TEST_GEN driven low (docs/bridge-hardware.md).
            Self::hold_undriven(true);
            Self::sio_set(pins::CAPTURE_OE, true);
            force(pioregs::force_set(false, 0));
            force(pioregs::force_set(true, 1));
        } else {
            force(pioregs::force_set(true, 0));
            Self::sio_set(pins::CAPTURE_OE, false);
            Self::hold_undriven(false);
        }
    }

    fn gen_start(&mut self, words: [u32; 3]) -> u64 {
        let s = pioregs::TEST_GEN_SM;
        pio(0).ctrl().write_value(Ctrl(pioregs::TEST_GEN_STOP));
        configure(0, s, &pioregs::test_gen(&self.gen));
        for w in words {
            pio(0).txf(s).write_value(w);
        }
        cortex_m::interrupt::free(|_| {
            pio(0).ctrl().write_value(Ctrl(pioregs::TEST_GEN_RUN));
            self.stamp()
        })
    }

    fn gen_stop(&mut self) {
        pio(0).ctrl().write_value(Ctrl(pioregs::TEST_GEN_STOP));
    }

    fn set_input(&mut self, i: usize, high: bool) {
        Self::sio_set(pins::INPUTS[i], high);
    }

    fn set_input_at(&mut self, i: usize, high: bool, at: u64) -> u64 {
        let g = pins::INPUTS[i];
        let out = pac::SIO.gpio_out((g / 32) as usize);
        let reg = if high {
            out.value_set()
        } else {
            out.value_clr()
        };
        let bit = 1 << (g % 32);
        let (now, f0) = self.clock_pair();
        let wait = at.saturating_sub(now).min(1 << 30) as u32;
        while DWT::cycle_count().wrapping_sub(f0) < wait {}
        reg.write_value(bit);
        now + u64::from(DWT::cycle_count().wrapping_sub(f0))
    }

    fn read_pins_grid(&mut self, t0: u64, step: u64, slack: u64, n: usize) {
        // On the cycle counter from one reading of the clock: the grid
        // spans at most a few milliseconds (`Board::sample_run`).
        let (now, f0) = self.clock_pair();
        self.grid_base = now;
        let (step, slack) = (step.min(1 << 30) as u32, slack.min(1 << 30) as u32);
        let mut t = t0.saturating_sub(now).min(1 << 30) as u32;
        let gpio = pac::SIO.gpio_in(1);
        // SAFETY: only core 1's board code uses the grid, one call at a
        // time (`GRID`).
        let grid = unsafe { &mut *GRID.0.get() };
        for o in grid.iter_mut().take(n) {
            let seen = loop {
                let c = DWT::cycle_count().wrapping_sub(f0);
                if c >= t {
                    break c;
                }
            };
            let word = gpio.read() as u16;
            let at = if seen > t + slack { seen } else { t };
            *o = (at, word);
            t = at + step;
        }
    }

    fn grid_read(&self, k: usize) -> (u64, u16) {
        // SAFETY: as in `read_pins_grid`.
        let grid = unsafe { &*GRID.0.get() };
        grid.get(k)
            .map_or((0, 0), |&(at, word)| (self.grid_base + u64::from(at), word))
    }

    fn set_reset(&mut self, high: bool) {
        Self::sio_set(pins::RESET, high);
    }

    fn read_high_pins(&mut self) -> u16 {
        (pac::SIO.gpio_in(1).read() & 0xFFFF) as u16
    }

    fn keepalive(&mut self) {
        // Fed only while core 0 is alive too: its heartbeat moved within
        // half the watchdog's period. A core that stopped, either, lets the
        // watchdog restart the bridge.
        let beat = HEARTBEAT.load(Ordering::Relaxed);
        let now = self.cycles();
        if beat != self.beat.0 {
            self.beat = (beat, now);
        }
        let half = WATCHDOG_MS / 2 * u64::from(self.sysclk_hz / 1_000);
        if now.saturating_sub(self.beat.1) > half {
            return;
        }
        // As embassy-rp's `Watchdog::feed`: the count, in microseconds.
        pac::WATCHDOG
            .load()
            .write_value(pac::watchdog::regs::Load(WATCHDOG_MS as u32 * 1_000));
    }

    fn idle(&mut self, until: u64) -> u64 {
        // A tight loop on the sampled outputs and the rings: a change, or
        // a word not yet read, is seen within a pass (some 40 cycles). The cycle
        // counter's raw value marks the last pass that saw nothing.
        let sampled = u32::from(pins::SAMPLED_HIGH);
        let seen = pac::SIO.gpio_in(1).read() & sampled;
        let start = DWT::cycle_count();
        // The cycles to `until`, counted on the raw cycle counter every
        // pass (a pass is some 20 cycles: the end is met to within one).
        let budget = until.saturating_sub(self.cycles()).min(1 << 30) as u32;
        let mut quiet = start;
        let mut passes: u32 = 0;
        loop {
            if pac::SIO.gpio_in(1).read() & sampled != seen || self.rings.hold_words(&mut RpDma) {
                let now = self.cycles();
                return now - u64::from(DWT::cycle_count().wrapping_sub(quiet));
            }
            quiet = DWT::cycle_count();
            if quiet.wrapping_sub(start) >= budget {
                return self.cycles();
            }
            passes = passes.wrapping_add(1);
            if passes.is_multiple_of(4096) {
                self.keepalive();
            }
        }
    }
}
