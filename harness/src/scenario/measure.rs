//! Table 3-3 measurements: each latency taken from the trace of the
//! scenario so far, graded against its band at this board's straps.

use super::driver::Driver;
use super::outcome::{fail, need, Failure, HarnessError, Outcome, Stop};
use crate::protocol::{Flag, Pin, Register, TimingId};
use crate::time::{Duration, Instant, Limit};
use ppmc_record::{signed_ns, Bound, Deviation, DeviationUnit, Grade, Reference};

/// By how much a deceleration that started from pulse index `j1` (of
/// `times`, after the trigger at `t`) missed its latency band `lo` to
/// `hi`: one run brackets the latency between the pulse before `j1` and
/// `j1`, so a late start's latency is at least the time to the pulse
/// before, an early one's at most the time to `j1` (each as sure as an
/// edge, `edge`).
fn bracketed(
    times: &[Instant],
    t: Instant,
    j1: u64,
    j_hi: u64,
    lo: Duration,
    hi: Duration,
    edge: Duration,
) -> Deviation {
    let after = |j: u64| {
        times
            .get(j as usize)
            .map_or(Duration::ZERO, |p| p.saturating_since(t))
    };
    let (measured, reference, bound) = if j1 > j_hi {
        (after(j1 - 1), hi, Bound::AtLeast)
    } else {
        (after(j1), lo, Bound::AtMost)
    };
    Deviation {
        unit: DeviationUnit::Ns,
        measured: signed_ns(measured),
        reference: signed_ns(reference),
        reference_is: Reference::Limit,
        u: edge.as_nanos(),
        bound: Some(bound),
    }
}

impl Driver<'_> {
    /// Grades a measurement whose two ends are as sure as `u`, together.
    fn record_measure(
        &mut self,
        id: TimingId,
        value: Duration,
        u: Duration,
        at: Instant,
    ) -> Outcome<Grade> {
        let m = self.opts.grading.grade(id, &self.straps, value, u, at);
        let grade = m.grade;
        let (lo, hi, got) = (m.lo, m.hi, m.shown());
        let deviation = Deviation::of_measurement(&m);
        self.measurements.push(m);
        if grade == Grade::Fail {
            return Err(Stop::Failed(Failure {
                expectation: format!("{} (Table 3-3)", id.name()),
                expected: format!("{lo} to {}", Limit(hi)),
                got,
                at,
                deviation: Some(deviation),
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

    /// [`need`] of a time set by a queued step: flushes first.
    fn flushed(&mut self, what: &str, t: fn(&Self) -> Option<Instant>) -> Outcome<Instant> {
        self.flush()?;
        need(what, t(self))
    }

    fn last_move_pulse_times(&mut self) -> Outcome<(Instant, Instant)> {
        let now = self.batch.clock();
        let s = self.capture()?.last_move_pulses();
        match (s.first, s.last) {
            (Some(a), Some(b)) => Ok((a, b)),
            _ => Err(fail("the move output pulses", "at least 1", 0, now)),
        }
    }

    /// Measures the Table 3-3 quantity `id` from what has happened so far
    /// and grades it. A FAIL stops the scenario; MARGINAL is recorded.
    pub fn expect_latency(&mut self, id: TimingId) -> Outcome<Duration> {
        // Each end, and how sure the target is of it: a write or an input
        // change is an access's stamp, a pulse an edge, a pin change its
        // pin's path.
        let u = self.u;
        let ((from, u_from), (to, u_to)) = match id {
            TimingId::BusyRise => {
                let a = self.flushed("an operation command", |d| d.batch.anchor())?;
                (
                    (a, u.access),
                    (self.pin_after(Pin::Busy, Some(1), a)?, u.of_pin(Pin::Busy)),
                )
            }
            TimingId::AccelFirstPout | TimingId::ConstantFirstPout => {
                let a = self.flushed("an operation command", |d| d.batch.anchor())?;
                let (first, _) = self.last_move_pulse_times()?;
                ((a, u.access), (Some(first), u.edge))
            }
            TimingId::SingleStep => {
                let a = self.flushed("an operation command", |d| d.batch.anchor())?;
                (
                    (a, u.access),
                    (self.pin_after(Pin::Busy, Some(0), a)?, u.of_pin(Pin::Busy)),
                )
            }
            TimingId::InterruptOutput => {
                let (_, last) = self.last_move_pulse_times()?;
                (
                    (last, u.edge),
                    (self.pin_after(Pin::Int, Some(1), last)?, u.of_pin(Pin::Int)),
                )
            }
            TimingId::HoldOn => {
                let (_, last) = self.last_move_pulse_times()?;
                (
                    (last, u.edge),
                    (
                        self.pin_after(Pin::Hold, Some(1), last)?,
                        u.of_pin(Pin::Hold),
                    ),
                )
            }
            TimingId::AbnormalTermination => {
                let t = self.flushed("a stop or limit", |d| d.batch.trigger())?;
                (
                    (t, u.access),
                    (self.pin_after(Pin::Busy, Some(0), t)?, u.of_pin(Pin::Busy)),
                )
            }
            TimingId::AuxOn => {
                let t = self.flushed("an AUX ON command", |d| d.batch.trigger())?;
                (
                    (t, u.access),
                    (self.pin_after(Pin::Aux, Some(1), t)?, u.of_pin(Pin::Aux)),
                )
            }
            TimingId::AuxOff => {
                let t = self.flushed("an AUX OFF command", |d| d.batch.trigger())?;
                (
                    (t, u.access),
                    (self.pin_after(Pin::Aux, Some(0), t)?, u.of_pin(Pin::Aux)),
                )
            }
            TimingId::ExcitationOff => {
                let t = self.flushed("a software reset", |d| d.batch.trigger())?;
                (
                    (t, u.access),
                    (
                        self.pin_after(Pin::Phases, Some(0), t)?,
                        u.of_pin(Pin::Phases),
                    ),
                )
            }
            TimingId::InitOutputsSet => {
                let t = self.flushed("an initialization", |d| d.batch.init_write())?;
                (
                    (t, u.access),
                    (self.pin_after(Pin::Phases, None, t)?, u.of_pin(Pin::Phases)),
                )
            }
            TimingId::InitProcessing => return self.measure_init_processing(),
            TimingId::NextCommand => return self.measure_next_command(),
            TimingId::DecelStopProcessing
            | TimingId::HighSpeedLimitAccel
            | TimingId::HighSpeedLimitCruise => return self.expect_decel_start(id),
        };
        let now = self.batch.clock();
        let to = to.ok_or_else(|| {
            fail(
                format!("{} (Table 3-3): the event it ends with", id.name()),
                "observed",
                "never happened",
                now,
            )
        })?;
        let value = to.saturating_since(from);
        self.record_measure(id, value, u_from.saturating_add(u_to), to)?;
        Ok(value)
    }

    /// Initialization processing: from the final data byte until the chip
    /// takes the next command (an input status read, harmless once its
    /// byte is read).
    fn measure_init_processing(&mut self) -> Outcome<Duration> {
        let timeout = self.opts.ibf_timeout;
        self.expect_flag(Flag::Ibf, false, timeout)?;
        self.raw_command(Register::InputSignals.code())?;
        self.expect_flag(Flag::Ibf, false, timeout)?;
        let t = self.flushed("an initialization", |d| d.batch.init_write())?;
        let value = self.batch.clock().saturating_since(t);
        let at = self.batch.clock();
        self.drain_probe()?;
        // From the final byte's write to the end of the wait for IBF.
        let u = self.u.access.saturating_add(self.u.polled);
        self.record_measure(TimingId::InitProcessing, value, u, at)?;
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
        let value = self.batch.clock().saturating_since(last);
        let at = self.batch.clock();
        self.drain_probe()?;
        // From the last pulse to the end of the wait for IBF.
        let u = self.u.edge.saturating_add(self.u.polled);
        self.record_measure(TimingId::NextCommand, value, u, at)?;
        Ok(value)
    }

    /// Reads the byte the probe (an input status read) puts in the data
    /// register. Left there, it would be what the scenario's next register
    /// read gets whenever the host's next request comes after the chip
    /// answered the probe, as on every real board (section 3-1: the host
    /// reads the data register when OBF = 1).
    fn drain_probe(&mut self) -> Outcome {
        self.read_data().map(drop)
    }

    /// The deceleration latencies: after the move, the pulse count says from
    /// which pulse the deceleration started; it must be the first pulse
    /// after the trigger plus a latency inside the row's band. A pass/fail
    /// check, not a graded measurement: one run only brackets the latency
    /// between two pulses. Returns the time from the trigger to that pulse.
    fn expect_decel_start(&mut self, id: TimingId) -> Outcome<Duration> {
        let pa = self.init.map(|i| u64::from(i.data.pa)).ok_or_else(|| {
            Stop::Error(HarnessError::Scenario(
                "scenario bug: measuring needs an initialization".into(),
            ))
        })?;
        self.wait_idle()?;
        let t = self.flushed("a decelerating stop or high-speed limit", |d| {
            d.batch.trigger()
        })?;
        let rec = self.capture()?;
        let from = rec.moves.last().map_or(0, |m| m.first_run);
        let before: u64 = rec.runs[..from].iter().map(|r| u64::from(r.count)).sum();
        let times: Vec<Instant> = rec.runs[from..]
            .iter()
            .flat_map(|r| (0..r.count).map(move |i| r.at(i)))
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
        let start_time = times
            .get(j1 as usize)
            .copied()
            .unwrap_or(self.batch.clock());
        if j1 < j_lo || j1 > j_hi {
            // Pulses numbered from 1 over the whole scenario, as every
            // report numbers them (a golden comparison, the plots): the
            // move's pulse at index j is the scenario's pulse before + j + 1.
            let (first, last, got) = (before + j_lo + 1, before + j_hi + 1, before + j1 + 1);
            let expected = match first == last {
                true => format!("from pulse {first}"),
                false => format!("from pulse {first} to {last}"),
            };
            return Err(Stop::Failed(Failure {
                expectation: format!(
                    "{} (Table 3-3): deceleration starts at the first pulse after the latency",
                    id.name()
                ),
                expected: format!("{expected} (latency {lo} to {})", Limit(hi)),
                got: format!("from pulse {got}"),
                at: start_time,
                deviation: Some(bracketed(&times, t, j1, j_hi, lo, hi, self.u.edge)),
            }));
        }
        // The latency itself lies between the pulse before j1 and j1; what is
        // observable is how long after the trigger the first pulse of the
        // deceleration came.
        Ok(start_time.saturating_since(t))
    }
}
