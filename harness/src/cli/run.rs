//! `ppmc run`: the conformance suite on a target, graded, with reports.

use super::args::{SelectArgs, TargetArgs, ToleranceArgs};
use super::progress::Progress;
use crate::cli::{usage, CliError};
use crate::compare::{compare, Tolerances};
use crate::files;
use crate::golden::{self};
use crate::report::{self, RunInfo, RunOptions, Tally};
use crate::runner::run_suite_until;
use crate::scenario::{
    DriverOptions, Failure, Grading, HarnessError, NotRun, Scenario, ScenarioResult, Verdict,
};
use crate::time::Duration;
use clap::Args;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub(super) select: SelectArgs,
    #[command(flatten)]
    pub(super) target: TargetArgs,
    /// Compare each scenario's trace with its golden trace in DIR as it runs.
    #[arg(long, value_name = "DIR")]
    pub(super) golden: Option<PathBuf>,
    #[command(flatten)]
    pub(super) tolerance: ToleranceArgs,
    /// Write a JUnit XML report (one test case per scenario); `-` for
    /// standard output (the verdict lines then go to standard error).
    #[arg(long, value_name = "FILE")]
    pub(super) junit: Option<PathBuf>,
    /// Write a JSON run record (docs/run-record.schema.json: target, board,
    /// options, every verdict and measurement with its limits); `-` for
    /// standard output.
    #[arg(long, value_name = "FILE")]
    pub(super) json: Option<PathBuf>,
    /// Keep the trace and VCD of every scenario that did not pass here.
    #[arg(long, value_name = "DIR")]
    pub(super) artifacts: Option<PathBuf>,
    /// Board revision label for the reports.
    #[arg(long)]
    pub(super) board_rev: Option<String>,
    /// Run the selection this many times (soak runs). SIGINT or SIGTERM
    /// stops after the scenario under way and still writes the reports.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) repeat: u32,
    /// Width of the MARGINAL zone inside each Table 3-3 limit, in percent of
    /// the limit.
    #[arg(long, default_value_t = 0.25)]
    pub(super) marginal: f64,
}

fn verdict_line(r: &ScenarioResult) -> String {
    let tag = match r.verdict {
        Verdict::Passed => "PASS",
        Verdict::Marginal => "MARGINAL",
        Verdict::Failed(_) => "FAIL",
        Verdict::Error(_) => "ERROR",
        Verdict::NotRun(_) => "NOT RUN",
    };
    let mut s = format!(
        "{} {} (section {})",
        super::out::verdict_word(tag, 8),
        r.name,
        r.section
    );
    if let Some(d) = r.verdict.detail() {
        s.push_str("\n         ");
        s.push_str(&d);
    }
    s
}

/// Applies the golden comparison to a result: a divergence or an unusable
/// golden file fails the scenario (never the process).
fn check_golden(r: &mut ScenarioResult, dir: &Path, tol: &Tolerances) {
    if !r.verdict.ok() {
        return;
    }
    let Some(trace) = &r.trace else {
        r.verdict = Verdict::Error(HarnessError::Golden(
            "no capture to compare with the golden trace".into(),
        ));
        return;
    };
    let fail = |expectation: String, expected: String, got: String, at| {
        Verdict::Failed(Failure {
            expectation,
            expected,
            got,
            at,
        })
    };
    match golden::load_for(dir, r.name, &trace.straps) {
        Ok(g) => {
            if let Err(d) = compare(&g, trace, tol) {
                r.verdict = fail(
                    format!("golden trace: first divergence in {}", d.quantity),
                    format!("{} (allowed {})", d.golden, d.allowed),
                    d.got,
                    d.at,
                );
            }
        }
        // A missing, corrupt or mismatched golden file is the harness's
        // input at fault, never the device.
        Err(e) => r.verdict = Verdict::Error(HarnessError::Golden(e.to_string())),
    }
}

/// Saves `r`'s trace and VCD in `dir`, adding each file written to `saved`
/// (for the reports to point at).
fn save_artifacts(dir: &Path, r: &ScenarioResult, saved: &mut Vec<String>) -> Result<(), String> {
    let Some(trace) = &r.trace else { return Ok(()) };
    let text = trace.render();
    let tpath = dir.join(format!("{}.trace", r.name));
    files::write(&tpath, text.as_bytes()).map_err(|e| e.to_string())?;
    saved.push(tpath.display().to_string());
    let vpath = dir.join(format!("{}.vcd", r.name));
    files::write_with(&vpath, |w| crate::vcd_export::export(trace, w))
        .map_err(|e| e.to_string())?;
    saved.push(vpath.display().to_string());
    Ok(())
}

fn write_report(path: &Path, text: Result<String, report::ReportError>) -> Result<(), String> {
    let text = text.map_err(|e| format!("{}: {e}", path.display()))?;
    files::write_report(path, text.as_bytes()).map_err(|e| e.to_string())
}

fn summary_lines(t: &Tally, results: usize) {
    outln!(
        "{results} scenarios: {} passed, {} marginal, {} failed, {} errors, {} not run",
        t.passed,
        t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
    // The closing line CI log readers look for; the same counts.
    outln!(
        "suite: {} passed, {} failed, {} errors, {} not run",
        t.passed + t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
}

impl RunArgs {
    fn target_name(&self) -> String {
        self.target.name().to_string()
    }

    /// The options in force, for the run record.
    fn options(&self, tol: &Tolerances) -> RunOptions {
        let mut o = RunOptions {
            repeat: self.repeat,
            golden: self.golden.as_ref().map(|g| g.display().to_string()),
            marginal_pct: self.marginal,
            latency_tol_pct: tol.latency_bp as f64 / 100.0,
            interval_tol_pct: tol.interval_bp as f64 / 100.0,
            time_floor_ns: tol.floor.as_nanos(),
            ..RunOptions::default()
        };
        self.select.describe(&mut o);
        o
    }
}

pub fn run(args: RunArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    let tol = match args.tolerance.tolerances() {
        Ok(t) => t,
        Err(e) => return Err(usage(e)),
    };
    if !(args.marginal.is_finite() && (0.0..=50.0).contains(&args.marginal)) {
        return Err(usage(format!(
            "--marginal {}: give a percentage from 0 to 50",
            args.marginal
        )));
    }
    let reports: Vec<&PathBuf> = [&args.junit, &args.json].into_iter().flatten().collect();
    for report in &reports {
        files::check_writable(report)?;
    }
    match reports.iter().filter(|p| p.as_os_str() == "-").count() {
        0 => {}
        // Standard output carries the report: the verdicts go to stderr.
        1 => super::out::people_to_stderr(),
        _ => {
            return Err(usage(
                "--junit - and --json - cannot both take standard output",
            ))
        }
    }
    if let Some(dir) = &args.golden {
        if !dir.is_dir() {
            return Err(usage(format!(
                "{}: golden directory not found",
                dir.display()
            )));
        }
    }
    let mut target = match args.target.open() {
        Ok(t) => t,
        Err(e @ super::args::OpenError::Infrastructure(_)) => {
            // Nothing ran: say so in the reports too, so CI shows an
            // infrastructure problem rather than a bad board.
            let why = e.to_string();
            let results: Vec<ScenarioResult> = scenarios
                .iter()
                .map(|s| ScenarioResult {
                    name: s.name,
                    section: s.section,
                    tags: s.tags,
                    verdict: Verdict::NotRun(NotRun::Unreachable(why.clone())),
                    measurements: Vec::new(),
                    trace: None,
                    elapsed: Duration::ZERO,
                    wall: std::time::Duration::ZERO,
                })
                .collect();
            let mut info = RunInfo::unreached(args.target_name(), args.board_rev.clone());
            info.options = args.options(&tol);
            let _ = args
                .junit
                .as_ref()
                .map(|p| write_report(p, report::junit(&info, &results, &[])));
            let _ = args
                .json
                .as_ref()
                .map(|p| write_report(p, report::json(&info, &results)));
            summary_lines(&Tally::of(&results), results.len());
            return Err(e.into());
        }
        Err(e) => return Err(e.into()),
    };
    let started = std::time::Instant::now();
    let mut info = RunInfo::new(&target.info(), args.board_rev.clone());
    info.options = args.options(&tol);
    let opts = DriverOptions {
        grading: Grading {
            marginal_bp: (args.marginal * 100.0).round() as u64,
        },
        ..DriverOptions::default()
    };
    let repeat = args.repeat as usize;
    let progress = Progress::new(scenarios.len() * repeat);
    let mut problems = Vec::new();
    // The files saved for each result, in the results' order.
    let mut attachments: Vec<Vec<String>> = Vec::new();
    let stop = super::signals::stop_requested();
    let stopped = || stop.load(Ordering::Relaxed) || super::out::stdout_closed();
    let results = run_suite_until(target.as_mut(), &scenarios, repeat, opts, stopped, |r| {
        if let Some(dir) = &args.golden {
            check_golden(r, dir, &tol);
        }
        progress.step(r.name);
        if !matches!(r.verdict, Verdict::NotRun(NotRun::Interrupted)) {
            progress.line(&verdict_line(r));
        }
        let mut saved = Vec::new();
        if let (Some(dir), false) = (&args.artifacts, r.verdict.ok()) {
            if let Err(e) = save_artifacts(dir, r, &mut saved) {
                problems.push(e);
            }
        }
        attachments.push(saved);
        // Judged, compared and saved: a soak run need not keep it.
        r.trace = None;
    });
    progress.finish();
    let interrupted = stopped();
    info.wall_s = started.elapsed().as_secs_f64();
    let tally = Tally::of(&results);
    if let Some(p) = &args.junit {
        if let Err(e) = write_report(p, report::junit(&info, &results, &attachments)) {
            problems.push(e);
        }
    }
    if let Some(p) = &args.json {
        if let Err(e) = write_report(p, report::json(&info, &results)) {
            problems.push(e);
        }
    }
    summary_lines(&tally, results.len());
    for p in &problems {
        errln!("ppmc: {p}");
    }
    if interrupted {
        Err(CliError::Interrupted)
    } else if tally.ok() && problems.is_empty() {
        Ok(())
    } else {
        Err(CliError::Verdict)
    }
}
