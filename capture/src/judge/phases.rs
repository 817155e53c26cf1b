//! The excitation outputs S1..S5 (issue 40), compared at their levels:
//! each step of the excitation sequence as POUT steps it, each pattern
//! the chip sets, under the output logic the capture's initialization set
//! (Section 3-2-1), and stop switching's chopping (Section 3-5-1).
//!
//! The model's record keeps energized patterns, not levels, and not the
//! chopping's edges: [`PhaseLevels`] draws the levels from it (the
//! patterns set, each move's winding and start position, a step per
//! pulse, stop switching on and off) under the output logic (from the
//! moment the model set it) and the ON and OFF times the model holds when
//! the chopping starts.
//!
//! The chopping is judged by its intervals, not edge against edge: each
//! ON and OFF the board shows must last the model's ON or OFF time within
//! the latency tolerance of it (the first from where the model's chopping
//! starts, within the tolerance of the time since what caused it), and
//! where the chopping ends (BUSY rises, the phases are switched off) the
//! board's phase must be at the model's level within that moment's
//! tolerance. A board whose chopping runs a little slow or fast, within
//! the tolerance, drifts from the model's edges over a long stop and ends
//! with an edge more or fewer, and passes; one whose ON or OFF is too long
//! or too short fails at the first such interval.

use super::frame::Frame;
use super::{Divergence, Marginal};
use ppmc::emu::Board;
use ppmc::protocol::{Direction, PhaseOutputs, Pin, Winding};
use ppmc::time::{Duration, Instant};
use ppmc_logic::map::Signal;
use ppmc_logic::source::Change as Sample;
use std::collections::VecDeque;

/// What the model did to S1..S5, in the order it did it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PhaseChange {
    /// The levels (S1 in bit 4) from here.
    Levels(u8),
    /// Stop switching starts: the levels alternate between `on` (as they
    /// stand) and `off`, for `on_time` and `off_time`.
    ChopStart {
        on: u8,
        off: u8,
        on_time: Duration,
        off_time: Duration,
    },
    /// Stop switching ends, the levels `on` from here.
    ChopEnd(u8),
}

/// The levels of S1..S5 over model time, drawn from the model's record as
/// it grows.
#[derive(Clone)]
pub(super) struct PhaseLevels {
    /// Where the record has been read to.
    next_pin: usize,
    next_move: usize,
    run: usize,
    pulse: u32,
    /// The excitation sequence and step position the pulses step.
    winding: Option<Winding>,
    index: u32,
    /// The move's direction, which the phases step in.
    dir: Option<Direction>,
    /// The energized phases (the chopping aside).
    pattern: u8,
    setup: PhaseOutputs,
    levels: u8,
    /// The changes drawn and not yet taken by every phase; `base` is how
    /// many were taken before the first.
    changes: VecDeque<(Instant, PhaseChange)>,
    base: usize,
}

impl PhaseLevels {
    /// The levels as `board` drives them now, its record read from here.
    pub(super) fn new(board: &Board) -> PhaseLevels {
        let record = board.record();
        let setup = board.phase_outputs();
        let pattern = board.pins().phases;
        PhaseLevels {
            next_pin: record.pins.len(),
            next_move: record.moves.len(),
            run: record.runs.len(),
            pulse: 0,
            winding: None,
            index: 0,
            dir: None,
            pattern,
            setup,
            levels: setup.logic.levels(pattern),
            changes: VecDeque::new(),
            base: 0,
        }
    }

    /// The `n`-th change drawn (counting from the first ever), if drawn.
    fn change(&self, n: usize) -> Option<(Instant, PhaseChange)> {
        self.changes.get(n.checked_sub(self.base)?).copied()
    }

    /// Forgets the changes before the `n`-th: every phase has taken them.
    fn taken(&mut self, n: usize) {
        while self.base < n && self.changes.pop_front().is_some() {
            self.base += 1;
        }
    }

    fn levels_now(&mut self, at: Instant) {
        let levels = self.setup.logic.levels(self.pattern);
        if levels == self.levels {
            return;
        }
        self.levels = levels;
        match self.changes.back_mut() {
            // The chopping ends and the phases change at one instant (a
            // software reset): the levels after both are where it ends.
            Some((t, PhaseChange::ChopEnd(v))) if *t == at => *v = levels,
            _ => self.changes.push_back((at, PhaseChange::Levels(levels))),
        }
    }

    /// Draws the changes up to where the model stands.
    pub(super) fn draw(&mut self, board: &Board) {
        let until = board.chip().now();
        let record = board.record();
        let setup = board.phase_outputs();
        self.setup.on = setup.on;
        self.setup.off = setup.off;
        let mut logic = (setup.logic != self.setup.logic).then_some(setup.logic_since);
        loop {
            // A run done, and another after it: on to that one.
            while record
                .runs
                .get(self.run)
                .is_some_and(|r| self.pulse >= r.count)
                && self.run + 1 < record.runs.len()
            {
                self.run += 1;
                self.pulse = 0;
            }
            let pin = record.pins.get(self.next_pin).map(|e| e.at);
            let mv = record.moves.get(self.next_move).map(|m| m.at);
            let pulse = record
                .runs
                .get(self.run)
                .filter(|r| self.pulse < r.count)
                .map(|r| r.at(self.pulse));
            let next = [logic, mv, pin, pulse].into_iter().flatten().min();
            let Some(at) = next.filter(|&t| t <= until) else {
                break;
            };
            // Where they share a time: the logic first, a move's start
            // before its pulses, a pattern before the chopping it starts.
            if logic == Some(at) {
                self.setup.logic = setup.logic;
                logic = None;
                self.levels_now(at);
            } else if mv == Some(at) {
                let m = &record.moves[self.next_move];
                self.winding = m.winding;
                self.index = m.phase_index;
                self.dir = Some(m.dir);
                self.next_move += 1;
            } else if pin == Some(at) {
                let e = record.pins[self.next_pin];
                self.next_pin += 1;
                match e.pin {
                    Pin::Phases => {
                        self.pattern = e.value;
                        self.levels_now(at);
                    }
                    Pin::Switching => {
                        self.levels_now(at);
                        let change = if e.value != 0 {
                            PhaseChange::ChopStart {
                                on: self.levels,
                                off: self.setup.logic.levels(0),
                                on_time: self.setup.on,
                                off_time: self.setup.off,
                            }
                        } else {
                            PhaseChange::ChopEnd(self.levels)
                        };
                        self.changes.push_back((at, change));
                    }
                    _ => {}
                }
            } else {
                let dir = self.dir.unwrap_or(record.runs[self.run].dir);
                if let Some(w) = self.winding {
                    self.index = w.advance(self.index, dir, 1);
                    self.pattern = w.pattern(self.index);
                }
                self.pulse += 1;
                self.levels_now(at);
            }
        }
    }
}

/// How the phases are compared: the capture's frame and its tolerances,
/// lent by the outputs' comparison.
pub(super) struct Rules<'a> {
    pub(super) frame: &'a Frame<'a>,
    /// The register accesses an output's change is timed from.
    pub(super) accesses: &'a VecDeque<u64>,
    pub(super) horizon_ps: u64,
    pub(super) after: Option<String>,
}

impl Rules<'_> {
    fn capture_ps(&self, t: Instant) -> u64 {
        self.frame.capture_ps(t)
    }

    /// How far a change at capture time `ps` may be from the model's: a
    /// phase steps with a pulse, so its cause is what caused the pulse,
    /// the pulse or access before it.
    fn allowed(&self, ps: u64) -> u64 {
        self.frame.allowed(ps, self.accesses, true)
    }

    /// The tolerance of an interval `ps` long.
    fn interval(&self, ps: u64) -> u64 {
        self.frame.within(ps)
    }

    /// Two samples: the capture's uncertainty.
    fn u_ps(&self) -> u64 {
        2 * self.frame.resolution_ps
    }
}

/// The chopping of one phase, as the board shows it.
#[derive(Debug, Clone, Copy)]
struct Chopping {
    on_level: bool,
    on_ps: u64,
    off_ps: u64,
    /// The board's last edge (or the model's start), and the phase's
    /// level since.
    last_ps: u64,
    level: bool,
    /// The model's start: the first edge is timed from it.
    first: bool,
}

impl Chopping {
    /// How long the level since the last edge lasts.
    fn lasts(&self) -> u64 {
        if self.level == self.on_level {
            self.on_ps
        } else {
            self.off_ps
        }
    }
}

/// One of S1..S5 and its two sides.
#[derive(Clone)]
pub(super) struct PhaseWatch {
    /// 1 for S1.
    k: u8,
    channel: usize,
    /// The board's changes not compared yet: capture time, level.
    board: VecDeque<(u64, bool)>,
    seen: Option<bool>,
    /// The model's level as far as compared, and where its changes have
    /// been read to.
    model: bool,
    next: usize,
    chopping: Option<Chopping>,
}

impl PhaseWatch {
    pub(super) fn new(k: u8, channel: usize, board: &Board) -> PhaseWatch {
        PhaseWatch {
            k,
            channel,
            board: VecDeque::new(),
            seen: None,
            model: board.pins().phase_levels >> (5 - k) & 1 == 1,
            next: 0,
            chopping: None,
        }
    }

    pub(super) fn signal(&self) -> Signal {
        Signal::Phase(self.k)
    }

    fn bit(&self, levels: u8) -> bool {
        levels >> (5 - self.k) & 1 == 1
    }

    /// The capture's change `c`: the board's side. Its first level counts
    /// as a change when the model's differs.
    pub(super) fn observe(&mut self, c: &Sample) {
        let level = c.high(self.channel);
        match self.seen {
            Some(l) if l == level => {}
            None if level == self.model => {}
            _ => self.board.push_back((c.time_ps, level)),
        }
        self.seen = Some(level);
    }

    fn diverge(
        &self,
        r: &Rules<'_>,
        at_ps: u64,
        level: bool,
        board: String,
        model: String,
    ) -> Divergence {
        Divergence {
            at_ps,
            what: format!("S{} {}", self.k, if level { "high" } else { "low" }),
            board,
            model,
            after: r.after.clone(),
        }
    }

    /// Compares the changes before `r.horizon_ps` by more than their
    /// tolerance; `compared` counts the board's changes matched.
    pub(super) fn compare(
        &mut self,
        levels: &PhaseLevels,
        r: &Rules<'_>,
        marginal: &mut Marginal,
        compared: &mut u64,
    ) -> Result<(), Divergence> {
        let at = |ps: u64| Instant::from_nanos(ps / 1000);
        let span = |ps: u64| Duration::from_nanos(ps / 1000);
        loop {
            if let Some(mut ch) = self.chopping {
                // The chopping's end, where the model has drawn it, and how
                // far from it the board's may be.
                let end = match levels.change(self.next) {
                    Some((t, PhaseChange::ChopEnd(_))) => {
                        let c = r.capture_ps(t);
                        Some((c, r.allowed(c)))
                    }
                    _ => None,
                };
                let expected = ch.last_ps.saturating_add(ch.lasts());
                let tol = if ch.first {
                    r.allowed(expected)
                } else {
                    r.interval(ch.lasts())
                };
                let fits = |b: u64| b.abs_diff(expected) <= tol;
                // At or past the earliest the chopping may end; past the
                // latest.
                let ending = |t: u64| end.is_some_and(|(c, a)| t >= c.saturating_sub(a));
                let ended = |t: u64| end.is_some_and(|(c, a)| t > c.saturating_add(a));
                match self.board.front().copied() {
                    // An edge of the chopping: the board's may run on a
                    // little past the model's end.
                    Some((b, level)) if fits(b) && !ended(b) => {
                        marginal.note(b.abs_diff(expected), tol, r.u_ps(), || {
                            format!(
                                "S{} chopping at {}: {} from its ON or OFF time, allowed {} (two samples of it the capture's uncertainty)",
                                self.k,
                                at(b),
                                span(b.abs_diff(expected)),
                                span(tol)
                            )
                        });
                        self.board.pop_front();
                        ch.last_ps = b;
                        ch.level = level;
                        ch.first = false;
                        self.chopping = Some(ch);
                        *compared += 1;
                    }
                    // Out of rhythm where the model has not reached the
                    // chopping's end: the board's may come first (its move
                    // started within the capture's uncertainty before the
                    // model's). Wait as long as the end may be behind it.
                    Some((b, _))
                        if end.is_none() && b.saturating_add(r.allowed(b)) >= r.horizon_ps =>
                    {
                        return Ok(())
                    }
                    Some((b, level)) if !ending(b) => {
                        let what = if ch.level == ch.on_level { "ON" } else { "OFF" };
                        return Err(self.diverge(
                            r,
                            b.min(expected),
                            level,
                            format!(
                                "at {} ({} after the last edge)",
                                at(b),
                                span(b - ch.last_ps)
                            ),
                            format!(
                                "stop switching's {what} time {} from {} (allowed {}): at {}",
                                span(ch.lasts()),
                                at(ch.last_ps),
                                span(tol),
                                at(expected)
                            ),
                        ));
                    }
                    None if !ending(expected.saturating_add(tol)) => {
                        // The board's edge is due: missed once the capture
                        // is past it.
                        if expected.saturating_add(tol) >= r.horizon_ps {
                            return Ok(());
                        }
                        return Err(self.diverge(
                            r,
                            expected,
                            !ch.level,
                            "no change".into(),
                            format!(
                                "stop switching's edge at {} (allowed {})",
                                at(expected),
                                span(tol)
                            ),
                        ));
                    }
                    // An edge that may yet come, where the chopping may
                    // have ended: wait for it.
                    None if expected.saturating_add(tol) >= r.horizon_ps => return Ok(()),
                    _ => {
                        // The chopping ends: the phase as the board left
                        // it, and the model's level after, compared as
                        // any change (the board's change near the end, if
                        // it makes one).
                        self.model = ch.level;
                        self.chopping = None;
                    }
                }
                continue;
            }
            // The model's next change of this phase.
            let mut model = None;
            while let Some((t, change)) = levels.change(self.next) {
                match change {
                    PhaseChange::Levels(v) | PhaseChange::ChopEnd(v)
                        if self.bit(v) != self.model =>
                    {
                        model = Some((t, self.bit(v)));
                        break;
                    }
                    PhaseChange::ChopStart {
                        on,
                        off,
                        on_time,
                        off_time,
                    } if self.bit(on) != self.bit(off) => {
                        let s = r.capture_ps(t);
                        // A change of the board's before the chopping
                        // starts is one no model change explains.
                        if self.board.front().is_some_and(|&(b, _)| b < s) {
                            break;
                        }
                        self.chopping = Some(Chopping {
                            on_level: self.bit(on),
                            on_ps: on_time.as_nanos().saturating_mul(1000),
                            off_ps: off_time.as_nanos().saturating_mul(1000),
                            last_ps: s,
                            level: self.bit(on),
                            first: true,
                        });
                        self.next += 1;
                        break;
                    }
                    _ => self.next += 1,
                }
            }
            if self.chopping.is_some() {
                continue;
            }
            match (self.board.front().copied(), model) {
                (None, None) => return Ok(()),
                (Some((b, level)), None) => {
                    let allowed = r.allowed(b);
                    if b.saturating_add(allowed) >= r.horizon_ps {
                        return Ok(());
                    }
                    return Err(self.diverge(
                        r,
                        b,
                        level,
                        format!("at {}", at(b)),
                        format!("no change within {}", span(allowed)),
                    ));
                }
                (b, Some((m, level))) => {
                    let m_ps = r.capture_ps(m);
                    let allowed = r.allowed(m_ps);
                    match b {
                        Some((b, bl)) if bl == level && b.abs_diff(m_ps) <= allowed => {
                            marginal.note(b.abs_diff(m_ps), allowed, r.u_ps(), || {
                                format!(
                                    "S{} {} at {}: {} from the model's, allowed {} (two samples of it the capture's uncertainty)",
                                    self.k,
                                    if level { "high" } else { "low" },
                                    at(b),
                                    span(b.abs_diff(m_ps)),
                                    span(allowed)
                                )
                            });
                            self.board.pop_front();
                            self.model = level;
                            self.next += 1;
                            *compared += 1;
                        }
                        Some((b, bl)) if b.min(m_ps).saturating_add(allowed) < r.horizon_ps => {
                            let (at_ps, shown) = if b < m_ps { (b, bl) } else { (m_ps, level) };
                            return Err(self.diverge(
                                r,
                                at_ps,
                                shown,
                                format!("{} at {}", if bl { "high" } else { "low" }, at(b)),
                                format!(
                                    "{} at {} (allowed {})",
                                    if level { "high" } else { "low" },
                                    at(m_ps),
                                    span(allowed)
                                ),
                            ));
                        }
                        None if m_ps.saturating_add(allowed) < r.horizon_ps => {
                            return Err(self.diverge(
                                r,
                                m_ps,
                                level,
                                "no change".into(),
                                format!("at {}", at(m_ps)),
                            ));
                        }
                        _ => return Ok(()),
                    }
                }
            }
        }
    }
}

/// Forgets what every phase has taken.
pub(super) fn taken(levels: &mut PhaseLevels, watches: &[PhaseWatch]) {
    if let Some(n) = watches.iter().map(|w| w.next).min() {
        levels.taken(n);
    }
}
