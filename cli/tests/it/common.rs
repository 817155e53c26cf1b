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

/// A `ppmc bridge-sim` child process, killed when dropped.
///
/// The host reaches it through a link of its own (`--link`), as it reaches
/// a board through a stable device path: a pseudo-terminal's number is
/// reused as soon as it is free, so a host still reconnecting after its
/// bridge went away could otherwise open another test's bridge.
pub struct BridgeSim {
    pub child: std::process::Child,
    path: String,
    _stdout: std::io::BufReader<std::process::ChildStdout>,
    _dir: Option<tempfile::TempDir>,
}

impl BridgeSim {
    pub fn start(args: &[&str]) -> BridgeSim {
        let dir = scratch("clibridge");
        let link = dir.path().join("pty");
        let mut sim = BridgeSim::start_at(&link, args);
        sim._dir = Some(dir);
        sim
    }

    /// A bridge-sim whose link is `link`.
    pub fn start_at(link: &std::path::Path, args: &[&str]) -> BridgeSim {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ppmc"))
            .arg("bridge-sim")
            .arg("--link")
            .arg(link)
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("bridge-sim starts");
        let stdout = child.stdout.take().expect("stdout piped");
        let mut reader = std::io::BufReader::new(stdout);
        let mut first = String::new();
        std::io::BufRead::read_line(&mut reader, &mut first).expect("bridge-sim prints its pty");
        assert!(
            first.trim().starts_with("bridge-sim: serving on /dev/"),
            "unexpected first line `{first}`"
        );
        BridgeSim {
            child,
            path: link.to_str().expect("utf-8 path").to_string(),
            _stdout: reader,
            _dir: None,
        }
    }

    pub fn target(&self) -> String {
        format!("serial:{}", self.path)
    }
}

impl Drop for BridgeSim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The JSON Schema of the run record, `docs/run-record.schema.json`.
pub fn run_record_schema() -> jsonschema::Validator {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/run-record.schema.json");
    let schema: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("schema")).expect("JSON");
    jsonschema::validator_for(&schema).expect("a valid schema")
}

/// Fails with every schema error of `record`, each with where it is.
pub fn check_record(validator: &jsonschema::Validator, record: &serde_json::Value) {
    let errors: Vec<String> = validator
        .iter_errors(record)
        .map(|e| format!("{} at {}", e, e.instance_path))
        .collect();
    assert!(errors.is_empty(), "{errors:#?}");
}

pub use ppmc_test_support::sigrok_cli;
