//! `ppmc run`, `list`, `record`, `compare` and `export`.

use crate::TargetArgs;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ppmc::compare::{compare, Tolerances};
use ppmc::golden::{self, GoldenError, Written};
use ppmc::report::{self, RunInfo, Tally};
use ppmc::runner::{parse_shard, run_suite, validate_suite, Selection};
use ppmc::scenario::{DriverOptions, Failure, Grading, Scenario, ScenarioResult, Verdict};
use ppmc::time::Duration;
use ppmc::trace::Trace;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct SelectArgs {
    /// Only scenarios whose name contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// Only scenarios with this tag (repeat for several; all must match).
    #[arg(long = "tag")]
    tags: Vec<String>,
    /// Run the I-th of N interleaved parts of the suite, e.g. 2/4, to split
    /// it across CI jobs or boards.
    #[arg(long, value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
}

impl SelectArgs {
    fn selection(&self) -> Selection {
        Selection {
            filter: self.filter.clone(),
            tags: self.tags.clone(),
            shard: self.shard,
        }
    }

    /// The suite, validated, narrowed to the selection.
    fn scenarios(&self) -> Result<Vec<Scenario>, String> {
        let all = ppmc::suite::all();
        validate_suite(&all)?;
        let chosen = self.selection().select(&all);
        if chosen.is_empty() {
            return Err("no scenario matches the selection (see `ppmc list`)".into());
        }
        Ok(chosen)
    }
}

/// Comparison tolerances, defaulting to the datasheet's 1 %.
#[derive(Debug, Args)]
pub struct ToleranceArgs {
    /// Relative tolerance on latencies, in percent of the golden value.
    #[arg(long, default_value_t = 1.0)]
    latency_tol: f64,
    /// Relative tolerance on each pulse interval, in percent.
    #[arg(long, default_value_t = 1.0)]
    interval_tol: f64,
    /// Absolute slack on every timing (timer resolution).
    #[arg(long, default_value = "100ns", value_parser = crate::parse_duration)]
    time_floor: Duration,
}

impl ToleranceArgs {
    fn tolerances(&self) -> Result<Tolerances, String> {
        let bp = |pct: f64, name: &str| {
            if pct.is_finite() && (0.0..=100.0).contains(&pct) {
                Ok((pct * 100.0).round() as u64)
            } else {
                Err(format!("--{name} {pct}: give a percentage from 0 to 100"))
            }
        };
        Ok(Tolerances {
            latency_bp: bp(self.latency_tol, "latency-tol")?,
            interval_bp: bp(self.interval_tol, "interval-tol")?,
            floor: self.time_floor,
        })
    }
}

#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    select: SelectArgs,
    #[command(flatten)]
    target: TargetArgs,
    /// Compare each scenario's trace with its golden trace in DIR as it runs.
    #[arg(long, value_name = "DIR")]
    golden: Option<PathBuf>,
    #[command(flatten)]
    tolerance: ToleranceArgs,
    /// Write a JUnit XML report (one test case per scenario).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Write a JSON run record (target, board, harness version, every
    /// measurement with its limits).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Keep the trace and VCD of every scenario that did not pass here.
    #[arg(long, value_name = "DIR")]
    artifacts: Option<PathBuf>,
    /// Board revision label for the reports.
    #[arg(long)]
    board_rev: Option<String>,
    /// Run the selection this many times (soak runs).
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Width of the MARGINAL zone inside each Table 3-3 limit, in percent of
    /// the limit.
    #[arg(long, default_value_t = 0.25)]
    marginal: f64,
}

/// Progress on a terminal, plain lines otherwise.
struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    fn new(total: usize) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}") {
                b.set_style(style);
            }
            b
        });
        Progress { bar }
    }

    fn line(&self, text: &str) {
        match &self.bar {
            Some(b) => b.println(text),
            None => println!("{text}"),
        }
    }

    fn step(&self, name: &str) {
        if let Some(b) = &self.bar {
            b.inc(1);
            b.set_message(name.to_string());
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

fn verdict_line(r: &ScenarioResult) -> String {
    let tag = match r.verdict {
        Verdict::Passed => "PASS",
        Verdict::Marginal => "MARGINAL",
        Verdict::Failed(_) => "FAIL",
        Verdict::Error(_) => "ERROR",
        Verdict::NotRun(_) => "NOT RUN",
    };
    let mut s = format!("{tag:<8} {} (section {})", r.name, r.section);
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
        r.verdict = Verdict::Error("no capture to compare with the golden trace".into());
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
    match golden::load(dir, r.name) {
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
        Err(e) => {
            r.verdict = fail(
                "golden trace usable".into(),
                "a valid golden file".into(),
                e.to_string(),
                ppmc::time::Instant::ZERO,
            );
        }
    }
}

fn save_artifacts(dir: &Path, r: &ScenarioResult) -> Result<(), String> {
    let Some(trace) = &r.trace else { return Ok(()) };
    let text = trace.render();
    let tpath = dir.join(format!("{}.trace", r.name));
    golden::write_atomic(&tpath, text.as_bytes())
        .map_err(|e| format!("{}: {e}", tpath.display()))?;
    let vpath = dir.join(format!("{}.vcd", r.name));
    let mut buf = Vec::new();
    ppmc::vcd_export::export(trace, &mut buf).map_err(|e| format!("{}: {e}", vpath.display()))?;
    golden::write_atomic(&vpath, &buf).map_err(|e| format!("{}: {e}", vpath.display()))
}

fn write_report(path: &Path, text: Result<String, String>) -> Result<(), String> {
    let text = text.map_err(|e| format!("{}: {e}", path.display()))?;
    golden::write_atomic(path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

fn summary_lines(t: &Tally, results: usize) {
    println!(
        "{results} scenarios: {} passed, {} marginal, {} failed, {} errors, {} not run",
        t.passed, t.marginal, t.failed, t.errors, t.not_run
    );
    // The closing line CI log readers look for.
    println!(
        "suite: {} passed, {} failed",
        t.passed + t.marginal,
        t.failed + t.errors + t.not_run
    );
}

impl RunArgs {
    fn target_name(&self) -> String {
        self.target.name().to_string()
    }
}

pub fn run(args: RunArgs) -> ExitCode {
    let scenarios = match args.select.scenarios() {
        Ok(s) => s,
        Err(e) => return crate::usage_error(e),
    };
    let tol = match args.tolerance.tolerances() {
        Ok(t) => t,
        Err(e) => return crate::usage_error(e),
    };
    if !(args.marginal.is_finite() && (0.0..=50.0).contains(&args.marginal)) {
        return crate::usage_error(format!(
            "--marginal {}: give a percentage from 0 to 50",
            args.marginal
        ));
    }
    if let Some(dir) = &args.golden {
        if !dir.is_dir() {
            return crate::usage_error(format!("{}: golden directory not found", dir.display()));
        }
    }
    let mut target = match args.target.open() {
        Ok(t) => t,
        Err(e @ crate::OpenError::Infrastructure(_)) => {
            // Nothing ran: say so in the reports too, so CI shows an
            // infrastructure problem rather than a bad board.
            let why = e.to_string();
            let results: Vec<ScenarioResult> = scenarios
                .iter()
                .map(|s| ScenarioResult {
                    name: s.name,
                    section: s.section,
                    tags: s.tags,
                    verdict: Verdict::NotRun(why.clone()),
                    measurements: Vec::new(),
                    trace: None,
                    elapsed: Duration::ZERO,
                })
                .collect();
            let info = RunInfo::new(
                &ppmc::target::TargetInfo {
                    name: args.target_name(),
                    details: Vec::new(),
                },
                args.board_rev.clone(),
            );
            let _ = args
                .junit
                .as_ref()
                .map(|p| write_report(p, report::junit(&info, &results)));
            let _ = args
                .json
                .as_ref()
                .map(|p| write_report(p, report::json(&info, &results)));
            summary_lines(&Tally::of(&results), results.len());
            return e.exit();
        }
        Err(e) => return e.exit(),
    };
    let info = RunInfo::new(&target.info(), args.board_rev.clone());
    let opts = DriverOptions {
        grading: Grading {
            marginal_bp: (args.marginal * 100.0).round() as u64,
        },
        ..DriverOptions::default()
    };
    let progress = Progress::new(scenarios.len() * args.repeat.max(1));
    let mut problems = Vec::new();
    let results = run_suite(target.as_mut(), &scenarios, args.repeat, opts, |r| {
        if let Some(dir) = &args.golden {
            check_golden(r, dir, &tol);
        }
        progress.step(r.name);
        progress.line(&verdict_line(r));
        if let (Some(dir), false) = (&args.artifacts, r.verdict.ok()) {
            if let Err(e) = save_artifacts(dir, r) {
                problems.push(e);
            }
        }
    });
    progress.finish();
    let tally = Tally::of(&results);
    if let Some(p) = &args.junit {
        if let Err(e) = write_report(p, report::junit(&info, &results)) {
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
        eprintln!("ppmc: {p}");
    }
    if tally.ok() && problems.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

#[derive(Debug, Args)]
pub struct ListArgs {
    #[command(flatten)]
    select: SelectArgs,
}

pub fn list(args: ListArgs) -> ExitCode {
    let scenarios = match args.select.scenarios() {
        Ok(s) => s,
        Err(e) => return crate::usage_error(e),
    };
    for s in &scenarios {
        println!(
            "{:<58} {:<7} [{}]  {}",
            s.name,
            s.section,
            s.tags.join(","),
            s.summary
        );
    }
    println!("{} scenarios", scenarios.len());
    ExitCode::SUCCESS
}

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

pub fn record(args: RecordArgs) -> ExitCode {
    let scenarios = match args.select.scenarios() {
        Ok(s) => s,
        Err(e) => return crate::usage_error(e),
    };
    let mut target = match args.target.open() {
        Ok(t) => t,
        Err(e) => return e.exit(),
    };
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
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

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

pub fn compare_cmd(args: CompareArgs) -> ExitCode {
    let tol = match args.tolerance.tolerances() {
        Ok(t) => t,
        Err(e) => return crate::usage_error(e),
    };
    if !args.golden.is_dir() {
        return crate::usage_error(format!(
            "{}: golden directory not found",
            args.golden.display()
        ));
    }
    let scenarios = match args.select.scenarios() {
        Ok(s) => s,
        Err(e) => return crate::usage_error(e),
    };
    let Some(dir) = &args.traces else {
        // Against a target: the run itself, with the golden check.
        let run_args = RunArgs {
            select: args.select,
            target: args.target,
            golden: Some(args.golden),
            tolerance: args.tolerance,
            junit: None,
            json: None,
            artifacts: None,
            board_rev: None,
            repeat: 1,
            marginal: 0.25,
        };
        return run(run_args);
    };
    if !dir.is_dir() {
        return crate::usage_error(format!("{}: trace directory not found", dir.display()));
    }
    let (mut ok, mut bad) = (0usize, 0usize);
    for s in &scenarios {
        let line = match (
            golden::load(&args.golden, s.name),
            golden::load(dir, s.name),
        ) {
            (Ok(g), Ok(t)) => match compare(&g, &t, &tol) {
                Ok(()) => {
                    ok += 1;
                    format!("MATCH    {}", s.name)
                }
                Err(d) => {
                    bad += 1;
                    format!("DIVERGE  {}\n         first divergence {d}", s.name)
                }
            },
            (Err(e), _) | (_, Err(e)) => {
                bad += 1;
                format!("BAD FILE {}\n         {e}", s.name)
            }
        };
        println!("{line}");
    }
    println!("compare: {ok} passed, {bad} failed");
    if bad == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A trace or golden file.
    trace: PathBuf,
    /// The VCD file to write (default: the trace's name with .vcd).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn export(args: ExportArgs) -> ExitCode {
    let text = match std::fs::read_to_string(&args.trace) {
        Ok(t) => t,
        Err(e) => return crate::usage_error(format!("{}: {e}", args.trace.display())),
    };
    let trace = match Trace::parse(&text) {
        Ok(t) => t,
        Err(e) => {
            return crate::usage_error(format!(
                "{}:{}: {}",
                args.trace.display(),
                e.line,
                e.message
            ))
        }
    };
    let out = args
        .output
        .unwrap_or_else(|| args.trace.with_extension("vcd"));
    let mut buf = Vec::new();
    if let Err(e) = ppmc::vcd_export::export(&trace, &mut buf) {
        eprintln!("ppmc: {}: {e}", out.display());
        return ExitCode::from(1);
    }
    if let Err(e) = golden::write_atomic(&out, &buf) {
        eprintln!("ppmc: {}: {e}", out.display());
        return ExitCode::from(1);
    }
    println!("wrote {}", out.display());
    ExitCode::SUCCESS
}
