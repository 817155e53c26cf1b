//! The chip on the bridge's pins, as the bridge engine's [`Bus`]: bus
//! cycles through the PIO step player, inputs on GPIO outputs, outputs
//! captured by the PIO edge counters and by sampling, the capture kept as
//! the protocol's record (pulse runs through `EdgeRuns`, move records
//! through `MoveTracker`). The pin map is docs/bridge-hardware.md's.

use embassy_rp::gpio::{Input, Level, Output};
use embassy_rp::peripherals::{PIO0, PIO1};
use embassy_rp::pio::{StateMachine, StateMachineRx};
use ppmc_bridge_fw::bus::{BusTiming, Cycle};
use ppmc_bridge_fw::timebase;
use ppmc_core::bridge::moves::MoveTracker;
use ppmc_core::bridge::wire::Timer;
use ppmc_core::bus::{Bus, Op, Reply};
use ppmc_core::protocol::{
    Direction, EdgeRuns, Input as ChipInput, OutputLogic, Pin, Pins, Record, Status, Straps,
};
use ppmc_core::time::{Duration, Instant};

use crate::clock::Clock;

/// The chip's input pins, in [`ChipInput::ALL`]'s order: L1*..L4*, ALM*,
/// CNP*, AUXI0..3, each active low at the chip.
pub type InputPins = [Output<'static>; 10];

/// Outputs of the chip the CPU samples: S1..S5 and AUXO0..3 (DIR, which
/// the POUT counter also reads, through the SIO input register).
pub struct Sampled {
    pub s: [Input<'static>; 5],
    pub auxo: [Input<'static>; 4],
}

/// DIR's GPIO (33), read by the CPU without taking it from the PIO.
fn dir_level() -> bool {
    embassy_rp::pac::SIO.gpio_in(1).read() >> (33 - 32) & 1 == 1
}

/// The PIO state machines: the bus player, and the edge counters of POUT
/// (with DIR), INT*, HOLD and AUX*, started together.
pub struct Machines {
    pub bus: StateMachine<'static, PIO0, 0>,
    pub pout: StateMachine<'static, PIO1, 0>,
    pub int: StateMachine<'static, PIO1, 1>,
    pub hold: StateMachine<'static, PIO1, 2>,
    pub aux: StateMachine<'static, PIO1, 3>,
    /// Bridge ticks when the edge counters started.
    pub started: u64,
}

impl core::fmt::Debug for Machines {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Machines")
            .field("started", &self.started)
            .finish_non_exhaustive()
    }
}

/// What the bridge is wired to: the state machines and the GPIOs.
pub struct Wiring {
    pub sm: Machines,
    pub inputs: InputPins,
    pub reset: Output<'static>,
    pub sampled: Sampled,
}

pub struct BoardBus {
    clock: Clock,
    sysclk_hz: u32,
    timer: Timer,
    timing: BusTiming,
    straps: Straps,
    hw: Wiring,
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
}

/// Phases that go off and on again within this (ticks at 75 MHz: 1 ms)
/// are being chopped (stop switching), not switched.
const CHOP_TICKS: u64 = 75_000;

impl core::fmt::Debug for BoardBus {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("BoardBus")
            .field("timer", &self.timer)
            .field("straps", &self.straps)
            .field("epoch", &self.epoch)
            .field("busy", &self.busy)
            .field("lost", &self.lost)
            .finish_non_exhaustive()
    }
}

fn level(asserted: bool) -> Level {
    // The chip's inputs are active low.
    if asserted {
        Level::Low
    } else {
        Level::High
    }
}

impl BoardBus {
    pub fn new(
        clock: Clock,
        sysclk_hz: u32,
        timing: BusTiming,
        straps: Straps,
        hw: Wiring,
    ) -> BoardBus {
        let timer = Timer {
            hz: timebase::timer_hz(sysclk_hz),
        };
        let epoch = clock.ticks();
        let mut bus = BoardBus {
            clock,
            sysclk_hz,
            timer,
            timing,
            straps,
            hw,
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
        };
        bus.sample(false);
        bus
    }

    /// The timer HELLO_REPLY announces.
    pub fn timer(&self) -> Timer {
        self.timer
    }

    /// Ticks to the record's time.
    fn at(&self, ticks: u64) -> Instant {
        record_time(self.timer, self.epoch, ticks)
    }

    fn now_ticks(&self) -> u64 {
        self.clock.ticks()
    }

    fn deadline(&self, d: Duration) -> u64 {
        self.now_ticks() + self.timer.to_ticks(d.as_nanos())
    }

    /// Takes what the capture holds: edge words from the PIO counters and
    /// changes of the sampled outputs. Called between ops, in every wait,
    /// and while the bridge waits for the host.
    pub fn poll(&mut self) {
        let now = self.now_ticks().saturating_sub(self.hw.sm.started);
        let (started, timer, epoch) = (self.hw.sm.started, self.timer, self.epoch);
        // A pushed word's time in the record.
        let place = |w: u32| {
            let e = timebase::place(w, now);
            (e.bit, record_time(timer, epoch, started + e.at))
        };
        let mut stepped = false;
        while let Some(w) = self.hw.sm.pout.rx().try_pull() {
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
        take_edges(self.hw.sm.int.rx(), Pin::Int, &mut self.record, place);
        take_edges(self.hw.sm.hold.rx(), Pin::Hold, &mut self.record, place);
        take_edges(self.hw.sm.aux.rx(), Pin::Aux, &mut self.record, place);
        self.lost |= self.hw.sm.pout.rx().stalled()
            | self.hw.sm.int.rx().stalled()
            | self.hw.sm.hold.rx().stalled()
            | self.hw.sm.aux.rx().stalled();
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
        let s = self
            .hw
            .sampled
            .s
            .iter()
            .fold(0u8, |v, p| v << 1 | u8::from(p.is_high()));
        let auxo = self
            .hw
            .sampled
            .auxo
            .iter()
            .enumerate()
            .fold(0u8, |v, (i, p)| v | u8::from(p.is_low()) << i);
        let dir = dir_level();
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

    /// One bus cycle; the byte read, if a read.
    fn cycle(&mut self, c: Cycle) -> (u64, Option<u8>) {
        let steps = match self.timing.steps(c, self.sysclk_hz) {
            Ok(s) => s,
            // The default timing fits; a board's own is checked at start.
            Err(_) => return (self.now_ticks(), None),
        };
        cortex_m::interrupt::free(|_| {
            for w in steps.words() {
                self.hw.sm.bus.tx().push(*w);
            }
        });
        let byte = match c {
            Cycle::Read { .. } => loop {
                if let Some(w) = self.hw.sm.bus.rx().try_pull() {
                    break Some(w as u8);
                }
            },
            Cycle::Write { .. } => {
                while !self.hw.sm.bus.tx().empty() {}
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
        self.hw.reset.set_low();
        // RESET held low for 100 us, well beyond any chip's minimum.
        let until = self.deadline(Duration::from_micros(100));
        while self.now_ticks() < until {}
        self.hw.reset.set_high();
        self.poll();
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

/// Records the edges an INT*, HOLD or AUX* counter pushed: HOLD's level as
/// it is, INT*'s and AUX*'s (active low) asserted when low.
fn take_edges<const SM: usize>(
    rx: &mut StateMachineRx<'static, PIO1, SM>,
    pin: Pin,
    record: &mut Record,
    place: impl Fn(u32) -> (bool, Instant),
) {
    while let Some(w) = rx.try_pull() {
        let (high, at) = place(w);
        let value = match pin {
            Pin::Hold => high,
            _ => !high,
        };
        record.pin(at, pin, u8::from(value));
    }
}

impl Bus for BoardBus {
    fn run(&mut self, op: Op) -> Reply {
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
                self.hw.inputs[i].set_level(level(asserted));
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
}
