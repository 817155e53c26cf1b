//! The bridge firmware on a virtual microcontroller: `firmware/run-qemu`
//! boots the firmware image (a Cortex-M4, QEMU's mps2-an386) with the
//! reference model as its chip, and the whole suite runs through the
//! firmware's UART on a pseudo-terminal, as it would through a board's USB.
//!
//! Needs qemu-system-arm and Debian's Rust for the Cortex-M target
//! (firmware/README.md). Without them the tests say so and pass, except in
//! CI (`CI` set), where `.ci/run` installs them and their absence fails.

mod common;

use common::served::{only_error_3_fails, Served};
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Verdict};
use std::path::Path;
use std::process::{Command, Stdio};

/// Whether this machine can build and run the firmware; in CI it must.
fn available() -> bool {
    let qemu = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    let rust = Path::new("/usr/lib/rustlib/src/rust/library").is_dir();
    if !(qemu && rust) {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must run the firmware on QEMU: .ci/run installs qemu-system-arm and Debian's Rust"
        );
        eprintln!("qemu-system-arm or Debian's Rust is missing: the firmware is not run");
    }
    qemu && rust
}

#[test]
fn the_whole_suite_through_the_firmware_equals_the_in_process_run() {
    if !available() {
        return;
    }
    let board = Served::start("run-qemu", &[]);
    let mut t = board.target();
    let hello = t.hello().clone();
    assert!(
        hello.firmware.starts_with("ppmc-bridge-qemu "),
        "{}",
        hello.firmware
    );
    assert!(hello.virtual_time);
    assert_eq!(hello.capture_capacity, 50_000, "what the heap holds");
    let over = run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        DriverOptions::default(),
        |_| {},
    );
    let local = common::suite_in_process();
    assert_eq!(over.len(), local.len());
    for (a, b) in over.iter().zip(&local) {
        assert_eq!(a.verdict, b.verdict, "{}", a.name);
        assert_eq!(a.verdict, Verdict::Passed, "{}", a.name);
        let (ta, tb) = (
            a.trace.as_ref().expect("trace"),
            b.trace.as_ref().expect("trace"),
        );
        assert_eq!(
            ta.events, tb.events,
            "{}: same trace through the firmware",
            a.name
        );
    }
    drop(t);
    let link = board.link.clone();
    drop(board);
    assert!(!link.exists(), "run-qemu removes its link when stopped");
}

#[test]
fn a_chip_fault_in_the_virtual_chip_is_caught_and_straps_come_from_the_board() {
    if !available() {
        return;
    }
    let board = Served::start(
        "run-qemu",
        &["--chip-fault", "swap-error-3-4", "--clock-mhz", "12"],
    );
    let mut t = board.target();
    assert_eq!(t.hello().straps.sysclk_hz, 12_000_000);
    only_error_3_fails(&mut t);
}

/// At most once across reconnects, in the firmware: the connection to the
/// virtual board cut at every frame boundary of a scenario in turn,
/// through a proxy that keeps its own connection to the board's UART, as
/// ser2net does (`docs/bridge-protocol.md` section 3).
#[test]
fn a_connection_cut_at_every_frame_boundary_changes_no_verdict_on_the_firmware() {
    if !available() {
        return;
    }
    let board = Served::start("run-qemu", &[]);
    let path = board.link.to_str().expect("utf-8 path").to_string();
    let frames = common::drop_at_every_frame(
        ppmc::chaos::Upstream::Serial(path),
        // A move and its capture: batches, waits and fragmented replies.
        &["s3_2_2_ramp_runs_from_rl_to_rh"],
    );
    assert!(frames >= 10, "{frames} frames");
}
