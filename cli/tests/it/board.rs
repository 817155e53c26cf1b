//! The hardware test group: a real board behind a bridge, off unless
//! `PPMC_BOARD` names its target (`PPMC_BOARD=serial:/dev/ttyACM0 cargo
//! test -p ppmc-cli --test it board::`; docs/bridge-hardware.md,
//! bring-up). Each test runs what a user runs, through the `ppmc` binary:
//!
//! - the suite without its long scenarios (the 16,777,216-step move takes
//!   11 minutes on a board);
//! - the same against the golden traces, within the default tolerances
//!   and `PPMC_TIME_FLOOR` (default 100ns) for the bridge's timer;
//! - with `PPMC_BOARD_LOOPBACK=1`, the capture's loop-back self-test: a
//!   jumper from the bridge's 100 kHz test signal (GPIO 25) to POUT's
//!   capture input, the chip's POUT off the net: 10 ms of capture must
//!   gain 1,000 pulses (one either way for where the window falls), all
//!   10 us apart within the capture's resolution.
//!
//! CI runs the first two against the firmware on its QEMU board
//! (`.ci/run`), so this group cannot rot while nobody has a board at hand.

use crate::common;

use common::{ppmc, text};

/// One board: its tests take turns (a serial port opens once at a time).
static BOARD: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The board's target and a turn at it, or `None` (and the test passes,
/// saying so).
fn board() -> Option<(String, std::sync::MutexGuard<'static, ()>)> {
    let b = std::env::var("PPMC_BOARD").ok().filter(|b| !b.is_empty());
    if b.is_none() {
        eprintln!("PPMC_BOARD is not set: no board to test");
    }
    let turn = BOARD.lock().unwrap_or_else(|e| e.into_inner());
    b.map(|b| (b, turn))
}

#[test]
fn the_suite_passes_on_the_board() {
    let Some((target, _turn)) = board() else {
        return;
    };
    let out = ppmc(&["run", "--target", &target, "--skip-tag", "long"]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains(" 0 failed, 0 errors, 0 not run"),
        "{stdout}"
    );
}

#[test]
fn the_board_matches_the_golden_traces() {
    let Some((target, _turn)) = board() else {
        return;
    };
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/../golden");
    let floor = std::env::var("PPMC_TIME_FLOOR").unwrap_or_else(|_| "100ns".into());
    let out = ppmc(&[
        "run",
        "--target",
        &target,
        "--skip-tag",
        "long",
        "--golden",
        golden,
        "--time-floor",
        &floor,
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
}

#[test]
fn the_capture_loop_back_counts_the_test_signal() {
    let Some((target, _turn)) = board() else {
        return;
    };
    if std::env::var("PPMC_BOARD_LOOPBACK").as_deref() != Ok("1") {
        eprintln!("PPMC_BOARD_LOOPBACK is not 1: the loop-back jumper is not fitted");
        return;
    }
    let out = ppmc(&[
        "console",
        "--target",
        &target,
        "-e",
        "pulses; wait 10ms; pulses",
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    // Two lines `pulses count=N cw=.. ccw=.. first=.. last=.. min=.. max=..`:
    // the capture since the chip's last reset, before and after 10 ms.
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("pulses "))
        .collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    let field = |line: &str, key: &str| {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .map(str::to_string)
            .unwrap_or_else(|| panic!("no {key} in `{line}`"))
    };
    let count = |line: &str| -> u64 { field(line, "count=").parse().expect("a count") };
    let n = count(lines[1]) - count(lines[0]);
    assert!((999..=1001).contains(&n), "{n} pulses in 10 ms: {stdout}");
    let us = |v: String| -> f64 { v.trim_end_matches("us").parse().expect("a time in us") };
    let (min, max) = (us(field(lines[1], "min=")), us(field(lines[1], "max=")));
    // 10 us, within the capture's resolution (13.3 ns at 75 MHz) and its
    // bound.
    assert!(
        (9.95..=10.05).contains(&min) && (9.95..=10.05).contains(&max),
        "{stdout}"
    );
}
