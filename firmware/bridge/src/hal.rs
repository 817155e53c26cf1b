//! The thin hardware layer under the bridge's board code ([`crate::board`]):
//! what the board code asks of the RP2350. The RP2350 image implements it
//! with embassy-rp and the PAC (`firmware/rp2350/src/hw.rs`); the board
//! twin implements it with the PIO model ([`crate::twin`]). Everything
//! above it, the same code, runs on both.

/// One of the four edge counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Counter {
    /// POUT's rising edges, with DIR.
    Pout,
    /// INT*, HOLD and AUX*: both edges, with the new level.
    Int,
    Hold,
    Aux,
}

impl Counter {
    pub const ALL: [Counter; 4] = [Counter::Pout, Counter::Int, Counter::Hold, Counter::Aux];

    /// Its place in [`Counter::ALL`]: its DMA channel and ring reader.
    pub const fn index(self) -> usize {
        match self {
            Counter::Pout => 0,
            Counter::Int => 1,
            Counter::Hold => 2,
            Counter::Aux => 3,
        }
    }
}

pub trait Hal {
    /// The system clock's frequency.
    fn sysclk_hz(&self) -> u32;

    /// System clock cycles since boot: cheap (the RP2350 image extends the
    /// core's cycle counter), and exact as long as the core has not slept
    /// since the last [`Hal::resync`].
    fn cycles(&self) -> u64;

    /// The low 32 bits of a clock that counts system clock cycles, to
    /// time spans shorter than 2^31 cycles the cheapest way (on the RP2350
    /// the core's cycle counter itself). Its differences agree with
    /// [`Hal::cycles`]'s; [`Hal::clock_pair`] gives both at one reading.
    fn fine(&self) -> u32 {
        self.cycles() as u32
    }

    /// [`Hal::cycles`] and [`Hal::fine`] at one reading.
    fn clock_pair(&self) -> (u64, u32) {
        let c = self.cycles();
        (c, c as u32)
    }

    /// Sets the clock right again from a source that keeps counting while
    /// the core sleeps (the 1 MHz timer): the board code calls it at every
    /// op and whenever it polls between requests.
    fn resync(&mut self);

    /// FSTAT.TXFULL of the bus player.
    fn bus_tx_full(&mut self) -> bool;

    /// Writes one step to the bus player's TX FIFO; the cycle the word went
    /// in, as closely as the implementation can tell. The board code calls
    /// it only when the FIFO has room: a write to a full FIFO is lost.
    fn bus_push(&mut self, word: u32) -> u64;

    /// [`Hal::bus_push`], stamped on [`Hal::fine`]'s clock.
    fn bus_push_fine(&mut self, word: u32) -> u32 {
        self.bus_push(word) as u32
    }

    /// FSTAT.TXEMPTY of the bus player.
    fn bus_tx_empty(&mut self) -> bool;

    /// A byte the bus player read, if one is waiting.
    fn bus_pull(&mut self) -> Option<u32>;

    /// A word counter `c` pushed, if one is waiting.
    fn capture_pull(&mut self, c: Counter) -> Option<u32>;

    /// The `k`-th word (from 0) counter `c` pushed that is not pulled yet,
    /// if there is one, left where it is: a wait for a pulse finds its
    /// pulse among words not drained yet.
    fn capture_peek(&mut self, c: Counter, k: usize) -> Option<u32>;

    /// The most words any counter has waiting, in its ring, not yet read.
    fn capture_level(&mut self) -> usize;

    /// Whether any counter stalled on a full RX FIFO since the last call
    /// (FDEBUG.RXSTALL, cleared by the call): its count stopped meanwhile.
    fn capture_stalled(&mut self) -> bool;

    /// Stops the four counters, empties their FIFOs, sets their counts to
    /// all ones and their start by each pin's level, and starts them on
    /// one cycle; that cycle.
    fn start_counters(&mut self) -> u64;

    /// Drives the chip's input `i` (`pins::INPUTS` order) to `high`.
    fn set_input(&mut self, i: usize, high: bool);

    /// [`Hal::set_input`] at cycle `at` (or at once, if past): the
    /// register and the bit worked out first, then a spin on the clock,
    /// then the write alone; the cycle just after the write. On the image
    /// on rp2350-emu a spin on [`Hal::cycles`] and the write after it came
    /// 0.5 us late, and the latency probes of Table 3-3 allow 0.3.
    fn set_input_at(&mut self, i: usize, high: bool, at: u64) -> u64 {
        while self.cycles() < at {}
        self.set_input(i, high);
        self.cycles()
    }

    /// Drives RESET* to `high`.
    fn set_reset(&mut self, high: bool);

    /// The levels of GPIO 32-47, bit 0 being GPIO 32.
    fn read_high_pins(&mut self) -> u16;

    /// `n` reads of [`Hal::read_high_pins`] on a grid (at most
    /// [`crate::limits::GRID_SAMPLES`]), kept for [`Hal::grid_read`]: the
    /// first at cycle `t0`, each next `step` cycles after the one before,
    /// or after the cycle the clock said when it was read, if that was
    /// more than `slack` past its time (the CPU came to it late). The
    /// RP2350 spins on its raw cycle counter between reads: a sample costs
    /// it some 15 instructions, where an op of the engine costs it
    /// thousands.
    fn read_pins_grid(&mut self, t0: u64, step: u64, slack: u64, n: usize);

    /// The `k`th read of the last [`Hal::read_pins_grid`]: its cycle and
    /// the levels.
    fn grid_read(&self, k: usize) -> (u64, u16);

    /// Gives the capture inputs of POUT and INT* to the self-test
    /// generator (`on`: CAPTURE_OE* high, the chip's outputs cut off,
    /// then TEST_GEN driven low), or back to the chip (TEST_GEN released,
    /// then CAPTURE_OE* low).
    fn gen_connect(&mut self, on: bool);

    /// Starts a burst of the generator (`programs::test_gen`): stops and
    /// restarts its state machine, writes `words` into its TX FIFO, and
    /// enables it; the cycle it was enabled on.
    fn gen_start(&mut self, words: [u32; 3]) -> u64;

    /// Stops the generator (TEST_GEN keeps its level: low after a burst).
    fn gen_stop(&mut self);

    /// The board code is alive: feeds the watchdog (the RP2350 image). Called
    /// from every loop of the board code that may last.
    fn keepalive(&mut self) {}

    /// Nothing to do before cycle `until` but watch the outputs: returns
    /// at `until`, or soon after a sampled output (S1..S5, AUXO, DIR)
    /// changes or a capture FIFO takes a word, whichever comes first; and
    /// the last cycle it saw the sampled outputs as they were when called,
    /// so that a change is stamped within a pass of a short loop.
    fn idle(&mut self, until: u64) -> u64;
}
