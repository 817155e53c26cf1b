//! Run reports: JUnit XML for CI systems, and a JSON run record with every
//! measurement and its limits.

use crate::backend::TargetInfo;
use crate::scenario::{Grade, ScenarioResult, Verdict};
use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};
use serde::Serialize;

/// A report that could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot render the JUnit report: {0}")]
    Junit(#[source] quick_junit::SerializeError),
    #[error("cannot render the JSON run record: {0}")]
    Json(#[source] serde_json::Error),
}

/// Facts about a run that every report carries.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RunInfo {
    pub harness_version: String,
    pub git_revision: String,
    pub target: String,
    pub target_details: Vec<(String, String)>,
    /// The board revision label given with `--board-rev`.
    pub board_rev: Option<String>,
    /// The bus bridge's firmware version, when the target is a board.
    pub bridge_firmware: Option<String>,
}

impl RunInfo {
    pub fn new(target: &TargetInfo, board_rev: Option<String>) -> RunInfo {
        let bridge_firmware = target
            .extra
            .iter()
            .find(|(k, _)| k == "bridge_firmware")
            .map(|(_, v)| v.clone());
        RunInfo {
            harness_version: crate::VERSION.to_string(),
            git_revision: crate::GIT_REV.to_string(),
            target: target.name.clone(),
            target_details: target.details(),
            board_rev,
            bridge_firmware,
        }
    }

    /// A run whose target could not be reached: nothing is known of it
    /// but its name.
    pub fn unreached(target: String, board_rev: Option<String>) -> RunInfo {
        RunInfo {
            harness_version: crate::VERSION.to_string(),
            git_revision: crate::GIT_REV.to_string(),
            target,
            target_details: Vec::new(),
            board_rev,
            bridge_firmware: None,
        }
    }
}

/// Counts of verdicts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Tally {
    pub passed: usize,
    pub marginal: usize,
    pub failed: usize,
    pub errors: usize,
    pub not_run: usize,
}

impl Tally {
    pub fn of(results: &[ScenarioResult]) -> Tally {
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

/// JUnit XML: one test case per scenario (classname = datasheet section),
/// the failure text = the first divergence; run facts as properties.
pub fn junit(info: &RunInfo, results: &[ScenarioResult]) -> Result<String, ReportError> {
    let mut report = Report::new("ppmc");
    let mut suite = TestSuite::new("ppmc-conformance");
    let props: Vec<(String, String)> = [
        ("harness_version".to_string(), info.harness_version.clone()),
        ("git_revision".to_string(), info.git_revision.clone()),
        ("target".to_string(), info.target.clone()),
        (
            "board_rev".to_string(),
            info.board_rev.clone().unwrap_or_default(),
        ),
        (
            "bridge_firmware".to_string(),
            info.bridge_firmware.clone().unwrap_or_default(),
        ),
    ]
    .into_iter()
    .chain(
        info.target_details
            .iter()
            .map(|(k, v)| (format!("target.{k}"), v.clone())),
    )
    .collect();
    for (k, v) in props {
        suite.add_property((k, v));
    }
    for r in results {
        let status = match &r.verdict {
            Verdict::Passed | Verdict::Marginal => TestCaseStatus::success(),
            Verdict::Failed(f) => {
                let mut s = TestCaseStatus::non_success(NonSuccessKind::Failure);
                s.set_message(f.to_string());
                s.set_type("device");
                s
            }
            Verdict::Error(e) => {
                let mut s = TestCaseStatus::non_success(NonSuccessKind::Error);
                s.set_message(e.to_string());
                s.set_type("harness");
                s
            }
            Verdict::NotRun(why) => {
                let mut s = TestCaseStatus::skipped();
                s.set_message(why.to_string());
                s
            }
        };
        let mut case = TestCase::new(r.name, status);
        case.set_classname(format!("section {}", r.section));
        case.set_time(std::time::Duration::from_nanos(r.elapsed.as_nanos()));
        if r.verdict == Verdict::Marginal {
            let names: Vec<String> = r
                .measurements
                .iter()
                .filter(|m| m.grade == Grade::Marginal)
                .map(|m| m.to_string())
                .collect();
            case.set_system_out(format!("MARGINAL: {}", names.join("; ")));
        }
        suite.add_test_case(case);
    }
    report.add_test_suite(suite);
    report.to_string().map_err(ReportError::Junit)
}

#[derive(Serialize)]
struct JsonMeasurement<'a> {
    name: &'a str,
    value_ns: u64,
    lo_ns: u64,
    hi_ns: Option<u64>,
    marginal_lo_ns: u64,
    marginal_hi_ns: Option<u64>,
    grade: &'static str,
    at_ns: u64,
}

#[derive(Serialize)]
struct JsonScenario<'a> {
    name: &'a str,
    section: &'a str,
    tags: &'a [&'a str],
    verdict: &'static str,
    detail: Option<String>,
    elapsed_ns: u64,
    measurements: Vec<JsonMeasurement<'a>>,
}

#[derive(Serialize)]
struct JsonRun<'a> {
    format: &'static str,
    run: &'a RunInfo,
    summary: Tally,
    scenarios: Vec<JsonScenario<'a>>,
}

fn finite(d: crate::time::Duration) -> Option<u64> {
    (d != crate::time::Duration::MAX).then_some(d.as_nanos())
}

/// The JSON run record.
pub fn json(info: &RunInfo, results: &[ScenarioResult]) -> Result<String, ReportError> {
    let run = JsonRun {
        format: "ppmc-run-record/1",
        run: info,
        summary: Tally::of(results),
        scenarios: results
            .iter()
            .map(|r| JsonScenario {
                name: r.name,
                section: r.section,
                tags: r.tags,
                verdict: r.verdict.label(),
                detail: r.verdict.detail(),
                elapsed_ns: r.elapsed.as_nanos(),
                measurements: r
                    .measurements
                    .iter()
                    .map(|m| JsonMeasurement {
                        name: &m.name,
                        value_ns: m.value.as_nanos(),
                        lo_ns: m.lo.as_nanos(),
                        hi_ns: finite(m.hi),
                        marginal_lo_ns: m.marginal_lo.as_nanos(),
                        marginal_hi_ns: finite(m.marginal_hi),
                        grade: m.grade.name(),
                        at_ns: m.at.as_nanos(),
                    })
                    .collect(),
            })
            .collect(),
    };
    serde_json::to_string_pretty(&run).map_err(ReportError::Json)
}
