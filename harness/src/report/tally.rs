//! [`Tally`]: counts of verdicts, for a run, a board or a scenario's
//! repeated runs.

use crate::scenario::{ScenarioResult, Verdict};
use serde::Serialize;

/// Counts of verdicts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Tally {
    pub passed: usize,
    pub marginal: usize,
    /// Passed (or marginal) only on a retry: counted here, not in
    /// `passed` or `marginal`.
    pub flaky: usize,
    pub failed: usize,
    /// Spelled as the verdict is in the JSON record.
    #[serde(rename = "error")]
    pub errors: usize,
    pub not_run: usize,
}

impl Tally {
    pub fn of(results: &[ScenarioResult]) -> Tally {
        Tally::of_refs(&results.iter().collect::<Vec<_>>())
    }

    /// [`Tally::of`] some of a run's results.
    pub fn of_refs(results: &[&ScenarioResult]) -> Tally {
        let mut t = Tally::default();
        for r in results {
            t.count(r);
        }
        t
    }

    /// Counts one result: a pass on a retry as flaky.
    pub fn count(&mut self, r: &ScenarioResult) {
        match r.verdict {
            _ if r.flaky() => self.flaky += 1,
            Verdict::Passed => self.passed += 1,
            Verdict::Marginal => self.marginal += 1,
            Verdict::Failed(_) => self.failed += 1,
            Verdict::Error(_) => self.errors += 1,
            Verdict::NotRun(_) => self.not_run += 1,
        }
    }

    /// How many results it counts.
    pub fn runs(&self) -> usize {
        self.passed + self.marginal + self.flaky + self.failed + self.errors + self.not_run
    }

    /// Whether the run passes: nothing failed, errored or was left out (a
    /// flaky pass passes, unless `--flaky-is-failure`: [`Tally::ok_strict`]).
    pub fn ok(&self) -> bool {
        self.failed == 0 && self.errors == 0 && self.not_run == 0
    }

    /// [`Tally::ok`], and nothing passed only on a retry.
    pub fn ok_strict(&self) -> bool {
        self.ok() && self.flaky == 0
    }
}
