//! A board judged from a capture of its bus and pins (issue 30,
//! `docs/capture.md`): the host's writes, decoded from the capture, go
//! into the reference model at their captured times; what the chip
//! answered (status and data reads) and put out (POUT's pulses) is
//! compared with what the model does, within the capture's resolution and
//! the usual tolerances. The verdict keeps the parties apart:
//!
//! - a **board** divergence: the chip answered or pulsed otherwise than
//!   the model would, given the same writes at the same times;
//! - **host** findings: the firmware driving the chip used it against
//!   chapter 3 (a byte written while IBF is 1, which replaces the waiting
//!   one; a data read before OBF; a byte the chip answered with an error
//!   of Table 3-2; the rules are in `host.rs`), not failures of the board;
//! - a **capture** problem: a signal missing, a sample rate too low for
//!   the strobes, a file that does not read.
//!
//! The model starts at the capture's start, or where the `reset` channel
//! falls when the capture has one (the chip's RESET released).

use ppmc::compare::Tolerances;
use ppmc::emu::{Board, ModelConfig};
use ppmc::protocol::{Input, Straps};
use ppmc::time::{Duration, Instant};
use ppmc_logic::decode::{BusDecoder, GLITCH_PS};
use ppmc_logic::map::{ChannelMap, Inverted, Signal};
use ppmc_logic::source::{Change, LogicError, LogicSource};
use std::fmt;

mod bench;
mod branch;
mod frame;
mod host;
mod outputs;
mod phases;
mod record;
mod suspect;
pub mod trace;
use bench::{run_until, Bench, StatusLog};
use branch::{best, prune, Branch};
pub use host::HostFinding;
use host::HostRules;
pub use suspect::{judge_reopening, Opener};

/// How to judge.
#[derive(Debug, Clone)]
pub struct JudgeOptions {
    pub straps: Straps,
    pub model: ModelConfig,
    pub tolerances: Tolerances,
    /// Strobes shorter than this are glitches, in picoseconds.
    pub glitch_ps: u64,
    /// Judge what a capture holds though it was cut short (it ends
    /// mid-line, mid-access, or while the board is still moving) or has
    /// no channel for POUT while the model pulses: a pass then says what
    /// was not judged. Without it, such a capture is the capture's
    /// problem, never a pass.
    pub partial: bool,
    /// Stop at the first divergence: the verdict and nothing after it
    /// (the counts, host findings and end checks are then partial). For
    /// trying another channel map (`suspect.rs`).
    pub stop_at_divergence: bool,
    /// Where the capture cannot order a host access against a change of
    /// IBF, OBF or BUSY, follow both orders (`Branch`; the default).
    /// Off, the model takes every access at its captured time, as the
    /// judge did before issue 40: for measuring what the capture's
    /// uncertainty costs a verdict.
    pub follow_orders: bool,
}

impl Default for JudgeOptions {
    fn default() -> Self {
        JudgeOptions {
            straps: Straps::default(),
            model: ModelConfig::default(),
            tolerances: Tolerances::default(),
            glitch_ps: GLITCH_PS,
            partial: false,
            stop_at_divergence: false,
            follow_orders: true,
        }
    }
}

/// Where the board first did otherwise than the model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Divergence {
    /// When, in picoseconds of the capture.
    pub at_ps: u64,
    /// What differs, in words: `POUT pulse 12`, `status read`.
    pub what: String,
    pub board: String,
    pub model: String,
    /// The last register access before it, as the console writes it.
    pub after: Option<String>,
}

/// The verdict on a capture.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CaptureVerdict {
    /// The board did what the model does, as far as the capture shows.
    Passed,
    /// The board diverged from the model: the board's fault.
    Failed(Divergence),
    /// The capture cannot be judged (or only in part): its fault, not the
    /// board's.
    Capture(String),
}

/// The comparisons whose difference from the model lies within the
/// capture's uncertainty of its limit (two samples: each edge is seen up to
/// a sample from where it was), by the decision rule of
/// `docs/conformance.md`: neither proven inside the tolerance nor outside
/// it. The board passes, MARGINAL.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Marginal {
    pub count: u64,
    /// The first of them, in words.
    pub first: Option<String>,
}

impl Marginal {
    /// A comparison that passed: `d` from the model, within `allowed`,
    /// which holds the uncertainty `u` beside the tolerance. Marginal
    /// unless `d ± u` lies wholly within the tolerance.
    fn note(&mut self, d: u64, allowed: u64, u: u64, what: impl FnOnce() -> String) {
        if d.saturating_add(u) > allowed.saturating_sub(u) {
            self.count += 1;
            if self.first.is_none() {
                self.first = Some(what());
            }
        }
    }
}

/// What judging a capture found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Judgement {
    pub verdict: CaptureVerdict,
    pub host: Vec<HostFinding>,
    /// The register accesses decoded and the POUT pulses compared.
    pub accesses: u64,
    pub pulses: u64,
    /// The changes of the other outputs compared (INT*, BUSY, HOLD, AUX*,
    /// AUXO0..3, S1..S5 and the chopping's edges).
    pub changes: u64,
    /// What could not be judged, and why (a signal with no channel).
    pub not_judged: Vec<String>,
    /// What the capture suggests of its own map where the board diverged
    /// (`POUT looks inverted: ...`), for the user to weigh.
    pub hints: Vec<String>,
    /// The comparisons within the capture's uncertainty of their limits.
    pub marginal: Marginal,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} at {}: board {}, model {}",
            self.what,
            Instant::from_nanos(self.at_ps / 1000),
            self.board,
            self.model
        )?;
        if let Some(a) = &self.after {
            write!(f, " (after `{a}`)")?;
        }
        Ok(())
    }
}

/// A capture read with a little look-ahead: the board's pulses just
/// after an input's change say on which side of it they came.
struct Lookahead<'a> {
    src: &'a mut dyn LogicSource,
    ahead: std::collections::VecDeque<Change>,
    /// The source is done, or failed (the error given in its turn).
    done: bool,
    failed: Option<LogicError>,
}

impl<'a> Lookahead<'a> {
    fn new(src: &'a mut dyn LogicSource) -> Self {
        Lookahead {
            src,
            ahead: Default::default(),
            done: false,
            failed: None,
        }
    }

    fn next(&mut self) -> Result<Option<Change>, LogicError> {
        if let Some(c) = self.ahead.pop_front() {
            return Ok(Some(c));
        }
        if let Some(e) = self.failed.take() {
            return Err(e);
        }
        if self.done {
            return Ok(None);
        }
        self.src.next_change()
    }

    /// The changes to come up to `ps`, read ahead.
    fn peek_until(&mut self, ps: u64) -> impl Iterator<Item = &Change> {
        while !self.done
            && self.failed.is_none()
            && self.ahead.back().is_none_or(|b| b.time_ps <= ps)
        {
            match self.src.next_change() {
                Ok(Some(c)) => self.ahead.push_back(c),
                Ok(None) => self.done = true,
                Err(e) => self.failed = Some(e),
            }
        }
        self.ahead.iter().take_while(move |c| c.time_ps <= ps)
    }
}

/// What a capture that ends while the model is still moving leaves
/// unjudged: which move, and how many pulses the model has still to put
/// out (found by running a copy on, a bounded while).
fn unfinished(board: &Board) -> String {
    let moves = board.record().moves.len();
    let mut probe = board.clone();
    let limit = probe.now() + Duration::from_secs(3600);
    let rests = run_until(&mut probe, limit, |s| !s.busy());
    let left = probe.record().pulse_count() - board.record().pulse_count();
    match (rests, left) {
        (true, 0) => format!(
            "the recording ends before move {moves} finished (BUSY still 1, its last pulse out): its end is unjudged"
        ),
        (true, _) => format!(
            "the recording ends during move {moves}, the board still moving: {left} pulses unjudged"
        ),
        (false, 0) => format!(
            "the recording ends during move {moves}, BUSY still 1: the model puts out no pulse in the hour after it and is still BUSY then"
        ),
        (false, _) => format!(
            "the recording ends during move {moves}, the board still moving: {left} pulses unjudged in the hour after it, and more"
        ),
    }
}

/// Why a capture could not be judged at all.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum JudgeError {
    /// The capture does not read.
    #[error("{0}")]
    Capture(#[from] LogicError),
    /// The model cannot take the options (straps out of range).
    #[error("the reference model: {0}")]
    Model(String),
}

/// Judges the capture `source` of a board whose signals are on `map`'s
/// channels.
pub fn judge(
    source: &mut dyn LogicSource,
    map: &ChannelMap,
    opts: &JudgeOptions,
) -> Result<Judgement, JudgeError> {
    judge_traced(source, map, opts, None).map(|(j, _)| j)
}

/// [`judge`], and with `scenario` the capture as a trace of that name
/// (`ppmc judge --trace`, [`trace`]): `None` where the bus cannot be
/// decoded.
pub fn judge_traced(
    source: &mut dyn LogicSource,
    map: &ChannelMap,
    opts: &JudgeOptions,
    scenario: Option<&str>,
) -> Result<(Judgement, Option<ppmc::trace::Trace>), JudgeError> {
    let info = source.info().clone();
    // The map's inverted channels read as the chip's levels.
    let mut source = Inverted::new(source, map);
    let mut not_judged = Vec::new();
    let bus = match map.require_bus(&info) {
        Ok(bus) => bus,
        Err(why) => {
            return Ok((
                Judgement {
                    verdict: CaptureVerdict::Capture(why),
                    host: Vec::new(),
                    accesses: 0,
                    pulses: 0,
                    changes: 0,
                    not_judged,
                    hints: Vec::new(),
                    marginal: Marginal::default(),
                },
                None,
            ))
        }
    };
    let pout = map.get(Signal::Pout);
    if pout.is_none() {
        not_judged.push("POUT's pulses: no channel for POUT".to_string());
    } else if map.get(Signal::Dir).is_none() {
        not_judged.push("the direction of each pulse: no channel for DIR".to_string());
    }
    let inputs: Vec<(Input, usize)> = Input::ALL
        .into_iter()
        .filter_map(|i| map.get(Signal::Input(i)).map(|c| (i, c)))
        .collect();
    if inputs.len() < Input::ALL.len() {
        let missing: Vec<String> = Input::ALL
            .into_iter()
            .filter(|i| !inputs.iter().any(|(j, _)| j == i))
            .map(|i| Signal::Input(i).name())
            .collect();
        not_judged.push(format!(
            "inputs {}: no channel, taken as never asserted",
            missing.join(", ")
        ));
    }
    let reset = info.channel("reset");
    let board = Board::new(opts.straps, opts.model.clone())
        .map_err(|e| JudgeError::Model(e.to_string()))?;
    let bench = Bench {
        pulses_judged: pout.is_some(),
        board,
        zero_ps: 0,
        tol: opts.tolerances,
        resolution_ps: info.resolution_ps,
        edges: Default::default(),
        run: 0,
        pulse: 0,
        last_model: None,
        chain: None,
        pulse_offset_ps: 0,
        last_cause_ps: 0,
        compared: 0,
        last_access: None,
        marginal: Marginal::default(),
    };
    let outputs = outputs::Outputs::new(map, &bench.board);
    let unwatched: Vec<String> = [Signal::Int, Signal::Busy, Signal::Hold, Signal::Aux]
        .into_iter()
        .chain((0..4).map(Signal::Auxo))
        .chain((1..=5).map(Signal::Phase))
        .filter(|s| !outputs.signals().any(|w| w == *s))
        .map(Signal::name)
        .collect();
    if !unwatched.is_empty() {
        not_judged.push(format!("outputs {}: no channel", unwatched.join(", ")));
    }
    let mut decoder = BusDecoder::new(bus, &info, opts.glitch_ps);
    let mut branches = vec![Branch {
        bench,
        outputs,
        rules: HostRules::default(),
        host: Vec::new(),
        status_log: StatusLog::default(),
        failed: None,
    }];
    let mut prev: Option<Change> = None;
    let mut started = reset.is_none();
    // POUT's level where the model starts: the chip idles it low.
    let mut pout_at_start: Option<bool> = None;
    let mut source = Lookahead::new(&mut source);
    let mut tracer = scenario.map(|_| trace::CaptureTrace::new(map, &info));
    while let Some(c) = source.next()? {
        // The inputs' levels before this change: none at the model's start
        // (an input held asserted through reset is asserted from it).
        let mut inputs_before = prev;
        if !started {
            // The model starts where RESET is released.
            if let Some(r) = reset {
                if c.high(r) {
                    prev = Some(c);
                    continue;
                }
                started = true;
                for b in &mut branches {
                    b.bench.zero_ps = c.time_ps;
                }
                inputs_before = None;
            }
        }
        if pout_at_start.is_none() {
            pout_at_start = pout.map(|ch| c.high(ch));
            // Another map tried (`suspect`): one that reads POUT idling
            // high is no better, known at once.
            if opts.stop_at_divergence && pout_at_start == Some(true) {
                break;
            }
        }
        // The inputs as the board drove them (active low).
        let changed: Vec<(Input, bool)> = inputs
            .iter()
            .filter(|&&(_, ch)| c.high(ch) != inputs_before.is_none_or(|q| q.high(ch)))
            .map(|&(input, ch)| (input, !c.high(ch)))
            .collect();
        for b in &mut branches {
            if !changed.is_empty() {
                // A pulse this close to the change may stand on either
                // side of it: the pulses' own tolerance, at least a sample.
                let bench = &mut b.bench;
                let w = bench.pulse_window(c.time_ps);
                let board_pulsed = bench.edges.iter().any(|e| e.0.abs_diff(c.time_ps) <= w)
                    || pout.is_some_and(|ch| {
                        let mut level = prev.is_some_and(|q| q.high(ch));
                        let this = std::iter::once(&c);
                        this.chain(source.peek_until(c.time_ps.saturating_add(w)))
                            .any(|n| {
                                let rose = n.high(ch) && !level;
                                level = n.high(ch);
                                rose
                            })
                    });
                bench.give_inputs(c.time_ps, &changed, board_pulsed, w);
            }
            b.change(&c, prev.as_ref(), map, pout);
        }
        if let Some(tr) = &mut tracer {
            let bench = &branches[0].bench;
            tr.change(&c, prev.as_ref(), bench.model_time(c.time_ps), &bench.board);
        }
        if let Some(t) = decoder.push(c) {
            let mut forks = Vec::new();
            for b in &mut branches {
                forks.extend(b.access(&t, opts.follow_orders));
            }
            branches.extend(forks);
            if let Some(tr) = &mut tracer {
                tr.access(&t, branches[0].bench.model_time(t.end_ps));
            }
            prune(&mut branches);
        }
        prev = Some(c);
        if opts.stop_at_divergence && branches.iter().all(|b| b.failed.is_some()) {
            break;
        }
    }
    let stopped = opts.stop_at_divergence && branches.iter().all(|b| b.failed.is_some());
    let cut = source.src.cut_short();
    let end = source.src.end_ps();
    for b in &mut branches {
        b.finish(end);
    }
    let chosen = best(&branches);
    let Branch {
        bench,
        outputs,
        host,
        failed,
        ..
    } = branches.swap_remove(chosen);
    let summary = decoder.summary();
    let held = (!started).then(|| {
        "the `reset` channel never falls: the chip is held in reset for the whole capture"
            .to_string()
    });
    let quiet = (summary.transactions == 0).then(|| {
        "no register access on the bus: nothing to judge (are the probes on CS*, RD*, WR*? did the recording start after the host's accesses?)"
            .to_string()
    });
    // Where the recording ends before the board is done, or lacks what
    // the model's moves need: the capture's problem, or with `partial`
    // what was not judged.
    let mut short = Vec::new();
    if !stopped {
        short.extend(cut);
        if let Some(c) = prev.filter(|c| !c.high(bus.rd) || !c.high(bus.wr)) {
            short.push(format!(
                "the recording ends during a register access ({} low at its last change, {})",
                if c.high(bus.rd) { "WR*" } else { "RD*" },
                Instant::from_nanos(c.time_ps / 1000)
            ));
        }
        if started && bench.board.read_status().busy() {
            short.push(unfinished(&bench.board));
        }
        let made = bench.board.record().pulse_count();
        if pout.is_none() && made > 0 {
            short.push(format!(
                "the model put out {made} POUT pulses and the capture has no channel for POUT: none of them judged (map it: --map POUT=CHANNEL)"
            ));
        }
    }
    let partial_problem = match (short.is_empty(), opts.partial) {
        (true, _) => None,
        (false, true) => {
            not_judged.extend(short);
            None
        }
        (false, false) => Some(format!(
            "{} (judge what it holds with --partial)",
            short.join("; ")
        )),
    };
    // A POUT that idles high is read inverted: its rising edges are the
    // ends of the pulses, a pulse width late, which the tolerance may
    // hide. The capture's, naming the map that reads it.
    let pout_inverted = pout.filter(|_| pout_at_start == Some(true)).map(|ch| {
        format!(
            "POUT is high where the model starts (the chip idles it low): it looks inverted (an inverting or open-collector output stage): read it so with --map POUT=~{}",
            info.channels.get(ch).map_or("CHANNEL", String::as_str)
        )
    });
    let problem = summary
        .rate_problem(&info)
        .or_else(|| summary.strobe_problem())
        .or(pout_inverted)
        .or(held)
        .or(quiet)
        .or(partial_problem);
    let verdict = match (failed, problem) {
        (_, Some(why)) => CaptureVerdict::Capture(why),
        (Some(d), None) => CaptureVerdict::Failed(d),
        (None, None) => CaptureVerdict::Passed,
    };
    let trace = tracer
        .zip(scenario)
        .map(|(tr, name)| tr.finish(name, &info, &bench.board, opts.straps));
    Ok((
        Judgement {
            verdict,
            host,
            accesses: summary.transactions,
            pulses: bench.compared,
            changes: outputs.compared(),
            not_judged,
            hints: Vec::new(),
            marginal: {
                let mut m = bench.marginal;
                let o = outputs.marginal();
                m.count += o.count;
                m.first = m.first.or(o.first);
                m
            },
        },
        trace,
    ))
}
