//! The bridge firmware on a virtual microcontroller: `firmware/run-qemu`
//! boots the firmware image (a Cortex-M4, QEMU's mps2-an386) with the
//! reference model as its chip, and the whole suite runs through the
//! firmware's UART on a pseudo-terminal, as it would through a board's USB.
//!
//! Needs qemu-system-arm and Debian's Rust for the Cortex-M target
//! (firmware/README.md). Without them the tests say so and pass, except in
//! CI (`CI` set), where `.ci/run` installs them and their absence fails.

mod common;

use ppmc::backend::{SerialLink, SerialOptions, SerialTarget};
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Verdict};
use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

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

/// `firmware/run-qemu` in its own process group, stopped with SIGTERM (so
/// that it stops QEMU and removes its link) when dropped.
struct VirtualBoard {
    child: Child,
    link: PathBuf,
    _dir: tempfile::TempDir,
}

impl VirtualBoard {
    fn start(args: &[&str]) -> VirtualBoard {
        let dir = tempfile::tempdir().expect("scratch dir");
        let link = dir.path().join("bridge");
        let mut child = Command::new(repo().join("firmware/run-qemu"))
            .arg("--link")
            .arg(&link)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .process_group(0)
            .spawn()
            .expect("run-qemu starts");
        let stdout = child.stdout.take().expect("piped");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                if tx.send(line.unwrap_or_default()).is_err() {
                    break;
                }
            }
        });
        // Building the image the first time takes a minute or two.
        let first = rx
            .recv_timeout(Duration::from_secs(400))
            .expect("run-qemu says where it serves within the time limit");
        let mut board = VirtualBoard {
            child,
            link,
            _dir: dir,
        };
        assert!(
            first.starts_with("run-qemu: serving on /dev/"),
            "unexpected first line `{first}`"
        );
        assert!(board.link.exists(), "the link is there");
        assert!(board.child.try_wait().expect("wait").is_none());
        board
    }

    fn target(&self) -> SerialTarget<SerialLink> {
        let path = self.link.to_str().expect("utf-8 path");
        SerialTarget::open(
            SerialLink::open(path, 115_200).expect("the pty opens"),
            SerialOptions::default(),
        )
        .expect("the firmware answers HELLO")
    }
}

impl Drop for VirtualBoard {
    fn drop(&mut self) {
        // The whole group: run-qemu and the QEMU it started.
        let group = format!("-{}", self.child.id());
        let signal = |sig: &str| {
            let _ = Command::new("kill")
                .args([sig, "--", &group])
                .stderr(Stdio::null())
                .status();
        };
        signal("-TERM");
        let deadline = std::time::Instant::now() + Duration::from_secs(10);
        while self.child.try_wait().ok().flatten().is_none() {
            if std::time::Instant::now() > deadline {
                signal("-KILL");
                let _ = self.child.wait();
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

#[test]
fn the_whole_suite_through_the_firmware_equals_the_in_process_run() {
    if !available() {
        return;
    }
    let board = VirtualBoard::start(&[]);
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
    let board = VirtualBoard::start(&["--chip-fault", "swap-error-3-4", "--clock-mhz", "12"]);
    let mut t = board.target();
    assert_eq!(t.hello().straps.sysclk_hz, 12_000_000);
    let errors: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| s.has_tag("error"))
        .collect();
    let results = run_suite(&mut t, &errors, 1, DriverOptions::default(), |_| {});
    let failed: Vec<&str> = results
        .iter()
        .filter(|r| matches!(r.verdict, Verdict::Failed(_)))
        .map(|r| r.name)
        .collect();
    assert_eq!(failed, ["e3_data_without_a_command"], "{results:#?}");
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
    let board = VirtualBoard::start(&[]);
    let path = board.link.to_str().expect("utf-8 path").to_string();
    let frames = common::drop_at_every_frame(
        ppmc::chaos::Upstream::Serial(path),
        // A move and its capture: batches, waits and fragmented replies.
        &["s3_2_2_ramp_runs_from_rl_to_rh"],
    );
    assert!(frames >= 10, "{frames} frames");
}
