//! Several boards in one run: `ppmc run --target A --target B ...` with
//! `ppmc bridge-sim`s as the boards. The suite is spread over them (or, with
//! `--each`, run on every one), and one JUnit and one JSON report name the
//! board of every test case. A board that drops out hands what is left to
//! the others; the scenario it had under way is blamed on the target.

use crate::common;

use common::{check_record, ppmc, run_record_schema, scratch, text, wait_bounded, BridgeSim};
use std::collections::BTreeSet;
use std::io::Read;
use std::process::{Command, Stdio};
use std::time::Duration;

/// The `n`th board of a test: a bridge simulator linked at `dir/board<n>`.
fn sim(dir: &std::path::Path, n: usize) -> BridgeSim {
    BridgeSim::start_at(&dir.join(format!("board{n}")), &[])
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("JSON written")).expect("JSON")
}

/// Runs the suite shared by `n` bridge-sims; checks the merged reports.
fn shared_by(n: usize) {
    let dir = scratch("boards");
    let sims: Vec<BridgeSim> = (1..=n).map(|i| sim(dir.path(), i)).collect();
    let (junit, record) = (dir.path().join("r.xml"), dir.path().join("r.json"));
    let mut args = vec!["run".to_string()];
    for (i, s) in sims.iter().enumerate() {
        args.push("--target".into());
        args.push(format!("{},name=b{},rev=R{}", s.target(), i + 1, i + 1));
    }
    args.extend(["--golden", "../golden", "--junit"].map(String::from));
    args.push(junit.display().to_string());
    args.push("--json".into());
    args.push(record.display().to_string());
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = ppmc(&args);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(
        stdout.contains("suite: 96 passed, 0 failed, 0 errors, 0 not run"),
        "{stdout}"
    );
    // A line per board, and the board on every verdict line.
    for i in 1..=n {
        assert!(stdout.contains(&format!("\nboard b{i}: ")), "{stdout}");
    }
    assert!(stdout.contains("(section 3-1-1) on b"), "{stdout}");

    // JUnit: one suite of 96 cases, each board's facts and each case's board.
    let xml = std::fs::read_to_string(&junit).expect("JUnit written");
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("valid JUnit XML");
    assert_eq!(report.tests, 96);
    assert_eq!(report.test_suites.len(), 1);
    let suite = &report.test_suites[0];
    let prop = |name: &str| {
        suite
            .properties
            .iter()
            .find(|p| p.name.as_str() == name)
            .map(|p| p.value.to_string())
    };
    for i in 1..=n {
        assert_eq!(
            prop(&format!("board.b{i}.board_rev")),
            Some(format!("R{i}"))
        );
        assert!(prop(&format!("board.b{i}.target")).is_some_and(|t| t.starts_with("serial:")));
    }
    for case in &suite.test_cases {
        let board = prop(&format!("board_of.{}", case.name.as_str())).expect("each case's board");
        assert!(board.starts_with('b'), "{board}");
        let out = case.system_out.as_ref().expect("a board: line");
        assert_eq!(out.as_str(), format!("board: {board}"));
    }

    // JSON: the boards, and the board of every scenario.
    let v = json(&record);
    check_record(&run_record_schema(), &v);
    assert_eq!(v["run"]["spread"], "share");
    let boards: Vec<&str> = v["run"]["boards"]
        .as_array()
        .expect("boards")
        .iter()
        .map(|b| b["name"].as_str().expect("name"))
        .collect();
    assert_eq!(boards, (1..=n).map(|i| format!("b{i}")).collect::<Vec<_>>());
    let scenarios = v["scenarios"].as_array().expect("scenarios");
    assert_eq!(scenarios.len(), 96);
    let used: BTreeSet<&str> = scenarios
        .iter()
        .map(|s| s["board"].as_str().expect("every scenario names its board"))
        .collect();
    assert!(used.iter().all(|b| boards.contains(b)), "{used:?}");
    // The suite's order, whichever board ran what.
    let names: Vec<&str> = scenarios
        .iter()
        .map(|s| s["name"].as_str().expect("name"))
        .collect();
    let mut sorted = names.clone();
    sorted.sort_unstable();
    let listed = text(&ppmc(&["list"]).stdout);
    let order: Vec<&str> = listed
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|w| names.contains(w))
        .collect();
    assert_eq!(names, order);
}

#[test]
fn two_boards_share_the_suite_with_one_report_naming_each_cases_board() {
    shared_by(2);
}

#[test]
fn three_boards_share_the_suite_with_one_report_naming_each_cases_board() {
    shared_by(3);
}

#[test]
fn each_runs_the_suite_on_every_board_one_junit_suite_per_board() {
    let dir = scratch("boards");
    let sims: Vec<BridgeSim> = (1..=2).map(|i| sim(dir.path(), i)).collect();
    let junit = dir.path().join("r.xml");
    let out = ppmc(&[
        "run",
        "--each",
        "--target",
        &sims[0].target(),
        "--target",
        &format!("{},name=second", sims[1].target()),
        "--skip-tag",
        "long",
        "--junit",
        junit.to_str().expect("utf-8"),
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    let report = quick_junit::Report::deserialize_from_str(
        &std::fs::read_to_string(&junit).expect("JUnit written"),
    )
    .expect("valid JUnit XML");
    assert_eq!(report.test_suites.len(), 2);
    let first = &report.test_suites[0];
    let second = &report.test_suites[1];
    assert_eq!(
        first.name.as_str(),
        format!("ppmc-conformance on {}", sims[0].target())
    );
    assert_eq!(second.name.as_str(), "ppmc-conformance on second");
    assert_eq!(first.test_cases.len(), second.test_cases.len());
    assert!(first.test_cases.len() > 50);
    assert_eq!(report.tests, 2 * first.test_cases.len());
    // Each suite carries its own board's facts under the one-board names.
    assert!(second
        .properties
        .iter()
        .any(|p| p.name.as_str() == "target" && p.value.as_str() == sims[1].target()));
}

#[test]
fn a_board_that_drops_out_hands_its_scenarios_to_the_others() {
    let dir = scratch("boards");
    // Boards that answer in real time: a pass takes seconds, so board 2
    // goes away mid-run however late this test reads ppmc's output.
    let sims: Vec<BridgeSim> = (1..=3)
        .map(|i| BridgeSim::start_at(&dir.path().join(format!("board{i}")), &["--realtime"]))
        .collect();
    let record = dir.path().join("r.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(["run", "--repeat", "2", "--skip-tag", "long"])
        .args(["--target", &format!("{},name=b1", sims[0].target())])
        .args(["--target", &format!("{},name=b2", sims[1].target())])
        .args(["--target", &format!("{},name=b3", sims[2].target())])
        .args(["--link-timeout", "100ms", "--link-retries", "3", "--json"])
        .arg(&record)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("ppmc starts");
    // Some scenarios run on every board, then board 2 goes away.
    let mut stdout = child.stdout.take().expect("piped");
    let mut seen = Vec::new();
    let mut buf = [0u8; 4096];
    while seen.iter().filter(|&&b| b == b'\n').count() < 20 {
        let n = stdout.read(&mut buf).expect("read");
        assert!(n > 0, "ppmc ended early: {}", text(&seen));
        seen.extend_from_slice(&buf[..n]);
    }
    let mut gone = sims.into_iter().collect::<Vec<_>>();
    drop(gone.remove(1));
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).expect("the rest");
    let status = wait_bounded(&mut child, Duration::from_secs(120));
    let mut err = String::new();
    let _ = child.stderr.take().expect("piped").read_to_string(&mut err);
    // Not a pass (a scenario was cut short), but nothing on a board failed.
    assert_eq!(status.code(), Some(1), "{rest}\n{err}");
    let v = json(&record);
    assert_eq!(v["summary"]["failed"], 0, "{rest}");
    assert_eq!(v["summary"]["not_run"], 0, "handed to the others: {rest}");
    let scenarios = v["scenarios"].as_array().expect("scenarios");
    let errors: Vec<&serde_json::Value> = scenarios
        .iter()
        .filter(|s| s["verdict"] == "error")
        .collect();
    // The scenario under way on b2 is an error of the target, on b2. (If
    // another process takes b2's freed pseudo-terminal, the bridge's new
    // session is caught too: another error on b2, never a verdict.)
    assert!(!errors.is_empty());
    for e in &errors {
        assert_eq!(e["board"], "b2", "{e}");
        let message = e["error"]["message"].as_str().unwrap_or_default();
        assert!(message.contains("board2"), "names the link: {message}");
    }
    // After the drop-out only b1 and b3 ran anything: b2 ran fewer than
    // either, and the three ran the whole soak between them. (Not the
    // record's order, which lists the first pass first.)
    let ran = |board: &str| -> u64 {
        let line = rest
            .lines()
            .find(|l| l.starts_with(&format!("board {board}: ")))
            .unwrap_or_else(|| panic!("a line for {board}: {rest}"));
        let n = line.split(": ").nth(1).and_then(|t| t.split(' ').next());
        n.and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("a count in {line:?}"))
    };
    let (b1, b2, b3) = (ran("b1"), ran("b2"), ran("b3"));
    assert!(b2 < b1 && b2 < b3, "{rest}");
    let suite: BTreeSet<&str> = scenarios
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert!(suite.len() > 50, "{suite:?}");
    let summary = ["passed", "marginal", "flaky", "failed", "error", "not_run"]
        .map(|k| v["summary"][k].as_u64().unwrap_or_default());
    assert_eq!(summary.iter().sum::<u64>(), 2 * suite.len() as u64);
    assert_eq!(b1 + b2 + b3, 2 * suite.len() as u64, "{rest}");
}

#[test]
fn only_run_takes_several_targets_and_a_bad_board_option_is_refused() {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/examples/accel-1000-steps.ppmc"
    );
    let out = ppmc(&["console", "--target", "emu", "--target", "emu", script]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("only `ppmc run` drives several boards"),
        "{}",
        text(&out.stderr)
    );
    let out = ppmc(&["run", "--target", "emu,csel=middle"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("--target `emu,csel=middle`: csel=middle: write high or low"),
        "{}",
        text(&out.stderr)
    );
    // A board's own straps: the emulator strapped at 12 MHz runs at 12.
    let dir = scratch("boards");
    let record = dir.path().join("r.json");
    let out = ppmc(&[
        "run",
        "--target",
        "emu,clock-mhz=12,rev=C",
        "--target",
        "emu",
        "--filter",
        "s3_1_1",
        "--json",
        record.to_str().expect("utf-8"),
    ]);
    assert!(out.status.success(), "{}", text(&out.stdout));
    let v = json(&record);
    let boards = &v["run"]["boards"];
    assert_eq!(boards[0]["target_details"]["sysclk_hz"], "12000000");
    assert_eq!(boards[0]["board_rev"], "C");
    assert_eq!(boards[1]["name"], "emu#2");
    assert_eq!(boards[1]["target_details"]["sysclk_hz"], "16000000");
}

/// With `--each`, the files of what did not pass go to a folder per board:
/// here the 12 MHz emulator's, whose golden traces were recorded at 16 MHz
/// (an error of the golden file, on that board alone).
#[test]
fn each_keeps_every_boards_artifacts_apart() {
    let dir = scratch("boards");
    let arts = dir.path().join("arts");
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/../golden");
    let out = ppmc(&[
        "run",
        "--each",
        "--target",
        "emu",
        "--target",
        "emu,clock-mhz=12",
        "--golden",
        golden,
        "--filter",
        "s3_1_1_status_is_idle_after_reset",
        "--artifacts",
        arts.to_str().expect("utf-8"),
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("board emu: 1 scenarios, 1 passed"),
        "{stdout}"
    );
    assert!(
        stdout.contains("board emu#2: 1 scenarios, 0 passed, 0 failed, 1 errors"),
        "{stdout}"
    );
    let saved: Vec<String> = std::fs::read_dir(&arts)
        .expect("artifacts written")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(saved, ["emu#2"]);
    assert!(arts
        .join("emu#2/s3_1_1_status_is_idle_after_reset.trace")
        .is_file());
}

/// One board of several that cannot be reached makes the run an
/// infrastructure error (exit 1), though every scenario passed on the
/// other; its record names the address it was tried at as its `target`,
/// and its label as its `name`.
#[test]
fn an_unreachable_board_fails_the_run_and_its_record_names_its_address() {
    let dir = scratch("boards");
    let (junit, record) = (dir.path().join("r.xml"), dir.path().join("r.json"));
    let missing = dir.path().join("no-such-port");
    let address = format!("serial:{}", missing.display());
    let out = ppmc(&[
        "run",
        "--target",
        "emu",
        "--target",
        &format!("{address},name=ghost"),
        "--filter",
        "s3_1_1",
        "--junit",
        junit.to_str().expect("utf-8"),
        "--json",
        record.to_str().expect("utf-8"),
    ]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(
        stdout.contains(" 0 failed, 0 errors, 0 not run"),
        "{stdout}"
    );
    assert!(
        stderr.contains(&format!(
            "ppmc: infrastructure error: 1 of 2 boards could not be reached and took no part in the run: ghost ({address})"
        )),
        "{stderr}"
    );
    let v = json(&record);
    check_record(&run_record_schema(), &v);
    let ghost = &v["run"]["boards"][1];
    assert_eq!(ghost["name"], "ghost");
    assert_eq!(ghost["target"], address.as_str());
    assert!(ghost["error"].is_string(), "{ghost}");
    let xml = std::fs::read_to_string(&junit).expect("JUnit written");
    assert!(
        xml.contains(&format!(r#"name="board.ghost.target" value="{address}""#)),
        "{xml}"
    );
}

/// One bridge named twice would have two hosts drive one chip at once,
/// each taking the other's HELLO for a takeover: refused before anything
/// is opened. Several emulators are several chips, and stay allowed.
#[test]
fn the_same_bridge_twice_is_refused_before_anything_is_opened() {
    let out = ppmc(&[
        "run",
        "--target",
        "tcp://127.0.0.1:9",
        "--target",
        "tcp://127.0.0.1:9,name=again",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("--target tcp://127.0.0.1:9 given twice"),
        "{}",
        text(&out.stderr)
    );
}
