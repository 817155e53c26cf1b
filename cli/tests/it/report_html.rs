//! The HTML report as its reader sees it (issue 31): every scenario
//! present, every plot with the points it should have, the first
//! divergence marked on a faulty board, nothing that reaches the network;
//! flaky boards on record in JUnit (Maven Surefire's dialect), the JSON
//! record and the page. CI opens the same pages in headless Chromium
//! (`contrib/browser-check`).

use crate::common;

use common::{check_record, ppmc, run_record_schema, scratch, text, BridgeSim};
use std::path::Path;

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).expect("written")
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&read(p)).expect("JSON")
}

/// Where the `<details>` element of `scenario` starts in `html` (the
/// table of what did not pass names it too).
fn details_at(html: &str, scenario: &str) -> usize {
    html.match_indices(&format!("data-scenario=\"{scenario}\""))
        .map(|(i, _)| html[..i].rfind('<').expect("in a tag"))
        .find(|&tag| html[tag..].starts_with("<details"))
        .unwrap_or_else(|| panic!("{scenario} not in the page"))
}

/// The `<details>` section of `scenario` in `html`.
fn section<'a>(html: &'a str, scenario: &str) -> &'a str {
    let at = details_at(html, scenario);
    let end = html[at..].find("</details>").expect("closed") + at;
    &html[at..end]
}

/// Every value of `attr="..."` in `html`, in order.
fn attrs<'a>(html: &'a str, attr: &str) -> Vec<&'a str> {
    let key = format!("{attr}=\"");
    html.match_indices(&key)
        .map(|(i, _)| {
            let v = &html[i + key.len()..];
            &v[..v.find('"').expect("quoted")]
        })
        .collect()
}

/// Nothing in the page can reach anything outside it: no script, no
/// link, no external resource of any kind, and a policy that forbids
/// them anyway.
fn assert_offline(html: &str) {
    assert!(html.contains("Content-Security-Policy\" content=\"default-src 'none'"));
    for banned in [
        "<script", "<link", "<img", "<iframe", "src=", "url(", "@import", "http://", "https://",
    ] {
        assert!(!html.contains(banned), "the page holds {banned}");
    }
    assert_eq!(html.matches("<svg").count(), html.matches("</svg>").count());
    assert_eq!(
        html.matches("<details").count(),
        html.matches("</details>").count()
    );
}

/// Section 3-6 (Table 3-3, Decelerating Stop processing) on a board whose
/// Decelerating Stop acts 6 % late: the report marks where the scenario
/// failed on the move's speed profile, over the golden profile, and shows
/// the pins around it; every scenario of the suite is in the page, and
/// every move's profile holds one point per pulse interval (or, past the
/// plot's width, each pixel column's least and greatest, and says so).
#[test]
fn a_faulty_board_has_its_failure_marked_on_the_speed_profile() {
    let dir = scratch("report");
    let (html_path, json_path) = (dir.path().join("r.html"), dir.path().join("r.json"));
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/../golden");
    let out = ppmc(&[
        "run",
        "--golden",
        golden,
        "--target",
        "emu,chip-fault=decel-stop-slow,rev=B,board-serial=SN-0042",
        "--html",
        html_path.to_str().expect("utf-8"),
        "--json",
        json_path.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let html = read(&html_path);
    let record = json(&json_path);
    check_record(&run_record_schema(), &record);
    assert_offline(&html);

    // Every scenario of the suite, once.
    let listed = text(&ppmc(&["list"]).stdout);
    let names: Vec<&str> = listed
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| n.starts_with('s') || n.starts_with('e') || n.starts_with('f'))
        .collect();
    assert_eq!(names.len(), 96, "{listed}");
    // Each in full once; the one that failed once more, in the table the
    // page opens with (issue 42), before everything else.
    let in_page = attrs(&html, "data-scenario");
    let failed = "s3_6_decel_stop_17us_not_after";
    for n in &names {
        let want = if *n == failed { 2 } else { 1 };
        assert_eq!(in_page.iter().filter(|s| *s == n).count(), want, "{n}");
    }
    let first = html
        .find("<table class=\"first\">")
        .expect("the page opens with what failed");
    assert!(first < html.find("<table class=\"facts\">").expect("the facts"));
    let row = &html[first..first + html[first..].find("</table>").expect("closed")];
    assert!(
        row.contains(&format!("data-scenario=\"{failed}\"")),
        "{row}"
    );
    assert!(row.contains("<td class=\"by\">at least +"), "{row}");
    // The board's identity, as given.
    assert!(html.contains("<td>SN-0042</td>") && html.contains("<td>B</td>"));
    assert!(html.contains("chip_faults decel-stop-slow"));

    // The failure: marked on the first move's profiles, by pulse and by
    // time, at the pulse the failure's time falls on.
    let s = section(&html, failed);
    let tag = &html[details_at(&html, failed)..];
    let tag = &tag[..tag.find('>').expect("closed")];
    assert!(
        tag.contains("class=\"scenario failed\"") && tag.contains(" open"),
        "{tag}"
    );
    assert_eq!(s.matches("<g class=\"divergence\"").count(), 2, "{s}");
    let sc = record["scenarios"]
        .as_array()
        .expect("scenarios")
        .iter()
        .find(|x| x["name"] == failed)
        .expect("in the record");
    let at = sc["failure"]["at_ns"].as_u64().expect("at");
    let mv = &sc["figures"]["moves"][0];
    let (start, runs) = (
        mv["at_ns"].as_u64().expect("at"),
        mv["runs"].as_array().expect("runs"),
    );
    // The pulse the failure falls on: the first at or after it.
    let mut pulse = 0u64;
    let mut marked = None;
    for r in runs {
        let (from, n, span) = (
            r[0].as_u64().expect("n"),
            r[1].as_u64().expect("n"),
            r[2].as_u64().expect("n"),
        );
        for k in 0..n {
            let t = start + from + if n > 1 { k * span / (n - 1) } else { 0 };
            pulse += 1;
            if marked.is_none() && t >= at {
                marked = Some(pulse);
            }
        }
    }
    let marked = marked.expect("a pulse after the failure");
    let xs = attrs(s, "data-x");
    assert_eq!(xs[0], marked.to_string(), "the by-pulse mark");
    assert!(s.contains(&format!("failed here: pulse {marked}")));
    // Issue 42: the text names the pulse the plot marks (it said one
    // before: a 0-based index beside a 1-based count).
    let got = sc["failure"]["got"].as_str().expect("got");
    assert_eq!(got, format!("from pulse {marked}"), "{sc}");
    // And it says by how much: the latency is at least the time to the
    // pulse before, over the band's upper limit.
    let by = &sc["failure"]["deviation"];
    assert_eq!(by["unit"], "ns", "{sc}");
    assert_eq!(by["bound"], "at_least", "{sc}");
    assert_eq!(by["reference_is"], "limit", "{sc}");
    assert!(by["measured"].as_i64() > by["reference"].as_i64(), "{sc}");
    // The golden profile beneath, with its band; the pins around it.
    assert!(s.contains("polyline class=\"golden\"") && s.contains("polygon class=\"band\""));
    assert!(s.contains("<svg class=\"waveform\""));
    assert!(s.contains("POUT golden"));

    // Each move's profile: one point per interval up to the plot's
    // width, the columns' extremes past it.
    let columns = 470 - 56 - 12;
    let mut reduced = 0;
    for sc in record["scenarios"].as_array().expect("scenarios") {
        let s = section(&html, sc["name"].as_str().expect("name"));
        let moves = sc["figures"]["moves"].as_array().expect("moves");
        let profiles: Vec<&str> = s.split("<div class=\"move\"").skip(1).collect();
        assert_eq!(profiles.len(), moves.len());
        for (m, p) in moves.iter().zip(&profiles) {
            let pulses: u64 = m["runs"]
                .as_array()
                .expect("runs")
                .iter()
                .map(|r| r[1].as_u64().expect("count"))
                .sum();
            if pulses < 2 && m.get("golden").is_none() {
                continue;
            }
            let board_line = p
                .split("<polyline class=\"board\" data-points=\"")
                .nth(1)
                .expect("a board line");
            let n: u64 = board_line[..board_line.find('"').expect("q")]
                .parse()
                .expect("n");
            let intervals = pulses.saturating_sub(1);
            if intervals <= columns {
                assert_eq!(n, intervals, "{}", sc["name"]);
            } else {
                assert!(n <= 2 * columns && n >= columns / 2, "{}: {n}", sc["name"]);
                assert!(p.contains("Reduced for drawing: the least and the greatest interval"));
                reduced += 1;
            }
        }
    }
    assert!(reduced >= 1, "the 16,777,216-step move is reduced");
}

/// A record of the older format (3, before figures and retries) still
/// draws; a file that is no run record, a newer format and a report that
/// would overwrite its record are refused, by name.
#[test]
fn older_records_draw_and_bad_ones_are_refused_by_name() {
    let dir = scratch("report");
    let rec = dir.path().join("r.json");
    let out = ppmc(&[
        "run",
        "--filter",
        "s3_3_5",
        "--json",
        rec.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let mut old = json(&rec);
    old["format"] = "ppmc-run-record/3".into();
    for s in old["scenarios"].as_array_mut().expect("scenarios") {
        let s = s.as_object_mut().expect("object");
        s.remove("figures");
        s.remove("attempts");
    }
    old["summary"]
        .as_object_mut()
        .expect("summary")
        .remove("flaky");
    let old_path = dir.path().join("old.json");
    std::fs::write(&old_path, old.to_string()).expect("write");
    let page = dir.path().join("old.html");
    let out = ppmc(&[
        "report",
        old_path.to_str().expect("utf-8"),
        "-o",
        page.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = read(&page);
    assert_offline(&html);
    assert_eq!(attrs(&html, "data-scenario").len(), 3);
    assert!(
        !html.contains("class=\"move\""),
        "no figures in a format-3 record"
    );

    let bad = dir.path().join("notes.txt");
    std::fs::write(&bad, "not json").expect("write");
    let newer = dir.path().join("newer.json");
    std::fs::write(&newer, r#"{"format": "ppmc-run-record/99"}"#).expect("write");
    for (file, says) in [
        (&bad, "not a JSON run record"),
        (&newer, "newer than this ppmc reads"),
    ] {
        let out = ppmc(&[
            "report",
            file.to_str().expect("utf-8"),
            "-o",
            page.to_str().expect("utf-8"),
        ]);
        assert_eq!(out.status.code(), Some(2));
        let err = text(&out.stderr);
        assert!(
            err.contains(file.to_str().expect("utf-8")) && err.contains(says),
            "{err}"
        );
    }
    let out = ppmc(&[
        "report",
        rec.to_str().expect("utf-8"),
        "-o",
        rec.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        json(&rec)["scenarios"].is_array(),
        "the record is untouched"
    );
}

/// A link fault on one attempt (the emulator's third batch dropped, once)
/// and `--retries 1`: the scenario passes on its retry and is flaky, not
/// passed, in the summary line, in JUnit (a `flakyError` of type
/// `infrastructure`, in Maven Surefire's dialect), in the JSON record (its
/// attempt, schema-valid) and in the page; `--flaky-is-failure` fails the
/// run. A device failure on every attempt (`--retry-failures`) gives the
/// failure and a `rerunFailure` per earlier attempt.
#[test]
fn a_flaky_board_is_on_record_with_every_attempt() {
    let dir = scratch("report");
    let (xml, rec, page) = (
        dir.path().join("r.xml"),
        dir.path().join("r.json"),
        dir.path().join("r.html"),
    );
    let args = [
        "run",
        "--filter",
        "s3_3_5",
        "--target",
        "emu,drop-batch=3",
        "--retries",
        "1",
        "--junit",
        xml.to_str().expect("utf-8"),
        "--json",
        rec.to_str().expect("utf-8"),
        "--html",
        page.to_str().expect("utf-8"),
    ];
    let out = ppmc(&args);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{said}");
    assert!(said.contains("FLAKY"), "{said}");
    assert!(
        said.contains("suite: 2 passed, 1 flaky, 0 failed, 0 errors, 0 not run"),
        "{said}"
    );

    let record = json(&rec);
    check_record(&run_record_schema(), &record);
    assert_eq!(record["summary"]["flaky"], 1);
    assert_eq!(record["summary"]["passed"], 2);
    let flaky: Vec<&serde_json::Value> = record["scenarios"]
        .as_array()
        .expect("scenarios")
        .iter()
        .filter(|s| s["verdict"] == "flaky")
        .collect();
    assert_eq!(flaky.len(), 1);
    let attempt = &flaky[0]["attempts"][0];
    assert_eq!(attempt["verdict"], "error");
    assert_eq!(attempt["error"]["kind"], "infrastructure");

    let junit = read(&xml);
    let report = quick_junit::Report::deserialize_from_str(&junit).expect("parses");
    assert_eq!((report.tests, report.failures, report.errors), (3, 0, 0));
    // junit-10.xsd's rerunType: `type` required, then stackTrace,
    // system-out, system-err in that order.
    let element = junit
        .lines()
        .find(|l| l.contains("<flakyError"))
        .expect("a flakyError");
    assert!(
        element.contains("type=\"infrastructure\"")
            && element.contains("message=\"target: batch 3 dropped")
    );
    let (st, so) = (
        element.find("<stackTrace>").expect("trace"),
        element.find("<system-out>").expect("out"),
    );
    assert!(st < so, "{element}");
    assert!(!junit.contains("<flakyFailure") && !junit.contains("<rerun"));

    let html = read(&page);
    assert_offline(&html);
    assert_eq!(html.matches("class=\"scenario flaky\"").count(), 1);
    assert!(html.contains("<table class=\"attempts\">") && html.contains("batch 3 dropped"));

    let mut strict = args.to_vec();
    strict.push("--flaky-is-failure");
    let out = ppmc(&strict);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--flaky-is-failure"));

    // Failing every time: the failure, and the earlier attempts as reruns.
    let out = ppmc(&[
        "run",
        "--filter",
        "s3_6_decel_stop_17us_not_after",
        "--target",
        "emu,chip-fault=decel-stop-slow",
        "--retries",
        "2",
        "--retry-failures",
        "--junit",
        xml.to_str().expect("utf-8"),
        "--json",
        rec.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let junit = read(&xml);
    assert_eq!(junit.matches("<failure ").count(), 1, "{junit}");
    assert_eq!(
        junit.matches("<rerunFailure type=\"device\"").count(),
        2,
        "{junit}"
    );
    let record = json(&rec);
    check_record(&run_record_schema(), &record);
    assert_eq!(record["scenarios"][0]["verdict"], "failed");
    assert_eq!(
        record["scenarios"][0]["attempts"]
            .as_array()
            .expect("attempts")
            .len(),
        2
    );
}

/// Through a bridge (`ppmc bridge-sim`, protocol version 8 and later): the bridge's
/// serial number from its HELLO, its firmware, and the link's cost, in
/// the record, the store and the page.
#[test]
fn a_board_behind_a_bridge_is_named_by_the_bridge_and_its_link_shown() {
    let sim = BridgeSim::start(&["--serial", "E6614C311B4E5A2F"]);
    let dir = scratch("report");
    let (rec, page, db) = (
        dir.path().join("r.json"),
        dir.path().join("r.html"),
        dir.path().join("r.db"),
    );
    let target = format!("{},rev=B,board-serial=B-0007", sim.target());
    let out = ppmc(&[
        "run",
        "--filter",
        "s3_3_5_constant_speed_100",
        "--target",
        &target,
        "--json",
        rec.to_str().expect("utf-8"),
        "--html",
        page.to_str().expect("utf-8"),
        "--store",
        db.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    let record = json(&rec);
    check_record(&run_record_schema(), &record);
    let board = &record["run"]["boards"][0];
    assert_eq!(board["bridge_serial"], "E6614C311B4E5A2F");
    assert_eq!(board["board_serial"], "B-0007");
    assert!(board["bridge_firmware"]
        .as_str()
        .expect("firmware")
        .starts_with("ppmc-bridge-sim"));
    assert!(
        board["link"]["round_trips"].as_u64().expect("counted") > 0,
        "{board}"
    );
    let html = read(&page);
    assert!(html.contains("<td>E6614C311B4E5A2F</td>") && html.contains("round trips"));
    let c = ppmc(&["history", "--store", db.to_str().expect("utf-8")]);
    assert!(
        text(&c.stdout).contains("  B             100.0%  1 of 1 board test passed, on 1 board")
    );
}

/// The pulse a scenario's failure text names: the board's (after "got"),
/// else the check's (`first divergence in pulse 42 interval`).
fn text_pulse(section: &str) -> Option<u64> {
    let p = section.split("<p class=\"failure\">").nth(1)?;
    let p = &p[..p.find("</p>")?];
    let number = |t: &str| -> Option<u64> {
        let at = t.find("pulse ")? + "pulse ".len();
        let digits: String = t[at..].chars().take_while(char::is_ascii_digit).collect();
        digits.parse().ok()
    };
    p.split(", got ")
        .nth(1)
        .and_then(number)
        .or_else(|| number(p))
}

/// Issue 42: on every failing scenario of every board fault of the
/// catalogue (the fault matrix's boards), the plot's marker names the
/// pulse the failure's text names: one numbering, from 1, over the
/// scenario. (The README's own picture marked pulse 502 where the text
/// said 501.)
#[test]
fn the_marker_names_the_texts_pulse_on_every_fault_of_the_catalogue() {
    let dir = scratch("marker-pulses");
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../golden");
    let (mut compared, mut failing) = (0, 0);
    for fault in ppmc::faults::CATALOGUE {
        let page = dir.path().join(format!("{}.html", fault.name));
        let out = ppmc(&[
            "run",
            "--golden",
            golden.to_str().expect("utf-8"),
            "--target",
            &format!("emu,chip-fault={}", fault.name),
            "--html",
            page.to_str().expect("utf-8"),
        ]);
        assert!(
            matches!(out.status.code(), Some(0 | 1)),
            "{}: {}",
            fault.name,
            text(&out.stderr)
        );
        let html = read(&page);
        for at in html
            .match_indices("<details class=\"scenario failed\"")
            .map(|(i, _)| i)
        {
            failing += 1;
            let s = &html[at..at + html[at..].find("</details>").expect("closed")];
            let said = text_pulse(s);
            for drawn in s.split("<g class=\"divergence\"").skip(1) {
                let label = &drawn[drawn.find("<text").expect("a label")..];
                let label = &label
                    [label.find('>').expect("a tag") + 1..label.find("</text>").expect("closed")];
                let Some(m) = label.split("pulse ").nth(1) else {
                    continue;
                };
                let marked: u64 = m.trim().parse().expect("a pulse number");
                if let Some(said) = said {
                    assert_eq!(
                        marked, said,
                        "{}: {label} where the text says pulse {said}:\n{s}",
                        fault.name
                    );
                    compared += 1;
                }
            }
        }
    }
    assert!(failing > 0, "no fault failed a scenario");
    assert!(compared >= 2, "{compared} markers compared with their text");
    eprintln!(
        "{failing} failing scenarios over {} faults; {compared} markers named the text's pulse",
        ppmc::faults::CATALOGUE.len()
    );
}
