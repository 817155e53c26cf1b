//! `ppmc record`: golden traces from a run.

use super::args::{SelectArgs, TargetArgs};
use super::progress::Progress;
use crate::{usage, CliError};
use clap::Args;
use ppmc::golden::{self, GoldenError, Written};
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Scenario, Verdict};
use ppmc_files as files;
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
    /// Record scenarios the device failed too (normally refused, so that a
    /// broken board never becomes the reference). Scenarios that ended in a
    /// harness or link error, or did not run, are never recorded: their
    /// capture is incomplete.
    #[arg(long)]
    allow_failures: bool,
}

pub fn run(args: RecordArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    // The folder is made and tried before the run, not found unusable
    // after it.
    files::prepare_folder(&args.out)?;
    let mut target = args.target.open()?;
    let progress = Progress::new(scenarios.len());
    let mut tally = Tally::default();
    run_suite(
        target.as_mut(),
        &scenarios,
        1,
        DriverOptions::default(),
        |r| {
            progress.step(r.name);
            match golden::admit(r, args.allow_failures) {
                Err(why) => {
                    tally.refused += 1;
                    progress.line(&format!("refused   {}: {why}", r.name));
                }
                Ok(t) => match golden::write(&args.out, t, args.bless) {
                    Ok(w) => {
                        let word = tally.count(w);
                        if matches!(r.verdict, Verdict::Failed(_)) {
                            tally.device_failures += 1;
                        }
                        progress.line(&format!(
                            "{word:<9} {}",
                            golden::path_for(&args.out, r.name).display()
                        ));
                    }
                    Err(GoldenError::Exists { path }) => {
                        tally.refused += 1;
                        progress.line(&format!(
                            "refused   {}: exists and differs from this run; pass --bless to replace it",
                            path.display()
                        ));
                    }
                    Err(e) => {
                        tally.write_errors += 1;
                        progress.line(&format!("error     {e}"));
                    }
                },
            }
        },
    );
    progress.finish();
    outln!(
        "{} created, {} replaced, {} unchanged, {} refused, {} not written (I/O errors)",
        tally.created,
        tally.replaced,
        tally.unchanged,
        tally.refused,
        tally.write_errors
    );
    if tally.device_failures > 0 {
        outln!(
            "{} of the golden traces are of scenarios the device failed (--allow-failures)",
            tally.device_failures
        );
    }
    if tally.refused + tally.write_errors > 0 {
        Err(CliError::Verdict)
    } else {
        Ok(())
    }
}

#[derive(Debug, Default)]
struct Tally {
    created: usize,
    replaced: usize,
    unchanged: usize,
    refused: usize,
    write_errors: usize,
    device_failures: usize,
}

impl Tally {
    /// Counts a file written; the word for its line.
    fn count(&mut self, w: Written) -> &'static str {
        let (n, word) = match w {
            Written::Created => (&mut self.created, "created"),
            Written::Replaced => (&mut self.replaced, "replaced"),
            Written::Unchanged => (&mut self.unchanged, "unchanged"),
        };
        *n += 1;
        word
    }
}
