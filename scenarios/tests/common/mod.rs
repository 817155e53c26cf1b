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

/// A scratch folder named after `tag`, removed when dropped, even by a
/// failing test.
pub fn scratch(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("ppmc-{tag}-"))
        .tempdir()
        .expect("scratch dir")
}

/// Waits for `child` at most `limit`; kills it and fails the test past
/// that.
pub fn wait_bounded(
    child: &mut std::process::Child,
    limit: std::time::Duration,
) -> std::process::ExitStatus {
    let deadline = std::time::Instant::now() + limit;
    loop {
        if let Some(s) = child.try_wait().expect("wait") {
            return s;
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the child did not stop within {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}
