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
//! its length, and the acceleration periods are computed as pulses need
//! them, not as a table at each initialization.

use super::config::AccelCurve;
use crate::protocol::{Direction, MoveKind, StopCause, Straps};
use crate::time::{Duration, Instant};
use alloc::sync::Arc;
use alloc::vec::Vec;

/// The most ramp pulses one stretch covers: finding a stretch's end costs
/// a step per pulse, so a stretch cut short by the next timer (a host
/// operation, an input) wastes at most this much.
const RAMP_STRETCH_MAX: u32 = 64;

/// The periods a move is built from.
#[derive(Debug, Clone)]
pub(crate) enum Profile {
    /// One period for every pulse (constant-speed operations, single step).
    Constant { interval: Duration },
    /// `ramp.period(v)` for speed index `v < PA - 1`, `cruise` at
    /// `v = PA - 1`.
    Ramped { ramp: Ramp, cruise: Duration },
}

/// The periods between the PA acceleration pulses (PA - 1 of them),
/// computed when a move first needs them ([`Ramp::cover`]) and kept for the
/// moves after it: an initialization costs nothing per acceleration pulse,
/// and a short move only the periods it can reach.
#[derive(Debug, Clone)]
pub(crate) struct Ramp {
    /// Where the periods come from (`None`: given outright, in tests).
    accel: Option<AccelRamp>,
    /// The periods of indices `0..table.len()`.
    table: Arc<[Duration]>,
}

impl Ramp {
    pub(crate) fn new(accel: AccelRamp) -> Ramp {
        Ramp {
            accel: Some(accel),
            table: Arc::from(Vec::new()),
        }
    }

    /// Every period given (the motion tests).
    #[cfg(test)]
    fn table(periods: Vec<Duration>) -> Ramp {
        Ramp {
            accel: None,
            table: periods.into(),
        }
    }

    /// Computes the periods of indices below `need` not computed yet.
    pub(crate) fn cover(&mut self, need: u32) {
        let need = need.min(self.len());
        let have = self.table.len() as u32;
        if let Some(a) = self.accel.filter(|_| have < need) {
            let mut t = self.table.to_vec();
            t.extend((have..need).map(|v| a.period(v)));
            self.table = t.into();
        }
    }

    /// PA - 1: the speed index of the cruise.
    fn len(&self) -> u32 {
        self.accel.map_or(self.table.len() as u32, |a| a.len())
    }

    fn period(&self, v: u32) -> Option<Duration> {
        if v >= self.len() {
            return None;
        }
        match (self.table.get(v as usize), &self.accel) {
            (Some(d), _) => Some(*d),
            (None, Some(a)) => Some(a.period(v)),
            (None, None) => None,
        }
    }
}

/// The acceleration from the start-up rate RL towards the high speed rate
/// RH, on the chip's rate grid `(R + 1) x Tclock (+ 7.5 us)`: the period
/// after acceleration pulse `v` (of PA - 1) by [`AccelRamp::period`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct AccelRamp {
    curve: AccelCurve,
    straps: Straps,
    tclock: Duration,
    rl: u8,
    rh: u8,
    steps: u16,
    /// The start-up and high speed periods and VSEL low's term, in
    /// nanoseconds (the linear-speed curve's constants).
    pl: u64,
    ph: u64,
    off: u64,
}

impl AccelRamp {
    pub(crate) fn new(
        curve: AccelCurve,
        straps: &Straps,
        tclock: Duration,
        rl: u8,
        rh: u8,
        pa: u16,
    ) -> AccelRamp {
        let period = |r: u8| straps.pulse_interval(r, tclock);
        AccelRamp {
            curve,
            straps: *straps,
            tclock,
            rl,
            rh,
            steps: pa.saturating_sub(1).max(1),
            pl: period(rl).as_nanos(),
            ph: period(rh).as_nanos(),
            off: straps.vsel_offset(tclock).as_nanos(),
        }
    }

    fn len(&self) -> u32 {
        u32::from(self.steps)
    }

    /// The period after acceleration pulse `v` (`v < PA - 1`).
    fn period(&self, v: u32) -> Duration {
        let pa_f = f64::from(self.steps);
        let (rl, rh) = (self.rl, self.rh);
        let r = match self.curve {
            AccelCurve::LinearSpeed => {
                // Speed linear in v from 1/pl to 1/ph over K = PA - 1 steps:
                // the period is pl ph K / (ph K + (pl - ph) v). The rate
                // value R is the one whose period (R + 1) Tclock + off is
                // nearest, computed exactly; a tie (the period exactly
                // between two rate values) goes to the slower one (notes
                // N16, N49: floating point once put such ties either way).
                let (pl, ph) = (u128::from(self.pl), u128::from(self.ph));
                let k = u128::from(self.steps);
                let den = ph * k + (pl - ph) * u128::from(v);
                let num = (pl * ph * k).saturating_sub(u128::from(self.off) * den);
                let step = den * u128::from(self.tclock.as_nanos().max(1));
                let r1 = (2 * num + step) / (2 * step);
                let r = r1.saturating_sub(1).clamp(u128::from(rh), u128::from(rl));
                r as u8
            }
            AccelCurve::LinearRate => {
                let drop = libm::round(f64::from(rl - rh) * f64::from(v) / pa_f) as u8;
                rl - drop
            }
        };
        self.straps.pulse_interval(r, self.tclock)
    }
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
            Profile::Ramped { ramp, .. } => ramp.len(),
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
            Profile::Ramped { ramp, cruise } => ramp.period(self.speed(j)).unwrap_or(*cruise),
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
            Profile::Ramped { ramp, cruise } => {
                let pa = self.cruise_index();
                if self.cruising_from(j) {
                    // Last pulse index whose following period is still cruise.
                    let mut c_end = i64::from(self.total) - 2 - i64::from(pa);
                    if let Some((j0, _)) = self.decel {
                        c_end = c_end.min(i64::from(j0) - 1);
                    }
                    let run = (c_end + 2 - i64::from(j)).clamp(1, i64::from(left));
                    (*cruise, run as u32)
                } else {
                    self.ramp_stretch(ramp, *cruise, j, left)
                }
            }
        }
    }

    /// The ramp pulses from `j` on that are one period apart: the period
    /// after a speed index falls as the index grows (the rate grid is
    /// coarser than the ramp), so the indices sharing pulse `j`'s period
    /// are a range, found by galloping out from `j`'s; the pulses follow
    /// while their speed index stays in it, [`RAMP_STRETCH_MAX`] at most.
    fn ramp_stretch(&self, ramp: &Ramp, cruise: Duration, j: u32, left: u32) -> (Duration, u32) {
        let d = self.interval_after(j);
        // Ramp indices only: cruise (index PA) is a stretch of its own.
        let top = self.cruise_index().saturating_sub(1);
        let per = |v: u32| ramp.period(v).unwrap_or(cruise);
        let v0 = self.speed(j);
        if v0 > top {
            return (d, 1);
        }
        // Largest index up from v0 (at most top), smallest down, with d.
        let gallop = |up: bool| {
            let (mut good, mut step) = (0u32, 1u32);
            let room = (if up { top - v0 } else { v0 }).min(RAMP_STRETCH_MAX);
            loop {
                let probe = good.saturating_add(step).min(room);
                let v = if up { v0 + probe } else { v0 - probe };
                if probe == good || per(v) != d {
                    break;
                }
                good = probe;
                step = step.saturating_mul(2);
            }
            // Narrow between good (d) and good + step (not d, or past room).
            let mut bad = good.saturating_add(step).min(room + 1);
            while bad - good > 1 {
                let mid = good + (bad - good) / 2;
                let v = if up { v0 + mid } else { v0 - mid };
                if per(v) == d {
                    good = mid;
                } else {
                    bad = mid;
                }
            }
            good
        };
        let (hi, lo) = (v0 + gallop(true), v0 - gallop(false));
        let most = left.min(RAMP_STRETCH_MAX);
        let mut count = 1;
        while count < most && (lo..=hi).contains(&self.speed(j + count - 1)) {
            count += 1;
        }
        (d, count)
    }

    /// Whether the next stretch is on the ramp (each pulse recorded as if
    /// put out alone), not at cruise or a constant rate.
    pub fn on_ramp(&self) -> bool {
        self.ramped() && !self.cruising_from(self.emitted)
    }

    /// Whether pulse `j` and the one after it are at the high speed (a
    /// cruise stretch starts at `j`).
    fn cruising_from(&self, j: u32) -> bool {
        self.end - j > 1 && self.speed(j) == self.cruise_index()
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
    use alloc::vec::Vec;

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
                ramp: Ramp::table(table),
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
        // On the ramp, pulse 2 and the pulse 198 us after it: the period
        // after pulse 3 is 197 us.
        m.emitted = 2;
        assert_eq!(m.constant_stretch(), (Duration::from_micros(198), 2));
    }

    /// Ramp periods on the coarse rate grid repeat: the pulses one period
    /// apart are one stretch, on the way up and on the way down, and the
    /// stretches put out the same pulses as one pulse at a time.
    #[test]
    fn equal_ramp_periods_are_one_stretch() {
        let table = [200, 200, 200, 199, 199, 150].map(Duration::from_micros);
        let mut m = Motion::new(
            1,
            MoveKind::AccelDecel,
            Direction::Cw,
            false,
            true,
            Instant::ZERO,
            20,
            Some(Instant::ZERO),
            Profile::Ramped {
                ramp: Ramp::table(table.to_vec()),
                cruise: Duration::from_micros(42),
            },
        );
        // Pulses 0..=3 are 200 us apart; the period after pulse 3 is 199 us.
        assert_eq!(m.constant_stretch(), (Duration::from_micros(200), 4));
        // Pulses 16..=19 on the way down: after 16 (index 2) 200 us, the
        // rest too.
        m.emitted = 16;
        assert_eq!(m.constant_stretch(), (Duration::from_micros(200), 4));
        let one_by_one = intervals(&m.clone());
        let mut times = Vec::new();
        let mut t = Instant::ZERO;
        m.emitted = 0;
        while m.emitted < m.end {
            let (d, n) = m.constant_stretch();
            for _ in 0..n {
                times.push(t);
                t += d;
            }
            m.emitted += n;
            t = *times.last().expect("a pulse") + m.interval_after(m.emitted - 1);
        }
        let gaps: Vec<u64> = times
            .windows(2)
            .map(|w| w[1].saturating_since(w[0]).as_nanos() / 1_000)
            .collect();
        assert_eq!(gaps, one_by_one);
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
