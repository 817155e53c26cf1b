//! A scenario's result as a run record holds it
//! ([`ppmc_record::ScenarioRecord`]): the one place where a verdict, with
//! its device failure or harness error, becomes the record's status, its
//! failure's fields and its error's kind.

use super::outcome::{Failure, HarnessError};
use super::verdict::{Attempt, NotRun, ScenarioResult, Verdict};
use crate::backend::TargetErrorKind;
use ppmc_record::{AttemptRecord, ErrorKind, ErrorRecord, FailureRecord, ScenarioRecord, Status};

impl HarnessError {
    /// Whose problem it is, as a report types it: the infrastructure's
    /// when the link to the target failed under it or the instrument
    /// missed an op's aim (the board is not to blame, and neither is the
    /// harness), else the harness's.
    pub fn kind(&self) -> ErrorKind {
        match self {
            HarnessError::Target {
                kind: TargetErrorKind::Link,
                ..
            }
            | HarnessError::Aim(_)
            | HarnessError::Hung { .. } => ErrorKind::Infrastructure,
            _ => ErrorKind::Harness,
        }
    }
}

impl Failure {
    /// The failure as fields.
    pub fn record(&self) -> FailureRecord {
        FailureRecord {
            expectation: self.expectation.clone(),
            expected: self.expected.clone(),
            got: self.got.clone(),
            at_ns: self.at.as_nanos(),
            deviation: self.deviation.clone(),
        }
    }
}

impl Verdict {
    /// The record's status of this verdict; `retried`: it came after
    /// attempts that did not pass, so a pass is flaky.
    pub fn status(&self, retried: bool) -> Status {
        match self {
            _ if retried && self.ok() => Status::Flaky,
            Verdict::Passed => Status::Passed,
            Verdict::Marginal => Status::Marginal,
            Verdict::Failed(_) => Status::Failed,
            Verdict::Error(_) => Status::Error,
            Verdict::NotRun(_) => Status::NotRun,
        }
    }

    /// The error fields of a verdict that is an error or "not run": a
    /// scenario an interrupted run never reached is `interrupted`, one
    /// the target's loss kept from running `infrastructure`.
    pub fn error_record(&self) -> Option<ErrorRecord> {
        let (kind, message) = match self {
            Verdict::Error(e) => (e.kind(), e.to_string()),
            Verdict::NotRun(NotRun::Interrupted) => {
                (ErrorKind::Interrupted, NotRun::Interrupted.to_string())
            }
            Verdict::NotRun(why) => (ErrorKind::Infrastructure, why.to_string()),
            _ => return None,
        };
        Some(ErrorRecord { kind, message })
    }
}

impl Attempt {
    /// The attempt as a record lists it.
    pub fn record(&self) -> AttemptRecord {
        AttemptRecord {
            verdict: self.verdict.status(false),
            detail: self.verdict.detail(),
            error: self.verdict.error_record(),
            elapsed_ns: self.elapsed.as_nanos(),
            wall_s: self.wall.as_secs_f64(),
        }
    }
}

impl ScenarioResult {
    /// Its status in a record: a pass only on a retry is flaky.
    pub fn status(&self) -> Status {
        self.verdict.status(!self.attempts.is_empty())
    }

    /// The result as a run record holds it, on `board` (its name); its
    /// pass, figures and attachments are the run's to add.
    pub fn record(&self, board: Option<&str>) -> ScenarioRecord {
        ScenarioRecord {
            board: board.map(str::to_string),
            tags: self.tags.iter().map(|t| t.to_string()).collect(),
            detail: self.verdict.detail(),
            failure: match &self.verdict {
                Verdict::Failed(f) => Some(f.record()),
                _ => None,
            },
            error: self.verdict.error_record(),
            elapsed_ns: self.elapsed.as_nanos(),
            wall_s: self.wall.as_secs_f64(),
            measurements: self.measurements.clone(),
            attempts: self.attempts.iter().map(Attempt::record).collect(),
            ..ScenarioRecord::new(self.name, self.section, self.status())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::Duration;
    use ppmc_record::Tally;

    fn result(name: &'static str, e: HarnessError) -> ScenarioResult {
        ScenarioResult {
            name,
            section: "3-1-1",
            tags: &[],
            verdict: Verdict::Error(e),
            measurements: Vec::new(),
            trace: None,
            elapsed: Duration::ZERO,
            wall: std::time::Duration::ZERO,
            attempts: Vec::new(),
        }
    }

    /// A scenario cut short because the link to the board failed is the
    /// infrastructure's; a scenario's own bug stays the harness's; an
    /// interrupted run's leftovers are `interrupted`, a lost target's the
    /// infrastructure's.
    #[test]
    fn errors_are_typed_by_whose_they_are() {
        let cut = result(
            "cut",
            HarnessError::Target {
                kind: TargetErrorKind::Link,
                message: "link lost".into(),
            },
        )
        .record(Some("tcp://127.0.0.1:2000"));
        assert_eq!(cut.verdict, Status::Error);
        let e = cut.error.expect("an error");
        assert_eq!(
            (e.kind, e.message.as_str()),
            (ErrorKind::Infrastructure, "target: link lost")
        );
        assert_eq!(cut.board.as_deref(), Some("tcp://127.0.0.1:2000"));
        let bug = result("bug", HarnessError::Scenario("panicked".into())).record(None);
        assert_eq!(bug.error.map(|e| e.kind), Some(ErrorKind::Harness));
        let never = Verdict::NotRun(NotRun::Interrupted).error_record();
        assert_eq!(never.map(|e| e.kind), Some(ErrorKind::Interrupted));
        let lost = Verdict::NotRun(NotRun::TargetLost("gone".into())).error_record();
        assert_eq!(lost.map(|e| e.kind), Some(ErrorKind::Infrastructure));
    }

    /// A pass after an attempt that did not pass is flaky; a failure after
    /// one stays a failure.
    #[test]
    fn a_pass_on_a_retry_is_flaky() {
        let mut r = result("x", HarnessError::Reply("garbled".into()));
        r.attempts.push(Attempt::of(&r));
        r.verdict = Verdict::Passed;
        assert_eq!(r.status(), Status::Flaky);
        assert_eq!(r.record(None).attempts[0].verdict, Status::Error);
        r.verdict = Verdict::Failed(Failure {
            expectation: "e".into(),
            expected: "1".into(),
            got: "2".into(),
            at: crate::time::Instant::ZERO,
            deviation: None,
        });
        assert_eq!(r.status(), Status::Failed);
        assert_eq!(Tally::of([r.status()]).failed, 1);
    }
}
