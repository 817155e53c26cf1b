//! `ppmc fuzz [run] --target <t>`: a differential run against a target.

use crate::args::TargetArgs;
use crate::{usage, CliError};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ppmc::fuzzing::differential::{self, DiffSettings};
use std::path::PathBuf;
use std::time::Instant as WallClock;

#[derive(Debug, Args)]
pub struct DiffArgs {
    #[command(flatten)]
    target: TargetArgs,
    /// Seed of the action stream; the seed alone replays a run. Default: one
    /// taken from the clock, printed so that the run can be replayed.
    #[arg(long)]
    seed: Option<u64>,
    /// Actions to run (each a command with its parameter bytes, a wait, an
    /// input change or a register read, with the flowchart's waits).
    /// Memory does not grow with them: the run keeps what came since both
    /// sides were last at rest and agreed (and the last move's records);
    /// a departure is replayed from the seed, not from memory. Default:
    /// 1000, or no limit with --budget.
    #[arg(long)]
    ops: Option<usize>,
    /// Stop when the target's own clock (from its chip reset) has run
    /// this long, e.g. 60s: the same budget of board time as a `fuzz
    /// campaign`, to measure one against the other.
    #[arg(long, value_name = "DURATION", value_parser = crate::args::parse_duration)]
    budget: Option<ppmc::time::Duration>,
    /// Stop after this much wall time (e.g. 30s, 5m, 1h) even if --ops
    /// are not done.
    #[arg(long, value_parser = crate::args::parse_wall_duration)]
    duration: Option<ppmc::time::Duration>,
    /// Where to write the minimized reproducer (a console script).
    /// Default: fuzz-diff-<seed>.ppmc in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Most replays spent minimizing a departure on the target.
    #[arg(long, default_value_t = 200)]
    minimize_budget: usize,
    /// With --target emu: run the target emulator with this board fault
    /// (`ppmc fault-matrix --list`) against the clean reference.
    #[arg(long = "chip-fault", value_name = "FAULT")]
    chip_faults: Vec<String>,
}

pub fn run(args: DiffArgs) -> Result<(), CliError> {
    let straps = args.target.straps().map_err(usage)?;
    let seed = args.seed.unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(1, |d| d.as_nanos() as u64)
    });
    // Where a departure's reproducer goes, tried before the run.
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("fuzz-diff-{seed}.ppmc")));
    ppmc_files::check_writable(&out)?;
    let mut target = super::departure::open(&args.target, straps, &args.chip_faults)?;
    // On a board, its bridge's straps (the emulator's are those given).
    let straps = target.straps();
    let settings = DiffSettings {
        straps,
        reference: args.target.model(),
        ..DiffSettings::default()
    };
    let name = args.target.name().to_string();
    let n = match (args.ops, args.budget) {
        (Some(n), _) => n.max(1),
        (None, Some(_)) => usize::MAX,
        (None, None) => 1_000,
    };
    let budget = args.budget.map(|b| b.to_string());
    errln!(
        "ppmc fuzz: seed {seed}, {} against {name} (replay with --seed {seed})",
        match (&budget, args.ops) {
            (Some(b), None) => format!("{b} of board time"),
            (Some(b), Some(_)) => format!("{n} actions or {b} of board time"),
            (None, _) => format!("{n} actions"),
        }
    );
    // Generated as they run: a billion actions cost no more memory than ten.
    let bar = match args.budget {
        Some(b) => ProgressBar::new(b.as_nanos() / 1_000_000),
        None => ProgressBar::new(n as u64),
    };
    bar.set_style(
        ProgressStyle::with_template(match args.budget {
            Some(_) => "{bar:40} {pos}/{len} ms of board time {elapsed} {msg}",
            None => "{bar:40} {pos}/{len} actions {elapsed} {msg}",
        })
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = WallClock::now();
    let limit = args
        .duration
        .map(|d| std::time::Duration::from_nanos(d.as_nanos()));
    let (mut done, mut board) = (0, ppmc::time::Duration::ZERO);
    // The stream's domain coverage, counted as `fuzz campaign` counts its
    // features, to measure the two on one scale.
    let mut coverage = ppmc::fuzzing::campaign::Coverage::default();
    let mut walk = ppmc::fuzzing::campaign::Walk::new();
    let acts = differential::program(seed).take(n);
    let result = differential::run(target.as_mut(), acts, &settings, |step| {
        (done, board) = (step.actions, step.board_time);
        if let Some(w) = walk.as_mut() {
            step.ops.iter().for_each(|op| w.step(&mut coverage, *op));
        }
        match args.budget {
            Some(_) => bar.set_position(board.as_nanos() / 1_000_000),
            None => bar.set_position(done as u64),
        }
        limit.is_none_or(|l| t0.elapsed() < l) && args.budget.is_none_or(|b| board < b)
    });
    bar.finish_and_clear();
    let spent = format!(
        "{done} actions in {:.1} s of board time ({:.1} s wall), {} features",
        board.as_secs_f64(),
        t0.elapsed().as_secs_f64(),
        coverage.cells().len()
    );
    match result {
        Ok(None) => {
            outln!("seed {seed}: {spent}, no departure from the emulator");
            Ok(())
        }
        Ok(Some(d)) => {
            outln!("seed {seed}: {d}");
            outln!("seed {seed}: departed after {spent}");
            super::departure::keep(
                target.as_mut(),
                &settings,
                seed,
                &name,
                &d,
                args.minimize_budget,
                &out,
            )
        }
        Err(e) => {
            errln!("ppmc fuzz: infrastructure error after {done} actions: {e}");
            Err(CliError::Verdict)
        }
    }
}
