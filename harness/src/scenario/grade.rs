//! PASS / MARGINAL / FAIL grading of measured latencies against Table 3-3.
//!
//! The limits are the datasheet's band (`[min, max]`, or the single typical
//! figure) widened by its 1 % footnote. A value outside fails. A value
//! inside but within [`Grading::marginal_bp`] of an edge (default
//! 0.25 % of the edge value, a quarter of the footnote's tolerance) is
//! MARGINAL: it passes, but a hardware test station would flag the board
//! for a look, as OpenHTF's marginal limits do.

use crate::protocol::{Straps, TimingId};
use crate::time::{Duration, Instant, Limit};
use std::fmt;

/// How a measurement compares with its limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Grade {
    Pass,
    Marginal,
    Fail,
}

impl Grade {
    pub fn name(self) -> &'static str {
        match self {
            Grade::Pass => "PASS",
            Grade::Marginal => "MARGINAL",
            Grade::Fail => "FAIL",
        }
    }
}

/// The grading rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grading {
    /// Width of the marginal zone inside each edge, in basis points
    /// (hundredths of a percent) of the edge value.
    pub marginal_bp: u64,
}

impl Default for Grading {
    fn default() -> Self {
        Grading { marginal_bp: 25 }
    }
}

/// A graded measurement: value, limits and where it was taken.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Measurement {
    pub name: String,
    pub value: Duration,
    pub lo: Duration,
    pub hi: Duration,
    /// The marginal zone: values below `marginal_lo` or above `marginal_hi`
    /// (but inside `lo..=hi`) are MARGINAL.
    pub marginal_lo: Duration,
    pub marginal_hi: Duration,
    pub grade: Grade,
    /// When the measured interval ended, on the target's clock.
    pub at: Instant,
}

impl Grading {
    /// Grades `value` against the Table 3-3 row `id` on a board with
    /// `straps`.
    pub fn grade(
        &self,
        id: TimingId,
        straps: &Straps,
        value: Duration,
        at: Instant,
    ) -> Measurement {
        let (lo, hi) = id.row().band_for(straps);
        self.grade_in(id.name(), lo, hi, value, at)
    }

    /// Grades `value` against explicit limits.
    pub fn grade_in(
        &self,
        name: &str,
        lo: Duration,
        hi: Duration,
        value: Duration,
        at: Instant,
    ) -> Measurement {
        let margin = |edge: Duration| edge.scale(self.marginal_bp, 10_000);
        let marginal_lo = lo + margin(lo);
        let marginal_hi = if hi == Duration::MAX {
            hi
        } else {
            hi.saturating_sub(margin(hi))
        };
        let grade = if value < lo || value > hi {
            Grade::Fail
        } else if value < marginal_lo || value > marginal_hi {
            Grade::Marginal
        } else {
            Grade::Pass
        };
        Measurement {
            name: name.to_string(),
            value,
            lo,
            hi,
            marginal_lo,
            marginal_hi,
            grade,
            at,
        }
    }
}

impl fmt::Display for Measurement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} [{}..={}]",
            self.name,
            self.value,
            self.lo,
            Limit(self.hi)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grade(id: TimingId, ns: u64) -> Grade {
        Grading::default()
            .grade(
                id,
                &Straps::default(),
                Duration::from_nanos(ns),
                Instant::ZERO,
            )
            .grade
    }

    #[test]
    fn single_figure_rows_allow_one_percent() {
        // Constant first POUT: 194 us typ, so 192.06 ..= 195.94 us.
        assert_eq!(grade(TimingId::ConstantFirstPout, 194_000), Grade::Pass);
        assert_eq!(grade(TimingId::ConstantFirstPout, 195_000), Grade::Pass);
        assert_eq!(grade(TimingId::ConstantFirstPout, 195_600), Grade::Marginal);
        assert_eq!(grade(TimingId::ConstantFirstPout, 192_200), Grade::Marginal);
        assert_eq!(grade(TimingId::ConstantFirstPout, 196_000), Grade::Fail);
        assert_eq!(grade(TimingId::ConstantFirstPout, 203_700), Grade::Fail);
    }

    #[test]
    fn range_rows_pass_inside_and_are_marginal_at_the_edge() {
        // BUSY rise: 27..112 us, widened to 26.73 ..= 113.12 us.
        assert_eq!(grade(TimingId::BusyRise, 27_000), Grade::Pass);
        assert_eq!(grade(TimingId::BusyRise, 60_000), Grade::Pass);
        assert_eq!(grade(TimingId::BusyRise, 112_900), Grade::Marginal);
        assert_eq!(grade(TimingId::BusyRise, 26_750), Grade::Marginal);
        assert_eq!(grade(TimingId::BusyRise, 120_000), Grade::Fail);
        assert_eq!(grade(TimingId::BusyRise, 20_000), Grade::Fail);
    }

    #[test]
    fn max_only_rows_start_at_zero() {
        assert_eq!(grade(TimingId::AbnormalTermination, 180_000), Grade::Pass);
        assert_eq!(
            grade(TimingId::AbnormalTermination, 201_900),
            Grade::Marginal
        );
        assert_eq!(grade(TimingId::AbnormalTermination, 210_000), Grade::Fail);
    }
}
