//! `ppmc compare`: a golden trace set against traces or a fresh run.

use super::args::{SelectArgs, TargetArgs, ToleranceArgs};
use crate::cli::{usage, CliError};
use crate::compare::compare;
use crate::golden::{self};
use crate::scenario::Scenario;
use clap::Args;
use std::path::PathBuf;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The golden trace set.
    golden: PathBuf,
    /// A second trace set to compare (a board revision's recording). Without
    /// it, the scenarios run on --target and are compared as they run.
    #[arg(long, value_name = "DIR")]
    traces: Option<PathBuf>,
    #[command(flatten)]
    select: SelectArgs,
    #[command(flatten)]
    target: TargetArgs,
    #[command(flatten)]
    tolerance: ToleranceArgs,
}

pub fn run(args: CompareArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let tol = match args.tolerance.tolerances() {
        Ok(t) => t,
        Err(e) => return Err(usage(e)),
    };
    if !args.golden.is_dir() {
        return Err(usage(format!(
            "{}: golden directory not found",
            args.golden.display()
        )));
    }
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    let Some(dir) = &args.traces else {
        // Against a target: the run itself, with the golden check.
        let run_args = super::run::RunArgs {
            select: args.select,
            target: args.target,
            golden: Some(args.golden),
            tolerance: args.tolerance,
            junit: None,
            json: None,
            artifacts: None,
            artifacts_window: super::run::Window::All,
            board_rev: None,
            each: false,
            repeat: 1,
            marginal: 0.25,
        };
        return super::run::run(run_args, suite);
    };
    if !dir.is_dir() {
        return Err(usage(format!(
            "{}: trace directory not found",
            dir.display()
        )));
    }
    // A trace that diverges fails; a file that cannot be used (missing,
    // unreadable, corrupt, at other straps) is an error of its own: the
    // file is at fault, not the board.
    let (mut ok, mut bad, mut errors) = (0usize, 0usize, 0usize);
    for s in &scenarios {
        // Traces at other straps than the golden's are refused by name.
        let pair = golden::load(dir, s.name)
            .and_then(|t| golden::load_for(&args.golden, s.name, &t.straps).map(|g| (g, t)));
        let line = match pair {
            Ok((g, t)) => match compare(&g, &t, &tol) {
                Ok(()) => {
                    ok += 1;
                    format!("MATCH    {}", s.name)
                }
                Err(d) => {
                    bad += 1;
                    format!("DIVERGE  {}\n         first divergence {d}", s.name)
                }
            },
            Err(e) => {
                errors += 1;
                format!("BAD FILE {}\n         {e}", s.name)
            }
        };
        outln!("{line}");
    }
    outln!("compare: {ok} passed, {bad} failed, {errors} errors");
    if bad + errors == 0 {
        Ok(())
    } else {
        Err(CliError::Verdict)
    }
}
