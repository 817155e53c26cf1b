//! What the JUnit and JSON reports share: what they list ([`Listing`]),
//! how they type a scenario's error, and the error of a report that could
//! not be rendered ([`ReportError`]).

use super::figures::Figures;
use super::tally::Tally;
use crate::backend::TargetErrorKind;
use crate::scenario::{HarnessError, ScenarioResult};
use crate::soak::Repeated;

/// A report that could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot render the JSON run record: {0}")]
    Json(#[source] serde_json::Error),
}

/// What a report lists: the results one by one (with, for each, the files
/// saved for it, its board as an index into `RunInfo::boards`, and its pass
/// when the run repeats), and a soak run's repeated runs
/// ([`crate::soak`]), with the tally of the whole run.
#[derive(Debug, Clone, Copy)]
pub struct Listing<'a> {
    pub results: &'a [ScenarioResult],
    /// In the results' order; missing entries mean none.
    pub attachments: &'a [Vec<String>],
    pub boards: &'a [Option<usize>],
    /// Each result's pass, from 1; empty when the run does not repeat.
    pub passes: &'a [usize],
    pub repeated: &'a [Repeated],
    /// Every verdict of the run, listed or not.
    pub tally: Tally,
    /// What the results judged from a capture add (`ppmc judge`), in the
    /// results' order; empty for a run of boards.
    pub judged: &'a [Judged],
    /// What the HTML report draws of each result, in the results' order;
    /// missing entries mean none.
    pub figures: &'a [Option<Figures>],
}

/// The party a result judged from a capture blames (issue 30): the board,
/// the host firmware driving it, or the capture itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blame {
    Board,
    Host,
    Capture,
}

impl Blame {
    /// Its one spelling in the JSON record.
    pub fn name(self) -> &'static str {
        match self {
            Blame::Board => "board",
            Blame::Host => "host",
            Blame::Capture => "capture",
        }
    }
}

/// What a result judged from a capture adds to its verdict.
#[derive(Debug, Clone, Default)]
pub struct Judged {
    /// Whom the verdict blames; `None` when it passed.
    pub blame: Option<Blame>,
    /// The verdict's line as the judge prints it, in place of the
    /// verdict's own words.
    pub message: Option<String>,
    /// The host firmware's findings, on the result that judges the host.
    pub host: Option<Vec<crate::judge::HostFinding>>,
    /// What the verdict's text says after its message: what was not
    /// judged, what was compared, each finding.
    pub notes: Vec<String>,
}

impl<'a> Listing<'a> {
    /// Every result of a run, listed one by one.
    pub fn all(
        results: &'a [ScenarioResult],
        attachments: &'a [Vec<String>],
        boards: &'a [Option<usize>],
    ) -> Listing<'a> {
        Listing {
            results,
            attachments,
            boards,
            passes: &[],
            repeated: &[],
            tally: Tally::of(results),
            judged: &[],
            figures: &[],
        }
    }

    /// The results, with what the HTML report draws of each.
    pub fn with_figures(mut self, figures: &'a [Option<Figures>]) -> Listing<'a> {
        self.figures = figures;
        self
    }

    pub(super) fn figures_of(&self, i: usize) -> Option<&'a Figures> {
        self.figures.get(i).and_then(Option::as_ref)
    }

    /// The results, judged from a capture: `judged` in their order.
    pub fn judged(mut self, judged: &'a [Judged]) -> Listing<'a> {
        self.judged = judged;
        self
    }

    pub(super) fn judged_of(&self, i: usize) -> Option<&'a Judged> {
        self.judged.get(i)
    }

    pub(super) fn board_of(&self, i: usize) -> Option<usize> {
        self.boards.get(i).copied().flatten()
    }
}

/// How a report types a scenario's error: `infrastructure` when the link
/// to the target failed under it (the board is not to blame, and neither
/// is the harness), else `harness`.
pub(super) fn error_kind(e: &HarnessError) -> &'static str {
    match e {
        HarnessError::Target {
            kind: TargetErrorKind::Link,
            ..
        } => "infrastructure",
        _ => "harness",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::TargetInfo;
    use crate::report::info::{BoardInfo, RunInfo};
    use crate::report::json::json;
    use crate::report::junit::junit;
    use crate::scenario::Verdict;

    /// A scenario cut short because the link to the board failed is the
    /// infrastructure's, in both reports; a scenario's own bug stays the
    /// harness's.
    #[test]
    fn a_scenario_the_link_failed_is_typed_infrastructure() {
        let info = RunInfo::new(
            vec![BoardInfo::new(
                "tcp://127.0.0.1:2000".into(),
                &TargetInfo {
                    name: "tcp://127.0.0.1:2000".into(),
                    straps: crate::protocol::Straps::default(),
                    extra: Vec::new(),
                },
                None,
            )],
            "one",
        );
        let result = |name, e| ScenarioResult {
            name,
            section: "3-1-1",
            tags: &[],
            verdict: Verdict::Error(e),
            measurements: Vec::new(),
            trace: None,
            elapsed: crate::time::Duration::ZERO,
            wall: std::time::Duration::ZERO,
            attempts: Vec::new(),
        };
        let results = [
            result(
                "cut",
                HarnessError::Target {
                    kind: TargetErrorKind::Link,
                    message: "link lost".into(),
                },
            ),
            result("bug", HarnessError::Scenario("panicked".into())),
        ];
        let on = [Some(0), Some(0)];
        let xml = junit(&info, &results, &[Vec::new(), Vec::new()], &on).expect("junit");
        assert!(
            xml.contains("<error type=\"infrastructure\" message=\"target: link lost\""),
            "{xml}"
        );
        assert!(
            xml.contains("<error type=\"harness\" message=\"panicked\""),
            "{xml}"
        );
        let record: serde_json::Value =
            serde_json::from_str(&json(&info, &results, &on).expect("json")).expect("JSON");
        assert_eq!(record["scenarios"][0]["error"]["kind"], "infrastructure");
        assert_eq!(record["scenarios"][1]["error"]["kind"], "harness");
    }
}
