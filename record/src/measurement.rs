//! PASS / MARGINAL / FAIL grading of measured latencies against Table 3-3,
//! by the decision rule of `docs/conformance.md` (ISO 14253-1's: a
//! measurement proves conformance only when its value plus or minus its
//! uncertainty lies inside the band, and non-conformance only when it lies
//! outside).
//!
//! The limits are the datasheet's band (`[min, max]`, or the single typical
//! figure) widened by its 1 % footnote. Each measurement carries its
//! uncertainty `U` (±), the instrument's: 0 on the emulator, on a board
//! the sum of its two ends' as the bridge declares them per path (an
//! access's stamp, a captured edge, a sampled output, a polled flag; the
//! harness's `Target::uncertainty`). Then:
//!
//! - FAIL: the whole interval `value ± U` lies outside the band;
//! - MARGINAL: it straddles a limit (the instrument cannot tell: "within
//!   the instrument's uncertainty"), or it lies inside but reaches into
//!   the zone within [`Grading::marginal_bp`] of an edge (default 0.25 %
//!   of the edge value, a quarter of the footnote's tolerance), where a
//!   hardware test station would flag the board for a look, as OpenHTF's
//!   marginal limits do;
//! - PASS: otherwise.
//!
//! With `U` = 0 this is the band and the marginal zone alone.

use ppmc_core::protocol::{Straps, TimingId};
use ppmc_core::time::{Duration, Instant, Limit};
use serde::{Deserialize, Serialize};
use std::fmt;

/// How a measurement compares with its limits; in a run record `PASS`,
/// `MARGINAL` or `FAIL`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
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

/// The grading rule. Its default is the one marginal zone every command
/// starts from ([`MARGINAL_PCT`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grading {
    /// Width of the marginal zone inside each edge, in basis points
    /// (hundredths of a percent) of the edge value.
    pub marginal_bp: u64,
}

/// The marginal zone's default width, percent of each limit (`--marginal`).
pub const MARGINAL_PCT: f64 = 0.25;

impl Default for Grading {
    fn default() -> Self {
        Grading::percent(MARGINAL_PCT)
    }
}

impl Grading {
    /// The rule with a marginal zone `pct` percent of each limit wide.
    pub fn percent(pct: f64) -> Grading {
        Grading {
            marginal_bp: (pct * 100.0).round() as u64,
        }
    }
}

/// A graded measurement: value, limits and where it was taken. In a run
/// record its times are nanoseconds (`value_ns`, ...; an open upper limit
/// `null`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "MeasurementFields", from = "MeasurementFields")]
pub struct Measurement {
    pub name: String,
    pub value: Duration,
    pub lo: Duration,
    pub hi: Duration,
    /// The marginal zone: values below `marginal_lo` or above `marginal_hi`
    /// (but inside `lo..=hi`) are MARGINAL.
    pub marginal_lo: Duration,
    pub marginal_hi: Duration,
    /// The measurement's uncertainty (±): the instrument's.
    pub u: Duration,
    pub grade: Grade,
    /// When the measured interval ended, on the target's clock.
    pub at: Instant,
}

impl Grading {
    /// Grades `value` (± `u`) against the Table 3-3 row `id` on a board
    /// with `straps`.
    pub fn grade(
        &self,
        id: TimingId,
        straps: &Straps,
        value: Duration,
        u: Duration,
        at: Instant,
    ) -> Measurement {
        let (lo, hi) = id.row().band_for(straps);
        self.grade_in(id.name(), lo, hi, value, u, at)
    }

    /// Grades `value` (± `u`) against explicit limits, by the decision
    /// rule (this module's doc).
    pub fn grade_in(
        &self,
        name: &str,
        lo: Duration,
        hi: Duration,
        value: Duration,
        u: Duration,
        at: Instant,
    ) -> Measurement {
        let margin = |edge: Duration| edge.scale(self.marginal_bp, 10_000);
        let marginal_lo = lo + margin(lo);
        let marginal_hi = if hi == Duration::MAX {
            hi
        } else {
            hi.saturating_sub(margin(hi))
        };
        let (low, high) = (value.saturating_sub(u), value.saturating_add(u));
        let grade = if high < lo || low > hi {
            Grade::Fail
        } else if low < marginal_lo || high > marginal_hi {
            // Straddling a limit, or reaching into the marginal zone.
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
            u,
            grade,
            at,
        }
    }
}

impl Measurement {
    /// The interval `value ± u` straddles a limit: the instrument cannot
    /// tell whether the value is inside.
    pub fn within_uncertainty(&self) -> bool {
        let (low, high) = (
            self.value.saturating_sub(self.u),
            self.value.saturating_add(self.u),
        );
        (low < self.lo && high >= self.lo) || (high > self.hi && low <= self.hi)
    }

    /// The upper limit in nanoseconds; `None` when there is none.
    pub fn hi_ns(&self) -> Option<u64> {
        finite(self.hi)
    }

    /// The marginal zone's upper edge in nanoseconds; `None` when the
    /// band has no upper limit.
    pub fn marginal_hi_ns(&self) -> Option<u64> {
        finite(self.marginal_hi)
    }

    /// The value as measured: `112.000us`, or `112.400us ±0.020us`.
    pub fn shown(&self) -> String {
        match self.u == Duration::ZERO {
            true => self.value.to_string(),
            false => format!("{} ±{}", self.value, self.u),
        }
    }
}

/// A [`Measurement`] as a run record spells it.
#[derive(Serialize, Deserialize)]
struct MeasurementFields {
    name: String,
    value_ns: u64,
    lo_ns: u64,
    hi_ns: Option<u64>,
    marginal_lo_ns: u64,
    marginal_hi_ns: Option<u64>,
    /// The uncertainty (±); 0 in records written before it was kept.
    #[serde(default)]
    u_ns: u64,
    grade: Grade,
    at_ns: u64,
}

/// An open limit (`Duration::MAX`) is `null`.
fn finite(d: Duration) -> Option<u64> {
    (d != Duration::MAX).then_some(d.as_nanos())
}

impl From<Measurement> for MeasurementFields {
    fn from(m: Measurement) -> Self {
        MeasurementFields {
            value_ns: m.value.as_nanos(),
            lo_ns: m.lo.as_nanos(),
            hi_ns: finite(m.hi),
            marginal_lo_ns: m.marginal_lo.as_nanos(),
            marginal_hi_ns: finite(m.marginal_hi),
            u_ns: m.u.as_nanos(),
            grade: m.grade,
            at_ns: m.at.as_nanos(),
            name: m.name,
        }
    }
}

impl From<MeasurementFields> for Measurement {
    fn from(m: MeasurementFields) -> Self {
        let open = |ns: Option<u64>| ns.map_or(Duration::MAX, Duration::from_nanos);
        Measurement {
            name: m.name,
            value: Duration::from_nanos(m.value_ns),
            lo: Duration::from_nanos(m.lo_ns),
            hi: open(m.hi_ns),
            marginal_lo: Duration::from_nanos(m.marginal_lo_ns),
            marginal_hi: open(m.marginal_hi_ns),
            u: Duration::from_nanos(m.u_ns),
            grade: m.grade,
            at: Instant::from_nanos(m.at_ns),
        }
    }
}

impl fmt::Display for Measurement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} [{}..={}]",
            self.name,
            self.shown(),
            self.lo,
            Limit(self.hi)
        )?;
        if self.within_uncertainty() {
            write!(f, " (within the instrument's uncertainty, ±{})", self.u)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grade(id: TimingId, ns: u64) -> Grade {
        graded(id, ns, 0).grade
    }

    fn graded(id: TimingId, ns: u64, u_ns: u64) -> Measurement {
        Grading::default().grade(
            id,
            &Straps::default(),
            Duration::from_nanos(ns),
            Duration::from_nanos(u_ns),
            Instant::ZERO,
        )
    }

    /// The decision rule (docs/conformance.md): BUSY rise, 27..112 us,
    /// accepted from 26.73 to 113.12 us, marginal above 112.84 us. A
    /// value is FAIL only when value ± U lies wholly outside, PASS only
    /// when wholly inside and clear of the marginal zone.
    #[test]
    fn s3_6_a_value_within_its_uncertainty_of_a_limit_is_marginal() {
        // 113.20 us ± 0.02 us: wholly outside, FAIL.
        assert_eq!(graded(TimingId::BusyRise, 113_200, 20).grade, Grade::Fail);
        // 113.20 us ± 0.10 us: straddles 113.12 us, MARGINAL, and says so.
        let m = graded(TimingId::BusyRise, 113_200, 100);
        assert_eq!(m.grade, Grade::Marginal);
        assert!(m.within_uncertainty());
        assert!(
            m.to_string()
                .contains("within the instrument's uncertainty, ±0.100us"),
            "{m}"
        );
        // 112.00 us ± 1 us: reaches into the marginal zone, MARGINAL, but
        // inside the band.
        let m = graded(TimingId::BusyRise, 112_000, 1_000);
        assert_eq!(m.grade, Grade::Marginal);
        assert!(!m.within_uncertainty());
        // 60 us ± 1 us: wholly inside, PASS.
        assert_eq!(graded(TimingId::BusyRise, 60_000, 1_000).grade, Grade::Pass);
        // 26.70 us ± 0.05 us: straddles 26.73 us from below.
        let m = graded(TimingId::BusyRise, 26_700, 50);
        assert_eq!((m.grade, m.within_uncertainty()), (Grade::Marginal, true));
        // U = 0: the band alone.
        assert_eq!(graded(TimingId::BusyRise, 113_200, 0).grade, Grade::Fail);
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
