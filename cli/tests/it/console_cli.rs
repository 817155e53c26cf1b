//! The `ppmc console` binary as a user runs it.

use crate::common;

use common::text;
use std::io::Write;
use std::process::{Command, Output, Stdio};

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../docs/examples/accel-1000-steps.ppmc"
);

fn ppmc(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("ppmc starts");
    child
        .stdin
        .take()
        .expect("stdin piped")
        .write_all(stdin.as_bytes())
        .expect("script written");
    child.wait_with_output().expect("ppmc finishes")
}

/// Issue 2's acceptance script: 1,000 CW pulses, 42 us shortest interval,
/// finish status 0x83.
#[test]
fn example_script_moves_1000_steps_cw() {
    let out = ppmc(&["console", EXAMPLE], "");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("pulses count=1000 cw=1000 ccw=0 "),
        "{stdout}"
    );
    assert!(stdout.contains(" min=42.000us "), "{stdout}");
    assert!(stdout.contains("\nrd 0x83 at "), "{stdout}");
    insta::assert_snapshot!("accel_1000_steps", stdout);
}

#[test]
fn same_script_gives_byte_identical_output() {
    let a = ppmc(&["console", EXAMPLE], "");
    let b = ppmc(
        &["console", "-"],
        &std::fs::read_to_string(EXAMPLE).expect("example"),
    );
    assert_eq!(a.stdout, b.stdout);
    assert!(!a.stdout.is_empty());
}

#[test]
fn a_bad_line_stops_with_its_number_and_exit_2_before_anything_runs() {
    let out = ppmc(&["console", "-e", "rs\nrs\nwc 0x1FF\nrs"], "");
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        text(&out.stderr).trim(),
        "line 3: `0x1FF` is out of range for a byte (0..=255)"
    );
    assert!(out.stdout.is_empty(), "nothing ran: {}", text(&out.stdout));
}

#[test]
fn a_bad_line_in_a_file_names_the_file() {
    let scratch = common::scratch("console");
    let dir = scratch.path();
    let f = dir.join("bad.ppmc");
    std::fs::write(&f, "# ok\nfrobnicate\n").expect("script");
    let out = ppmc(&["console", f.to_str().expect("utf-8 path")], "");
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("bad.ppmc: line 2: unknown op `frobnicate`"),
        "{err}"
    );
}

#[test]
fn stdin_script_and_result_lines() {
    let out = ppmc(
        &["console"],
        "rs\nwc 0x87\nawait ibf=0 100us\nrs\nnow\npins\nrd!\n",
    );
    assert!(out.status.success());
    assert_eq!(
        text(&out.stdout),
        "rs 0x00 at 0.000us\nawait ibf=0 after 6.000us at 6.000us\nrs 0x80 at 6.000us\n\
         now at 6.000us\npins int=0 hold=0 aux=0 auxo=0b0000 s=0b00000 dir=cw at 6.000us\n\
         rd 0x00 at 6.000us\n"
    );
}

#[test]
fn timeouts_are_results_not_errors() {
    let out = ppmc(
        &["console", "--obf-timeout", "1ms"],
        "rd\nawait busy=1 2ms\n",
    );
    assert!(out.status.success());
    assert_eq!(
        text(&out.stdout),
        "rd timeout obf=0 at 1000.000us\nawait busy=1 timeout at 3000.000us\n"
    );
}

#[test]
fn unknown_target_and_bad_straps_are_usage_errors() {
    let out = ppmc(&["console", "--target", "jtag", "-e", "rs"], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unknown target `jtag`"));
    let out = ppmc(&["console", "--clock-mhz", "0.1", "-e", "rs"], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("system clock"));
}

#[test]
fn straps_change_the_pulse_rate() {
    let script = "wc 0x02; wd 100; wd 20; wd 100; wd 0; wait 200ms; wc 0x44; wd 9; wd 9; wd 0; wd 0\nawait busy=1 1ms; await busy=0 1s; pulses";
    let out = ppmc(&["console", "--csel", "low", "-e", script], "");
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("count=10 cw=10 ccw=0"),
        "{}",
        text(&out.stdout)
    );
    assert!(
        text(&out.stdout).contains("min=80.000us max=80.000us"),
        "{}",
        text(&out.stdout)
    );
}

/// docs/examples/chop-period.sh as docs/console.md shows it: Diagram 3-5
/// (Section 3-5-1) from the stamps of the console's pin samples, on the
/// emulator exactly, and through a bridge (`ppmc bridge-sim`, whose timer
/// ticks every 1 ns) with the stamps' uncertainty printed and the same
/// stretches.
#[test]
fn the_chop_period_example_measures_diagram_3_5_from_the_stamps() {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/examples/chop-period.sh"
    );
    let run = |args: &[&str]| {
        let out = Command::new(script)
            .args(args)
            .env("PPMC", env!("CARGO_BIN_EXE_ppmc"))
            .output()
            .expect("the script runs");
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    let emu = run(&[]);
    let want = "off 108.750us\non 65.000us\noff 108.750us\non 65.000us\n";
    assert!(emu.starts_with(want), "{emu}");
    let sim = common::BridgeSim::start(&[]);
    let board = run(&["--target", &sim.target()]);
    assert!(board.starts_with(want), "{board}");
    // The stamps a bridge gives carry its U.
    let out = ppmc(&["console", "--target", &sim.target()], "pins\n");
    assert!(
        text(&out.stdout).trim_end().ends_with(" \u{b1}0.001us"),
        "{}",
        text(&out.stdout)
    );
}
