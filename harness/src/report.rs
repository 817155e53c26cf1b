//! Run reports: JUnit XML for CI systems, and a JSON run record with every
//! measurement and its limits.

use crate::backend::TargetInfo;
use crate::scenario::{Grade, NotRun, ScenarioResult, Verdict};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::time::SystemTime;

/// A report that could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot render the JSON run record: {0}")]
    Json(#[source] serde_json::Error),
}

/// The selection and settings a run was made with, for the record.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RunOptions {
    pub filter: Option<String>,
    pub tags: Vec<String>,
    pub skip_tags: Vec<String>,
    /// `I/N`, when the run is one shard of the suite.
    pub shard: Option<String>,
    pub repeat: u32,
    /// The golden directory compared against, if any.
    pub golden: Option<String>,
    /// Width of the MARGINAL zone, percent of each limit.
    pub marginal_pct: f64,
    /// The golden comparison's tolerances.
    pub latency_tol_pct: f64,
    pub interval_tol_pct: f64,
    pub time_floor_ns: u64,
}

/// A board of a run: what the reports call it and what is known of it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoardInfo {
    /// The board's label: the `--target` given, or its `name=`.
    pub name: String,
    /// The target as reached: `serial:/dev/ttyACM0`, or
    /// `labgrid:rig1 (rfc2217://lab:2001)`.
    pub target: String,
    pub target_details: BTreeMap<String, String>,
    /// The board revision label (`rev=` or `--board-rev`).
    pub board_rev: Option<String>,
    /// The bus bridge's firmware version, when the target is a board.
    pub bridge_firmware: Option<String>,
    /// Why the board took no part in the run, or left it early.
    pub error: Option<String>,
}

impl BoardInfo {
    pub fn new(name: String, target: &TargetInfo, board_rev: Option<String>) -> BoardInfo {
        let bridge_firmware = target
            .extra
            .iter()
            .find(|(k, _)| k == "bridge_firmware")
            .map(|(_, v)| v.clone());
        BoardInfo {
            name,
            target: target.name.clone(),
            target_details: target.details().into_iter().collect(),
            board_rev,
            bridge_firmware,
            error: None,
        }
    }

    /// A board that could not be reached: nothing is known of it but its
    /// name, the address it was tried at (`target`) and why.
    pub fn unreached(
        name: String,
        target: String,
        board_rev: Option<String>,
        why: String,
    ) -> BoardInfo {
        BoardInfo {
            target,
            name,
            target_details: BTreeMap::new(),
            board_rev,
            bridge_firmware: None,
            error: Some(why),
        }
    }
}

/// Facts about a run that every report carries.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunInfo {
    pub harness_version: String,
    pub git_revision: String,
    /// The boards, in the order of `--target`; results name them by index.
    pub boards: Vec<BoardInfo>,
    /// `one` (a single board), `share` (each scenario on one of several
    /// boards) or `each` (every scenario on every board).
    pub spread: &'static str,
    /// When the run started, UTC, RFC 3339.
    pub started: String,
    /// Wall-clock duration of the whole run, seconds.
    pub wall_s: f64,
    /// The machine the harness ran on.
    pub host: String,
    pub options: RunOptions,
}

impl RunInfo {
    pub fn new(boards: Vec<BoardInfo>, spread: &'static str) -> RunInfo {
        RunInfo {
            harness_version: crate::VERSION.to_string(),
            git_revision: crate::GIT_REV.to_string(),
            boards,
            spread,
            started: rfc3339(SystemTime::now()),
            wall_s: 0.0,
            host: hostname(),
            options: RunOptions::default(),
        }
    }

    /// The label of board `b`, or `(none)` for a result no board took.
    pub fn board_name(&self, b: Option<usize>) -> &str {
        b.and_then(|b| self.boards.get(b))
            .map_or("(none)", |b| b.name.as_str())
    }
}

/// The machine's name, as far as it can be learned without privileges.
fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// `t` as `YYYY-MM-DDTHH:MM:SSZ` (UTC).
pub fn rfc3339(t: SystemTime) -> String {
    let secs = t
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3_600,
        rem % 3_600 / 60,
        rem % 60
    )
}

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

/// JUnit XML for CI systems, valid under the Jenkins xunit schema
/// (`junit-10.xsd`) and read by GitLab and junitparser: one test case per
/// scenario run (classname = datasheet section; names made unique under
/// `--repeat` with ` [pass K]`), `time` in wall seconds with the device's
/// virtual time as a suite property per case; a failure or error carries
/// its explanation in `message` and as its text; infrastructure problems
/// (target unreachable or lost) are errors, an interrupted run's leftovers
/// are skipped; the files saved for each result (`attachments`, in the
/// results' order; missing entries mean none) are `[[ATTACHMENT|path]]`
/// lines in `system-out`.
///
/// `boards` gives each result's board (an index into `info.boards`). A run
/// on one board is one test suite with the board's facts as properties
/// (`target`, `board_rev`, `target.*`). A run shared by several boards is
/// one test suite too: each board's facts are `board.<name>.*` properties,
/// and each test case names its board in a `board_of.<case>` property and a
/// `board:` line of its `system-out`. A run with `--each` is one test suite
/// per board, named after it.
pub fn junit(
    info: &RunInfo,
    results: &[ScenarioResult],
    attachments: &[Vec<String>],
    boards: &[Option<usize>],
) -> Result<String, ReportError> {
    let tally = Tally::of(results);
    let skipped = |rs: &[&ScenarioResult]| {
        rs.iter()
            .filter(|r| r.verdict == Verdict::NotRun(NotRun::Interrupted))
            .count()
    };
    let all: Vec<&ScenarioResult> = results.iter().collect();
    let errors = tally.errors + tally.not_run - skipped(&all);
    let board_of = |i: usize| boards.get(i).copied().flatten();
    // The suites: their board (when they have one) and their results.
    let groups: Vec<(Option<usize>, Vec<usize>)> = if info.spread == "each" {
        (0..info.boards.len())
            .map(|b| {
                let cases = (0..results.len()).filter(|&i| board_of(i) == Some(b));
                (Some(b), cases.collect())
            })
            .collect()
    } else if info.boards.len() == 1 {
        vec![(Some(0), (0..results.len()).collect())]
    } else {
        vec![(None, (0..results.len()).collect())]
    };
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<testsuites name=\"ppmc\" tests=\"{}\" failures=\"{}\" errors=\"{errors}\" time=\"{:.6}\">",
        results.len(),
        tally.failed,
        info.wall_s
    );
    for (board, cases) in groups {
        let rs: Vec<&ScenarioResult> = cases.iter().map(|&i| &results[i]).collect();
        let t = Tally::of_refs(&rs);
        let suite_skipped = skipped(&rs);
        let suite_errors = t.errors + t.not_run - suite_skipped;
        let wall: f64 = rs.iter().map(|r| r.wall.as_secs_f64()).sum();
        let mut suite_name = "ppmc-conformance".to_string();
        if let Some(shard) = &info.options.shard {
            suite_name.push_str(&format!(" shard {shard}"));
        }
        if info.spread == "each" {
            suite_name.push_str(&format!(" on {}", info.board_name(board)));
        }
        let names = unique_names(&rs);
        let _ = writeln!(
            x,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{suite_errors}\" skipped=\"{suite_skipped}\" \
             time=\"{wall:.6}\" timestamp=\"{}\" hostname=\"{}\">",
            esc(&suite_name),
            rs.len(),
            t.failed,
            esc(&info.started),
            esc(&info.host)
        );
        x.push_str("    <properties>\n");
        let mut props: Vec<(String, String)> = vec![
            ("harness_version".into(), info.harness_version.clone()),
            ("git_revision".into(), info.git_revision.clone()),
        ];
        match board {
            Some(b) => props.extend(board_props("", &info.boards[b])),
            None => {
                for b in &info.boards {
                    props.extend(board_props(&format!("board.{}.", b.name), b));
                }
                props.extend(cases.iter().zip(&names).map(|(&i, n)| {
                    (
                        format!("board_of.{n}"),
                        info.board_name(board_of(i)).to_string(),
                    )
                }));
            }
        }
        props.extend(rs.iter().zip(&names).map(|(r, n)| {
            (
                format!("device_time.{n}"),
                format!("{:.9}", r.elapsed.as_nanos() as f64 / 1e9),
            )
        }));
        for (k, v) in props {
            let _ = writeln!(
                x,
                "      <property name=\"{}\" value=\"{}\"/>",
                esc(&k),
                esc(&v)
            );
        }
        x.push_str("    </properties>\n");
        for (&i, name) in cases.iter().zip(&names) {
            let shared = board.is_none().then(|| info.board_name(board_of(i)));
            testcase(&mut x, &results[i], name, attachments.get(i), shared);
        }
        x.push_str("  </testsuite>\n");
    }
    x.push_str("</testsuites>\n");
    Ok(x)
}

/// A board's facts as suite properties, their names prefixed by `prefix`.
fn board_props(prefix: &str, b: &BoardInfo) -> Vec<(String, String)> {
    let mut props = vec![
        (format!("{prefix}target"), b.target.clone()),
        (
            format!("{prefix}board_rev"),
            b.board_rev.clone().unwrap_or_default(),
        ),
        (
            format!("{prefix}bridge_firmware"),
            b.bridge_firmware.clone().unwrap_or_default(),
        ),
    ];
    if let Some(e) = &b.error {
        props.push((format!("{prefix}error"), e.clone()));
    }
    props.extend(
        b.target_details
            .iter()
            .map(|(k, v)| (format!("{prefix}target.{k}"), v.clone())),
    );
    props
}

/// One `<testcase>`; `board` names the board when the suite is shared.
fn testcase(
    x: &mut String,
    r: &ScenarioResult,
    name: &str,
    attachments: Option<&Vec<String>>,
    board: Option<&str>,
) {
    let _ = write!(
        x,
        "    <testcase name=\"{}\" classname=\"section {}\" time=\"{:.6}\"",
        esc(name),
        esc(r.section),
        r.wall.as_secs_f64()
    );
    let mut body = String::new();
    let mut element = |tag: &str, kind: &str, message: &str| {
        let _ = writeln!(
            body,
            "      <{tag} type=\"{kind}\" message=\"{}\">{}</{tag}>",
            esc(message),
            esc_text(message)
        );
    };
    match &r.verdict {
        Verdict::Passed | Verdict::Marginal => {}
        Verdict::Failed(f) => element("failure", "device", &f.to_string()),
        Verdict::Error(e) => element("error", "harness", &e.to_string()),
        Verdict::NotRun(NotRun::Interrupted) => {
            element("skipped", "interrupted", &NotRun::Interrupted.to_string())
        }
        Verdict::NotRun(why) => element("error", "infrastructure", &why.to_string()),
    }
    let mut out: Vec<String> = Vec::new();
    if let Some(b) = board {
        out.push(format!("board: {b}"));
    }
    if r.verdict == Verdict::Marginal {
        let near: Vec<String> = r
            .measurements
            .iter()
            .filter(|m| m.grade == Grade::Marginal)
            .map(|m| m.to_string())
            .collect();
        out.push(format!("MARGINAL: {}", near.join("; ")));
    }
    out.extend(
        attachments
            .into_iter()
            .flatten()
            .map(|p| format!("[[ATTACHMENT|{p}]]")),
    );
    if !out.is_empty() {
        let _ = writeln!(
            body,
            "      <system-out>{}</system-out>",
            esc_text(&out.join("\n"))
        );
    }
    if body.is_empty() {
        x.push_str("/>\n");
    } else {
        x.push_str(">\n");
        x.push_str(&body);
        x.push_str("    </testcase>\n");
    }
}

/// Test case names, with ` [pass K]` when a scenario ran more than once.
fn unique_names(results: &[&ScenarioResult]) -> Vec<String> {
    let mut runs: BTreeMap<&str, usize> = BTreeMap::new();
    for r in results {
        *runs.entry(r.name).or_default() += 1;
    }
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    results
        .iter()
        .map(|r| {
            let k = seen.entry(r.name).or_default();
            *k += 1;
            if runs[r.name] > 1 {
                format!("{} [pass {k}]", r.name)
            } else {
                r.name.to_string()
            }
        })
        .collect()
}

/// Text as an XML attribute value (a newline kept as `&#10;`).
fn esc(s: &str) -> String {
    escape(s, true)
}

/// Text as XML element content (newlines as they are).
fn esc_text(s: &str) -> String {
    escape(s, false)
}

/// Characters XML 1.0 cannot carry at all (most control characters)
/// become `?`.
fn escape(s: &str, attribute: bool) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\n' if !attribute => o.push('\n'),
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            '\n' => o.push_str("&#10;"),
            '\t' | '\r' => o.push(' '),
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => o.push('?'),
            c => o.push(c),
        }
    }
    o
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

/// What the device did wrong, as fields.
#[derive(Serialize)]
struct JsonFailure<'a> {
    expectation: &'a str,
    expected: &'a str,
    got: &'a str,
    at_ns: u64,
}

/// Why the harness could not judge, as fields.
#[derive(Serialize)]
struct JsonError {
    /// `harness`, `infrastructure` (target unreachable or lost) or
    /// `interrupted`.
    kind: &'static str,
    message: String,
}

#[derive(Serialize)]
struct JsonScenario<'a> {
    name: &'a str,
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
    let run = JsonRun {
        format: "ppmc-run-record/3",
        run: info,
        summary: Tally::of(results),
        scenarios: results
            .iter()
            .enumerate()
            .map(|(i, r)| JsonScenario {
                name: r.name,
                board: boards
                    .get(i)
                    .copied()
                    .flatten()
                    .and_then(|b| info.boards.get(b))
                    .map(|b| b.name.as_str()),
                section: r.section,
                tags: r.tags,
                verdict: json_verdict(&r.verdict),
                detail: r.verdict.detail(),
                failure: match &r.verdict {
                    Verdict::Failed(f) => Some(JsonFailure {
                        expectation: &f.expectation,
                        expected: &f.expected,
                        got: &f.got,
                        at_ns: f.at.as_nanos(),
                    }),
                    _ => None,
                },
                error: match &r.verdict {
                    Verdict::Error(e) => Some(JsonError {
                        kind: "harness",
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
                },
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
                        grade: m.grade.name(),
                        at_ns: m.at.as_nanos(),
                    })
                    .collect(),
            })
            .collect(),
    };
    serde_json::to_string_pretty(&run).map_err(ReportError::Json)
}
