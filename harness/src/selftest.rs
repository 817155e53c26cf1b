//! `ppmc selftest`: a bus bridge's test of its own capture, the first step
//! of bringing up a bridge (`docs/bridge-hardware.md`), needing no jumper
//! and no working chip.
//!
//! The bridge's pulse generator drives the capture inputs of POUT and INT*
//! while the chip's outputs are cut off from them (`SELF_TEST`,
//! `docs/bridge-protocol.md`). The bridge says when each burst's first
//! pulse rose by its own clock; every other edge follows from the pulse
//! times it generated. [`judge`] compares the capture with that schedule:
//! every pulse there, none extra, each within the offset and jitter limits,
//! for the chip's slowest and fastest rates and bursts; and a rate beyond
//! what the capture can keep is either kept whole or reported lost, never
//! handed over short ([`Check::beyond`]).

use crate::backend::{SelfTestPlan, SelfTestRun};
use crate::protocol::{OutputRecord, Pin};
use crate::time::{Duration, Instant};

/// One self-test: a name, what the generator makes, and whether the rate
/// is beyond what the capture is made to keep.
#[derive(Debug, Clone, Copy)]
pub struct Check {
    pub name: &'static str,
    pub plan: SelfTestPlan,
    /// Past the capture's limit: the capture may report an overrun (and
    /// must, rather than lose an edge without a word).
    pub beyond: bool,
}

fn plan(count: u32, high_ns: u64, low_ns: u64, bursts: u16, gap_us: u64) -> SelfTestPlan {
    SelfTestPlan {
        count,
        high: Duration::from_nanos(high_ns),
        low: Duration::from_nanos(low_ns),
        bursts,
        gap: Duration::from_micros(gap_us),
    }
}

/// The checks `ppmc selftest` runs, in order. Every time is a whole
/// number of ticks of an RP2350 bridge's 75 MHz timer (40 ns is 3), so
/// that the times the bridge reports back, in whole nanoseconds, are its
/// own. Each keeps its INT* changes
/// (two a pulse) under the 748 records an RP2350 bridge's capture holds,
/// but for the one beyond the limit, which the one after shows recovered.
pub fn checks() -> Vec<Check> {
    vec![
        Check {
            name: "10 kpps",
            plan: plan(100, 10_000, 90_000, 1, 0),
            beyond: false,
        },
        Check {
            // Section 3-2's limit: 40 kpps x SysClk / 16 at 40 MHz.
            name: "100 kpps, 3 bursts",
            plan: plan(100, 5_000, 5_000, 3, 200),
            beyond: false,
        },
        Check {
            name: "403 kpps, 20 bursts",
            plan: plan(10, 1_240, 1_240, 20, 20),
            beyond: false,
        },
        Check {
            name: "beyond the capture",
            plan: plan(2_000, 120, 120, 1, 0),
            beyond: true,
        },
        Check {
            name: "after an overrun",
            plan: plan(50, 10_000, 90_000, 1, 0),
            beyond: false,
        },
    ]
}

/// How far captured edges may lie from the generator's schedule.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Largest offset (either way) of any edge.
    pub offset: Duration,
    /// Largest spread of the offsets: the capture's jitter.
    pub jitter: Duration,
}

impl Default for Limits {
    /// 100 ns of offset (the input synchroniser, a counter's loop and the
    /// 1 kOhm into the pin's capacitance take some 40 ns on an RP2350 at
    /// 150 MHz) and 30 ns of jitter (two ticks of its 75 MHz timer).
    fn default() -> Self {
        Limits {
            offset: Duration::from_nanos(100),
            jitter: Duration::from_nanos(30),
        }
    }
}

/// Captured edges of one signal against the schedule.
#[derive(Debug, Clone, PartialEq)]
pub struct Edges {
    pub signal: &'static str,
    pub expected: usize,
    pub seen: usize,
    /// Offsets of the edges (captured less scheduled), in ns, when every
    /// edge was there.
    pub offsets: Option<(i64, i64)>,
    /// The largest spread of the offsets within one burst: the jitter.
    /// (Each burst's start is stamped by the bridge's CPU on its own, a
    /// cycle or two apart from the next: that is the offset's, not the
    /// capture's jitter.)
    pub jitter_ns: u64,
    /// POUT's pulses inside a pulse run are not stamped one by one: the
    /// run's first and last are, and the rest lie within this of the line
    /// between them (the run's jitter bound, docs/bridge-protocol.md
    /// section 7). Offsets and jitter count the stamped ones.
    pub bound_ns: Option<u64>,
    /// The first edge whose level was not the scheduled one, if any.
    pub wrong_level: Option<usize>,
}

impl Edges {
    fn faults(&self, limits: &Limits) -> Vec<String> {
        let mut v = Vec::new();
        if self.seen != self.expected {
            v.push(format!(
                "{}: captured {} of {} edges",
                self.signal, self.seen, self.expected
            ));
        }
        if let Some(i) = self.wrong_level {
            v.push(format!(
                "{}: edge {} has the wrong level",
                self.signal,
                i + 1
            ));
        }
        if let Some((lo, hi)) = self.offsets {
            let most = lo.unsigned_abs().max(hi.unsigned_abs());
            if most > limits.offset.as_nanos() {
                v.push(format!(
                    "{}: an edge {most} ns from its time, over the {} ns limit",
                    self.signal,
                    limits.offset.as_nanos()
                ));
            }
            if self.jitter_ns > limits.jitter.as_nanos() {
                v.push(format!(
                    "{}: jitter {} ns, over the {} ns limit",
                    self.signal,
                    self.jitter_ns,
                    limits.jitter.as_nanos()
                ));
            }
            if let Some(b) = self.bound_ns.filter(|b| *b > limits.jitter.as_nanos()) {
                v.push(format!(
                    "{}: pulses within a run lie up to {b} ns off its line, over the {} ns jitter limit",
                    self.signal,
                    limits.jitter.as_nanos()
                ));
            }
        }
        v
    }
}

impl std::fmt::Display for Edges {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}/{}", self.signal, self.seen, self.expected)?;
        if let Some((lo, hi)) = self.offsets {
            if lo == hi {
                write!(f, ", offset {lo:+} ns")?;
            } else {
                write!(f, ", offset {lo:+}..{hi:+} ns")?;
            }
            write!(f, ", jitter {} ns", self.jitter_ns)?;
            if let Some(b) = self.bound_ns {
                write!(f, " (run ends; within runs, {b} ns of the line)")?;
            }
        }
        Ok(())
    }
}

/// A check's outcome.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub check: Check,
    /// The high and low times the bridge made.
    pub high: Duration,
    pub low: Duration,
    /// POUT's rising edges and INT*'s changes, when there was a capture.
    pub edges: Vec<Edges>,
    /// The overrun the bridge reported instead of a capture.
    pub overrun: Option<String>,
    /// Why the check failed; empty when it passed.
    pub faults: Vec<String>,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.faults.is_empty()
    }
}

/// Judges a self-test's run against its check.
pub fn judge(check: &Check, run: &SelfTestRun, limits: &Limits) -> Outcome {
    let r = &run.reply;
    let mut out = Outcome {
        check: *check,
        high: r.high,
        low: r.low,
        edges: Vec::new(),
        overrun: None,
        faults: Vec::new(),
    };
    if r.starts.len() != usize::from(check.plan.bursts) {
        out.faults.push(format!(
            "the bridge ran {} bursts of the {} asked",
            r.starts.len(),
            check.plan.bursts
        ));
        return out;
    }
    if r.high == Duration::ZERO || r.low == Duration::ZERO {
        out.faults
            .push("the bridge reports a pulse with no high or no low time".into());
        return out;
    }
    let capture = match &run.capture {
        Ok(c) => c,
        Err(detail) => {
            out.overrun = Some(detail.clone());
            if !check.beyond {
                out.faults.push(format!(
                    "the capture overran at a rate it must keep: {detail}"
                ));
            }
            return out;
        }
    };
    let period = r.high + r.low;
    let rises: Vec<Instant> = r
        .starts
        .iter()
        .flat_map(|s| (0..u64::from(check.plan.count)).map(move |k| *s + period.saturating_mul(k)))
        .collect();
    let (Some(first), Some(last)) = (rises.first(), rises.last()) else {
        out.faults.push("no pulse was asked for".into());
        return out;
    };
    // What lies within a period of the bursts: the capture also holds the
    // chip's outputs coming back after the test.
    let from = Instant::from_nanos(first.as_nanos().saturating_sub(period.as_nanos()));
    let to = *last + period;
    let within = |t: Instant| t >= from && t <= to;
    let bursts = r.starts.len();
    out.edges.push(pout(capture, &rises, bursts, within));
    out.edges.push(int(capture, &rises, bursts, r.high, within));
    for e in &out.edges {
        out.faults.extend(e.faults(limits));
    }
    out
}

/// POUT's pulses against the rises.
fn pout(
    capture: &OutputRecord,
    rises: &[Instant],
    bursts: usize,
    within: impl Fn(Instant) -> bool,
) -> Edges {
    let mut seen = Vec::new();
    let mut stamped = Vec::new();
    let mut bound = 0;
    for run in &capture.runs {
        for i in 0..run.count {
            let t = run.at(i);
            if within(t) {
                seen.push(t);
                // The first and last pulses of a run are its own times.
                stamped.push(i == 0 || i + 1 == run.count);
                if run.count > 2 {
                    bound = bound.max(run.jitter.as_nanos());
                }
            }
        }
    }
    let per = rises.len() / bursts.max(1);
    let mut e = compare("POUT", rises, &seen, &stamped, per, |_| true);
    e.bound_ns = Some(bound);
    e
}

/// INT*'s changes against both edges of every pulse: released (0) at a
/// rise, asserted (1) at a fall.
fn int(
    capture: &OutputRecord,
    rises: &[Instant],
    bursts: usize,
    high: Duration,
    within: impl Fn(Instant) -> bool,
) -> Edges {
    let want: Vec<Instant> = rises.iter().flat_map(|r| [*r, *r + high]).collect();
    let changes: Vec<(Instant, u8)> = capture
        .pins
        .iter()
        .filter(|p| p.pin == Pin::Int && within(p.at))
        .map(|p| (p.at, p.value))
        .collect();
    let times: Vec<Instant> = changes.iter().map(|c| c.0).collect();
    let per = want.len() / bursts.max(1);
    compare("INT*", &want, &times, &vec![true; times.len()], per, |i| {
        changes.get(i).is_some_and(|c| c.1 == u8::from(i % 2 == 1))
    })
}

fn compare(
    signal: &'static str,
    want: &[Instant],
    seen: &[Instant],
    stamped: &[bool],
    per_burst: usize,
    level_ok: impl Fn(usize) -> bool,
) -> Edges {
    let mut e = Edges {
        signal,
        expected: want.len(),
        seen: seen.len(),
        offsets: None,
        jitter_ns: 0,
        bound_ns: None,
        wrong_level: None,
    };
    if want.len() != seen.len() {
        return e;
    }
    e.wrong_level = (0..seen.len()).find(|i| !level_ok(*i));
    // (burst, offset) of every stamped edge.
    let offsets: Vec<(usize, i64)> = want
        .iter()
        .zip(seen)
        .enumerate()
        .filter(|(i, _)| stamped[*i])
        .map(|(i, (w, s))| {
            let d = s.as_nanos() as i64 - w.as_nanos() as i64;
            (i / per_burst.max(1), d)
        })
        .collect();
    let spread = |v: &mut dyn Iterator<Item = i64>| {
        v.fold(None, |m: Option<(i64, i64)>, d| {
            Some(m.map_or((d, d), |(lo, hi)| (lo.min(d), hi.max(d))))
        })
    };
    e.offsets = spread(&mut offsets.iter().map(|o| o.1));
    let bursts = offsets.last().map_or(0, |o| o.0 + 1);
    e.jitter_ns = (0..bursts)
        .filter_map(|b| spread(&mut offsets.iter().filter(|o| o.0 == b).map(|o| o.1)))
        .map(|(lo, hi)| (hi - lo).unsigned_abs())
        .max()
        .unwrap_or(0);
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::SelfTestReply;
    use crate::protocol::{Direction, PinEvent, PulseRun};

    /// A capture of `plan` as a perfect bridge makes it, every edge
    /// `delay` ns late.
    fn perfect(plan: &SelfTestPlan, delay: u64) -> SelfTestRun {
        let period = plan.high + plan.low;
        let burst = period.saturating_mul(u64::from(plan.count)) + plan.gap;
        let starts: Vec<Instant> = (0..u64::from(plan.bursts))
            .map(|b| Instant::from_nanos(2_000) + burst.saturating_mul(b))
            .collect();
        let mut rec = OutputRecord::default();
        for s in &starts {
            let at = *s + Duration::from_nanos(delay);
            rec.runs
                .push(PulseRun::exact(at, period, plan.count, Direction::Cw));
            for k in 0..u64::from(plan.count) {
                let rise = at + period.saturating_mul(k);
                for (t, v) in [(rise, 0), (rise + plan.high, 1)] {
                    rec.pins.push(PinEvent {
                        at: t,
                        pin: Pin::Int,
                        value: v,
                    });
                }
            }
        }
        SelfTestRun {
            reply: SelfTestReply {
                starts,
                high: plan.high,
                low: plan.low,
            },
            capture: Ok(rec),
        }
    }

    #[test]
    fn a_capture_that_keeps_every_edge_on_time_passes_and_says_its_offset() {
        for check in checks() {
            let o = judge(&check, &perfect(&check.plan, 40), &Limits::default());
            assert!(o.passed(), "{}: {:?}", check.name, o.faults);
            assert_eq!(o.edges.len(), 2);
            assert!(o.edges.iter().all(|e| e.offsets == Some((40, 40))));
            assert_eq!(o.edges[0].to_string(), {
                let n = check.plan.count as usize * usize::from(check.plan.bursts);
                format!("POUT {n}/{n}, offset +40 ns, jitter 0 ns (run ends; within runs, 0 ns of the line)")
            });
        }
    }

    #[test]
    fn a_missing_late_or_jittery_edge_fails_and_says_which() {
        let check = checks()[1];
        let limits = Limits::default();
        // A pulse lost from a run, silently.
        let mut run = perfect(&check.plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            rec.runs[1].count -= 1;
        }
        let o = judge(&check, &run, &limits);
        assert_eq!(o.faults, ["POUT: captured 299 of 300 edges"]);
        // Late by more than the limit.
        let o = judge(&check, &perfect(&check.plan, 150), &limits);
        assert!(
            o.faults.iter().any(|f| f.contains("150 ns from its time")),
            "{:?}",
            o.faults
        );
        // One INT* change 50 ns off: jitter.
        let mut run = perfect(&check.plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            rec.pins[7].at += Duration::from_nanos(50);
        }
        let o = judge(&check, &run, &limits);
        assert_eq!(o.faults, ["INT*: jitter 50 ns, over the 30 ns limit"]);
        // INT* stuck: its changes inverted.
        let mut run = perfect(&check.plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            for p in &mut rec.pins {
                p.value ^= 1;
            }
        }
        let o = judge(&check, &run, &limits);
        assert_eq!(o.faults, ["INT*: edge 1 has the wrong level"]);
        // A run whose jitter bound is over the limit.
        let mut run = perfect(&check.plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            rec.runs[0].jitter = Duration::from_nanos(35);
        }
        let o = judge(&check, &run, &limits);
        assert_eq!(
            o.faults,
            ["POUT: pulses within a run lie up to 35 ns off its line, over the 30 ns jitter limit"]
        );
        // A run whose last pulse came 40 ns late: its ends spread.
        let mut run = perfect(&check.plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            rec.runs[2].span += Duration::from_nanos(40);
        }
        let o = judge(&check, &run, &limits);
        assert_eq!(o.faults, ["POUT: jitter 40 ns, over the 30 ns limit"]);
        // Nothing at all: the generator never reached the capture.
        let mut run = perfect(&check.plan, 40);
        run.capture = Ok(OutputRecord::default());
        let o = judge(&check, &run, &limits);
        assert_eq!(
            o.faults,
            [
                "POUT: captured 0 of 300 edges",
                "INT*: captured 0 of 600 edges"
            ]
        );
    }

    #[test]
    fn an_overrun_passes_only_beyond_the_captures_limit() {
        let mut run = perfect(&checks()[3].plan, 40);
        run.capture = Err("edges came faster than the capture was drained".into());
        let o = judge(&checks()[3], &run, &Limits::default());
        assert!(o.passed() && o.overrun.is_some());
        let mut run = perfect(&checks()[0].plan, 40);
        run.capture = Err("edges came faster than the capture was drained".into());
        let o = judge(&checks()[0], &run, &Limits::default());
        assert_eq!(
            o.faults,
            ["the capture overran at a rate it must keep: edges came faster than the capture was drained"]
        );
        // Beyond the limit, a capture handed over short is the worst case.
        let mut run = perfect(&checks()[3].plan, 40);
        if let Ok(rec) = run.capture.as_mut() {
            rec.pins.truncate(700);
        }
        let o = judge(&checks()[3], &run, &Limits::default());
        assert_eq!(o.faults, ["INT*: captured 700 of 4000 edges"]);
    }

    #[test]
    fn a_burst_stamped_late_moves_the_offset_not_the_jitter() {
        // The bridge's CPU stamps each burst's start on its own: a burst
        // whose every edge is 10 ns later than the others is an offset of
        // 40..50 ns, with no jitter within a burst.
        let check = checks()[1];
        let mut run = perfect(&check.plan, 40);
        run.reply.starts[1] = Instant::from_nanos(run.reply.starts[1].as_nanos() - 10);
        let o = judge(&check, &run, &Limits::default());
        assert!(o.passed(), "{:?}", o.faults);
        for e in &o.edges {
            assert_eq!((e.offsets, e.jitter_ns), (Some((40, 50)), 0), "{e}");
        }
    }

    #[test]
    fn a_reply_with_the_wrong_bursts_fails() {
        let check = checks()[1];
        let mut run = perfect(&check.plan, 40);
        run.reply.starts.pop();
        let o = judge(&check, &run, &Limits::default());
        assert_eq!(o.faults, ["the bridge ran 2 bursts of the 3 asked"]);
    }
}
