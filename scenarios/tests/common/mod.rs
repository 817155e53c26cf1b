//! Helpers of the command-line tests.
#![allow(dead_code)] // each test file uses its own part

/// Runs the `ppmc` binary with `args`, as a user would from a shell.
pub fn ppmc(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(args)
        .output()
        .expect("ppmc runs")
}

/// Output bytes as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}
