//! The model beside the capture ([`Bench`]): run up to each change, the
//! board's pulses matched with the model's, and the windows within which
//! the capture cannot tell the board's timing from the model's.

use super::frame::Frame;
use super::{Divergence, Marginal};
use ppmc::compare::Tolerances;
use ppmc::emu::Board;
use ppmc::protocol::{Direction, Input, Status};
use ppmc::time::{Duration, Instant};
use ppmc_logic::decode::{Access, Transaction};

/// The model beside the capture, and what has been compared.
#[derive(Clone)]
pub(super) struct Bench {
    /// The capture has POUT: the pulses are compared.
    pub(super) pulses_judged: bool,
    pub(super) board: Board,
    /// The capture's time of the model's time zero, in picoseconds.
    pub(super) zero_ps: u64,
    pub(super) tol: Tolerances,
    pub(super) resolution_ps: u64,
    /// Captured POUT rising edges not yet compared, in capture time, each
    /// with DIR's level then (high: CCW) where the capture has DIR.
    pub(super) edges: std::collections::VecDeque<(u64, Option<bool>)>,
    /// The next model pulse to compare: its run and index.
    pub(super) run: usize,
    pub(super) pulse: u32,
    /// The last model pulse compared, for the interval tolerance.
    pub(super) last_model: Option<Instant>,
    /// The last pair of pulses matched in the move in progress (board,
    /// model, capture time): the next pulse of the move is expected where
    /// the board's last one was plus the model's interval, so that a board
    /// whose clock runs a few ppm off the model's is judged interval by
    /// interval, not drifting out of its tolerance as a move goes on.
    pub(super) chain: Option<(u64, u64)>,
    /// How far the board's last matched pulse was from the model's: the
    /// outputs timed from it (INT*, BUSY, HOLD) may be as far off.
    pub(super) pulse_offset_ps: u64,
    /// The last write, data read or matched pulse, in capture time: what
    /// a flag's change is timed from.
    pub(super) last_cause_ps: u64,
    pub(super) compared: u64,
    pub(super) last_access: Option<Transaction>,
    /// The pulses matched within the capture's uncertainty of their limit.
    pub(super) marginal: Marginal,
}

impl Bench {
    /// The model's time for capture time `ps` (never before its zero).
    pub(super) fn model_time(&self, ps: u64) -> Instant {
        Instant::from_nanos(ps.saturating_sub(self.zero_ps) / 1000)
    }

    /// Runs the model up to capture time `ps` (never back).
    pub(super) fn run_to(&mut self, ps: u64) {
        let t = self.model_time(ps);
        if t > self.board.now() {
            self.board.advance_to(t);
        }
    }

    pub(super) fn capture_ps(&self, t: Instant) -> u64 {
        t.as_nanos()
            .saturating_mul(1000)
            .saturating_add(self.zero_ps)
    }

    /// Where the board's pulse matching the model's at `m_ps` is
    /// expected, in capture time: chained from the last matched pair
    /// within a move, at the model's own time for a move's first pulse.
    pub(super) fn expected_ps(&self, m_ps: u64, first_of_move: bool) -> u64 {
        match self.chain {
            Some((b, last_m)) if !first_of_move && last_m <= m_ps => {
                b.saturating_add(m_ps - last_m)
            }
            _ => m_ps,
        }
    }

    /// How far a pulse may be from the model's, in picoseconds: the
    /// floor, two samples, and the interval tolerance of the time since
    /// the model's last pulse; for a move's first pulse, the latency
    /// tolerance of the time since the write that started the move (Table
    /// 3-3's first POUT, within its 1 %), its cause.
    pub(super) fn allowed_ps(&self, model: Instant, first_of_move: bool) -> u64 {
        let rel_ps = match first_of_move {
            true => {
                let since = self.capture_ps(model).saturating_sub(self.last_cause_ps);
                since.saturating_mul(self.tol.latency_bp) / 10_000
            }
            false => {
                let since = self
                    .last_model
                    .map_or(0, |l| model.as_nanos().saturating_sub(l.as_nanos()));
                since.saturating_mul(self.tol.interval_bp) / 10_000 * 1000
            }
        };
        (self.tol.floor.as_nanos().saturating_mul(1000))
            .saturating_add(rel_ps)
            .saturating_add(2 * self.resolution_ps)
    }

    /// How far a flag the board changes may stand from the model's, for
    /// a status read at `ps`: the floor, two samples, the latency
    /// tolerance of the time since its cause (the last write, data read
    /// or pulse), and the last pulse's offset.
    pub(super) fn latency_window(&self, ps: u64) -> u64 {
        let since = ps.saturating_sub(self.last_cause_ps);
        (self.tol.floor.as_nanos().saturating_mul(1000))
            .saturating_add(since.saturating_mul(self.tol.latency_bp) / 10_000)
            .saturating_add(2 * self.resolution_ps)
            .saturating_add(self.pulse_offset_ps)
    }

    /// Whether the model takes a status `matches` accepts at some time
    /// from now to capture time `ps`, ahead of the model (a copy run on,
    /// event by event; the model itself stays): every status in force in
    /// that window, not only the last.
    pub(super) fn status_until(&self, ps: u64, matches: impl Fn(u8) -> bool) -> bool {
        let mut probe = self.board.clone();
        run_until(&mut probe, self.model_time(ps), |s| matches(s.0))
    }

    /// Where an access of kind `access` at capture time `ps`, which the
    /// model's flags forbid there (a write while IBF or BUSY is 1, a data
    /// read while OBF is 0), would be allowed within the capture's
    /// uncertainty after it ([`Bench::latency_window`]): the capture time
    /// just after the flag's change, if any. The model itself stays.
    pub(super) fn allowed_within(&self, ps: u64, access: Access) -> Option<u64> {
        let forbids = |s: Status| match access {
            Access::WriteCommand | Access::WriteData => s.ibf() || s.busy(),
            Access::ReadData => !s.obf(),
            Access::ReadStatus => false,
        };
        if !forbids(self.board.read_status()) {
            return None;
        }
        let mut probe = self.board.clone();
        let limit = self.model_time(ps.saturating_add(self.latency_window(ps)));
        run_until(&mut probe, limit, |s| !forbids(s)).then(|| self.capture_ps(probe.now()))
    }

    /// The model as the outputs are compared with it.
    pub(super) fn frame(&self) -> Frame<'_> {
        Frame {
            board: &self.board,
            zero_ps: self.zero_ps,
            tol: &self.tol,
            resolution_ps: self.resolution_ps,
            slack_ps: self.pulse_offset_ps,
        }
    }

    /// How close to an input's change at `ps` a pulse may stand on
    /// either side of it, as far as the capture can tell: the pulses' own
    /// tolerance there, and at least a sample.
    pub(super) fn pulse_window(&self, ps: u64) -> u64 {
        self.allowed_ps(self.model_time(ps), false)
            .max(self.resolution_ps)
    }

    /// The inputs changed at capture time `ps`: given to the model. Where
    /// the model has a pulse within `w` of the change (the pulses'
    /// tolerance, [`Bench::pulse_window`]), the capture cannot say on
    /// which side of the change the chip's came: the board's own pulses
    /// there say (`board_pulsed`). The model takes the change after its
    /// pulse if the board pulsed, before it if not (notes N53).
    pub(super) fn give_inputs(
        &mut self,
        ps: u64,
        changes: &[(Input, bool)],
        board_pulsed: bool,
        w: u64,
    ) {
        self.run_to(ps.saturating_sub(w));
        let mut probe = self.board.clone();
        let late = self.model_time(ps.saturating_add(w));
        if late > probe.now() {
            probe.advance_to(late);
        }
        let model_pulsed = probe.record().pulse_count() > self.board.record().pulse_count();
        if !model_pulsed {
            self.run_to(ps);
        } else if board_pulsed {
            // Just past the model's pulse (or the change, if later).
            if let Some(last) = probe.record().runs.last().map(|r| r.last()) {
                let after = self.capture_ps(last).saturating_add(1000);
                self.run_to(after.max(ps));
            }
        }
        for &(input, asserted) in changes {
            self.board.set_input(input, asserted);
        }
    }

    /// The model's next pulse, if it has put it out by now, and whether
    /// it is the first of its move.
    pub(super) fn next_model_pulse(&self) -> Option<(Instant, Direction, bool)> {
        let record = self.board.record();
        let mut run = self.run;
        let mut pulse = self.pulse;
        while let Some(r) = record.runs.get(run) {
            if pulse < r.count {
                let first = pulse == 0 && record.moves.iter().any(|m| m.first_run == run);
                return Some((r.at(pulse), r.dir, first));
            }
            run += 1;
            pulse = 0;
        }
        None
    }

    pub(super) fn take_model_pulse(&mut self) {
        let runs = &self.board.record().runs;
        while let Some(r) = runs.get(self.run) {
            if self.pulse < r.count {
                self.pulse += 1;
                return;
            }
            self.run += 1;
            self.pulse = 0;
        }
    }

    /// Compares the pulses, the board's and the model's, that lie before
    /// `horizon_ps` by more than their tolerance: the model has been run
    /// up to `horizon_ps`, so nothing earlier can still change.
    pub(super) fn compare_pulses(&mut self, horizon_ps: u64) -> Result<(), Divergence> {
        // A signal with no channel is never a reason to fail the board.
        if !self.pulses_judged {
            return Ok(());
        }
        loop {
            let model = self.next_model_pulse();
            let board_dir = self.edges.front().and_then(|e| e.1);
            let board = self.edges.front().map(|e| e.0);
            let diverge =
                |what: String, board: String, model: String, at_ps: u64, s: &Bench| Divergence {
                    at_ps,
                    what,
                    board,
                    model,
                    after: s.last_access.map(|t| t.to_string()),
                };
            match (board, model) {
                (None, None) => return Ok(()),
                (Some(b), None) => {
                    let allowed = self.allowed_ps(self.model_time(b), false);
                    if b.saturating_add(allowed) >= horizon_ps {
                        return Ok(());
                    }
                    return Err(diverge(
                        format!("POUT pulse {}", self.compared + 1),
                        format!("a pulse at {}", Instant::from_nanos(b / 1000)),
                        "no pulse".into(),
                        b,
                        self,
                    ));
                }
                (b, Some((m, dir, first))) => {
                    let model_ps = self.capture_ps(m);
                    let m_ps = self.expected_ps(model_ps, first);
                    let allowed = self.allowed_ps(m, first);
                    match b {
                        Some(b) if b.abs_diff(m_ps) <= allowed => {
                            let ccw = dir == Direction::Ccw;
                            if board_dir.is_some_and(|high| high != ccw) {
                                let word = |ccw: bool| {
                                    if ccw {
                                        "CCW (DIR high)"
                                    } else {
                                        "CW (DIR low)"
                                    }
                                };
                                return Err(diverge(
                                    format!("DIR at POUT pulse {}", self.compared + 1),
                                    word(!ccw).to_string(),
                                    word(ccw).to_string(),
                                    b,
                                    self,
                                ));
                            }
                            let n = self.compared + 1;
                            self.marginal.note(
                                b.abs_diff(m_ps),
                                allowed,
                                2 * self.resolution_ps,
                                || {
                                    format!(
                                        "POUT pulse {n} at {}: {} from the model's, allowed {} (two samples of it the capture's uncertainty)",
                                        Instant::from_nanos(b / 1000),
                                        Duration::from_nanos(b.abs_diff(m_ps) / 1000),
                                        Duration::from_nanos(allowed / 1000)
                                    )
                                },
                            );
                            self.edges.pop_front();
                            self.take_model_pulse();
                            self.last_model = Some(m);
                            self.chain = Some((b, model_ps));
                            self.pulse_offset_ps = b.abs_diff(model_ps);
                            self.last_cause_ps = self.last_cause_ps.max(b);
                            self.compared += 1;
                        }
                        Some(b) if b.min(m_ps).saturating_add(allowed) < horizon_ps => {
                            return Err(diverge(
                                format!("POUT pulse {}", self.compared + 1),
                                format!("at {}", Instant::from_nanos(b / 1000)),
                                format!(
                                    "at {} (allowed {})",
                                    Instant::from_nanos(m_ps / 1000),
                                    Duration::from_nanos(allowed / 1000)
                                ),
                                b.min(m_ps),
                                self,
                            ));
                        }
                        None if m_ps.saturating_add(allowed) < horizon_ps => {
                            return Err(diverge(
                                format!("POUT pulse {}", self.compared + 1),
                                "no pulse".into(),
                                format!("a pulse at {}", Instant::from_nanos(m_ps / 1000)),
                                m_ps,
                                self,
                            ));
                        }
                        _ => return Ok(()),
                    }
                }
            }
        }
    }
}

/// The model's status at the capture's recent changes, for a status read
/// that may have seen it as its strobe began.
#[derive(Default, Clone)]
pub(super) struct StatusLog(std::collections::VecDeque<(u64, u8)>);

impl StatusLog {
    pub(super) fn push(&mut self, ps: u64, status: u8) {
        if self.0.len() == 64 {
            self.0.pop_front();
        }
        self.0.push_back((ps, status));
    }

    /// The status at the last change at or before `ps`.
    pub(super) fn at(&self, ps: u64) -> Option<u8> {
        self.0.iter().rev().find(|(t, _)| *t <= ps).map(|&(_, s)| s)
    }

    /// The statuses in force from `ps` on: the one at `ps`, and those of
    /// the changes after it.
    pub(super) fn since(&self, ps: u64) -> impl Iterator<Item = u8> + '_ {
        let first = self.0.iter().rposition(|(t, _)| *t <= ps).unwrap_or(0);
        self.0.iter().skip(first).map(|&(_, s)| s)
    }
}

/// Runs `probe` on, from one event of the model to the next, until `done`
/// holds of its status or `limit` has passed: whether it held.
pub(super) fn run_until(probe: &mut Board, limit: Instant, done: impl Fn(Status) -> bool) -> bool {
    loop {
        if done(probe.read_status()) {
            return true;
        }
        let now = probe.now();
        match probe.poll_at() {
            Some(t) if t <= limit => probe.advance_to(t.max(now + Duration::from_nanos(1))),
            _ => return false,
        }
    }
}
