//! The fault matrix: each board fault of the catalogue (and the clean
//! board) against the five checks a user has: the conformance suite, the
//! golden trace comparison, a bounded differential fuzz against the
//! emulator, the fuzz oracle's invariants judged on the board's own
//! replies, and the board judged from logic-analyzer captures of the suite
//! ([`capture`], `ppmc judge`). Which caught it, with what, after how much
//! wall time.

use ppmc::backend::{Target, TargetError};
use ppmc::compare::{compare, Tolerances};
use ppmc::emu::ModelConfig;
use ppmc::fuzzing::actions::lower;
use ppmc::fuzzing::differential::{self, DiffSettings};
use ppmc::invariants::replay;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Scenario, Verdict};
use std::path::Path;
use std::time::{Duration as WallDuration, Instant as WallClock};

pub mod capture;

use capture::{CaptureError, Skipped};

/// A check that caught a fault: what it saw first, and the wall time from
/// the start of that check to the moment it was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Catch {
    pub first: String,
    pub after: WallDuration,
}

/// One row: a board and what each check made of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    /// The fault's name, or `clean`.
    pub board: String,
    pub suite: Option<Catch>,
    pub golden: Option<Catch>,
    pub fuzz: Option<Catch>,
    pub oracle: Option<Catch>,
    /// The first scenario whose capture the judge failed the board on.
    pub capture: Option<Catch>,
    /// The scenarios whose capture was not judged, as too long for one.
    pub capture_skipped: Vec<Skipped>,
}

impl Row {
    pub fn caught(&self) -> bool {
        self.suite.is_some()
            || self.golden.is_some()
            || self.fuzz.is_some()
            || self.oracle.is_some()
            || self.capture.is_some()
    }
}

/// Why a row could not be made: never a verdict on the board.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The target failed (the link).
    #[error(transparent)]
    Target(#[from] TargetError),
    /// The harness failed to make or judge one of its own captures.
    #[error("harness error in the capture column: {0}")]
    Capture(#[from] CaptureError),
}

/// How much fuzzing a row gets: the differential fuzz runs `seeds`
/// programs of `actions` actions against the emulator; the oracle replays
/// the same programs as bus ops (as they ran on the clean emulator, waits
/// included) and judges the board's replies by the invariants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FuzzBudget {
    /// Seeds tried, from 0.
    pub seeds: u64,
    /// Actions per seed.
    pub actions: usize,
}

impl Default for FuzzBudget {
    fn default() -> Self {
        FuzzBudget {
            seeds: 8,
            actions: 300,
        }
    }
}

/// Runs the five checks on `target`, a board with `model`: the capture
/// column runs the suite on its own emulator with that model, as a logic
/// analyzer on the board would record it ([`capture::judge_captures`]).
/// A target failure (the link) or a capture the harness cannot make is an
/// error, not a catch.
pub fn check_board(
    board: &str,
    target: &mut dyn Target,
    model: &ModelConfig,
    suite: &[Scenario],
    golden_dir: &Path,
    budget: FuzzBudget,
) -> Result<Row, CheckError> {
    let t0 = WallClock::now();
    let mut first_fail: Option<Catch> = None;
    let mut first_divergence: Option<Catch> = None;
    let mut link_error: Option<String> = None;
    run_suite(target, suite, 1, DriverOptions::default(), |r| {
        match &r.verdict {
            v @ (Verdict::Error(_) | Verdict::NotRun(_)) if link_error.is_none() => {
                link_error = Some(format!("{}: {}", r.name, v.detail().unwrap_or_default()));
            }
            v if !v.ok() && first_fail.is_none() => {
                first_fail = Some(Catch {
                    first: format!("{}: {}", r.name, v.detail().unwrap_or_default()),
                    after: t0.elapsed(),
                });
            }
            _ => {}
        }
        if first_divergence.is_some() {
            return;
        }
        let Some(trace) = r.trace.as_ref() else {
            return;
        };
        let diverged = match ppmc::golden::load_for(golden_dir, r.name, &trace.straps) {
            Ok(g) => compare(&g, trace, &Tolerances::default()).err().map(|d| {
                format!(
                    "{}: {} at {}: golden {}, got {}",
                    r.name, d.quantity, d.at, d.golden, d.got
                )
            }),
            Err(e) => Some(format!("{}: {e}", r.name)),
        };
        if let Some(first) = diverged {
            first_divergence = Some(Catch {
                first,
                after: t0.elapsed(),
            });
        }
    });
    if let Some(message) = link_error {
        return Err(TargetError::new(ppmc::backend::TargetErrorKind::Link, message).into());
    }
    let t1 = WallClock::now();
    let settings = DiffSettings::default();
    let mut fuzz = None;
    for seed in 0..budget.seeds {
        let acts = differential::program(seed).take(budget.actions);
        if let Some(d) = differential::run(target, acts, &settings, |_| true)? {
            let dv = d.divergence;
            fuzz = Some(Catch {
                first: format!(
                    "seed {seed} action {}: {}: emulator {}, target {}",
                    d.action + 1,
                    dv.quantity,
                    dv.golden,
                    dv.got
                ),
                after: t1.elapsed(),
            });
            break;
        }
    }
    let t2 = WallClock::now();
    let mut oracle = None;
    for seed in 0..budget.seeds {
        let acts: Vec<_> = differential::program(seed).take(budget.actions).collect();
        let (ops, _) = lower(&acts, ModelConfig::default());
        if let Some(f) = replay::replay(target, &ops)? {
            oracle = Some(Catch {
                first: format!("seed {seed}: {}", f.violation),
                after: t2.elapsed(),
            });
            break;
        }
    }
    let captures = capture::judge_captures(model, suite)?;
    Ok(Row {
        board: board.to_string(),
        suite: first_fail,
        golden: first_divergence,
        fuzz,
        oracle,
        capture: captures.catch,
        capture_skipped: captures.skipped,
    })
}

/// The matrix as a Markdown table, with a verdict per row.
pub fn render(rows: &[Row]) -> String {
    let cell = |c: &Option<Catch>| match c {
        Some(c) => format!("{:.0} ms", c.after.as_secs_f64() * 1e3),
        None => "-".into(),
    };
    let mut s = String::from(
        "| board | conformance suite | golden traces | differential fuzz | fuzz oracle | judged from captures | verdict |\n|---|---:|---:|---:|---:|---:|---|\n",
    );
    for r in rows {
        let verdict = match (r.board == "clean", r.caught()) {
            (true, false) => "no false alarm",
            (true, true) => "FALSE ALARM",
            (false, true) => "caught",
            (false, false) => "MISSED",
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {verdict} |\n",
            r.board,
            cell(&r.suite),
            cell(&r.golden),
            cell(&r.fuzz),
            cell(&r.oracle),
            cell(&r.capture)
        ));
    }
    s
}

/// Whether the matrix is as it must be: every fault caught, the clean
/// board by nothing (its captures included). A fault the capture column
/// misses is no failure of the matrix: [`capture::why_missed`] says why.
pub fn all_as_expected(rows: &[Row]) -> bool {
    rows.iter().all(|r| r.caught() != (r.board == "clean"))
}

/// A board's row, the clean one or one with a fault of the catalogue
/// (`name`, `model`): in process, or behind `bridge-sim` on a pty as a
/// board is reached. A board whose health check refuses it before any
/// scenario (as `ppmc run` would stop right there) is caught by the suite
/// column, and judged from captures all the same: a logic analyzer on
/// the board needs no link.
pub fn board_row(
    name: &str,
    model: ModelConfig,
    in_process: bool,
    suite: &[Scenario],
    golden: &Path,
    budget: FuzzBudget,
) -> Result<Row, String> {
    use ppmc::backend::{BridgeOptions, BridgeTarget, EmuTarget, SerialLink};
    use ppmc::bridge::sim::{LinkFaults, PtyBridge};
    let emu = EmuTarget::new(ppmc::protocol::Straps::default(), model.clone())
        .map_err(|e| e.to_string())?;
    if in_process {
        let mut t = emu;
        return check_board(name, &mut t, &model, suite, golden, budget).map_err(|e| e.to_string());
    }
    let sim = PtyBridge::start(emu, LinkFaults::default()).map_err(|e| e.to_string())?;
    let t0 = WallClock::now();
    let link = SerialLink::open(sim.path(), 115_200).map_err(|e| e.to_string())?;
    let mut t: Box<dyn Target> = match BridgeTarget::open(link, BridgeOptions::default()) {
        Ok(t) => Box::new(t),
        Err(e) if e.to_string().contains("health check") => {
            let refused = t0.elapsed();
            let captures = capture::judge_captures(&model, suite)
                .map_err(|e| format!("harness error in the capture column: {e}"))?;
            return Ok(Row {
                board: name.to_string(),
                suite: Some(Catch {
                    first: format!("refused by the health check: {e}"),
                    after: refused,
                }),
                golden: None,
                fuzz: None,
                oracle: None,
                capture: captures.catch,
                capture_skipped: captures.skipped,
            });
        }
        Err(e) => return Err(e.to_string()),
    };
    let row =
        check_board(name, t.as_mut(), &model, suite, golden, budget).map_err(|e| e.to_string());
    drop(t);
    sim.stop();
    row
}

/// What each check saw first on each board, one Markdown line each.
pub fn first_seen(rows: &[Row]) -> String {
    let mut text = String::new();
    for r in rows {
        for (check, c) in [
            ("suite", &r.suite),
            ("golden", &r.golden),
            ("fuzz", &r.fuzz),
            ("oracle", &r.oracle),
            ("capture", &r.capture),
        ] {
            if let Some(c) = c {
                let first = c.first.replace('\n', " ");
                text.push_str(&format!("- `{}` / {check}: {first}\n", r.board));
            }
        }
    }
    text
}
