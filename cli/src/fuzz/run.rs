//! `ppmc fuzz [run] --target <t>`: a differential run against a target.

use crate::args::TargetArgs;
use crate::{usage, CliError};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ppmc::backend::{EmuTarget, Target};
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
    /// a departure is replayed from the seed, not from memory.
    #[arg(long, default_value_t = 1_000)]
    ops: usize,
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
    let straps = match args.target.straps() {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
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
    let mut target: Box<dyn Target> = if args.target.name() == "emu" {
        let mut model = args.target.model();
        if let Err(e) = ppmc::faults::apply_all(&args.chip_faults, &mut model) {
            return Err(usage(format!("--chip-fault: {e}")));
        }
        match EmuTarget::new(straps, model) {
            Ok(t) => Box::new(t),
            Err(e) => return Err(usage(e)),
        }
    } else if !args.chip_faults.is_empty() {
        return Err(usage(
            "--chip-fault applies to --target emu; a bridge simulator takes it as `ppmc bridge-sim --chip-fault`",
        ));
    } else {
        args.target.open()?
    };
    // On a board, its bridge's straps (the emulator's are those given).
    let straps = target.straps();
    let settings = DiffSettings {
        straps,
        reference: args.target.model(),
        ..DiffSettings::default()
    };
    let name = args.target.name().to_string();
    errln!(
        "ppmc fuzz: seed {seed}, {} actions against {name} (replay with --seed {seed})",
        args.ops
    );
    // Generated as they run: a billion actions cost no more memory than ten.
    let n = args.ops.max(1);
    let bar = ProgressBar::new(n as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} actions {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = WallClock::now();
    let limit = args
        .duration
        .map(|d| std::time::Duration::from_nanos(d.as_nanos()));
    let mut done = 0;
    let acts = differential::program(seed).take(n);
    let result = differential::run(target.as_mut(), acts, &settings, |n| {
        done = n;
        bar.set_position(n as u64);
        limit.is_none_or(|l| t0.elapsed() < l)
    });
    bar.finish_and_clear();
    let departure = match result {
        Ok(d) => d,
        Err(e) => {
            errln!("ppmc fuzz: infrastructure error after {done} actions: {e}");
            return Err(CliError::Verdict);
        }
    };
    let Some(d) = departure else {
        outln!(
            "seed {seed}: {done} actions in {:.1} s, no departure from the emulator",
            t0.elapsed().as_secs_f64()
        );
        return Ok(());
    };
    outln!("seed {seed}: {d}");
    // The seed replays the run up to the departure.
    let acts: Vec<_> = differential::program(seed).take(d.action + 1).collect();
    let (small, small_d) =
        match differential::minimize(target.as_mut(), &acts, &settings, args.minimize_budget) {
            Ok(x) => x,
            Err(e) => {
                errln!("ppmc fuzz: infrastructure error while minimizing: {e}");
                return Err(CliError::Verdict);
            }
        };
    let (acts_out, d_out) = match small_d {
        Some(sd) => (small, sd),
        // Not reproducible from a reset (a flaky board): keep the whole run.
        None => {
            errln!("ppmc fuzz: the departure did not repeat from a reset; keeping the whole run");
            (acts, d.clone())
        }
    };
    let text = differential::script(&acts_out, &d_out, seed, &name);
    ppmc_files::write(&out, text.as_bytes())?;
    outln!(
        "minimized to {} actions; reproducer written to {}",
        acts_out.len(),
        out.display()
    );
    Err(CliError::Verdict)
}
