//! Wall-clock figures of the emulator and of the bridge path (`ppmc
//! bench`, the source of `docs/performance.md`): each measured here and
//! printed by the command line. Timings live here and never in tests: the
//! machines are shared and noisy.

use crate::backend::{
    BridgeError, BridgeOptions, BridgeTarget, EmuTarget, Op, Reply, SerialLink, Target,
};
use crate::bridge::sim::{LinkFaults, PtyBridge};
use crate::emu::ModelConfig;
use crate::protocol::{InitData, PulseCount, Status, Straps};
use crate::runner::run_suite;
use crate::scenario::{DriverOptions, Scenario, ScenarioResult, Verdict};
use crate::time::Duration;
use crate::trace::Trace;
use std::time::Instant as WallClock;

/// What one move on the emulator made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MoveTiming {
    pub pulses: u64,
    /// Pulse runs the record stores them in.
    pub runs: usize,
    /// Virtual time from the move's final write to its end.
    pub virtual_time: Duration,
}

/// A named benchmark case.
pub type Case = (&'static str, Box<dyn Fn() -> MoveTiming>);

fn write_all(t: &mut EmuTarget, bytes: &[(bool, u8)]) {
    let ops: Vec<Op> = bytes
        .iter()
        .map(|&(cmd, byte)| {
            let wait_ibf = Some(Duration::from_secs(1));
            if cmd {
                Op::WriteCommand { byte, wait_ibf }
            } else {
                Op::WriteData { byte, wait_ibf }
            }
        })
        .collect();
    let _ = t.execute(&ops);
}

/// Initializes a 4-phase motor and runs one move to its end; returns the
/// target and the virtual time the move took from its final write.
fn run_move(init: InitData, cmd: u8, params: &[u8]) -> Option<(EmuTarget, Duration)> {
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).ok()?;
    let mut bytes = vec![(true, 0x02)];
    bytes.extend(init.to_bytes().iter().map(|b| (false, *b)));
    bytes.push((true, cmd));
    bytes.extend(params.iter().map(|b| (false, *b)));
    write_all(&mut t, &bytes);
    let start = t.chip().now();
    let replies = t
        .execute(&[
            Op::AwaitStatus {
                mask: Status::BUSY,
                value: Status::BUSY,
                timeout: Duration::from_millis(10),
            },
            Op::AwaitStatus {
                mask: Status::BUSY,
                value: 0,
                timeout: Duration::from_secs(3_600),
            },
        ])
        .ok()?;
    let end = replies.last().map_or(start, Reply::at);
    Some((t, end.saturating_since(start)))
}

fn one_move(init: InitData, cmd: u8, params: &[u8]) -> MoveTiming {
    match run_move(init, cmd, params) {
        Some((t, virtual_time)) => MoveTiming {
            pulses: t.chip().record().pulse_count(),
            runs: t.chip().record().runs.len(),
            virtual_time,
        },
        None => MoveTiming::default(),
    }
}

/// The median of `samples` (0 for none).
pub fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples.get(samples.len() / 2).copied().unwrap_or(0.0)
}

/// `f` run `repeat` times: its median wall time in milliseconds, and what
/// it made.
pub fn time_case(repeat: usize, f: impl Fn() -> MoveTiming) -> (f64, MoveTiming) {
    let mut samples = Vec::with_capacity(repeat);
    let mut last = MoveTiming::default();
    for _ in 0..repeat.max(1) {
        let t0 = WallClock::now();
        last = f();
        samples.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    (median(samples), last)
}

const MAX_RAMP: InitData = InitData {
    rl: 200,
    rh: 20,
    pa: 11_220,
};

/// The emulator's cases: the longest moves and the console example.
pub fn emulator_cases() -> Vec<Case> {
    let short_ramp = InitData {
        rl: 100,
        rh: 20,
        pa: 100,
    };
    let full = PulseCount::MAX.to_bytes();
    let thousand = PulseCount::new(1_000).map_or([0; 3], PulseCount::to_bytes);
    vec![
        (
            "accel/decel 16,777,216 steps, PA 11,220 (trapezoid)",
            Box::new(move || one_move(MAX_RAMP, 0x43, &full)),
        ),
        (
            "accel/decel 1,000 steps, PA 100 (console example)",
            Box::new(move || one_move(short_ramp, 0x43, &thousand)),
        ),
        (
            "constant speed 1,000 steps, rate 100",
            Box::new(move || {
                let [a, b, c] = thousand;
                one_move(short_ramp, 0x44, &[100, a, b, c])
            }),
        ),
        (
            "constant speed 16,777,216 steps, rate 100",
            Box::new(move || one_move(short_ramp, 0x44, &[100, full[0], full[1], full[2]])),
        ),
    ]
}

/// The per-pulse expansion of the longest record: milliseconds and
/// pulses; `None` when the emulator could not be built.
pub fn expansion() -> Option<(f64, u64)> {
    let (t, _) = run_move(MAX_RAMP, 0x43, &PulseCount::MAX.to_bytes())?;
    let t0 = WallClock::now();
    let mut pulses = 0u64;
    for (at, _) in t.chip().record().pulses() {
        std::hint::black_box(at);
        pulses += 1;
    }
    Some((t0.elapsed().as_secs_f64() * 1e3, pulses))
}

/// The suite in process and over a pseudo-terminal to the bridge
/// simulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeFigures {
    /// Median wall time in process, milliseconds.
    pub local_ms: f64,
    /// Median wall time over the pty, milliseconds.
    pub remote_ms: f64,
    /// Round trips of one run over the pty.
    pub round_trips: u64,
}

/// The conformance suite in process and over a pseudo-terminal to the
/// bridge simulator, `repeat` times each; the error says what was missing.
pub fn suite_over_bridge(repeat: usize, suite: &[Scenario]) -> Result<BridgeFigures, String> {
    let mut local = Vec::new();
    for _ in 0..repeat {
        let mut t =
            EmuTarget::new(Straps::default(), ModelConfig::default()).map_err(|e| e.to_string())?;
        let t0 = WallClock::now();
        run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
        local.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let emu =
        EmuTarget::new(Straps::default(), ModelConfig::default()).map_err(|e| e.to_string())?;
    let sim = PtyBridge::start(emu, LinkFaults::default())
        .map_err(|e| format!("no bridge simulator: {e}"))?;
    let path = sim.path().to_string();
    let mut remote = Vec::new();
    let mut round_trips = 0;
    for _ in 0..repeat {
        let mut t = SerialLink::open(&path, 115_200)
            .map_err(BridgeError::from)
            .and_then(|l| BridgeTarget::open(l, BridgeOptions::default()))
            .map_err(|e| format!("the bridge simulator did not answer: {e}"))?;
        let t0 = WallClock::now();
        run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
        remote.push(t0.elapsed().as_secs_f64() * 1e3);
        round_trips = t.stats.round_trips;
    }
    sim.stop();
    Ok(BridgeFigures {
        local_ms: median(local),
        remote_ms: median(remote),
        round_trips,
    })
}

/// The line faults of a noisy-link row (`kind` one of corrupt, drop,
/// duplicate, reorder, mixed; `rate` per byte, both ways).
pub fn line_faults(kind: &str, rate: f64) -> LinkFaults {
    let mut f = LinkFaults::default();
    match kind {
        "corrupt" => f.corrupt_rate = rate,
        "drop" => f.drop_rate = rate,
        "duplicate" => f.dup_rate = rate,
        "reorder" => f.reorder_rate = rate,
        _ => {
            f.corrupt_rate = rate;
            f.drop_rate = rate;
            f.dup_rate = rate;
            f.reorder_rate = rate;
        }
    }
    f
}

/// The rows of `docs/performance.md`'s noisy-link table.
pub fn noisy_rows() -> Vec<(String, f64)> {
    let mut rows = Vec::new();
    for kind in ["corrupt", "drop", "duplicate"] {
        for rate in [0.001, 0.005, 0.01, 0.02] {
            rows.push((kind.to_string(), rate));
        }
    }
    rows.push(("duplicate".into(), 0.05));
    rows.push(("reorder".into(), 0.005));
    rows.push(("mixed".into(), 0.005));
    rows
}

/// One seed of a noisy-link row: the suite over a pty to the bridge
/// simulator with `faults`, against the `clean` in-process run.
#[derive(Debug, Clone, PartialEq)]
pub struct NoisySeed {
    /// Scenarios that completed with the clean run's verdict and trace.
    pub complete: usize,
    /// Scenarios that got another verdict or trace: a wrong verdict.
    pub wrong: usize,
    pub wall_ms: f64,
    pub round_trips: u64,
    /// The link errors met, each in one line (scenario: error).
    pub errors: Vec<String>,
}

/// The suite over a noisy pty, one seed: how many scenarios completed with
/// the verdict and trace of the `clean` run (the rest ended as link
/// errors), and whether any got a wrong verdict.
pub fn noisy_seed(
    faults: LinkFaults,
    suite: &[Scenario],
    clean: &[ScenarioResult],
) -> Result<NoisySeed, String> {
    let emu =
        EmuTarget::new(Straps::default(), ModelConfig::default()).map_err(|e| e.to_string())?;
    let sim = PtyBridge::start(emu, faults).map_err(|e| format!("no bridge simulator: {e}"))?;
    let t0 = WallClock::now();
    let opened = SerialLink::open(sim.path(), 115_200)
        .map_err(BridgeError::from)
        .and_then(|l| BridgeTarget::open(l, BridgeOptions::default()));
    let mut seed = NoisySeed {
        complete: 0,
        wrong: 0,
        wall_ms: 0.0,
        round_trips: 0,
        errors: Vec::new(),
    };
    match opened {
        Ok(mut t) => {
            let got = run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
            for (g, c) in got.iter().zip(clean) {
                match &g.verdict {
                    Verdict::Error(e) => seed.errors.push(format!("{}: {e}", g.name)),
                    Verdict::NotRun(_) => {}
                    v if *v == c.verdict
                        && g.trace.as_ref().map(Trace::values)
                            == c.trace.as_ref().map(Trace::values) =>
                    {
                        seed.complete += 1
                    }
                    _ => seed.wrong += 1,
                }
            }
            seed.round_trips = t.stats.round_trips;
        }
        Err(e) => seed.errors.push(e.to_string()),
    }
    seed.wall_ms = t0.elapsed().as_secs_f64() * 1e3;
    sim.stop();
    Ok(seed)
}
