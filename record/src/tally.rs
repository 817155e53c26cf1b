//! [`Tally`]: counts of verdicts, for a run, a board or a scenario's
//! repeated runs.

use crate::result::{ScenarioRecord, Status};
use serde::{Deserialize, Serialize};

/// Counts of verdicts; a run record's `summary`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    pub passed: usize,
    pub marginal: usize,
    /// Passed (or marginal) only on a retry: counted here, not in
    /// `passed` or `marginal`. Absent from records of format 3.
    #[serde(default)]
    pub flaky: usize,
    pub failed: usize,
    /// Spelled as the verdict is in the JSON record.
    #[serde(rename = "error")]
    pub errors: usize,
    pub not_run: usize,
}

impl Tally {
    /// The tally of `results`.
    pub fn of<'a>(results: impl IntoIterator<Item = &'a ScenarioRecord>) -> Tally {
        let mut t = Tally::default();
        for r in results {
            t.add(r.verdict);
        }
        t
    }

    /// Counts one verdict.
    pub fn add(&mut self, s: Status) {
        match s {
            Status::Passed => self.passed += 1,
            Status::Marginal => self.marginal += 1,
            Status::Flaky => self.flaky += 1,
            Status::Failed => self.failed += 1,
            Status::Error => self.errors += 1,
            Status::NotRun => self.not_run += 1,
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
