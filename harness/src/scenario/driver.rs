//! The driver a scenario is written against: flowchart-style helpers over a
//! [`Target`], a raw layer to break the protocol on purpose, and
//! expectations that stop the scenario at the first thing that went wrong.

use super::grade::{Grade, Grading, Measurement};
use super::{Failure, Move, Outcome, Stop};
use crate::backend::{Op, Reply, Target};
use crate::protocol::{
    ClockSource, Direction, ErrorCode, Excitation, Flag, InitCommand, InitData, Input, MotorType,
    OutputLogic, Pin, Pins, Record, Register, Status, StatusField, Straps, TimingId,
};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, Event, EventKind};

/// The initialization command and data, built up like the datasheet's
/// Diagram 3-2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Init {
    pub cmd: InitCommand,
    pub data: InitData,
}

impl Init {
    /// A motor with 2-phase excitation, negative logic, the internal clock,
    /// no stop switching, RL = 100, RH = 20, PA = 100.
    pub fn new(motor: MotorType) -> Init {
        Init {
            cmd: InitCommand {
                motor,
                excitation: Excitation::TwoPhase,
                logic: OutputLogic::Negative,
                clock: ClockSource::Internal,
                stop_switching: false,
            },
            data: InitData {
                rl: 100,
                rh: 20,
                pa: 100,
            },
        }
    }

    /// The reference set-up of the suite: 4-phase, RL 100, RH 20, PA 100.
    pub fn four_phase() -> Init {
        Init::new(MotorType::FourPhase)
    }

    pub fn half_step(mut self) -> Init {
        self.cmd.excitation = Excitation::HalfStep;
        self
    }

    pub fn positive_logic(mut self) -> Init {
        self.cmd.logic = OutputLogic::Positive;
        self
    }

    pub fn external_clock(mut self) -> Init {
        self.cmd.clock = ClockSource::External;
        self
    }

    pub fn stop_switching(mut self) -> Init {
        self.cmd.stop_switching = true;
        self
    }

    pub fn rates(mut self, rl: u8, rh: u8) -> Init {
        self.data.rl = rl;
        self.data.rh = rh;
        self
    }

    pub fn accel_pulses(mut self, pa: u16) -> Init {
        self.data.pa = pa;
        self
    }

    pub fn code(&self) -> u8 {
        crate::protocol::Command::Init(self.cmd).encode()
    }
}

/// One step: an op and how its reply is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    Write {
        byte: u8,
        command: bool,
        wait: bool,
    },
    Status,
    ReadData,
    /// `must`: a timeout fails the scenario.
    Await {
        flag: Flag,
        value: bool,
        timeout: Duration,
        must: bool,
    },
    Delay(Duration),
    Set {
        input: Input,
        on: bool,
    },
    AwaitPulses {
        count: u64,
        timeout: Duration,
    },
    Reset,
    Pins,
}

/// What a step gave back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Done {
    At,
    Status(Status),
    Byte(u8),
    Waited(Option<Duration>),
    Pins(Pins),
}

/// What the driver remembers of a step once it has run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Plain,
    /// The final byte of an initialization.
    InitWrite,
    /// The final byte of an operation command: the anchor of measurements.
    Anchor,
    /// A stop, an input edge or an auxiliary command: the trigger of
    /// latency measurements.
    Trigger,
}

/// A deferred expectation, judged on the replies of its group, or on the
/// capture as it stood where the check was queued.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Check {
    /// The most recent move output `n` pulses, all in `dir`.
    Pulses {
        n: u64,
        dir: Direction,
    },
    /// The shortest and longest interval of the most recent move.
    Intervals {
        min: Duration,
        max: Duration,
    },
    /// No pulse of the most recent move after this time.
    NoPulsesAfter(Instant),
    /// No pulse of the most recent move later than this after the last
    /// trigger.
    NoPulsesAfterTrigger(Duration),
    Bytes {
        what: &'static str,
        expected: Vec<u8>,
    },
    Error(ErrorCode),
    NoError,
    Params(u8),
    StatusMask {
        mask: u8,
        value: u8,
    },
    Phases(u8),
    Pins {
        int: Option<bool>,
        hold: Option<bool>,
        aux: Option<bool>,
        auxo: Option<u8>,
    },
}

/// Steps queued to go to the target together, and what to check of them.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Group {
    steps: Vec<(Step, Role)>,
    check: Option<Check>,
}

/// Most groups the driver queues before it sends them anyway.
const MAX_QUEUED: usize = 64;

/// Timeouts and limits of a [`Driver`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriverOptions {
    /// Flowchart writes wait at most this long for IBF = 0.
    pub ibf_timeout: Duration,
    /// Flowchart reads wait at most this long for OBF = 1.
    pub obf_timeout: Duration,
    /// An operation command must raise BUSY within this.
    pub busy_timeout: Duration,
    /// [`Driver::wait_idle`] waits at most this long for BUSY = 0.
    pub idle_timeout: Duration,
    /// Virtual time one scenario may use before it is stopped as an error.
    pub budget: Duration,
    pub grading: Grading,
}

impl Default for DriverOptions {
    fn default() -> Self {
        DriverOptions {
            ibf_timeout: Duration::from_secs(1),
            obf_timeout: Duration::from_millis(100),
            busy_timeout: Duration::from_millis(5),
            idle_timeout: Duration::from_secs(60),
            budget: Duration::from_secs(120),
            grading: Grading::default(),
        }
    }
}

/// Drives one scenario on a target and records what it saw.
pub struct Driver<'t> {
    target: &'t mut dyn Target,
    opts: DriverOptions,
    bus: Vec<Event>,
    measurements: Vec<Measurement>,
    now: Instant,
    /// Final write of the most recent operation command.
    anchor: Option<Instant>,
    /// Final write of the most recent initialization.
    init_write: Option<Instant>,
    init: Option<Init>,
    /// The most recent stop write, input edge or auxiliary command write.
    trigger: Option<Instant>,
    capture: Option<Record>,
    straps: Straps,
    /// Steps not yet sent (see [`Driver::flush`]).
    queue: Vec<Group>,
}

impl std::fmt::Debug for Driver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Driver")
            .field("now", &self.now)
            .field("anchor", &self.anchor)
            .finish_non_exhaustive()
    }
}

fn fail(
    expectation: impl Into<String>,
    expected: impl ToString,
    got: impl ToString,
    at: Instant,
) -> Stop {
    Stop::Failed(Failure {
        expectation: expectation.into(),
        expected: expected.to_string(),
        got: got.to_string(),
        at,
    })
}

impl<'t> Driver<'t> {
    pub fn new(target: &'t mut dyn Target, opts: DriverOptions) -> Self {
        let straps = target.straps();
        Driver {
            straps,
            target,
            opts,
            bus: Vec::new(),
            measurements: Vec::new(),
            now: Instant::ZERO,
            anchor: None,
            init_write: None,
            init: None,
            trigger: None,
            capture: None,
            queue: Vec::new(),
        }
    }

    /// The bus events and measurements recorded so far.
    pub(crate) fn into_parts(self) -> (Vec<Event>, Vec<Measurement>) {
        (self.bus, self.measurements)
    }

    pub fn measurements(&self) -> &[Measurement] {
        &self.measurements
    }

    /// How the target's board is strapped, as it reports it.
    pub fn straps(&self) -> Straps {
        self.straps
    }

    /// The pulse period of rate value `rate` on this board's internal clock
    /// (Equations 3-1..3-4).
    pub fn period(&self, rate: u8) -> Duration {
        let t = self
            .straps
            .tclock(ClockSource::Internal)
            .unwrap_or(Duration::from_micros(2));
        self.straps.pulse_interval(rate, t)
    }

    /// A firmware time given at the datasheet's 16 MHz, on this board's
    /// system clock (notes N10).
    pub fn fw(&self, at_16mhz: Duration) -> Duration {
        self.straps.firmware_time(at_16mhz)
    }

    /// The fastest rate value whose pulses stay within the speed limit
    /// (Section 3-2-2), and the slowest that exceeds it, in phase mode or
    /// POUT mode: `(within, over)`, either `None` if no rate value 1..=254
    /// qualifies on this board.
    pub fn speed_limit_rates(&self, pout: bool) -> (Option<u8>, Option<u8>) {
        let limit = self.straps.min_interval(pout);
        let within = (1..=254u8).find(|r| self.period(*r) >= limit);
        let over = (1..=254u8).rev().find(|r| self.period(*r) < limit);
        (within, over)
    }

    /// The target's clock, once everything queued has run.
    pub fn now(&mut self) -> Outcome<Instant> {
        self.flush()?;
        Ok(self.now)
    }

    /// The clock as of the last op sent (for reports).
    pub(crate) fn clock(&self) -> Instant {
        self.now
    }

    // ----- raw layer -------------------------------------------------------

    /// Runs ops on the target (after everything queued); a target failure
    /// stops the scenario as an error (not the device's fault).
    pub fn exec(&mut self, ops: &[Op]) -> Outcome<Vec<Reply>> {
        Ok(self.flush_with(ops, false)?.1)
    }

    /// Runs ops on the target; with `capture`, also fetches the capture
    /// after them (one round trip less on a board).
    fn send_then(&mut self, ops: &[Op], capture: bool) -> Outcome<Vec<Reply>> {
        if self.now.as_nanos() > self.opts.budget.as_nanos() {
            return Err(Stop::Error(format!(
                "scenario exceeded its time budget of {} (virtual time)",
                self.opts.budget
            )));
        }
        let (replies, record) = if capture {
            let (replies, record) = self
                .target
                .execute_then_capture(ops)
                .map_err(|e| Stop::Error(format!("target: {e}")))?;
            (replies, Some(record))
        } else {
            let replies = self
                .target
                .execute(ops)
                .map_err(|e| Stop::Error(format!("target: {e}")))?;
            (replies, None)
        };
        if replies.len() != ops.len() {
            return Err(Stop::Error(format!(
                "target answered {} of {} operations",
                replies.len(),
                ops.len()
            )));
        }
        if let Some(last) = replies.last() {
            self.now = last.at();
        }
        self.capture = record;
        Ok(replies)
    }

    /// Puts a bus transaction into the scenario's trace: for code that
    /// runs raw ops with [`Driver::exec`] and wants them shown.
    pub fn log_bus(&mut self, at: Instant, e: BusEvent) {
        self.bus.push(Event {
            at,
            kind: EventKind::Bus(e),
        });
    }

    fn unexpected(&self, op: &str, reply: &Reply) -> Stop {
        Stop::Error(format!("target answered {reply:?} to {op}"))
    }

    /// Queues steps (and a check of their replies) to go with the next
    /// flush: on a board, one round trip per point where the scenario must
    /// see a result rather than one per call.
    fn enqueue(&mut self, steps: Vec<(Step, Role)>, check: Option<Check>) -> Outcome {
        self.queue.push(Group { steps, check });
        if self.queue.len() >= MAX_QUEUED {
            self.flush()?;
        }
        Ok(())
    }

    fn plain(steps: impl IntoIterator<Item = Step>) -> Vec<(Step, Role)> {
        steps.into_iter().map(|s| (s, Role::Plain)).collect()
    }

    /// Sends everything queued as one batch, then logs and judges the
    /// replies in order, stopping at the first failure. Ops queued after a
    /// failing one have run on the target too; the verdict and the failure
    /// are those of the first failing step.
    pub fn flush(&mut self) -> Outcome {
        self.flush_then(false)
    }

    /// Flushes what is queued at the end of a scenario, fetching the
    /// capture in the same round trip.
    pub fn finish(&mut self) -> Outcome {
        self.flush_then(true)
    }

    /// [`Driver::flush`]; with `capture`, the capture after the batch comes
    /// back with it.
    fn flush_then(&mut self, capture: bool) -> Outcome {
        if self.queue.is_empty() {
            return Ok(());
        }
        self.flush_with(&[], capture).map(drop)
    }

    /// Sends everything queued and then `extra` as one batch (one round trip
    /// on a board), judges the queued groups as [`Driver::flush`] does, and
    /// returns when `extra` began (the end of the last queued op) and the
    /// replies to `extra`. With `capture`, the capture after the batch comes
    /// back with it.
    fn flush_with(&mut self, extra: &[Op], capture: bool) -> Outcome<(Instant, Vec<Reply>)> {
        let groups = std::mem::take(&mut self.queue);
        let capture = capture
            || groups
                .iter()
                .any(|g| g.check.as_ref().is_some_and(Check::on_capture));
        let mut ops: Vec<Op> = groups
            .iter()
            .flat_map(|g| g.steps.iter().map(|(s, _)| self.step_op(*s)))
            .collect();
        let queued = ops.len();
        ops.extend_from_slice(extra);
        let mut began = self.now;
        if ops.is_empty() {
            return Ok((began, Vec::new()));
        }
        let mut replies = self.send_then(&ops, capture)?;
        let tail = replies.split_off(queued);
        let mut replies = replies.into_iter();
        for g in groups {
            let mut done = Vec::with_capacity(g.steps.len());
            for (step, role) in g.steps {
                let reply = replies
                    .next()
                    .ok_or_else(|| Stop::Error("target answered too few operations".into()))?;
                let at = reply.at();
                done.push(self.judge(step, reply, began)?);
                match role {
                    Role::Plain => {}
                    Role::InitWrite => self.init_write = Some(at),
                    Role::Anchor => self.anchor = Some(at),
                    Role::Trigger => self.trigger = Some(at),
                }
                began = at;
            }
            if let Some(c) = g.check {
                self.judge_check(&c, &done, began)?;
            }
        }
        Ok((began, tail))
    }

    /// Runs steps now (with everything queued before them, in one batch)
    /// and returns their results.
    fn steps(&mut self, steps: &[Step]) -> Outcome<Vec<Done>> {
        let ops: Vec<Op> = steps.iter().map(|s| self.step_op(*s)).collect();
        let (mut began, replies) = self.flush_with(&ops, false)?;
        let mut out = Vec::with_capacity(steps.len());
        for (step, reply) in steps.iter().zip(replies) {
            let at = reply.at();
            out.push(self.judge(*step, reply, began)?);
            began = at;
        }
        Ok(out)
    }

    fn step(&mut self, step: Step) -> Outcome<Done> {
        let mut v = self.steps(&[step])?;
        v.pop().ok_or_else(|| Stop::Error("no reply".into()))
    }

    /// Hardware reset; every scenario starts with one.
    pub fn reset(&mut self) -> Outcome {
        self.anchor = None;
        self.init_write = None;
        self.init = None;
        self.trigger = None;
        self.enqueue(Self::plain([Step::Reset]), None)
    }

    /// The op a step sends.
    fn step_op(&self, step: Step) -> Op {
        match step {
            Step::Write {
                byte,
                command,
                wait,
            } => {
                let wait_ibf = wait.then_some(self.opts.ibf_timeout);
                if command {
                    Op::WriteCommand { byte, wait_ibf }
                } else {
                    Op::WriteData { byte, wait_ibf }
                }
            }
            Step::Status => Op::ReadStatus,
            Step::ReadData => Op::ReadData {
                wait_obf: Some(self.opts.obf_timeout),
            },
            Step::Await {
                flag,
                value,
                timeout,
                ..
            } => Op::await_flag(flag, value, timeout),
            Step::Delay(d) => Op::Delay(d),
            Step::Set { input, on } => Op::SetInput {
                input,
                asserted: on,
            },
            Step::AwaitPulses { count, timeout } => Op::AwaitPulses { count, timeout },
            Step::Reset => Op::Reset,
            Step::Pins => Op::ReadPins,
        }
    }

    /// Logs a step's reply and judges it. `began` is when the step started
    /// (the end of the step before it).
    fn judge(&mut self, step: Step, reply: Reply, began: Instant) -> Outcome<Done> {
        match (step, reply) {
            (
                Step::Write {
                    byte,
                    command,
                    wait,
                },
                Reply::Written { at, waited },
            ) => {
                let waited = wait.then_some(waited);
                let e = if command {
                    BusEvent::WriteCommand { byte, waited }
                } else {
                    BusEvent::WriteData { byte, waited }
                };
                self.log_bus(at, e);
                Ok(Done::At)
            }
            (Step::Write { byte, command, .. }, Reply::WriteTimedOut { at, status }) => {
                self.log_bus(at, BusEvent::WriteTimedOut { command, byte });
                Err(fail(
                    format!("IBF = 0 before writing 0x{byte:02X} (flowchart)"),
                    format!("IBF = 0 within {}", self.opts.ibf_timeout),
                    format!("status 0x{:02X}", status.0),
                    at,
                ))
            }
            (Step::Status, Reply::Status { at, status }) => {
                self.log_bus(at, BusEvent::ReadStatus(status.0));
                Ok(Done::Status(status))
            }
            (Step::ReadData, Reply::Data { at, byte, waited }) => {
                self.log_bus(
                    at,
                    BusEvent::ReadData {
                        byte,
                        waited: Some(waited),
                    },
                );
                Ok(Done::Byte(byte))
            }
            (Step::ReadData, Reply::ReadTimedOut { at, status }) => {
                self.log_bus(at, BusEvent::ReadTimedOut);
                Err(fail(
                    "OBF = 1 before reading (flowchart)",
                    format!("OBF = 1 within {}", self.opts.obf_timeout),
                    format!("status 0x{:02X}", status.0),
                    at,
                ))
            }
            (Step::Await { flag, value, .. }, Reply::Awaited { at, waited, status }) => {
                self.log_bus(
                    at,
                    BusEvent::Await {
                        flag,
                        value,
                        waited: Some(waited),
                        status: status.0,
                    },
                );
                Ok(Done::Waited(Some(waited)))
            }
            (
                Step::Await {
                    flag,
                    value,
                    timeout,
                    must,
                },
                Reply::AwaitTimedOut { at, status },
            ) => {
                self.log_bus(
                    at,
                    BusEvent::Await {
                        flag,
                        value,
                        waited: None,
                        status: status.0,
                    },
                );
                if must {
                    return Err(fail(
                        format!("{} = {}", flag.name(), u8::from(value)),
                        format!("within {timeout}"),
                        "timeout",
                        began + timeout,
                    ));
                }
                Ok(Done::Waited(None))
            }
            (Step::Delay(_), Reply::Delayed { .. }) => Ok(Done::At),
            (Step::Set { input, on }, Reply::InputSet { at }) => {
                self.log_bus(
                    at,
                    BusEvent::SetInput {
                        input,
                        asserted: on,
                    },
                );
                Ok(Done::At)
            }
            (Step::AwaitPulses { count, .. }, Reply::PulsesReached { at }) => {
                self.log_bus(
                    at,
                    BusEvent::AwaitPulses {
                        count,
                        reached: true,
                    },
                );
                Ok(Done::At)
            }
            (Step::AwaitPulses { count: n, .. }, Reply::PulsesTimedOut { at, count }) => {
                self.log_bus(
                    at,
                    BusEvent::AwaitPulses {
                        count: n,
                        reached: false,
                    },
                );
                Err(fail(
                    "pulses output so far",
                    format!("at least {n}"),
                    count,
                    at,
                ))
            }
            (Step::Reset, Reply::ResetDone { at }) => {
                self.log_bus(at, BusEvent::Reset);
                Ok(Done::At)
            }
            (Step::Pins, Reply::Pins { pins, .. }) => Ok(Done::Pins(pins)),
            (step, other) => Err(self.unexpected(&format!("{step:?}"), &other)),
        }
    }

    /// Judges a deferred expectation on the results of its group; `at` is
    /// when the group's last step ended.
    fn judge_check(&self, c: &Check, done: &[Done], at: Instant) -> Outcome {
        if c.on_capture() {
            let mut rec = self
                .capture
                .as_ref()
                .ok_or_else(|| Stop::Error("the capture did not come back".into()))?
                .until(at);
            // A move is recorded at the time of its final byte, and a write
            // takes no time: a move at the cut belongs before the check only
            // if the write was.
            let wrote_at_cut = self.bus.iter().rev().take_while(|e| e.at == at).any(|e| {
                matches!(
                    e.kind,
                    EventKind::Bus(BusEvent::WriteCommand { .. } | BusEvent::WriteData { .. })
                )
            });
            if !wrote_at_cut {
                rec.moves.retain(|m| m.at < at);
            }
            return self.judge_capture(c, &rec, at);
        }
        let status = done.iter().rev().find_map(|d| match d {
            Done::Status(s) => Some(*s),
            _ => None,
        });
        let pins = done.iter().rev().find_map(|d| match d {
            Done::Pins(p) => Some(*p),
            _ => None,
        });
        match (c, status, pins) {
            (Check::Bytes { what, expected }, _, _) => {
                let got: Vec<u8> = done
                    .iter()
                    .filter_map(|d| match d {
                        Done::Byte(b) => Some(*b),
                        _ => None,
                    })
                    .collect();
                if &got != expected {
                    return Err(fail(*what, hex(expected), hex(&got), at));
                }
            }
            (Check::Error(code), Some(s), _) => {
                if s.error() != Some(*code) {
                    return Err(fail(
                        "status error (Table 3-2)",
                        code,
                        describe_status(s),
                        at,
                    ));
                }
            }
            (Check::NoError, Some(s), _) => {
                if s.error_flag() {
                    return Err(fail("no error", "error flag 0", describe_status(s), at));
                }
            }
            (Check::Params(n), Some(s), _) => {
                if s.field() != StatusField::ParamsRemaining(*n) {
                    return Err(fail(
                        "parameter count (status bits 6-4)",
                        format!("{n} remaining"),
                        describe_status(s),
                        at,
                    ));
                }
            }
            (Check::StatusMask { mask, value }, Some(s), _) => {
                if s.0 & mask != value & mask {
                    return Err(fail(
                        format!("status & 0x{mask:02X}"),
                        format!("0x{:02X}", value & mask),
                        format!("0x{:02X}", s.0 & mask),
                        at,
                    ));
                }
            }
            (Check::Phases(pattern), _, Some(p)) => {
                if p.phases != *pattern {
                    return Err(fail(
                        "energized phases S1..S5",
                        format!("0b{pattern:05b}"),
                        format!("0b{:05b}", p.phases),
                        at,
                    ));
                }
            }
            (
                Check::Pins {
                    int,
                    hold,
                    aux,
                    auxo,
                },
                _,
                Some(p),
            ) => {
                let checks = [
                    ("INT*", int.map(u8::from), u8::from(p.int)),
                    ("HOLD", hold.map(u8::from), u8::from(p.hold)),
                    ("AUX*", aux.map(u8::from), u8::from(p.aux)),
                    ("AUXO0..3", *auxo, p.auxo),
                ];
                for (name, want, got) in checks {
                    if let Some(w) = want {
                        if w != got {
                            return Err(fail(format!("{name} asserted"), w, got, at));
                        }
                    }
                }
            }
            (c, _, _) => {
                return Err(Stop::Error(format!(
                    "scenario bug: check {c:?} has no reply to judge"
                )))
            }
        }
        Ok(())
    }

    /// Judges a check of the capture `rec`, cut at `at` where the check
    /// was queued.
    fn judge_capture(&self, c: &Check, rec: &Record, at: Instant) -> Outcome {
        let s = rec.last_move_pulses();
        match *c {
            Check::Pulses { n, dir } => {
                let got = if dir == Direction::Cw { s.cw } else { s.ccw };
                if s.count != n || got != n {
                    return Err(fail(
                        format!("pulses {}", dir.name()),
                        n,
                        format!("{} ({} cw, {} ccw)", s.count, s.cw, s.ccw),
                        s.last.unwrap_or(at),
                    ));
                }
            }
            Check::Intervals { min, max } => {
                let got = (s.min_interval, s.max_interval);
                if got != (Some(min), Some(max)) {
                    return Err(fail(
                        "pulse intervals (min, max)",
                        format!("({min}, {max})"),
                        format!("({}, {})", opt(s.min_interval), opt(s.max_interval)),
                        s.first.unwrap_or(at),
                    ));
                }
            }
            Check::NoPulsesAfter(t) => no_pulses_after(rec, t)?,
            Check::NoPulsesAfterTrigger(margin) => {
                let t = self.need("a stop or an input edge", self.trigger)?;
                no_pulses_after(rec, t + margin)?;
            }
            _ => {
                return Err(Stop::Error(format!(
                    "scenario bug: check {c:?} is not one of the capture"
                )))
            }
        }
        Ok(())
    }

    fn write(&mut self, byte: u8, command: bool, wait: bool, role: Role) -> Outcome {
        self.enqueue(
            vec![(
                Step::Write {
                    byte,
                    command,
                    wait,
                },
                role,
            )],
            None,
        )
    }

    /// Flowchart write of the command register (waits for IBF = 0).
    pub fn command(&mut self, byte: u8) -> Outcome {
        self.write(byte, true, true, Role::Plain)
    }

    /// Flowchart write of the data register.
    pub fn data(&mut self, byte: u8) -> Outcome {
        self.write(byte, false, true, Role::Plain)
    }

    /// Writes the command register at once, whatever IBF says.
    pub fn raw_command(&mut self, byte: u8) -> Outcome {
        self.write(byte, true, false, Role::Plain)
    }

    /// Writes the data register at once, whatever IBF says.
    pub fn raw_data(&mut self, byte: u8) -> Outcome {
        self.write(byte, false, false, Role::Plain)
    }

    /// Reads the status register.
    pub fn status(&mut self) -> Outcome<Status> {
        match self.step(Step::Status)? {
            Done::Status(s) => Ok(s),
            _ => Err(Stop::Error("status read answered otherwise".into())),
        }
    }

    /// Flowchart read of the data register (waits for OBF = 1).
    pub fn read_data(&mut self) -> Outcome<u8> {
        match self.step(Step::ReadData)? {
            Done::Byte(b) => Ok(b),
            _ => Err(Stop::Error("data read answered otherwise".into())),
        }
    }

    /// Waits until `flag` has `value`; `Some(waited)` or `None` on timeout.
    pub fn await_flag(
        &mut self,
        flag: Flag,
        value: bool,
        timeout: Duration,
    ) -> Outcome<Option<Duration>> {
        match self.step(Step::Await {
            flag,
            value,
            timeout,
            must: false,
        })? {
            Done::Waited(w) => Ok(w),
            _ => Err(Stop::Error("await answered otherwise".into())),
        }
    }

    /// Waits for a flag and fails the scenario if it does not come.
    pub fn expect_flag(&mut self, flag: Flag, value: bool, timeout: Duration) -> Outcome {
        self.enqueue(
            Self::plain([Step::Await {
                flag,
                value,
                timeout,
                must: true,
            }]),
            None,
        )
    }

    /// The two waits every flowchart puts before an operation command.
    fn ready_steps(&self) -> [Step; 2] {
        [
            Step::Await {
                flag: Flag::Busy,
                value: false,
                timeout: self.opts.idle_timeout,
                must: true,
            },
            Step::Await {
                flag: Flag::Ibf,
                value: false,
                timeout: self.opts.ibf_timeout,
                must: true,
            },
        ]
    }

    /// A command and its data bytes, as flowchart writes; the final byte
    /// takes `role`.
    fn command_steps(code: u8, data: &[u8], role: Role) -> Vec<(Step, Role)> {
        let n = data.len() + 1;
        std::iter::once((code, true))
            .chain(data.iter().map(|b| (*b, false)))
            .enumerate()
            .map(|(i, (byte, command))| {
                (
                    Step::Write {
                        byte,
                        command,
                        wait: true,
                    },
                    if i + 1 == n { role } else { Role::Plain },
                )
            })
            .collect()
    }

    /// Lets time pass.
    pub fn wait(&mut self, d: Duration) -> Outcome {
        self.enqueue(Self::plain([Step::Delay(d)]), None)
    }

    /// Drives an input (`on` = asserted, pin low). An assertion counts as
    /// the trigger for latency measurements.
    pub fn set(&mut self, input: Input, on: bool) -> Outcome {
        let role = if on { Role::Trigger } else { Role::Plain };
        self.enqueue(vec![(Step::Set { input, on }, role)], None)
    }

    /// Waits until the move in progress has output `n` pulses; the next op
    /// acts right after that pulse, on the target's clock.
    pub fn after_pulses(&mut self, n: u64) -> Outcome {
        let timeout = self.opts.idle_timeout;
        self.enqueue(Self::plain([Step::AwaitPulses { count: n, timeout }]), None)
    }

    /// The output pins now.
    pub fn pins(&mut self) -> Outcome<Pins> {
        match self.step(Step::Pins)? {
            Done::Pins(p) => Ok(p),
            _ => Err(Stop::Error("pins read answered otherwise".into())),
        }
    }

    /// Samples the output pins `n` times, `step` apart, in one batch (one
    /// round trip on a board). Returns `(time, pins)` pairs.
    pub fn sample_pins(&mut self, step: Duration, n: usize) -> Outcome<Vec<(Instant, Pins)>> {
        let mut ops = Vec::with_capacity(2 * n);
        for _ in 0..n {
            ops.push(Op::ReadPins);
            ops.push(Op::Delay(step));
        }
        let replies = self.exec(&ops)?;
        Ok(replies
            .into_iter()
            .filter_map(|r| match r {
                Reply::Pins { at, pins } => Some((at, pins)),
                _ => None,
            })
            .collect())
    }

    /// Measures the stop-switching ON and OFF times (Section 3-5-1) by
    /// sampling the phases every `step` over three cycles of the expected
    /// period, and checks each within 1 % (plus the sampling step) of
    /// `on` / `off`. Both are recorded as measurements.
    pub fn expect_chopping(&mut self, on: Duration, off: Duration, step: Duration) -> Outcome {
        let cycles = (on + off).saturating_mul(3);
        let n = (cycles.as_nanos() / step.as_nanos().max(1)) as usize + 1;
        let samples = self.sample_pins(step, n)?;
        // Edges of "any phase energized".
        let mut edges: Vec<(Instant, bool)> = Vec::new();
        for w in samples.windows(2) {
            let (a, b) = (w[0].1.phases != 0, w[1].1.phases != 0);
            if a != b {
                edges.push((w[1].0, b));
            }
        }
        // A full ON stretch (rise .. fall) and a full OFF stretch (fall .. rise).
        let stretch = |level: bool| {
            edges
                .windows(2)
                .find(|w| w[0].1 == level && w[1].1 != level)
                .map(|w| (w[1].0.saturating_since(w[0].0), w[1].0))
        };
        let now = self.now;
        for (name, level, want) in [("switching_on", true, on), ("switching_off", false, off)] {
            let Some((got, at)) = stretch(level) else {
                return Err(fail(
                    format!("{name}: stop switching chops the phases"),
                    "ON and OFF stretches",
                    "none seen",
                    now,
                ));
            };
            let slack = want.scale(1, 100) + step;
            let m =
                self.opts
                    .grading
                    .grade_in(name, want.saturating_sub(slack), want + slack, got, at);
            let grade = m.grade;
            let (lo, hi) = (m.lo, m.hi);
            self.measurements.push(m);
            if grade == Grade::Fail {
                return Err(fail(
                    format!("{name} (Equations 3-5..3-8)"),
                    format!("{lo}..={hi}"),
                    got,
                    at,
                ));
            }
        }
        Ok(())
    }

    /// The capture since reset (fetched once per change, after everything
    /// queued has run).
    pub fn capture(&mut self) -> Outcome<&Record> {
        self.flush_then(true)?;
        if self.capture.is_none() {
            let c = self
                .target
                .capture()
                .map_err(|e| Stop::Error(format!("target capture: {e}")))?;
            self.capture = Some(c);
        }
        self.capture
            .as_ref()
            .ok_or_else(|| Stop::Error("capture unavailable".into()))
    }

    // ----- flowchart helpers ---------------------------------------------

    /// Waits for BUSY = 0, then IBF = 0: the condition every flowchart puts
    /// before an operation command.
    pub fn wait_ready(&mut self) -> Outcome {
        let steps = Self::plain(self.ready_steps());
        self.enqueue(steps, None)
    }

    /// The initialization flowchart (Diagram 3-3). Later writes wait for
    /// the processing through IBF.
    pub fn init(&mut self, init: Init) -> Outcome {
        let mut steps = Self::plain(self.ready_steps());
        steps.extend(Self::command_steps(
            init.code(),
            &init.data.to_bytes(),
            Role::InitWrite,
        ));
        self.init = Some(init);
        self.enqueue(steps, None)
    }

    /// Initialization, then waiting out its processing time (Table 3-3 max
    /// plus 1 %, from the final byte), so that what follows is timed from an
    /// idle chip.
    pub fn init_and_wait(&mut self, init: Init) -> Outcome {
        self.init(init)?;
        let (_, max) = TimingId::InitProcessing.row().band_for(&self.straps);
        self.wait(max)
    }

    /// Issues a move by its flowchart and waits for BUSY = 1.
    pub fn start(&mut self, m: Move) -> Outcome {
        let mut steps = Self::plain(self.ready_steps());
        steps.extend(Self::command_steps(m.code(), &m.params(), Role::Anchor));
        // The chip may still be busy with earlier work (an initialization):
        // BUSY is due once it has taken the final byte.
        steps.extend(Self::plain([
            Step::Await {
                flag: Flag::Ibf,
                value: false,
                timeout: self.opts.ibf_timeout,
                must: true,
            },
            Step::Await {
                flag: Flag::Busy,
                value: true,
                timeout: self.opts.busy_timeout,
                must: true,
            },
        ]));
        self.enqueue(steps, None)
    }

    /// Issues a move's command and data without waiting for BUSY (for
    /// scenarios that expect it to be refused).
    pub fn issue(&mut self, m: Move) -> Outcome {
        let mut steps = Self::plain(self.ready_steps());
        steps.extend(Self::command_steps(m.code(), &m.params(), Role::Anchor));
        self.enqueue(steps, None)
    }

    /// Issues a move and waits for it to end.
    pub fn run(&mut self, m: Move) -> Outcome {
        self.start(m)?;
        self.wait_idle()
    }

    /// Waits for BUSY = 0 (the move ends), at most the idle timeout or the
    /// scenario's budget, whichever is longer.
    pub fn wait_idle(&mut self) -> Outcome {
        let t = self.opts.idle_timeout.max(self.opts.budget);
        self.expect_flag(Flag::Busy, false, t)
    }

    /// Immediate Stop (Section 3-3-1): writes 0x40 after IBF = 0.
    pub fn immediate_stop(&mut self) -> Outcome {
        self.write(0x40, true, true, Role::Trigger)
    }

    /// Decelerating Stop (Section 3-3-2): writes 0x41 after IBF = 0.
    pub fn decel_stop(&mut self) -> Outcome {
        self.write(0x41, true, true, Role::Trigger)
    }

    /// A command with no data that acts on an output (AUX ON/OFF, software
    /// reset): writes it and marks it as the trigger.
    pub fn trigger_command(&mut self, byte: u8) -> Outcome {
        self.write(byte, true, true, Role::Trigger)
    }

    /// A register read by its flowchart: BUSY = 0, IBF = 0, the command,
    /// then OBF = 1 before each byte.
    fn register_steps(&self, reg: Register) -> Vec<(Step, Role)> {
        let mut steps = Self::plain(self.ready_steps());
        steps.extend(Self::command_steps(reg.code(), &[], Role::Plain));
        steps.extend(Self::plain(std::iter::repeat_n(
            Step::ReadData,
            reg.byte_count(),
        )));
        steps
    }

    /// Reads a register (after everything queued) and returns its bytes.
    pub fn read_register(&mut self, reg: Register) -> Outcome<Vec<u8>> {
        let steps: Vec<Step> = self
            .register_steps(reg)
            .into_iter()
            .map(|(s, _)| s)
            .collect();
        Ok(self
            .steps(&steps)?
            .into_iter()
            .filter_map(|d| match d {
                Done::Byte(b) => Some(b),
                _ => None,
            })
            .collect())
    }

    /// Waits until the chip has taken the last byte written, then reads the
    /// status register: the steps of the status expectations.
    fn settled_status_steps(&self) -> Vec<(Step, Role)> {
        Self::plain([
            Step::Await {
                flag: Flag::Ibf,
                value: false,
                timeout: self.opts.ibf_timeout,
                must: true,
            },
            Step::Status,
        ])
    }

    // ----- expectations --------------------------------------------------

    /// A scenario's own check: fails with `what`, expected vs got, now.
    /// Everything queued is judged first, so an earlier failure is the one
    /// reported.
    pub fn check<T: PartialEq + std::fmt::Debug>(
        &mut self,
        what: &str,
        expected: T,
        got: T,
    ) -> Outcome {
        self.flush()?;
        if expected != got {
            return Err(fail(
                what,
                format!("{expected:?}"),
                format!("{got:?}"),
                self.now,
            ));
        }
        Ok(())
    }

    /// Expects the error flag with `code` (Table 3-2).
    pub fn expect_error(&mut self, code: ErrorCode) -> Outcome {
        let steps = self.settled_status_steps();
        self.enqueue(steps, Some(Check::Error(code)))
    }

    /// Expects no error flag.
    pub fn expect_no_error(&mut self) -> Outcome {
        let steps = self.settled_status_steps();
        self.enqueue(steps, Some(Check::NoError))
    }

    /// Expects status bits 6-4 to count `n` parameter bytes still wanted.
    pub fn expect_params_remaining(&mut self, n: u8) -> Outcome {
        let steps = self.settled_status_steps();
        self.enqueue(steps, Some(Check::Params(n)))
    }

    /// Expects `status & mask == value`.
    pub fn expect_status(&mut self, mask: u8, value: u8) -> Outcome {
        self.enqueue(
            Self::plain([Step::Status]),
            Some(Check::StatusMask { mask, value }),
        )
    }

    fn expect_register(&mut self, reg: Register, what: &'static str, expected: &[u8]) -> Outcome {
        let steps = self.register_steps(reg);
        self.enqueue(
            steps,
            Some(Check::Bytes {
                what,
                expected: expected.to_vec(),
            }),
        )
    }

    /// Reads the finish status (Section 3-4-1) and expects `value`.
    pub fn expect_finish(&mut self, value: u8) -> Outcome {
        self.expect_register(Register::FinishStatus, "finish status", &[value])
    }

    /// Reads the remaining pulses (Section 3-4-4) and expects `value` as
    /// read (one less than the true remainder).
    pub fn expect_remaining(&mut self, value: u32) -> Outcome {
        let b = value.to_le_bytes();
        self.expect_register(
            Register::RemainingPulses,
            "remaining pulses (read value)",
            &b[..3],
        )
    }

    pub fn expect_input_status(&mut self, value: u8) -> Outcome {
        self.expect_register(Register::InputSignals, "input signal status", &[value])
    }

    pub fn expect_output_status(&mut self, value: u8) -> Outcome {
        self.expect_register(Register::OutputSignals, "output signal status", &[value])
    }

    pub fn expect_aux_inputs(&mut self, value: u8) -> Outcome {
        self.expect_register(Register::AuxInputs, "auxiliary input status", &[value])
    }

    /// Expects the most recent move to have output `n` pulses in `dir`,
    /// judged on the capture as it stands now (deferred: no round trip of
    /// its own on a board).
    pub fn expect_pulses(&mut self, n: u64, dir: Direction) -> Outcome {
        self.enqueue(Vec::new(), Some(Check::Pulses { n, dir }))
    }

    /// Expects the most recent move's pulse count within `lo..=hi`.
    pub fn expect_pulses_between(&mut self, lo: u64, hi: u64) -> Outcome<u64> {
        let now = self.now;
        let s = self.capture()?.last_move_pulses();
        if s.count < lo || s.count > hi {
            return Err(fail(
                "pulse count",
                format!("{lo}..={hi}"),
                s.count,
                s.last.unwrap_or(now),
            ));
        }
        Ok(s.count)
    }

    /// Expects the shortest and longest interval of the most recent move
    /// (deferred, as [`Driver::expect_pulses`]).
    pub fn expect_intervals(&mut self, min: Duration, max: Duration) -> Outcome {
        self.enqueue(Vec::new(), Some(Check::Intervals { min, max }))
    }

    /// Expects no pulse of the most recent move after `t` (deferred, as
    /// [`Driver::expect_pulses`]).
    pub fn expect_no_pulses_after(&mut self, t: Instant) -> Outcome {
        self.enqueue(Vec::new(), Some(Check::NoPulsesAfter(t)))
    }

    /// Expects no pulse of the most recent move later than `margin` after
    /// the last trigger (a stop write or an input edge).
    pub fn expect_no_pulses_after_trigger(&mut self, margin: Duration) -> Outcome {
        self.enqueue(Vec::new(), Some(Check::NoPulsesAfterTrigger(margin)))
    }

    /// Expects the energized phases (S1 in bit 4).
    pub fn expect_phases(&mut self, pattern: u8) -> Outcome {
        self.enqueue(Self::plain([Step::Pins]), Some(Check::Phases(pattern)))
    }

    /// Expects output pins: each `Some` is checked.
    pub fn expect_pins(
        &mut self,
        int: Option<bool>,
        hold: Option<bool>,
        aux: Option<bool>,
        auxo: Option<u8>,
    ) -> Outcome {
        self.enqueue(
            Self::plain([Step::Pins]),
            Some(Check::Pins {
                int,
                hold,
                aux,
                auxo,
            }),
        )
    }

    // ----- Table 3-3 measurements ---------------------------------------

    fn record_measure(&mut self, id: TimingId, value: Duration, at: Instant) -> Outcome<Grade> {
        let m = self.opts.grading.grade(id, &self.straps, value, at);
        let grade = m.grade;
        let (lo, hi) = (m.lo, m.hi);
        self.measurements.push(m);
        if grade == Grade::Fail {
            return Err(Stop::Failed(Failure {
                expectation: format!("{} (Table 3-3)", id.name()),
                expected: format!("{lo}..={}", super::grade::fmt_hi(hi)),
                got: value.to_string(),
                at,
            }));
        }
        Ok(grade)
    }

    fn pin_after(
        &mut self,
        pin: Pin,
        value: Option<u8>,
        from: Instant,
    ) -> Outcome<Option<Instant>> {
        Ok(self
            .capture()?
            .pins
            .iter()
            .find(|e| e.pin == pin && e.at >= from && value.is_none_or(|v| e.value == v))
            .map(|e| e.at))
    }

    /// [`Driver::need`] of a time set by a queued step: flushes first.
    fn flushed(&mut self, what: &str, t: fn(&Self) -> Option<Instant>) -> Outcome<Instant> {
        self.flush()?;
        self.need(what, t(self))
    }

    fn need(&self, what: &str, t: Option<Instant>) -> Outcome<Instant> {
        t.ok_or_else(|| {
            Stop::Error(format!(
                "scenario bug: measuring needs {what}, which this scenario has not done"
            ))
        })
    }

    fn last_move_pulse_times(&mut self) -> Outcome<(Instant, Instant)> {
        let now = self.now;
        let s = self.capture()?.last_move_pulses();
        match (s.first, s.last) {
            (Some(a), Some(b)) => Ok((a, b)),
            _ => Err(fail("the move output pulses", "at least 1", 0, now)),
        }
    }

    /// Measures the Table 3-3 quantity `id` from what has happened so far
    /// and grades it. A FAIL stops the scenario; MARGINAL is recorded.
    pub fn expect_latency(&mut self, id: TimingId) -> Outcome<Duration> {
        let (from, to) = match id {
            TimingId::BusyRise => {
                let a = self.flushed("an operation command", |d| d.anchor)?;
                (a, self.pin_after(Pin::Busy, Some(1), a)?)
            }
            TimingId::AccelFirstPout | TimingId::ConstantFirstPout => {
                let a = self.flushed("an operation command", |d| d.anchor)?;
                let (first, _) = self.last_move_pulse_times()?;
                (a, Some(first))
            }
            TimingId::SingleStep => {
                let a = self.flushed("an operation command", |d| d.anchor)?;
                (a, self.pin_after(Pin::Busy, Some(0), a)?)
            }
            TimingId::InterruptOutput => {
                let (_, last) = self.last_move_pulse_times()?;
                (last, self.pin_after(Pin::Int, Some(1), last)?)
            }
            TimingId::HoldOn => {
                let (_, last) = self.last_move_pulse_times()?;
                (last, self.pin_after(Pin::Hold, Some(1), last)?)
            }
            TimingId::AbnormalTermination => {
                let t = self.flushed("a stop or limit", |d| d.trigger)?;
                (t, self.pin_after(Pin::Busy, Some(0), t)?)
            }
            TimingId::AuxOn => {
                let t = self.flushed("an AUX ON command", |d| d.trigger)?;
                (t, self.pin_after(Pin::Aux, Some(1), t)?)
            }
            TimingId::AuxOff => {
                let t = self.flushed("an AUX OFF command", |d| d.trigger)?;
                (t, self.pin_after(Pin::Aux, Some(0), t)?)
            }
            TimingId::ExcitationOff => {
                let t = self.flushed("a software reset", |d| d.trigger)?;
                (t, self.pin_after(Pin::Phases, Some(0), t)?)
            }
            TimingId::InitOutputsSet => {
                let t = self.flushed("an initialization", |d| d.init_write)?;
                (t, self.pin_after(Pin::Phases, None, t)?)
            }
            TimingId::InitProcessing => return self.measure_init_processing(),
            TimingId::NextCommand => return self.measure_next_command(),
            TimingId::DecelStopProcessing
            | TimingId::HighSpeedLimitAccel
            | TimingId::HighSpeedLimitCruise => return self.expect_decel_start(id),
        };
        let now = self.now;
        let to = to.ok_or_else(|| {
            fail(
                format!("{} (Table 3-3): the event it ends with", id.name()),
                "observed",
                "never happened",
                now,
            )
        })?;
        let value = to.saturating_since(from);
        self.record_measure(id, value, to)?;
        Ok(value)
    }

    /// Initialization processing: from the final data byte until the chip
    /// takes the next command (an input status read, harmless).
    fn measure_init_processing(&mut self) -> Outcome<Duration> {
        let timeout = self.opts.ibf_timeout;
        self.expect_flag(Flag::Ibf, false, timeout)?;
        self.raw_command(Register::InputSignals.code())?;
        self.expect_flag(Flag::Ibf, false, timeout)?;
        let t = self.flushed("an initialization", |d| d.init_write)?;
        let value = self.now.saturating_since(t);
        let at = self.now;
        self.record_measure(TimingId::InitProcessing, value, at)?;
        Ok(value)
    }

    /// Normal termination: the final POUT to the chip taking a command
    /// written as soon as BUSY = 0.
    fn measure_next_command(&mut self) -> Outcome<Duration> {
        self.wait_idle()?;
        self.raw_command(Register::InputSignals.code())?;
        let timeout = self.opts.ibf_timeout;
        self.expect_flag(Flag::Ibf, false, timeout)?;
        // The move had ended before the command: its last pulse is in the
        // capture fetched with the batch.
        let (_, last) = self.last_move_pulse_times()?;
        let value = self.now.saturating_since(last);
        let at = self.now;
        self.record_measure(TimingId::NextCommand, value, at)?;
        Ok(value)
    }

    /// The deceleration latencies: after the move, the pulse count says from
    /// which pulse the deceleration started; it must be the first pulse
    /// after the trigger plus a latency inside the row's band. A pass/fail
    /// check, not a graded measurement: one run only brackets the latency
    /// between two pulses. Returns the time from the trigger to that pulse.
    fn expect_decel_start(&mut self, id: TimingId) -> Outcome<Duration> {
        let pa = self
            .init
            .map(|i| u64::from(i.data.pa))
            .ok_or_else(|| Stop::Error("scenario bug: measuring needs an initialization".into()))?;
        self.wait_idle()?;
        let t = self.flushed("a decelerating stop or high-speed limit", |d| d.trigger)?;
        let rec = self.capture()?;
        let from = rec.moves.last().map_or(0, |m| m.first_run);
        let times: Vec<Instant> = rec.runs[from..]
            .iter()
            .flat_map(|r| {
                (0..r.count).map(move |i| r.start + r.interval.saturating_mul(u64::from(i)))
            })
            .collect();
        let n = times.len() as u64;
        // Pulse index the deceleration started from: at high speed it and
        // PA - 1 more make the PA pulses of deceleration; during acceleration
        // from index j the ramp down takes j (notes N16, N24).
        let j1 = if id == TimingId::HighSpeedLimitAccel {
            n / 2
        } else {
            n.saturating_sub(pa)
        };
        let (lo, hi) = id.row().band_for(&self.straps);
        let first_after = |d: Duration| {
            times
                .iter()
                .position(|p| *p > t + d)
                .map_or(n, |i| i as u64)
        };
        let (j_lo, j_hi) = (first_after(lo), first_after(hi));
        let start_time = times.get(j1 as usize).copied().unwrap_or(self.now);
        if j1 < j_lo || j1 > j_hi {
            return Err(Stop::Failed(Failure {
                expectation: format!(
                    "{} (Table 3-3): deceleration starts at the first pulse after the latency",
                    id.name()
                ),
                expected: format!(
                    "from pulse {j_lo}..={j_hi} (latency {lo}..={})",
                    super::grade::fmt_hi(hi)
                ),
                got: format!("from pulse {j1}"),
                at: start_time,
            }));
        }
        // The latency itself lies between the pulse before j1 and j1; what is
        // observable is how long after the trigger the first pulse of the
        // deceleration came.
        Ok(start_time.saturating_since(t))
    }
}

impl Check {
    /// Whether the check is judged on the capture rather than on replies.
    fn on_capture(&self) -> bool {
        matches!(
            self,
            Check::Pulses { .. }
                | Check::Intervals { .. }
                | Check::NoPulsesAfter(_)
                | Check::NoPulsesAfterTrigger(_)
        )
    }
}

/// Fails if the most recent move of `rec` has a pulse after `t`.
fn no_pulses_after(rec: &Record, t: Instant) -> Outcome {
    let from = rec.moves.last().map_or(0, |m| m.first_run);
    let (mut late, mut first) = (0u64, None);
    for r in rec.runs.get(from..).unwrap_or_default() {
        let count = u64::from(r.count);
        // Pulses of the run at or before `t`.
        let on_time = if r.start > t {
            0
        } else if r.interval == Duration::ZERO {
            count
        } else {
            (t.saturating_since(r.start).as_nanos() / r.interval.as_nanos() + 1).min(count)
        };
        if on_time < count {
            first.get_or_insert(r.start + r.interval.saturating_mul(on_time));
            late += count - on_time;
        }
    }
    match first {
        Some(first) => Err(fail(format!("no pulse after {t}"), 0, late, first)),
        None => Ok(()),
    }
}

fn describe_status(s: Status) -> String {
    match s.field() {
        StatusField::Error(e) => format!("0x{:02X} ({e})", s.0),
        StatusField::ParamsRemaining(n) => {
            format!("0x{:02X} (no error, {n} parameters wanted)", s.0)
        }
    }
}

fn hex(b: &[u8]) -> String {
    b.iter()
        .map(|x| format!("0x{x:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn opt(d: Option<Duration>) -> String {
    d.map_or("-".into(), |d| d.to_string())
}
