//! The command line under the things users and CI do to it: a pipe that
//! closes, SIGINT in a long run, odd selections, a terminal or not.

use crate::common;

use common::{ppmc, scratch, text, wait_bounded};
use std::io::Read;
use std::process::{Command, Stdio};
use std::time::Duration;

/// `ppmc ARGS | head -0`: standard output closed before anything is read.
/// The pipe's reading end is closed before ppmc starts: closed after, a
/// run fast enough to write all its lines into the pipe's buffer first
/// would never see it closed.
fn with_closed_stdout(args: &[&str]) -> (std::process::ExitStatus, String) {
    // A connected pair of sockets stands for the pipe (std's own pipe is
    // newer than this crate's Rust): writing to one whose peer is closed
    // fails as a closed pipe does (EPIPE).
    let (reader, writer) = std::os::unix::net::UnixStream::pair().expect("a socket pair");
    drop(reader);
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(args)
        .stdout(std::os::fd::OwnedFd::from(writer))
        .stderr(Stdio::piped())
        .spawn()
        .expect("ppmc starts");
    let mut err = String::new();
    let mut stderr = child.stderr.take().expect("stderr");
    let status = wait_bounded(&mut child, Duration::from_secs(120));
    stderr.read_to_string(&mut err).expect("stderr");
    (status, err)
}

#[test]
fn a_closed_pipe_ends_list_and_run_quietly_and_run_still_writes_its_reports() {
    let (status, err) = with_closed_stdout(&["list"]);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(status.code(), Some(0), "{err}");

    let dir = scratch("behaves");
    let junit = dir.path().join("r.xml");
    // Passes enough that the run cannot end before its first line is
    // written: the scenarios run on a thread of their own, which on a busy
    // machine finished one pass of the suite (7 ms) before the line that
    // finds the pipe closed was written (CI, 2026-11-29).
    let (status, err) = with_closed_stdout(&[
        "run",
        "--junit",
        junit.to_str().expect("utf-8"),
        "--skip-tag",
        "long",
        "--repeat",
        "1000",
    ]);
    assert!(!err.contains("panicked"), "{err}");
    // Nobody reads: the run stops as on SIGINT, the rest not run.
    assert_eq!(status.code(), Some(130), "{err}");
    let xml = std::fs::read_to_string(&junit).expect("JUnit written");
    assert!(xml.contains("the run was interrupted"), "{xml}");
}

#[test]
fn sigint_in_a_soak_run_writes_both_reports_and_exits_non_zero() {
    let dir = scratch("behaves");
    let (junit, json) = (dir.path().join("s.xml"), dir.path().join("s.json"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args([
            "run",
            "--repeat",
            "1000000",
            "--skip-tag",
            "long",
            "--junit",
        ])
        .arg(&junit)
        .arg("--json")
        .arg(&json)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("ppmc starts");
    // Let it run some scenarios (their verdict lines arrive).
    let mut stdout = child.stdout.take().expect("stdout");
    let mut seen = Vec::new();
    let mut buf = [0u8; 4096];
    while seen.iter().filter(|&&b| b == b'\n').count() < 20 {
        let n = stdout.read(&mut buf).expect("read");
        assert!(n > 0, "ppmc ended early");
        seen.extend_from_slice(&buf[..n]);
    }
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let mut rest = String::new();
    stdout.read_to_string(&mut rest).expect("rest of stdout");
    let status = wait_bounded(&mut child, Duration::from_secs(60));
    assert_eq!(status.code(), Some(130), "{rest}");
    assert!(rest.contains("not run"), "{rest}");
    let xml = std::fs::read_to_string(&junit).expect("JUnit written");
    assert!(xml.contains("<testcase"), "{xml}");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("JSON written"))
            .expect("valid JSON");
    assert!(record["summary"]["passed"].as_u64().expect("passed") > 0);
}

#[test]
fn repeat_zero_is_refused_and_a_shard_past_the_end_is_empty() {
    let out = ppmc(&["run", "--repeat", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--repeat"));

    let out = ppmc(&["run", "--shard", "150/200"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("0 scenarios"),
        "{}",
        text(&out.stdout)
    );

    // A filter that matches nothing is still a mistake worth saying.
    let out = ppmc(&["run", "--filter", "no_such_scenario"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn skip_tag_leaves_out_the_long_scenario() {
    let all = text(&ppmc(&["list"]).stdout);
    let short = text(&ppmc(&["list", "--skip-tag", "long"]).stdout);
    assert!(
        all.contains("s3_3_4_accel_ffffff_is_16777216_steps"),
        "{all}"
    );
    assert!(
        !short.contains("s3_3_4_accel_ffffff_is_16777216_steps"),
        "{short}"
    );
    assert_eq!(all.lines().count(), short.lines().count() + 1);
}

#[test]
fn verdicts_are_coloured_only_when_asked() {
    let plain = ppmc(&["run", "--filter", "e0_undefined"]);
    assert!(!text(&plain.stdout).contains('\x1b'));
    let coloured = ppmc(&["run", "--filter", "e0_undefined", "--color", "always"]);
    assert!(
        text(&coloured.stdout).contains("\x1b[32mPASS\x1b[0m"),
        "{}",
        text(&coloured.stdout)
    );
}

/// Issue 29: `bridge-sim --help` listed the client's options (`--target`,
/// `--link-timeout`, `--link-retries`), which mean nothing to a server.
/// It takes the chip's straps and ramp only; the commands that drive a
/// target take all of them.
#[test]
fn bridge_sim_takes_the_chips_options_and_no_clients() {
    let help = |cmd: &str| {
        let out = ppmc(&[cmd, "--help"]);
        assert!(out.status.success(), "{cmd} --help");
        text(&out.stdout)
    };
    let sim = help("bridge-sim");
    for client in ["--target", "--link-timeout", "--link-retries"] {
        let listed = sim.lines().any(|l| l.trim_start().starts_with(client));
        assert!(!listed, "bridge-sim --help lists {client}");
    }
    for chip in [
        "--clock-mhz",
        "--csel",
        "--vsel",
        "--ext-clock-khz",
        "--accel-curve",
    ] {
        assert!(sim.contains(chip), "bridge-sim --help lacks {chip}");
    }
    for cmd in ["run", "record", "console", "selftest"] {
        let h = help(cmd);
        for flag in ["--target", "--link-timeout", "--clock-mhz", "--accel-curve"] {
            assert!(h.contains(flag), "{cmd} --help lacks {flag}");
        }
    }
    let out = ppmc(&["bridge-sim", "--target", "emu"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "an unknown option is a usage error"
    );
}

/// Issue 29: a script's `--help` printed lines of its code
/// (`scripts/network-figures`), or was not read at all and started the
/// work (`scripts/fuzz-figures` began building every fuzz target). Each
/// prints its header comment, and only that, and ends at once.
#[test]
fn each_scripts_help_is_its_header_comment_and_starts_nothing() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for script in [
        "scripts/network-figures",
        "scripts/fuzz-figures",
        "scripts/judge-figures",
        "scripts/campaign-figures",
    ] {
        let path = root.join(script);
        let source = std::fs::read_to_string(&path).expect("the script");
        let header: Vec<String> = source
            .lines()
            .skip(1)
            .take_while(|l| l.starts_with('#'))
            .map(|l| {
                l.trim_start_matches('#')
                    .strip_prefix(' ')
                    .unwrap_or(l.trim_start_matches('#'))
                    .to_string()
            })
            .collect();
        let mut child = Command::new(&path)
            .arg("--help")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the script runs");
        let status = wait_bounded(&mut child, Duration::from_secs(20));
        let mut out = String::new();
        let mut err = String::new();
        child
            .stdout
            .take()
            .expect("piped")
            .read_to_string(&mut out)
            .expect("stdout");
        child
            .stderr
            .take()
            .expect("piped")
            .read_to_string(&mut err)
            .expect("stderr");
        assert!(status.success(), "{script} --help: {status:?}\n{err}");
        assert!(err.is_empty(), "{script} --help started something:\n{err}");
        let printed: Vec<&str> = out.lines().collect();
        assert_eq!(printed, header, "{script} --help");
        let bad = Command::new(&path)
            .arg("--no-such-option")
            .output()
            .expect("runs");
        assert_eq!(bad.status.code(), Some(2), "{script}: an unknown option");
    }
}
