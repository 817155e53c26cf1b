//! A bridge served on a pseudo-terminal by a script of `firmware/`
//! (`run-qemu`, `run-twin`): started in its own process group with
//! `--link`, reached through the link, stopped with SIGTERM (so that it
//! stops what it started and removes its link) when dropped.

use ppmc::backend::{BridgeOptions, BridgeTarget, SerialLink, Target};
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Verdict};
use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

pub struct Served {
    child: Child,
    pub link: PathBuf,
    _dir: tempfile::TempDir,
}

impl Served {
    /// Starts `firmware/<script>` with `args`, and waits until it says it
    /// serves (`<script>: serving on /dev/...`).
    pub fn start(script: &str, args: &[&str]) -> Served {
        let dir = tempfile::tempdir().expect("scratch dir");
        let link = dir.path().join("bridge");
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut child = Command::new(repo.join("firmware").join(script))
            .arg("--link")
            .arg(&link)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .process_group(0)
            .spawn()
            .unwrap_or_else(|e| panic!("{script} starts: {e}"));
        let stdout = child.stdout.take().expect("piped");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                if tx.send(line.unwrap_or_default()).is_err() {
                    break;
                }
            }
        });
        // Held from here on, so that a panic below stops what it started.
        let mut served = Served {
            child,
            link,
            _dir: dir,
        };
        // Building the image the first time takes a minute or two.
        let first = match rx.recv_timeout(Duration::from_secs(400)) {
            Ok(line) => line,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                panic!("{script} did not say where it serves within 400 s")
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => panic!(
                "{script} ended before saying where it serves ({:?}; its stderr is above)",
                served.child.wait()
            ),
        };
        assert!(
            first.starts_with(&format!("{script}: serving on /dev/")),
            "unexpected first line `{first}`"
        );
        assert!(served.link.exists(), "the link is there");
        assert!(served.child.try_wait().expect("wait").is_none());
        served
    }

    /// A serial target on the link, past HELLO.
    pub fn target(&self) -> BridgeTarget<SerialLink> {
        self.target_with(BridgeOptions::default())
    }

    /// [`Served::target`] with `opts`.
    ///
    /// A port just let go of may still be locked for a moment: the lock
    /// (serialport's `flock`) belongs to the open file, and a child that
    /// another test thread forks in that moment holds a copy until its
    /// `exec` closes it (CI found the QEMU board's port busy so when a
    /// test opened it again at once). Busy is tried again for up to 5 s.
    pub fn target_with(&self, opts: BridgeOptions) -> BridgeTarget<SerialLink> {
        let path = self.link.to_str().expect("utf-8 path");
        let began = std::time::Instant::now();
        let link = loop {
            match SerialLink::open(path, 115_200) {
                Err(e)
                    if e.kind() == std::io::ErrorKind::ResourceBusy
                        && began.elapsed() < Duration::from_secs(5) =>
                {
                    std::thread::sleep(Duration::from_millis(50));
                }
                other => break other.expect("the pty opens"),
            }
        };
        BridgeTarget::open(link, opts).expect("the bridge answers HELLO")
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        // The whole group: the script and what it started.
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

/// Runs the error scenarios on `t`, a bridge whose chip swaps error codes
/// 3 and 4 (`--chip-fault swap-error-3-4`): exactly the scenario that
/// proves error 3 must fail.
pub fn only_error_3_fails(t: &mut dyn Target) {
    let errors: Vec<_> = ppmc_scenarios::all()
        .into_iter()
        .filter(|s| s.has_tag("error"))
        .collect();
    let results = run_suite(t, &errors, 1, DriverOptions::default(), |_| {});
    let failed: Vec<&str> = results
        .iter()
        .filter(|r| matches!(r.verdict, Verdict::Failed(_)))
        .map(|r| r.name)
        .collect();
    assert_eq!(failed, ["e3_data_without_a_command"], "{results:#?}");
}

/// A host stopped (as by Ctrl-C) in the 16,777,216-step move on the
/// bridge `served`, then the next host on the same bridge: the first
/// host's ABORT stopped the bridge's batch
/// (`docs/bridge-protocol.md` section 5), so the next one opens at once
/// and runs. `short` names the scenario the next host runs. How long the
/// next host took to open is printed and returned; what is asserted is
/// that it opens and passes at all (a bridge left running the move
/// answers nothing for the rest of it, and the host gives up).
pub fn stopped_in_the_long_move_then_reopened(served: &Served, short: &str) -> Duration {
    use ppmc::stop::StopRequest;
    let stop = StopRequest::new();
    let mut first = served.target_with(BridgeOptions {
        stop: stop.clone(),
        ..BridgeOptions::default()
    });
    let long = vec![scenario("s3_3_4_accel_ffffff_is_16777216_steps")];
    let running = std::thread::spawn(move || {
        let r = run_suite(&mut first, &long, 1, DriverOptions::default(), |_| {});
        (r, first.link_stats())
    });
    // Into the move (or, on a slow bridge, still in its initialization:
    // a batch either way).
    std::thread::sleep(Duration::from_secs(3));
    stop.request();
    let (results, stats) = running.join().expect("the first host ends");
    let aborts = stats
        .unwrap_or_default()
        .into_iter()
        .find(|(k, _)| *k == "aborts")
        .map(|(_, v)| v);
    match &results[0].verdict {
        // A bridge in virtual time that is fast (the QEMU board: the
        // chip's ten minutes take it a second or two) was done before
        // the stop: nothing to abort.
        Verdict::Passed => assert_eq!(aborts, Some(0), "nothing ran to abort"),
        Verdict::NotRun(_) | Verdict::Error(_) => {
            assert_eq!(aborts, Some(1), "the first host sent ABORT")
        }
        other => panic!("the first host: {other:?}"),
    }
    let began = std::time::Instant::now();
    let mut next = served.target();
    let opened = began.elapsed();
    eprintln!(
        "{}: the next host opened in {opened:?}",
        served.link.display()
    );
    let short = vec![scenario(short)];
    let results = run_suite(&mut next, &short, 1, DriverOptions::default(), |_| {});
    assert_eq!(results[0].verdict, Verdict::Passed, "{results:#?}");
    opened
}

/// The suite's scenario of this name.
fn scenario(name: &str) -> ppmc::scenario::Scenario {
    ppmc_scenarios::all()
        .into_iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no scenario `{name}`"))
}
