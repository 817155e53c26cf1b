//! How a scenario ended: its [`Verdict`] (or why it never ran,
//! [`NotRun`]) and everything the run learned of it, [`ScenarioResult`].

use super::outcome::{Failure, HarnessError};
use crate::time::Duration;
use crate::trace::Trace;
use ppmc_record::Measurement;

/// How a scenario ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    Passed,
    /// Passed, with at least one measurement near a limit.
    Marginal,
    /// The device did something wrong.
    Failed(Failure),
    /// The harness or the link failed.
    Error(HarnessError),
    /// Never started (the run stopped before it).
    NotRun(NotRun),
}

/// Why a scenario was never started: the infrastructure, never the device.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NotRun {
    /// The target could not be reached or was not healthy before the run
    /// began (the text says why).
    #[error("{0}")]
    Unreachable(String),
    /// The target stopped answering during the run (after a harness error,
    /// the health check failed too).
    #[error("not run: the target stopped answering ({0})")]
    TargetLost(String),
    /// The run was stopped before it (SIGINT, SIGTERM, or its output
    /// closed).
    #[error("not run: the run was interrupted")]
    Interrupted,
}

impl Verdict {
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Passed => "passed",
            Verdict::Marginal => "marginal",
            Verdict::Failed(_) => "failed",
            Verdict::Error(_) => "error",
            Verdict::NotRun(_) => "not run",
        }
    }

    /// Whether the verdict lets a run pass (passed or marginal).
    pub fn ok(&self) -> bool {
        matches!(self, Verdict::Passed | Verdict::Marginal)
    }

    /// The one-line reason, for reports.
    pub fn detail(&self) -> Option<String> {
        match self {
            Verdict::Passed => None,
            Verdict::Marginal => Some(
                "a measurement is near its limit, or within the instrument's uncertainty of it"
                    .into(),
            ),
            Verdict::Failed(f) => Some(f.to_string()),
            Verdict::Error(e) => Some(e.to_string()),
            Verdict::NotRun(why) => Some(why.to_string()),
        }
    }
}

/// Everything a run learned about one scenario.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    pub name: &'static str,
    pub section: &'static str,
    pub tags: &'static [&'static str],
    pub verdict: Verdict,
    pub measurements: Vec<Measurement>,
    /// `None` when the target could not deliver a capture.
    pub trace: Option<Trace>,
    /// Virtual time the scenario took on the target.
    pub elapsed: Duration,
    /// Wall-clock time the harness spent on it.
    pub wall: std::time::Duration,
    /// The attempts before this one, oldest first, when the runner tried
    /// the scenario again ([`Retry`]); empty when it ran once.
    pub attempts: Vec<Attempt>,
}

impl ScenarioResult {
    /// Passed, but only on a retry: an attempt before it did not.
    pub fn flaky(&self) -> bool {
        self.verdict.ok() && !self.attempts.is_empty()
    }
}

/// An attempt at a scenario that was tried again: how it ended.
#[derive(Debug, Clone)]
pub struct Attempt {
    pub verdict: Verdict,
    pub elapsed: Duration,
    pub wall: std::time::Duration,
}

impl Attempt {
    /// The attempt `r` was.
    pub fn of(r: &ScenarioResult) -> Attempt {
        Attempt {
            verdict: r.verdict.clone(),
            elapsed: r.elapsed,
            wall: r.wall,
        }
    }
}

/// When the runner tries a scenario again, on the same board (`--retries`,
/// `--retry-failures`): every attempt stays on record, and a scenario
/// that passed only on a retry is flaky, never plainly passed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Retry {
    /// Attempts after the first, at most.
    pub times: u32,
    /// Retry a device failure too, not only a link or bridge error.
    pub failures: bool,
}

impl Retry {
    /// Whether a scenario that ended in `v` is tried again: a link error
    /// (the link, a garbled reply, a capture that did not come back), an
    /// op the target did too far from its aim, and with `failures` a
    /// device failure. Never the scenario's own bug, a
    /// budget, a golden file, or a stop.
    pub fn takes(&self, v: &Verdict) -> bool {
        use crate::backend::TargetErrorKind;
        match v {
            Verdict::Error(HarnessError::Target { kind, .. }) => *kind == TargetErrorKind::Link,
            Verdict::Error(
                HarnessError::Reply(_) | HarnessError::Capture(_) | HarnessError::Aim(_),
            ) => true,
            Verdict::Failed(_) => self.failures,
            _ => false,
        }
    }
}
