//! `ppmc run`: the conformance suite on a target, graded, with reports.

use super::args::{SelectArgs, TargetArgs, ToleranceArgs};
use super::progress::Progress;
use crate::{usage, CliError};
use clap::Args;
use ppmc::compare::{compare_graded, Tolerances};
use ppmc::golden::{self};
use ppmc::runner::{Farm, Spread};
use ppmc::scenario::{
    DriverOptions, Failure, Grade, Grading, HarnessError, Measurement, NotRun, Retry, Scenario,
    ScenarioResult, Verdict,
};
use ppmc::soak::{Kept, Soak};
use ppmc::trace::Trace;
use ppmc_files as files;
use ppmc_record::{BoardInfo, Figures, RunInfo, RunOptions, RunRecord, Tally};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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
    /// Write the HTML report: one file, offline (docs/reports.md): every
    /// verdict, each measurement against its Table 3-3 band, each move's
    /// speed profile over the golden one (with --golden) and the first
    /// divergence marked, the pins around each failure.
    #[arg(long, value_name = "FILE")]
    pub(super) html: Option<PathBuf>,
    /// Keep the run record in a results store (SQLite; made when not
    /// there), for `ppmc history` and `ppmc report --store`
    /// (docs/results-store.md).
    #[arg(long, value_name = "FILE")]
    pub(super) store: Option<PathBuf>,
    /// Keep the trace and VCD of every scenario that did not pass here.
    /// The VCD shows `--artifacts-window` either side of the failure.
    #[arg(long, value_name = "DIR")]
    pub(super) artifacts: Option<PathBuf>,
    /// How much of a failed scenario's waveform `--artifacts` writes:
    /// this long before and after the failure (e.g. 10ms), or `all` for
    /// the whole trace (a failure in the 16,777,216-step move makes a VCD
    /// of some 650 MB). A scenario that ended in an error has no failure
    /// time: its VCD is whole.
    #[arg(long, value_name = "DURATION|all", default_value = "10ms", value_parser = parse_window)]
    pub(super) artifacts_window: Window,
    /// With several `--target`s: run the whole selection on every board
    /// (to compare boards), instead of spreading it over them.
    #[arg(long)]
    pub(super) each: bool,
    /// Run the selection this many times (soak runs). Memory stays flat:
    /// the reports list the first pass and every run that did not pass (up
    /// to 1,000 after the first pass), and count the other runs per
    /// scenario and board (verdicts, each measurement's min, mean and
    /// max). SIGINT or SIGTERM stops after the scenario under way and
    /// still writes the reports.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) repeat: u32,
    /// Try a scenario that ended in a link or bridge error again, up to N
    /// times, on the same board. Every attempt stays on record (JUnit in
    /// Maven Surefire's dialect, the JSON record, the HTML report); one
    /// that passed only on a retry is FLAKY, never plainly passed.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub(super) retries: u32,
    /// With --retries: try a device failure again too (a board that fails
    /// and then passes is flaky hardware, and says so).
    #[arg(long, requires = "retries")]
    pub(super) retry_failures: bool,
    /// A scenario that passed only on a retry fails the run (exit 1).
    #[arg(long)]
    pub(super) flaky_is_failure: bool,
    /// Width of the MARGINAL zone inside each Table 3-3 limit, in percent of
    /// the limit.
    #[arg(long, default_value_t = 0.25)]
    pub(super) marginal: f64,
}

pub(super) fn verdict_line(r: &ScenarioResult, board: Option<&str>) -> String {
    let tag = match r.verdict {
        _ if r.flaky() => "FLAKY",
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
    if let Some(b) = board {
        s.push_str(" on ");
        s.push_str(b);
    }
    if let Some(d) = r.verdict.detail() {
        s.push_str("\n         ");
        s.push_str(&d);
    }
    // Which measurement, against what, and how sure it is.
    if r.verdict == Verdict::Marginal {
        for m in r.measurements.iter().filter(|m| m.grade == Grade::Marginal) {
            s.push_str(&format!("\n         {m}"));
        }
    }
    for (n, a) in r.attempts.iter().enumerate() {
        s.push_str(&format!("\n         attempt {}: ", n + 1));
        s.push_str(&a.verdict.detail().unwrap_or_else(|| "passed".into()));
    }
    s
}

/// Applies the golden comparison to a result: a divergence or an unusable
/// golden file fails the scenario (never the process). Returns the golden
/// trace compared with, for the report to draw.
pub(super) fn check_golden(r: &mut ScenarioResult, dir: &Path, tol: &Tolerances) -> Option<Trace> {
    if !r.verdict.ok() {
        // Not compared, but drawn beside the board's all the same.
        let straps = &r.trace.as_ref()?.straps;
        return golden::load_for(dir, r.name, straps).ok();
    }
    let Some(trace) = &r.trace else {
        r.verdict = Verdict::Error(HarnessError::Golden(
            "no capture to compare with the golden trace".into(),
        ));
        return None;
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
            match compare_graded(&g, trace, tol) {
                Err(d) => {
                    r.verdict = fail(
                        format!("golden trace: first divergence in {}", d.quantity),
                        format!("{} (allowed {})", d.golden, d.allowed),
                        d.got,
                        d.at,
                    );
                }
                // Within the instruments' uncertainty of a limit: the
                // first such comparison, graded as a measurement is.
                Ok(graded) => {
                    if let Some(m) = graded.first {
                        r.measurements.push(Measurement {
                            name: format!("golden trace: {}", m.quantity),
                            value: m.got,
                            lo: m.lo,
                            hi: m.hi,
                            marginal_lo: m.lo,
                            marginal_hi: m.hi,
                            u: m.u,
                            grade: Grade::Marginal,
                            at: m.at,
                        });
                        if r.verdict == Verdict::Passed {
                            r.verdict = Verdict::Marginal;
                        }
                    }
                }
            }
            Some(g)
        }
        // A missing, corrupt or mismatched golden file is the harness's
        // input at fault, never the device.
        Err(e) => {
            r.verdict = Verdict::Error(HarnessError::Golden(e.to_string()));
            None
        }
    }
}

/// What the HTML report draws of a result: its moves over the golden
/// trace's, and the pins around its failure.
pub(super) fn figures_of(r: &ScenarioResult, golden: Option<&Trace>) -> Option<Figures> {
    let failed_at = match &r.verdict {
        Verdict::Failed(f) => Some(f.at),
        _ => None,
    };
    r.trace
        .as_ref()
        .map(|t| ppmc::trace::figures(t, golden, failed_at))
}

/// How much of a failed scenario's waveform to keep.
#[derive(Debug, Clone, Copy)]
pub(super) enum Window {
    All,
    Around(ppmc::time::Duration),
}

fn parse_window(s: &str) -> Result<Window, String> {
    if s == "all" {
        return Ok(Window::All);
    }
    super::args::parse_duration(s).map(Window::Around)
}

/// Saves `r`'s trace and VCD in `dir`, adding each file written to `saved`
/// (for the reports to point at). The VCD covers `window` either side of
/// the failure, when there is one.
fn save_artifacts(
    dir: &Path,
    r: &ScenarioResult,
    window: Window,
    saved: &mut Vec<String>,
) -> Result<(), String> {
    let Some(trace) = &r.trace else { return Ok(()) };
    let text = trace.render();
    let tpath = dir.join(format!("{}.trace", r.name));
    files::write(&tpath, text.as_bytes()).map_err(|e| e.to_string())?;
    saved.push(tpath.display().to_string());
    let vpath = dir.join(format!("{}.vcd", r.name));
    let around = match (&r.verdict, window) {
        (Verdict::Failed(f), Window::Around(d)) => {
            let from =
                ppmc::time::Instant::from_nanos(f.at.as_nanos().saturating_sub(d.as_nanos()));
            Some((from, f.at + d))
        }
        _ => None,
    };
    files::write_with(&vpath, |w| {
        ppmc::vcd_export::export_window(trace, around, w)
    })
    .map_err(|e| e.to_string())?;
    saved.push(vpath.display().to_string());
    Ok(())
}

fn summary_lines(t: &Tally, results: usize) {
    // Flaky only when there are any: a clean run's lines stay as CI log
    // readers know them.
    let flaky = match t.flaky {
        0 => String::new(),
        n => format!(" {n} flaky (passed only on a retry),"),
    };
    outln!(
        "{results} scenarios: {} passed,{flaky} {} marginal, {} failed, {} errors, {} not run",
        t.passed,
        t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
    // The closing line CI log readers look for; the same counts.
    let flaky = match t.flaky {
        0 => String::new(),
        n => format!(" {n} flaky,"),
    };
    outln!(
        "suite: {} passed,{flaky} {} failed, {} errors, {} not run",
        t.passed + t.marginal,
        t.failed,
        t.errors,
        t.not_run
    );
}

impl RunArgs {
    /// The options in force, for the run record.
    fn options(&self, tol: &Tolerances) -> RunOptions {
        let mut o = RunOptions {
            repeat: self.repeat,
            golden: self.golden.as_ref().map(|g| g.display().to_string()),
            marginal_pct: self.marginal,
            latency_tol_pct: tol.latency_bp as f64 / 100.0,
            interval_tol_pct: tol.interval_bp as f64 / 100.0,
            time_floor_ns: tol.floor.as_nanos(),
            retries: self.retries,
            retry_failures: self.retry_failures,
            flaky_is_failure: self.flaky_is_failure,
            ..RunOptions::default()
        };
        self.select.describe(&mut o);
        o
    }
}

pub fn run(mut args: RunArgs, suite: &[Scenario]) -> Result<(), CliError> {
    // Before anything is opened: a signal during the open still leaves
    // reports, and ends every wait on a link within a second.
    let stop = super::signals::install();
    args.target.stop = stop.clone();
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
    // Every output is tried before the run, not found unusable after it.
    if let Some(dir) = &args.artifacts {
        files::prepare_folder(dir)?;
    }
    super::reports::prepare_reports(
        args.junit.as_deref(),
        args.json.as_deref(),
        args.html.as_deref(),
        args.store.as_deref(),
    )?;
    if args.store.is_some() && args.repeat > 1 {
        return Err(usage(
            "--store with --repeat: a soak's record lists its first pass and what did not pass, and counts the rest, so the store would see its failures and not its passes; store single runs",
        ));
    }
    let mut store = super::reports::open_store(args.store.as_deref())?;
    let outputs = super::reports::Outputs::of(&args.junit, &args.json, &args.html);
    if let Some(dir) = &args.golden {
        if !dir.is_dir() {
            return Err(usage(format!(
                "{}: golden directory not found",
                dir.display()
            )));
        }
    }
    let specs = args.target.specs().map_err(usage)?;
    let several_specs = specs.len();
    let spread = match args.each && several_specs > 1 {
        true => Spread::Each,
        false => Spread::Share,
    };
    let mut farm = Farm::open(specs, &args.target.open_options())?;
    let boards = farm
        .specs()
        .iter()
        .enumerate()
        .map(|(b, spec)| {
            let rev = spec.rev.clone().or_else(|| args.target.board_rev.clone());
            let serial = spec
                .serial
                .clone()
                .or_else(|| args.target.board_serial.clone());
            let name = spec.label().to_string();
            let board = match farm.board(b) {
                Ok(t) => t.board_info(name, rev),
                Err(e) => BoardInfo::unreached(name, spec.address.clone(), rev, e.to_string()),
            };
            BoardInfo {
                board_serial: serial,
                bridge_serial: farm.bridge_serial(b),
                ..board
            }
        })
        .collect();
    let mut info = ppmc::runner::run_info(boards, spread.name(several_specs));
    info.options = args.options(&tol);
    if farm.reached_none() {
        // Nothing ran: say so in the reports too, so CI shows an
        // infrastructure problem rather than a bad board.
        let why = farm.unreached_reason();
        let mut results = Vec::new();
        farm.stream(
            &scenarios,
            1,
            DriverOptions::default(),
            spread,
            || true,
            |_, _, _| {},
            |r| {
                let board = r.board.and_then(|b| info.boards.get(b));
                results.push(r.result.record(board.map(|b| b.name.as_str())));
            },
        );
        let record = RunRecord::new(info, results);
        for e in super::reports::write(&record, outputs, store.as_mut()) {
            errln!("ppmc: {e}");
        }
        summary_lines(&record.summary, record.scenarios.len());
        if stop.requested() {
            return Err(CliError::Interrupted);
        }
        return Err(CliError::Infrastructure(
            why.strip_prefix("infrastructure error: ")
                .unwrap_or(&why)
                .to_string(),
        ));
    }
    for (b, e) in farm.unreached() {
        errln!(
            "ppmc: board {} takes no part in the run: {e}",
            info.boards[*b].name
        );
    }
    let started = std::time::Instant::now();
    let opts = DriverOptions {
        grading: Grading {
            marginal_bp: (args.marginal * 100.0).round() as u64,
        },
        retry: Retry {
            times: args.retries,
            failures: args.retry_failures,
        },
        ..DriverOptions::default()
    };
    let repeat = args.repeat as usize;
    let runs = match spread {
        Spread::Each => several_specs - farm.unreached().len(),
        Spread::Share => 1,
    };
    let progress = Progress::new(scenarios.len() * repeat * runs);
    let mut problems = Vec::new();
    // The files saved for each result, by its slot, until the soak takes it.
    let saved: RefCell<BTreeMap<usize, Vec<String>>> = RefCell::new(BTreeMap::new());
    // What the reports draw of each result, by its slot, likewise.
    let drawn: RefCell<BTreeMap<usize, Figures>> = RefCell::new(BTreeMap::new());
    let draw = args.json.is_some() || args.html.is_some();
    // What the reports keep of the results as they come (`--repeat`: the
    // first pass and what did not pass, in full; the rest counted).
    let mut soak = Soak::new(scenarios.len(), repeat);
    let stopped = || stop.requested() || super::out::stdout_closed();
    let several = info.boards.len() > 1;
    let board_name = |b: Option<usize>| info.board_name(b).to_string();
    let names: Vec<String> = info.boards.iter().map(|b| b.name.clone()).collect();
    farm.stream(
        &scenarios,
        repeat,
        opts,
        spread,
        stopped,
        |slot, b, r| {
            let golden = args
                .golden
                .as_ref()
                .and_then(|dir| check_golden(r, dir, &tol));
            if draw {
                if let Some(f) = figures_of(r, golden.as_ref()) {
                    drawn.borrow_mut().insert(slot, f);
                }
            }
            progress.step(r.name);
            let name = board_name(b);
            if !matches!(r.verdict, Verdict::NotRun(NotRun::Interrupted)) {
                progress.line(&verdict_line(r, several.then_some(name.as_str())));
            }
            if let (Some(dir), false) = (&args.artifacts, r.verdict.ok()) {
                let dir = match spread {
                    Spread::Each => dir.join(file_name(&name)),
                    Spread::Share => dir.clone(),
                };
                let mut saved = saved.borrow_mut();
                let window = args.artifacts_window;
                if let Err(e) = save_artifacts(&dir, r, window, saved.entry(slot).or_default()) {
                    problems.push(e);
                }
            }
            // Judged, compared and saved: a soak run need not keep it.
            r.trace = None;
        },
        |r| {
            let board = r.board;
            let attachments = saved.borrow_mut().remove(&r.slot).unwrap_or_default();
            let figures = drawn.borrow_mut().remove(&r.slot);
            soak.add(
                r,
                board,
                &names,
                Kept {
                    attachments,
                    figures,
                },
            );
        },
    );
    progress.finish();
    for (b, board) in info.boards.iter_mut().enumerate() {
        board.link = farm
            .link_stats(b)
            .map(|stats| stats.into_iter().map(|(k, v)| (k.to_string(), v)).collect());
    }
    let interrupted = stopped();
    info.wall_s = started.elapsed().as_secs_f64();
    let tally = soak.tally();
    let unlisted = soak.unlisted();
    let board_tallies: Vec<Tally> = (0..info.boards.len())
        .map(|b| soak.board_tally(Some(b)))
        .collect();
    let record = soak.record(info);
    problems.extend(super::reports::write(&record, outputs, store.as_mut()));
    let info = &record.run;
    if unlisted > 0 {
        outln!(
            "{unlisted} runs that did not pass are counted, not listed: the reports list the first {} after the first pass",
            ppmc::soak::MAX_LISTED
        );
    }
    summary_lines(&tally, runs_of(&tally));
    if several {
        board_lines(info, &board_tallies);
    }
    for p in &problems {
        errln!("ppmc: {p}");
    }
    if interrupted {
        Err(CliError::Interrupted)
    } else if !farm.unreached().is_empty() {
        // A board that took no part is an infrastructure error however well
        // the others did: CI must see that the farm is not whole.
        Err(CliError::Infrastructure(format!(
            "{} of {} boards could not be reached and took no part in the run: {}",
            farm.unreached().len(),
            info.boards.len(),
            farm.unreached()
                .iter()
                .map(|(b, _)| {
                    let board = &info.boards[*b];
                    match board.name == board.target {
                        true => board.name.clone(),
                        false => format!("{} ({})", board.name, board.target),
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        )))
    } else if args.flaky_is_failure && tally.flaky > 0 {
        errln!(
            "ppmc: {} scenarios passed only on a retry, and --flaky-is-failure is given",
            tally.flaky
        );
        Err(CliError::Verdict)
    } else if tally.ok() && problems.is_empty() {
        Ok(())
    } else {
        Err(CliError::Verdict)
    }
}

/// A board's label as a folder name: `serial:/dev/ttyACM0` becomes
/// `serial__dev_ttyACM0`.
fn file_name(label: &str) -> String {
    label
        .chars()
        .map(|c| match c {
            'a'..='z' | 'A'..='Z' | '0'..='9' | '-' | '.' | '#' => c,
            _ => '_',
        })
        .collect()
}

/// How many runs a tally counts.
fn runs_of(t: &Tally) -> usize {
    t.runs()
}

/// One line per board: how many scenarios it ran and how they went
/// (`tallies` in the order of the boards).
fn board_lines(info: &RunInfo, tallies: &[Tally]) {
    for (board, t) in info.boards.iter().zip(tallies) {
        let state = match &board.error {
            Some(_) => " (not reached)",
            None => "",
        };
        let flaky = match t.flaky {
            0 => String::new(),
            n => format!(" {n} flaky,"),
        };
        outln!(
            "board {}{state}: {} scenarios, {} passed,{flaky} {} failed, {} errors, {} not run",
            board.name,
            runs_of(t),
            t.passed + t.marginal,
            t.failed,
            t.errors,
            t.not_run
        );
    }
}
