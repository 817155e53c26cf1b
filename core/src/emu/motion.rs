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
//! its length: at high speed, and on the ramp, whose periods come in steps
//! of one rate value each ([`Ramp`]), found in closed form as far as a move
//! can reach rather than as a table at each initialization.

use super::config::AccelCurve;
use crate::protocol::{Direction, MoveKind, StopCause, Straps};
use crate::time::{Duration, Instant};
use alloc::sync::Arc;
use alloc::vec::Vec;
use core::cell::Cell;

/// The periods a move is built from.
#[derive(Debug, Clone)]
pub(crate) enum Profile {
    /// One period for every pulse (constant-speed operations, single step).
    Constant { interval: Duration },
    /// `ramp.period(v)` for speed index `v < PA - 1`, `cruise` at
    /// `v = PA - 1`.
    Ramped { ramp: Ramp, cruise: Duration },
}

/// The periods between the PA acceleration pulses (PA - 1 speed indices).
/// The rate grid is coarser than the ramp, so consecutive indices share a
/// period: the ramp is kept as steps, at most one per rate value (so at
/// most 254 for up to 11,219 indices), each found in closed form
/// ([`AccelRamp::end_of`]). They are computed when a move first needs them
/// ([`Ramp::cover`]) and kept for the moves after it: an initialization
/// costs nothing, and a short move only the steps it can reach.
#[derive(Clone)]
pub(crate) struct Ramp {
    /// Where the periods come from (`None`: given outright, in tests).
    accel: Option<AccelRamp>,
    /// `(first index, period)` of each step, first indices rising from 0;
    /// a step runs up to the next one's first index, the last one up to
    /// `covered`.
    steps: Arc<[(u32, Duration)]>,
    /// The step last asked for: a move asks for the step of the same
    /// index, or the next one, a few times a stretch.
    hint: Cell<usize>,
    /// The indices `0..covered` are in `steps`.
    covered: u32,
    /// PA - 1: the speed index of the cruise.
    len: u32,
}

/// The ramp as its definition: the steps computed so far are derived
/// from it, and a ramp reused from an earlier move or chip may have more.
impl core::fmt::Debug for Ramp {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Ramp")
            .field("accel", &self.accel)
            .field("len", &self.len)
            .finish_non_exhaustive()
    }
}

impl Ramp {
    pub(crate) fn new(accel: AccelRamp) -> Ramp {
        Ramp {
            accel: Some(accel),
            steps: Arc::from(Vec::new()),
            hint: Cell::new(0),
            covered: 0,
            len: accel.len(),
        }
    }

    /// Every period given (the motion tests).
    #[cfg(test)]
    fn table(periods: Vec<Duration>) -> Ramp {
        let mut steps: Vec<(u32, Duration)> = Vec::new();
        for (v, d) in periods.iter().enumerate() {
            if steps.last().is_none_or(|s| s.1 != *d) {
                steps.push((v as u32, *d));
            }
        }
        Ramp {
            accel: None,
            steps: steps.into(),
            hint: Cell::new(0),
            covered: periods.len() as u32,
            len: periods.len() as u32,
        }
    }

    /// Whether this is the ramp `accel` describes (with whatever steps it
    /// has computed so far, which are the same).
    pub(crate) fn is_of(&self, accel: &AccelRamp) -> bool {
        self.accel.as_ref() == Some(accel)
    }

    /// Computes the steps holding the indices below `need` not computed
    /// yet: two divisions a step, whatever its length.
    pub(crate) fn cover(&mut self, need: u32) {
        let need = need.min(self.len);
        let Some(a) = self.accel.filter(|_| self.covered < need) else {
            return;
        };
        let mut steps = self.steps.to_vec();
        let mut v = self.covered;
        while v < need {
            let r = a.rate(v);
            // The rate falls as the index rises, so the step ends where the
            // indices at rate `r` or above end.
            let end = a.end_of(r).max(v + 1);
            steps.push((v, a.interval(r)));
            v = end;
        }
        self.covered = v;
        self.steps = steps.into();
    }

    /// The step holding speed index `v`: its first and last index and its
    /// period; `None` at the cruise index and above.
    fn step_of(&self, v: u32) -> Option<(u32, u32, Duration)> {
        if v >= self.len {
            return None;
        }
        if v >= self.covered {
            // Past what a move asked for (never, as moves cover their
            // reach): the index on its own.
            let a = self.accel?;
            return Some((v, v, a.interval(a.rate(v))));
        }
        let steps: &[(u32, Duration)] = &self.steps;
        // Whether step `i` starts at or before `v` (steps[0] starts at 0):
        // `v` is in the last such step.
        let from = |i: usize| steps.get(i).is_some_and(|s| s.0 <= v);
        let near = self.hint.get();
        let i = if from(near) {
            if !from(near + 1) {
                near
            } else if !from(near + 2) {
                near + 1
            } else {
                steps.partition_point(|s| s.0 <= v) - 1
            }
        } else if near > 0 && from(near - 1) {
            near - 1
        } else {
            steps.partition_point(|s| s.0 <= v).checked_sub(1)?
        };
        self.hint.set(i);
        let (first, d) = *steps.get(i)?;
        let end = steps.get(i + 1).map_or(self.covered, |s| s.0);
        Some((first, end - 1, d))
    }

    fn period(&self, v: u32) -> Option<Duration> {
        self.step_of(v).map(|(_, _, d)| d)
    }
}

/// The acceleration from the start-up rate RL towards the high speed rate
/// RH, on the chip's rate grid `(R + 1) x Tclock (+ 7.5 us)`: the rate
/// value after acceleration pulse `v` (of PA - 1) by [`AccelRamp::rate`],
/// and where each rate value's indices end by [`AccelRamp::end_of`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    /// The ramp from `rl` down to `rh` (`rh < rl`, as an initialization
    /// checks) over `pa` acceleration pulses.
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
            rh: rh.min(rl),
            steps: pa.saturating_sub(1).max(1),
            pl: period(rl).as_nanos(),
            ph: period(rh.min(rl)).as_nanos(),
            off: straps.vsel_offset(tclock).as_nanos(),
        }
    }

    fn len(&self) -> u32 {
        u32::from(self.steps)
    }

    fn interval(&self, r: u8) -> Duration {
        self.straps.pulse_interval(r, self.tclock)
    }

    /// The rate value after acceleration pulse `v` (`v < PA - 1`).
    fn rate(&self, v: u32) -> u8 {
        let (rl, rh) = (self.rl, self.rh);
        let k = u128::from(self.steps);
        let v = u128::from(v);
        match self.curve {
            AccelCurve::LinearSpeed => {
                // Speed linear in v from 1/pl to 1/ph over K = PA - 1 steps:
                // the period is pl ph K / (ph K + (pl - ph) v). The rate
                // value R is the one whose period (R + 1) Tclock + off is
                // nearest, computed exactly; a tie (the period exactly
                // between two rate values) goes to the slower one (notes
                // N16, N49: floating point once put such ties either way).
                let (pl, ph) = (u128::from(self.pl), u128::from(self.ph));
                let den = ph * k + (pl - ph) * v;
                let num = (pl * ph * k).saturating_sub(u128::from(self.off) * den);
                let step = den * self.tc();
                let r1 = (2 * num + step) / (2 * step);
                r1.saturating_sub(1).clamp(u128::from(rh), u128::from(rl)) as u8
            }
            AccelCurve::LinearRate => {
                // RL - (RL - RH) v / K, rounded half up.
                let span = u128::from(rl - rh);
                let drop = (2 * span * v + k) / (2 * k);
                rl - drop.min(span) as u8
            }
        }
    }

    /// How many indices have a rate value of `r` or above: where the step
    /// at `r` ends, as the rate never rises with the index. Closed forms of
    /// [`AccelRamp::rate`]'s roundings, checked against it index by index
    /// in the tests.
    fn end_of(&self, r: u8) -> u32 {
        if r <= self.rh {
            return self.len();
        }
        let k = u128::from(self.steps);
        let n = match self.curve {
            AccelCurve::LinearSpeed => {
                // rate >= r  <=>  r1 >= m = r + 1  <=>  2 num >= (2m - 1) step
                // <=>  den <= 2 pl ph K / (2 off + (2m - 1) Tclock)  (num
                // saturating at 0 changes nothing: it fails both sides).
                let (pl, ph) = (u128::from(self.pl), u128::from(self.ph));
                let m = u128::from(r) + 1;
                let most = 2 * pl * ph * k / (2 * u128::from(self.off) + (2 * m - 1) * self.tc());
                match most.checked_sub(ph * k) {
                    // den = ph K + (pl - ph) v
                    Some(room) => room / (pl - ph) + 1,
                    None => 0,
                }
            }
            AccelCurve::LinearRate => {
                // rate >= r  <=>  drop <= rl - r  <=>  2 span v + K < 2 m K
                // with m = rl - r + 1  <=>  v < (2m - 1) K / (2 span).
                let span = u128::from(self.rl - self.rh);
                let m = u128::from(self.rl - r) + 1;
                ((2 * m - 1) * k).div_ceil(2 * span)
            }
        };
        n.min(k) as u32
    }

    fn tc(&self) -> u128 {
        u128::from(self.tclock.as_nanos().max(1))
    }
}

/// The pulses a move puts out next at one period: `count` pulses from
/// the next one on, each `interval` after the one before.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Stretch {
    pub interval: Duration,
    pub count: u32,
    /// On the ramp, not at cruise or a constant rate: each pulse is
    /// recorded as if put out alone.
    pub on_ramp: bool,
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
            Profile::Ramped { ramp, .. } => ramp.len,
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

    /// Counts `n` pulses, the first at `first` and each `interval` after
    /// the one before, as put out, and plans the next one if any remain.
    /// The time of the last.
    pub fn put_out(&mut self, first: Instant, interval: Duration, n: u32) -> Instant {
        let last = first + interval.saturating_mul(u64::from(n.saturating_sub(1)));
        self.emitted += n;
        self.last_pulse = Some(last);
        if self.emitted < self.end {
            self.next_pulse = Some(last + self.interval_after(self.emitted - 1));
        }
        last
    }

    /// Whether more pulses are to come.
    pub fn pulses_left(&self) -> bool {
        !self.halted && self.emitted < self.end
    }

    /// The period being timed now (between the last pulse and the next).
    pub fn current_interval(&self) -> Option<Duration> {
        (self.emitted > 0 && self.pulses_left()).then(|| self.interval_after(self.emitted - 1))
    }

    /// The next pulses at one period: `count` pulses starting with the
    /// next one, each `interval` after the one before, and whether they
    /// are on the ramp.
    pub fn stretch(&self) -> Stretch {
        let j = self.emitted;
        let left = self.end - j;
        match &self.profile {
            Profile::Constant { interval } => Stretch {
                interval: *interval,
                count: left,
                on_ramp: false,
            },
            Profile::Ramped { ramp, cruise } => {
                let pa = self.cruise_index();
                if self.cruising_from(j) {
                    // Last pulse index whose following period is still cruise.
                    let mut c_end = i64::from(self.total) - 2 - i64::from(pa);
                    if let Some((j0, _)) = self.decel {
                        c_end = c_end.min(i64::from(j0) - 1);
                    }
                    let run = (c_end + 2 - i64::from(j)).clamp(1, i64::from(left));
                    Stretch {
                        interval: *cruise,
                        count: run as u32,
                        on_ramp: false,
                    }
                } else {
                    let (interval, count) = self.ramp_stretch(ramp, *cruise, j, left);
                    Stretch {
                        interval,
                        count,
                        on_ramp: true,
                    }
                }
            }
        }
    }

    /// The ramp pulses from `j` on that are one period apart: those whose
    /// speed index stays in the ramp step holding pulse `j`'s. Found in
    /// O(1) from the shape of [`Motion::speed`]: the index rises (by one a
    /// pulse) only where it equals the pulse number, and once it has
    /// stopped rising it never rises again but falls, by at most one a
    /// pulse. So the pulses leave the step upwards only at pulse `hi + 1`,
    /// where the index would be `hi + 1`, and downwards at the first pulse
    /// where one of the falling bounds of the index drops below `lo`.
    fn ramp_stretch(&self, ramp: &Ramp, cruise: Duration, j: u32, left: u32) -> (Duration, u32) {
        let v0 = self.speed(j);
        // The cruise (index PA) is a stretch of its own.
        let Some((lo, hi, d)) = ramp.step_of(v0) else {
            return (cruise, 1);
        };
        let (j, lo) = (i64::from(j), i64::from(lo));
        // The first pulse past `j` whose following period is not `d`.
        let mut exit = j + i64::from(left);
        let up = hi + 1;
        if i64::from(up) > j && self.speed(up) > hi {
            exit = exit.min(i64::from(up));
        }
        if lo > 0 {
            // total - 2 - k < lo, and c - 1 - (k - j0) < lo from j0 on.
            exit = exit.min(i64::from(self.total) - 1 - lo);
            if let Some((j0, c)) = self.decel {
                let j0 = i64::from(j0);
                exit = exit.min(j0 + (i64::from(c) - lo).max(0));
            }
        }
        // Pulse j and one more for each index in the step from j on.
        let count = (exit - j + 1).clamp(1, i64::from(left));
        (d, count as u32)
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
        on_table(total, table)
    }

    /// A CW accel/decel move of `total` pulses on a ramp of `table`'s
    /// periods, cruising at 42 us.
    fn on_table(total: u32, table: Vec<Duration>) -> Motion {
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
        assert_eq!(
            m.stretch(),
            Stretch {
                interval: Duration::from_micros(42),
                count: 992,
                on_ramp: false
            }
        );
        // On the ramp, pulse 2 and the pulse 198 us after it: the period
        // after pulse 3 is 197 us.
        m.emitted = 2;
        assert_eq!(
            m.stretch(),
            Stretch {
                interval: Duration::from_micros(198),
                count: 2,
                on_ramp: true
            }
        );
    }

    /// Ramp periods on the coarse rate grid repeat: the pulses one period
    /// apart are one stretch, on the way up and on the way down, and the
    /// stretches put out the same pulses as one pulse at a time.
    #[test]
    fn equal_ramp_periods_are_one_stretch() {
        let table = [200, 200, 200, 199, 199, 150].map(Duration::from_micros);
        let mut m = on_table(20, table.to_vec());
        // Pulses 0..=3 are 200 us apart; the period after pulse 3 is 199 us.
        assert_eq!(
            m.stretch(),
            Stretch {
                interval: Duration::from_micros(200),
                count: 4,
                on_ramp: true
            }
        );
        // Pulses 16..=19 on the way down: after 16 (index 2) 200 us, the
        // rest too.
        m.emitted = 16;
        assert_eq!(
            m.stretch(),
            Stretch {
                interval: Duration::from_micros(200),
                count: 4,
                on_ramp: true
            }
        );
        let one_by_one = intervals(&m.clone());
        let mut times = Vec::new();
        let mut t = Instant::ZERO;
        m.emitted = 0;
        while m.emitted < m.end {
            let Stretch {
                interval: d,
                count: n,
                ..
            } = m.stretch();
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

    /// The ramp's steps, found in closed form, hold exactly the rate
    /// [`AccelRamp::rate`] gives each index, and each step is as long as
    /// it can be: on both curves, over straps whose clocks and VSEL term
    /// differ, and rates and PA from the smallest to the largest.
    #[test]
    fn ramp_steps_hold_the_rate_of_every_index() {
        use crate::protocol::ClockSource;
        let ext = |hz| Straps {
            ext_clock_hz: Some(hz),
            ..Straps::default()
        };
        let straps = [
            Straps::default(),
            Straps {
                csel_high: false,
                vsel_high: false,
                ..Straps::default()
            },
            Straps {
                sysclk_hz: 40_000_000,
                vsel_high: false,
                ..Straps::default()
            },
            ext(115_200),
        ];
        let rates = [(254, 1), (254, 253), (2, 1), (200, 33), (100, 99), (37, 5)];
        let pas = [1, 2, 3, 7, 100, 1_001, 5_435, 11_220];
        for curve in [AccelCurve::LinearSpeed, AccelCurve::LinearRate] {
            let clocks = straps.iter().flat_map(|s| {
                [ClockSource::Internal, ClockSource::External]
                    .into_iter()
                    .filter_map(move |c| Some((s, s.tclock(c)?)))
            });
            for (s, tclock) in clocks {
                for &(rl, rh) in &rates {
                    for &pa in &pas {
                        let a = AccelRamp::new(curve, s, tclock, rl, rh, pa);
                        let mut ramp = Ramp::new(a);
                        // Covered in two goes, as two moves would.
                        ramp.cover(a.len() / 3);
                        ramp.cover(a.len());
                        for v in 0..a.len() {
                            let (first, last, d) = ramp.step_of(v).expect("a ramp index");
                            let at = |i| a.interval(a.rate(i));
                            let case = (curve, s, tclock, rl, rh, pa, v);
                            assert_eq!(d, at(v), "{case:?}");
                            assert!(first <= v && v <= last, "{case:?}");
                            assert!(first == 0 || at(first - 1) != d, "{case:?}");
                            assert!(last + 1 == a.len() || at(last + 1) != d, "{case:?}");
                        }
                        assert_eq!(ramp.step_of(a.len()), None);
                    }
                }
            }
        }
    }

    proptest::proptest! {
        /// A ramp stretch found in O(1) is the run of pulses one period
        /// apart that walking them pulse by pulse finds: on trapezoids and
        /// triangles, with or without an early deceleration.
        #[test]
        fn ramp_stretches_are_the_pulses_one_period_apart(
            drops in proptest::collection::vec(0u64..3, 1..40),
            total in 1u32..120,
            stop_at in proptest::option::of(0u32..120),
        ) {
            let mut us = 300;
            let table: Vec<Duration> = drops
                .iter()
                .map(|d| {
                    us -= d;
                    Duration::from_micros(us)
                })
                .collect();
            let mut m = on_table(total, table);
            while m.pulses_left() {
                if stop_at == Some(m.emitted) {
                    m.begin_decel();
                    if !m.pulses_left() {
                        break;
                    }
                }
                let Stretch { interval: d, count: n, on_ramp } = m.stretch();
                let j = m.emitted;
                if on_ramp {
                    let mut walked = 1;
                    while j + walked < m.end && m.interval_after(j + walked - 1) == d {
                        walked += 1;
                    }
                    // The stretch ends where the period changes (the
                    // table's steps hold every run of equal periods), or
                    // at the last pulse.
                    proptest::prop_assert_eq!(n, walked, "pulse {}", j);
                }
                // Stop where asked even inside a stretch.
                let n = match stop_at {
                    Some(s) if s > j && s < j + n => s - j,
                    _ => n,
                };
                m.emitted += n;
            }
        }
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
