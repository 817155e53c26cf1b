//! `ppmc compare`: a golden trace set against traces or a fresh run.

use super::args::{SelectArgs, TargetArgs, ToleranceArgs};
use crate::{usage, CliError};
use clap::Args;
use ppmc::golden::{self, GoldenError};
use ppmc::scenario::{HarnessError, Scenario, ScenarioResult, Verdict};
use ppmc::time::Duration;
use ppmc_record::{BoardInfo, RunOptions, RunRecord, MARGINAL_PCT};
use std::path::{Path, PathBuf};

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
    /// Write a JUnit XML report: a test case per scenario, a divergence a
    /// failure, an unusable file an error (as `ppmc run` writes them).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Write a JSON run record (docs/run-record.schema.json, as `ppmc run`
    /// writes it; the compared trace set stands as the board).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write the HTML report (docs/reports.md): each move's speed profile
    /// over the golden one with its tolerance band, the first divergence
    /// marked, the pins around it.
    #[arg(long, value_name = "FILE")]
    html: Option<PathBuf>,
    /// Keep the run record in a results store (docs/results-store.md).
    #[arg(long, value_name = "FILE")]
    store: Option<PathBuf>,
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
            junit: args.junit,
            json: args.json,
            html: args.html,
            store: args.store,
            artifacts: None,
            artifacts_window: super::run::Window::All,
            each: false,
            repeat: 1,
            retries: 0,
            retry_failures: false,
            flaky_is_failure: false,
            marginal: MARGINAL_PCT,
        };
        return super::run::run(run_args, suite);
    };
    if !dir.is_dir() {
        return Err(usage(format!(
            "{}: trace directory not found",
            dir.display()
        )));
    }
    super::reports::prepare_reports(
        args.junit.as_deref(),
        args.json.as_deref(),
        args.html.as_deref(),
        args.store.as_deref(),
    )?;
    let mut store = super::reports::open_store(args.store.as_deref())?;
    // A trace that diverges fails, as in `ppmc run --golden`; a file that
    // cannot be used (missing, unreadable, corrupt, at other straps) is an
    // error of its own: the file is at fault, not the board.
    let started = std::time::Instant::now();
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
    let mut results = Vec::with_capacity(scenarios.len());
    let mut figures = Vec::with_capacity(scenarios.len());
    for s in &scenarios {
        let mut r = ScenarioResult {
            name: s.name,
            section: s.section,
            tags: s.tags,
            verdict: Verdict::Passed,
            measurements: Vec::new(),
            trace: None,
            elapsed: Duration::ZERO,
            wall: std::time::Duration::ZERO,
            attempts: Vec::new(),
        };
        match golden::load(dir, s.name) {
            Ok(t) => {
                r.elapsed = Duration::from_nanos(t.events.last().map_or(0, |e| e.at.as_nanos()));
                r.trace = Some(t);
                let golden = super::run::check_golden(&mut r, &args.golden, &tol);
                figures.push(super::run::figures_of(&r, golden.as_ref()));
                r.trace = None;
            }
            Err(GoldenError::Missing { path }) => {
                r.verdict = Verdict::Error(HarnessError::Golden(missing(dir, &path)));
            }
            Err(e) => r.verdict = Verdict::Error(HarnessError::Golden(e.to_string())),
        }
        figures.resize(results.len() + 1, None);
        outln!("{}", super::run::verdict_line(&r, None));
        results.push(r);
    }
    info.wall_s = started.elapsed().as_secs_f64();
    let scenarios = results.iter().zip(figures).map(|(r, figures)| {
        let record = r.record(Some(&board));
        ppmc_record::ScenarioRecord { figures, ..record }
    });
    let record = RunRecord::new(info, scenarios.collect());
    let outputs = super::reports::Outputs::of(&args.junit, &args.json, &args.html);
    let problems = super::reports::write(&record, outputs, store.as_mut());
    let count = |f: fn(&Verdict) -> bool| results.iter().filter(|r| f(&r.verdict)).count();
    let ok = count(|v| v.ok());
    let bad = count(|v| matches!(v, Verdict::Failed(_)));
    let errors = count(|v| matches!(v, Verdict::Error(_)));
    outln!("compare: {ok} passed, {bad} failed, {errors} errors");
    if let Some(p) = problems.first() {
        return Err(CliError::Failed(p.clone()));
    }
    if bad + errors == 0 {
        Ok(())
    } else {
        Err(CliError::Verdict)
    }
}

/// The error of a scenario the compared set has no trace of: the
/// recording's gap, not the golden set's.
fn missing(dir: &Path, path: &Path) -> String {
    format!(
        "{}: no trace of this scenario in {} (record it there with `ppmc record --out {}`)",
        path.display(),
        dir.display(),
        dir.display()
    )
}
