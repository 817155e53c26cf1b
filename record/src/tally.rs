//! A result's verdict as a record spells it ([`Status`]), and [`Tally`]:
//! counts of verdicts, for a run, a board or a scenario's repeated runs.

use serde::{Deserialize, Serialize};

/// A result's verdict as the record spells it: the keys of `summary`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Passed,
    /// Passed, with a measurement near a limit or within the instrument's
    /// uncertainty of it.
    Marginal,
    /// Passed (or marginal) only on a retry.
    Flaky,
    /// The device did something wrong.
    Failed,
    /// The harness, the link, the capture or a file failed: no verdict on
    /// the device.
    Error,
    /// Never started.
    NotRun,
}

impl Status {
    /// Its one spelling in the record.
    pub fn name(self) -> &'static str {
        match self {
            Status::Passed => "passed",
            Status::Marginal => "marginal",
            Status::Flaky => "flaky",
            Status::Failed => "failed",
            Status::Error => "error",
            Status::NotRun => "not_run",
        }
    }

    /// Whether it lets a run pass (passed, marginal, or flaky).
    pub fn ok(self) -> bool {
        matches!(self, Status::Passed | Status::Marginal | Status::Flaky)
    }
}

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
    /// The tally of `verdicts`.
    pub fn of(verdicts: impl IntoIterator<Item = Status>) -> Tally {
        let mut t = Tally::default();
        for s in verdicts {
            t.add(s);
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
