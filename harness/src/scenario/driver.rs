//! The driver a scenario is written against: flowchart-style helpers over a
//! [`Target`], a raw layer to break the protocol on purpose, and
//! expectations that stop the scenario at the first thing that went wrong.
//!
//! The author API lives here. The driver owns a `Batch`, which queues
//! its steps into round trips and judges them (`batch.rs`, with the steps
//! in `steps.rs` and the deferred checks in `check.rs`); the Table 3-3
//! measurements are in `measure.rs`.

use super::batch::{Batch, Limits};
use super::builders::{Init, Move};
use super::check::Check;
use super::outcome::{fail, fail_outside, outside, HarnessError, Outcome, Stop};
use super::steps::{Done, Role, Step};
use crate::backend::{Op, Reply, Target, Uncertainty};
use crate::protocol::{
    ClockSource, Direction, ErrorCode, Flag, Input, OutputRecord, Pins, Register, Status, Straps,
    TimingId,
};
use crate::time::{Duration, Instant};
use crate::trace::{BusEvent, Event};
use ppmc_record::{Deviation, DeviationUnit, Grade, Measurement};

// Defined beside the driver, and public here as they always were.
pub use super::options::DriverOptions;
pub use super::outcome::Shown;

/// Drives one scenario on a target and records what it saw.
pub struct Driver<'t> {
    /// The target, the steps queued for it, and what came back: the bus
    /// log, the clock, the times measurements start from, the capture.
    pub(super) batch: Batch<'t>,
    pub(super) opts: DriverOptions,
    pub(super) measurements: Vec<Measurement>,
    pub(super) init: Option<Init>,
    pub(super) straps: Straps,
    /// How sure the target's times are, by path
    /// ([`Target::uncertainty`]): a measurement's is its two ends'.
    pub(super) u: Uncertainty,
}

impl std::fmt::Debug for Driver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Driver")
            .field("now", &self.batch.clock())
            .field("anchor", &self.batch.anchor())
            .finish_non_exhaustive()
    }
}

impl<'t> Driver<'t> {
    pub fn new(target: &'t mut dyn Target, opts: DriverOptions) -> Self {
        let straps = target.straps();
        let u = target.uncertainty();
        let opts = DriverOptions {
            ibf_timeout: straps.stretch(opts.ibf_timeout),
            obf_timeout: straps.stretch(opts.obf_timeout),
            busy_timeout: straps.stretch(opts.busy_timeout),
            idle_timeout: straps.stretch(opts.idle_timeout),
            budget: straps.stretch(opts.budget),
            ..opts
        };
        let limits = Limits {
            ibf_timeout: opts.ibf_timeout,
            obf_timeout: opts.obf_timeout,
            budget: opts.budget,
        };
        Driver {
            straps,
            u,
            batch: Batch::new(target, limits),
            opts,
            measurements: Vec::new(),
            init: None,
        }
    }

    /// The bus events and measurements recorded so far.
    /// The scenario's body is over: its `--timeout` no longer applies.
    pub(crate) fn lift_deadline(&mut self) {
        self.batch.lift_deadline();
    }

    pub(crate) fn into_parts(self) -> (Vec<Event>, Vec<Measurement>) {
        (self.batch.into_bus(), self.measurements)
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
        self.period_on(ClockSource::Internal, rate)
            .unwrap_or(Duration::from_micros(2))
    }

    /// The pulse period of rate value `rate` on `clock` (Equations 3-1..3-4,
    /// VSEL included); `None` on an external clock the board lacks.
    pub fn period_on(&self, clock: ClockSource, rate: u8) -> Option<Duration> {
        let t = self.straps.tclock(clock)?;
        Some(self.straps.pulse_interval(rate, t))
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
        Ok(self.batch.clock())
    }

    /// The clock as of the last op sent (for reports).
    pub(crate) fn clock(&self) -> Instant {
        self.batch.clock()
    }

    /// Sends everything queued as one batch, then logs and judges the
    /// replies in order, stopping at the first failure. Ops queued after a
    /// failing one have run on the target too; the verdict and the failure
    /// are those of the first failing step.
    pub fn flush(&mut self) -> Outcome {
        self.batch.flush()
    }

    /// Flushes what is queued at the end of a scenario, fetching the
    /// capture in the same round trip.
    pub fn finish(&mut self) -> Outcome {
        self.batch.finish()
    }

    /// Steps that play no role for the measurements.
    fn plain(steps: impl IntoIterator<Item = Step>) -> Vec<(Step, Role)> {
        steps.into_iter().map(|s| (s, Role::Plain)).collect()
    }

    /// Queues a write of the command (`command`) or data register, after
    /// IBF = 0 if `wait`.
    fn write(&mut self, byte: u8, command: bool, wait: bool, role: Role) -> Outcome {
        self.batch.enqueue(
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

    // ----- raw layer -------------------------------------------------------

    /// Runs ops on the target (after everything queued); a target failure
    /// stops the scenario as an error (not the device's fault).
    pub fn exec(&mut self, ops: &[Op]) -> Outcome<Vec<Reply>> {
        Ok(self.batch.flush_with(ops, false)?.1)
    }

    /// Puts a bus transaction into the scenario's trace: for code that
    /// runs raw ops with [`Driver::exec`] and wants them shown.
    pub fn log_bus(&mut self, at: Instant, e: BusEvent) {
        self.batch.log_bus(at, e);
    }

    /// Hardware reset; every scenario starts with one.
    pub fn reset(&mut self) -> Outcome {
        self.batch.forget_marks();
        self.init = None;
        self.batch.enqueue(Self::plain([Step::Reset]), None)
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
        match self.batch.step(Step::Status)? {
            Done::Status(s) => Ok(s),
            _ => Err(Stop::Error(HarnessError::Reply(
                "status read answered otherwise".into(),
            ))),
        }
    }

    /// Flowchart read of the data register (waits for OBF = 1).
    pub fn read_data(&mut self) -> Outcome<u8> {
        match self.batch.step(Step::ReadData)? {
            Done::Byte(b) => Ok(b),
            _ => Err(Stop::Error(HarnessError::Reply(
                "data read answered otherwise".into(),
            ))),
        }
    }

    /// Waits until `flag` has `value`; `Some(waited)` or `None` on timeout.
    /// `timeout` is taken as given: a scenario that expects `None` (the
    /// flag must not come within it) chooses it from the straps itself.
    pub fn await_flag(
        &mut self,
        flag: Flag,
        value: bool,
        timeout: Duration,
    ) -> Outcome<Option<Duration>> {
        match self.batch.step(Step::Await {
            flag,
            value,
            timeout,
            must: false,
        })? {
            Done::Waited(w) => Ok(w),
            _ => Err(Stop::Error(HarnessError::Reply(
                "await answered otherwise".into(),
            ))),
        }
    }

    /// Waits for a flag and fails the scenario if it does not come within
    /// `timeout` (given for the reference board, stretched for a slower
    /// one).
    pub fn expect_flag(&mut self, flag: Flag, value: bool, timeout: Duration) -> Outcome {
        let timeout = self.straps.stretch(timeout);
        self.batch.enqueue(
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
        self.batch.enqueue(Self::plain([Step::Delay(d)]), None)
    }

    /// Drives an input (`on` = asserted, pin low). An assertion counts as
    /// the trigger for latency measurements.
    pub fn set(&mut self, input: Input, on: bool) -> Outcome {
        let role = if on { Role::Trigger } else { Role::Plain };
        self.batch
            .enqueue(vec![(Step::Set { input, on }, role)], None)
    }

    /// Waits until the move in progress has output `n` pulses; the next op
    /// acts right after that pulse, on the target's clock.
    pub fn after_pulses(&mut self, n: u64) -> Outcome {
        let timeout = self.opts.idle_timeout;
        self.batch
            .enqueue(Self::plain([Step::AwaitPulses { count: n, timeout }]), None)
    }

    /// The output pins now.
    pub fn pins(&mut self) -> Outcome<Pins> {
        match self.batch.step(Step::Pins)? {
            Done::Pins(p) => Ok(p),
            _ => Err(Stop::Error(HarnessError::Reply(
                "pins read answered otherwise".into(),
            ))),
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
        let stamps = self.u.access.saturating_mul(2);
        let stretch = |level: bool| chop_stretch(&samples, level, on.min(off), stamps);
        let now = self.batch.clock();
        for (name, level, want) in [("switching_on", true, on), ("switching_off", false, off)] {
            let Some((got, at, u)) = stretch(level) else {
                return Err(fail(
                    format!("{name}: stop switching chops the phases"),
                    "ON and OFF stretches",
                    "none seen",
                    now,
                ));
            };
            let slack = want.scale(1, 100) + step;
            let m = self.opts.grading.grade_in(
                name,
                want.saturating_sub(slack),
                want + slack,
                got,
                u,
                at,
            );
            let grade = m.grade;
            let (lo, hi, m_shown) = (m.lo, m.hi, m.shown());
            let deviation = Deviation::of_measurement(&m);
            self.measurements.push(m);
            if grade == Grade::Fail {
                return Err(fail_outside(
                    format!("{name} (Equations 3-5..3-8)"),
                    format!("{lo} to {hi}"),
                    m_shown,
                    at,
                    deviation,
                ));
            }
        }
        Ok(())
    }

    /// The capture since reset (fetched once per change, after everything
    /// queued has run).
    pub fn capture(&mut self) -> Outcome<&OutputRecord> {
        self.batch.capture()
    }

    // ----- flowchart helpers ---------------------------------------------

    /// Waits for BUSY = 0, then IBF = 0: the condition every flowchart puts
    /// before an operation command.
    pub fn wait_ready(&mut self) -> Outcome {
        let steps = Self::plain(self.ready_steps());
        self.batch.enqueue(steps, None)
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
        self.batch.enqueue(steps, None)
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
        self.batch.enqueue(steps, None)
    }

    /// Issues a move's command and data without waiting for BUSY (for
    /// scenarios that expect it to be refused).
    pub fn issue(&mut self, m: Move) -> Outcome {
        let mut steps = Self::plain(self.ready_steps());
        steps.extend(Self::command_steps(m.code(), &m.params(), Role::Anchor));
        self.batch.enqueue(steps, None)
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
            .batch
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
    pub fn check<T: PartialEq + Shown>(&mut self, what: &str, expected: T, got: T) -> Outcome {
        self.flush()?;
        if expected != got {
            return Err(fail(
                what,
                expected.shown(),
                got.shown(),
                self.batch.clock(),
            ));
        }
        Ok(())
    }

    /// Expects the error flag with `code` (Table 3-2).
    pub fn expect_error(&mut self, code: ErrorCode) -> Outcome {
        let steps = self.settled_status_steps();
        self.batch.enqueue(steps, Some(Check::Error(code)))
    }

    /// Expects no error flag.
    pub fn expect_no_error(&mut self) -> Outcome {
        let steps = self.settled_status_steps();
        self.batch.enqueue(steps, Some(Check::NoError))
    }

    /// Expects status bits 6-4 to count `n` parameter bytes still wanted.
    pub fn expect_params_remaining(&mut self, n: u8) -> Outcome {
        let steps = self.settled_status_steps();
        self.batch.enqueue(steps, Some(Check::Params(n)))
    }

    /// Expects `status & mask == value`.
    pub fn expect_status(&mut self, mask: u8, value: u8) -> Outcome {
        self.batch.enqueue(
            Self::plain([Step::Status]),
            Some(Check::StatusMask { mask, value }),
        )
    }

    fn expect_register(&mut self, reg: Register, what: &'static str, expected: &[u8]) -> Outcome {
        let steps = self.register_steps(reg);
        self.batch.enqueue(
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
        self.batch
            .enqueue(Vec::new(), Some(Check::Pulses { n, dir }))
    }

    /// Expects the most recent move's pulse count within `lo..=hi`.
    pub fn expect_pulses_between(&mut self, lo: u64, hi: u64) -> Outcome<u64> {
        let now = self.batch.clock();
        let s = self.capture()?.last_move_pulses();
        if s.count < lo || s.count > hi {
            let n = |v: u64| i64::try_from(v).unwrap_or(i64::MAX);
            return Err(fail_outside(
                "pulse count",
                format!("{lo} to {hi}"),
                s.count,
                s.last.unwrap_or(now),
                outside(n(lo), n(hi), n(s.count), DeviationUnit::Count, 0),
            ));
        }
        Ok(s.count)
    }

    /// Expects the shortest interval of the most recent move to be `min`
    /// and the longest to be `max`, each exactly (but for the capture's
    /// own bound on a bridge whose timer is not locked to the chip):
    /// a check of a ramp's ends, not a band. For "every interval within
    /// 1 % of 1 ms", [`Driver::expect_intervals_within`]. Deferred, as
    /// [`Driver::expect_pulses`].
    pub fn expect_intervals(&mut self, min: Duration, max: Duration) -> Outcome {
        self.batch
            .enqueue(Vec::new(), Some(Check::Intervals { min, max }))
    }

    /// Expects every interval of the most recent move within `percent` of
    /// `nominal` (and the capture's own bound, on a bridge whose timer is
    /// not locked to the chip): `d.expect_intervals_within(us(1_000),
    /// 1.0)` passes intervals of 990 to 1,010 us. Deferred, as
    /// [`Driver::expect_pulses`].
    pub fn expect_intervals_within(&mut self, nominal: Duration, percent: f64) -> Outcome {
        // To the nanosecond, never wider than asked.
        let tol = (nominal.as_nanos() as f64 * percent.abs() / 100.0).floor() as u64;
        let tolerance = Duration::from_nanos(tol);
        self.batch.enqueue(
            Vec::new(),
            Some(Check::IntervalsWithin { nominal, tolerance }),
        )
    }

    /// Expects no pulse of the most recent move after `t` (deferred, as
    /// [`Driver::expect_pulses`]).
    pub fn expect_no_pulses_after(&mut self, t: Instant) -> Outcome {
        self.batch
            .enqueue(Vec::new(), Some(Check::NoPulsesAfter(t)))
    }

    /// Expects no pulse of the most recent move later than `margin` after
    /// the last trigger (a stop write or an input edge); `margin` is a
    /// firmware time at 16 MHz, longer on a slower clock.
    pub fn expect_no_pulses_after_trigger(&mut self, margin: Duration) -> Outcome {
        // The chip's reaction is a firmware time: longer on a slower clock.
        let margin = self.fw(margin).max(margin);
        self.batch
            .enqueue(Vec::new(), Some(Check::NoPulsesAfterTrigger(margin)))
    }

    /// Expects the energized phases (S1 in bit 4).
    pub fn expect_phases(&mut self, pattern: u8) -> Outcome {
        self.batch
            .enqueue(Self::plain([Step::Pins]), Some(Check::Phases(pattern)))
    }

    /// Expects output pins: each `Some` is checked.
    pub fn expect_pins(
        &mut self,
        int: Option<bool>,
        hold: Option<bool>,
        aux: Option<bool>,
        auxo: Option<u8>,
    ) -> Outcome {
        self.batch.enqueue(
            Self::plain([Step::Pins]),
            Some(Check::Pins {
                int,
                hold,
                aux,
                auxo,
            }),
        )
    }
}

/// The first full stretch of stop switching's chopping at `level` (ON:
/// any phase energized) in `samples`: from the edge that starts it to the
/// edge that ends it, the time of its end, and its uncertainty (the two
/// samples' `stamps`, and the larger of the gaps its two edges lie in: the
/// sampling's own resolution). Only a stretch sampled throughout counts:
/// no gap between samples, at its ends or within, as long as `shortest`
/// (the shorter of ON and OFF), which could hide a whole stretch.
fn chop_stretch(
    samples: &[(Instant, Pins)],
    level: bool,
    shortest: Duration,
    stamps: Duration,
) -> Option<(Duration, Instant, Duration)> {
    // Each edge: its time, its new level, the gap it lies in, and the
    // widest gap since the edge before.
    let mut edges: Vec<(Instant, bool, Duration, Duration)> = Vec::new();
    let mut widest = Duration::ZERO;
    for w in samples.windows(2) {
        let gap = w[1].0.saturating_since(w[0].0);
        let (a, b) = (w[0].1.phases != 0, w[1].1.phases != 0);
        if a != b {
            edges.push((w[1].0, b, gap, widest));
            widest = Duration::ZERO;
        } else {
            widest = widest.max(gap);
        }
    }
    edges
        .windows(2)
        .find(|w| w[0].1 == level && w[1].1 != level && w[0].2.max(w[1].2).max(w[1].3) < shortest)
        .map(|w| {
            let u = stamps.saturating_add(w[0].2.max(w[1].2));
            (w[1].0.saturating_since(w[0].0), w[1].0, u)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of the phases (`true`: energized) at the given times (us).
    fn sampled(points: &[(u64, bool)]) -> Vec<(Instant, Pins)> {
        points
            .iter()
            .map(|&(t, on)| {
                let pins = Pins {
                    int: false,
                    hold: true,
                    aux: false,
                    auxo: 0,
                    phases: if on { 0b00011 } else { 0 },
                    phase_levels: if on { 0b00011 } else { 0 },
                    dir: ppmc_core::protocol::Direction::Cw,
                    busy: false,
                };
                (Instant::from_nanos(t * 1_000), pins)
            })
            .collect()
    }

    /// Section 3-5-1's chopping, 65 us ON and 108.75 us OFF, sampled every
    /// microsecond but for a gap of 6.7 ms (a bridge's samples in two
    /// runs, with its bookkeeping between): the OFF stretch across the gap
    /// may hide ON stretches, and is not measured; the next one, sampled
    /// throughout, is.
    #[test]
    fn a_stretch_across_a_gap_that_could_hide_a_stretch_is_not_measured() {
        let level = |t: u64| (t % 174) < 65;
        let mut points: Vec<(u64, bool)> = (0..130).map(|t| (t, level(t))).collect();
        points.extend((6_830..7_400).map(|t| (t, level(t))));
        let s = sampled(&points);
        let (off, end, u) = chop_stretch(&s, false, Duration::from_micros(65), Duration::ZERO)
            .expect("an OFF stretch sampled throughout");
        assert!(
            end.as_nanos() > 6_830_000,
            "measured across the gap: ends at {end}"
        );
        assert_eq!(off, Duration::from_micros(109), "{off}");
        assert_eq!(u, Duration::from_micros(1));
    }
}
