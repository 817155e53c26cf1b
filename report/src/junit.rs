//! JUnit XML for CI systems (see [`junit`]).

use ppmc_core::time::Duration;
use ppmc_record::{
    AttemptRecord, Blame, BoardInfo, ErrorKind, ErrorRecord, Grade, RepeatedRecord, RunRecord,
    ScenarioRecord, Status, MAX_LISTED,
};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// JUnit XML for CI systems, valid under the Jenkins xunit schema
/// (`junit-10.xsd`) and read by GitLab and junitparser: one test case per
/// scenario run (classname = datasheet section; names made unique under
/// `--repeat` with ` [pass K]`), `time` in wall seconds with the device's
/// virtual time as a suite property per case; a failure or error carries
/// its explanation in `message` and as its text; infrastructure problems
/// (target unreachable or lost) are errors, an interrupted run's leftovers
/// are skipped, and the suite counts one error more for the interruption,
/// which its `system-err` explains; the files saved for each result (its `attachments`) are
/// `[[ATTACHMENT|path]]` lines in `system-out`.
///
/// A run on one board is one test suite with the board's facts as
/// properties (`target`, `board_rev`, `target.*`). A run shared by several
/// boards is one test suite too: each board's facts are
/// `board.<name>.*` properties, and each test case names its board in a
/// `board_of.<case>` property and a `board:` line of its `system-out`. A
/// run with `--each` is one test suite per board, named after it.
///
/// Each scenario's repeated runs counted rather than listed (`--repeat`)
/// are one test case, ` [passes A-B]` (with ` on <board>` in a suite
/// several boards share), whose `system-out` gives their counts and each
/// measurement's range, `time` their wall time and `device_time` their
/// virtual time, summed.
pub fn junit(record: &RunRecord) -> String {
    let info = &record.run;
    let results = &record.scenarios;
    let repeated: &[RepeatedRecord] = record.repeated.as_deref().unwrap_or(&[]);
    let board_of = |name: &Option<String>| info.board_index(name.as_deref());
    let in_board = |b: Option<usize>| {
        (0..results.len())
            .filter(move |&i| board_of(&results[i].board) == b)
            .map(Case::One)
    };
    let many_in = |b: Option<usize>| {
        repeated
            .iter()
            .filter(move |r| board_of(&r.board) == b)
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
            .chain(repeated.iter().map(Case::Many))
            .collect();
        vec![(board, cases)]
    };
    let element = |c: &Case| match c {
        Case::One(i) => verdict_element(&results[*i]),
        Case::Many(r) => repeated_element(r),
    };
    let kind_count = |cases: &[Case], tag: &str| {
        cases
            .iter()
            .filter(|c| element(c).is_some_and(|(t, _, _)| t == tag))
            .count()
    };
    // The runs an interrupted run never reached: each case skipped, and
    // its suite an error of its own, so that a CI page that reads only the
    // counts sees the run did not finish.
    let interrupted = |cases: &[Case]| -> usize {
        cases
            .iter()
            .map(|c| match c {
                Case::One(i) => usize::from(
                    results[*i].error.as_ref().map(|e| e.kind) == Some(ErrorKind::Interrupted),
                ),
                Case::Many(r) => r.interrupted,
            })
            .sum()
    };
    let suite_errors =
        |cases: &[Case]| kind_count(cases, "error") + usize::from(interrupted(cases) > 0);
    let all: usize = groups.iter().map(|(_, c)| c.len()).sum();
    let (failures, errors): (usize, usize) = groups.iter().fold((0, 0), |(f, e), (_, c)| {
        (f + kind_count(c, "failure"), e + suite_errors(c))
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
                    match results[*i].pass {
                        Some(p) => format!("{} [pass {p}]", results[*i].name),
                        None => n,
                    }
                }
                Case::Many(r) => {
                    let mut n = format!("{} [passes {}-{}]", r.name, r.first_pass, r.last_pass);
                    if shared {
                        n.push_str(&format!(" on {}", board_label(&r.board)));
                    }
                    n
                }
            })
            .collect();
        let wall: f64 = cases
            .iter()
            .map(|c| match c {
                Case::One(i) => results[*i].wall_s,
                Case::Many(r) => r.wall_s,
            })
            .sum();
        let mut suite_name = match info.source {
            Some(_) => "ppmc-judge",
            None => "ppmc-conformance",
        }
        .to_string();
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
            suite_errors(&cases),
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
                        Case::One(i) => &results[*i].board,
                        Case::Many(r) => &r.board,
                    };
                    (format!("board_of.{n}"), board_label(b).to_string())
                }));
            }
        }
        if let Some(c) = &info.source {
            props.extend([
                ("capture.path".into(), c.path.clone()),
                ("capture.format".into(), c.format.clone()),
                ("capture.channels".into(), c.channels.join(",")),
                (
                    "capture.sample_rate_hz".into(),
                    c.sample_rate_hz.map(|r| r.to_string()).unwrap_or_default(),
                ),
                ("capture.resolution_ps".into(), c.resolution_ps.to_string()),
            ]);
        }
        props.extend(cases.iter().zip(&names).map(|(c, n)| {
            let elapsed = match c {
                Case::One(i) => results[*i].elapsed_ns,
                Case::Many(r) => r.elapsed_ns,
            };
            (
                format!("device_time.{n}"),
                format!("{:.9}", elapsed as f64 / 1e9),
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
                    let r = &results[*i];
                    let shared = board.is_none().then(|| board_label(&r.board));
                    testcase(&mut x, r, name, shared);
                }
                Case::Many(r) => {
                    let shared = board.is_none().then(|| board_label(&r.board));
                    repeated_case(&mut x, r, name, shared);
                }
            }
        }
        let never = interrupted(&cases);
        if never > 0 {
            let _ = writeln!(
                x,
                "    <system-err>{}</system-err>",
                esc(&format!(
                    "the run was interrupted before its end (SIGINT or SIGTERM, or its standard output closed): {never} of its scenario runs here were never run, each a skipped test case; this suite counts one error for it, and ppmc exited 130"
                ))
            );
        }
        x.push_str("  </testsuite>\n");
    }
    x.push_str("</testsuites>\n");
    x
}

/// A test case: a result, or a scenario's repeated runs.
enum Case<'a> {
    One(usize),
    Many(&'a RepeatedRecord),
}

/// A result's board as a test case names it: `(none)` when no board took
/// it.
fn board_label(b: &Option<String>) -> &str {
    b.as_deref().unwrap_or("(none)")
}

/// The child element a verdict gives its test case, if any: failure,
/// error or skipped, with its type and message. The device's failure is
/// of type `device`; an error is of its kind (`harness`,
/// `infrastructure`, `capture`); a scenario an interrupted run never
/// reached is skipped, one a lost target never reached an
/// `infrastructure` error.
fn own_element(
    status: Status,
    error: Option<&ErrorRecord>,
    detail: Option<&String>,
) -> Option<(&'static str, &'static str, String)> {
    let message = detail.cloned().unwrap_or_default();
    match status {
        Status::Passed | Status::Marginal | Status::Flaky => None,
        Status::Failed => Some(("failure", "device", message)),
        Status::Error => Some(("error", error.map_or("harness", |e| e.kind.name()), message)),
        Status::NotRun => match error.map(|e| e.kind) {
            Some(ErrorKind::Interrupted) => Some(("skipped", "interrupted", message)),
            _ => Some(("error", "infrastructure", message)),
        },
    }
}

/// [`own_element`] of a result; one judged from a capture is typed by
/// whom it blames: `device` (the board), `host` (the host firmware) or
/// `capture`, with the judge's line as its message.
fn verdict_element(r: &ScenarioRecord) -> Option<(&'static str, &'static str, String)> {
    let (tag, kind, message) = own_element(r.verdict, r.error.as_ref(), r.detail.as_ref())?;
    let kind = match r.blame.flatten() {
        Some(Blame::Board) => "device",
        Some(Blame::Host) => "host",
        Some(Blame::Capture) => "capture",
        None => kind,
    };
    Some((tag, kind, message))
}

/// The element of a scenario's repeated runs: a failure or error when runs
/// that did not pass were counted past the listing's cap.
fn repeated_element(r: &RepeatedRecord) -> Option<(&'static str, &'static str, String)> {
    let t = &r.summary;
    let past = format!(
        "past the first {MAX_LISTED} results after the first pass that did not pass, which are listed one by one"
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

/// One `<testcase>` for a scenario's repeated runs.
fn repeated_case(x: &mut String, r: &RepeatedRecord, name: &str, board: Option<&str>) {
    let t = &r.summary;
    let mut out = Vec::new();
    if let Some(b) = board {
        out.push(format!("board: {b}"));
    }
    out.push(format!(
        "repeated: {} runs of passes {}-{} not listed one by one: {} passed, {} marginal, {} flaky, {} failed, {} errors, {} not run ({} interrupted)",
        r.runs,
        r.first_pass,
        r.last_pass,
        t.passed,
        t.marginal,
        t.flaky,
        t.failed,
        t.errors,
        t.not_run,
        r.interrupted
    ));
    let ns = Duration::from_nanos;
    out.extend(r.measurements.iter().map(|m| {
        format!(
            "{}: {} runs, min {}, mean {}, max {}, worst {}",
            m.name,
            m.count,
            ns(m.min_ns),
            ns(m.mean_ns),
            ns(m.max_ns),
            m.worst_grade.name()
        )
    }));
    let _ = writeln!(
        x,
        "    <testcase name=\"{}\" classname=\"section {}\" time=\"{:.6}\">",
        esc(name),
        esc(&r.section),
        r.wall_s
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
    for (key, value) in [
        ("board_serial", &b.board_serial),
        ("bridge_serial", &b.bridge_serial),
    ] {
        if let Some(v) = value {
            props.push((format!("{prefix}{key}"), v.clone()));
        }
    }
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

/// The attempts before a scenario's last, in Maven Surefire's dialect
/// (as nextest and Jenkins read it): in a test that passed in the end,
/// each is a `flakyFailure` (the device) or `flakyError` (the link, the
/// harness); in one that never passed, a `rerunFailure` or `rerunError`
/// beside the last attempt's `failure` or `error`. Each carries its type
/// (which `junit-10.xsd` requires), its message, and its text in
/// `stackTrace`.
fn attempts(body: &mut String, r: &ScenarioRecord) {
    let prefix = if r.verdict.ok() { "flaky" } else { "rerun" };
    let own = |a: &AttemptRecord| own_element(a.verdict, a.error.as_ref(), a.detail.as_ref());
    // Surefire's own schema takes the failures before the errors.
    let mut earlier: Vec<(usize, &str, &str, String)> = r
        .attempts
        .iter()
        .enumerate()
        .filter_map(|(n, a)| {
            let (tag, kind, message) = own(a)?;
            let tag = match tag {
                "failure" => "Failure",
                _ => "Error",
            };
            Some((n, tag, kind, message))
        })
        .collect();
    earlier.sort_by_key(|(n, tag, ..)| (*tag != "Failure", *n));
    for (n, tag, kind, message) in earlier {
        let a = &r.attempts[n];
        let _ = writeln!(
            body,
            "      <{prefix}{tag} type=\"{kind}\" message=\"{}\"><stackTrace>{}</stackTrace><system-out>{}</system-out></{prefix}{tag}>",
            esc(&message),
            esc_text(&message),
            esc_text(&format!(
                "attempt {} of {}, {:.6} s",
                n + 1,
                r.attempts.len() + 1,
                a.wall_s
            ))
        );
    }
}

/// One `<testcase>`. A result judged from a capture has the judge's notes
/// (what was not judged, what was compared, each finding) after its
/// failure's or error's message, or in `system-out` when it passed;
/// `board` names its board in a suite several boards share.
fn testcase(x: &mut String, r: &ScenarioRecord, name: &str, board: Option<&str>) {
    let notes = &r.notes;
    let _ = write!(
        x,
        "    <testcase name=\"{}\" classname=\"section {}\" time=\"{:.6}\"",
        esc(name),
        esc(&r.section),
        r.wall_s
    );
    let mut body = String::new();
    let element = verdict_element(r);
    if let Some((tag, kind, message)) = &element {
        let text = std::iter::once(message.as_str())
            .chain(notes.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join("\n");
        let _ = writeln!(
            body,
            "      <{tag} type=\"{kind}\" message=\"{}\">{}</{tag}>",
            esc(message),
            esc_text(&text)
        );
    }
    attempts(&mut body, r);
    let mut out: Vec<String> = Vec::new();
    if element.is_none() {
        out.extend(notes.iter().cloned());
    }
    if let Some(b) = board {
        out.push(format!("board: {b}"));
    }
    if r.verdict.ok() {
        let near: Vec<String> = r
            .measurements
            .iter()
            .filter(|m| m.grade == Grade::Marginal)
            .map(|m| m.to_string())
            .collect();
        // A judged capture's marginal comparisons are in its notes.
        if !near.is_empty() {
            out.push(format!("MARGINAL: {}", near.join("; ")));
        }
    }
    out.extend(r.attachments.iter().map(|p| format!("[[ATTACHMENT|{p}]]")));
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
fn unique_names(results: &[&ScenarioRecord]) -> Vec<String> {
    let mut runs: BTreeMap<&str, usize> = BTreeMap::new();
    for r in results {
        *runs.entry(&r.name).or_default() += 1;
    }
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    results
        .iter()
        .map(|r| {
            let k = seen.entry(&r.name).or_default();
            *k += 1;
            if runs[r.name.as_str()] > 1 {
                format!("{} [pass {k}]", r.name)
            } else {
                r.name.clone()
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
