//! Boards on the network: a bridge's serial port served by ser2net (the
//! Debian package, with its default settings), reached as
//! `--target tcp://127.0.0.1:PORT` (raw) and `rfc2217://127.0.0.1:PORT`
//! (telnet with RFC 2217). ser2net listens on 127.0.0.1 only, in
//! front of a `ppmc bridge-sim`; every process is stopped at the end.
//!
//! Without ser2net the tests say so and pass, except in CI (`CI` set),
//! where `.ci/run` installs it and its absence fails.

use crate::common;

use common::{ppmc, scratch, text};
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn have_ser2net() -> bool {
    let found = Command::new("ser2net")
        .arg("-v")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must test the network targets with ser2net (apt install ser2net)"
        );
        eprintln!("ser2net is not installed: the tcp:// target is not tested");
    }
    found
}

/// A child process killed when dropped.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A bridge simulator and ser2net in front of its pty, on 127.0.0.1.
struct Served {
    /// One port per accepter, in the order given.
    ports: Vec<u16>,
    ser2net: Killed,
    _bridge: Killed,
    _dir: tempfile::TempDir,
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

impl Served {
    /// ser2net with `accepter` (`tcp` for raw, `telnet(rfc2217),tcp` for
    /// RFC 2217) on a free port of 127.0.0.1.
    fn start(accepter: &str) -> Served {
        Served::start_all(&[accepter])
    }

    /// ser2net with one connection per accepter, all to the same bridge:
    /// a lab that serves one board both raw and over RFC 2217.
    fn start_all(accepters: &[&str]) -> Served {
        let dir = scratch("ser2net");
        let mut bridge = Command::new(env!("CARGO_BIN_EXE_ppmc"))
            .args(["bridge-sim", "--link"])
            .arg(dir.path().join("pty"))
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("bridge-sim starts");
        let mut first = String::new();
        BufReader::new(bridge.stdout.take().expect("piped"))
            .read_line(&mut first)
            .expect("bridge-sim says where");
        let pty = first
            .trim()
            .strip_prefix("bridge-sim: serving on ")
            .expect("a pty")
            .to_string();
        let bridge = Killed(bridge);
        let ports: Vec<u16> = accepters.iter().map(|_| free_port()).collect();
        let config = dir.path().join("ser2net.yaml");
        let mut yaml = String::from("%YAML 1.1\n---\n");
        for (i, (accepter, port)) in accepters.iter().zip(&ports).enumerate() {
            yaml.push_str(&format!(
                "connection: &bridge{i}\n    accepter: {accepter},127.0.0.1,{port}\n    connector: serialdev,{pty},115200n81,local\n"
            ));
        }
        std::fs::write(&config, yaml).expect("config written");
        let ser2net = Killed(
            Command::new("ser2net")
                .arg("-n")
                .arg("-c")
                .arg(&config)
                .arg("-P")
                .arg(dir.path().join("ser2net.pid"))
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("ser2net starts"),
        );
        // Until it listens (bounded).
        let deadline = Instant::now() + Duration::from_secs(10);
        for &port in &ports {
            while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
                assert!(
                    Instant::now() < deadline,
                    "ser2net did not listen on {port}"
                );
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        // That probe connection is closed; give ser2net a moment to free
        // the port for the next client.
        std::thread::sleep(Duration::from_millis(100));
        Served {
            ports,
            ser2net,
            _bridge: bridge,
            _dir: dir,
        }
    }

    fn target(&self, scheme: &str) -> String {
        self.target_at(0, scheme)
    }

    fn target_at(&self, accepter: usize, scheme: &str) -> String {
        format!("{scheme}://127.0.0.1:{}", self.ports[accepter])
    }
}

/// The whole suite through ser2net with `accepter` as `--target
/// scheme://...`: it passes, with the same verdicts as the emulator's.
fn suite_through(accepter: &str, scheme: &str) {
    let served = Served::start(accepter);
    let out = ppmc(&["run", "--target", &served.target(scheme)]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains("suite: 96 passed, 0 failed, 0 errors, 0 not run"),
        "{stdout}"
    );
    assert_eq!(stdout, text(&ppmc(&["run"]).stdout));
}

#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn the_suite_passes_through_ser2net_with_its_defaults() {
    if have_ser2net() {
        suite_through("tcp", "tcp");
    }
}

/// RFC 2217 is telnet: bridge frames are full of 0xFF, which must be
/// escaped both ways, and the server negotiates options first.
#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn the_suite_passes_through_ser2net_in_rfc2217_mode() {
    if have_ser2net() {
        suite_through("telnet(rfc2217),tcp", "rfc2217");
    }
}

/// One bridge behind one ser2net, reached raw and over RFC 2217 in turn,
/// as a lab switches between its tools: every suite passes. (A host that
/// took the session of the HELLO it had not yet heard for a restart once
/// failed most of these switches.)
#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn alternating_raw_and_rfc2217_through_one_ser2net_passes_every_time() {
    if !have_ser2net() {
        return;
    }
    let served = Served::start_all(&["tcp", "telnet(rfc2217),tcp"]);
    for i in 0..20 {
        let target = match i % 2 {
            0 => served.target_at(0, "tcp"),
            _ => served.target_at(1, "rfc2217"),
        };
        let out = ppmc(&["run", "--target", &target]);
        let stdout = text(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(0),
            "switch {i} ({target}): {}{}",
            stdout.lines().last().unwrap_or_default(),
            text(&out.stderr)
        );
        assert!(
            stdout.contains("suite: 96 passed, 0 failed, 0 errors, 0 not run"),
            "switch {i}"
        );
    }
}

/// Issue 42: `tcp://` aimed at an RFC 2217 port failed with "corrupt
/// frames" and no word of telnet.
#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn a_raw_link_to_an_rfc2217_port_is_told_to_try_rfc2217() {
    if !have_ser2net() {
        return;
    }
    let served = Served::start("telnet(rfc2217),tcp");
    let out = ppmc(&[
        "run",
        "--filter",
        "s3_3_5_constant_speed_100_steps",
        "--target",
        &served.target("tcp"),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("infrastructure error"), "{stderr}");
    assert!(
        stderr.contains("try rfc2217:// in place of tcp://"),
        "{stderr}"
    );
}

#[test]
fn a_server_that_is_not_there_is_an_infrastructure_error() {
    let port = free_port();
    let out = ppmc(&["run", "--target", &format!("tcp://127.0.0.1:{port}")]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("infrastructure error"), "{stderr}");
    assert!(
        stderr.contains(&format!("tcp://127.0.0.1:{port}")),
        "{stderr}"
    );
    let bad = ppmc(&["run", "--target", "tcp://127.0.0.1"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(text(&bad.stderr).contains("tcp://<host>:<port>"));
}

/// The server goes away mid-run: the scenarios left are not run, blamed on
/// the infrastructure, never on the board, and the reports are written.
#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn a_connection_cut_mid_run_ends_it_as_an_infrastructure_error() {
    if !have_ser2net() {
        return;
    }
    let mut served = Served::start("tcp");
    let dir = scratch("cut");
    let junit = dir.path().join("report.xml");
    let mut run = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args([
            "run",
            "--repeat",
            "1000",
            "--link-timeout",
            "200ms",
            "--target",
        ])
        .arg(served.target("tcp"))
        .arg("--junit")
        .arg(&junit)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("ppmc runs");
    // Read both pipes while it runs: a thousand passes print a lot.
    let pipe = |mut r: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let out_t = pipe(Box::new(run.stdout.take().expect("piped")));
    let err_t = pipe(Box::new(run.stderr.take().expect("piped")));
    // Let it get going, then pull the plug.
    std::thread::sleep(Duration::from_millis(800));
    let _ = served.ser2net.0.kill();
    let _ = served.ser2net.0.wait();
    let status = common::wait_bounded(&mut run, Duration::from_secs(120));
    let stdout = out_t.join().unwrap_or_default();
    let stderr = err_t.join().unwrap_or_default();
    assert_eq!(status.code(), Some(1), "{stdout}{stderr}");
    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.contains(" 0 failed,"),
        "nothing blamed on the board: {last}"
    );
    assert!(!last.contains(" 0 not run"), "the rest is not run: {last}");
    // The scenario under way is an error of the target, the rest not run:
    // both say the link went away.
    assert!(
        stdout.contains("not run: the target stopped answering")
            && stdout.contains("link lost and not back"),
        "{}",
        &stdout[stdout.len().saturating_sub(2000)..]
    );
    assert!(std::fs::read_to_string(&junit).is_ok_and(|x| x.contains("<testcase")));
}

/// `scripts/network-figures`, which makes the figures of
/// `docs/performance.md`, runs every row once (the debug build): each row
/// is a whole suite that passes, through ser2net and on several boards.
#[cfg_attr(
    ppmc_missing_ser2net,
    ignore = "ser2net is not installed (apt install ser2net)"
)]
#[test]
fn the_figures_script_runs_every_row() {
    if !have_ser2net() {
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts/network-figures");
    let mut child = Command::new(script)
        .args(["--runs", "1", "--ppmc", env!("CARGO_BIN_EXE_ppmc")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the script runs");
    let (so, se) = (child.stdout.take(), child.stderr.take());
    let read = |p: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || p.map(|p| std::io::read_to_string(p).unwrap_or_default()))
    };
    let out = read(so.map(|p| Box::new(p) as Box<dyn std::io::Read + Send>));
    let err = read(se.map(|p| Box::new(p) as Box<dyn std::io::Read + Send>));
    let status = common::wait_bounded(&mut child, Duration::from_secs(600));
    let out = out.join().expect("stdout").unwrap_or_default();
    let err = err.join().expect("stderr").unwrap_or_default();
    assert!(status.success(), "{status}\n{out}\n{err}");
    for row in [
        "| the pty, direct",
        "| ser2net raw, its defaults (",
        "replies not padded",
        "| ser2net telnet(rfc2217), its defaults",
        "| 3 boards, ser2net raw defaults |",
        "| 3 boards |",
    ] {
        let line = out
            .lines()
            .find(|l| l.starts_with(row) || l.contains(row))
            .unwrap_or_else(|| panic!("no row `{row}`:\n{out}"));
        assert!(line.ends_with("x |") && line.contains(" s |"), "{line}");
    }
}

/// The `--target` help, docs/board-farm.md's table of targets and the
/// usage error of an unknown target each list every link kind of
/// `ppmc::backend::DRIVERS`, in its order, with its form: a new driver
/// cannot be left out of any of them.
#[test]
fn every_link_driver_is_in_the_help_the_docs_and_the_usage_error() {
    let help = text(&ppmc(&["run", "--help"]).stdout);
    let docs = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/board-farm.md"
    ))
    .expect("docs");
    let unknown = ppmc(&["run", "--target", "usb:0"]);
    assert_eq!(unknown.status.code(), Some(2));
    let usage = text(&unknown.stderr);
    let drivers = ppmc::backend::DRIVERS;
    assert!(drivers.len() >= 4);
    let lines: Vec<&str> = help.lines().map(str::trim).collect();
    let mut at = (0, 0, 0);
    for d in drivers {
        let form = d.form();
        let in_help = lines[at.0..]
            .iter()
            .position(|l| *l == form)
            .map(|i| at.0 + i);
        let in_docs = docs[at.1..]
            .find(&format!("| `{form}` |"))
            .map(|i| at.1 + i);
        let in_usage = usage[at.2..].find(&format!("`{form}`")).map(|i| at.2 + i);
        match (in_help, in_docs, in_usage) {
            (Some(h), Some(o), Some(u)) => at = (h + 1, o + 1, u + 1),
            found => panic!(
                "{form}: in the help, the docs, the usage error (in order): {found:?}\n{usage}"
            ),
        }
        let about = lines[at.0];
        assert!(about.starts_with(d.about()), "{form}: {about}");
        let pad = format!("reply padding {} bytes", d.default_pad());
        assert!(about.contains(&pad), "{form}: {about}");
    }
}
