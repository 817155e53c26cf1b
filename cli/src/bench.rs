//! `ppmc bench`: wall-clock figures for the emulator and the bridge path,
//! printed as Markdown tables (the source of `docs/performance.md`). The
//! measuring is the library's (`ppmc::bench`).

use crate::CliError;
use clap::Args;
use ppmc::backend::EmuTarget;
use ppmc::bench::{self, median};
use ppmc::emu::ModelConfig;
use ppmc::protocol::Straps;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Scenario};

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

pub fn run(args: BenchArgs, suite: &[Scenario]) -> Result<(), CliError> {
    if args.noisy_link {
        return noisy_link(args.seeds.max(1), args.faults, suite);
    }
    outln!("| case | median wall time | pulses | stored runs | virtual time |");
    outln!("|---|---:|---:|---:|---:|");
    for (name, f) in &bench::emulator_cases() {
        let (ms, o) = bench::time_case(args.repeat, f);
        let secs = o.virtual_time.as_secs_f64();
        outln!(
            "| {name} | {ms:.3} ms | {} | {} | {secs:.3} s |",
            o.pulses,
            o.runs
        );
    }
    let Some((ms, pulses)) = bench::expansion() else {
        errln!("ppmc bench: the emulator could not be built");
        return Err(CliError::Verdict);
    };
    outln!("| per-pulse expansion of the 16,777,216-step record | {ms:.3} ms | {pulses} | - | - |");
    outln!();
    let b = bench::suite_over_bridge(args.repeat.clamp(1, 5), suite).map_err(|e| {
        errln!("ppmc bench: {e}");
        CliError::Verdict
    })?;
    let (l, r, trips) = (b.local_ms, b.remote_ms, b.round_trips);
    outln!("| conformance suite ({} scenarios) | median wall time | round trips | round trips per scenario |", suite.len());
    outln!("|---|---:|---:|---:|");
    outln!("| in process (emulator) | {l:.1} ms | 0 | 0 |");
    let per = trips as f64 / suite.len() as f64;
    outln!("| over a pty to `ppmc bridge-sim` | {r:.1} ms | {trips} | {per:.1} |");
    outln!("\nover the pty / in process: {:.1}x", r / l.max(1e-9));
    Ok(())
}

/// A `--fault` row: `KIND:PERCENT`.
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

/// The suite over a noisy pty to the bridge simulator, with the shipped
/// link settings: per fault kind and rate, how many scenarios completed
/// with the verdict and trace of the clean in-process run (the rest ended
/// as link errors), and whether any got a wrong verdict.
fn noisy_link(seeds: u64, only: Vec<(String, f64)>, suite: &[Scenario]) -> Result<(), CliError> {
    let mut t = EmuTarget::new(Straps::default(), ModelConfig::default())
        .map_err(|e| CliError::Failed(e.to_string()))?;
    let clean = run_suite(&mut t, suite, 1, DriverOptions::default(), |_| {});
    let rows = match only.is_empty() {
        true => bench::noisy_rows(),
        false => only,
    };
    outln!(
        "| line fault (each byte, both ways) | scenarios complete of {} | wrong verdicts | wall time (median) | round trips (median) |",
        suite.len()
    );
    outln!("|---|---:|---:|---:|---:|");
    let mut any_wrong = false;
    for (kind, rate) in rows {
        let what = match kind.as_str() {
            "mixed" => format!(
                "{}% each of corrupt, drop, duplicate, reorder",
                rate * 100.0
            ),
            _ => format!("{}% {kind}", rate * 100.0),
        };
        let (mut done, mut wrong, mut walls, mut trips) = (Vec::new(), 0, Vec::new(), Vec::new());
        for seed in 1..=seeds {
            let faults = ppmc::bridge::sim::LinkFaults {
                seed,
                ..bench::line_faults(&kind, rate)
            };
            let s = bench::noisy_seed(faults, suite, &clean).map_err(CliError::Failed)?;
            for e in &s.errors {
                errln!("{what} seed {seed}: {e}");
            }
            done.push(s.complete);
            wrong += s.wrong;
            walls.push(s.wall_ms);
            trips.push(s.round_trips as f64);
        }
        any_wrong |= wrong > 0;
        let (lo, hi) = (done.iter().min(), done.iter().max());
        let span = match (lo, hi) {
            (Some(lo), Some(hi)) if lo != hi => format!("{lo}-{hi}"),
            (Some(lo), _) => lo.to_string(),
            _ => "0".into(),
        };
        let (wall_s, rt) = (median(walls) / 1e3, median(trips));
        outln!("| {what} | {span} | {wrong} | {wall_s:.2} s | {rt:.0} |");
    }
    outln!("\n{seeds} seeds per row (1..={seeds}); `ppmc bench --noisy-link --seeds {seeds}`");
    if any_wrong {
        errln!("ppmc bench: a noisy link produced a wrong verdict");
        return Err(CliError::Verdict);
    }
    Ok(())
}
