//! Run reports: JUnit XML for CI systems, and a JSON run record with every
//! measurement and its limits.

use crate::backend::{TargetErrorKind, TargetInfo};
use crate::scenario::{Grade, HarnessError, NotRun, ScenarioResult, Verdict};
use crate::soak::Repeated;
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
        }
    }

    fn board_of(&self, i: usize) -> Option<usize> {
        self.boards.get(i).copied().flatten()
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
    junit_listing(info, &Listing::all(results, attachments, boards))
}

/// A test case: a result, or a scenario's repeated runs.
enum Case<'a> {
    One(usize),
    Many(&'a Repeated),
}

/// The child element a test case's verdict gives it, if any: failure,
/// error or skipped, with its type and message.
fn verdict_element(v: &Verdict) -> Option<(&'static str, &'static str, String)> {
    match v {
        Verdict::Passed | Verdict::Marginal => None,
        Verdict::Failed(f) => Some(("failure", "device", f.to_string())),
        Verdict::Error(e) => Some(("error", error_kind(e), e.to_string())),
        Verdict::NotRun(NotRun::Interrupted) => {
            Some(("skipped", "interrupted", NotRun::Interrupted.to_string()))
        }
        Verdict::NotRun(why) => Some(("error", "infrastructure", why.to_string())),
    }
}

/// The element of a scenario's repeated runs: a failure or error when runs
/// that did not pass were counted past the listing's cap.
fn repeated_element(r: &Repeated) -> Option<(&'static str, &'static str, String)> {
    let t = &r.tally;
    let past = format!(
        "past the first {} results after the first pass that did not pass, which are listed one by one",
        crate::soak::MAX_LISTED
    );
    let lost = t.not_run - r.interrupted;
    if t.failed > 0 {
        Some((
            "failure",
            "device",
            format!("{} runs failed {past}", t.failed),
        ))
    } else if t.errors > 0 {
        Some((
            "error",
            "harness",
            format!("{} runs were errors {past}", t.errors),
        ))
    } else if lost > 0 {
        Some((
            "error",
            "infrastructure",
            format!("{lost} runs were not run {past}"),
        ))
    } else {
        None
    }
}

/// [`junit`] of what `listing` lists: each listed result a test case (named
/// ` [pass K]` when the run repeats), and each scenario's repeated runs one
/// test case, ` [passes A-B]` (with ` on <board>` in a suite several
/// boards share), whose `system-out` gives their counts and each
/// measurement's range, `time` their wall time and `device_time` their
/// virtual time, summed.
pub fn junit_listing(info: &RunInfo, l: &Listing) -> Result<String, ReportError> {
    let results = l.results;
    let repeats = info.options.repeat > 1 && !l.passes.is_empty();
    let in_board = |b: Option<usize>| {
        (0..results.len())
            .filter(move |&i| l.board_of(i) == b)
            .map(Case::One)
    };
    let many_in = |b: Option<usize>| {
        l.repeated
            .iter()
            .filter(move |r| r.board == b)
            .map(Case::Many)
    };
    // The suites: their board (when they have one) and their cases.
    let groups: Vec<(Option<usize>, Vec<Case>)> = if info.spread == "each" {
        (0..info.boards.len())
            .map(|b| (Some(b), in_board(Some(b)).chain(many_in(Some(b))).collect()))
            .collect()
    } else {
        let board = (info.boards.len() == 1).then_some(0);
        let cases = (0..results.len())
            .map(Case::One)
            .chain(l.repeated.iter().map(Case::Many))
            .collect();
        vec![(board, cases)]
    };
    let element = |c: &Case| match c {
        Case::One(i) => verdict_element(&results[*i].verdict),
        Case::Many(r) => repeated_element(r),
    };
    let kind_count = |cases: &[Case], tag: &str| {
        cases
            .iter()
            .filter(|c| element(c).is_some_and(|(t, _, _)| t == tag))
            .count()
    };
    let all: usize = groups.iter().map(|(_, c)| c.len()).sum();
    let (failures, errors): (usize, usize) = groups.iter().fold((0, 0), |(f, e), (_, c)| {
        (f + kind_count(c, "failure"), e + kind_count(c, "error"))
    });
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<testsuites name=\"ppmc\" tests=\"{all}\" failures=\"{failures}\" errors=\"{errors}\" time=\"{:.6}\">",
        info.wall_s
    );
    for (board, cases) in groups {
        let shared = board.is_none() && info.boards.len() > 1;
        let one_names = unique_names(
            &cases
                .iter()
                .filter_map(|c| match c {
                    Case::One(i) => Some(&results[*i]),
                    Case::Many(_) => None,
                })
                .collect::<Vec<_>>(),
        );
        let mut ones = one_names.into_iter();
        let names: Vec<String> = cases
            .iter()
            .map(|c| match c {
                Case::One(i) => {
                    let n = ones.next().unwrap_or_default();
                    match l.passes.get(*i) {
                        Some(p) if repeats => format!("{} [pass {p}]", results[*i].name),
                        _ => n,
                    }
                }
                Case::Many(r) => {
                    let mut n = format!("{} [passes {}-{}]", r.name, r.first_pass, r.last_pass);
                    if shared {
                        n.push_str(&format!(" on {}", info.board_name(r.board)));
                    }
                    n
                }
            })
            .collect();
        let wall: f64 = cases
            .iter()
            .map(|c| match c {
                Case::One(i) => results[*i].wall.as_secs_f64(),
                Case::Many(r) => r.wall.as_secs_f64(),
            })
            .sum();
        let mut suite_name = "ppmc-conformance".to_string();
        if let Some(shard) = &info.options.shard {
            suite_name.push_str(&format!(" shard {shard}"));
        }
        if info.spread == "each" {
            suite_name.push_str(&format!(" on {}", info.board_name(board)));
        }
        let _ = writeln!(
            x,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" \
             time=\"{wall:.6}\" timestamp=\"{}\" hostname=\"{}\">",
            esc(&suite_name),
            cases.len(),
            kind_count(&cases, "failure"),
            kind_count(&cases, "error"),
            kind_count(&cases, "skipped"),
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
                props.extend(cases.iter().zip(&names).map(|(c, n)| {
                    let b = match c {
                        Case::One(i) => l.board_of(*i),
                        Case::Many(r) => r.board,
                    };
                    (format!("board_of.{n}"), info.board_name(b).to_string())
                }));
            }
        }
        props.extend(cases.iter().zip(&names).map(|(c, n)| {
            let elapsed = match c {
                Case::One(i) => results[*i].elapsed,
                Case::Many(r) => r.elapsed,
            };
            (
                format!("device_time.{n}"),
                format!("{:.9}", elapsed.as_nanos() as f64 / 1e9),
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
        for (c, name) in cases.iter().zip(&names) {
            match c {
                Case::One(i) => {
                    let shared = board.is_none().then(|| info.board_name(l.board_of(*i)));
                    testcase(&mut x, &results[*i], name, l.attachments.get(*i), shared);
                }
                Case::Many(r) => {
                    let shared = board.is_none().then(|| info.board_name(r.board));
                    repeated_case(&mut x, r, name, shared);
                }
            }
        }
        x.push_str("  </testsuite>\n");
    }
    x.push_str("</testsuites>\n");
    Ok(x)
}

/// One `<testcase>` for a scenario's repeated runs.
fn repeated_case(x: &mut String, r: &Repeated, name: &str, board: Option<&str>) {
    let t = &r.tally;
    let mut out = Vec::new();
    if let Some(b) = board {
        out.push(format!("board: {b}"));
    }
    out.push(format!(
        "repeated: {} runs of passes {}-{} not listed one by one: {} passed, {} marginal, {} failed, {} errors, {} not run ({} interrupted)",
        r.runs(),
        r.first_pass,
        r.last_pass,
        t.passed,
        t.marginal,
        t.failed,
        t.errors,
        t.not_run,
        r.interrupted
    ));
    out.extend(r.measurements.iter().map(|m| {
        format!(
            "{}: {} runs, min {}, mean {}, max {}, worst {}",
            m.name,
            m.count,
            m.min,
            m.mean(),
            m.max,
            m.worst.name()
        )
    }));
    let _ = writeln!(
        x,
        "    <testcase name=\"{}\" classname=\"section {}\" time=\"{:.6}\">",
        esc(name),
        esc(r.section),
        r.wall.as_secs_f64()
    );
    if let Some((tag, kind, message)) = repeated_element(r) {
        let _ = writeln!(
            x,
            "      <{tag} type=\"{kind}\" message=\"{}\">{}</{tag}>",
            esc(&message),
            esc_text(&message)
        );
    }
    let _ = writeln!(
        x,
        "      <system-out>{}</system-out>",
        esc_text(&out.join("\n"))
    );
    x.push_str("    </testcase>\n");
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
    if let Some((tag, kind, message)) = verdict_element(&r.verdict) {
        let _ = writeln!(
            body,
            "      <{tag} type=\"{kind}\" message=\"{}\">{}</{tag}>",
            esc(&message),
            esc_text(&message)
        );
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
        format: "ppmc-run-record/3",
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

/// How a report types a scenario's error: `infrastructure` when the link
/// to the target failed under it (the board is not to blame, and neither
/// is the harness), else `harness`.
fn error_kind(e: &HarnessError) -> &'static str {
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
