//! The HTML report (see [`html`]): one file, offline, from run records.

use super::plots;
use super::svg::esc;
use ppmc_record::{RunRecord, ScenarioRecord};
use std::fmt::Write as _;

/// The page's style: inline, like everything else in it.
const STYLE: &str = include_str!("report.css");

/// One self-contained HTML page of `records`: the runs' facts and boards,
/// every scenario with its verdict, each measurement against its band,
/// each move's speed profile over the golden one with the first
/// divergence marked, the pins around each failure, and the link's health.
/// Nothing in it reaches the network (its Content-Security-Policy forbids
/// it too): no script, no font, no style from elsewhere; it opens from
/// `file://` and as a CI artifact, as it is, years later.
pub fn html(records: &[RunRecord], title: &str) -> String {
    let mut s = String::with_capacity(64 << 10);
    head(&mut s, title);
    if records.len() > 1 {
        s.push_str(r#"<section class="runs"><h2>Runs</h2><table><tr><th>run</th><th>board</th><th>revision</th><th>started</th><th>verdicts</th></tr>"#);
        for (i, r) in records.iter().enumerate() {
            let board = r.run.boards.first();
            let _ = write!(
                s,
                r##"<tr><td><a href="#run-{i}">run {}</a></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>"##,
                i + 1,
                esc(board.map_or("", |b| b.name.as_str())),
                esc(board.and_then(|b| b.board_rev.as_deref()).unwrap_or("")),
                esc(&r.run.started),
                summary_chips(r)
            );
        }
        s.push_str("</table></section>\n");
    }
    for (i, r) in records.iter().enumerate() {
        run_section(&mut s, r, i);
    }
    let _ = write!(
        s,
        r#"<footer>Made by ppmc {} from {} run record{}. Long speed profiles are reduced for drawing to the least and greatest interval in each pixel column; such plots say so.</footer>
</body></html>
"#,
        esc(crate::VERSION),
        records.len(),
        if records.len() == 1 { "" } else { "s" }
    );
    s
}

/// A page's head and title, as every page of ppmc's has it: the style
/// inline, and a Content-Security-Policy that lets nothing load.
pub(super) fn head(s: &mut String, title: &str) {
    let _ = write!(
        s,
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; style-src 'unsafe-inline'; img-src data:">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{0}</title><style>{STYLE}</style></head><body>
<h1>{0}</h1>
"#,
        esc(title)
    );
}

/// The verdict counts as coloured chips.
fn summary_chips(r: &RunRecord) -> String {
    let t = &r.summary;
    let mut s = String::new();
    for (class, n, word) in [
        ("passed", t.passed, "passed"),
        ("marginal", t.marginal, "marginal"),
        ("flaky", t.flaky, "flaky"),
        ("failed", t.failed, "failed"),
        ("error", t.errors, "errors"),
        ("not_run", t.not_run, "not run"),
    ] {
        if n > 0 || class == "passed" || class == "failed" {
            let _ = write!(s, r#"<span class="chip {class}">{n} {word}</span> "#);
        }
    }
    s
}

/// Whether a scenario is one to look at first: it did not pass cleanly.
fn noteworthy(sc: &ScenarioRecord) -> bool {
    !sc.passed_cleanly()
}

fn run_section(s: &mut String, r: &RunRecord, i: usize) {
    let _ = write!(
        s,
        r#"<section class="run" id="run-{i}"><h2>Run {} <span class="summary">{}</span></h2>"#,
        i + 1,
        summary_chips(r)
    );
    // What did not pass first, then the boards, then the run's facts and
    // everything else.
    let first = not_passed(s, r, i);
    boards(s, r);
    let golden = r.run.options.golden.as_deref().unwrap_or("none");
    let _ = write!(
        s,
        r#"<table class="facts"><tr><th>ppmc</th><td>{}</td><th>commit</th><td>{}</td></tr><tr><th>started</th><td>{}</td><th>wall time</th><td>{:.1} s</td></tr><tr><th>host</th><td>{}</td><th>golden traces</th><td>{}</td></tr><tr><th>tolerances</th><td>intervals {}%, floor {} ns</td><th>marginal zone</th><td>{}% of each limit</td></tr></table>"#,
        esc(&r.run.harness_version),
        esc(&r.run.git_revision),
        esc(&r.run.started),
        r.run.wall_s,
        esc(&r.run.host),
        esc(golden),
        r.run.options.interval_tol_pct,
        r.run.options.time_floor_ns,
        r.run.options.marginal_pct,
    );
    // The scenarios: a table of all (folded away when something did not
    // pass: that is above), then each in full, those that did not pass
    // first and open.
    let _ = write!(
        s,
        r#"<details class="all-scenarios"{}><summary>All {} scenarios</summary><table class="scenarios"><tr><th>scenario</th><th>section</th><th>board</th><th>verdict</th><th>attempts</th><th>device time</th></tr>"#,
        if first { "" } else { " open" },
        r.scenarios.len()
    );
    for (k, sc) in r.scenarios.iter().enumerate() {
        let _ = write!(
            s,
            r##"<tr class="{}"><td><a href="#r{i}-s{k}">{}</a></td><td>{}</td><td>{}</td><td><span class="chip {}">{}</span></td><td>{}</td><td>{}</td></tr>"##,
            esc(sc.verdict.name()),
            esc(&display_name(sc)),
            esc(&sc.section),
            esc(sc.board.as_deref().unwrap_or("")),
            esc(sc.verdict.name()),
            esc(&sc.verdict.name().replace('_', " ")),
            sc.attempts.len() + 1,
            esc(&ppmc_record::human_ns(sc.elapsed_ns)),
        );
    }
    s.push_str("</table></details>");
    let tol = (r.run.options.interval_tol_pct, r.run.options.time_floor_ns);
    let order = r
        .scenarios
        .iter()
        .enumerate()
        .filter(|(_, sc)| noteworthy(sc))
        .chain(
            r.scenarios
                .iter()
                .enumerate()
                .filter(|(_, sc)| !noteworthy(sc)),
        );
    let mut budget = MAX_PAGE_MOVES;
    for (k, sc) in order {
        scenario(s, sc, &format!("r{i}-s{k}"), tol, &mut budget);
    }
    s.push_str("</section>\n");
}

/// Rows a page's "did not pass" table holds at most; the rest are below.
const MAX_FIRST: usize = 50;

/// The table a page opens with: every scenario that did not pass, the
/// board's failures first, each with its board, the check, what was
/// expected against what was measured, and by how much. Whether there was
/// any.
fn not_passed(s: &mut String, r: &RunRecord, i: usize) -> bool {
    let rows = r.not_passed();
    if rows.is_empty() {
        return false;
    }
    let _ = write!(
        s,
        r#"<section class="not-passed"><h3>Did not pass: {}</h3><table class="first"><tr><th>scenario</th><th>board</th><th>verdict</th><th>check</th><th>expected</th><th>measured</th><th>by how much</th><th>at</th></tr>"#,
        rows.len()
    );
    for (k, sc) in rows.iter().take(MAX_FIRST) {
        let f = sc.shortfall();
        let _ = write!(
            s,
            r##"<tr class="{0}" data-scenario="{1}"><td><a href="#r{i}-s{k}">{2}</a></td><td>{3}</td><td><span class="chip {0}">{4}</span></td><td>{5}</td><td>{6}</td><td class="got">{7}</td><td class="by">{8}</td><td>{9}</td></tr>"##,
            esc(sc.verdict.name()),
            esc(&sc.name),
            esc(&display_name(sc)),
            esc(sc.board.as_deref().unwrap_or("")),
            esc(&sc.verdict.name().replace('_', " ")),
            esc(&f.check),
            esc(&f.expected),
            esc(&f.got),
            esc(f.by.as_deref().unwrap_or("")),
            esc(&f.at_ns.map(plots::us).unwrap_or_default()),
        );
    }
    s.push_str("</table>");
    if rows.len() > MAX_FIRST {
        let _ = write!(
            s,
            r#"<p class="detail">{} more below, each in full.</p>"#,
            rows.len() - MAX_FIRST
        );
    }
    s.push_str("</section>");
    true
}

fn display_name(sc: &ScenarioRecord) -> String {
    match sc.pass {
        Some(p) => format!("{} [pass {p}]", sc.name),
        None => sc.name.clone(),
    }
}

/// The boards: identity, straps and, through a bridge, the link's health.
fn boards(s: &mut String, r: &RunRecord) {
    s.push_str(r#"<h3>Boards</h3><table class="boards"><tr><th>board</th><th>target</th><th>revision</th><th>serial</th><th>bridge firmware</th><th>bridge serial</th><th>details</th><th>link</th></tr>"#);
    for b in &r.run.boards {
        let details: Vec<String> = b
            .target_details
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        let link = b.link.as_ref().map_or("(no bridge)".to_string(), |l| {
            l.iter()
                .map(|(k, v)| format!("{} {v}", k.replace('_', " ")))
                .collect::<Vec<_>>()
                .join(", ")
        });
        let _ = write!(
            s,
            r#"<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class="small">{}</td><td class="link">{}</td></tr>"#,
            esc(&b.name),
            esc(&b.target),
            esc(b.board_rev.as_deref().unwrap_or("")),
            esc(b.board_serial.as_deref().unwrap_or("")),
            esc(b.bridge_firmware.as_deref().unwrap_or("")),
            esc(b.bridge_serial.as_deref().unwrap_or("")),
            esc(&details.join(", ")),
            esc(&link),
        );
        if let Some(e) = &b.error {
            let _ = write!(
                s,
                r#"<tr><td colspan="8" class="error">not reached: {}</td></tr>"#,
                esc(e)
            );
        }
    }
    s.push_str("</table>");
}

/// Moves drawn at most for a scenario, and on a page: a record is read
/// from a file, and the page stays a page whatever it holds (the suite's
/// scenarios have a few moves each, 122 in all).
const MAX_MOVES: usize = 64;
const MAX_PAGE_MOVES: usize = 2_000;

fn scenario(s: &mut String, sc: &ScenarioRecord, id: &str, tol: (f64, u64), budget: &mut usize) {
    let _ = write!(
        s,
        r#"<details class="scenario {}" id="{id}" data-scenario="{}"{}><summary><span class="chip {}">{}</span> {} <span class="section">section {}</span></summary>"#,
        esc(sc.verdict.name()),
        esc(&sc.name),
        if noteworthy(sc) {
            " open data-open"
        } else {
            ""
        },
        esc(sc.verdict.name()),
        esc(&sc.verdict.name().replace('_', " ")),
        esc(&display_name(sc)),
        esc(&sc.section),
    );
    if let Some(f) = &sc.failure {
        let _ = write!(
            s,
            r#"<p class="failure"><b>{}</b> at {}: expected {}, got {}{}</p>"#,
            esc(&f.expectation),
            esc(&plots::us(f.at_ns)),
            esc(&f.expected),
            esc(&f.got),
            f.deviation
                .as_ref()
                .map(|d| format!(": {}", esc(&d.describe())))
                .unwrap_or_default()
        );
    } else if let Some(e) = &sc.error {
        let _ = write!(
            s,
            r#"<p class="error">{} error: {}</p>"#,
            esc(e.kind.name()),
            esc(&e.message)
        );
    } else if let Some(d) = &sc.detail {
        let _ = write!(s, r#"<p class="detail">{}</p>"#, esc(d));
    }
    if !sc.attempts.is_empty() {
        s.push_str(r#"<table class="attempts"><tr><th>attempt</th><th>verdict</th><th>what happened</th></tr>"#);
        // The earlier attempts, then the last, which the scenario's own
        // fields are.
        let last = match sc.verdict.name() {
            "flaky" => "passed",
            v => v,
        };
        let rows = sc
            .attempts
            .iter()
            .map(|a| (a.verdict.name(), a.detail.as_deref()))
            .chain(std::iter::once((last, sc.detail.as_deref())));
        for (n, (verdict, detail)) in rows.enumerate() {
            let _ = write!(
                s,
                r#"<tr><td>{}</td><td><span class="chip {}">{}</span></td><td>{}</td></tr>"#,
                n + 1,
                esc(verdict),
                esc(&verdict.replace('_', " ")),
                esc(detail.unwrap_or(""))
            );
        }
        s.push_str("</table>");
    }
    if !sc.measurements.is_empty() {
        s.push_str(r#"<table class="measurements"><tr><th>measurement</th><th>value</th><th>grade</th><th>against its band</th></tr>"#);
        for m in &sc.measurements {
            let _ = write!(
                s,
                r#"<tr><td>{}</td><td>{}</td><td><span class="chip {}">{}</span></td><td>{}</td></tr>"#,
                esc(&m.name),
                esc(&match m.u.as_nanos() {
                    0 => plots::us(m.value.as_nanos()),
                    u => format!(
                        "{} ±{}",
                        plots::us(m.value.as_nanos()),
                        ppmc_record::human_ns(u)
                    ),
                }),
                esc(m.grade.name()),
                esc(m.grade.name()),
                plots::measurement(m)
            );
        }
        s.push_str("</table>");
    }
    if let Some(fig) = &sc.figures {
        let label = match &sc.failure {
            Some(f) if f.expectation.starts_with("golden trace") => "first divergence",
            _ => "failed here",
        };
        let mark = sc.failure.as_ref().map(|f| f.at_ns);
        // The move the failure is in: the last that started before it.
        let marked = mark.and_then(|at| fig.moves.iter().rposition(|m| m.at_ns <= at));
        let shown = fig.moves.len().min(MAX_MOVES).min(*budget);
        *budget -= shown;
        // The marked move is drawn whatever the cap.
        let drawn = |n: usize| n < shown || Some(n) == marked;
        let left_out = (0..fig.moves.len()).filter(|n| !drawn(*n)).count();
        // The scenario's pulses before each move: pulses are numbered over
        // the scenario, in the plots as in the failure texts.
        let before: Vec<u64> = fig
            .moves
            .iter()
            .scan(0u64, |sum, m| {
                let b = *sum;
                *sum = sum.saturating_add(m.pulses());
                Some(b)
            })
            .collect();
        for (n, m) in fig.moves.iter().enumerate().filter(|(n, _)| drawn(*n)) {
            let _ = write!(
                s,
                r#"<div class="move" data-move="{}" data-pulses="{}"><h4>move {}: {} {}, {} steps, {} pulses{}</h4>"#,
                n + 1,
                m.pulses(),
                n + 1,
                esc(&m.kind),
                esc(&m.dir),
                m.steps,
                m.pulses(),
                if m.golden.is_some() {
                    r#" <span class="legend"><span class="key board">the board</span><span class="key golden">the golden trace</span><span class="key band">its tolerance band</span></span>"#
                } else {
                    ""
                }
            );
            if m.pulses() > 1 || m.golden.is_some() {
                let mark = mark.filter(|_| marked == Some(n)).map(|at| (at, label));
                let (svg, reduced) = plots::profiles(m, before[n], mark, tol);
                s.push_str(&svg);
                if reduced {
                    s.push_str(r#"<p class="detail reduced">Reduced for drawing: the least and the greatest interval in each pixel column.</p>"#);
                }
            }
            s.push_str("</div>");
        }
        if left_out > 0 {
            let _ = write!(
                s,
                r#"<p class="detail">{left_out} more moves, not drawn (the run record holds them; a page draws at most {MAX_MOVES} a scenario and {MAX_PAGE_MOVES} in all)</p>"#
            );
        }
        if let Some(w) = &fig.waveform {
            let _ = write!(
                s,
                r#"<h4>the pins around the failure ({} to {})</h4>{}"#,
                esc(&plots::us(w.from_ns)),
                esc(&plots::us(w.to_ns)),
                plots::waveform(w)
            );
        }
    }
    s.push_str("</details>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record as a file gives it: one scenario with `moves` moves, a
    /// failure, and a waveform whose window is `window`.
    fn record(moves: usize, window: (u64, u64)) -> RunRecord {
        let m = r#"{"at_ns":1000,"kind":"constant","dir":"cw","steps":3,"runs":[[10,3,200]]}"#;
        let text = format!(
            r#"{{"format":"ppmc-run-record/4","run":{{"harness_version":"0","git_revision":"x",
            "boards":[{{"name":"b","target":"emu","board_rev":null,"bridge_firmware":null,"error":null}}],
            "started":"s","wall_s":0,"host":"h","options":{{"golden":null,"marginal_pct":0.25,
            "interval_tol_pct":1,"time_floor_ns":100}}}},"summary":{{"passed":0,"marginal":0,
            "failed":1,"error":0,"not_run":0}},"scenarios":[{{"name":"s","board":"b","section":"3-1",
            "verdict":"failed","detail":null,"failure":{{"expectation":"e","expected":"x","got":"y",
            "at_ns":1100}},"error":null,"elapsed_ns":5,"measurements":[],"figures":{{"moves":[{}],
            "waveform":{{"from_ns":{},"to_ns":{},"mark_ns":1100,"pout":[1010],"pins":[{{"name":"busy",
            "bits":255,"initial":1,"changes":[[1200,0]]}}],"bus":[]}}}}}}]}}"#,
            vec![m; moves].join(","),
            window.0,
            window.1
        );
        let mut r = RunRecord::parse(&text, "t").expect("a record");
        // A label no record may hold (parse refuses it), drawn all the
        // same by a page made of a record built otherwise.
        r.run.boards[0].name = "b\u{0}<i>".into();
        r
    }

    #[test]
    fn a_record_with_too_much_to_draw_is_drawn_within_bounds() {
        let page = html(&[record(100, (900, 1300))], "t");
        // The cap's moves, and the one the failure is in (the last).
        assert_eq!(page.matches("<div class=\"move\"").count(), MAX_MOVES + 1);
        assert!(page.contains("data-move=\"100\""));
        assert!(page.contains("35 more moves, not drawn"), "{page}");
        assert!(page.contains("<svg class=\"waveform\""));
        // Text is escaped, and a control character is no HTML text.
        assert!(page.contains("b\u{FFFD}&lt;i&gt;") && !page.contains('\0'));
    }

    #[test]
    fn a_waveform_with_an_empty_window_is_said_not_drawn() {
        for window in [(1300, 900), (1000, 1000)] {
            let page = html(&[record(1, window)], "t");
            assert!(!page.contains("<svg class=\"waveform\""));
            assert!(page.contains("empty window: not drawn"));
        }
    }
}
