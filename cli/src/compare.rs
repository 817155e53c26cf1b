//! `ppmc compare`: a golden trace set against traces or a fresh run.

use super::args::{SelectArgs, TargetArgs, ToleranceArgs};
use crate::args::ReportArgs;
use crate::lines::verdict_line;
use crate::run::RunArgs;
use crate::{usage, CliError};
use clap::Args;
use ppmc::scenario::Scenario;
use ppmc::session;
use ppmc_record::{BoardInfo, RunOptions};
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
    #[command(flatten)]
    reports: ReportArgs,
}

pub fn run(args: CompareArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let tol = args.tolerance.tolerances().map_err(usage)?;
    if !args.golden.is_dir() {
        let dir = args.golden.display();
        return Err(usage(format!("{dir}: golden directory not found")));
    }
    let scenarios = args.select.scenarios(suite).map_err(usage)?;
    let Some(dir) = &args.traces else {
        // Against a target: the run itself, with the golden check.
        let run = RunArgs {
            select: args.select,
            target: args.target,
            golden: Some(args.golden),
            tolerance: args.tolerance,
            reports: args.reports,
            ..RunArgs::defaults().map_err(|e| CliError::Failed(e.to_string()))?
        };
        return super::run::run(run, suite);
    };
    if !dir.is_dir() {
        return Err(usage(format!(
            "{}: trace directory not found",
            dir.display()
        )));
    }
    args.reports.prepare()?;
    let mut store = args.reports.open_store()?;
    let board = dir.display().to_string();
    let traces = BoardInfo::new(board.clone(), format!("traces:{board}"), Vec::new(), None);
    let mut info = ppmc::runner::run_info(vec![traces], "one");
    info.options = RunOptions {
        repeat: 1,
        golden: Some(args.golden.display().to_string()),
        marginal_pct: 0.0,
        latency_tol_pct: tol.latency_bp as f64 / 100.0,
        interval_tol_pct: tol.interval_bp as f64 / 100.0,
        time_floor_ns: tol.floor.as_nanos(),
        ..Default::default()
    };
    args.select.describe(&mut info.options);
    let record = session::compare_sets(&scenarios, &args.golden, dir, &tol, info, |r| {
        outln!("{}", verdict_line(r, None));
    });
    let problems = crate::reports::write(&record, args.reports.outputs(), store.as_mut());
    let t = record.summary;
    let ok = t.passed + t.marginal + t.flaky;
    outln!(
        "compare: {ok} passed, {} failed, {} errors",
        t.failed,
        t.errors
    );
    if let Some(p) = problems.first() {
        return Err(CliError::Failed(p.clone()));
    }
    match t.failed + t.errors {
        0 => Ok(()),
        _ => Err(CliError::Verdict),
    }
}
