//! A run of a suite on a farm of boards, into its run record: what `ppmc
//! run` (and `ppmc compare` against a target) does between opening the
//! boards and writing the reports. Each result is held to its golden trace
//! (the golden verdict rule, [`crate::golden::check`]), what a report
//! draws of it is kept, its artifacts are saved when it did not pass, and
//! the result sink ([`crate::sink`]) makes the record in constant memory
//! whatever `repeat` is.

use crate::artifacts::{self, Window};
use crate::compare::Tolerances;
use crate::runner::{Farm, Spread};
use crate::scenario::{DriverOptions, Scenario, ScenarioResult, Verdict};
use crate::sink::{Kept, Sink};
use ppmc_record::{BoardInfo, Figures, RunInfo, RunRecord, Tally};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::Path;

/// What a run does besides running the scenarios.
#[derive(Debug, Clone, Copy)]
pub struct Plan<'a> {
    pub scenarios: &'a [Scenario],
    /// Passes over the scenarios, from 1.
    pub repeat: usize,
    pub options: DriverOptions,
    pub spread: Spread,
    /// The golden traces each result is held to, and the tolerances.
    pub golden: Option<(&'a Path, Tolerances)>,
    /// Where a result that did not pass leaves its trace and VCD (under a
    /// folder per board with `Spread::Each`), and how much of the VCD.
    pub artifacts: Option<(&'a Path, Window)>,
    /// Keep what a report draws of each result (`figures`).
    pub draw: bool,
}

/// How a run ended.
#[derive(Debug)]
pub struct Ended {
    pub record: RunRecord,
    /// Each board's verdicts, in the order of `record.run.boards`.
    pub board_tallies: Vec<Tally>,
    /// Runs that did not pass and are counted, not listed (`--repeat`).
    pub unlisted: usize,
    /// Files that could not be saved, each naming where and why.
    pub problems: Vec<String>,
    /// The run was stopped before its end.
    pub interrupted: bool,
}

/// The boards of `farm` as a run record names them: each board's own
/// revision and serial (`rev=`, `board-serial=`), else `rev` and `serial`
/// for all; a board that could not be reached with why.
pub fn boards(farm: &Farm, rev: Option<&str>, serial: Option<&str>) -> Vec<BoardInfo> {
    farm.specs()
        .iter()
        .enumerate()
        .map(|(b, spec)| {
            let rev = spec.rev.clone().or_else(|| rev.map(str::to_string));
            let name = spec.label().to_string();
            let board = match farm.board(b) {
                Ok(t) => t.board_info(name, rev),
                Err(e) => BoardInfo::unreached(name, spec.address.clone(), rev, e.to_string()),
            };
            BoardInfo {
                board_serial: spec.serial.clone().or_else(|| serial.map(str::to_string)),
                bridge_serial: farm.bridge_serial(b),
                ..board
            }
        })
        .collect()
}

/// The record of a run in which no board could be reached: every scenario
/// not run, the infrastructure's.
pub fn unreached(farm: &mut Farm, plan: &Plan, info: RunInfo) -> RunRecord {
    let mut results = Vec::new();
    farm.stream(
        plan.scenarios,
        1,
        DriverOptions::default(),
        plan.spread,
        || true,
        |_, _, _| {},
        |r| {
            let board = r.board.and_then(|b| info.boards.get(b));
            results.push(r.result.record(board.map(|b| b.name.as_str())));
        },
    );
    RunRecord::new(info, results)
}

/// Runs `plan` on `farm` until its end or until `stopped` says so; `each`
/// is told every result as it comes, with its board's name, after the
/// golden check. `info` names the boards; its link costs and wall time
/// are filled in.
pub fn run(
    farm: &mut Farm,
    plan: &Plan,
    mut info: RunInfo,
    stopped: impl Fn() -> bool + Sync,
    mut each: impl FnMut(&ScenarioResult, &str),
) -> Ended {
    let started = std::time::Instant::now();
    let mut problems = Vec::new();
    // The files saved and what the reports draw of each result, by its
    // slot, until the sink takes it.
    let saved: RefCell<BTreeMap<usize, Vec<String>>> = RefCell::new(BTreeMap::new());
    let drawn: RefCell<BTreeMap<usize, Figures>> = RefCell::new(BTreeMap::new());
    let mut sink = Sink::new(plan.scenarios.len(), plan.repeat);
    let names: Vec<String> = info.boards.iter().map(|b| b.name.clone()).collect();
    let name_of = |b: Option<usize>| info.board_name(b).to_string();
    farm.stream(
        plan.scenarios,
        plan.repeat,
        plan.options,
        plan.spread,
        &stopped,
        |slot, b, r| {
            let golden = plan
                .golden
                .and_then(|(dir, tol)| crate::golden::check(r, dir, &tol));
            if plan.draw {
                if let Some(f) = figures(r, golden.as_ref()) {
                    drawn.borrow_mut().insert(slot, f);
                }
            }
            let name = name_of(b);
            each(r, &name);
            if let (Some((dir, window)), false) = (plan.artifacts, r.verdict.ok()) {
                let dir = match plan.spread {
                    Spread::Each => dir.join(artifacts::folder_name(&name)),
                    Spread::Share => dir.to_path_buf(),
                };
                let mut saved = saved.borrow_mut();
                if let Err(e) = artifacts::save(&dir, r, window, saved.entry(slot).or_default()) {
                    problems.push(e);
                }
            }
            // Judged, compared and saved: a soak run need not keep it.
            r.trace = None;
        },
        |r| {
            let board = r.board;
            let kept = Kept {
                attachments: saved.borrow_mut().remove(&r.slot).unwrap_or_default(),
                figures: drawn.borrow_mut().remove(&r.slot),
            };
            sink.add(r, board, &names, kept);
        },
    );
    for (b, board) in info.boards.iter_mut().enumerate() {
        board.link = farm
            .link_stats(b)
            .map(|stats| stats.into_iter().map(|(k, v)| (k.to_string(), v)).collect());
    }
    info.wall_s = started.elapsed().as_secs_f64();
    let board_tallies = (0..info.boards.len())
        .map(|b| sink.board_tally(Some(b)))
        .collect();
    let unlisted = sink.unlisted();
    Ended {
        record: sink.record(info),
        board_tallies,
        unlisted,
        problems,
        interrupted: stopped(),
    }
}

/// What a report draws of a result: its moves over the golden trace's,
/// and the pins around its failure.
pub fn figures(r: &ScenarioResult, golden: Option<&crate::trace::Trace>) -> Option<Figures> {
    let failed_at = match &r.verdict {
        Verdict::Failed(f) => Some(f.at),
        _ => None,
    };
    r.trace
        .as_ref()
        .map(|t| crate::trace::figures(t, golden, failed_at))
}

/// A recorded trace set (`traces`, a board revision's recording) held to
/// the golden set (`golden`) within `tol`, scenario by scenario, as `ppmc
/// run --golden` holds a board: a trace that diverges fails; one that
/// cannot be used (missing, unreadable, corrupt, at other straps) is an
/// error of its own, the file's, not the board's. `each` is told every
/// result as it comes; the record names the trace set as its board.
pub fn compare_sets(
    scenarios: &[Scenario],
    golden: &Path,
    traces: &Path,
    tol: &Tolerances,
    mut info: RunInfo,
    mut each: impl FnMut(&ScenarioResult),
) -> RunRecord {
    use crate::golden::GoldenError;
    use crate::scenario::HarnessError;
    use crate::time::Duration;
    let started = std::time::Instant::now();
    let board = info.boards.first().map(|b| b.name.clone());
    let mut results = Vec::with_capacity(scenarios.len());
    for s in scenarios {
        let mut r = crate::runner::not_run(s, crate::scenario::NotRun::Interrupted);
        r.verdict = Verdict::Passed;
        let mut drawn = None;
        match crate::golden::load(traces, s.name) {
            Ok(t) => {
                r.elapsed = Duration::from_nanos(t.events.last().map_or(0, |e| e.at.as_nanos()));
                r.trace = Some(t);
                let g = crate::golden::check(&mut r, golden, tol);
                drawn = figures(&r, g.as_ref());
                r.trace = None;
            }
            Err(GoldenError::Missing { path }) => {
                let why = format!(
                    "{}: no trace of this scenario in {} (record it there with `{} record --out {}`)",
                    path.display(),
                    traces.display(),
                    crate::program(),
                    traces.display()
                );
                r.verdict = Verdict::Error(HarnessError::Golden(why));
            }
            Err(e) => r.verdict = Verdict::Error(HarnessError::Golden(e.to_string())),
        }
        each(&r);
        results.push(ppmc_record::ScenarioRecord {
            figures: drawn,
            ..r.record(board.as_deref())
        });
    }
    info.wall_s = started.elapsed().as_secs_f64();
    RunRecord::new(info, results)
}

/// What a whole run says, for its exit status.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunVerdict {
    /// Every scenario passed (or was marginal, or flaky when flaky passes
    /// pass).
    Passed,
    /// A scenario did not pass, a flaky pass failed the run, or a report
    /// could not be written.
    Failed,
    /// Boards of the farm could not be reached: the infrastructure's,
    /// however well the others did (CI must see that the farm is not
    /// whole). The text names them.
    Infrastructure(String),
    /// The run was stopped before its end.
    Interrupted,
}

impl Ended {
    /// The run's verdict on `farm`; `flaky_is_failure`: a scenario that
    /// passed only on a retry fails the run.
    pub fn verdict(&self, farm: &Farm, flaky_is_failure: bool) -> RunVerdict {
        let tally = self.record.summary;
        let boards = &self.record.run.boards;
        if self.interrupted {
            return RunVerdict::Interrupted;
        }
        if !farm.unreached().is_empty() {
            let names: Vec<String> = farm
                .unreached()
                .iter()
                .map(|(b, _)| match boards[*b].name == boards[*b].target {
                    true => boards[*b].name.clone(),
                    false => format!("{} ({})", boards[*b].name, boards[*b].target),
                })
                .collect();
            return RunVerdict::Infrastructure(format!(
                "{} of {} boards could not be reached and took no part in the run: {}",
                farm.unreached().len(),
                boards.len(),
                names.join(", ")
            ));
        }
        let ok = match flaky_is_failure {
            true => tally.ok_strict(),
            false => tally.ok(),
        };
        match ok && self.problems.is_empty() {
            true => RunVerdict::Passed,
            false => RunVerdict::Failed,
        }
    }
}
