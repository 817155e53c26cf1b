//! By how much a failed check missed ([`Deviation`]): the measured value
//! against the value it was held to, in the check's unit, so that a
//! report can say "1.030 us late, 6.0 % over the 17.170 us limit" rather
//! than show two ranges to subtract.

use crate::measurement::Measurement;
use ppmc_core::time::Duration;
use serde::{Deserialize, Serialize};

/// A duration as a deviation's signed nanoseconds (saturating: an open
/// limit, `Duration::MAX`, stays the greatest).
pub fn signed_ns(d: Duration) -> i64 {
    i64::try_from(d.as_nanos()).unwrap_or(i64::MAX)
}

/// The unit a deviation's numbers are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviationUnit {
    /// Nanoseconds: a latency, an interval, a time.
    Ns,
    /// Output pulses (POUT), numbered from 1.
    Pulses,
    /// A count of anything else.
    Count,
}

/// What a deviation's reference is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reference {
    /// The nearer end of the band the value fell outside.
    Limit,
    /// The one value expected.
    Expected,
    /// The golden trace's value.
    Golden,
}

/// Whether the measured value is a bound: a latency bracketed between
/// two pulses is known to be at least (or at most) the measured value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    AtLeast,
    AtMost,
}

/// A failed check's measured value and the value it was held to, as
/// integers of `unit` (exact, comparable, and the same in every report).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Deviation {
    pub unit: DeviationUnit,
    pub measured: i64,
    pub reference: i64,
    pub reference_is: Reference,
    /// The measurement's own uncertainty (±), in `unit`; 0 where exact or
    /// unknown.
    #[serde(default)]
    pub u: u64,
    /// The measured value is a bound, not the value itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<Bound>,
}

impl Deviation {
    /// A graded measurement's deviation from the limit of its band it fell
    /// outside (the upper one if above it), with its uncertainty.
    pub fn of_measurement(m: &Measurement) -> Deviation {
        let limit = if m.value > m.hi { m.hi } else { m.lo };
        Deviation {
            unit: DeviationUnit::Ns,
            measured: signed_ns(m.value),
            reference: signed_ns(limit),
            reference_is: Reference::Limit,
            u: m.u.as_nanos(),
            bound: None,
        }
    }

    /// `measured - reference`: positive over, negative under.
    pub fn by(&self) -> i64 {
        self.measured.saturating_sub(self.reference)
    }

    /// [`Deviation::by`] in percent of the reference; `None` where the
    /// reference is 0.
    pub fn pct(&self) -> Option<f64> {
        (self.reference != 0).then(|| self.by() as f64 / self.reference as f64 * 100.0)
    }

    /// A value of this unit as a person reads it: `17.170 us`, `3 pulses`.
    pub fn amount(&self, v: i64) -> String {
        match self.unit {
            DeviationUnit::Ns => {
                let sign = if v < 0 { "-" } else { "" };
                format!("{sign}{}", human_ns(v.unsigned_abs()))
            }
            DeviationUnit::Pulses if v.abs() == 1 => format!("{v} pulse"),
            DeviationUnit::Pulses => format!("{v} pulses"),
            DeviationUnit::Count => v.to_string(),
        }
    }

    /// One line: `+1.030 us (+6.0 % of the 17.170 us limit), ±50 ns`.
    pub fn describe(&self) -> String {
        let by = self.by();
        let sign = if by > 0 { "+" } else { "" };
        let what = match self.reference_is {
            Reference::Limit => "limit",
            Reference::Expected => "expected",
            Reference::Golden => "golden",
        };
        let mut s = match self.bound {
            Some(Bound::AtLeast) => format!("at least {sign}{}", self.amount(by)),
            Some(Bound::AtMost) => format!("at most {sign}{}", self.amount(by)),
            None => format!("{sign}{}", self.amount(by)),
        };
        match self.pct() {
            Some(p) => s.push_str(&format!(
                " ({sign}{p:.1} % of the {} {what})",
                self.amount(self.reference)
            )),
            None => s.push_str(&format!(" (the {what} is 0)")),
        }
        if self.u > 0 {
            s.push_str(&format!(
                ", ±{}",
                self.amount(i64::try_from(self.u).unwrap_or(i64::MAX))
            ));
        }
        s
    }
}

/// Nanoseconds in the unit that reads best: `850 ns`, `17.170 us`,
/// `164.452 ms`, `637.551 s`.
pub fn human_ns(ns: u64) -> String {
    match ns {
        0..=999 => format!("{ns} ns"),
        1_000..=999_999 => format!("{:.3} us", ns as f64 / 1e3),
        1_000_000..=999_999_999 => format!("{:.3} ms", ns as f64 / 1e6),
        _ => format!("{:.3} s", ns as f64 / 1e9),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_late_latency_says_by_how_much_and_of_what() {
        let d = Deviation {
            unit: DeviationUnit::Ns,
            measured: 18_200,
            reference: 17_170,
            reference_is: Reference::Limit,
            u: 50,
            bound: None,
        };
        assert_eq!(
            d.describe(),
            "+1.030 us (+6.0 % of the 17.170 us limit), ±50 ns"
        );
        let early = Deviation {
            measured: 16_000,
            ..d.clone()
        };
        assert_eq!(
            early.describe(),
            "-1.170 us (-6.8 % of the 17.170 us limit), ±50 ns"
        );
        let pulses = Deviation {
            unit: DeviationUnit::Pulses,
            measured: 502,
            reference: 501,
            reference_is: Reference::Limit,
            u: 0,
            bound: None,
        };
        assert_eq!(
            pulses.describe(),
            "+1 pulse (+0.2 % of the 501 pulses limit)"
        );
        let bracketed = Deviation {
            measured: 17_900,
            u: 0,
            bound: Some(Bound::AtLeast),
            ..d
        };
        assert_eq!(
            bracketed.describe(),
            "at least +730 ns (+4.3 % of the 17.170 us limit)"
        );
    }
}
