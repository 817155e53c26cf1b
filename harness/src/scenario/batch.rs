//! How a driver's steps reach the target: a [`Batch`] queues the steps
//! that need no reply yet, sends them in one batch with the next step
//! whose result the scenario must see, and judges the replies in order
//! when they come back, so that a scenario on a board costs a round trip
//! per point where it looks, not one per call. Deferred checks are judged
//! on their group's replies, or on the capture as it stood where they
//! were queued.

use super::check::Check;
use super::outcome::{fail, HarnessError, Outcome, Stop};
use super::steps::{Done, Role, Step};
use crate::backend::{Op, Reply, Target};
use crate::protocol::OutputRecord;
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, Event, EventKind};

/// Steps queued to go to the target together, and what to check of them.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Group {
    steps: Vec<(Step, Role)>,
    check: Option<Check>,
}

/// Most groups a batch queues before it sends them anyway.
const MAX_QUEUED: usize = 64;

/// What a batch takes of the driver's options, stretched for the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Limits {
    /// Flowchart writes wait at most this long for IBF = 0.
    pub(super) ibf_timeout: Duration,
    /// Flowchart reads wait at most this long for OBF = 1.
    pub(super) obf_timeout: Duration,
    /// Virtual time the scenario may use before it is stopped as an error.
    pub(super) budget: Duration,
}

/// A driver's way to its target: the steps queued and not yet sent, and
/// what came back of those sent: the bus transactions for the trace, the
/// target's clock, the times measurements start from, and the capture.
pub(super) struct Batch<'t> {
    target: &'t mut dyn Target,
    limits: Limits,
    /// Steps not yet sent (see [`Batch::flush`]).
    queue: Vec<Group>,
    bus: Vec<Event>,
    now: Instant,
    /// Final write of the most recent operation command.
    anchor: Option<Instant>,
    /// Final write of the most recent initialization.
    init_write: Option<Instant>,
    /// The most recent stop write, input edge or auxiliary command write.
    trigger: Option<Instant>,
    capture: Option<OutputRecord>,
}

impl<'t> Batch<'t> {
    pub(super) fn new(target: &'t mut dyn Target, limits: Limits) -> Self {
        Batch {
            target,
            limits,
            queue: Vec::new(),
            bus: Vec::new(),
            now: Instant::ZERO,
            anchor: None,
            init_write: None,
            trigger: None,
            capture: None,
        }
    }

    /// The target's clock as of the last op sent.
    pub(super) fn clock(&self) -> Instant {
        self.now
    }

    /// Final write of the most recent operation command, once sent.
    pub(super) fn anchor(&self) -> Option<Instant> {
        self.anchor
    }

    /// Final write of the most recent initialization, once sent.
    pub(super) fn init_write(&self) -> Option<Instant> {
        self.init_write
    }

    /// The most recent stop write, input edge or auxiliary command write,
    /// once sent.
    pub(super) fn trigger(&self) -> Option<Instant> {
        self.trigger
    }

    /// Forgets the times measurements start from (at a reset).
    pub(super) fn forget_marks(&mut self) {
        self.anchor = None;
        self.init_write = None;
        self.trigger = None;
    }

    /// The bus events logged so far.
    /// Lifts the target's wall-clock deadline (`--timeout`): what comes
    /// after the scenario's body (fetching the capture it left) is not
    /// cut short by it.
    pub(super) fn lift_deadline(&mut self) {
        self.target.set_deadline(None);
    }

    pub(super) fn into_bus(self) -> Vec<Event> {
        self.bus
    }

    /// Puts a bus transaction into the scenario's trace.
    pub(super) fn log_bus(&mut self, at: Instant, e: BusEvent) {
        self.bus.push(Event {
            at,
            kind: EventKind::Bus(e),
        });
    }

    /// The capture since reset (fetched once per change, after everything
    /// queued has run).
    pub(super) fn capture(&mut self) -> Outcome<&OutputRecord> {
        self.flush_then(true)?;
        if self.capture.is_none() {
            let c = self
                .target
                .capture()
                .map_err(|e| Stop::Error(HarnessError::Capture(format!("target capture: {e}"))))?;
            self.capture = Some(c);
        }
        self.capture
            .as_ref()
            .ok_or_else(|| Stop::Error(HarnessError::Capture("capture unavailable".into())))
    }

    /// Runs ops on the target; with `capture`, also fetches the capture
    /// after them (one round trip less on a board).
    fn send_then(&mut self, ops: &[Op], capture: bool) -> Outcome<Vec<Reply>> {
        if self.now.as_nanos() > self.limits.budget.as_nanos() {
            return Err(Stop::Error(HarnessError::Budget(self.limits.budget)));
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

    fn unexpected(&self, op: &str, reply: &Reply) -> Stop {
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

    /// Sends everything queued as one batch, then logs and judges the
    /// replies in order, stopping at the first failure. Ops queued after a
    /// failing one have run on the target too; the verdict and the failure
    /// are those of the first failing step.
    pub(super) fn flush(&mut self) -> Outcome {
        self.flush_then(false)
    }

    /// Flushes what is queued at the end of a scenario, fetching the
    /// capture in the same round trip.
    pub(super) fn finish(&mut self) -> Outcome {
        self.flush_then(true)
    }

    /// [`Batch::flush`]; with `capture`, the capture after the batch comes
    /// back with it.
    fn flush_then(&mut self, capture: bool) -> Outcome {
        if self.queue.is_empty() {
            return Ok(());
        }
        self.flush_with(&[], capture).map(drop)
    }

    /// Sends everything queued and then `extra` as one batch (one round trip
    /// on a board), judges the queued groups as [`Batch::flush`] does, and
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
    fn step_op(&self, step: Step) -> Op {
        match step {
            Step::Write {
                byte,
                command,
                wait,
            } => {
                let wait_ibf = wait.then_some(self.limits.ibf_timeout);
                if command {
                    Op::WriteCommand { byte, wait_ibf }
                } else {
                    Op::WriteData { byte, wait_ibf }
                }
            }
            Step::Status => Op::ReadStatus,
            Step::ReadData => Op::ReadData {
                wait_obf: Some(self.limits.obf_timeout),
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

    /// Logs a step's reply ([`BusEvent::of`]) and judges it. `began` is when the step started
    /// (the end of the step before it).
    fn judge(&mut self, step: Step, reply: Reply, began: Instant) -> Outcome<Done> {
        if let Some(e) = BusEvent::of(&self.step_op(step), &reply) {
            self.log_bus(reply.at(), e);
        }
        match (step, reply) {
            (Step::Write { .. }, Reply::Written { .. }) => Ok(Done::At),
            (Step::Write { byte, .. }, Reply::WriteTimedOut { at, status }) => Err(fail(
                format!("IBF = 0 before writing 0x{byte:02X} (flowchart)"),
                format!("IBF = 0 within {}", self.limits.ibf_timeout),
                format!("status 0x{:02X}", status.0),
                at,
            )),
            (Step::Status, Reply::Status { status, .. }) => Ok(Done::Status(status)),
            (Step::ReadData, Reply::Data { byte, .. }) => Ok(Done::Byte(byte)),
            (Step::ReadData, Reply::ReadTimedOut { at, status }) => Err(fail(
                "OBF = 1 before reading (flowchart)",
                format!("OBF = 1 within {}", self.limits.obf_timeout),
                format!("status 0x{:02X}", status.0),
                at,
            )),
            (Step::Await { .. }, Reply::Awaited { waited, .. }) => Ok(Done::Waited(Some(waited))),
            (
                Step::Await {
                    flag,
                    value,
                    timeout,
                    must,
                },
                Reply::AwaitTimedOut { .. },
            ) => {
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
            (Step::Set { .. }, Reply::InputSet { .. }) => Ok(Done::At),
            (Step::AwaitPulses { .. }, Reply::PulsesReached { .. }) => Ok(Done::At),
            (Step::AwaitPulses { count: n, .. }, Reply::PulsesTimedOut { at, count }) => Err(fail(
                "pulses output so far",
                format!("at least {n}"),
                count,
                at,
            )),
            (Step::Reset, Reply::ResetDone { .. }) => Ok(Done::At),
            (Step::Pins, Reply::Pins { pins, .. }) => Ok(Done::Pins(pins)),
            (step, other) => Err(self.unexpected(&format!("`{}`", self.step_op(step)), &other)),
        }
    }

    /// Judges a deferred expectation on the results of its group; `at` is
    /// when the group's last step ended.
    fn judge_check(&self, c: &Check, done: &[Done], at: Instant) -> Outcome {
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
            return c.judge_capture(&rec, at, self.trigger);
        }
        c.judge_results(done, at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{EmuTarget, Target, TargetError, TargetErrorKind, TargetInfo};
    use crate::emu::ModelConfig;
    use crate::protocol::Straps;
    use crate::protocol::{Direction, ErrorCode};
    use crate::scenario::{Driver, DriverOptions, Failure, Init, Move};

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
        fn capture(&mut self) -> Result<OutputRecord, TargetError> {
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
        ) -> Result<(Vec<Reply>, OutputRecord), TargetError> {
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
        fn capture(&mut self) -> Result<OutputRecord, TargetError> {
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
