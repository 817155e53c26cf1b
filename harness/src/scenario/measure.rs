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
        let (before, times) = self.last_move_times()?;
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

    /// The pulses before the most recent move (all the scenario's), and
    /// that move's pulse times.
    fn last_move_times(&mut self) -> Outcome<(u64, Vec<Instant>)> {
        let rec = self.capture()?;
        let from = rec.moves.last().map_or(0, |m| m.first_run);
        let before: u64 = rec.runs[..from].iter().map(|r| u64::from(r.count)).sum();
        let times = rec.runs[from..]
            .iter()
            .flat_map(|r| (0..r.count).map(move |i| r.at(i)))
            .collect();
        Ok((before, times))
    }

    /// A latency probe's outcome (Table 3-3, section 3-6): the trigger was
    /// aimed `ahead` before pulse `index` (from 0) of the most recent move,
    /// just outside `id`'s band, so that the pulse count `check` expects
    /// says on which side of the band the latency lies. That holds only
    /// where the trigger landed on the aimed side of the band's edge. A
    /// count that differs is the device's failure where the trigger's
    /// stamp and the pulse's, with their uncertainty, put it surely on
    /// that side; otherwise the instrument missed its aim
    /// ([`HarnessError::Aim`]), and the count says nothing of the device.
    /// (What the device did is still held to the trigger's stamp, where
    /// it landed: [`Driver::expect_latency`].)
    pub fn expect_probe(
        &mut self,
        id: TimingId,
        index: u64,
        ahead: Duration,
        check: impl FnOnce(&mut Self) -> Outcome,
    ) -> Outcome {
        let (lo, hi) = id.row().band_for(&self.straps);
        let outside = ahead > hi || ahead < lo;
        if !outside {
            return Err(Stop::Error(HarnessError::Scenario(format!(
                "scenario bug: a probe of {} aimed {ahead} ahead, inside its band of {lo} to {}",
                id.name(),
                Limit(hi)
            ))));
        }
        let counted = check(self).and_then(|()| self.flush());
        let Err(Stop::Failed(failure)) = counted else {
            return counted;
        };
        let t = self.flushed("a probe's trigger", |d| d.batch.trigger())?;
        let (before, times) = self.last_move_times()?;
        let Some(&p) = times.get(index as usize) else {
            return Err(Stop::Failed(failure));
        };
        let got = p.saturating_since(t);
        let u = self.u.access.saturating_add(self.u.edge);
        let sure = if ahead > hi {
            got.saturating_sub(u) > hi
        } else {
            got.saturating_add(u) < lo
        };
        if sure {
            return Err(Stop::Failed(failure));
        }
        let edge = if ahead > hi { hi } else { lo };
        Err(Stop::Error(HarnessError::Aim(format!(
            "{} probe: the trigger was aimed {ahead} before pulse {}, and landed {got} \
             (±{u}) before it, not surely on the aimed side of the band's edge at {edge}; \
             the pulse count that then differed ({}) says nothing of the device",
            id.name(),
            before + index + 1,
            failure.got,
        ))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{EmuTarget, Op, Reply, Target, TargetError, TargetInfo};
    use crate::emu::ModelConfig;
    use crate::protocol::{Direction, OutputRecord, Straps};
    use crate::scenario::{DriverOptions, Init, Move};

    /// The emulator behind an instrument that lands the op after a wait
    /// for pulses `late` after its aim, as a bridge whose CPU is slower
    /// than its delays assume does.
    #[derive(Debug)]
    struct Late {
        emu: EmuTarget,
        late: Duration,
        after_await: bool,
    }

    impl Target for Late {
        fn info(&self) -> TargetInfo {
            self.emu.info()
        }
        fn capture(&mut self) -> Result<OutputRecord, TargetError> {
            self.emu.capture()
        }
        fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
            let ops: Vec<Op> = ops
                .iter()
                .map(|op| match *op {
                    Op::AwaitPulses { .. } => {
                        self.after_await = true;
                        *op
                    }
                    Op::Delay(d) if self.after_await => {
                        self.after_await = false;
                        Op::Delay(d + self.late)
                    }
                    _ => *op,
                })
                .collect();
            self.emu.execute(&ops)
        }
    }

    /// Section 3-6's Decelerating Stop probe (Table 3-3, 17 us): at high
    /// speed, the stop aimed 17.4 us before pulse 501, so that the
    /// deceleration starts from it and the move outputs 500 + PA pulses.
    fn decel_stop_probe(late: Duration, pulses: u64) -> Outcome {
        let mut t = Late {
            emu: EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator"),
            late,
            after_await: false,
        };
        let mut d = Driver::new(&mut t, DriverOptions::default());
        d.reset()?;
        d.init_and_wait(Init::four_phase())?;
        d.start(Move::accel(Direction::Cw, 5_000))?;
        d.after_pulses(500)?;
        let ahead = d.fw(Duration::from_nanos(17_400));
        d.wait(d.period(20).saturating_sub(ahead))?;
        d.decel_stop()?;
        d.expect_latency(TimingId::DecelStopProcessing)?;
        d.wait_idle()?;
        d.expect_probe(TimingId::DecelStopProcessing, 500, ahead, |d| {
            d.expect_pulses(pulses, Direction::Cw)
        })
    }

    #[test]
    fn a_probe_whose_trigger_landed_where_aimed_passes() {
        assert_eq!(decel_stop_probe(Duration::ZERO, 600), Ok(()));
    }

    /// The instrument landed the stop 2.6 us late (as the RP2350 image
    /// built by clippy's driver did on the emulated CPU): 14.8 us before
    /// pulse 501, inside the band, where either count is the chip's right.
    /// The count then differs from the probe's, and the device is not to
    /// blame: an infrastructure error that says where the trigger landed.
    #[test]
    fn a_count_that_differs_after_a_missed_aim_blames_the_instrument() {
        match decel_stop_probe(Duration::from_nanos(2_600), 600) {
            Err(Stop::Error(e @ HarnessError::Aim(_))) => {
                assert_eq!(e.kind(), ppmc_record::ErrorKind::Infrastructure);
                let m = e.to_string();
                assert!(m.contains("aimed 17.400us before pulse 501"), "{m}");
                assert!(m.contains("landed 14.800us"), "{m}");
            }
            other => panic!("expected the instrument's miss, got {other:?}"),
        }
    }

    /// The trigger landed where aimed, and the count is not the one the
    /// datasheet gives (here the probe expects a pulse too many): the
    /// device's failure, as before.
    #[test]
    fn a_count_that_differs_after_a_good_aim_is_the_devices_failure() {
        match decel_stop_probe(Duration::ZERO, 601) {
            Err(Stop::Failed(f)) => assert!(f.got.starts_with("600"), "{f:?}"),
            other => panic!("expected a device failure, got {other:?}"),
        }
    }
}
