//! The board team's crate gets the whole command line from one call: its
//! own scenarios are listed and run next to ppmc's suite, with JUnit.

use std::process::Command;

fn board_suite(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_board-suite"))
        .args(args)
        .output()
        .expect("board-suite runs")
}

#[test]
fn its_own_scenarios_are_listed_next_to_the_conformance_suite() {
    let out = board_suite(&["list"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    let suite = ppmc_scenarios::all().len();
    assert!(text.contains(&format!("{} scenarios", suite + 3)), "{text}");
    assert!(text.contains("s3_3_4_accel_one_step"), "{text}");
    assert!(
        text.contains("x_axis_homes_on_cnp") && text.contains("3-3-8"),
        "{text}"
    );
}

#[test]
fn its_own_scenarios_run_with_a_junit_report() {
    let dir = std::env::temp_dir().join(format!("board-suite-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let junit = dir.join("report.xml");
    let out = board_suite(&[
        "run",
        "--tag",
        "board",
        "--junit",
        junit.to_str().expect("utf-8 path"),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("suite: 3 passed, 0 failed"), "{text}");
    let xml = std::fs::read_to_string(&junit).expect("JUnit written");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(xml.matches("<testcase").count(), 3, "{xml}");
    for name in [
        "x_axis_travel_4000_steps",
        "x_axis_homes_on_cnp",
        "x_axis_end_stop_l1",
    ] {
        assert!(xml.contains(&format!("name=\"{name}\"")), "{name} in {xml}");
    }
}

/// Issue 42: a missing golden trace named `ppmc record`, a command this
/// crate's user does not have; the help named `ppmc` too.
#[test]
fn its_messages_name_its_own_binary() {
    let dir = std::env::temp_dir().join(format!("board-suite-golden-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let out = board_suite(&[
        "run",
        "--filter",
        "x_axis_homes_on_cnp",
        "--golden",
        dir.to_str().expect("utf-8 path"),
    ]);
    let _ = std::fs::remove_dir_all(&dir);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("record one with `board-suite record`"),
        "{text}"
    );
    assert!(!text.contains("ppmc record"), "{text}");
    let help = board_suite(&["--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("Usage: board-suite"), "{help}");
}
