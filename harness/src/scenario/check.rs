//! Deferred expectations, [`Check`], and how each is judged: on the
//! results of the steps queued with it, or on the capture as it stood
//! where it was queued.

use super::outcome::{fail, need, HarnessError, Outcome, Stop};
use super::steps::Done;
use crate::protocol::{Direction, ErrorCode, OutputRecord, Status, StatusField};
use crate::time::{Duration, Instant};

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

    /// Judges a check of the results of its group, `done`; `at` is when
    /// the group's last step ended.
    pub(super) fn judge_results(&self, done: &[Done], at: Instant) -> Outcome {
        let c = self;
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
    /// was queued; `trigger` is the most recent stop write, input edge or
    /// auxiliary command write.
    pub(super) fn judge_capture(
        &self,
        rec: &OutputRecord,
        at: Instant,
        trigger: Option<Instant>,
    ) -> Outcome {
        let c = self;
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
                let t = need("a stop or an input edge", trigger)?;
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
}

/// Fails if the most recent move of `rec` has a pulse after `t`.
fn no_pulses_after(rec: &OutputRecord, t: Instant) -> Outcome {
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
