//! How a driver's steps reach the target: steps that need no reply yet
//! are queued, sent in one batch with the next step whose result the
//! scenario must see, and judged in order when the replies come back, so
//! that a scenario on a board costs a round trip per point where it looks,
//! not one per call. Deferred checks are judged on their group's replies,
//! or on the capture as it stood where they were queued.

use super::driver::Driver;
use super::outcome::{fail, HarnessError, Outcome, Stop};
use crate::backend::{Op, Reply};
use crate::protocol::{Direction, ErrorCode, Flag, Input, Pins, Record, Status, StatusField};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, EventKind};

/// One step: an op and how its reply is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Step {
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
pub(super) enum Done {
    At,
    Status(Status),
    Byte(u8),
    Waited(Option<Duration>),
    Pins(Pins),
}

/// What the driver remembers of a step once it has run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
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
pub(super) enum Check {
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
    /// Every interval of the most recent move within `tolerance` of
    /// `nominal`.
    IntervalsWithin {
        nominal: Duration,
        tolerance: Duration,
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
pub(super) struct Group {
    pub(super) steps: Vec<(Step, Role)>,
    pub(super) check: Option<Check>,
}

/// Most groups the driver queues before it sends them anyway.
const MAX_QUEUED: usize = 64;

impl Driver<'_> {
    /// Runs ops on the target; with `capture`, also fetches the capture
    /// after them (one round trip less on a board).
    pub(super) fn send_then(&mut self, ops: &[Op], capture: bool) -> Outcome<Vec<Reply>> {
        if self.now.as_nanos() > self.opts.budget.as_nanos() {
            return Err(Stop::Error(HarnessError::Budget(self.opts.budget)));
        }
        let (replies, record) = if capture {
            let (replies, record) = self
                .target
                .execute_then_capture(ops)
                .map_err(|e| Stop::Error(HarnessError::target(&e)))?;
            (replies, Some(record))
        } else {
            let replies = self
                .target
                .execute(ops)
                .map_err(|e| Stop::Error(HarnessError::target(&e)))?;
            (replies, None)
        };
        if replies.len() != ops.len() {
            return Err(Stop::Error(HarnessError::Reply(format!(
                "target answered {} of {} operations",
                replies.len(),
                ops.len()
            ))));
        }
        if let Some(last) = replies.last() {
            self.now = last.at();
        }
        self.capture = record;
        Ok(replies)
    }

    pub(super) fn unexpected(&self, op: &str, reply: &Reply) -> Stop {
        Stop::Error(HarnessError::Reply(format!(
            "target answered `{reply}` to {op}"
        )))
    }

    /// Queues steps (and a check of their replies) to go with the next
    /// flush: on a board, one round trip per point where the scenario must
    /// see a result rather than one per call.
    pub(super) fn enqueue(&mut self, steps: Vec<(Step, Role)>, check: Option<Check>) -> Outcome {
        self.queue.push(Group { steps, check });
        if self.queue.len() >= MAX_QUEUED {
            self.flush()?;
        }
        Ok(())
    }

    pub(super) fn plain(steps: impl IntoIterator<Item = Step>) -> Vec<(Step, Role)> {
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
    pub(super) fn flush_then(&mut self, capture: bool) -> Outcome {
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
    pub(super) fn flush_with(
        &mut self,
        extra: &[Op],
        capture: bool,
    ) -> Outcome<(Instant, Vec<Reply>)> {
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
            // Only checks of the capture, queued after the last flush (a
            // scenario that reads a value, then checks the move): judged on
            // the capture as it stands. They were once dropped unjudged
            // here, and a wrong one passed.
            if groups.iter().any(|g| g.check.is_some()) {
                let record = self
                    .target
                    .capture()
                    .map_err(|e| Stop::Error(HarnessError::target(&e)))?;
                self.capture = Some(record);
                for g in &groups {
                    if let Some(c) = &g.check {
                        self.judge_check(c, &[], began)?;
                    }
                }
            }
            return Ok((began, Vec::new()));
        }
        let mut replies = self.send_then(&ops, capture)?;
        let tail = replies.split_off(queued);
        let mut replies = replies.into_iter();
        for g in groups {
            let mut done = Vec::with_capacity(g.steps.len());
            for (step, role) in g.steps {
                let reply = replies.next().ok_or_else(|| {
                    Stop::Error(HarnessError::Reply(
                        "target answered too few operations".into(),
                    ))
                })?;
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
    pub(super) fn steps(&mut self, steps: &[Step]) -> Outcome<Vec<Done>> {
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

    pub(super) fn step(&mut self, step: Step) -> Outcome<Done> {
        let mut v = self.steps(&[step])?;
        v.pop()
            .ok_or_else(|| Stop::Error(HarnessError::Reply("no reply".into())))
    }

    /// The op a step sends.
    pub(super) fn step_op(&self, step: Step) -> Op {
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
    pub(super) fn judge(&mut self, step: Step, reply: Reply, began: Instant) -> Outcome<Done> {
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
            (step, other) => Err(self.unexpected(&format!("`{}`", self.step_op(step)), &other)),
        }
    }

    /// Judges a deferred expectation on the results of its group; `at` is
    /// when the group's last step ended.
    pub(super) fn judge_check(&self, c: &Check, done: &[Done], at: Instant) -> Outcome {
        if c.on_capture() {
            let mut rec = self
                .capture
                .as_ref()
                .ok_or_else(|| {
                    Stop::Error(HarnessError::Capture(
                        "the capture did not come back".into(),
                    ))
                })?
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
                return Err(Stop::Error(HarnessError::Scenario(format!(
                    "scenario bug: check {c:?} has no reply to judge"
                ))))
            }
        }
        Ok(())
    }

    /// Judges a check of the capture `rec`, cut at `at` where the check
    /// was queued.
    pub(super) fn judge_capture(&self, c: &Check, rec: &Record, at: Instant) -> Outcome {
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
                // Exact, but for what the capture cannot tell (the jitter
                // bound of a bridge whose timer is not locked to the chip).
                let bound = s.interval_bound;
                let near = |got: Option<Duration>, want: Duration| {
                    got.is_some_and(|g| g.abs_diff(want) <= bound)
                };
                if !(near(s.min_interval, min) && near(s.max_interval, max)) {
                    let expected = if bound == Duration::ZERO {
                        format!("({min}, {max})")
                    } else {
                        format!("({min}, {max}), each within {bound} (the capture's bound)")
                    };
                    return Err(fail(
                        "pulse intervals (min, max)",
                        expected,
                        format!("({}, {})", opt(s.min_interval), opt(s.max_interval)),
                        s.first.unwrap_or(at),
                    ));
                }
            }
            Check::IntervalsWithin { nominal, tolerance } => {
                // A band around the nominal interval, widened by what the
                // capture cannot tell.
                let band = tolerance + s.interval_bound;
                let lo = Duration::from_nanos(nominal.as_nanos().saturating_sub(band.as_nanos()));
                let hi = nominal + band;
                let inside = |g: Option<Duration>| g.is_some_and(|g| g >= lo && g <= hi);
                if !(inside(s.min_interval) && inside(s.max_interval)) {
                    return Err(fail(
                        "every pulse interval",
                        format!("within {nominal} ± {band} ({lo} to {hi})"),
                        format!("from {} to {}", opt(s.min_interval), opt(s.max_interval)),
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
                return Err(Stop::Error(HarnessError::Scenario(format!(
                    "scenario bug: check {c:?} is not one of the capture"
                ))))
            }
        }
        Ok(())
    }

    pub(super) fn write(&mut self, byte: u8, command: bool, wait: bool, role: Role) -> Outcome {
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
}

impl Check {
    /// Whether the check is judged on the capture rather than on replies.
    pub(super) fn on_capture(&self) -> bool {
        matches!(
            self,
            Check::Pulses { .. }
                | Check::Intervals { .. }
                | Check::IntervalsWithin { .. }
                | Check::NoPulsesAfter(_)
                | Check::NoPulsesAfterTrigger(_)
        )
    }
}

/// Fails if the most recent move of `rec` has a pulse after `t`.
pub(super) fn no_pulses_after(rec: &Record, t: Instant) -> Outcome {
    let from = rec.moves.last().map_or(0, |m| m.first_run);
    let (mut late, mut first) = (0u64, None);
    for r in rec.runs.get(from..).unwrap_or_default() {
        let count = u64::from(r.count);
        // Pulses of the run at or before `t`.
        let on_time = r.count_until(t);
        if on_time < r.count {
            first.get_or_insert(r.at(on_time));
            late += count - u64::from(on_time);
        }
    }
    match first {
        Some(first) => Err(fail(format!("no pulse after {t}"), 0, late, first)),
        None => Ok(()),
    }
}

pub(super) fn describe_status(s: Status) -> String {
    match s.field() {
        StatusField::Error(e) => format!("0x{:02X} ({e})", s.0),
        StatusField::ParamsRemaining(n) => {
            format!("0x{:02X} (no error, {n} parameters wanted)", s.0)
        }
    }
}

pub(super) fn hex(b: &[u8]) -> String {
    b.iter()
        .map(|x| format!("0x{x:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

pub(super) fn opt(d: Option<Duration>) -> String {
    d.map_or("-".into(), |d| d.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{EmuTarget, Target, TargetError, TargetErrorKind, TargetInfo};
    use crate::emu::ModelConfig;
    use crate::protocol::Straps;
    use crate::scenario::{DriverOptions, Failure, Init, Move};

    /// The emulator, counting round trips and the ops in each.
    #[derive(Debug)]
    struct Counting {
        emu: EmuTarget,
        batches: Vec<usize>,
        captures: usize,
    }

    impl Counting {
        fn new() -> Counting {
            Counting {
                emu: EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator"),
                batches: Vec::new(),
                captures: 0,
            }
        }
    }

    impl Target for Counting {
        fn info(&self) -> TargetInfo {
            self.emu.info()
        }
        fn capture(&mut self) -> Result<Record, TargetError> {
            self.captures += 1;
            self.emu.capture()
        }
        fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
            self.batches.push(ops.len());
            self.emu.execute(ops)
        }
        /// As a board does it: one round trip for both.
        fn execute_then_capture(
            &mut self,
            ops: &[Op],
        ) -> Result<(Vec<Reply>, Record), TargetError> {
            self.batches.push(ops.len());
            Ok((self.emu.execute(ops)?, self.emu.capture()?))
        }
    }

    fn failure(o: Outcome) -> Failure {
        match o {
            Err(Stop::Failed(f)) => f,
            other => panic!("expected a device failure, got {other:?}"),
        }
    }

    #[test]
    fn steps_that_need_no_reply_go_in_one_batch_with_the_next_that_does() {
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        d.init(Init::four_phase()).expect("queued");
        d.wait(Duration::from_millis(20)).expect("queued");
        d.expect_no_error().expect("queued");
        let status = d.status().expect("runs");
        assert_eq!(status.0 & 0x80, 0, "no error after a valid initialization");
        drop(d);
        assert_eq!(t.batches.len(), 1, "one round trip: {:?}", t.batches);
        assert!(
            t.batches[0] > 6,
            "reset, five writes and more: {:?}",
            t.batches
        );
    }

    #[test]
    fn replies_are_judged_in_order_so_the_first_failure_in_time_is_reported() {
        // Section 3-1-1: a data byte before any command is error 3. The
        // scenario wrongly expects error 2 first, then error 1: the
        // failure reported must be the first one, at the first check.
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        d.data(0x55).expect("queued");
        d.expect_error(ErrorCode::NotInitialized).expect("queued");
        d.wait(Duration::from_millis(1)).expect("queued");
        d.expect_error(ErrorCode::NotAllowedWhileBusy)
            .expect("queued");
        let f = failure(d.flush());
        assert_eq!(f.expected, ErrorCode::NotInitialized.to_string(), "{f}");
        assert!(f.got.contains("error 3"), "{f}");
    }

    #[test]
    fn intervals_within_a_percent_of_nominal_pass_and_two_percent_off_fail() {
        // Section 3-3-5: a constant move at rate 50 (four-phase, internal
        // clock, reference straps) pulses at one interval; a band of 1 %
        // around it passes, the same band around an interval 2 % longer
        // fails and says both.
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.run(Move::constant(Direction::Cw, 50, 100)).expect("runs");
        let period = d.period(50);
        d.expect_intervals_within(period, 1.0)
            .expect("on the nominal");
        d.flush().expect("within 1 %");
        let off = Duration::from_nanos(period.as_nanos() * 102 / 100);
        d.expect_intervals_within(off, 1.0).expect("queued");
        let f = failure(d.flush());
        assert_eq!(f.expectation, "every pulse interval", "{f}");
        assert!(f.expected.starts_with(&format!("within {off} ± ")), "{f}");
        assert_eq!(f.got, format!("from {period} to {period}"), "{f}");
    }

    #[test]
    fn a_capture_check_queued_alone_after_a_flush_is_judged() {
        // A check of the capture with nothing queued before it: it once
        // went unjudged, and this wrong one passed.
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.run(Move::constant(Direction::Cw, 50, 100)).expect("runs");
        d.flush().expect("runs");
        d.expect_intervals(Duration::from_nanos(1), Duration::from_nanos(2))
            .expect("queued");
        let f = failure(d.finish());
        assert_eq!(f.expectation, "pulse intervals (min, max)", "{f}");
    }

    /// A driver right after the tenth pulse of a 100-step constant move
    /// (Section 3-3-5).
    fn ten_pulses_into_a_move(t: &mut Counting) -> Driver<'_> {
        let mut d = Driver::new(t, DriverOptions::default());
        d.reset().expect("queued");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.start(Move::constant(Direction::Cw, 50, 100))
            .expect("queued");
        d.after_pulses(10).expect("queued");
        d
    }

    #[test]
    fn a_pulse_check_is_judged_on_the_capture_where_it_was_asked() {
        // Checked after its tenth pulse, the move has 10 pulses, though
        // the capture that comes back at the end holds all 100.
        let mut t = Counting::new();
        let mut d = ten_pulses_into_a_move(&mut t);
        d.expect_pulses(10, Direction::Cw).expect("queued");
        d.wait_idle().expect("queued");
        d.expect_pulses(100, Direction::Cw).expect("queued");
        d.finish().expect("both checks hold");
        assert_eq!(d.capture().expect("capture").last_move_pulses().count, 100);

        let mut t = Counting::new();
        let mut d = ten_pulses_into_a_move(&mut t);
        d.expect_pulses(100, Direction::Cw).expect("queued");
        let f = failure(d.finish());
        assert!(f.got.starts_with("10 "), "{f}");
    }

    #[test]
    fn the_capture_comes_back_with_the_last_batch_not_in_a_round_trip_of_its_own() {
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.run(Move::accel(Direction::Cw, 1)).expect("queued");
        d.expect_pulses(1, Direction::Cw).expect("queued");
        d.finish().expect("holds");
        let trips = {
            let _ = d.capture().expect("capture");
            drop(d);
            t.batches.len()
        };
        assert_eq!(trips, 1, "{:?}", t.batches);
        assert_eq!(t.captures, 0, "no separate capture request");
    }

    #[test]
    fn a_long_queue_is_sent_in_batches_of_at_most_max_queued_groups() {
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, DriverOptions::default());
        for _ in 0..(2 * MAX_QUEUED + 1) {
            d.wait(Duration::from_micros(1)).expect("queued");
        }
        d.flush().expect("runs");
        drop(d);
        assert_eq!(t.batches, vec![MAX_QUEUED, MAX_QUEUED, 1]);
    }

    /// A target whose cable is pulled.
    #[derive(Debug)]
    struct Unplugged;

    impl Target for Unplugged {
        fn info(&self) -> TargetInfo {
            TargetInfo {
                name: "unplugged".into(),
                straps: Straps::default(),
                extra: Vec::new(),
            }
        }
        fn capture(&mut self) -> Result<Record, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
        fn execute(&mut self, _: &[Op]) -> Result<Vec<Reply>, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
    }

    #[test]
    fn a_target_failure_is_a_harness_error_that_keeps_its_kind() {
        let mut t = Unplugged;
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset().expect("queued");
        match d.flush() {
            Err(Stop::Error(HarnessError::Target { kind, message })) => {
                assert_eq!(kind, TargetErrorKind::Link);
                assert_eq!(message, "cable pulled");
            }
            other => panic!("expected a link error, got {other:?}"),
        }
    }

    #[test]
    fn a_scenario_past_its_budget_is_a_budget_error_not_a_failure() {
        let opts = DriverOptions {
            budget: Duration::from_millis(1),
            ..DriverOptions::default()
        };
        let mut t = Counting::new();
        let mut d = Driver::new(&mut t, opts);
        d.wait(Duration::from_millis(2)).expect("queued");
        d.flush().expect("the first batch runs");
        assert_eq!(
            d.status(),
            Err(Stop::Error(HarnessError::Budget(Duration::from_millis(1))))
        );
    }
}
