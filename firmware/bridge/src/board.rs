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

use crate::bus::{self, BusTiming, Cycle};
use crate::hal::{Counter, Hal};
use crate::pins;
use crate::programs::{self, TEST_GEN_LEAD};
use crate::{limits, timebase};
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use ppmc_core::bridge::move_tracker::MoveTracker;
use ppmc_core::bridge::wire::Timer;
use ppmc_core::bus::{Bus, Op, Reply, SelfTestPlan, SelfTestReply};
use ppmc_core::protocol::{
    Direction, EdgeRuns, Input as ChipInput, OutputLogic, Pin, PinEvent, Pins, Record, Status,
    Straps,
};
use ppmc_core::time::{Duration, Instant};

/// The longest a bus cycle may take before the bridge calls its player
/// stuck: 1 ms (a cycle of the longest steps takes 35 us at 150 MHz).
const CYCLE_DEADLINE_US: u64 = 1_000;

/// An edge counter has pushed its word within this many ticks of the edge
/// (16 system clock cycles: the 2-cycle input synchroniser, a pass of the
/// counter's loop, the push), so a drain that starts after a tick has
/// every edge from before it, less this.
const SETTLE_TICKS: u64 = 8;

/// What the code between a delay's end and the next op's moment may take,
/// beyond the op's bus cycles, so that the op can aim its moment at the
/// delay's end ([`Board::lead`]).
const CPU_LEAD_US: u64 = 2;

/// The most records the board code keeps between chip resets: the
/// capture's capacity and what one op may add beyond it
/// ([`limits::OP_RECORDS`]). Past it, edges and pin changes are dropped,
/// and the engine answers CAPTURE_OVERRUN (the record holds more than the
/// capacity): a chip that pulses without end cannot exhaust the heap.
const MOST_RECORDS: usize = limits::CAPTURE_RECORDS as usize + limits::OP_RECORDS;

/// The longest self-test the board runs in one request (cycles at most
/// 2^40: two hours at 150 MHz; the host asks for far less).
const SELF_TEST_MOST_CYCLES: u64 = 1 << 40;

/// Time enough for a look at the capture FIFOs' levels (ticks: 32 cycles).
const LOOK_TICKS: u64 = 16;

/// The step an aimed cycle starts with: the bus left idle for 47 cycles,
/// time enough for the CPU to write the wait step after it.
const ANCHOR: u32 = bus::step(0xFF, bus::IDLE, false, 40);

pub struct Board<H: Hal> {
    hal: H,
    sysclk_hz: u32,
    timer: Timer,
    timing: BusTiming,
    straps: Straps,
    /// The cycle the edge counters started on.
    started: u64,
    /// Bridge ticks at the last chip reset: time zero of the record.
    epoch: u64,
    record: Record,
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
    /// How long the last poll took (ticks).
    poll_ticks: u64,
    /// RD*'s fall at the last status read (ticks).
    last_status: u64,
    /// The sampled outputs (masked) as last seen, and the last tick they
    /// were seen so.
    last_word: u16,
    unchanged: u64,
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
    /// When S1..S5 last went all off or came back from it (ticks).
    last_toggle: u64,
    /// The bridge's own hardware failed: what.
    fault: Option<String>,
    /// Capture overruns since boot (each restarted the counters).
    pub overruns: u32,
}

/// Phases that go off and on again within this (ticks at 75 MHz: 1 ms)
/// are being chopped (stop switching), not switched.
const CHOP_TICKS: u64 = 75_000;

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

/// The kinds of op a delay ends early for ([`Bus::next_op`]), to aim
/// their moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Lag {
    /// A write that waits for IBF = 0 (a status read first).
    WriteAfterIbf,
    Write,
    /// A read that waits for OBF = 1.
    ReadAfterObf,
    Read,
    Input,
    /// A pin sample.
    Pins,
}

impl Lag {
    fn of(op: Op) -> Option<Lag> {
        Some(match op {
            Op::WriteCommand { wait_ibf, .. } | Op::WriteData { wait_ibf, .. } => {
                if wait_ibf.is_some() {
                    Lag::WriteAfterIbf
                } else {
                    Lag::Write
                }
            }
            Op::ReadData { wait_obf: Some(_) } => Lag::ReadAfterObf,
            Op::ReadData { wait_obf: None } | Op::ReadStatus => Lag::Read,
            Op::SetInput { .. } => Lag::Input,
            Op::ReadPins => Lag::Pins,
            _ => return None,
        })
    }
}

fn level(asserted: bool) -> bool {
    // The chip's inputs are active low: asserted is low.
    !asserted
}

/// S1..S5 (S1 in bit 4), AUXO0..3 asserted (bit i: AUXOi) and DIR, from
/// [`Hal::read_high_pins`]'s word.
fn sampled_levels(word: u16) -> (u8, u8, bool) {
    let s = pins::S
        .iter()
        .fold(0u8, |v, g| v << 1 | u8::from(high(word, *g)));
    let auxo = pins::AUXO
        .iter()
        .enumerate()
        .fold(0u8, |v, (i, g)| v | u8::from(!high(word, *g)) << i);
    (s, auxo, high(word, pins::DIR))
}

/// GPIO `g` (32-47) in [`Hal::read_high_pins`]'s word.
fn high(word: u16, g: u32) -> bool {
    word >> (g - 32) & 1 == 1
}

impl<H: Hal> Board<H> {
    /// The board code over `hal`: starts the edge counters and samples the
    /// outputs.
    pub fn new(mut hal: H, timing: BusTiming, straps: Straps) -> Board<H> {
        let sysclk_hz = hal.sysclk_hz();
        let timer = Timer {
            hz: timebase::timer_hz(sysclk_hz),
        };
        let started = hal.start_counters();
        let epoch = hal.cycles() / 2;
        let mut bus = Board {
            hal,
            sysclk_hz,
            timer,
            timing,
            straps,
            started,
            epoch,
            record: Record::default(),
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
            edges: EdgeRuns::new(timer.edge_tolerance()),
            tracker: MoveTracker::new(),
            last_s: 0,
            last_auxo: 0,
            last_dir: false,
            busy: false,
            lost: false,
            switching: false,
            last_toggle: 0,
            fault: None,
            overruns: 0,
        };
        let word = bus.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let now = bus.now_ticks();
        bus.sample(word, bus.at(now), now, false);
        bus.last_word = word;
        bus
    }

    /// The timer HELLO_REPLY announces.
    pub fn timer(&self) -> Timer {
        self.timer
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

    /// Takes what the capture holds: the outputs the CPU samples, then the
    /// edge words from the PIO counters (an edge from before the sample is
    /// in its FIFO by then), and moves into the record the pin changes no
    /// source can precede any more. Called between ops, in every wait, and
    /// while the bridge waits for the host.
    pub fn poll(&mut self) {
        // Called between requests, when the core may have slept.
        self.hal.resync();
        self.refresh();
    }

    /// [`Board::poll`] within an op.
    fn refresh(&mut self) {
        self.hal.keepalive();
        let started = self.now_ticks();
        self.poll_inner();
        self.poll_ticks = self.now_ticks() - started;
    }

    fn poll_inner(&mut self) {
        let word = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let sampled = self.now_ticks();
        let before = core::mem::replace(&mut self.last_sample, sampled);
        // A change happened after the outputs were last seen unchanged and
        // by now: stamped halfway (within half a pass of the loop that
        // watched them).
        let since = core::mem::replace(&mut self.unchanged, sampled);
        let changed = self.at(since + sampled.saturating_sub(since) / 2);
        self.last_word = word;
        self.drain();
        // A change of S1..S5 is a step when a POUT edge came since the
        // last sample (or just before it, its word then still on its way).
        let stepped = self.last_pulse + SETTLE_TICKS >= before;
        self.sample(word, changed, sampled, stepped);
        let horizon = self.at(sampled.saturating_sub(SETTLE_TICKS));
        let n = self.pending.partition_point(|p| p.at <= horizon);
        self.record.pins.extend(self.pending.drain(..n));
    }

    /// The edge counters' words, each placed in time by the clock read
    /// after it was taken from its FIFO (so at or after its edge).
    fn drain(&mut self) {
        let (timer, epoch) = (self.timer, self.epoch);
        let ticks = |hal: &H, started: u64, w: u32| {
            let e = timebase::place(w, (hal.cycles() - started) / 2);
            (e.bit, started / 2 + e.at)
        };
        while let Some(w) = self.hal.capture_pull(Counter::Pout) {
            if !self.room() {
                continue;
            }
            let (bit, t) = ticks(&self.hal, self.started, w);
            self.last_pulse = self.last_pulse.max(t);
            let new_move = self
                .record
                .moves
                .last()
                .is_some_and(|m| m.first_run == self.record.runs.len());
            let at = record_time(timer, epoch, t);
            self.edges
                .push(&mut self.record, at, Direction::from_bit(bit), new_move);
        }
        for (c, pin) in [
            (Counter::Int, Pin::Int),
            (Counter::Hold, Pin::Hold),
            (Counter::Aux, Pin::Aux),
        ] {
            while let Some(w) = self.hal.capture_pull(c) {
                let (high, t) = ticks(&self.hal, self.started, w);
                // HOLD's level as it is, INT*'s and AUX*'s (active low)
                // asserted when low.
                let value = match pin {
                    Pin::Hold => high,
                    _ => !high,
                };
                self.pin(record_time(timer, epoch, t), pin, u8::from(value));
            }
        }
        if self.hal.capture_stalled() {
            // A counter stopped counting while its FIFO was full: this
            // capture has a hole, and every later count would be late by
            // the stall. The capture is lost until the next chip reset;
            // the counters start again now, on a fresh timebase.
            self.lost = true;
            self.overruns += 1;
            self.started = self.hal.start_counters();
        }
    }

    /// A pin change, kept in time order until [`Board::poll`] moves it to
    /// the record.
    fn pin(&mut self, at: Instant, pin: Pin, value: u8) {
        if !self.room() {
            return;
        }
        let i = self.pending.partition_point(|p| p.at <= at);
        self.pending.insert(i, PinEvent { at, pin, value });
    }

    /// Whether the record (and the changes on their way to it) has room
    /// for another record ([`MOST_RECORDS`]).
    fn room(&self) -> bool {
        let r = &self.record;
        r.runs.len() + r.pins.len() + r.moves.len() + self.pending.len() < MOST_RECORDS
    }

    /// Drains the capture until tick `t`.
    fn drain_until(&mut self, t: u64) {
        while self.now_ticks() < t {
            self.refresh();
            self.idle(t);
        }
    }

    /// The self-test ([`Bus::self_test`]): the generator connected to the
    /// capture inputs of POUT and INT* (the chip's outputs cut off), a
    /// chip reset (a fresh record and timebase, started with the
    /// generator's level), the bursts, each started when the last one and
    /// its gap have passed, the capture drained throughout; then the
    /// inputs given back to the chip. Each burst's first rise is predicted
    /// from the cycle the generator was enabled on
    /// ([`programs::TEST_GEN_LEAD`]): what the capture says about it is
    /// the capture's offset.
    fn run_self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestReply, String> {
        // Ticks are two cycles: times in whole ticks keep every edge on
        // the counters' grid.
        let cycles = |d: Duration| 2 * self.timer.to_ticks(d.as_nanos());
        let (high, low, gap) = (cycles(plan.high), cycles(plan.low), cycles(plan.gap));
        let words = programs::test_gen_words(plan.count, high, low).ok_or_else(|| {
            format!(
                "the generator cannot make pulses {} high and {} low: each must be at least {} and at most 2^32 cycles",
                plan.high,
                plan.low,
                Duration::from_nanos(self.timer.to_nanos(2))
            )
        })?;
        let burst = (high + low).saturating_mul(u64::from(plan.count));
        let total = (burst + gap).saturating_mul(u64::from(plan.bursts));
        if total > SELF_TEST_MOST_CYCLES {
            return Err(format!(
                "a self-test of {} bursts of {} pulses takes longer than the bridge allows in one request",
                plan.bursts, plan.count
            ));
        }
        self.hal.resync();
        self.hal.gen_connect(true);
        self.reset_chip();
        let mut starts = Vec::with_capacity(usize::from(plan.bursts));
        // The first burst a little after the reset (the counters started).
        let mut next = self.hal.cycles() + u64::from(self.sysclk_hz / 500_000);
        for _ in 0..plan.bursts {
            self.drain_until(next / 2);
            let enabled = self.hal.gen_start(words);
            let first = enabled + TEST_GEN_LEAD;
            starts.push(self.time_of_cycle(first));
            let end = first + burst;
            self.drain_until(end.div_ceil(2) + SETTLE_TICKS);
            self.hal.gen_stop();
            next = end + gap;
        }
        // Every edge of the last burst into the record, then the chip's
        // outputs back.
        let settled = self.now_ticks() + 2 * SETTLE_TICKS;
        self.drain_until(settled);
        self.refresh();
        self.hal.gen_connect(false);
        self.moment = self.now_ticks();
        self.batch_done = true;
        let dur = |c: u64| Duration::from_nanos(self.timer.to_nanos(c / 2));
        Ok(SelfTestReply {
            starts,
            high: dur(high),
            low: dur(low),
        })
    }

    /// Records changes of the outputs the CPU samples.
    ///
    /// S1..S5 change with every step of a move; the protocol records their
    /// pattern only when it changes otherwise (initialization, excitation
    /// off), so a change with pulses since the last sample is a step and
    /// is not recorded (`stepped`: the capture took pulses since the last
    /// sample). Stop switching chops the phases off and on while
    /// stopped: toggles closer than 1 ms are recorded as SWITCHING on, and
    /// a millisecond without one as SWITCHING off. (A heuristic of the
    /// firmware, not yet checked on hardware: docs/bridge-hardware.md.)
    fn sample(&mut self, word: u16, at: Instant, now: u64, stepped: bool) {
        let (s, auxo, dir) = sampled_levels(word);
        if s != self.last_s {
            let (was, is) = (self.energized(self.last_s), self.energized(s));
            let toggle = was == 0 || is == 0;
            // Only an initialization that asked for it makes the chip
            // chop (Section 3-2, bit 5), never before the first one.
            let chopping = toggle
                && self.tracker.stop_switching()
                && now.saturating_sub(self.last_toggle) < CHOP_TICKS;
            if toggle {
                self.last_toggle = now;
            }
            self.last_s = s;
            if chopping {
                if !self.switching {
                    self.switching = true;
                    self.pin(at, Pin::Switching, 1);
                }
            } else if !stepped {
                self.pin(at, Pin::Phases, is);
            }
        } else if self.switching && now.saturating_sub(self.last_toggle) >= CHOP_TICKS {
            self.switching = false;
            self.pin(at, Pin::Switching, 0);
        }
        if auxo != self.last_auxo {
            self.last_auxo = auxo;
            self.pin(at, Pin::Auxo, auxo);
        }
        if dir != self.last_dir {
            self.last_dir = dir;
            self.pin(at, Pin::Dir, u8::from(dir));
        }
    }

    /// S1..S5 levels as the energized pattern, by the logic the
    /// initialization chose (negative until one did).
    fn energized(&self, levels: u8) -> u8 {
        match self.tracker.logic() {
            Some(OutputLogic::Positive) => levels,
            _ => !levels & 0x1F,
        }
    }

    /// The bridge's own hardware failed: later ops do nothing, and the
    /// engine answers `HARDWARE` with `what`.
    fn fail(&mut self, what: String) {
        if self.fault.is_none() {
            self.fault = Some(what);
        }
    }

    /// One bus cycle: its moment (ticks: WR*'s rise, RD*'s fall), and the
    /// byte read, if a read. Each step is written only when the player's TX
    /// FIFO has room (4 steps deep; a write to a full FIFO is lost), and
    /// every wait has a deadline.
    ///
    /// The moment is predicted, not observed: the player takes a step at
    /// its `pull` when both the step is in the FIFO and the step before has
    /// played, and every step lasts what its word says, so the cycle each
    /// step starts on follows from the cycle each word went in. (Watching
    /// the FIFO empty would be late by the hold step and the CPU's loop:
    /// more than Table 3-3's tolerances allow.)
    fn cycle(&mut self, c: Cycle, aim: Option<u64>) -> (u64, Option<u8>) {
        if self.fault.is_some() {
            return (self.now_ticks(), None);
        }
        let steps = match self.timing.steps(c, self.sysclk_hz) {
            Ok(s) => s,
            // The default timing fits; a board's own is checked at start.
            Err(_) => return (self.now_ticks(), None),
        };
        let deadline =
            self.hal.cycles() + CYCLE_DEADLINE_US * u64::from(self.sysclk_hz / 1_000_000);
        let mut moment = self.hal.cycles();
        if let Some(t) = aim {
            // The cycle's moment at tick `t`: an anchor step, whose start
            // its push tells, then a wait step timed from it.
            let goal = t * 2;
            let before: u64 = steps.words()[..c.moment_step()]
                .iter()
                .map(|w| u64::from(bus::step_cycles(*w)))
                .sum::<u64>()
                + u64::from(bus::PINS_AT);
            let anchor = u64::from(bus::step_cycles(ANCHOR));
            let fits = anchor + u64::from(bus::MAX_COUNT + bus::STEP_CYCLES) + before;
            while self.hal.cycles() + fits < goal {}
            let Some(pull) = self.push_step(ANCHOR, deadline, c) else {
                return (self.now_ticks(), None);
            };
            let waited = pull + anchor + u64::from(bus::STEP_CYCLES) + before;
            if goal >= waited {
                let count = (goal - waited).min(u64::from(bus::MAX_COUNT)) as u32;
                if self
                    .push_step(bus::step(0xFF, bus::IDLE, false, count), deadline, c)
                    .is_none()
                {
                    return (self.now_ticks(), None);
                }
            }
        }
        for (i, w) in steps.words().iter().enumerate() {
            let Some(pull) = self.push_step(*w, deadline, c) else {
                return (self.now_ticks(), None);
            };
            if i == c.moment_step() {
                moment = pull + u64::from(bus::PINS_AT);
            }
        }
        self.moment = moment / 2;
        let byte = match c {
            Cycle::Read { .. } => loop {
                if let Some(w) = self.hal.bus_pull() {
                    break Some(w as u8);
                }
                if self.hal.cycles() > deadline {
                    self.fail(format!(
                        "the bus player (PIO0 SM0) returned no byte for 1 ms after a {c:?}"
                    ));
                    return (self.now_ticks(), None);
                }
            },
            Cycle::Write { .. } => {
                while !self.hal.bus_tx_empty() {
                    if self.hal.cycles() > deadline {
                        self.fail(format!(
                            "the bus player (PIO0 SM0) did not finish a {c:?} in 1 ms"
                        ));
                        return (self.now_ticks(), None);
                    }
                }
                None
            }
        };
        (moment / 2, byte)
    }

    /// Writes step `w` when the player's TX FIFO has room; the cycle the
    /// player will take it on (its `pull`), predicted. `None` when the
    /// player took no step for the cycle's deadline: a hardware fault.
    fn push_step(&mut self, w: u32, deadline: u64, c: Cycle) -> Option<u64> {
        while self.hal.bus_tx_full() {
            if self.hal.cycles() > deadline {
                self.fail(format!(
                    "the bus player (PIO0 SM0) took no step for 1 ms: a step of a {c:?} not written"
                ));
                return None;
            }
        }
        let pushed = self.hal.bus_push(w);
        let pull = self.player_free.max(pushed + 1);
        self.player_free = pull + u64::from(bus::step_cycles(w));
        Some(pull)
    }

    fn read_status(&mut self, aim: Option<u64>) -> (u64, Status) {
        let (t, b) = self.cycle(Cycle::Read { a0: true }, aim);
        let status = Status(b.unwrap_or(0));
        self.tracker.on_status(&mut self.record, status);
        let prev = core::mem::replace(&mut self.last_status, t);
        if status.busy() != self.busy {
            self.busy = status.busy();
            // BUSY changed between the last read and this one: halfway,
            // when the reads are close (a wait's loop); else at this one.
            let gap = t.saturating_sub(prev);
            let close = gap <= self.timer.to_ticks(2_000);
            let at = self.at(if close { prev + gap / 2 } else { t });
            self.pin(at, Pin::Busy, u8::from(self.busy));
        }
        (t, status)
    }

    /// Polls the status register until `status & mask == value`, at most
    /// until `deadline`; the ticks waited, or the last status. The flag
    /// changed between the last two reads: when they are close (the loop's
    /// pass), the wait is taken to end halfway, the best estimate of the
    /// chip's own moment.
    fn wait_status(
        &mut self,
        mask: u8,
        value: u8,
        deadline: u64,
    ) -> Result<(u64, Status), (u64, Status)> {
        let start = self.now_ticks();
        let mut prev = None;
        loop {
            let (t, s) = self.read_status(None);
            if s.0 & mask == value {
                let end = match prev {
                    Some(p) if t - p <= self.timer.to_ticks(2_000) => p + (t - p) / 2,
                    _ => t,
                };
                return Ok((end.saturating_sub(start), s));
            }
            prev = Some(t);
            if t >= deadline {
                return Err((t, s));
            }
            self.refresh();
        }
    }

    fn write(&mut self, command: bool, byte: u8, wait: Option<Duration>) -> Reply {
        let mut waited = Duration::ZERO;
        if let Some(d) = wait {
            let deadline = self.deadline(d);
            match self.wait_status(Status::IBF, 0, deadline) {
                Ok((w, _)) => waited = Duration::from_nanos(self.timer.to_nanos(w)),
                Err((t, status)) => {
                    return Reply::WriteTimedOut {
                        at: self.at(t),
                        status,
                    }
                }
            }
        }
        let phases = self.energized(self.last_s);
        let aim = self.aim;
        let (t, _) = self.cycle(Cycle::Write { a0: command, byte }, aim);
        let at = self.at(t);
        self.refresh();
        self.tracker
            .on_write(&mut self.record, command, byte, at, phases);
        Reply::Written { at, waited }
    }

    fn pins(&mut self) -> Pins {
        self.refresh();
        let phases = self.energized(self.last_s);
        Pins {
            int: self.sm_level(Pin::Int),
            hold: self.sm_level(Pin::Hold),
            aux: self.sm_level(Pin::Aux),
            auxo: self.last_auxo,
            phases,
            phase_levels: self.last_s,
            dir: Direction::from_bit(self.last_dir),
            busy: self.busy,
        }
    }

    /// The pins as GPIO 32-47 show them in `word`, read just now.
    fn pins_from(&self, word: u16) -> Pins {
        let (s, auxo, dir) = sampled_levels(word);
        Pins {
            int: !high(word, pins::INT),
            hold: high(word, pins::HOLD),
            aux: !high(word, pins::AUX),
            auxo,
            phases: self.energized(s),
            phase_levels: s,
            dir: Direction::from_bit(dir),
            busy: self.busy,
        }
    }

    /// The level of a PIO-captured pin: its last change.
    fn sm_level(&self, pin: Pin) -> bool {
        self.pending
            .iter()
            .rev()
            .chain(self.record.pins.iter().rev())
            .find(|p| p.pin == pin)
            .is_some_and(|p| p.value == 1)
    }

    /// How long before its moment an op of kind `k` must start (ticks):
    /// its bus cycles before the moment (a status read first, for one that
    /// waits on a flag), and [`CPU_LEAD_US`] for the code between.
    fn lead(&self, k: Lag) -> u64 {
        let cycles = |c: Cycle, to_moment: bool| -> u64 {
            let Ok(steps) = self.timing.steps(c, self.sysclk_hz) else {
                return 0;
            };
            let words = steps.words();
            let n = if to_moment {
                c.moment_step()
            } else {
                words.len()
            };
            let sum: u64 = words[..n]
                .iter()
                .map(|w| u64::from(bus::step_cycles(*w)))
                .sum();
            sum + if to_moment {
                u64::from(bus::PINS_AT)
            } else {
                0
            }
        };
        let read = Cycle::Read { a0: true };
        let write = Cycle::Write { a0: true, byte: 0 };
        let anchor = u64::from(bus::step_cycles(ANCHOR));
        let c = match k {
            Lag::WriteAfterIbf => cycles(read, false) + anchor + cycles(write, true),
            Lag::Write => anchor + cycles(write, true),
            Lag::ReadAfterObf => cycles(read, false) + anchor + cycles(read, true),
            Lag::Read => anchor + cycles(read, true),
            Lag::Input | Lag::Pins => 0,
        };
        c / 2 + self.timer.to_ticks(CPU_LEAD_US * 1_000)
    }

    /// `Op::Delay`: until `d` after the last op's moment. When the next op
    /// is one with a moment ([`Bus::next_op`]), the delay ends early by
    /// that op's [`Board::lead`], and the op aims its moment at the delay's
    /// end: a bus cycle through a wait step in the player, to the cycle; an
    /// input or a pin sample by spinning on the clock.
    fn delay(&mut self, d: Duration) -> Reply {
        let target = self.moment + self.timer.to_ticks(d.as_nanos());
        let kind = self.next.and_then(Lag::of);
        let until = target.saturating_sub(kind.map_or(0, |k| self.lead(k)));
        loop {
            let now = self.now_ticks();
            if now >= until {
                break;
            }
            // No poll that would end past `until`: the capture waits in
            // its FIFOs until the next op's poll.
            if now + self.poll_ticks < until {
                self.refresh();
            }
            self.idle(until);
        }
        let end = self.now_ticks();
        // Late (the CPU took longer than `d`): the next op acts now.
        self.aim = kind.map(|_| target.max(end));
        self.moment = target.max(end);
        Reply::Delayed {
            at: self.at(self.moment),
        }
    }

    /// Spins on the clock until tick `t`.
    fn spin_until(&mut self, t: u64) {
        while self.now_ticks() < t {}
    }

    /// Lets the hardware idle until tick `until` or a change of the
    /// outputs it watches.
    fn idle(&mut self, until: u64) {
        let seen = self.hal.idle(until * 2) / 2;
        self.unchanged = self.unchanged.max(seen);
    }

    /// The time of pulse `n` (from 1) of the last move, if it came.
    fn pulse_time(&self, n: u64) -> Option<Instant> {
        let first = self.record.moves.last()?.first_run;
        let mut left = n.checked_sub(1)?;
        for r in &self.record.runs[first..] {
            let c = u64::from(r.count);
            if left < c {
                return Some(r.at(left as u32));
            }
            left -= c;
        }
        None
    }

    fn reset_chip(&mut self) -> Reply {
        self.hal.set_reset(false);
        // The inputs start over too (`Op::Reset`): all released.
        for i in 0..pins::INPUTS.len() {
            self.hal.set_input(i, level(false));
        }
        // RESET held low for 100 us, well beyond any chip's minimum.
        let until = self.deadline(Duration::from_micros(100));
        while self.now_ticks() < until {
            self.idle(until);
        }
        self.hal.set_reset(true);
        self.refresh();
        // A fresh timebase for the new record: whatever a stall did to the
        // last one is gone.
        self.started = self.hal.start_counters();
        self.epoch = self.now_ticks();
        self.moment = self.epoch;
        self.record = Record::default();
        self.pending.clear();
        self.last_pulse = 0;
        self.edges.reset();
        self.tracker.reset();
        self.lost = false;
        self.busy = false;
        self.switching = false;
        Reply::ResetDone {
            at: self.at(self.epoch),
        }
    }
}

/// Bridge ticks as the record's time: since `epoch`, the last chip reset.
fn record_time(timer: Timer, epoch: u64, ticks: u64) -> Instant {
    Instant::from_nanos(timer.to_nanos(ticks.saturating_sub(epoch)))
}

impl<H: Hal> Bus for Board<H> {
    fn run(&mut self, op: Op) -> Reply {
        if self.fault.is_some() {
            // The engine answers HARDWARE for the whole batch.
            return Reply::InputSet {
                at: self.at(self.now_ticks()),
            };
        }
        // The core may have slept since the batch before (between
        // requests, in the executor's `wfe`), never within one.
        if self.batch_done {
            self.hal.resync();
            self.batch_done = false;
        }
        // The capture is drained between ops, but for those aimed at a
        // moment: an op right after a delay that ended early for it, and a
        // delay that will end early for the next (its loop drains the
        // capture while there is time). A tight run of pin samples so
        // drains nothing; a FIFO that fills meanwhile stalls its counter,
        // and the next drain reports the capture lost (CAPTURE_OVERRUN).
        let aimed = self.aim.is_some();
        let aiming = matches!(op, Op::Delay(_)) && self.next.and_then(Lag::of).is_some();
        if !aimed && !aiming {
            self.refresh();
        }
        let reply = match op {
            Op::WriteCommand { byte, wait_ibf } => self.write(true, byte, wait_ibf),
            Op::WriteData { byte, wait_ibf } => self.write(false, byte, wait_ibf),
            Op::ReadStatus => {
                let (t, status) = self.read_status(self.aim);
                Reply::Status {
                    at: self.at(t),
                    status,
                }
            }
            Op::ReadData { wait_obf } => {
                let mut waited = Duration::ZERO;
                if let Some(d) = wait_obf {
                    let deadline = self.deadline(d);
                    match self.wait_status(Status::OBF, Status::OBF, deadline) {
                        Ok((w, _)) => waited = Duration::from_nanos(self.timer.to_nanos(w)),
                        Err((t, status)) => {
                            return Reply::ReadTimedOut {
                                at: self.at(t),
                                status,
                            }
                        }
                    }
                }
                let aim = self.aim;
                let (t, b) = self.cycle(Cycle::Read { a0: false }, aim);
                Reply::Data {
                    at: self.at(t),
                    byte: b.unwrap_or(0),
                    waited,
                }
            }
            Op::Delay(d) => self.delay(d),
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => {
                let start = self.now_ticks();
                let deadline = self.deadline(timeout);
                match self.wait_status(mask, value & mask, deadline) {
                    Ok((w, status)) => Reply::Awaited {
                        at: self.at(start + w),
                        waited: Duration::from_nanos(self.timer.to_nanos(w)),
                        status,
                    },
                    Err((t, status)) => Reply::AwaitTimedOut {
                        at: self.at(t),
                        status,
                    },
                }
            }
            Op::SetInput { input, asserted } => {
                let i = ChipInput::ALL.iter().position(|x| *x == input).unwrap_or(0);
                if let Some(t) = self.aim {
                    self.spin_until(t);
                }
                self.hal.set_input(i, level(asserted));
                self.moment = self.now_ticks();
                Reply::InputSet {
                    at: self.at(self.moment),
                }
            }
            Op::ReadPins => match self.aim {
                Some(t) => {
                    // Read where the delay before it aimed, the cycles of a
                    // GPIO read after the clock said so: stamped there, so
                    // that regular samples stay on their grid (one SAMPLES
                    // entry on the wire, as on the model). No poll: the
                    // capture waits in its FIFOs (a tight sampling loop).
                    // Every 8th sample, a look at the capture's FIFOs, when
                    // there is time before the sample; every 64th, in any
                    // case. Drained when a quarter full, at the cost of
                    // that sample's place on the grid.
                    self.samples += 1;
                    let look = self.samples.is_multiple_of(8)
                        && (self.now_ticks() + LOOK_TICKS < t || self.samples.is_multiple_of(64));
                    let mut late = false;
                    if look {
                        if self.hal.capture_level() >= 2 {
                            self.refresh();
                        }
                        // Past the sample's time: stamped when read.
                        late = self.now_ticks() > t;
                    }
                    self.spin_until(t);
                    let word = self.hal.read_high_pins();
                    self.moment = if late { self.now_ticks() } else { t };
                    Reply::Pins {
                        at: self.at(self.moment),
                        pins: self.pins_from(word),
                    }
                }
                None => {
                    let pins = self.pins();
                    self.moment = self.last_sample;
                    Reply::Pins {
                        at: self.at(self.moment),
                        pins,
                    }
                }
            },
            Op::ReadPulses => Reply::Pulses {
                at: self.at(self.now_ticks()),
                summary: self.record.last_move_pulses(),
            },
            Op::AwaitPulses { count, timeout } => {
                let deadline = self.deadline(timeout);
                loop {
                    self.refresh();
                    let n = self.record.last_move_pulses().count;
                    let t = self.now_ticks();
                    if n >= count {
                        // The moment is the pulse's own, not when the
                        // capture brought it: a delay counts from it.
                        let at = self.pulse_time(count).unwrap_or(self.at(t));
                        self.moment = self.epoch + self.timer.to_ticks(at.as_nanos());
                        break Reply::PulsesReached { at };
                    }
                    if t >= deadline {
                        break Reply::PulsesTimedOut {
                            at: self.at(t),
                            count: n,
                        };
                    }
                    self.idle(deadline);
                }
            }
            Op::Reset => self.reset_chip(),
        };
        if matches!(op, Op::Delay(_)) && self.aim.is_some() {
            return reply;
        }
        let ends_batch = self.next.is_none();
        if !(aimed && op == Op::ReadPins) || ends_batch {
            self.refresh();
        }
        self.batch_done |= ends_batch;
        self.aim = None;
        reply
    }

    fn next_op(&mut self, next: Option<Op>) {
        self.next = next;
    }

    fn record(&self) -> &Record {
        &self.record
    }

    fn straps(&self) -> Straps {
        self.straps
    }

    fn now(&self) -> Instant {
        self.at(self.now_ticks())
    }

    fn capture_lost(&self) -> bool {
        self.lost
    }

    fn fault(&self) -> Option<&str> {
        self.fault.as_deref()
    }

    fn self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestReply, String> {
        self.run_self_test(plan)
    }
}
