//! Reports survive signals as CI sends them: SIGINT from `timeout` during
//! the 16,777,216-step move on a real-time bridge (11 minutes of it), two
//! signals in a row, and SIGTERM while the target is still being opened.
//! Each time the run stops within a few seconds, the scenario under way
//! and the rest are reported interrupted, and the JUnit and JSON reports
//! are written, the JSON valid against its schema.

use crate::common;

use common::{check_record, run_record_schema, scratch, wait_bounded, BridgeSim};
use ppmc::chaos::{Behaviour, ChaosProxy, Upstream};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long a stopped run may take to write its reports and end: every
/// wait on a link looks at the stop request every 100 ms.
const WIND_DOWN: Duration = Duration::from_secs(10);

/// `ppmc run` with reports in `dir`, started by `prefix` (e.g. `timeout`).
fn run(prefix: &[&str], target: &str, extra: &[&str], dir: &Path) -> Child {
    let ppmc = env!("CARGO_BIN_EXE_ppmc");
    let (program, pre) = match prefix.split_first() {
        Some((p, rest)) => (*p, [rest, &[ppmc]].concat()),
        None => (ppmc, Vec::new()),
    };
    Command::new(program)
        .args(pre)
        .args(["run", "--target", target, "--junit"])
        .arg(dir.join("report.xml"))
        .arg("--json")
        .arg(dir.join("run.json"))
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("ppmc runs")
}

/// The reports of a run that was stopped: written, the JSON valid, every
/// scenario interrupted (none blamed on the board or the link).
fn check_interrupted(dir: &Path, scenarios: usize) {
    let xml = std::fs::read_to_string(dir.join("report.xml")).expect("the JUnit report");
    assert_eq!(xml.matches("<testcase ").count(), scenarios, "{xml}");
    assert_eq!(
        xml.matches("type=\"interrupted\"").count(),
        scenarios,
        "{xml}"
    );
    // Issue 44: the interruption is an error of the suite, said in its
    // system-err, so that a CI page reading the counts sees the run did
    // not finish (it read failures="0" errors="0").
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("parses");
    assert!(report.errors >= 1, "{xml}");
    let suite = &report.test_suites[0];
    assert_eq!(suite.errors, 1, "{xml}");
    assert!(
        xml.contains("<system-err>the run was interrupted before its end"),
        "{xml}"
    );
    let record = record(dir);
    assert_eq!(
        record["summary"]["not_run"].as_u64(),
        Some(scenarios as u64),
        "{}",
        record["summary"]
    );
}

/// The run's JSON record in `dir`, checked against its schema.
fn record(dir: &Path) -> serde_json::Value {
    let record: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("run.json")).expect("the JSON record"),
    )
    .expect("JSON");
    check_record(&run_record_schema(), &record);
    record
}

/// `ppmc run --tag long` on `sim`, reports in `dir`, 1.5 s in: it has
/// opened the bridge and started the 16,777,216-step move.
fn into_the_long_move(sim: &BridgeSim, dir: &Path) -> Child {
    let child = run(&[], &sim.target(), &["--tag", "long"], dir);
    std::thread::sleep(Duration::from_millis(1500));
    child
}

fn signal(child: &Child, sig: &str) {
    let sent = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
}

/// `timeout -s INT 2 ppmc run ...` during the long move on a real-time
/// bridge, ten times: each run ends within seconds of the signal, and
/// leaves its reports.
#[test]
fn sigint_from_timeout_during_the_long_move_leaves_the_reports_every_time() {
    let sim = BridgeSim::start(&["--realtime"]);
    for i in 0..10 {
        let dir = scratch("sigint");
        let began = Instant::now();
        let mut child = run(
            &["timeout", "-s", "INT", "2"],
            &sim.target(),
            &["--tag", "long"],
            dir.path(),
        );
        let status = wait_bounded(&mut child, WIND_DOWN + Duration::from_secs(2));
        // GNU timeout exits 124 when it had to signal its command.
        assert_eq!(status.code(), Some(124), "try {i}: {status}");
        assert!(began.elapsed() >= Duration::from_secs(2));
        check_interrupted(dir.path(), 1);
    }
}

/// A second signal, as CI runners send one after the first, hurries the
/// wind-down but still writes the reports.
#[test]
fn two_signals_in_a_row_still_write_the_reports() {
    let sim = BridgeSim::start(&["--realtime"]);
    for sig in ["-INT", "-TERM"] {
        let dir = scratch("twice");
        let mut child = into_the_long_move(&sim, dir.path());
        signal(&child, sig);
        // The second as a CI runner sends it, after a moment (two within
        // 200 ms are one request, as GNU timeout delivers its one twice).
        std::thread::sleep(Duration::from_millis(300));
        signal(&child, sig);
        let status = wait_bounded(&mut child, WIND_DOWN);
        assert_eq!(status.code(), Some(130), "{sig}: {status}");
        check_interrupted(dir.path(), 1);
    }
}

/// SIGTERM while the target is being opened (here a server that takes
/// every connection and closes it, so the host keeps reconnecting): the
/// run ends at once, every scenario interrupted, the reports written.
#[test]
fn sigterm_while_the_target_is_opened_still_writes_the_reports() {
    let sim = BridgeSim::start(&[]);
    let bridge = Upstream::Serial(sim.target().trim_start_matches("serial:").to_string());
    let proxy = ChaosProxy::start("127.0.0.1:0", bridge, Behaviour::AcceptClose, 1).expect("proxy");
    let dir = scratch("open");
    let target = format!("tcp://{}", proxy.addr());
    let mut child = run(&[], &target, &["--skip-tag", "long"], dir.path());
    // The open takes seconds against this server (six reconnects).
    std::thread::sleep(Duration::from_millis(700));
    assert!(child.try_wait().expect("wait").is_none(), "still opening");
    signal(&child, "-TERM");
    let status = wait_bounded(&mut child, WIND_DOWN);
    assert_eq!(status.code(), Some(130), "{status}");
    check_interrupted(dir.path(), 95);
}

/// Ctrl-C during the 16,777,216-step move (eleven minutes on a real-time
/// bridge), then the next run on the same bridge: the first host's ABORT
/// (`docs/bridge-protocol.md` section 5) stopped the move, so the next
/// run opens at once and passes, where before it found the bridge busy
/// for the rest of the move and gave up ("no bridge answering"). A host
/// killed outright sends no ABORT: the next host's HELLO, from another
/// host session, stops the move instead. How soon it opens is printed
/// (`docs/performance.md`); what is asserted is that it works at all.
#[test]
fn after_ctrl_c_in_the_long_move_the_next_run_on_the_bridge_opens_at_once() {
    let sim = BridgeSim::start(&["--realtime"]);
    for sig in ["-INT", "-KILL"] {
        let dir = scratch("abort");
        let mut child = into_the_long_move(&sim, dir.path());
        signal(&child, sig);
        let status = wait_bounded(&mut child, WIND_DOWN);
        if sig == "-INT" {
            assert_eq!(status.code(), Some(130), "{status}");
            // The record says the host stopped the bridge.
            let record = record(dir.path());
            let stats = &record["run"]["boards"][0]["link"];
            assert_eq!(stats["aborts"].as_u64(), Some(1), "{record}");
        }
        let next = scratch("next");
        let began = Instant::now();
        let mut second = run(
            &[],
            &sim.target(),
            &["--filter", "s3_3_4_pout_mode_holds_the_phases"],
            next.path(),
        );
        let status = wait_bounded(&mut second, Duration::from_secs(60));
        eprintln!("after {sig}: the next run took {:?}", began.elapsed());
        assert_eq!(status.code(), Some(0), "after {sig}: {status}");
    }
}

/// `--timeout` on a real-time bridge: the 16,777,216-step move runs past
/// it, so the host tells the bridge to stop (ABORT) and the scenario is an
/// error naming the limit, not a failure of the board; the run goes on,
/// and the scenarios after it pass on the same bridge.
#[test]
fn a_scenario_past_its_timeout_is_stopped_on_the_bridge_and_the_run_goes_on() {
    let sim = BridgeSim::start(&["--realtime"]);
    let dir = scratch("timeout");
    let mut child = run(
        &[],
        &sim.target(),
        &["--filter", "s3_3_4_a", "--timeout", "2s"],
        dir.path(),
    );
    let status = wait_bounded(&mut child, Duration::from_secs(120));
    assert_eq!(status.code(), Some(1), "{status}");
    let record = record(dir.path());
    let scenarios = record["scenarios"].as_array().expect("scenarios");
    assert!(scenarios.len() > 3, "{}", scenarios.len());
    for s in scenarios {
        let name = s["name"].as_str().unwrap_or_default();
        if name == "s3_3_4_accel_ffffff_is_16777216_steps" {
            assert_eq!(s["verdict"], "error", "{s}");
            let message = s["error"]["message"].as_str().unwrap_or_default();
            assert!(
                message.contains("--timeout passed")
                    && message.contains("the bridge stopped the request in flight (ABORT)"),
                "{message}"
            );
        } else {
            assert_eq!(s["verdict"], "passed", "{s}");
        }
    }
    assert_eq!(record["summary"]["error"], 1, "{}", record["summary"]);
}

/// Whether `pid` holds (blocks) or catches SIGTERM, from its
/// `/proc/PID/status`: `(held, caught)`.
fn sigterm_state(pid: u32) -> Option<(bool, bool)> {
    // Not before ppmc is the program: between fork and exec the C library
    // holds every signal in the child.
    let exe = std::fs::read_link(format!("/proc/{pid}/exe")).ok()?;
    if exe != Path::new(env!("CARGO_BIN_EXE_ppmc")) {
        return None;
    }
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let mask = |field: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(field))
            .and_then(|v| u64::from_str_radix(v.trim(), 16).ok())
            .unwrap_or(0)
    };
    let (term, hup) = (1 << (15 - 1), 1);
    // Held by ppmc: SIGTERM alone, not every signal as the C library
    // holds them for a moment while it starts a thread.
    let blocked = mask("SigBlk:");
    Some((
        blocked & term != 0 && blocked & hup == 0,
        mask("SigCgt:") & term != 0,
    ))
}

/// SIGTERM in a run's first milliseconds (issue 44: 11 of 40 such runs on
/// the emulator left no report, the signal arriving before the handlers
/// were installed). Forty tries: each waits until the process is in its
/// own code (it holds SIGTERM, or already catches it; before that it is
/// still being loaded, which no program can help), then signals it 0 to
/// 7.8 ms later. Every run leaves both reports: a run the signal reached
/// is interrupted (exit 130), its record valid and, where scenarios were
/// left, its JUnit suite an error; one that ended first passed. The signal must be seen held in
/// some tries: a ppmc that installs its handlers late, with nothing held
/// meanwhile, shows only "caught".
#[test]
fn sigterm_in_the_first_milliseconds_still_leaves_the_reports() {
    let (mut interrupted, mut held) = (0, 0);
    for i in 0..40u64 {
        let dir = scratch("early");
        let mut child = run(&[], "emu", &["--skip-tag", "long"], dir.path());
        let deadline = Instant::now() + WIND_DOWN;
        loop {
            match sigterm_state(child.id()) {
                Some((true, _)) => {
                    held += 1;
                    break;
                }
                Some((false, true)) => break,
                _ => {}
            }
            assert!(
                Instant::now() < deadline,
                "try {i}: ppmc never reached its code"
            );
            std::thread::yield_now();
        }
        std::thread::sleep(Duration::from_micros(200 * i));
        signal(&child, "-TERM");
        let status = wait_bounded(&mut child, WIND_DOWN);
        let xml = std::fs::read_to_string(dir.path().join("report.xml"))
            .unwrap_or_else(|e| panic!("try {i} ({status}): no JUnit report: {e}"));
        let record = record(dir.path());
        match status.code() {
            // Interrupted: the scenarios it did not reach are in the
            // reports (none when the signal came after the last one).
            Some(130) => {
                let never = record["summary"]["not_run"].as_u64().unwrap_or(0);
                interrupted += usize::from(never > 0);
                assert_eq!(
                    xml.contains("<system-err>the run was interrupted"),
                    never > 0,
                    "try {i}: {never} not run"
                );
            }
            Some(0) => assert_eq!(record["summary"]["not_run"].as_u64(), Some(0)),
            other => panic!("try {i}: exit {other:?}"),
        }
    }
    eprintln!("{held} of 40 tries saw SIGTERM held, {interrupted} were interrupted");
    assert!(
        held > 0,
        "SIGTERM was never seen held before the handlers were in"
    );
    // The signal came first in most tries: the test is about them.
    assert!(
        interrupted >= 10,
        "only {interrupted} of 40 runs were interrupted"
    );
}
