//! The lines `ppmc run` and `ppmc compare` print: a verdict per result,
//! the run's summary, a line per board.

use ppmc::scenario::{Grade, ScenarioResult, Verdict};
use ppmc_record::{RunInfo, RunRecord, Tally};

pub(crate) fn verdict_line(r: &ScenarioResult, board: Option<&str>) -> String {
    let tag = match r.verdict {
        _ if r.flaky() => "FLAKY",
        Verdict::Passed => "PASS",
        Verdict::Marginal => "MARGINAL",
        Verdict::Failed(_) => "FAIL",
        Verdict::Error(_) => "ERROR",
        Verdict::NotRun(_) => "NOT RUN",
    };
    let mut s = format!(
        "{} {} (section {})",
        crate::out::verdict_word(tag, 8),
        r.name,
        r.section
    );
    if let Some(b) = board {
        s.push_str(" on ");
        s.push_str(b);
    }
    if let Some(d) = r.verdict.detail() {
        s.push_str("\n         ");
        s.push_str(&d);
    }
    // Which measurement, against what, and how sure it is.
    if r.verdict == Verdict::Marginal {
        for m in r.measurements.iter().filter(|m| m.grade == Grade::Marginal) {
            s.push_str(&format!("\n         {m}"));
        }
    }
    for (n, a) in r.attempts.iter().enumerate() {
        s.push_str(&format!("\n         attempt {}: ", n + 1));
        s.push_str(&a.verdict.detail().unwrap_or_else(|| "passed".into()));
    }
    s
}

/// Rows the recap lists at most; the reports hold the rest.
const MAX_RECAP: usize = 20;

/// Above the counts, what did not pass again, the board's failures first
/// ([`RunRecord::not_passed`]), each with its board, the check and by how
/// much: the end of a long log is what a reader sees first.
pub(crate) fn not_passed_lines(record: &RunRecord) {
    let rows = record.not_passed();
    if rows.is_empty() {
        return;
    }
    outln!("did not pass ({}), the board's failures first:", rows.len());
    for (_, sc) in rows.iter().take(MAX_RECAP) {
        let board = sc
            .board
            .as_deref()
            .map_or(String::new(), |b| format!(" on {b}"));
        let f = sc.shortfall();
        let what = match (f.expected.is_empty(), f.by) {
            (true, _) => format!("{}: {}", f.check, f.got),
            (false, None) => format!("{}: expected {}, got {}", f.check, f.expected, f.got),
            (false, Some(by)) => {
                format!("{}: expected {}, got {} [{by}]", f.check, f.expected, f.got)
            }
        };
        let word = match sc.verdict.name() {
            "failed" => "FAIL",
            "error" => "ERROR",
            "flaky" => "FLAKY",
            _ => "NOT RUN",
        };
        outln!(
            "  {} {}{board}: {}",
            crate::out::verdict_word(word, 7),
            sc.name,
            ppmc_record::printable(&what)
        );
    }
    if rows.len() > MAX_RECAP {
        outln!(
            "  and {} more (the reports list them)",
            rows.len() - MAX_RECAP
        );
    }
}

/// The run's counts: every verdict, then the closing line CI log readers
/// look for.
pub(crate) fn summary_lines(t: &Tally, results: usize) {
    // Flaky only when there are any: a clean run's lines stay as CI log
    // readers know them.
    let flaky = match t.flaky {
        0 => String::new(),
        n => format!(" {n} flaky (passed only on a retry),"),
    };
    outln!(
        "{results} scenarios: {} passed,{flaky} {} marginal, {} failed, {} errors, {} not run",
        t.passed,
        t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
    // The closing line CI log readers look for; the same counts.
    let flaky = match t.flaky {
        0 => String::new(),
        n => format!(" {n} flaky,"),
    };
    outln!(
        "suite: {} passed,{flaky} {} failed, {} errors, {} not run",
        t.passed + t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
}

/// How many runs a tally counts.
fn runs_of(t: &Tally) -> usize {
    t.runs()
}

/// One line per board: how many scenarios it ran and how they went
/// (`tallies` in the order of the boards).
pub(crate) fn board_lines(info: &RunInfo, tallies: &[Tally]) {
    for (board, t) in info.boards.iter().zip(tallies) {
        let state = match &board.error {
            Some(_) => " (not reached)",
            None => "",
        };
        let flaky = match t.flaky {
            0 => String::new(),
            n => format!(" {n} flaky,"),
        };
        outln!(
            "board {}{state}: {} scenarios, {} passed,{flaky} {} failed, {} errors, {} not run",
            board.name,
            runs_of(t),
            t.passed + t.marginal,
            t.failed,
            t.errors,
            t.not_run
        );
    }
}
