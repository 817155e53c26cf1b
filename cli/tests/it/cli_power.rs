//! Recovery by power from the command line (docs/board-farm.md, "A board
//! that hangs"): a `ppmc bridge-sim` made to hang (`--stall-after`) is
//! power-cycled by `scripts/bridge-sim-power`, once through `--power-cmd`
//! and once as a USB hub port through `--power-hub` (a stand-in for
//! `uhubctl`, `PPMC_UHUBCTL`, that says how it was called), and the run
//! goes on: every other scenario graded, the one in flight an
//! infrastructure error that names the hang. labgrid's power driver is
//! tried in `cli_labgrid.rs`.

use crate::common;

use common::{ppmc, scratch, text};
use std::path::{Path, PathBuf};
use std::process::Command;

fn power_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/bridge-sim-power")
}

/// Starts a bridge-sim in `dir` that stops answering after 60 frames.
fn hanging_bridge(dir: &Path) {
    let started = Command::new(power_script())
        .arg(dir)
        .args(["on", "--stall-after", "60"])
        .env("PPMC", env!("CARGO_BIN_EXE_ppmc"))
        .status()
        .expect("the power script runs");
    assert!(started.success());
}

fn stop_bridge(dir: &Path) {
    let _ = Command::new(power_script()).arg(dir).arg("off").status();
}

/// Runs the suite, less its long moves, on the bridge in `dir` with
/// `power`, a short link bound (so the hang shows within seconds): its
/// exit code, its output and its JUnit report.
fn run_with(dir: &Path, power: &[&str], env: &[(&str, &Path)]) -> (Option<i32>, String, String) {
    let junit = dir.join("report.xml");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ppmc"));
    cmd.args(["run", "--skip-tag", "long", "--link-timeout", "500ms"])
        .args(["--link-retries", "3", "--target"])
        .arg(format!("serial:{}", dir.join("pty").display()))
        .arg("--junit")
        .arg(&junit)
        .args(power)
        .env("PPMC", env!("CARGO_BIN_EXE_ppmc"));
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("ppmc runs");
    stop_bridge(dir);
    let said = format!("{}{}", text(&out.stdout), text(&out.stderr));
    (
        out.status.code(),
        said,
        std::fs::read_to_string(&junit).unwrap_or_default(),
    )
}

/// What every recovered run shows: one infrastructure error naming the
/// hang and the switch, every other scenario passed.
fn check_recovered(code: Option<i32>, said: &str, junit: &str, switch: &str) {
    assert_eq!(code, Some(1), "an error fails the run:\n{said}");
    assert!(
        said.contains("suite: 94 passed, 0 failed, 1 errors, 0 not run"),
        "{said}"
    );
    let error = said
        .lines()
        .find(|l| l.contains("infrastructure error: the board hung: "))
        .unwrap_or_else(|| panic!("no hang named:\n{said}"));
    assert!(
        error.contains("the board hung: its bridge stopped answering (serial:"),
        "{error}"
    );
    assert!(
        error.ends_with(&format!(
            "power-cycled by `{switch}` (1 of 3), and the run went on"
        )),
        "{error}"
    );
    assert_eq!(junit.matches("<error ").count(), 1, "{junit}");
    assert!(junit.contains("type=\"infrastructure\""), "{junit}");
}

#[test]
fn a_hung_bridge_is_power_cycled_by_the_power_command_and_the_run_goes_on() {
    let dir = scratch("power-cmd");
    hanging_bridge(dir.path());
    let cmd = format!("{} {}", power_script().display(), dir.path().display());
    let (code, said, junit) = run_with(dir.path(), &["--power-cmd", &cmd], &[]);
    check_recovered(code, &said, &junit, &format!("{cmd} cycle"));
}

#[test]
fn a_hung_bridge_is_power_cycled_through_its_usb_hub_port() {
    let dir = scratch("power-hub");
    hanging_bridge(dir.path());
    // uhubctl as the test has it: says how it was called, and cycles the
    // bridge-sim as a hub port's power would.
    let uhubctl = dir.path().join("uhubctl");
    std::fs::write(
        &uhubctl,
        format!(
            "#!/bin/sh\necho \"$@\" >> '{log}'\nexec '{script}' '{dir}' cycle\n",
            log = dir.path().join("uhubctl.log").display(),
            script = power_script().display(),
            dir = dir.path().display()
        ),
    )
    .expect("writes");
    let chmod = Command::new("chmod").arg("+x").arg(&uhubctl).status();
    assert!(chmod.expect("chmod runs").success());
    let (code, said, junit) = run_with(
        dir.path(),
        &["--power-hub", "1-1.4:2"],
        &[("PPMC_UHUBCTL", &uhubctl)],
    );
    check_recovered(
        code,
        &said,
        &junit,
        &format!("{} -l 1-1.4 -p 2 -a cycle", uhubctl.display()),
    );
    let called = std::fs::read_to_string(dir.path().join("uhubctl.log")).unwrap_or_default();
    assert_eq!(called, "-l 1-1.4 -p 2 -a cycle\n");
}

#[test]
fn power_options_the_user_got_wrong_are_refused_before_any_board_is_touched() {
    let out = ppmc(&["run", "--power-hub", "1-1.4"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("--power-hub `1-1.4`: write LOCATION:PORT"),
        "{err}"
    );
    let out = ppmc(&[
        "run",
        "--power-hub",
        "1-1:2",
        "--target",
        "emu",
        "--target",
        "emu",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("--power-hub 1-1:2 with 2 --target: one port would cycle every board"),
        "{err}"
    );
    let out = ppmc(&["run", "--power-hub", "1-1:2", "--power-cmd", "relay"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("cannot be used with"),
        "{}",
        text(&out.stderr)
    );
    let help = text(&ppmc(&["run", "--help"]).stdout);
    assert!(
        help.contains("Recovery by power:") && help.contains("--power-cycles <N>"),
        "{help}"
    );
}

/// Issue 45: a board made to hang mid-campaign is brought back by its
/// power switch; the input it hung under is a finding, and the campaign
/// goes on to the end of its budget.
#[test]
fn a_board_made_to_hang_mid_campaign_is_power_cycled_and_the_campaign_goes_on() {
    let dir = scratch("power-campaign");
    hanging_bridge(dir.path());
    let cmd = format!("{} {}", power_script().display(), dir.path().display());
    let findings = dir.path().join("findings");
    let out = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args([
            "fuzz",
            "campaign",
            "--budget",
            "20s",
            "--link-timeout",
            "500ms",
        ])
        .args(["--link-retries", "3", "--target"])
        .arg(format!("serial:{}", dir.path().join("pty").display()))
        .arg("--findings")
        .arg(&findings)
        .args(["--power-cmd", &cmd])
        .env("PPMC", env!("CARGO_BIN_EXE_ppmc"))
        .output()
        .expect("ppmc runs");
    stop_bridge(dir.path());
    let said = format!("{}{}", text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "a hang is a finding:\n{said}");
    assert!(
        said.contains(" s of board time: the board hung: its bridge stopped answering (serial:")
            && said.contains(&format!("power-cycled by `{cmd} cycle` (1 of 3) -> ")),
        "{said}"
    );
    let summary = said
        .lines()
        .find(|l| l.starts_with("campaign on "))
        .unwrap_or_else(|| panic!("no summary:\n{said}"));
    assert!(summary.contains(" findings (1 hangs), "), "{summary}");
    let board_time: f64 = summary
        .split(" executions in ")
        .nth(1)
        .and_then(|r| r.split(" s of board time").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{summary}"));
    assert!(
        board_time >= 20.0,
        "the campaign went on to its budget: {summary}"
    );
    let kept: Vec<String> = std::fs::read_dir(&findings)
        .expect("findings")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(kept.iter().any(|n| n.starts_with("hang-")), "{kept:?}");
}
