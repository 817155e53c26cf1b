//! The model beside the capture as the outputs are compared with it
//! (INT*, BUSY, HOLD, AUX*, AUXO and S1..S5), and how far a change of the
//! board's may be from the model's.

use ppmc::compare::Tolerances;
use ppmc::emu::Board;
use ppmc::protocol::PulseRun;
use ppmc::time::Instant;
use std::collections::VecDeque;

/// The model beside the capture, as the outputs are compared with it.
#[derive(Clone, Copy)]
pub(super) struct Frame<'a> {
    pub(super) board: &'a Board,
    /// The capture's time of the model's zero.
    pub(super) zero_ps: u64,
    pub(super) tol: &'a Tolerances,
    pub(super) resolution_ps: u64,
    /// How far the board's last pulse was from the model's: an output
    /// timed from it may be as far off.
    pub(super) slack_ps: u64,
}

impl Frame<'_> {
    /// The capture's time of model time `t`.
    pub(super) fn capture_ps(&self, t: Instant) -> u64 {
        t.as_nanos()
            .saturating_mul(1000)
            .saturating_add(self.zero_ps)
    }

    /// The tolerance of a time `ps` after its cause: the floor, two
    /// samples, and the latency tolerance of it.
    pub(super) fn within(&self, ps: u64) -> u64 {
        (self.tol.floor.as_nanos().saturating_mul(1000))
            .saturating_add(ps.saturating_mul(self.tol.latency_bp) / 10_000)
            .saturating_add(2 * self.resolution_ps)
    }

    /// How far a change at capture time `ps` may be from the model's:
    /// [`Frame::within`] the time since its cause (the last pulse or
    /// register access at it or before it; strictly before it with
    /// `before`, for what comes with a pulse), and how far the board's
    /// last pulse was from the model's.
    pub(super) fn allowed(&self, ps: u64, accesses: &VecDeque<u64>, before: bool) -> u64 {
        let m = Instant::from_nanos(ps.saturating_sub(self.zero_ps) / 1000);
        let (m, by_ps) = if before {
            (
                Instant::from_nanos(m.as_nanos().saturating_sub(1)),
                ps.saturating_sub(1),
            )
        } else {
            (m, ps)
        };
        let pulse = last_pulse_by(&self.board.record().runs, m).map(|t| self.capture_ps(t));
        let access = accesses.iter().rev().find(|&&a| a <= by_ps).copied();
        let cause = pulse.max(access).unwrap_or(self.zero_ps);
        self.within(ps.saturating_sub(cause))
            .saturating_add(self.slack_ps)
    }
}

/// The last pulse of `runs` at or before `t`.
fn last_pulse_by(runs: &[PulseRun], t: Instant) -> Option<Instant> {
    let run = runs.iter().rev().find(|r| r.count > 0 && r.start <= t)?;
    let (mut lo, mut hi) = (0u32, run.count - 1);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if run.at(mid) <= t {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    Some(run.at(lo))
}
