//! The JSON run record (see [`json`]; its schema is
//! `docs/run-record.schema.json`).

use super::figures::Figures;
use super::info::RunInfo;
use super::listing::{error_kind, Blame, Listing, ReportError};
use super::tally::Tally;
use crate::scenario::{NotRun, ScenarioResult, Verdict};
use serde::Serialize;

#[derive(Serialize)]
struct JsonMeasurement<'a> {
    name: &'a str,
    value_ns: u64,
    lo_ns: u64,
    hi_ns: Option<u64>,
    marginal_lo_ns: u64,
    marginal_hi_ns: Option<u64>,
    /// The measurement's uncertainty (±), the instrument's.
    u_ns: u64,
    grade: &'static str,
    at_ns: u64,
}

/// What the device did wrong, as fields.
#[derive(Serialize)]
struct JsonFailure<'a> {
    expectation: &'a str,
    expected: &'a str,
    got: &'a str,
    at_ns: u64,
}

/// The host firmware using the chip against chapter 3, found in a capture.
#[derive(Serialize)]
struct JsonFinding<'a> {
    at_ns: u64,
    section: &'a str,
    what: &'a str,
}

/// Why the harness could not judge, as fields.
#[derive(Serialize)]
struct JsonError {
    /// `harness`, `infrastructure` (target unreachable or lost),
    /// `interrupted`, or `capture` (a capture that cannot be judged).
    kind: &'static str,
    message: String,
}

#[derive(Serialize)]
struct JsonScenario<'a> {
    name: &'a str,
    /// Its pass, from 1, when the run repeats.
    #[serde(skip_serializing_if = "Option::is_none")]
    pass: Option<usize>,
    /// The board it ran on (`run.boards[].name`); null if none took it.
    board: Option<&'a str>,
    section: &'a str,
    tags: &'a [&'a str],
    /// `passed`, `marginal`, `failed`, `error` or `not_run`: the keys of
    /// `summary`.
    verdict: &'static str,
    detail: Option<String>,
    failure: Option<JsonFailure<'a>>,
    error: Option<JsonError>,
    elapsed_ns: u64,
    wall_s: f64,
    measurements: Vec<JsonMeasurement<'a>>,
    /// Judged from a capture (absent otherwise): whom the verdict blames,
    /// `board`, `host` or `capture`; null when it passed.
    #[serde(skip_serializing_if = "Option::is_none")]
    blame: Option<Option<&'static str>>,
    /// On the result that judges the host firmware: its findings.
    #[serde(skip_serializing_if = "Option::is_none")]
    host_findings: Option<Vec<JsonFinding<'a>>>,
    /// The attempts before the last, when the scenario was tried again.
    attempts: Vec<JsonAttempt>,
    /// What the HTML report draws: each move's pulse runs (the board's and
    /// the golden's), the pins around the failure.
    #[serde(skip_serializing_if = "Option::is_none")]
    figures: Option<&'a Figures>,
}

/// An attempt before a scenario's last.
#[derive(Serialize)]
struct JsonAttempt {
    verdict: &'static str,
    detail: Option<String>,
    error: Option<JsonError>,
    elapsed_ns: u64,
    wall_s: f64,
}

/// The error fields of a verdict that is an error or "not run".
fn json_error(v: &Verdict) -> Option<JsonError> {
    match v {
        Verdict::Error(e) => Some(JsonError {
            kind: error_kind(e),
            message: e.to_string(),
        }),
        Verdict::NotRun(NotRun::Interrupted) => Some(JsonError {
            kind: "interrupted",
            message: NotRun::Interrupted.to_string(),
        }),
        Verdict::NotRun(why) => Some(JsonError {
            kind: "infrastructure",
            message: why.to_string(),
        }),
        _ => None,
    }
}

/// The verdict's one spelling in the JSON record.
fn json_verdict(v: &Verdict) -> &'static str {
    match v {
        Verdict::Passed => "passed",
        Verdict::Marginal => "marginal",
        Verdict::Failed(_) => "failed",
        Verdict::Error(_) => "error",
        Verdict::NotRun(_) => "not_run",
    }
}

#[derive(Serialize)]
struct JsonRun<'a> {
    format: &'static str,
    run: &'a RunInfo,
    summary: Tally,
    scenarios: Vec<JsonScenario<'a>>,
    /// Under `--repeat`: each scenario's runs after the first pass that
    /// are not in `scenarios`, counted.
    #[serde(skip_serializing_if = "Option::is_none")]
    repeated: Option<Vec<JsonRepeated<'a>>>,
}

/// One measurement over a scenario's repeated runs.
#[derive(Serialize)]
struct JsonRange<'a> {
    name: &'a str,
    count: u64,
    min_ns: u64,
    mean_ns: u64,
    max_ns: u64,
    worst_grade: &'static str,
}

/// A scenario's runs on one board after the first pass, counted.
#[derive(Serialize)]
struct JsonRepeated<'a> {
    name: &'a str,
    board: Option<&'a str>,
    section: &'a str,
    tags: &'a [&'a str],
    first_pass: usize,
    last_pass: usize,
    runs: usize,
    summary: Tally,
    interrupted: usize,
    elapsed_ns: u64,
    wall_s: f64,
    measurements: Vec<JsonRange<'a>>,
}

fn finite(d: crate::time::Duration) -> Option<u64> {
    (d != crate::time::Duration::MAX).then_some(d.as_nanos())
}

/// The JSON run record; `boards` gives each result's board (an index into
/// `info.boards`).
pub fn json(
    info: &RunInfo,
    results: &[ScenarioResult],
    boards: &[Option<usize>],
) -> Result<String, ReportError> {
    json_listing(info, &Listing::all(results, &[], boards))
}

/// [`json`] of what `listing` lists: `summary` counts every run; under
/// `--repeat` each listed scenario carries its `pass`, and `repeated`
/// holds each scenario's other runs after the first pass, counted, with
/// each measurement's range.
pub fn json_listing(info: &RunInfo, l: &Listing) -> Result<String, ReportError> {
    let (results, boards) = (l.results, l.boards);
    let repeats = info.options.repeat > 1 && !l.passes.is_empty();
    let board_name = |b: Option<usize>| b.and_then(|b| info.boards.get(b)).map(|b| b.name.as_str());
    let run = JsonRun {
        format: "ppmc-run-record/4",
        run: info,
        summary: l.tally,
        repeated: repeats.then(|| {
            l.repeated
                .iter()
                .map(|r| JsonRepeated {
                    name: r.name,
                    board: board_name(r.board),
                    section: r.section,
                    tags: r.tags,
                    first_pass: r.first_pass,
                    last_pass: r.last_pass,
                    runs: r.runs(),
                    summary: r.tally,
                    interrupted: r.interrupted,
                    elapsed_ns: r.elapsed.as_nanos(),
                    wall_s: r.wall.as_secs_f64(),
                    measurements: r
                        .measurements
                        .iter()
                        .map(|m| JsonRange {
                            name: &m.name,
                            count: m.count,
                            min_ns: m.min.as_nanos(),
                            mean_ns: m.mean().as_nanos(),
                            max_ns: m.max.as_nanos(),
                            worst_grade: m.worst.name(),
                        })
                        .collect(),
                })
                .collect()
        }),
        scenarios: results
            .iter()
            .enumerate()
            .map(|(i, r)| JsonScenario {
                name: r.name,
                pass: l.passes.get(i).copied().filter(|_| repeats),
                board: boards
                    .get(i)
                    .copied()
                    .flatten()
                    .and_then(|b| info.boards.get(b))
                    .map(|b| b.name.as_str()),
                section: r.section,
                tags: r.tags,
                verdict: match r.flaky() {
                    true => "flaky",
                    false => json_verdict(&r.verdict),
                },
                attempts: r
                    .attempts
                    .iter()
                    .map(|a| JsonAttempt {
                        verdict: json_verdict(&a.verdict),
                        detail: a.verdict.detail(),
                        error: json_error(&a.verdict),
                        elapsed_ns: a.elapsed.as_nanos(),
                        wall_s: a.wall.as_secs_f64(),
                    })
                    .collect(),
                detail: l
                    .judged_of(i)
                    .and_then(|j| j.message.clone())
                    .or_else(|| r.verdict.detail()),
                failure: match &r.verdict {
                    Verdict::Failed(f) => Some(JsonFailure {
                        expectation: &f.expectation,
                        expected: &f.expected,
                        got: &f.got,
                        at_ns: f.at.as_nanos(),
                    }),
                    _ => None,
                },
                error: json_error(&r.verdict).map(|e| match l.judged_of(i).and_then(|j| j.blame) {
                    Some(Blame::Capture) if matches!(r.verdict, Verdict::Error(_)) => JsonError {
                        kind: "capture",
                        ..e
                    },
                    _ => e,
                }),
                elapsed_ns: r.elapsed.as_nanos(),
                wall_s: r.wall.as_secs_f64(),
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
                        u_ns: m.u.as_nanos(),
                        grade: m.grade.name(),
                        at_ns: m.at.as_nanos(),
                    })
                    .collect(),
                blame: l.judged_of(i).map(|j| j.blame.map(Blame::name)),
                host_findings: l.judged_of(i).and_then(|j| j.host.as_ref()).map(|h| {
                    h.iter()
                        .map(|f| JsonFinding {
                            at_ns: f.at_ps / 1000,
                            section: f.section,
                            what: &f.what,
                        })
                        .collect()
                }),
                figures: l.figures_of(i),
            })
            .collect(),
    };
    serde_json::to_string_pretty(&run).map_err(ReportError::Json)
}
