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

use crate::bus::{BusTiming, Cycle};
use crate::hal::{Counter, Hal};
use crate::pins;
use crate::timebase;
use alloc::format;
use alloc::string::String;
use ppmc_core::bridge::moves::MoveTracker;
use ppmc_core::bridge::wire::Timer;
use ppmc_core::bus::{Bus, Op, Reply};
use ppmc_core::protocol::{
    Direction, EdgeRuns, Input as ChipInput, OutputLogic, Pin, Pins, Record, Status, Straps,
};
use ppmc_core::time::{Duration, Instant};

/// The longest a bus cycle may take before the bridge calls its player
/// stuck: 1 ms (a cycle of the longest steps takes 35 us at 150 MHz).
const CYCLE_DEADLINE_US: u64 = 1_000;

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

fn level(asserted: bool) -> bool {
    // The chip's inputs are active low: asserted is low.
    !asserted
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
        bus.sample(false);
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

    /// Takes what the capture holds: edge words from the PIO counters and
    /// changes of the sampled outputs. Called between ops, in every wait,
    /// and while the bridge waits for the host.
    pub fn poll(&mut self) {
        // Ticks of the counters' timebase now: after every word waiting.
        let now = (self.hal.cycles() - self.started) / 2;
        let (started, timer, epoch) = (self.started, self.timer, self.epoch);
        // A pushed word's time in the record.
        let place = |w: u32| {
            let e = timebase::place(w, now);
            (e.bit, record_time(timer, epoch, started / 2 + e.at))
        };
        let mut stepped = false;
        while let Some(w) = self.hal.capture_pull(Counter::Pout) {
            stepped = true;
            let (bit, at) = place(w);
            let new_move = self
                .record
                .moves
                .last()
                .is_some_and(|m| m.first_run == self.record.runs.len());
            self.edges
                .push(&mut self.record, at, Direction::from_bit(bit), new_move);
        }
        for (c, pin) in [
            (Counter::Int, Pin::Int),
            (Counter::Hold, Pin::Hold),
            (Counter::Aux, Pin::Aux),
        ] {
            while let Some(w) = self.hal.capture_pull(c) {
                let (high, at) = place(w);
                // HOLD's level as it is, INT*'s and AUX*'s (active low)
                // asserted when low.
                let value = match pin {
                    Pin::Hold => high,
                    _ => !high,
                };
                self.record.pin(at, pin, u8::from(value));
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
        self.sample(stepped);
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
    fn sample(&mut self, stepped: bool) {
        let word = self.hal.read_high_pins();
        let s = pins::S
            .iter()
            .fold(0u8, |v, g| v << 1 | u8::from(high(word, *g)));
        let auxo = pins::AUXO
            .iter()
            .enumerate()
            .fold(0u8, |v, (i, g)| v | u8::from(!high(word, *g)) << i);
        let dir = high(word, pins::DIR);
        let now = self.now_ticks();
        let at = self.at(now);
        if s != self.last_s {
            let (was, is) = (self.energized(self.last_s), self.energized(s));
            let toggle = was == 0 || is == 0;
            let chopping = toggle && now.saturating_sub(self.last_toggle) < CHOP_TICKS;
            if toggle {
                self.last_toggle = now;
            }
            self.last_s = s;
            if chopping {
                if !self.switching {
                    self.switching = true;
                    self.record.pin(at, Pin::Switching, 1);
                }
            } else if !stepped {
                self.record.pin(at, Pin::Phases, is);
            }
        } else if self.switching && now.saturating_sub(self.last_toggle) >= CHOP_TICKS {
            self.switching = false;
            self.record.pin(at, Pin::Switching, 0);
        }
        if auxo != self.last_auxo {
            self.last_auxo = auxo;
            self.record.pin(at, Pin::Auxo, auxo);
        }
        if dir != self.last_dir {
            self.last_dir = dir;
            self.record.pin(at, Pin::Dir, u8::from(dir));
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

    /// One bus cycle: its time, and the byte read, if a read. Each step is
    /// written only when the player's TX FIFO has room (4 steps deep; a
    /// write to a full FIFO is lost), and every wait has a deadline.
    fn cycle(&mut self, c: Cycle) -> (u64, Option<u8>) {
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
        for (i, w) in steps.words().iter().enumerate() {
            while self.hal.bus_tx_full() {
                if self.hal.cycles() > deadline {
                    self.fail(format!(
                        "the bus player (PIO0 SM0) took no step for 1 ms: step {} of a {c:?} not written",
                        i + 1
                    ));
                    return (self.now_ticks(), None);
                }
            }
            self.hal.bus_push(*w);
        }
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
        (self.now_ticks(), byte)
    }

    fn read_status(&mut self) -> (u64, Status) {
        let (t, b) = self.cycle(Cycle::Read { a0: true });
        let status = Status(b.unwrap_or(0));
        self.tracker.on_status(&mut self.record, status);
        if status.busy() != self.busy {
            self.busy = status.busy();
            let at = self.at(t);
            self.record.pin(at, Pin::Busy, u8::from(self.busy));
        }
        (t, status)
    }

    /// Polls the status register until `status & mask == value`, at most
    /// until `deadline`; the ticks waited, or the last status.
    fn wait_status(
        &mut self,
        mask: u8,
        value: u8,
        deadline: u64,
    ) -> Result<(u64, Status), (u64, Status)> {
        let start = self.now_ticks();
        loop {
            let (t, s) = self.read_status();
            if s.0 & mask == value {
                return Ok((t - start.min(t), s));
            }
            if t >= deadline {
                return Err((t, s));
            }
            self.poll();
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
        let (t, _) = self.cycle(Cycle::Write { a0: command, byte });
        let at = self.at(t);
        self.poll();
        self.tracker
            .on_write(&mut self.record, command, byte, at, phases);
        Reply::Written { at, waited }
    }

    fn pins(&mut self) -> Pins {
        self.poll();
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

    /// The level of a PIO-captured pin: its last recorded change.
    fn sm_level(&self, pin: Pin) -> bool {
        self.record
            .pins
            .iter()
            .rev()
            .find(|p| p.pin == pin)
            .is_some_and(|p| p.value == 1)
    }

    fn reset_chip(&mut self) -> Reply {
        self.hal.set_reset(false);
        // RESET held low for 100 us, well beyond any chip's minimum.
        let until = self.deadline(Duration::from_micros(100));
        while self.now_ticks() < until {
            self.hal.idle(until * 2);
        }
        self.hal.set_reset(true);
        self.poll();
        // A fresh timebase for the new record: whatever a stall did to the
        // last one is gone.
        self.started = self.hal.start_counters();
        self.epoch = self.now_ticks();
        self.record = Record::default();
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
        self.poll();
        let reply = match op {
            Op::WriteCommand { byte, wait_ibf } => self.write(true, byte, wait_ibf),
            Op::WriteData { byte, wait_ibf } => self.write(false, byte, wait_ibf),
            Op::ReadStatus => {
                let (t, status) = self.read_status();
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
                let (t, b) = self.cycle(Cycle::Read { a0: false });
                Reply::Data {
                    at: self.at(t),
                    byte: b.unwrap_or(0),
                    waited,
                }
            }
            Op::Delay(d) => {
                let until = self.deadline(d);
                while self.now_ticks() < until {
                    self.poll();
                    self.hal.idle(until * 2);
                }
                Reply::Delayed { at: self.at(until) }
            }
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => {
                let deadline = self.deadline(timeout);
                match self.wait_status(mask, value & mask, deadline) {
                    Ok((w, status)) => Reply::Awaited {
                        at: self.at(self.now_ticks()),
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
                self.hal.set_input(i, level(asserted));
                Reply::InputSet {
                    at: self.at(self.now_ticks()),
                }
            }
            Op::ReadPins => {
                let pins = self.pins();
                Reply::Pins {
                    at: self.at(self.now_ticks()),
                    pins,
                }
            }
            Op::ReadPulses => Reply::Pulses {
                at: self.at(self.now_ticks()),
                summary: self.record.last_move_pulses(),
            },
            Op::AwaitPulses { count, timeout } => {
                let deadline = self.deadline(timeout);
                loop {
                    self.poll();
                    let n = self.record.last_move_pulses().count;
                    let t = self.now_ticks();
                    if n >= count {
                        break Reply::PulsesReached { at: self.at(t) };
                    }
                    if t >= deadline {
                        break Reply::PulsesTimedOut {
                            at: self.at(t),
                            count: n,
                        };
                    }
                    self.hal.idle(deadline * 2);
                }
            }
            Op::Reset => self.reset_chip(),
        };
        self.poll();
        reply
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
}
