//! `ppmc bench`: wall-clock figures for the emulator, printed as a Markdown
//! table (the source of `docs/performance.md`). Timings live here and never
//! in tests: the machines are shared and noisy.

use crate::CliError;
use clap::Args;
use ppmc::backend::{EmuTarget, Op, Reply, Target};
use ppmc::emu::ModelConfig;
use ppmc::protocol::{InitData, PulseCount, Status, Straps};
use ppmc::scenario::Scenario;
use ppmc::time::Duration;
use ppmc::trace::Trace;
use std::time::Instant as WallClock;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Repetitions of each case; the median is reported.
    #[arg(long, default_value_t = 15)]
    repeat: usize,
    /// Instead: the suite over a noisy link to the bridge simulator, with
    /// the host's default link settings, for each kind and rate of line
    /// fault (the table in docs/performance.md).
    #[arg(long)]
    noisy_link: bool,
    /// With --noisy-link: the fault seeds to run each row with.
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// With --noisy-link: only these rows, each KIND:PERCENT with KIND one
    /// of corrupt, drop, duplicate, reorder, mixed (e.g. corrupt:2).
    #[arg(long = "fault", value_name = "KIND:PERCENT", value_parser = parse_fault_row)]
    faults: Vec<(String, f64)>,
}

/// A named benchmark case.
type Case = (&'static str, Box<dyn Fn() -> Outcome>);

struct Outcome {
    pulses: u64,
    runs: usize,
    virtual_time: Duration,
}

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

fn one_move(init: InitData, cmd: u8, params: &[u8]) -> Outcome {
    match run_move(init, cmd, params) {
        Some((t, virtual_time)) => Outcome {
            pulses: t.chip().record().pulse_count(),
            runs: t.chip().record().runs.len(),
            virtual_time,
        },
        None => Outcome {
            pulses: 0,
            runs: 0,
            virtual_time: Duration::ZERO,
        },
    }
}

fn median_ms(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples.get(samples.len() / 2).copied().unwrap_or(0.0)
}

fn time_case(repeat: usize, f: impl Fn() -> Outcome) -> (f64, Outcome) {
    let mut samples = Vec::with_capacity(repeat);
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t0 = WallClock::now();
        let o = f();
        samples.push(t0.elapsed().as_secs_f64() * 1e3);
        last = Some(o);
    }
    let outcome = last.unwrap_or(Outcome {
        pulses: 0,
        runs: 0,
        virtual_time: Duration::ZERO,
    });
    (median_ms(samples), outcome)
}

pub fn run(args: BenchArgs, suite: &[Scenario]) -> Result<(), CliError> {
    if args.noisy_link {
        return noisy_link(args.seeds.max(1), &args.faults, suite);
    }
    let max_ramp = InitData {
        rl: 200,
        rh: 20,
        pa: 11_220,
    };
    let short_ramp = InitData {
        rl: 100,
        rh: 20,
        pa: 100,
    };
    let full = PulseCount::MAX.to_bytes();
    let thousand = PulseCount::new(1_000).map_or([0; 3], PulseCount::to_bytes);
    let cases: Vec<Case> = vec![
        (
            "accel/decel 16,777,216 steps, PA 11,220 (trapezoid)",
            Box::new(move || one_move(max_ramp, 0x43, &full)),
        ),
        (
            "accel/decel 1,000 steps, PA 100 (console example)",
            Box::new(move || one_move(short_ramp, 0x43, &thousand)),
        ),
        (
            "constant speed 1,000 steps, rate 100",
            Box::new(move || {
                one_move(
                    short_ramp,
                    0x44,
                    &[100, thousand[0], thousand[1], thousand[2]],
                )
            }),
        ),
        (
            "constant speed 16,777,216 steps, rate 100",
            Box::new(move || one_move(short_ramp, 0x44, &[100, full[0], full[1], full[2]])),
        ),
    ];
    outln!("| case | median wall time | pulses | stored runs | virtual time |");
    outln!("|---|---:|---:|---:|---:|");
    for (name, f) in &cases {
        let (ms, o) = time_case(args.repeat, f);
        outln!(
            "| {name} | {ms:.3} ms | {} | {} | {:.3} s |",
            o.pulses,
            o.runs,
            o.virtual_time.as_secs_f64()
        );
    }
    // Per-pulse expansion of the longest record, on request.
    let Some((t, _)) = run_move(max_ramp, 0x43, &full) else {
        errln!("ppmc bench: the emulator could not be built");
        return Err(CliError::Verdict);
    };
    let t0 = WallClock::now();
    let mut pulses = 0u64;
    for (at, _) in t.chip().record().pulses() {
        std::hint::black_box(at);
        pulses += 1;
    }
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    outln!("| per-pulse expansion of the 16,777,216-step record | {ms:.3} ms | {pulses} | - | - |");
    outln!();
    suite_over_bridge(args.repeat.clamp(1, 5), suite)
}

/// The conformance suite in process and over a pseudo-terminal to the
/// bridge simulator: wall time and round trips.
fn suite_over_bridge(repeat: usize, suite: &[Scenario]) -> Result<(), CliError> {
    use ppmc::backend::{SerialLink, SerialOptions, SerialTarget};
    use ppmc::bridge::sim::{LinkFaults, PtyBridge};
    use ppmc::runner::run_suite;
    use ppmc::scenario::DriverOptions;

    let mut local = Vec::new();
    for _ in 0..repeat {
        let Ok(mut t) = EmuTarget::new(Straps::default(), ModelConfig::default()) else {
            return Err(CliError::Verdict);
        };
        let t0 = WallClock::now();
        run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
        local.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let sim = EmuTarget::new(Straps::default(), ModelConfig::default())
        .map_err(|e| e.to_string())
        .and_then(|emu| PtyBridge::start(emu, LinkFaults::default()).map_err(|e| e.to_string()));
    let sim = match sim {
        Ok(s) => s,
        Err(e) => {
            errln!("ppmc bench: no bridge simulator: {e}");
            return Err(CliError::Verdict);
        }
    };
    let path = sim.path().to_string();
    let mut remote = Vec::new();
    let mut trips = 0;
    for _ in 0..repeat {
        let target = SerialLink::open(&path, 115_200)
            .and_then(|l| SerialTarget::open(l, SerialOptions::default()));
        let Ok(mut t) = target else {
            errln!("ppmc bench: the bridge simulator did not answer");
            return Err(CliError::Verdict);
        };
        let t0 = WallClock::now();
        run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
        remote.push(t0.elapsed().as_secs_f64() * 1e3);
        trips = t.stats.round_trips;
    }
    sim.stop();
    let (l, r) = (median_ms(local), median_ms(remote));
    outln!("| conformance suite ({} scenarios) | median wall time | round trips | round trips per scenario |", suite.len());
    outln!("|---|---:|---:|---:|");
    outln!("| in process (emulator) | {l:.1} ms | 0 | 0 |");
    outln!(
        "| over a pty to `ppmc bridge-sim` | {r:.1} ms | {trips} | {:.1} |",
        trips as f64 / suite.len() as f64
    );
    outln!("\nover the pty / in process: {:.1}x", r / l.max(1e-9));
    Ok(())
}

/// The suite over a noisy pty to the bridge simulator, with the shipped
/// link settings: per fault kind and rate, how many scenarios completed
/// with the verdict and trace of the clean in-process run (the rest ended
/// as link errors), and whether any got a wrong verdict.
fn parse_fault_row(s: &str) -> Result<(String, f64), String> {
    let (kind, pct) = s
        .split_once(':')
        .ok_or("write KIND:PERCENT, e.g. corrupt:1")?;
    if !["corrupt", "drop", "duplicate", "reorder", "mixed"].contains(&kind) {
        return Err(format!(
            "`{kind}`: the kinds are corrupt, drop, duplicate, reorder and mixed"
        ));
    }
    let pct: f64 = pct
        .parse()
        .map_err(|_| format!("`{pct}` is not a percentage"))?;
    if !(0.0..=100.0).contains(&pct) {
        return Err(format!("{pct}% is not a percentage"));
    }
    Ok((kind.to_string(), pct / 100.0))
}

fn noisy_link(seeds: u64, only: &[(String, f64)], suite: &[Scenario]) -> Result<(), CliError> {
    use ppmc::backend::{SerialLink, SerialOptions, SerialTarget};
    use ppmc::bridge::sim::{LinkFaults, PtyBridge};
    use ppmc::runner::run_suite;
    use ppmc::scenario::{DriverOptions, Verdict};

    let Ok(mut t) = EmuTarget::new(Straps::default(), ModelConfig::default()) else {
        return Err(CliError::Verdict);
    };
    let clean = run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
    let row = |name: &str, rate: f64| -> LinkFaults {
        let mut f = LinkFaults::default();
        match name {
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
    };
    let mut rows = Vec::new();
    for kind in ["corrupt", "drop", "duplicate"] {
        for rate in [0.001, 0.005, 0.01, 0.02] {
            rows.push((kind, rate));
        }
    }
    rows.push(("duplicate", 0.05));
    rows.push(("reorder", 0.005));
    rows.push(("mixed", 0.005));
    if !only.is_empty() {
        rows = only.iter().map(|(k, r)| (k.as_str(), *r)).collect();
    }
    outln!(
        "| line fault (each byte, both ways) | scenarios complete of {} | wrong verdicts | wall time (median) | round trips (median) |",
        suite.len()
    );
    outln!("|---|---:|---:|---:|---:|");
    let mut any_wrong = false;
    for (kind, rate) in rows {
        let what = if kind == "mixed" {
            format!(
                "{}% each of corrupt, drop, duplicate, reorder",
                rate * 100.0
            )
        } else {
            format!("{}% {kind}", rate * 100.0)
        };
        let (mut done, mut wrong, mut walls, mut trips) = (Vec::new(), 0, Vec::new(), Vec::new());
        for seed in 1..=seeds {
            let faults = LinkFaults {
                seed,
                ..row(kind, rate)
            };
            let emu = EmuTarget::new(Straps::default(), ModelConfig::default())
                .map_err(|e| CliError::Failed(e.to_string()))?;
            let sim = PtyBridge::start(emu, faults)
                .map_err(|e| CliError::Failed(format!("no bridge simulator: {e}")))?;
            let t0 = WallClock::now();
            let opened = SerialLink::open(sim.path(), 115_200)
                .and_then(|l| SerialTarget::open(l, SerialOptions::default()));
            let (ok, rt) = match opened {
                Ok(mut t) => {
                    let got = run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
                    let mut ok = 0;
                    for (g, c) in got.iter().zip(&clean) {
                        match &g.verdict {
                            Verdict::Error(e) => {
                                errln!("{what} seed {seed}: {}: {e}", g.name);
                            }
                            Verdict::NotRun(_) => {}
                            v if *v == c.verdict
                                && g.trace.as_ref().map(Trace::values)
                                    == c.trace.as_ref().map(Trace::values) =>
                            {
                                ok += 1
                            }
                            _ => wrong += 1,
                        }
                    }
                    (ok, t.stats.round_trips)
                }
                Err(e) => {
                    errln!("{what} seed {seed}: {e}");
                    (0, 0)
                }
            };
            walls.push(t0.elapsed().as_secs_f64() * 1e3);
            sim.stop();
            done.push(ok);
            trips.push(rt as f64);
        }
        any_wrong |= wrong > 0;
        let (lo, hi) = (
            done.iter().min().copied().unwrap_or(0),
            done.iter().max().copied().unwrap_or(0),
        );
        let span = if lo == hi {
            lo.to_string()
        } else {
            format!("{lo}-{hi}")
        };
        outln!(
            "| {what} | {span} | {wrong} | {:.2} s | {:.0} |",
            median_ms(walls) / 1e3,
            median_ms(trips)
        );
    }
    outln!("\n{seeds} seeds per row (1..={seeds}); `ppmc bench --noisy-link --seeds {seeds}`");
    if any_wrong {
        errln!("ppmc bench: a noisy link produced a wrong verdict");
        return Err(CliError::Verdict);
    }
    Ok(())
}
