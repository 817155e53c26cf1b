//! [`Tally`]: counts of verdicts, for a run, a board or a scenario's
//! repeated runs.

use crate::scenario::{ScenarioResult, Verdict};
use serde::Serialize;

/// Counts of verdicts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Tally {
    pub passed: usize,
    pub marginal: usize,
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
            match r.verdict {
                Verdict::Passed => t.passed += 1,
                Verdict::Marginal => t.marginal += 1,
                Verdict::Failed(_) => t.failed += 1,
                Verdict::Error(_) => t.errors += 1,
                Verdict::NotRun(_) => t.not_run += 1,
            }
        }
        t
    }

    /// Whether the run passes: nothing failed, errored or was left out.
    pub fn ok(&self) -> bool {
        self.failed == 0 && self.errors == 0 && self.not_run == 0
    }
}
