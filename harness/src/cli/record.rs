//! `ppmc record`: golden traces from a run.

use super::args::{SelectArgs, TargetArgs};
use super::progress::Progress;
use crate::cli::{usage, CliError};
use crate::golden::{self, GoldenError, Written};
use crate::runner::run_suite;
use crate::scenario::{DriverOptions, Scenario};
use clap::Args;
use std::path::PathBuf;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct RecordArgs {
    #[command(flatten)]
    select: SelectArgs,
    #[command(flatten)]
    target: TargetArgs,
    /// Where the golden files go.
    #[arg(long, default_value = "golden")]
    out: PathBuf,
    /// Replace golden files that exist and differ. Without it, nothing is
    /// ever overwritten.
    #[arg(long)]
    bless: bool,
    /// Record scenarios that did not pass too (normally refused, so that a
    /// broken run never becomes the reference).
    #[arg(long)]
    allow_failures: bool,
}

pub fn run(args: RecordArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    let mut target = args.target.open()?;
    let progress = Progress::new(scenarios.len());
    let mut counts = [0usize; 4]; // created, replaced, unchanged, refused
    let mut failed = false;
    run_suite(
        target.as_mut(),
        &scenarios,
        1,
        DriverOptions::default(),
        |r| {
            progress.step(r.name);
            let outcome = match (&r.trace, r.verdict.ok() || args.allow_failures) {
                (None, _) => Err(format!("{}: the target gave no capture", r.name)),
                (Some(_), false) => Err(format!(
                    "{}: not recorded, it did not pass ({}); fix it or pass --allow-failures",
                    r.name,
                    r.verdict.detail().unwrap_or_default()
                )),
                (Some(t), true) => golden::write(&args.out, t, args.bless).map_err(|e| match e {
                    GoldenError::Exists { .. } => format!("{e} (it differs from this run)"),
                    other => other.to_string(),
                }),
            };
            match outcome {
                Ok(w) => {
                    let (i, word) = match w {
                        Written::Created => (0, "created"),
                        Written::Replaced => (1, "replaced"),
                        Written::Unchanged => (2, "unchanged"),
                    };
                    counts[i] += 1;
                    progress.line(&format!(
                        "{word:<9} {}",
                        golden::path_for(&args.out, r.name).display()
                    ));
                }
                Err(e) => {
                    counts[3] += 1;
                    failed = true;
                    progress.line(&format!("refused   {e}"));
                }
            }
        },
    );
    progress.finish();
    println!(
        "{} created, {} replaced, {} unchanged, {} refused",
        counts[0], counts[1], counts[2], counts[3]
    );
    if failed {
        Err(CliError::Verdict)
    } else {
        Ok(())
    }
}
