//! Running another program for a board (labgrid's client, a power switch)
//! with a bound: its output, or an error that names the command and says
//! why (it could not start, it failed and what it said last, it did not
//! answer in time and was killed).

use std::io;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `cmd` (shown in messages as `shown`), at most `limit`, its input
/// closed: its standard output when it succeeds. A program that does not
/// end in time is killed; one that fails gives its last line of complaint.
pub(crate) fn run_within(cmd: &mut Command, shown: &str, limit: Duration) -> io::Result<String> {
    // A process group of its own: a terminal's Ctrl-C meant for ppmc does
    // not cut a power switch off half way, and a program that does not end
    // in time is stopped with everything it started.
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(cmd, 0);
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| io::Error::new(e.kind(), format!("cannot run `{shown}`: {e}")))?;
    // Both pipes drained on the side, so a chatty program never blocks.
    // A program that leaves something running behind it (a power script
    // that restarts a service) may leave the pipes open: its output is
    // then what arrived by a moment after it ended.
    let out = drain(child.stdout.take());
    let err = drain(child.stderr.take());
    let end = Instant::now() + limit;
    let status = loop {
        let ended = child.try_wait();
        if let Ok(Some(s)) = ended {
            break s;
        }
        if ended.is_err() || Instant::now() >= end {
            stop_group(&mut child);
            return Err(match ended {
                Err(e) => io::Error::new(e.kind(), format!("`{shown}`: {e}")),
                Ok(_) => io::Error::new(
                    io::ErrorKind::TimedOut,
                    format!("`{shown}` did not answer within {limit:?}"),
                ),
            });
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (text, err) = (out.collect(), err.collect());
    if !status.success() {
        let why = err
            .lines()
            .chain(text.lines())
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        let why = match why.trim() {
            "" => format!("{status}"),
            line => format!("{status}: {line}"),
        };
        return Err(io::Error::other(format!("`{shown}` failed ({why})")));
    }
    Ok(text)
}

/// Kills `child` and every process of its group (what a shell started),
/// and reaps it.
fn stop_group(child: &mut std::process::Child) {
    #[cfg(unix)]
    let _ = Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    let _ = child.kill();
    let _ = child.wait();
}

/// A pipe read to its end on a thread of its own.
struct Drained {
    text: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
    done: std::sync::mpsc::Receiver<()>,
}

fn drain(pipe: Option<impl io::Read + Send + 'static>) -> Drained {
    let text = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let (tx, done) = std::sync::mpsc::channel();
    if let Some(mut pipe) = pipe {
        let text = text.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n @ 1..) = pipe.read(&mut buf) {
                if let Ok(mut t) = text.lock() {
                    t.extend_from_slice(&buf[..n]);
                }
            }
            let _ = tx.send(());
        });
    }
    Drained { text, done }
}

impl Drained {
    /// What the pipe gave: all of it once it closes, or what arrived
    /// within a moment.
    fn collect(self) -> String {
        let _ = self.done.recv_timeout(Duration::from_millis(500));
        let bytes = self.text.lock().map(|t| t.clone()).unwrap_or_default();
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_failure_and_a_program_that_hangs_each_say_so() {
        let ok = run_within(
            Command::new("sh").args(["-c", "echo hi"]),
            "sh hi",
            Duration::from_secs(10),
        );
        assert_eq!(ok.expect("works"), "hi\n");
        let failed = run_within(
            Command::new("sh").args(["-c", "echo no such relay >&2; exit 3"]),
            "relay",
            Duration::from_secs(10),
        )
        .expect_err("fails")
        .to_string();
        assert!(
            failed.contains("`relay` failed (exit status: 3: no such relay)"),
            "{failed}"
        );
        // A program that hangs is stopped with what it started.
        let dir = tempfile::tempdir().expect("works");
        let pid = dir.path().join("pid");
        let hung = run_within(
            Command::new("sh")
                .arg("-c")
                .arg(format!("sleep 600 & echo $! > '{}'; wait", pid.display())),
            "relay 3",
            Duration::from_millis(500),
        )
        .expect_err("fails");
        assert_eq!(hung.kind(), io::ErrorKind::TimedOut);
        assert!(
            hung.to_string()
                .contains("`relay 3` did not answer within 500ms"),
            "{hung}"
        );
        let pid = std::fs::read_to_string(&pid).expect("works");
        let proc = std::path::Path::new("/proc").join(pid.trim());
        let gone = (0..100).any(|_| {
            std::thread::sleep(Duration::from_millis(20));
            !proc.exists()
                || std::fs::read_to_string(proc.join("stat")).is_ok_and(|s| s.contains(") Z "))
        });
        assert!(gone, "the program's child outlived it");
        let missing = run_within(
            &mut Command::new("/nonexistent/ppmc-power"),
            "ppmc-power",
            Duration::from_secs(1),
        )
        .expect_err("fails");
        assert!(
            missing.to_string().starts_with("cannot run `ppmc-power`"),
            "{missing}"
        );
    }

    /// A power script that restarts a service leaves it running with the
    /// script's pipes: the script's end is what counts, not the service's.
    #[test]
    fn a_program_that_leaves_a_child_holding_its_pipes_still_ends() {
        let said = run_within(
            Command::new("sh").args(["-c", "sleep 600 & echo $!"]),
            "restart",
            Duration::from_secs(60),
        )
        .expect("works");
        let pid = said.trim();
        let alive = std::path::Path::new("/proc").join(pid).exists();
        let _ = Command::new("kill").arg(pid).status();
        assert!(alive, "run_within waited for what the program left running");
    }
}
