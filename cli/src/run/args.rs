//! `ppmc run`'s arguments, and the options they put on record.

use crate::args::ReportArgs;
use crate::args::{SelectArgs, TargetArgs, ToleranceArgs};
use crate::{usage, CliError};
use clap::Args;
use ppmc::artifacts::Window;
use std::path::PathBuf;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub(crate) select: SelectArgs,
    #[command(flatten)]
    pub(crate) target: TargetArgs,
    /// Compare each scenario's trace with its golden trace in DIR as it runs.
    #[arg(long, value_name = "DIR")]
    pub(crate) golden: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) tolerance: ToleranceArgs,
    #[command(flatten)]
    pub(crate) reports: ReportArgs,
    /// Keep the trace and VCD of every scenario that did not pass here.
    /// The VCD shows `--artifacts-window` either side of the failure.
    #[arg(long, value_name = "DIR")]
    pub(crate) artifacts: Option<PathBuf>,
    /// How much of a failed scenario's waveform `--artifacts` writes:
    /// this long before and after the failure (e.g. 10ms), or `all` for
    /// the whole trace (a failure in the 16,777,216-step move makes a VCD
    /// of some 650 MB). A scenario that ended in an error has no failure
    /// time: its VCD is whole.
    #[arg(long, value_name = "DURATION|all", default_value = "10ms", value_parser = parse_window)]
    pub(crate) artifacts_window: Window,
    /// With several `--target`s: run the whole selection on every board
    /// (to compare boards), instead of spreading it over them.
    #[arg(long)]
    pub(crate) each: bool,
    /// Run the selection this many times (soak runs). Memory stays flat:
    /// the reports list the first pass and every run that did not pass (up
    /// to 1,000 after the first pass), and count the other runs per
    /// scenario and board (verdicts, each measurement's min, mean and
    /// max). SIGINT or SIGTERM stops after the scenario under way and
    /// still writes the reports.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) repeat: u32,
    /// Try a scenario that ended in a link or bridge error again, up to N
    /// times, on the same board. Every attempt stays on record (JUnit in
    /// Maven Surefire's dialect, the JSON record, the HTML report); one
    /// that passed only on a retry is FLAKY, never plainly passed.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub(crate) retries: u32,
    /// With --retries: try a device failure again too (a board that fails
    /// and then passes is flaky hardware, and says so).
    #[arg(long, requires = "retries")]
    pub(crate) retry_failures: bool,
    /// A scenario that passed only on a retry fails the run (exit 1).
    #[arg(long)]
    pub(crate) flaky_is_failure: bool,
    /// On a board: the longest one scenario may take on the wall clock,
    /// e.g. 90s, 20m. Past it the host tells the bridge to stop (ABORT:
    /// the move is stopped, the chip left idle), the scenario is an error
    /// naming the limit, and the run goes on. Default: no limit but each
    /// scenario's own budget of chip time.
    #[arg(long, value_name = "DURATION", value_parser = crate::args::parse_duration)]
    pub(crate) timeout: Option<ppmc::time::Duration>,
    /// Width of the MARGINAL zone inside each Table 3-3 limit, in percent of
    /// the limit.
    #[arg(long, default_value_t = ppmc_record::MARGINAL_PCT)]
    pub(crate) marginal: f64,
    #[command(flatten)]
    pub(crate) power: crate::power::PowerArgs,
}

fn parse_window(s: &str) -> Result<Window, String> {
    if s == "all" {
        return Ok(Window::All);
    }
    crate::args::parse_duration(s).map(Window::Around)
}

impl RunArgs {
    /// What can be told wrong before the run: the marginal zone, every
    /// output (tried, not found unusable after the run), the golden folder.
    pub(super) fn check(&self) -> Result<(), CliError> {
        if !(self.marginal.is_finite() && (0.0..=50.0).contains(&self.marginal)) {
            return Err(usage(format!(
                "--marginal {}: give a percentage from 0 to 50",
                self.marginal
            )));
        }
        if let Some(dir) = &self.artifacts {
            ppmc_files::prepare_folder(dir)?;
        }
        self.reports.prepare()?;
        if self.reports.store.is_some() && self.repeat > 1 {
            return Err(usage(
                "--store with --repeat: a soak's record lists its first pass and what did not pass, and counts the rest, so the store would see its failures and not its passes; store single runs",
            ));
        }
        match &self.golden {
            Some(dir) if !dir.is_dir() => Err(usage(format!(
                "{}: golden directory not found",
                dir.display()
            ))),
            _ => Ok(()),
        }
    }
}

impl RunArgs {
    /// `ppmc run` with no argument: every option at the default its
    /// `--help` shows (one definition, the attribute's).
    pub(crate) fn defaults() -> Result<RunArgs, clap::Error> {
        use clap::Parser;
        #[derive(Debug, Parser)]
        struct Bare {
            #[command(flatten)]
            run: RunArgs,
        }
        Bare::try_parse_from(["run"]).map(|b| b.run)
    }
}
