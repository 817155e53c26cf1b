//! The bridge firmware on a virtual microcontroller: `firmware/run-qemu`
//! boots the firmware image (a Cortex-M4, QEMU's mps2-an386) with the
//! reference model as its chip, and the whole suite runs through the
//! firmware's UART on a pseudo-terminal, as it would through a board's USB.
//!
//! Needs qemu-system-arm and Debian's Rust for the Cortex-M target
//! (firmware/README.md). Without them the tests say so and pass, except in
//! CI (`CI` set), where `.ci/run` installs them and their absence fails.
//! The test of `run-qemu --help` needs neither.

use ppmc_test_support as common;

use common::served::{only_error_3_fails, Served};
use ppmc::backend::{BridgeError, Op, Reply, Target, TargetError};
use ppmc::protocol::Direction::{Ccw, Cw};
use ppmc::protocol::Flag;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Init, Move, Verdict};
use ppmc::time::Duration;
use std::path::Path;
use std::process::{Command, Stdio};

/// Records the board's capture holds (`ppmc_bridge_fw::limits::CAPTURE_RECORDS`,
/// firmware/README.md): the QEMU board keeps the RP2350 board's heap and
/// capture, so that it shows what the board does when they fill.
const BOARD_CAPTURE_RECORDS: u32 = 748;

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

/// `run-qemu --help` prints the comment at the script's top and nothing
/// else: every line it prints is a line of that comment, less its `# `
/// (no line of the script's code, as `set -euo pipefail` once was). Needs
/// neither QEMU nor the image: the options are read first.
#[test]
fn run_qemu_help_prints_its_header_comment_and_no_line_of_code() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/run-qemu");
    let source = std::fs::read_to_string(&script).expect("firmware/run-qemu");
    let header: Vec<&str> = source
        .lines()
        .skip(1)
        .take_while(|l| l.starts_with('#'))
        .collect();
    let out = Command::new(&script)
        .arg("--help")
        .output()
        .expect("run firmware/run-qemu --help");
    assert!(out.status.success(), "{out:?}");
    let help = String::from_utf8(out.stdout).expect("utf-8 help");
    let lines: Vec<&str> = help.lines().collect();
    assert_eq!(lines.len(), header.len(), "{help}");
    for (printed, comment) in lines.iter().zip(&header) {
        let bare = comment.strip_prefix("# ").or(comment.strip_prefix('#'));
        assert_eq!(
            Some(*printed),
            bare,
            "a line of --help that is not the header's:\n{help}"
        );
    }
    assert!(
        help.starts_with("Runs the bridge firmware on a virtual board"),
        "{help}"
    );
    for option in [
        "--clock-mhz",
        "--csel",
        "--vsel",
        "--ext-clock-khz",
        "--chip-fault",
        "--link",
    ] {
        assert!(help.contains(option), "--help names {option}:\n{help}");
    }
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
    assert_eq!(
        hello.capture_capacity, BOARD_CAPTURE_RECORDS,
        "the board's capture"
    );
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
        // The same events; each measurement through the firmware carries
        // the board's uncertainty, which the exact model's does not.
        assert_eq!(
            common::values_of(ta).0,
            common::values_of(tb).0,
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

/// The ops that write `code` and its data bytes, each waiting for IBF.
fn command(code: u8, data: &[u8]) -> Vec<Op> {
    let wait_ibf = Some(Duration::from_secs(1));
    let mut ops = vec![Op::WriteCommand {
        byte: code,
        wait_ibf,
    }];
    ops.extend(data.iter().map(|&byte| Op::WriteData { byte, wait_ibf }));
    ops
}

/// The bridge's CAPTURE_OVERRUN, as the host reports it: an error of the
/// capture, not a failure of the device.
fn is_capture_overrun(e: &TargetError) -> bool {
    matches!(
        e.get_ref().downcast_ref::<BridgeError>(),
        Some(BridgeError::CaptureOverrun { detail, .. })
            if detail.contains(&format!("the buffer holds {BOARD_CAPTURE_RECORDS}"))
    )
}

/// A ramped move of `steps` after initializing with `init`, waited out,
/// and the capture after it.
fn ramped_move(
    t: &mut dyn Target,
    init: Init,
    steps: u32,
    dir: ppmc::protocol::Direction,
) -> Result<ppmc::protocol::OutputRecord, TargetError> {
    let mut ops = command(init.code(), &init.data.to_bytes());
    ops.push(Op::Delay(Duration::from_millis(300)));
    let m = Move::accel(dir, steps);
    ops.extend(command(m.code(), &m.params()));
    ops.push(Op::await_flag(Flag::Busy, true, Duration::from_secs(1)));
    ops.push(Op::await_flag(Flag::Busy, false, Duration::from_secs(10)));
    let replies = t.execute(&ops)?;
    assert!(
        matches!(replies.last(), Some(Reply::Awaited { .. })),
        "the move ended: {replies:?}"
    );
    t.capture()
}

/// The board's limits on the virtual board: ramped moves, each step of a
/// ramp its own pulse run (the heaviest record, 32 bytes on the board),
/// fill the capture to just under its capacity, then a long ramp (about
/// 470 runs, in one wait) takes it past: the bridge answers
/// CAPTURE_OVERRUN, as the host reports it (the scenario's error, not the
/// device's), has not run out of heap with the capture at its largest
/// (the pulse runs' `Vec` grown to 2,048), and serves on, the next chip
/// reset emptying the capture. With the QEMU board's old 3 MiB heap and
/// 50,000 records the capture does not fill here; with the board's old
/// 4,096 records on its heap the board stops (a failed allocation is a
/// panic) at its 2,049th pulse run.
#[test]
fn a_capture_heavy_run_fills_the_capture_before_the_heap_and_the_board_serves_on() {
    if !available() {
        return;
    }
    let board = Served::start("run-qemu", &[]);
    let mut t = board.target();
    let session = t.hello().session;
    assert_eq!(t.hello().capture_capacity, BOARD_CAPTURE_RECORDS);
    let capacity = BOARD_CAPTURE_RECORDS as usize;
    t.execute(&[Op::Reset]).expect("a chip reset");
    // RL 254 to RH 20: 83 pulse runs in a move of 200 steps (PA 100), 469
    // in one of 22,440 (PA 11,220), with a few pin changes and a move
    // record each.
    let short = Init::four_phase().rates(254, 20);
    let long = short.accel_pulses(11_220);
    let (mut moves, mut held, mut runs) = (0, 0, 0);
    let overrun = loop {
        assert!(
            moves < 40,
            "the capture never filled: {held} records after {moves} moves"
        );
        let dir = if moves % 2 == 0 { Cw } else { Ccw };
        let ran = if held + 100 <= capacity {
            ramped_move(&mut t, short, 200, dir)
        } else {
            ramped_move(&mut t, long, 22_440, dir)
        };
        match ran {
            Ok(rec) => {
                held = rec.runs.len() + rec.pins.len() + rec.moves.len();
                runs = rec.runs.len();
                assert!(held <= capacity, "{held} records");
                moves += 1;
            }
            Err(e) => break e,
        }
    };
    assert!(is_capture_overrun(&overrun), "{overrun}");
    // The long ramp came to a capture near its capacity, with more than
    // 555 runs: its 469 more took the runs' `Vec` past 1,024, to 2,048.
    assert!(
        held > capacity - 100 && runs > 1_024 - 469,
        "{held} records, {runs} runs"
    );
    // Overrun until the next chip reset: the capture, and a batch without
    // a reset, are answered so.
    let again = t.capture().expect_err("the capture is still overrun");
    assert!(is_capture_overrun(&again), "{again}");
    let status = t.execute(&[Op::ReadStatus]).expect_err("overrun");
    assert!(is_capture_overrun(&status), "{status}");
    // A chip reset empties it, and the board serves on.
    let mut ops = vec![Op::Reset];
    ops.extend(command(short.code(), &short.data.to_bytes()));
    ops.push(Op::Delay(Duration::from_millis(300)));
    let m = Move::single_step(Cw);
    ops.extend(command(m.code(), &m.params()));
    ops.push(Op::Delay(Duration::from_millis(5)));
    t.execute(&ops)
        .expect("the board serves on after a chip reset");
    let rec = t.capture().expect("a capture again");
    assert_eq!((rec.moves.len(), rec.pulse_count()), (1, 1), "{rec:?}");
    drop(t);
    // The same board: it did not restart.
    assert_eq!(board.target().hello().session, session);
}

/// Ctrl-C during the 16,777,216-step move, then the next host on the
/// QEMU board: it opens at once (`docs/bridge-protocol.md` section 5).
#[test]
fn after_a_stop_in_the_long_move_the_next_host_opens_the_qemu_board_at_once() {
    if !available() {
        return;
    }
    let board = Served::start("run-qemu", &[]);
    common::served::stopped_in_the_long_move_then_reopened(&board, "e3_data_without_a_command");
}
