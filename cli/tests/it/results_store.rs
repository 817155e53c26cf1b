//! A results store filled by runs of two board revisions, the second with
//! a board fault of the catalogue (the first POUT of an accel/decel move
//! 5 % late, Table 3-3): `ppmc history` and `ppmc report --store` show the
//! faulty revision's yield and its measurement's distribution apart from
//! the good one's (issue 31, docs/results-store.md).

use crate::common;

use common::{ppmc, scratch, text};

#[test]
fn the_store_sets_a_faulty_revision_apart_from_a_good_one() {
    let dir = scratch("store");
    let db = dir.path().join("results.db");
    let db_s = db.to_str().expect("utf-8");
    for (board, code) in [
        ("emu,rev=A,board-serial=A-1", 0),
        ("emu,rev=A,board-serial=A-2,clock-mhz=15.9", 0),
        (
            "emu,rev=B,board-serial=B-1,chip-fault=accel-first-pout-slow",
            1,
        ),
        (
            "emu,rev=B,board-serial=B-2,clock-mhz=15.9,chip-fault=accel-first-pout-slow",
            1,
        ),
    ] {
        let out = ppmc(&[
            "run",
            "--filter",
            "s3_3_4_longest_triangle_first_pout",
            "--target",
            board,
            "--store",
            db_s,
        ]);
        assert_eq!(
            out.status.code(),
            Some(code),
            "{board}: {}",
            text(&out.stdout)
        );
    }
    let out = ppmc(&["history", "--store", db_s]);
    let said = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{said}");
    assert!(said.contains("4 runs, 4 boards"), "{said}");
    assert!(
        said.contains("  A             100.0%  2 of 2 board tests passed, on 2 boards"),
        "{said}"
    );
    assert!(
        said.contains("  B               0.0%  0 of 2 board tests passed, on 2 boards"),
        "{said}"
    );
    // Issue 42: the value out of its band comes first, flagged, with its
    // band, every figure in one unit.
    let first = said
        .lines()
        .skip_while(|l| !l.starts_with("measurements by scenario"))
        .nth(1)
        .expect("a measurement line");
    assert!(
        first.starts_with(
            "  OUT  2/2  accel_first_pout in s3_3_4_longest_triangle_first_pout on B:"
        ),
        "{said}"
    );
    assert!(
        first.contains(", band ") && first.contains("sd=") && !first.contains("ns"),
        "{first}"
    );

    let page = dir.path().join("history.html");
    let out = ppmc(&[
        "report",
        "--store",
        db_s,
        "-o",
        page.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = std::fs::read_to_string(&page).expect("written");
    for banned in ["<script", "http://", "https://", "src="] {
        assert!(!html.contains(banned), "{banned} in the page");
    }
    // The measurement of the faulty revision outside its band comes first,
    // both revisions on one scale, B's mean 5 % above A's.
    let group = html
        .split("<div class=\"measure-group\"")
        .nth(1)
        .expect("a measurement group");
    assert!(
        group.contains("data-measure=\"accel_first_pout\""),
        "{group}"
    );
    let mean = |rev: &str| -> f64 {
        let at = group
            .find(&format!(
                "<g class=\"rev\" data-rev=\"{rev}\" data-mean-ns=\""
            ))
            .unwrap_or_else(|| panic!("{rev} in {group}"));
        let v = &group[at..];
        let v = &v[v.find("data-mean-ns=\"").expect("mean") + 14..];
        v[..v.find('"').expect("q")].parse().expect("a number")
    };
    let (a, b) = (mean("A"), mean("B"));
    assert!((b / a - 1.05).abs() < 0.01, "A {a} ns, B {b} ns");
    assert!(html.contains("data-rev=\"B\" data-yield=\"0.0000\""));
    assert!(html.contains("data-rev=\"A\" data-yield=\"1.0000\""));

    // Nothing is written over: not the store, not a report asked onto it,
    // and a soak, whose record counts its passes, is not stored.
    let out = ppmc(&["report", "--store", db_s, "-o", db_s]);
    assert_eq!(out.status.code(), Some(2));
    let refused = |more: &[&str], says: &str| {
        let mut args = vec!["run", "--filter", "e0_undefined", "--store", db_s];
        args.extend_from_slice(more);
        let out = ppmc(&args);
        assert_eq!(out.status.code(), Some(2), "{more:?}");
        let err = text(&out.stderr);
        assert!(err.contains(says), "{more:?}: {err}");
    };
    for flag in ["--json", "--html", "--junit"] {
        refused(&[flag, db_s], "are the same file");
    }
    refused(&["--repeat", "2"], "--store with --repeat");
    let out = ppmc(&["history", "--store", db_s]);
    assert_eq!(out.status.code(), Some(0));
}

/// `scripts/store-figures`, as docs/performance.md runs it, on a store of
/// three runs: its table has the row it promises, every run's results.
#[test]
fn the_store_figures_script_fills_a_store_and_times_its_report() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let out = std::process::Command::new(format!("{root}/scripts/store-figures"))
        .args([
            "--runs",
            "3",
            "--draws",
            "1",
            "--ppmc",
            env!("CARGO_BIN_EXE_ppmc"),
        ])
        .output()
        .expect("the script runs");
    let said = text(&out.stdout);
    assert!(out.status.success(), "{said}{}", text(&out.stderr));
    let row = said.lines().last().expect("a row");
    assert!(row.starts_with("| 3 | 288 | "), "{said}");
}

/// `ppmc judge --store`: a board judged from a capture is kept beside the
/// boards run through a bridge. A board that diverges fails its board
/// test; one whose host firmware broke a rule of chapter 3 (exit 3) does
/// not, its finding blamed on the host firmware.
#[test]
fn boards_judged_from_captures_are_kept_with_whom_they_blame() {
    let dir = scratch("store");
    let db = dir.path().join("results.db");
    let db_s = db.to_str().expect("utf-8");
    let capture = |name: &str, scenario: &str, fault: Option<&str>| {
        let path = dir.path().join(name);
        let mut args = vec!["export", "--scenario", scenario, "--bus", "-o"];
        args.push(path.to_str().expect("utf-8"));
        if let Some(f) = fault {
            args.extend(["--chip-fault", f]);
        }
        let out = ppmc(&args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        path
    };
    let faulty = capture(
        "faulty.vcd",
        "s3_3_5_constant_speed_100_steps",
        Some("drop-last-pulse"),
    );
    let misused = capture("misused.vcd", "e0_undefined_command_code", None);
    for (file, rev, code) in [(&faulty, "C", 1), (&misused, "D", 3)] {
        let out = ppmc(&[
            "judge",
            file.to_str().expect("utf-8"),
            "--store",
            db_s,
            "--board-rev",
            rev,
            "--board-serial",
            &format!("{rev}-1"),
        ]);
        assert_eq!(out.status.code(), Some(code), "{}", text(&out.stdout));
    }
    let out = ppmc(&["history", "--store", db_s]);
    let said = text(&out.stdout);
    assert!(
        said.contains("  C               0.0%  0 of 1 board test passed, on 1 board"),
        "{said}"
    );
    assert!(
        said.contains("  D             100.0%  1 of 1 board test passed, on 1 board"),
        "{said}"
    );
}

/// Issue 42: the store's page names every board, with its last verdict.
/// A store of 1,000 runs over 40 boards of three revisions, each board
/// passing or failing by turns (the last run of every fifth board fails):
/// the page's table lists each board once, with the verdict of its last
/// test and how many tests it had, the ones last failing first.
#[test]
fn the_store_page_lists_every_board_of_a_thousand_runs_with_its_last_verdict() {
    use ppmc_record::RunRecord;
    use ppmc_report::store::Store;
    let dir = scratch("store-boards");
    let json = dir.path().join("run.json");
    let out = ppmc(&[
        "run",
        "--filter",
        "s3_3_5_constant_speed_100_steps",
        "--json",
        json.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let template: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    let db = dir.path().join("results.db");
    let mut store = Store::open(&db).expect("a new store");
    const BOARDS: usize = 40;
    let fails_last = |b: usize| b % 5 == 0;
    for run in 0..1_000usize {
        let board = run % BOARDS;
        let last = run + BOARDS >= 1_000;
        // Every board passes and fails by turns; its last run fails only
        // for every fifth board.
        let failed = if last {
            fails_last(board)
        } else {
            (run / BOARDS) % 2 == 1
        };
        let mut r = template.clone();
        let rev = ["A", "B", "C"][board % 3];
        r["run"]["boards"][0]["board_serial"] = format!("SN-{board:04}").into();
        r["run"]["boards"][0]["board_rev"] = rev.into();
        r["run"]["host"] = format!("station-{}", board % 4).into();
        // Each a run of its own (a store keeps a run's id once).
        r["run"]["id"] = format!("00000000-0000-4000-8000-{run:012}").into();
        // A run a minute, in order.
        r["run"]["started"] = format!("2026-11-01T{:02}:{:02}:00Z", run / 60, run % 60).into();
        if failed {
            let sc = &mut r["scenarios"][0];
            sc["verdict"] = "failed".into();
            sc["failure"] = serde_json::json!({
                "expectation": "pulse count", "expected": "100", "got": "99", "at_ns": 1000
            });
            r["summary"]["passed"] = 0.into();
            r["summary"]["failed"] = 1.into();
        }
        let record = RunRecord::parse(&r.to_string(), "run.json").expect("a record");
        store.add(&record).expect("added");
    }
    drop(store);
    let page = dir.path().join("history.html");
    let out = ppmc(&[
        "report",
        "--store",
        db.to_str().expect("utf-8"),
        "-o",
        page.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = std::fs::read_to_string(&page).expect("written");
    let table = html
        .split("<table class=\"boards\">")
        .nth(1)
        .and_then(|t| t.split("</table>").next())
        .expect("the boards' table");
    let rows: Vec<&str> = table.split("<tr class=\"").skip(1).collect();
    assert_eq!(rows.len(), BOARDS, "{table}");
    let failing = (0..BOARDS).filter(|b| fails_last(*b)).count();
    for (i, row) in rows.iter().enumerate() {
        // The ones last failing first.
        let want = if i < failing { "failed" } else { "passed" };
        assert!(row.starts_with(want), "row {i}: {row}");
        assert!(row.contains("<td>25</td>"), "25 tests a board: {row}");
    }
    for board in 0..BOARDS {
        let row = rows
            .iter()
            .find(|r| r.contains(&format!("data-board=\"SN-{board:04}\"")))
            .unwrap_or_else(|| panic!("SN-{board:04} is not listed"));
        let want = if fails_last(board) {
            "failed"
        } else {
            "passed"
        };
        assert!(
            row.contains(&format!("<span class=\"chip {want}\">")),
            "{row}"
        );
        assert!(row.contains(&format!("station-{}", board % 4)), "{row}");
    }
}
