//! A board in a labgrid farm: `ppmc run --target labgrid:<place>` against
//! a local labgrid coordinator and exporter (labgrid from PyPI), whose
//! place's serial port is a `ppmc bridge-sim` pseudo-terminal.
//!
//! labgrid's exporter starts ser2net listening on every address, so the
//! whole farm runs in a network namespace this test makes (`unshare -n`),
//! with only loopback: nothing in it is reachable from outside, and it
//! all ends with the namespace's script (`labgrid/place.sh`).
//!
//! Needs labgrid (`PPMC_LABGRID_BIN`, the directory of its programs, or
//! `labgrid-client` on the `PATH`) and the right to make a network
//! namespace. Without them the test says so and passes, except in CI
//! (`CI` set), where `.ci/run` provides them.

use crate::common;

use common::{scratch, text, wait_bounded};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// The directory of labgrid's programs, if there is one.
fn labgrid_bin() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("PPMC_LABGRID_BIN") {
        return Some(PathBuf::from(dir));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).find(|d| d.join("labgrid-client").is_file())
}

fn can_unshare() -> bool {
    Command::new("unshare")
        .args(["-n", "true"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn skip(why: &str) {
    assert!(
        std::env::var_os("CI").is_none(),
        "CI must test the labgrid target: {why}"
    );
    eprintln!("the labgrid target is not tested: {why}");
}

/// The `MARK name value` lines of the script's output.
fn mark<'a>(out: &'a str, name: &str) -> &'a str {
    out.lines()
        .find_map(|l| l.strip_prefix(&format!("MARK {name} ")))
        .unwrap_or_else(|| panic!("no `{name}` in the script's output:\n{out}"))
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_default()
}

#[cfg_attr(
    ppmc_missing_labgrid,
    ignore = "labgrid is not installed (pip install labgrid, or PPMC_LABGRID_BIN)"
)]
#[test]
fn the_suite_passes_on_a_labgrid_place_and_an_unacquired_place_is_refused() {
    let Some(bin) = labgrid_bin() else {
        return skip("labgrid is not installed (pip install labgrid; or set PPMC_LABGRID_BIN)");
    };
    if !can_unshare() {
        return skip("cannot make a network namespace here (unshare -n)");
    }
    let dir = scratch("labgrid");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it/labgrid/place.sh");
    let mut child = Command::new("unshare")
        .arg("-n")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_ppmc"))
        .arg(&bin)
        .arg(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("unshare runs");
    // Read the output on the side, so a full pipe never stalls the farm.
    let stdout = child.stdout.take().expect("piped");
    let stderr = child.stderr.take().expect("piped");
    let out = std::thread::spawn(move || std::io::read_to_string(stdout).unwrap_or_default());
    let err = std::thread::spawn(move || std::io::read_to_string(stderr).unwrap_or_default());
    let status = wait_bounded(&mut child, Duration::from_secs(240));
    let (out, err) = (
        out.join().expect("stdout read"),
        err.join().expect("stderr read"),
    );
    let logs = || {
        [
            "coordinator.log",
            "exporter.log",
            "bridge-sim.log",
            "run.err",
        ]
        .iter()
        .map(|f| format!("--- {f}\n{}", read(dir.path(), f)))
        .collect::<String>()
    };
    assert!(
        status.success(),
        "the farm script failed: {status}\n{out}\n{err}\n{}",
        logs()
    );
    assert!(
        mark(&out, "resources").contains("bench1/bridge/NetworkSerialPort"),
        "the exporter published no port:\n{out}\n{}",
        logs()
    );

    // Not acquired: an infrastructure error that says what to do, nothing
    // run, nothing blamed on the board.
    assert_eq!(mark(&out, "unacquired-exit"), "1");
    let refused = read(dir.path(), "unacquired.err");
    assert!(
        refused.contains("infrastructure error: labgrid:rig1")
            && refused.contains("not acquired")
            && refused.contains("labgrid-client -p rig1 acquire"),
        "{refused}"
    );
    assert!(
        read(dir.path(), "unacquired.out").contains("0 failed, 0 errors, 96 not run"),
        "{}",
        read(dir.path(), "unacquired.out")
    );

    // Acquired: the whole suite passes through labgrid's ser2net (RFC 2217).
    let run = read(dir.path(), "run.out");
    assert_eq!(mark(&out, "run-exit"), "0", "{run}\n{}", logs());
    assert!(
        run.ends_with("suite: 96 passed, 0 failed, 0 errors, 0 not run\n"),
        "{run}"
    );
    let junit = read(dir.path(), "report.xml");
    assert_eq!(junit.matches("<testcase ").count(), 96);
    assert!(
        junit.contains("value=\"labgrid:rig1 (rfc2217://127.0.0.1:"),
        "the report names the place and the port labgrid gave:\n{}",
        &junit[..junit.len().min(2000)]
    );
    // The labgrid-client ppmc started to learn the port is gone.
    assert_eq!(mark(&out, "exports-left"), "0", "{}", text(err.as_bytes()));

    // Two places in one run: the suite spread over both, each test case
    // naming its place.
    let two = read(dir.path(), "two/run.out");
    assert_eq!(
        mark(&out, "two-exit"),
        "0",
        "{two}\n{}",
        read(dir.path(), "two/run.err")
    );
    assert!(
        two.contains("suite: 95 passed, 0 failed, 0 errors, 0 not run\n"),
        "{two}"
    );
    assert!(
        two.contains("\nboard labgrid:rig1: ") && two.contains("\nboard labgrid:rig2: "),
        "{two}"
    );
    let junit = read(dir.path(), "two/report.xml");
    assert!(
        junit.contains("name=\"board.labgrid:rig2.board_rev\" value=\"C1\""),
        "{junit}"
    );
    assert_eq!(junit.matches("name=\"board_of.").count(), 95);
    assert_eq!(mark(&out, "exports-left-two"), "0");
    // Leases (issue 44): a place ppmc acquired is released when the run
    // passes and when it is stopped; a run killed outright leaves a lock
    // that the next run names by owner and age, and --steal-stale takes.
    assert_eq!(
        mark(&out, "lease-ok-exit"),
        "0",
        "{}",
        read(dir.path(), "lease/ok.err")
    );
    assert_eq!(mark(&out, "lease-after-ok"), "None");
    assert_eq!(
        mark(&out, "lease-int-exit"),
        "130",
        "{}",
        read(dir.path(), "lease/int.err")
    );
    assert_eq!(mark(&out, "lease-after-int"), "None");
    assert_ne!(
        mark(&out, "lease-after-kill"),
        "None",
        "a killed run cannot let go"
    );
    let pid = mark(&out, "lease-killed-pid");
    assert_eq!(mark(&out, "lease-stale-exit"), "1");
    let says = mark(&out, "lease-stale-says");
    assert!(
        says.contains(&format!("by ppmc pid {pid} on "))
            && says.contains(" s: that process is gone, and left its lock; --steal-stale takes it"),
        "{says}"
    );
    assert_eq!(
        mark(&out, "lease-steal-exit"),
        "0",
        "{}",
        mark(&out, "lease-steal-says")
    );
    assert!(mark(&out, "lease-steal-says").contains("took a stale lock"));
    assert_eq!(mark(&out, "lease-after-steal"), "None");
    // Recovery by power (issue 44): rig3's bridge hangs mid-run; labgrid's
    // ExternalPowerDriver restarts it, and every other scenario is graded.
    let run = read(dir.path(), "power/run.out");
    let why = || format!("{run}\n{}\n{}", read(dir.path(), "power/run.err"), logs());
    assert_eq!(mark(&out, "power-exit"), "1", "{}", why());
    assert!(
        run.ends_with("suite: 94 passed, 0 failed, 1 errors, 0 not run\n"),
        "{}",
        why()
    );
    let hang = run
        .lines()
        .find(|l| l.contains("infrastructure error: the board hung: "))
        .unwrap_or_else(|| panic!("no hang named: {}", why()));
    assert!(
        hang.contains("its bridge stopped answering (labgrid:rig3 (rfc2217://127.0.0.1:")
            && hang.ends_with(
                "power-cycled by `labgrid-client -p rig3 power cycle` (1 of 3), and the run went on"
            ),
        "{hang}"
    );
    assert_eq!(mark(&out, "power-starts"), "2", "one power cycle");
    assert_eq!(mark(&out, "power-after"), "None", "the place let go");
}
