//! Moves as the plain model runs them (Section 3-3): a move started, every
//! pulse an event of its own with the speed after it found from the one
//! before (the ramp on the rate grid, notes N16; the speed limit, N7),
//! stops, the limit and alarm inputs, and the end of a move (BUSY, INT*,
//! HOLD, the finish status and the remaining pulses).

use super::{div_round, Event, Move, PlainChip, PULSE_BUDGET};
use crate::plain_model::commands::{Cmd, Op};
use crate::protocol::{ClockSource, Direction, Input};
use crate::time::{Duration, Instant};

impl PlainChip {
    // ---- moves (3-3) ----

    pub(super) fn start(&mut self, cmd: Cmd, d: &[u8], base: u64) {
        let Cmd::Move {
            op,
            ccw,
            masked,
            pout,
        } = cmd
        else {
            return;
        };
        let Some(setup) = self.setup else {
            self.error(2);
            return;
        };
        let count = |b: &[u8]| u32::from(b[0]) | u32::from(b[1]) << 8 | u32::from(b[2]) << 16;
        let full = 1u32 << 24;
        let (steps, rate) = match op {
            Op::SingleStep => (1, None),
            Op::AccelDecel => (count(d) + 1, None),
            Op::Constant => (count(&d[1..]) + 1, Some(d[0])),
            Op::ContinuousConstant | Op::OriginSearch => (full, Some(d[0])),
            _ => (full, None),
        };
        let source = if setup.external {
            ClockSource::External
        } else {
            ClockSource::Internal
        };
        let tclock = self.straps.tclock(source).map(|t| t.as_nanos());
        self.move_seq += 1;
        let id = self.move_seq;
        self.mv = Some(Move {
            id,
            op,
            ccw,
            masked,
            pout,
            steps,
            end: steps,
            emitted: 0,
            index: -1,
            constant: rate.zip(tclock).map(|(r, t)| self.period(r, t)),
            tclock,
            decelerating: false,
            cause: 0,
            base,
            last_pulse: None,
            over: false,
        });
        let rise = base + self.fw(self.cfg.busy_rise);
        self.schedule(rise, Event::BusyRise { id });
        self.free_at = self.free_at.max(rise);
        let first = match op {
            Op::SingleStep => self.cfg.single_step_pout,
            Op::Constant | Op::ContinuousConstant | Op::OriginSearch => {
                self.cfg.constant_first_pout
            }
            Op::AccelDecel if steps < 2 * setup.pa => {
                // Triangle: the more steps, the longer (N17).
                let extra = self.cfg.accel_first_pout_triangle_max.as_nanos()
                    - self.cfg.accel_first_pout.as_nanos();
                self.cfg.accel_first_pout
                    + Duration::from_nanos(div_round(u128::from(extra) * u128::from(steps), 22_440))
            }
            _ => self.cfg.accel_first_pout,
        };
        if tclock.is_some() {
            self.schedule(base + self.fw(first), Event::Pulse { id });
        }
    }

    /// The period of rate value `r` (Equations 3-1 to 3-4, notes N8).
    fn period(&self, r: u8, tclock: u64) -> u64 {
        let vsel = if self.straps.vsel_high {
            0
        } else if tclock <= 8_000 {
            7_500
        } else if tclock >= 9_000 {
            0
        } else {
            7_500 * (9_000 - tclock) / 1_000
        };
        (u64::from(r) + 1) * tclock + vsel
    }

    /// The period of speed index `k` of the ramp from RL (index 0) to RH
    /// (index PA - 1), on the rate grid (notes N16). Exact: with K = PA - 1
    /// and the periods pl, ph of RL and RH, the linear-speed curve's
    /// period is pl ph K / (ph K + (pl - ph) k), and the rate value is the
    /// nearest (R + 1) x Tclock (+ VSEL's term) to it, a tie going to the
    /// slower rate.
    fn ramp_period(&self, k: u32, tclock: u64) -> u64 {
        let s = self.setup.expect("a ramped move needs an initialization");
        let big_k = u128::from(s.pa - 1);
        let k = u128::from(k);
        let rate = match self.cfg.accel_curve {
            crate::emu::AccelCurve::LinearSpeed => {
                let pl = u128::from(self.period(s.rl, tclock));
                let ph = u128::from(self.period(s.rh, tclock));
                let vsel = u128::from(self.period(0, tclock) - tclock);
                let den = ph * big_k + (pl - ph) * k;
                // (R + 1) = (T - vsel) / tclock, T = pl ph K / den.
                let num = pl * ph * big_k - vsel * den;
                div_round(num, den * u128::from(tclock)).saturating_sub(1)
            }
            crate::emu::AccelCurve::LinearRate => {
                let drop = div_round(u128::from(s.rl - s.rh) * k, big_k);
                u64::from(s.rl) - drop
            }
        };
        let r = rate.clamp(u64::from(s.rh), u64::from(s.rl)) as u8;
        self.period(r, tclock)
    }

    /// The speed limit (3-2-2): a period shorter than this starves the
    /// firmware (notes N7). Compared exactly: period x limit < 1 s.
    fn over_limit(&self, period: u64, pout: bool) -> bool {
        let max = if pout { 40_000u128 } else { 27_000 };
        let limit_pps = max * u128::from(self.straps.sysclk_hz) / 16_000_000;
        u128::from(period) * limit_pps < 1_000_000_000
    }

    pub(super) fn pulse(&mut self) {
        let now = self.now;
        let setup = self.setup;
        let Some(m) = self.mv.as_mut() else { return };
        if m.emitted == 0 {
            // Inputs already asserted are sampled before the first pulse
            // (notes N27).
            let limit = if m.ccw { Input::L2 } else { Input::L1 };
            let alm = self.inputs & (1 << Input::Alm.index()) != 0;
            let lim = self.inputs & (1 << limit.index()) != 0;
            let cnp = self.inputs & (1 << Input::Cnp.index()) != 0;
            if alm || lim || (m.op == Op::OriginSearch && cnp) {
                let cause = if alm {
                    0x20
                } else if lim {
                    0x10
                } else {
                    0
                };
                self.halt(cause, now);
                return;
            }
            // A high-speed limit already asserted in phase mode: the
            // deceleration starts from standstill and leaves this one
            // pulse (N27).
            let hs = if m.ccw { Input::L4 } else { Input::L3 };
            if m.op.ramped() && !m.pout && !m.decelerating && self.asserted(hs) {
                let m = self.mv.as_mut().expect("checked above");
                m.decelerating = true;
                if m.end > 1 {
                    m.cause = 0x08;
                    m.end = 1;
                }
            }
        }
        let m = self.mv.as_mut().expect("checked above");
        let dir = if m.ccw { Direction::Ccw } else { Direction::Cw };
        self.pulses.push((Instant::from_nanos(now), dir));
        m.emitted += 1;
        m.last_pulse = Some(now);
        let (pout, ccw) = (m.pout, m.ccw);
        if !pout {
            if let Some(w) = self.winding {
                let n = w.steps();
                self.step = if ccw {
                    (self.step + n - 1) % n
                } else {
                    (self.step + 1) % n
                };
            }
        }
        if self.pulses.len() as u64 >= PULSE_BUDGET {
            self.exhausted = true;
        }
        let m = self.mv.as_mut().expect("checked above");
        if m.emitted >= m.end || self.exhausted {
            self.finish_move(now);
            return;
        }
        let tclock = m.tclock.expect("a pulse needs a base clock");
        let period = match m.constant {
            Some(p) => p,
            None => {
                let pa = setup.map_or(4, |s| s.pa);
                // Accelerate while there is room to stop, never past RH.
                let room = i64::from(m.end - m.emitted) - 1;
                m.index = (m.index + 1).min(i64::from(pa) - 1).min(room);
                let k = m.index.max(0) as u32;
                // In POUT mode L3/L4 are not checked while accelerating;
                // one still asserted at high speed acts then (N26).
                let hs = if m.ccw { Input::L4 } else { Input::L3 };
                if m.pout
                    && !m.decelerating
                    && i64::from(k) == i64::from(pa) - 1
                    && self.inputs & (1 << hs.index()) != 0
                {
                    m.decelerating = true;
                    let (id, at) = (m.id, now + self.fw(self.cfg.hs_limit_cruise));
                    self.schedule(at, Event::Decelerate { id, limit: true });
                }
                self.ramp_period(k, tclock)
            }
        };
        let m = self.mv.as_ref().expect("checked above");
        let (id, pout) = (m.id, m.pout);
        // Starved while the period being timed is over the speed limit,
        // served again from the first pulse after which it is not (N7).
        self.starved = self.over_limit(period, pout);
        self.schedule(now + period, Event::Pulse { id });
    }

    /// The last pulse is out: a normal end, or the end of a deceleration
    /// (notes N22). A single step ends when its processing does (N18).
    fn finish_move(&mut self, last_pulse: u64) {
        let m = self.mv.as_ref().expect("a move to finish");
        let (fall, free) = if m.op == Op::SingleStep {
            let done = m.base + self.fw(self.cfg.single_step_done);
            (done, done)
        } else {
            (
                last_pulse + self.fw(self.cfg.interrupt_delay),
                last_pulse + self.fw(self.cfg.next_command),
            )
        };
        // From the final POUT the firmware is busy until it accepts the
        // next command (Table 3-3, N12).
        self.free_at = self.free_at.max(free);
        self.stop_pulsing(fall);
    }

    /// Pulses stop now: an Immediate Stop, L1/L2, ALM, CNP, or a
    /// Decelerating Stop on a constant-rate move (notes N13, N22).
    /// `trigger` is when the cause arose, from which the remaining-pulse
    /// calculation of an accel/decel-type move is timed.
    fn halt(&mut self, cause: u8, trigger: u64) {
        let Some(m) = self.mv.as_mut().filter(|m| !m.over) else {
            // Past its last pulse: it completes normally (N28).
            return;
        };
        m.cause = cause;
        let fall = if m.op == Op::SingleStep {
            m.base + self.fw(self.cfg.single_step_done)
        } else if m.op.ramped() {
            trigger + self.fw(self.cfg.remaining_calc)
        } else {
            self.now + self.fw(self.cfg.interrupt_delay)
        };
        self.stop_pulsing(fall.max(self.now));
    }

    fn stop_pulsing(&mut self, fall: u64) {
        let m = self.mv.as_mut().expect("a move to stop");
        m.over = true;
        let id = m.id;
        self.schedule(fall, Event::BusyFall { id });
        // Pulse output is over: the firmware is no longer starved by the
        // speed limit (3-2-1 (1): commands are refused "during pulse
        // output"), and takes a waiting byte when it is free (N7, N49).
        self.starved = false;
        self.retake();
    }

    /// BUSY falls: the finish status, the remaining pulses and INT* are
    /// set, HOLD comes 3.4 ms after the final POUT, and the firmware takes
    /// the next command 156 us after it (Table 3-3; after a stop, the same
    /// 130 us after BUSY falls, notes N49).
    pub(super) fn busy_fall(&mut self) {
        let m = self.mv.take().expect("a move to end");
        self.set_busy(false);
        self.finish = 0x80 | m.cause | m.op.code();
        self.remaining = m.steps - m.emitted;
        if !m.masked {
            self.set_int(true);
        }
        let free = if m.op == Op::SingleStep {
            self.now
        } else {
            let after = self
                .cfg
                .next_command
                .saturating_sub(self.cfg.interrupt_delay);
            self.now + self.fw(after)
        };
        self.free_at = self.free_at.max(free);
        self.hold_epoch += 1;
        let epoch = self.hold_epoch;
        let hold = m.last_pulse.unwrap_or(self.now) + self.fw(self.cfg.hold_on);
        self.schedule(hold, Event::HoldOn { epoch });
        self.retake();
    }

    /// After a move, a starved byte is taken again.
    fn retake(&mut self) {
        if self.inbuf.is_some() {
            let t = self.take_at.unwrap_or(self.now).max(self.free_at);
            self.take_at = Some(t);
        }
    }

    pub(super) fn immediate_stop(&mut self, base: u64) {
        self.halt(0x40, base);
    }

    pub(super) fn decel_stop(&mut self, base: u64) {
        let Some(m) = self.mv.as_ref().filter(|m| !m.over) else {
            return;
        };
        if !m.op.ramped() {
            self.halt(0x40, base);
            return;
        }
        if m.decelerating || self.in_final_deceleration() {
            self.error(7);
            return;
        }
        let id = m.id;
        let m = self.mv.as_mut().expect("checked above");
        m.decelerating = true;
        self.schedule(
            base + self.fw(self.cfg.decel_stop),
            Event::Decelerate { id, limit: false },
        );
    }

    /// Whether the ramp is already running down to the end (3-3-2): the
    /// pulse being timed is the move's last, or the period after it is
    /// slower than the one being timed, so the pulse being timed is the
    /// first of the deceleration's PA pulses at falling speed (notes N24,
    /// N49).
    fn in_final_deceleration(&self) -> bool {
        let Some(m) = self.mv.as_ref() else {
            return false;
        };
        let Some(s) = self.setup else { return false };
        if m.emitted == 0 {
            return false;
        }
        // The room the next pulse will leave, as `pulse` works it out.
        let room_next = i64::from(m.end - m.emitted) - 2;
        let next = (m.index + 1).min(i64::from(s.pa) - 1).min(room_next);
        m.emitted + 1 >= m.end || next < m.index
    }

    pub(super) fn decelerate(&mut self, limit: bool) {
        let Some(m) = self.mv.as_mut() else { return };
        // The pulse being timed is still output; from there the ramp runs
        // down from the speed reached (notes N24).
        let end = if m.emitted == 0 {
            1
        } else {
            m.emitted + (m.index.max(0) as u32) + 1
        };
        // A deceleration that would end the move where it ends anyway
        // changes nothing: all its pulses are output, a normal end (3-4-1).
        if end < m.end {
            m.end = end;
            m.cause = if limit { 0x08 } else { 0x40 };
        }
    }

    pub(super) fn input_asserted(&mut self, input: Input) {
        let now = self.now;
        let Some(m) = self.mv.as_ref().filter(|m| !m.over) else {
            return;
        };
        if m.emitted == 0 {
            // Not yet pulsing: the inputs are sampled as levels before the
            // first pulse; an edge that comes and goes before it is not
            // seen (N27).
            return;
        }
        let same_limit = if m.ccw { Input::L2 } else { Input::L1 };
        let same_hs = if m.ccw { Input::L4 } else { Input::L3 };
        if input == Input::Alm {
            self.halt(0x20, now);
        } else if input == same_limit {
            self.halt(0x10, now);
        } else if input == Input::Cnp && m.op == Op::OriginSearch {
            self.halt(0, now);
        } else if input == same_hs && m.op.ramped() && !m.decelerating {
            if self.in_final_deceleration() {
                return;
            }
            let s = self.setup.expect("a ramped move needs an initialization");
            let accelerating = m.index < i64::from(s.pa) - 1;
            if accelerating && m.pout {
                return;
            }
            let delay = if accelerating {
                self.cfg.hs_limit_accel
            } else {
                self.cfg.hs_limit_cruise
            };
            let id = m.id;
            self.mv.as_mut().expect("checked above").decelerating = true;
            let at = now + self.fw(delay);
            self.schedule(at, Event::Decelerate { id, limit: true });
        }
    }
}
