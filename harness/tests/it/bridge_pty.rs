//! The board path, end to end over a real pseudo-terminal: the bridge
//! simulator on the master side, the `serialport` driver on the slave path.

use ppmc_test_support as common;

use ppmc::backend::{BridgeError, BridgeOptions, BridgeTarget, EmuTarget, SerialLink};
use ppmc::bridge::sim::{LinkFaults, PtyBridge};
use ppmc::emu::{ModelConfig, WiringFaults};
use ppmc::protocol::Straps;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, ScenarioResult, Verdict};
use ppmc::trace::EventKind;
use std::time::Duration as WallDuration;

/// A bridge simulator serving on its own thread.
struct Sim(PtyBridge);

impl Sim {
    fn start(faults: LinkFaults, model: ModelConfig) -> Sim {
        let emu = EmuTarget::new(Straps::default(), model).expect("emulator");
        Sim(PtyBridge::start(emu, faults).expect("a pty"))
    }

    fn clean() -> Sim {
        Sim::start(LinkFaults::default(), ModelConfig::default())
    }

    fn target(&self, opts: BridgeOptions) -> Result<BridgeTarget<SerialLink>, BridgeError> {
        BridgeTarget::open(SerialLink::open(self.0.path(), 115_200)?, opts)
    }
}

fn fast() -> BridgeOptions {
    BridgeOptions {
        reply_timeout: WallDuration::from_millis(60),
        min_reply_timeout: WallDuration::from_millis(5),
        retries: 8,
        reopen_attempts: 3,
        backoff: WallDuration::from_millis(20),
        quiet: WallDuration::from_millis(4),
        pad: 0,
        ..BridgeOptions::default()
    }
}

fn in_process() -> Vec<ScenarioResult> {
    common::suite_in_process()
}

#[test]
fn the_whole_suite_over_the_pty_equals_the_in_process_run() {
    let sim = Sim::clean();
    let mut t = sim
        .target(BridgeOptions::default())
        .expect("bridge answers");
    let over_pty = run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        DriverOptions::default(),
        |_| {},
    );
    let local = in_process();
    assert_eq!(over_pty.len(), local.len());
    for (a, b) in over_pty.iter().zip(&local) {
        assert_eq!(a.verdict, b.verdict, "{}", a.name);
        let (ta, tb) = (
            a.trace.as_ref().expect("trace"),
            b.trace.as_ref().expect("trace"),
        );
        // The same events; each measurement over the pty carries the
        // bridge's uncertainty (its timer's tick at each end), which the
        // in-process run's, exact, does not.
        let ((pty, unsure), (local, exact)) = (common::values_of(ta), common::values_of(tb));
        assert_eq!(pty, local, "{}: same trace over the pty", a.name);
        assert_eq!(exact, 0, "{}", a.name);
        let measures = ta
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::Measure { .. }))
            .count();
        assert_eq!(unsure, measures, "{}: every measurement says its U", a.name);
        assert_eq!(ta.target, format!("serial:{}", sim.0.path()), "{}", a.name);
    }
    // A clean line garbles nothing. (A reply later than the measured
    // round trip allows, on a loaded machine, may be asked for again; that
    // costs a round trip, never a result.)
    assert_eq!(t.stats.corrupt_frames, 0);
    assert!(t.stats.round_trips > 0);
}

/// With the host's default link settings, a cable that corrupts 1 % of
/// its bytes costs time, not results: at least 95 of the 96 scenarios
/// complete, and whatever completes saw exactly what the chip did (the
/// rest end as link errors, never as a wrong verdict).
#[test]
fn corrupted_bytes_never_turn_into_wrong_values() {
    let faults = LinkFaults {
        corrupt_rate: 0.01,
        seed: 7,
        ..LinkFaults::default()
    };
    let sim = Sim::start(faults, ModelConfig::default());
    let mut t = sim
        .target(BridgeOptions::default())
        .expect("bridge answers through the noise");
    let noisy = run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        DriverOptions::default(),
        |_| {},
    );
    let local = in_process();
    let mut passed = 0;
    for (a, b) in noisy.iter().zip(&local) {
        match &a.verdict {
            // A link error is allowed (and reported as such) ...
            Verdict::Error(_) | Verdict::NotRun(_) => {}
            // ... but whatever completed saw exactly what the chip did.
            v => {
                assert_eq!(v, &b.verdict, "{}", a.name);
                let (ta, tb) = (
                    a.trace.as_ref().expect("trace"),
                    b.trace.as_ref().expect("trace"),
                );
                assert_eq!(
                    common::values_of(ta).0,
                    common::values_of(tb).0,
                    "{}: no corrupted value got through",
                    a.name
                );
                passed += 1;
            }
        }
    }
    eprintln!(
        "{passed} of {} completed under 1% corruption; {:?}",
        noisy.len(),
        t.stats
    );
    assert!(t.stats.corrupt_frames > 0, "the noise was noticed");
    assert!(
        t.stats.retransmissions > 0,
        "and repaired by retransmission"
    );
    let first_error = noisy.iter().find_map(|r| match &r.verdict {
        Verdict::Error(e) => Some(format!("{}: {e}", r.name)),
        _ => None,
    });
    assert!(
        passed + 1 >= noisy.len(),
        "{passed} of {} completed; first error {first_error:?}",
        noisy.len()
    );
}

#[test]
fn a_stalled_bridge_gives_a_timeout_naming_the_op() {
    let sim = Sim::start(
        LinkFaults {
            stall_after: Some(4),
            ..LinkFaults::default()
        },
        ModelConfig::default(),
    );
    let mut t = sim.target(fast()).expect("healthy before the stall");
    let err = ppmc::backend::Target::execute(&mut t, &[ppmc::backend::Op::ReadStatus])
        .map(|_| ())
        .and_then(|_| {
            ppmc::backend::Target::execute(&mut t, &[ppmc::backend::Op::ReadPins]).map(|_| ())
        })
        .expect_err("no answer");
    assert_eq!(err.kind, ppmc::backend::TargetErrorKind::Link);
    assert!(
        err.to_string().contains("no bridge answering"),
        "{}",
        err.to_string()
    );
    assert!(
        err.to_string().contains("starting with `sample the pins`")
            || err.to_string().contains("starting with `read status`"),
        "{}",
        err.to_string()
    );
}

#[test]
fn an_unhealthy_board_is_refused_at_open() {
    let sim = Sim::start(
        LinkFaults::default(),
        ModelConfig {
            board: WiringFaults {
                status_stuck_high: 0x08,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        },
    );
    let err = sim
        .target(fast())
        .expect_err("status is not 0x00 after reset");
    assert!(matches!(err, BridgeError::Unhealthy { .. }), "{err}");
    // A sentence a person reads, not Rust's debug output.
    assert!(
        err.to_string().ends_with(
            "health check failed: after a chip reset the status register reads 0x08, not 0x00"
        ),
        "{err}"
    );
}

#[test]
fn a_missing_port_says_so() {
    let err = SerialLink::open("/dev/ppmc-no-such-port", 115_200).expect_err("missing");
    assert!(err.to_string().contains("no such serial port"), "{err}");
}

#[test]
fn a_disconnect_mid_run_ends_with_the_rest_not_run() {
    let sim = Sim::start(
        LinkFaults {
            disconnect_after: Some(60),
            ..LinkFaults::default()
        },
        ModelConfig::default(),
    );
    let mut t = sim.target(fast()).expect("bridge answers");
    let results = run_suite(
        &mut t,
        &ppmc_scenarios::all(),
        1,
        DriverOptions::default(),
        |_| {},
    );
    let labels: Vec<&str> = results.iter().map(|r| r.verdict.label()).collect();
    let first_bad = labels
        .iter()
        .position(|l| *l != "passed")
        .expect("the link dropped");
    assert!(first_bad > 0, "some scenarios ran before the drop");
    assert_eq!(labels[first_bad], "error");
    assert!(
        labels[first_bad + 1..].iter().all(|l| *l == "not run"),
        "{labels:?}"
    );
    let detail = results[first_bad].verdict.detail().unwrap_or_default();
    assert!(
        detail.contains("link lost") || detail.contains("no bridge answering"),
        "{detail}"
    );
}

#[test]
fn a_realtime_bridge_takes_as_long_as_its_waits_and_the_host_waits_for_it() {
    use ppmc::backend::{Op, Reply, Target};
    use ppmc::bridge::sim::SimOptions;
    use ppmc::time::Duration;
    let emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    let bridge = SimOptions {
        realtime: true,
        ..SimOptions::default()
    };
    let sim = Sim(PtyBridge::start_with(emu, LinkFaults::default(), bridge).expect("a pty"));
    // A reply timeout shorter than the batch: the host must allow for the
    // batch's own delay on a bridge that says it runs in real time. (It
    // was 100 ms against a 400 ms delay, then 300 ms against 1.2 s; on a
    // loaded CI machine the reply twice came later than that after the
    // delay's end, and the host asked again: 1.5 s against 4.5 s keeps
    // the timeout a third of the batch, with room for the machine's load.)
    // The timeout is held there: a host that measured the link fast waits
    // less (down to `min_reply_timeout`), and the machine's load is not
    // what this test is about.
    let opts = BridgeOptions {
        reply_timeout: WallDuration::from_millis(1_500),
        min_reply_timeout: WallDuration::from_millis(1_500),
        ..fast()
    };
    let mut t = sim.target(opts).expect("bridge answers");
    assert!(!t.hello().virtual_time);
    let began = std::time::Instant::now();
    let r = t
        .execute(&[Op::Delay(Duration::from_millis(4_500)), Op::ReadStatus])
        .expect("the host waited for the delay");
    let took = began.elapsed();
    // A lower bound only: the machine may be slow, never early.
    assert!(took >= WallDuration::from_millis(4_500), "{took:?}");
    assert!(
        matches!(r[1], Reply::Status { at, .. } if at.as_nanos() >= 4_500_000_000),
        "{r:?}"
    );
    assert_eq!(t.stats.retransmissions, 0, "no reply was given up on");
}

#[test]
fn a_capture_overrun_is_an_error_of_that_scenario_and_the_run_goes_on() {
    use ppmc::bridge::sim::SimOptions;
    let emu = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
    // Room for a few pulse runs: the 1,000-step ramp needs about 80.
    let bridge = SimOptions {
        capture_capacity: 40,
        ..SimOptions::default()
    };
    let sim = Sim(PtyBridge::start_with(emu, LinkFaults::default(), bridge).expect("a pty"));
    let mut t = sim.target(fast()).expect("bridge answers");
    assert_eq!(t.hello().capture_capacity, 40);
    let pick = |name: &str| {
        ppmc_scenarios::all()
            .into_iter()
            .find(|s| s.name == name)
            .expect("in the suite")
    };
    let scenarios = [
        pick("s3_3_4_accel_1000_steps_cw"),
        pick("s3_3_3_single_step_cw_then_ccw"),
    ];
    let results = run_suite(&mut t, &scenarios, 1, DriverOptions::default(), |_| {});
    let labels: Vec<&str> = results.iter().map(|r| r.verdict.label()).collect();
    assert_eq!(labels, ["error", "passed"], "{:?}", results[1].verdict);
    let detail = results[0].verdict.detail().unwrap_or_default();
    assert!(detail.contains("capture buffer overran"), "{detail}");
    assert!(detail.contains("the buffer holds 40"), "{detail}");
}

/// At most once across reconnects, on the bridge simulator: the
/// connection cut at every frame boundary of two scenarios in turn, through
/// a proxy that keeps its own connection to the bridge.
#[test]
fn a_connection_cut_at_every_frame_boundary_changes_no_verdict() {
    let sim = Sim::clean();
    let frames = common::drop_at_every_frame(
        ppmc::chaos::Upstream::Serial(sim.0.path().to_string()),
        &[
            "s3_2_2_ramp_runs_from_rl_to_rh",
            "e1_operation_command_while_busy",
        ],
    );
    assert!(frames >= 10, "{frames} frames");
}
