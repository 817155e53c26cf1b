//! The pulse plan of one move.
//!
//! A move of N pulses is described by the period that follows each pulse.
//! For a ramped move (Sections 3-3-4 and 3-3-7) the period after pulse `j`
//! is `table[v(j)]`, where the speed index
//!
//! ```text
//! v(j) = min(j, N - 2 - j, PA - 1)    (PA = acceleration pulses)
//! ```
//!
//! rises by one per pulse, holds at PA - 1 (the high speed: the PA
//! acceleration pulses are pulses 0 .. PA-1, and the period after the last of
//! them is RH's) and falls by one per pulse at the end. Acceleration and
//! deceleration are mirror images, a move of 2 x PA steps just reaches RH and
//! a shorter one is a triangle, as Section 3-3-4 says (notes N16). A
//! deceleration started early (stop command or high-speed limit) from speed
//! `c` at pulse `j0` caps the index at `c - 1 - (j - j0)`. Because the plan
//! is a closed formula, a stretch at one period is emitted in O(1) whatever
//! its length.

use super::config::AccelCurve;
use crate::protocol::{Direction, MoveKind, StopCause, Straps};
use crate::time::{Duration, Instant};
use alloc::sync::Arc;
use alloc::vec::Vec;

/// The periods a move is built from.
#[derive(Debug, Clone)]
pub(crate) enum Profile {
    /// One period for every pulse (constant-speed operations, single step).
    Constant { interval: Duration },
    /// `table[v]` for speed index `v < PA - 1`, `cruise` at `v = PA - 1`.
    Ramped {
        table: Arc<[Duration]>,
        cruise: Duration,
    },
}

/// Builds the acceleration table: the periods between the PA acceleration
/// pulses (PA - 1 of them), from the start-up rate RL towards the high speed
/// rate RH, on the chip's rate grid `(R + 1) x Tclock (+ 7.5 us)`.
pub(crate) fn accel_table(
    curve: AccelCurve,
    straps: &Straps,
    tclock: Duration,
    rl: u8,
    rh: u8,
    pa: u16,
) -> Vec<Duration> {
    let period = |r: u8| straps.pulse_interval(r, tclock);
    let steps = pa.saturating_sub(1).max(1);
    let pa_f = f64::from(steps);
    (0..steps)
        .map(|v| {
            let r = match curve {
                AccelCurve::LinearSpeed => {
                    let sl = 1e9 / period(rl).as_nanos() as f64;
                    let sh = 1e9 / period(rh).as_nanos() as f64;
                    let speed = sl + (sh - sl) * f64::from(v) / pa_f;
                    let target_ns = 1e9 / speed;
                    let off = straps.vsel_offset(tclock).as_nanos() as f64;
                    let r = libm::round((target_ns - off) / tclock.as_nanos() as f64) - 1.0;
                    r.clamp(f64::from(rh), f64::from(rl)) as u8
                }
                AccelCurve::LinearRate => {
                    let drop = libm::round(f64::from(rl - rh) * f64::from(v) / pa_f) as u8;
                    rl - drop
                }
            };
            period(r)
        })
        .collect()
}

/// One move in progress, from the moment its final byte was accepted until
/// its termination is processed.
#[derive(Debug, Clone)]
pub(crate) struct Motion {
    pub id: u64,
    pub kind: MoveKind,
    pub dir: Direction,
    pub pout: bool,
    pub interrupt: bool,
    /// When the final byte was written, as seen by the chip.
    pub base: Instant,
    /// Steps requested (N).
    pub total: u32,
    /// Pulses output so far.
    pub emitted: u32,
    /// Pulses this move will output as now planned (`<= total`).
    pub end: u32,
    /// Time of pulse number `emitted`, when `emitted < end`; `None` for a
    /// move that never pulses (no base clock fitted).
    pub next_pulse: Option<Instant>,
    pub last_pulse: Option<Instant>,
    pub profile: Profile,
    /// `(j0, c)`: deceleration from speed index `c` starting at pulse `j0`.
    decel: Option<(u32, u32)>,
    /// A deceleration has been requested and is waiting for its latency.
    pub decel_requested: bool,
    /// Pulse output was cut off (immediate stop, limit, alarm, origin).
    pub halted: bool,
    /// Why the move ended, for finish status bits 6-3.
    pub cause: StopCause,
}

impl Motion {
    #[allow(clippy::too_many_arguments)] // one call site, every field named there
    pub fn new(
        id: u64,
        kind: MoveKind,
        dir: Direction,
        pout: bool,
        interrupt: bool,
        base: Instant,
        total: u32,
        first_pulse: Option<Instant>,
        profile: Profile,
    ) -> Self {
        Motion {
            id,
            kind,
            dir,
            pout,
            interrupt,
            base,
            total,
            emitted: 0,
            end: total,
            next_pulse: first_pulse,
            last_pulse: None,
            profile,
            decel: None,
            decel_requested: false,
            halted: false,
            cause: StopCause::Completed,
        }
    }

    fn cruise_index(&self) -> u32 {
        match &self.profile {
            Profile::Constant { .. } => 0,
            Profile::Ramped { table, .. } => table.len() as u32,
        }
    }

    /// Speed index for the period after pulse `j`.
    fn speed(&self, j: u32) -> u32 {
        let pa = i64::from(self.cruise_index());
        let j = i64::from(j);
        let mut v = j.min(i64::from(self.total) - 2 - j).min(pa);
        if let Some((j0, c)) = self.decel {
            let (j0, c) = (i64::from(j0), i64::from(c));
            if j >= j0 {
                v = v.min(c - 1 - (j - j0));
            }
        }
        v.max(0) as u32
    }

    /// The period between pulse `j` and pulse `j + 1`.
    pub fn interval_after(&self, j: u32) -> Duration {
        match &self.profile {
            Profile::Constant { interval } => *interval,
            Profile::Ramped { table, cruise } => {
                let v = self.speed(j) as usize;
                table.get(v).copied().unwrap_or(*cruise)
            }
        }
    }

    /// Whether more pulses are to come.
    pub fn pulses_left(&self) -> bool {
        !self.halted && self.emitted < self.end
    }

    /// The period being timed now (between the last pulse and the next).
    pub fn current_interval(&self) -> Option<Duration> {
        (self.emitted > 0 && self.pulses_left()).then(|| self.interval_after(self.emitted - 1))
    }

    /// The next `(period, count)`: `count` pulses starting with the next one,
    /// each `period` after the one before. `count` is 1 on a ramp.
    pub fn constant_stretch(&self) -> (Duration, u32) {
        let j = self.emitted;
        let left = self.end - j;
        match &self.profile {
            Profile::Constant { interval } => (*interval, left),
            Profile::Ramped { cruise, .. } => {
                let pa = self.cruise_index();
                if left > 1 && self.speed(j) == pa {
                    // Last pulse index whose following period is still cruise.
                    let mut c_end = i64::from(self.total) - 2 - i64::from(pa);
                    if let Some((j0, _)) = self.decel {
                        c_end = c_end.min(i64::from(j0) - 1);
                    }
                    let run = (c_end + 2 - i64::from(j)).clamp(1, i64::from(left));
                    (*cruise, run as u32)
                } else {
                    (self.interval_after(j), 1)
                }
            }
        }
    }

    fn ramped(&self) -> bool {
        matches!(self.profile, Profile::Ramped { .. })
    }

    /// Whether the speed is falling at the next pulse (the normal
    /// deceleration at the end of the move, or an early one).
    pub fn decelerating(&self) -> bool {
        if !self.ramped() || self.emitted == 0 {
            return false;
        }
        if self.decel.is_some() {
            return true;
        }
        let j = self.emitted;
        j + 1 >= self.end || self.speed(j) < self.speed(j - 1)
    }

    /// Whether the move runs at its high speed (speed index PA).
    pub fn at_high_speed(&self) -> bool {
        self.ramped()
            && self.emitted > 0
            && !self.decelerating()
            && self.speed(self.emitted - 1) == self.cruise_index()
    }

    /// Starts a deceleration from the present speed (Section 3-3-2: at high
    /// speed the pulse being timed and PA - 1 more, PA pulses of
    /// deceleration). Returns whether the move got shorter than planned.
    pub fn begin_decel(&mut self) -> bool {
        let j1 = self.emitted;
        let c = if j1 == 0 { 0 } else { self.speed(j1 - 1) };
        let new_end = self.end.min(j1.saturating_add(c).saturating_add(1));
        self.decel = Some((j1, c));
        let shorter = new_end < self.end;
        self.end = new_end;
        shorter
    }

    /// Steps not output, as the remaining-pulses register holds them before
    /// the read subtracts one.
    pub fn remaining(&self) -> u32 {
        self.total - self.emitted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramped(total: u32, pa: usize) -> Motion {
        let table: Vec<Duration> = (0..pa)
            .map(|v| Duration::from_micros(200 - v as u64))
            .collect();
        Motion::new(
            1,
            MoveKind::AccelDecel,
            Direction::Cw,
            false,
            true,
            Instant::ZERO,
            total,
            Some(Instant::ZERO),
            Profile::Ramped {
                table: table.into(),
                cruise: Duration::from_micros(42),
            },
        )
    }

    fn intervals(m: &Motion) -> Vec<u64> {
        (0..m.end - 1)
            .map(|j| m.interval_after(j).as_nanos() / 1_000)
            .collect()
    }

    #[test]
    fn trapezoid_is_symmetric() {
        let m = ramped(8, 2);
        assert_eq!(intervals(&m), vec![200, 199, 42, 42, 42, 199, 200]);
    }

    #[test]
    fn short_move_is_a_triangle() {
        let m = ramped(5, 3);
        assert_eq!(intervals(&m), vec![200, 199, 199, 200]);
        let m = ramped(6, 3);
        assert_eq!(intervals(&m), vec![200, 199, 198, 199, 200]);
    }

    #[test]
    fn cruise_is_one_stretch() {
        let mut m = ramped(1_000, 4);
        m.emitted = 4;
        // Pulses 4..=995 are 42 us apart: 992 pulses.
        assert_eq!(m.constant_stretch(), (Duration::from_micros(42), 992));
        m.emitted = 2;
        assert_eq!(m.constant_stretch(), (Duration::from_micros(198), 1));
    }

    #[test]
    fn early_decel_from_high_speed_takes_pa_more_periods() {
        let mut m = ramped(1_000, 3);
        m.emitted = 10;
        assert!(m.at_high_speed());
        assert!(m.begin_decel());
        assert_eq!(m.end, 14);
        let tail: Vec<u64> = (9..13)
            .map(|j| m.interval_after(j).as_nanos() / 1_000)
            .collect();
        assert_eq!(tail, vec![42, 198, 199, 200]);
        assert!(m.decelerating());
    }

    #[test]
    fn early_decel_during_acceleration_mirrors_what_was_done() {
        let mut m = ramped(1_000, 10);
        m.emitted = 3; // speeds 0,1,2 used so far
        assert!(!m.decelerating());
        m.begin_decel();
        assert_eq!(m.end, 6);
        let all: Vec<u64> = intervals(&m);
        assert_eq!(all, vec![200, 199, 198, 199, 200]);
    }
}
