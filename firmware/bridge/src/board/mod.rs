//! The chip on the bridge's pins, as the bridge engine's [`Bus`]: bus
//! cycles through the PIO step player, inputs on GPIO outputs, outputs
//! captured by the PIO edge counters and by sampling, the capture kept as
//! the protocol's record (pulse runs through `EdgeRuns`, move records
//! through `MoveTracker`). The pin map is [`crate::pins`].
//!
//! This is the RP2350 image's board code, over a thin hardware layer
//! ([`Hal`]): the image runs it on the RP2350, the board twin on the PIO
//! model ([`crate::twin`]), so that what the twin proves is this code.
//!
//! Every wait has a deadline: a state machine that never finishes a bus
//! cycle makes the bridge report a hardware fault (protocol error
//! `HARDWARE`), not hang.
//!
//! This file holds the board's state ([`Board`]), its start and its
//! clock; the rest is by concern:
//!
//! - `ops.rs`: the engine's ops ([`Bus`] for [`Board`]), delays that aim
//!   the next op's moment, the chip's reset;
//! - `cycles.rs`: bus cycles through the PIO step player, status and data
//!   reads, writes, waits on a status flag;
//! - `capture.rs`: the edge counters' words drained into the record, the
//!   pin changes kept in time order until no source can precede them;
//! - `outputs.rs`: the outputs the CPU samples, as pin changes and as the
//!   pins a read reports;
//! - `selftest.rs`: the self-test, the generator's bursts into the capture.
//!
//! [`Bus`]: ppmc_core::bus::Bus

mod capture;
mod cycles;
mod ops;
mod outputs;
mod selftest;

use crate::bus_cycle::{BusTiming, StepCounts};
use crate::hal::Hal;
use crate::limits;
use crate::pins;
use crate::timebase;
use alloc::string::String;
use alloc::vec::Vec;
use ppmc_core::bridge::abort::AbortLine;
use ppmc_core::bridge::move_tracker::MoveTracker;
use ppmc_core::bridge::wire::{FastTimer, Timer};
use ppmc_core::bus::{Op, Uncertainty};
use ppmc_core::protocol::{EdgeRuns, OutputRecord, PinEvent, Straps};
use ppmc_core::time::{Duration, Instant};

pub struct Board<H: Hal> {
    hal: H,
    sysclk_hz: u32,
    /// The timer HELLO_REPLY announces, its divisions prepared: the
    /// board code converts between its ticks and nanoseconds in every op.
    timer: FastTimer,
    /// The bus cycles' step counts at this clock (`BusTiming::counts`),
    /// `None` for a timing that does not fit the player (checked at start).
    counts: Option<StepCounts>,
    /// How long before its moment each kind of aimed op must start
    /// ([`Board::lead`]), by [`ops::Lag::ALL`]'s order.
    leads: [u64; 6],
    straps: Straps,
    /// The cycle the edge counters started on.
    started: u64,
    /// Bridge ticks at the last chip reset: time zero of the record.
    epoch: u64,
    record: OutputRecord,
    /// Pin changes not yet in the record, in time order: the record keeps
    /// them in time order, and they come from several sources (the edge
    /// counters, the sampled outputs, BUSY in status reads) at different
    /// delays. Each poll moves those no source can precede any more.
    pending: Vec<PinEvent>,
    /// Ticks of the last sample of the outputs the CPU reads, and of the
    /// last POUT edge taken.
    last_sample: u64,
    last_pulse: u64,
    /// The cycle the bus player will be back at its `pull` with every step
    /// written so far played, as the board code predicts from the steps'
    /// lengths: when the next cycle's steps start, unless they come later.
    player_free: u64,
    /// The moment of the last op (ticks): a write's WR* rise, a read's RD*
    /// fall, an input's change, the pulse an `AwaitPulses` waited for, a
    /// delay's end. A delay counts from it.
    moment: u64,
    /// The op after the one running, in its batch ([`Bus::next_op`]).
    next: Option<Op>,
    /// Where a delay that ended early aims the next op's moment (ticks).
    aim: Option<u64>,
    /// The last batch has ended (the core may sleep before the next: the
    /// clock is set right first). The op running ends its batch when
    /// `next` is `None`.
    batch_done: bool,
    /// Pin samples taken without a poll around them.
    samples: u32,
    /// The longest poll so far (ticks): a delay starts none it cannot end.
    poll_ticks: u64,
    /// RD*'s fall at the last status read (ticks).
    last_status: u64,
    /// The sampled outputs (masked) as last seen, and the last tick they
    /// were seen so.
    last_word: u16,
    unchanged: u64,
    /// Pin reads between polls saw them changed: the first sight of the
    /// levels they saw last (ticks), and those levels.
    changed_by: Option<(u64, u16)>,
    /// The time of the last pin read (ticks).
    last_read: u64,
    /// The widest bracket a sampled output's change has been stamped in
    /// (ticks): from the last sight of the old levels to the first of the
    /// new. Half of it is how sure such a stamp is.
    longest_bracket: u64,
    /// The longest pass of a wait's status loop that ended it (ticks).
    longest_pass: u64,
    /// The last move's pulses counted so far ([`Board::move_pulses`]).
    counted: Counted,
    /// The op before drained the capture as it ended (a wait for a pulse
    /// that came): the next runs without a drain of its own first.
    drained: bool,
    /// A status read the write before played right behind its own cycle,
    /// for the status read that follows it in the batch: its moment
    /// (ticks) and the status ([`Board::write`]).
    early_status: Option<(u64, ppmc_core::protocol::Status)>,
    /// A byte written since the last status read: a move may have begun
    /// that `busy` does not know of yet.
    wrote: bool,

    edges: EdgeRuns,
    tracker: MoveTracker,
    /// Last sampled S1..S5 levels, AUXO levels and DIR, for changes.
    last_s: u8,
    last_auxo: u8,
    last_dir: bool,
    busy: bool,
    lost: bool,
    /// Stop switching seen: the phases chopping on and off while stopped.
    switching: bool,
    /// When S1..S5 last went all off or came back from it while the chip
    /// may chop them (ticks).
    last_toggle: Option<u64>,
    /// The energized pattern the record last gave (S, pin code 6): a
    /// change is recorded only when the value changes.
    recorded_s: u8,
    /// The bridge's own hardware failed: what.
    fault: Option<String>,
    /// Capture overruns since boot (each restarted the counters).
    pub overruns: u32,
    /// Raised when the host's ABORT arrives: every wait ends at its next
    /// pass (`docs/bridge-protocol.md` section 5).
    abort: Option<AbortLine>,
}

impl<H: Hal> core::fmt::Debug for Board<H> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Board")
            .field("timer", &self.timer)
            .field("straps", &self.straps)
            .field("started", &self.started)
            .field("epoch", &self.epoch)
            .field("busy", &self.busy)
            .field("lost", &self.lost)
            .field("fault", &self.fault)
            .finish_non_exhaustive()
    }
}

impl<H: Hal> Board<H> {
    /// Whether the host's ABORT came for the request running: a wait ends.
    pub(super) fn aborted(&self) -> bool {
        self.abort.as_ref().is_some_and(AbortLine::pending)
    }

    /// The board code over `hal`: starts the edge counters and samples the
    /// outputs.
    pub fn new(mut hal: H, timing: BusTiming, straps: Straps) -> Board<H> {
        let sysclk_hz = hal.sysclk_hz();
        let timer = FastTimer::new(Timer {
            hz: timebase::timer_hz(sysclk_hz),
        });
        let started = hal.start_counters();
        let epoch = hal.cycles() / 2;
        let mut bus = Board {
            hal,
            sysclk_hz,
            timer,
            counts: timing.counts(sysclk_hz).ok(),
            leads: [0; 6],
            straps,
            started,
            epoch,
            record: OutputRecord::default(),
            pending: Vec::new(),
            last_sample: 0,
            last_pulse: 0,
            player_free: 0,
            moment: epoch,
            next: None,
            aim: None,
            poll_ticks: 0,
            samples: 0,
            batch_done: true,
            last_status: epoch,
            last_word: 0,
            unchanged: epoch,
            changed_by: None,
            last_read: epoch,
            longest_bracket: 0,
            longest_pass: 0,
            counted: Counted::default(),
            drained: false,
            early_status: None,
            wrote: false,

            edges: EdgeRuns::new(timer.edge_tolerance()),
            tracker: MoveTracker::new(),
            last_s: 0,
            last_auxo: 0,
            last_dir: false,
            busy: false,
            lost: false,
            switching: false,
            last_toggle: None,
            recorded_s: 0,
            fault: None,
            overruns: 0,
            abort: None,
        };
        bus.leads = ops::Lag::ALL.map(|k| bus.work_out_lead(k));
        let word = bus.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let now = bus.now_ticks();
        bus.sample(word, bus.at(now), now, false, None);
        bus.last_word = word;
        bus
    }

    /// The timer HELLO_REPLY announces.
    pub fn timer(&self) -> Timer {
        self.timer.timer()
    }

    /// How sure this board's times are, by path (HELLO_REPLY's
    /// `uncertainty`): a captured edge to the timer's tick (the engine's
    /// floor); an access within a pass of the spin that aims it
    /// and the read itself (`ops::ACCESS_TICKS`); a sampled output's change within half the
    /// widest bracket the sampling allows ([`limits::SAMPLE_BRACKET_NS`]);
    /// a polled flag within half a pass of the status loop
    /// (`cycles::CLOSE_NS`). The twin's tests hold the board code to the
    /// last two ([`Board::longest_bracket`], [`Board::longest_pass`]).
    pub fn uncertainty(&self) -> Uncertainty {
        Uncertainty {
            edge: Duration::ZERO,
            access: Duration::from_nanos(self.timer.to_nanos_up(ops::ACCESS_TICKS)),
            sampled: Duration::from_nanos(limits::SAMPLE_BRACKET_NS / 2),
            polled: Duration::from_nanos(cycles::CLOSE_NS / 2),
        }
    }

    /// The widest bracket a change of a sampled output was stamped in
    /// since boot.
    pub fn longest_bracket(&self) -> Duration {
        Duration::from_nanos(self.timer.to_nanos_up(self.longest_bracket))
    }

    /// The longest pass of a wait's status loop, since boot.
    pub fn longest_pass(&self) -> Duration {
        Duration::from_nanos(self.timer.to_nanos_up(self.longest_pass))
    }

    /// The hardware layer (the twin's tests look through it).
    pub fn hal(&self) -> &H {
        &self.hal
    }

    pub fn hal_mut(&mut self) -> &mut H {
        &mut self.hal
    }

    /// The record's time of system clock cycle `cycle`.
    pub fn time_of_cycle(&self, cycle: u64) -> Instant {
        self.at(cycle / 2)
    }

    /// Ticks to the record's time.
    fn at(&self, ticks: u64) -> Instant {
        record_time(self.timer, self.epoch, ticks)
    }

    fn now_ticks(&self) -> u64 {
        self.hal.cycles() / 2
    }

    fn deadline(&self, d: Duration) -> u64 {
        self.now_ticks() + self.timer.to_ticks(d.as_nanos())
    }
}

/// The pulses of the last move's closed runs, as far as counted: a wait
/// for a pulse asks after every drain, and a move's ramp is a run per
/// pulse, so counting them all each time (`last_move_pulses`) cost some
/// 20 cycles a run: 100 us of a Cortex-M33's time by pulse 700, during
/// which the wait saw nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Counted {
    /// The move (its index, its first run) the count is of.
    moves: usize,
    first_run: usize,
    /// Runs `first_run..upto` are counted, in `pulses`.
    upto: usize,
    pulses: u64,
}

impl<H: Hal> Board<H> {
    /// The last move's pulses so far (`OutputRecord::last_move_pulses`'s
    /// count), counting only the runs closed since the last call: the
    /// last run may still grow.
    pub(crate) fn move_pulses(&mut self) -> u64 {
        let runs = &self.record.runs;
        let first_run = self.record.moves.last().map_or(0, |m| m.first_run);
        let c = &mut self.counted;
        if c.moves != self.record.moves.len()
            || c.first_run != first_run
            || c.upto > runs.len()
            || c.upto < first_run
        {
            *c = Counted {
                moves: self.record.moves.len(),
                first_run,
                upto: first_run,
                pulses: 0,
            };
        }
        let closed = runs.len().saturating_sub(1).max(c.upto);
        for r in &runs[c.upto..closed] {
            c.pulses += u64::from(r.count);
        }
        c.upto = closed;
        c.pulses
            + runs[closed..]
                .iter()
                .map(|r| u64::from(r.count))
                .sum::<u64>()
    }
}

/// Bridge ticks as the record's time: since `epoch`, the last chip reset.
fn record_time(timer: FastTimer, epoch: u64, ticks: u64) -> Instant {
    Instant::from_nanos(timer.to_nanos(ticks.saturating_sub(epoch)))
}
