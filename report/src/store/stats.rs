//! What a results store says across runs ([`History`]): yield per
//! revision, each scenario's pass rate across boards, each measurement's
//! distribution per revision with its Cpk against the band, and the
//! trend of the pass rate over time.
//!
//! A board is known by its serial where it gave one (`--board-serial`),
//! else by its name in the run; a board test is one board in one run, and
//! it passed when none of its results failed, erred or was not run (a
//! flaky result passed, and is counted as flaky too; so did a result
//! judged from a capture that blames the host firmware, not the board).

use super::{Store, StoreError};
use std::collections::BTreeMap;

/// A board revision's yield: of its board tests, how many passed.
#[derive(Debug, Clone, PartialEq)]
pub struct RevisionYield {
    /// `(none)` for boards given no revision.
    pub rev: String,
    pub tests: u64,
    pub passed: u64,
    /// Distinct boards (by serial, or by name).
    pub boards: u64,
    /// Results that passed only on a retry.
    pub flaky: u64,
}

impl RevisionYield {
    pub fn rate(&self) -> f64 {
        ratio(self.passed, self.tests)
    }
}

/// A scenario across every run and board.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioRate {
    pub scenario: String,
    pub section: String,
    pub results: u64,
    /// Passed or marginal, at the first attempt.
    pub passed: u64,
    pub flaky: u64,
    pub failed: u64,
    pub errors: u64,
    pub not_run: u64,
    pub boards: u64,
}

impl ScenarioRate {
    /// Passed (a flaky pass included) of those that ran (a scenario not
    /// run, on a board not reached or a run stopped, is no verdict on a
    /// board).
    pub fn rate(&self) -> f64 {
        ratio(
            self.passed + self.flaky,
            self.results.saturating_sub(self.not_run),
        )
    }
}

/// One measurement of one scenario on one revision. Each value is also
/// placed in its own band ([`Distribution::positions`]): boards strapped
/// to other clocks have other bands, and a value is judged against its
/// own.
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution {
    pub scenario: String,
    pub name: String,
    pub rev: String,
    pub values: Vec<u64>,
    /// Each value's place in its band: 0 at the lower limit, 1 at the
    /// upper; with no upper limit, the distance above the lower limit in
    /// lower limits (so 0 is still the limit).
    pub positions: Vec<f64>,
    /// Whether the band has an upper limit.
    pub two_sided: bool,
    /// The first value's band and marginal zone, ns (the band of every
    /// value when the boards share their straps).
    pub lo_ns: u64,
    pub hi_ns: Option<u64>,
    pub marginal_lo_ns: u64,
    pub marginal_hi_ns: Option<u64>,
    /// Whether the values' bands differ (boards at other clocks).
    pub bands_differ: bool,
    pub mean_ns: f64,
    pub min_ns: u64,
    pub max_ns: u64,
}

/// Mean and sample standard deviation (n - 1; 0 for one value).
pub fn mean_sd(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    if xs.is_empty() {
        return (0.0, 0.0);
    }
    let mean = xs.iter().sum::<f64>() / n;
    let var = match xs.len() {
        1 => 0.0,
        _ => xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0),
    };
    (mean, var.sqrt())
}

impl Distribution {
    /// Process capability against the band: the distance from the mean to
    /// the nearer limit, in three standard deviations, of the values'
    /// places in their bands (the usual Cpk when the bands are one; only
    /// the lower limit counts when there is no upper one). `None` when
    /// every value sits at the same place (no spread to judge it by).
    pub fn cpk(&self) -> Option<f64> {
        let (mean, sd) = mean_sd(&self.positions);
        if sd.is_nan() || sd <= 1e-12 {
            return None;
        }
        Some(match self.two_sided {
            true => mean.min(1.0 - mean) / (3.0 * sd),
            false => mean / (3.0 * sd),
        })
    }

    /// How many values fell outside their own band.
    pub fn out_of_band(&self) -> usize {
        self.positions
            .iter()
            .filter(|&&p| p < 0.0 || (self.two_sided && p > 1.0))
            .count()
    }

    /// The standard deviation of the values, ns.
    pub fn sd_ns(&self) -> f64 {
        let xs: Vec<f64> = self.values.iter().map(|&v| v as f64).collect();
        mean_sd(&xs).1
    }
}

/// One board test in time order: its pass rate.
#[derive(Debug, Clone, PartialEq)]
pub struct TrendPoint {
    pub run: i64,
    pub started: String,
    pub rev: String,
    pub board: String,
    /// The station (host) the run was made on.
    pub station: String,
    pub results: u64,
    pub passed: u64,
}

/// Everything `ppmc history` prints and `ppmc report --store` draws.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct History {
    pub runs: u64,
    pub boards: u64,
    /// The first and the last run's start.
    pub span: Option<(String, String)>,
    pub revisions: Vec<RevisionYield>,
    /// Lowest pass rate first.
    pub scenarios: Vec<ScenarioRate>,
    /// By measurement name, band, then revision.
    pub measurements: Vec<Distribution>,
    /// Oldest first.
    pub trend: Vec<TrendPoint>,
}

impl TrendPoint {
    /// Whether this board test passed: it had results, and every one
    /// passed.
    pub fn passed(&self) -> bool {
        self.results > 0 && self.passed == self.results
    }
}

/// One board across the store: where and when it was last tested, and
/// how.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardRecord {
    /// Its serial, else its name.
    pub board: String,
    /// The revision and the station of its last test.
    pub rev: String,
    pub station: String,
    /// Its board tests, oldest first: indices into [`History::trend`].
    pub tests: Vec<usize>,
    pub last_passed: bool,
    pub last_seen: String,
}

impl History {
    /// Every board the store has seen, the one last seen failing first,
    /// then by serial.
    pub fn boards(&self) -> Vec<BoardRecord> {
        let mut by: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (i, t) in self.trend.iter().enumerate() {
            by.entry(t.board.as_str()).or_default().push(i);
        }
        let mut out: Vec<BoardRecord> = by
            .into_iter()
            .filter_map(|(board, tests)| {
                let last = &self.trend[*tests.last()?];
                Some(BoardRecord {
                    board: board.to_string(),
                    rev: last.rev.clone(),
                    station: last.station.clone(),
                    last_passed: last.passed(),
                    last_seen: last.started.clone(),
                    tests,
                })
            })
            .collect();
        out.sort_by(|a, b| {
            a.last_passed
                .cmp(&b.last_passed)
                .then(a.board.cmp(&b.board))
        });
        out
    }
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

/// A board's label in the store: its serial, else its name.
const BOARD: &str = "coalesce(b.board_serial, b.name)";
/// A board's revision, `(none)` when not given.
const REV: &str = "coalesce(b.board_rev, '(none)')";

impl Store {
    /// What the store says across all its runs.
    pub fn history(&self) -> Result<History, StoreError> {
        let q = |e: rusqlite::Error| self.fail(format!("reading the store: {e}"));
        let c = self.conn();
        let mut h = History {
            runs: self.runs()?,
            ..History::default()
        };
        h.boards = c
            .query_row(
                &format!("SELECT count(DISTINCT {BOARD}) FROM boards b WHERE b.reached"),
                [],
                |r| r.get(0),
            )
            .map_err(q)?;
        h.span = c
            .query_row("SELECT min(started), max(started) FROM runs", [], |r| {
                Ok(r.get::<_, Option<String>>(0)?
                    .zip(r.get::<_, Option<String>>(1)?))
            })
            .map_err(q)?;
        // Each board test: its revision, board, and whether it passed.
        let tests = format!(
            "SELECT b.id AS id, b.run_id AS run_id, {REV} AS rev, {BOARD} AS board,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id) AS results,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id
                     AND (r.verdict IN ('passed', 'marginal', 'flaky')
                          OR r.blame = 'host')) AS passed,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id
                     AND r.verdict = 'flaky') AS flaky
             FROM boards b WHERE b.reached"
        );
        let mut st = c
            .prepare(&format!(
                "SELECT rev, count(*), sum(results > 0 AND passed = results),
                     count(DISTINCT board), sum(flaky)
                 FROM ({tests}) GROUP BY rev ORDER BY rev"
            ))
            .map_err(q)?;
        h.revisions = st
            .query_map([], |r| {
                Ok(RevisionYield {
                    rev: r.get(0)?,
                    tests: r.get(1)?,
                    passed: r.get(2)?,
                    boards: r.get(3)?,
                    flaky: r.get(4)?,
                })
            })
            .map_err(q)?
            .collect::<Result<_, _>>()
            .map_err(q)?;
        let mut st = c
            .prepare(&format!(
                "SELECT run_id, coalesce((SELECT started FROM runs WHERE id = run_id), ''), rev, board,
                     results, passed, coalesce((SELECT host FROM runs WHERE id = run_id), '')
                 FROM ({tests}) ORDER BY 2, run_id, id"
            ))
            .map_err(q)?;
        h.trend = st
            .query_map([], |r| {
                Ok(TrendPoint {
                    run: r.get(0)?,
                    started: r.get(1)?,
                    rev: r.get(2)?,
                    board: r.get(3)?,
                    results: r.get(4)?,
                    passed: r.get(5)?,
                    station: r.get(6)?,
                })
            })
            .map_err(q)?
            .collect::<Result<_, _>>()
            .map_err(q)?;
        let mut st = c
            .prepare(&format!(
                "SELECT r.scenario, min(r.section), count(*),
                     sum(r.verdict IN ('passed', 'marginal')), sum(r.verdict = 'flaky'),
                     sum(r.verdict = 'failed'), sum(r.verdict = 'error'),
                     sum(r.verdict = 'not_run'),
                     count(DISTINCT CASE WHEN b.reached THEN {BOARD} END)
                 FROM results r LEFT JOIN boards b ON b.id = r.board_id
                 GROUP BY r.scenario"
            ))
            .map_err(q)?;
        h.scenarios = st
            .query_map([], |r| {
                Ok(ScenarioRate {
                    scenario: r.get(0)?,
                    section: r.get(1)?,
                    results: r.get(2)?,
                    passed: r.get(3)?,
                    flaky: r.get(4)?,
                    failed: r.get(5)?,
                    errors: r.get(6)?,
                    not_run: r.get(7)?,
                    boards: r.get(8)?,
                })
            })
            .map_err(q)?
            .collect::<Result<_, _>>()
            .map_err(q)?;
        h.scenarios.sort_by(|a, b| {
            a.rate()
                .total_cmp(&b.rate())
                .then_with(|| a.scenario.cmp(&b.scenario))
        });
        h.measurements = self.distributions()?;
        Ok(h)
    }

    /// Each measurement's values per scenario and revision.
    fn distributions(&self) -> Result<Vec<Distribution>, StoreError> {
        let q = |e: rusqlite::Error| self.fail(format!("reading the store: {e}"));
        let mut st = self
            .conn()
            .prepare(&format!(
                "SELECT r.scenario, m.name, {REV}, m.value_ns, m.lo_ns, m.hi_ns,
                     m.marginal_lo_ns, m.marginal_hi_ns
                 FROM measurements m JOIN results r ON r.id = m.result_id
                     LEFT JOIN boards b ON b.id = r.board_id
                 ORDER BY m.rowid"
            ))
            .map_err(q)?;
        let mut groups: BTreeMap<(String, String, String), Distribution> = BTreeMap::new();
        let rows = st
            .query_map([], |r| {
                Ok((
                    (
                        r.get::<_, String>(0)?,
                        r.get::<_, String>(1)?,
                        r.get::<_, String>(2)?,
                    ),
                    r.get::<_, u64>(3)?,
                    r.get::<_, u64>(4)?,
                    r.get::<_, Option<u64>>(5)?,
                    r.get::<_, u64>(6)?,
                    r.get::<_, Option<u64>>(7)?,
                ))
            })
            .map_err(q)?;
        for row in rows {
            let ((scenario, name, rev), v, lo, hi, mlo, mhi) = row.map_err(q)?;
            let place = match hi {
                Some(hi) if hi > lo => (v as f64 - lo as f64) / (hi - lo) as f64,
                Some(_) => 0.5,
                None => (v as f64 - lo as f64) / (lo.max(1)) as f64,
            };
            let key = (scenario.clone(), name.clone(), rev.clone());
            let d = groups.entry(key).or_insert_with(|| Distribution {
                scenario,
                name,
                rev,
                values: Vec::new(),
                positions: Vec::new(),
                two_sided: hi.is_some(),
                lo_ns: lo,
                hi_ns: hi,
                marginal_lo_ns: mlo,
                marginal_hi_ns: mhi,
                bands_differ: false,
                mean_ns: 0.0,
                min_ns: v,
                max_ns: v,
            });
            d.bands_differ |= d.lo_ns != lo || d.hi_ns != hi;
            d.two_sided &= hi.is_some();
            d.min_ns = d.min_ns.min(v);
            d.max_ns = d.max_ns.max(v);
            d.values.push(v);
            d.positions.push(place);
        }
        Ok(groups
            .into_values()
            .map(|mut d| {
                let xs: Vec<f64> = d.values.iter().map(|&v| v as f64).collect();
                d.mean_ns = mean_sd(&xs).0;
                d
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist(positions: &[f64], two_sided: bool) -> Distribution {
        Distribution {
            scenario: "s".into(),
            name: "x".into(),
            rev: "A".into(),
            values: Vec::new(),
            positions: positions.to_vec(),
            two_sided,
            lo_ns: 0,
            hi_ns: None,
            marginal_lo_ns: 0,
            marginal_hi_ns: None,
            bands_differ: false,
            mean_ns: 0.0,
            min_ns: 0,
            max_ns: 0,
        }
    }

    #[test]
    fn cpk_is_the_nearer_limit_in_three_sigma() {
        // Band 91..103 ns, values 99, 100, 101 (mean 100, sample sd 1):
        // the upper limit is 3 ns = 3 sigma away, Cpk 1.
        let place = |v: f64| (v - 91.0) / 12.0;
        let d = dist(&[place(99.0), place(100.0), place(101.0)], true);
        assert!((d.cpk().expect("spread") - 1.0).abs() < 1e-9);
        // No upper limit, lower at 97: 3 ns above it, Cpk 1 again.
        let place = |v: f64| (v - 97.0) / 97.0;
        let d = dist(&[place(99.0), place(100.0), place(101.0)], false);
        assert!((d.cpk().expect("spread") - 1.0).abs() < 1e-9);
        assert_eq!(dist(&[0.5, 0.5, 0.5], true).cpk(), None);
    }
}
