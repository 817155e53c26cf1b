//! `ppmc fuzz campaign --target T --budget 60s`: a guided campaign of
//! `bus_bytes` inputs against any target ([`ppmc::fuzzing::guided`]).

use crate::args::TargetArgs;
use crate::CliError;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ppmc::fuzzing::guided::{self, Event, Settings};
use ppmc::scenario::Scenario;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct CampaignArgs {
    #[command(flatten)]
    target: TargetArgs,
    /// Board time to spend (the board's clock from each chip reset to an
    /// input's last op, summed), e.g. 60s, 10m: a slow link costs wall
    /// time, not budget.
    #[arg(long, value_name = "DURATION", default_value = "60s", value_parser = crate::args::parse_duration)]
    budget: ppmc::time::Duration,
    /// The corpus: inputs that reached new coverage are written here, and
    /// those already here are run first (a campaign resumes where one
    /// left off). Default: none kept.
    #[arg(long, value_name = "DIR")]
    corpus: Option<PathBuf>,
    /// Seed inputs (`bus_bytes` files, e.g. fuzz/corpus/bus_bytes/); repeat
    /// for several folders. Default: the conformance suite's bus traffic.
    #[arg(long, value_name = "DIR")]
    seeds: Vec<PathBuf>,
    /// Where each finding is written, as a `bus_bytes` input named after
    /// the invariant it breaks (flaky ones start `flaky-`).
    #[arg(long, value_name = "DIR", default_value = "fuzz-findings")]
    findings: PathBuf,
    /// Seed of the mutations: the same seeds, target and seed give the
    /// same campaign.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// An input is cut where its waits would take the board past this
    /// (board time per execution, from the chip reset): shorter inputs,
    /// more executions per board-second.
    #[arg(long, value_name = "DURATION", default_value = "1s", value_parser = crate::args::parse_duration)]
    max_input_time: ppmc::time::Duration,
    /// No feedback: every input a mutation of a seed, nothing kept (the
    /// blind baseline to measure guidance against).
    #[arg(long)]
    blind: bool,
    /// Judge by the datasheet's invariants alone: not also against the
    /// reference model run on the board's timeline (for a board built to
    /// differ from the model).
    #[arg(long)]
    no_model: bool,
    /// A board that hangs under an input (its bridge silent, or its chip
    /// BUSY after a chip reset) is brought back by a chip reset, else by
    /// its power switch, and the input is kept as a finding.
    #[command(flatten)]
    power: crate::power::PowerArgs,
}

pub fn run(mut args: CampaignArgs, suite: &[Scenario]) -> Result<(), CliError> {
    // SIGINT and SIGTERM end the campaign after the input under way, with
    // its summary.
    let stop = crate::signals::install();
    args.target.stop = stop.clone();
    ppmc_files::prepare_folder(&args.findings)?;
    if let Some(dir) = &args.corpus {
        ppmc_files::prepare_folder(dir)?;
    }
    let seeds = super::corpus::seeds(&args.seeds, args.corpus.as_deref(), suite)?;
    let spec = args.target.single().map_err(crate::usage)?;
    let mut power = ppmc::backend::Power::of(&spec, &args.power.options(), &stop);
    let mut target = args.target.open()?;
    let settings = Settings {
        budget: args.budget,
        seed: args.seed,
        blind: args.blind,
        max_input_time: args.max_input_time,
        model: (!args.no_model).then(|| args.target.model()),
        ..Settings::default()
    };
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let t0 = std::time::Instant::now();
    let mut written: Result<(), CliError> = Ok(());
    // Board time when the last execution ended: where a finding came.
    let mut board = 0.0;
    let stats = guided::run(target.as_mut(), power.as_mut(), &seeds, &settings, |e| {
        let w = match e {
            Event::NewCoverage { input, .. } => match &args.corpus {
                Some(dir) => {
                    super::corpus::keep(dir, &format!("{}.bin", guided::name(input)), input)
                }
                None => Ok(()),
            },
            Event::Finding(f) => {
                let hang = matches!(f.what, guided::What::Hang { .. });
                let label = match (hang, f.repeated) {
                    (true, _) | (false, true) => "finding",
                    (false, false) => "flaky",
                };
                let flaky = if label == "flaky" { "flaky-" } else { "" };
                let name = format!("{flaky}{}-{}.bin", f.what.name(), guided::name(&f.input));
                bar.suspend(|| {
                    let at = args.findings.join(&name);
                    outln!(
                        "{label} at {board:.3} s of board time: {} -> {}",
                        f.what,
                        at.display()
                    )
                });
                super::corpus::keep(&args.findings, &name, &f.input)
            }
            Event::Progress(s) => {
                board = s.board_time.as_secs_f64();
                bar.set_message(format!(
                    "{} executions, {:.1} per board-second, {} features, {} findings ({} flaky), board time {:.1} s",
                    s.executions, s.per_board_second(), s.features, s.findings, s.flaky, s.board_time.as_secs_f64()
                ));
                Ok(())
            }
        };
        written = w;
        written.is_ok() && !stop.requested()
    });
    bar.finish_and_clear();
    written?;
    let s = stats.map_err(|e| CliError::Failed(format!("infrastructure error: {e}")))?;
    outln!(
        "campaign on {}: {} executions in {:.1} s of board time ({:.1} per board-second; {:.1} s wall), {} features, corpus {}, {} findings ({} hangs), {} flaky",
        args.target.name(),
        s.executions,
        s.board_time.as_secs_f64(),
        s.per_board_second(),
        t0.elapsed().as_secs_f64(),
        s.features,
        s.corpus,
        s.findings,
        s.hangs,
        s.flaky
    );
    (s.findings == 0).then_some(()).ok_or(CliError::Verdict)
}
