//! The link under attack: the whole suite through a chaos proxy on
//! 127.0.0.1 (`ppmc::chaos`) in front of a `ppmc bridge-sim`, once per
//! behaviour of a hostile network or server. For every one: no scenario
//! is a device failure (the board is good), every other verdict is the
//! clean run's or an infrastructure error, the run ends within its bound,
//! and the JUnit and JSON reports are written, the JSON valid against its
//! schema. `docs/detection.md` ("The link under attack") has the table.
//!
//! The runs use `--link-timeout 200ms --link-retries 4`, so that giving up
//! takes seconds, not the minute it may take with the defaults; the bounds
//! are the documented formulas at those settings.

use crate::common;

use common::{check_record, run_record_schema, scratch, BridgeSim};
use ppmc::chaos::{Behaviour, ChaosProxy, Upstream};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What one run through the proxy came to.
#[derive(Debug)]
struct Outcome {
    passed: usize,
    infrastructure: usize,
    interrupted: usize,
    secs: f64,
}

/// The longest a run may take at the test's link settings: a run that
/// completes (each reconnect costs at most a few round trips, each stall
/// a few seconds), or one that gives up (the open, one scenario and the
/// health check, each at most `3 T (R + 1)` = 3 s, reconnect loops
/// included).
fn bound(b: Behaviour) -> Duration {
    Duration::from_secs(match b {
        Behaviour::Stall(_) | Behaviour::HalfOpen(_) => 240,
        b if b.forwards() => 120,
        _ => 60,
    })
}

/// The suite through `behaviour`, as `ppmc run` with reports.
fn through(behaviour: &str) -> Outcome {
    let b: Behaviour = behaviour.parse().expect("a behaviour");
    let sim = BridgeSim::start(&[]);
    let bridge = Upstream::Serial(sim.target().trim_start_matches("serial:").to_string());
    let proxy = ChaosProxy::start("127.0.0.1:0", bridge, b, 7).expect("the proxy listens");
    let scheme = match b {
        Behaviour::OptionStorm => "rfc2217",
        _ => "tcp",
    };
    let dir = scratch("chaos");
    let junit = dir.path().join("report.xml");
    let json = dir.path().join("run.json");
    let began = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(["run", "--target"])
        .arg(format!("{scheme}://{}", proxy.addr()))
        .args(["--link-timeout", "200ms", "--link-retries", "4", "--junit"])
        .arg(&junit)
        .arg("--json")
        .arg(&json)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("ppmc runs");
    let status = common::wait_bounded(&mut child, bound(b));
    let secs = began.elapsed().as_secs_f64();
    let stats = proxy.stop();
    assert!(
        matches!(status.code(), Some(0 | 1)),
        "{behaviour}: exit {status} (0: all passed, 1: errors; never a crash)"
    );
    let xml = std::fs::read_to_string(&junit).expect("the JUnit report is written");
    assert!(
        !xml.contains("type=\"device\""),
        "{behaviour}: a good board was failed:\n{xml}"
    );
    assert_eq!(xml.matches("<testcase ").count(), 96, "{behaviour}");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the JSON record"))
            .expect("JSON");
    check_record(&run_record_schema(), &record);
    let mut o = Outcome {
        passed: 0,
        infrastructure: 0,
        interrupted: 0,
        secs,
    };
    for r in record["scenarios"].as_array().expect("scenarios") {
        let name = &r["name"];
        match (r["verdict"].as_str(), r["error"]["kind"].as_str()) {
            (Some("passed" | "marginal"), _) => o.passed += 1,
            (Some("error" | "not_run"), Some("infrastructure")) => o.infrastructure += 1,
            (Some("not_run"), Some("interrupted")) => o.interrupted += 1,
            other => panic!("{behaviour}: {name} ended {other:?}, neither the clean verdict nor an infrastructure error"),
        }
    }
    assert_eq!(o.interrupted, 0, "{behaviour}: nobody interrupted the run");
    assert_eq!(
        status.success(),
        o.passed == 96,
        "{behaviour}: exit status and verdicts agree"
    );
    // The behaviour must have acted, or the run proved nothing.
    match b {
        Behaviour::Clean => {}
        Behaviour::DropEvery(_)
        | Behaviour::DropAt(_)
        | Behaviour::DropBothEvery(_)
        | Behaviour::DropRandomByte(_)
        | Behaviour::HalfOpen(_)
        | Behaviour::AcceptClose => assert!(stats.cuts > 0, "{behaviour}: {stats:?}"),
        Behaviour::Stall(_)
        | Behaviour::Duplicate(_)
        | Behaviour::Reorder(_)
        | Behaviour::FloodAfter(_) => assert!(stats.acts > 0, "{behaviour}: {stats:?}"),
        _ => assert!(stats.connections > 0, "{behaviour}: {stats:?}"),
    }
    eprintln!(
        "| {behaviour} | {} / 96 | 0 | {} | {:.1} s | {} connections, {} cut, {} acts |",
        o.passed, o.infrastructure, o.secs, stats.connections, stats.cuts, stats.acts
    );
    o
}

/// The suite completes: the host reconnects and goes on. (A scenario may
/// still end as an infrastructure error on a machine so loaded that the
/// host gives up on a reply: never as a device failure, which `through`
/// checks; all but a few must pass.)
fn completes(b: &str) {
    let o = through(b);
    assert!(o.passed >= 90, "{b}: {o:?}");
}

/// Behaviours that leave the bridge reachable: the suite completes.
#[test]
fn a_link_that_drops_or_reorders_still_completes_the_suite() {
    for b in [
        "clean",
        "drop-every=40",
        "drop-both-every=40",
        "drop-random-byte=3000",
        "duplicate=5",
        "reorder=5",
    ] {
        completes(b);
    }
}

#[test]
fn a_link_that_drops_less_often_completes_the_suite() {
    for b in ["drop-every=60", "drop-every=100"] {
        completes(b);
    }
}

/// A connection that stalls, or dies without a word: the host hears
/// nothing, reconnects and goes on.
#[test]
fn a_stalled_or_half_open_connection_is_reconnected() {
    for b in ["stall=400", "half-open=300"] {
        completes(b);
    }
}

/// A link that turns to noise in the middle of a run: the scenario under
/// way and the rest are infrastructure errors, none a failure, and the run
/// ends within its bound (three requests given up at most).
#[test]
fn a_link_that_turns_to_noise_mid_run_ends_the_run_without_blaming_the_board() {
    let o = through("flood-after=300");
    assert!(o.passed > 0 && o.infrastructure > 0, "{o:?}");
}

/// Servers that never let a bridge through: the run gives up as an
/// infrastructure error, within its bound, with every report written.
#[test]
fn a_server_that_never_lets_the_bridge_through_ends_as_an_infrastructure_error() {
    for b in [
        "accept-close",
        "flood-random",
        "flood-ff",
        "endless-frame",
        "trickle",
        "wrong-seq",
        "error-only",
        "option-storm",
    ] {
        let o = through(b);
        assert_eq!((o.passed, o.infrastructure), (0, 96), "{b}: {o:?}");
    }
}

/// `ppmc chaos-proxy` as `docs/detection.md` shows it: it says where it
/// listens, the suite runs through it, and SIGINT stops it with what it
/// did.
#[test]
fn the_chaos_proxy_command_serves_until_stopped() {
    use std::io::{BufRead, BufReader, Read};
    let sim = BridgeSim::start(&[]);
    let mut proxy = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(["chaos-proxy", "--to"])
        .arg(sim.target())
        .args(["--behaviour", "drop-every=40", "--listen", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("chaos-proxy starts");
    let mut out = BufReader::new(proxy.stdout.take().expect("piped"));
    let mut first = String::new();
    out.read_line(&mut first).expect("it says where");
    let addr = first
        .split(" on ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .unwrap_or_else(|| panic!("`{first}`"))
        .to_string();
    assert!(
        first.starts_with("chaos-proxy: drop-every=40 on 127.0.0.1:"),
        "{first}"
    );
    let run = common::ppmc(&["run", "--target", &format!("tcp://{addr}")]);
    let stdout = common::text(&run.stdout);
    assert_eq!(run.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("suite: 96 passed, 0 failed, 0 errors, 0 not run"));
    let sent = Command::new("kill")
        .args(["-INT", &proxy.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
    let status = common::wait_bounded(&mut proxy, Duration::from_secs(10));
    assert!(status.success(), "{status}");
    let mut rest = String::new();
    out.read_to_string(&mut rest).expect("the rest");
    assert!(rest.contains(" cut, "), "{rest}");
    // A behaviour it does not have is bad usage.
    let bad = common::ppmc(&["chaos-proxy", "--to", &sim.target(), "--behaviour", "flood"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(common::text(&bad.stderr).contains("unknown behaviour `flood`"));
}

/// Every behaviour the proxy has is run above.
#[test]
fn every_behaviour_is_tried() {
    let src = include_str!("cli_chaos.rs");
    for b in Behaviour::ALL {
        assert!(src.contains(&format!("\"{b}\"")), "{b} is not run");
    }
}
