//! `ppmc fuzz reproduce` from the command line.

use std::path::Path;
use std::process::{Command, Output};

fn ppmc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(args)
        .output()
        .expect("ppmc runs")
}

#[test]
fn reproduce_prints_a_console_script_of_a_corpus_input() {
    let seed = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus/bus_bytes/e0_decel_stop_while_stopped.bin");
    let out = ppmc(&["fuzz", "reproduce", seed.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(0), "breaks nothing: exit 0");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("# breaks no invariant"), "{text}");
    // The decelerating stop written while stopped (Section 3-3-2) is there.
    assert!(text.lines().any(|l| l == "wc! 0x41"), "{text}");
    let lines = ppmc::console::parse_script(&text).expect("a valid console script");
    assert!(lines.len() > 5);
}

#[test]
fn reproduce_of_a_missing_file_is_a_usage_error_naming_it() {
    let out = ppmc(&["fuzz", "reproduce", "no/such/crash-file"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert!(err.contains("no/such/crash-file"), "{err}");
}
