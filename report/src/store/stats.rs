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

use super::db::{Conn, DbError};
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
    pub fn history(&mut self) -> Result<History, StoreError> {
        let mut h = History {
            runs: self.runs()?,
            ..History::default()
        };
        let read = self.read(&mut h);
        read.map_err(|e| {
            self.fail(DbError {
                why: format!("reading the store: {}", e.why),
                fault: e.fault,
            })
        })?;
        Ok(h)
    }

    fn read(&mut self, h: &mut History) -> Result<(), DbError> {
        let c = self.conn();
        refuse_unknown(c)?;
        h.boards = c
            .row(
                &format!("SELECT count(DISTINCT {BOARD}) FROM boards b WHERE b.reached <> 0"),
                &[],
            )?
            .uint(0)?;
        let span = c.row("SELECT min(started), max(started) FROM runs", &[])?;
        h.span = span.opt_text(0)?.zip(span.opt_text(1)?);
        // Each board test: its revision, board, and whether it passed.
        let tests = format!(
            "SELECT b.id AS id, b.run_id AS run_id, {REV} AS rev, {BOARD} AS board,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id) AS results,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id
                     AND (r.verdict IN ('passed', 'marginal', 'flaky')
                          OR r.blame = 'host')) AS passed,
                (SELECT count(*) FROM results r WHERE r.board_id = b.id
                     AND r.verdict = 'flaky') AS flaky
             FROM boards b WHERE b.reached <> 0"
        );
        h.revisions = c
            .query(
                &format!(
                    "SELECT rev, count(*), count(CASE WHEN results > 0 AND passed = results THEN 1 END),
                         count(DISTINCT board), CAST(sum(flaky) AS BIGINT)
                     FROM ({tests}) t GROUP BY rev"
                ),
                &[],
            )?
            .iter()
            .map(|r| {
                Ok(RevisionYield {
                    rev: r.text(0)?,
                    tests: r.uint(1)?,
                    passed: r.uint(2)?,
                    boards: r.uint(3)?,
                    flaky: r.uint(4)?,
                })
            })
            .collect::<Result<_, DbError>>()?;
        // In byte order on both databases (PostgreSQL's collation would
        // order them its own way).
        h.revisions.sort_by(|a, b| a.rev.cmp(&b.rev));
        h.trend = c
            .query(
                &format!(
                    "SELECT run_id, coalesce((SELECT started FROM runs WHERE id = run_id), ''), rev, board,
                         results, passed, coalesce((SELECT host FROM runs WHERE id = run_id), '')
                     FROM ({tests}) t ORDER BY 2, run_id, id"
                ),
                &[],
            )?
            .iter()
            .map(|r| {
                Ok(TrendPoint {
                    run: r.int(0)?,
                    started: r.text(1)?,
                    rev: r.text(2)?,
                    board: r.text(3)?,
                    results: r.uint(4)?,
                    passed: r.uint(5)?,
                    station: r.text(6)?,
                })
            })
            .collect::<Result<_, DbError>>()?;
        let mut scenarios: Vec<ScenarioRate> = c
            .query(
                &format!(
                    "SELECT r.scenario, min(r.section), count(*),
                         count(CASE WHEN r.verdict IN ('passed', 'marginal') THEN 1 END),
                         count(CASE WHEN r.verdict = 'flaky' THEN 1 END),
                         count(CASE WHEN r.verdict = 'failed' THEN 1 END),
                         count(CASE WHEN r.verdict = 'error' THEN 1 END),
                         count(CASE WHEN r.verdict = 'not_run' THEN 1 END),
                         count(DISTINCT CASE WHEN b.reached <> 0 THEN {BOARD} END)
                     FROM results r LEFT JOIN boards b ON b.id = r.board_id
                     GROUP BY r.scenario"
                ),
                &[],
            )?
            .iter()
            .map(|r| {
                Ok(ScenarioRate {
                    scenario: r.text(0)?,
                    section: r.text(1)?,
                    results: r.uint(2)?,
                    passed: r.uint(3)?,
                    flaky: r.uint(4)?,
                    failed: r.uint(5)?,
                    errors: r.uint(6)?,
                    not_run: r.uint(7)?,
                    boards: r.uint(8)?,
                })
            })
            .collect::<Result<_, DbError>>()?;
        scenarios.sort_by(|a, b| {
            a.rate()
                .total_cmp(&b.rate())
                .then_with(|| a.scenario.cmp(&b.scenario))
        });
        h.scenarios = scenarios;
        h.measurements = distributions(c)?;
        Ok(())
    }
}

/// A store whose verdicts, blames or grades are none of ppmc's (written
/// by another program, or edited) is refused by name: counted, they
/// would fall out of every rate without a word.
fn refuse_unknown(c: &mut Conn) -> Result<(), DbError> {
    let checks = [
        (
            "SELECT id, verdict FROM results WHERE verdict NOT IN
                 ('passed', 'marginal', 'flaky', 'failed', 'error', 'not_run') ORDER BY id LIMIT 1",
            "results",
            "verdict",
            "passed, marginal, flaky, failed, error, not_run",
        ),
        (
            "SELECT id, blame FROM results WHERE blame IS NOT NULL
                 AND blame NOT IN ('board', 'host', 'capture') ORDER BY id LIMIT 1",
            "results",
            "blame",
            "board, host, capture",
        ),
        (
            "SELECT result_id, grade FROM measurements WHERE grade NOT IN
                 ('PASS', 'MARGINAL', 'FAIL') ORDER BY result_id LIMIT 1",
            "measurements of result",
            "grade",
            "PASS, MARGINAL, FAIL",
        ),
    ];
    for (sql, table, column, known) in checks {
        if let Some(row) = c.query(sql, &[])?.first() {
            return Err(DbError::corrupt(format!(
                "{table} {}: {column} `{}`, not one of ppmc's ({known})",
                row.int(0)?,
                ppmc_record::printable(&row.text(1)?)
            )));
        }
    }
    Ok(())
}

/// Each measurement's values per scenario and revision, in the order they
/// were kept.
fn distributions(c: &mut Conn) -> Result<Vec<Distribution>, DbError> {
    let mut groups: BTreeMap<(String, String, String), Distribution> = BTreeMap::new();
    c.for_each(
        &format!(
            "SELECT r.scenario, m.name, {REV}, m.value_ns, m.lo_ns, m.hi_ns,
                 m.marginal_lo_ns, m.marginal_hi_ns
             FROM measurements m JOIN results r ON r.id = m.result_id
                 LEFT JOIN boards b ON b.id = r.board_id
             ORDER BY m.result_id, m.name, m.value_ns"
        ),
        &[],
        |r| {
            let (scenario, name, rev) = (r.text(0)?, r.text(1)?, r.text(2)?);
            let (v, lo, hi) = (r.uint(3)?, r.uint(4)?, r.opt_uint(5)?);
            let (mlo, mhi) = (r.uint(6)?, r.opt_uint(7)?);
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
            Ok(())
        },
    )?;
    Ok(groups
        .into_values()
        .map(|mut d| {
            let xs: Vec<f64> = d.values.iter().map(|&v| v as f64).collect();
            d.mean_ns = mean_sd(&xs).0;
            d
        })
        .collect())
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
