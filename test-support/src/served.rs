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
    pub fn target_with(&self, opts: BridgeOptions) -> BridgeTarget<SerialLink> {
        let path = self.link.to_str().expect("utf-8 path");
        BridgeTarget::open(
            SerialLink::open(path, 115_200).expect("the pty opens"),
            opts,
        )
        .expect("the bridge answers HELLO")
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
