//! Little-endian writing and checked reading of message fields, with
//! times converted to and from the bridge timer's ticks.

use super::message::*;
use crate::protocol::{Direction, Input};
use crate::time::{Duration, Instant};
use alloc::string::String;
use alloc::vec::Vec;

/// Converts between nanoseconds and ticks of a timer running at `hz`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timer {
    pub hz: u64,
}

impl Timer {
    /// The simulator's timer: one tick per nanosecond.
    pub const NANOS: Timer = Timer { hz: 1_000_000_000 };

    /// Nanoseconds to ticks, to the nearest tick: so that ticks turned into
    /// nanoseconds ([`Timer::to_nanos`], which truncates) and back are the
    /// same ticks for any timer up to 500 MHz.
    pub fn to_ticks(self, ns: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ns;
        }
        if let Some(n) = ns
            .checked_mul(self.hz)
            .and_then(|n| n.checked_add(NANOS_PER_S / 2))
        {
            return BY_SECOND.div_rem(n).0;
        }
        // ns = a s + b ns: a whole seconds are `a * hz` ticks exactly, and
        // only the part of a second is divided, in 64 bits.
        let (a, b) = (ns / NANOS_PER_S, ns % NANOS_PER_S);
        match b.checked_mul(self.hz) {
            Some(part) => whole_then(a, self.hz, (part + NANOS_PER_S / 2) / NANOS_PER_S),
            None => {
                let t = (u128::from(ns) * u128::from(self.hz) + 500_000_000) / 1_000_000_000;
                u64::try_from(t).unwrap_or(u64::MAX)
            }
        }
    }

    /// Nanoseconds to ticks, rounded up: for a bound, which must not
    /// shrink on the way.
    pub fn to_ticks_up(self, ns: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ns;
        }
        let (a, b) = (ns / NANOS_PER_S, ns % NANOS_PER_S);
        match b.checked_mul(self.hz) {
            Some(part) => whole_then(a, self.hz, part.div_ceil(NANOS_PER_S)),
            None => {
                let t = (u128::from(ns) * u128::from(self.hz)).div_ceil(1_000_000_000);
                u64::try_from(t).unwrap_or(u64::MAX)
            }
        }
    }

    /// Ticks to nanoseconds, rounded up (for a bound).
    pub fn to_nanos_up(self, ticks: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ticks;
        }
        if self.hz == 0 {
            return u64::MAX;
        }
        // ticks = q hz + r: q whole seconds, and the rest (r < hz, so
        // r * 10^9 fits 64 bits for any timer below 18 GHz) divided.
        let (q, r) = (ticks / self.hz, ticks % self.hz);
        match r.checked_mul(NANOS_PER_S) {
            Some(part) => whole_then(q, NANOS_PER_S, part.div_ceil(self.hz)),
            None => {
                let n = (u128::from(ticks) * 1_000_000_000).div_ceil(u128::from(self.hz));
                u64::try_from(n).unwrap_or(u64::MAX)
            }
        }
    }

    /// Whether a tick is a whole number of nanoseconds, so that times
    /// converted to nanoseconds keep their exact spacing.
    pub fn whole_nanos(self) -> bool {
        self.hz != 0 && 1_000_000_000 % self.hz == 0
    }

    /// How far pulses timestamped by this timer may stray from a straight
    /// line when the timer is not locked to the chip: a tick, plus the
    /// nanosecond lost turning ticks into nanoseconds when a tick is not a
    /// whole number of them. What a bridge gives [`crate::protocol::EdgeRuns`].
    pub fn edge_tolerance(self) -> Duration {
        let slack = if self.whole_nanos() { 0 } else { 1 };
        Duration::from_nanos(self.to_nanos_up(1) + slack)
    }

    pub fn to_nanos(self, ticks: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ticks;
        }
        if self.hz == 0 {
            return u64::MAX;
        }
        // One 64-bit division while the product fits (some four minutes
        // at 75 MHz), two past it.
        if let Some(n) = ticks.checked_mul(NANOS_PER_S) {
            return n / self.hz;
        }
        let (q, r) = (ticks / self.hz, ticks % self.hz);
        match r.checked_mul(NANOS_PER_S) {
            Some(part) => whole_then(q, NANOS_PER_S, part / self.hz),
            None => {
                let n = u128::from(ticks) * 1_000_000_000 / u128::from(self.hz);
                u64::try_from(n).unwrap_or(u64::MAX)
            }
        }
    }
}

/// A fixed 64-bit divisor with its reciprocal: `n / d` by a multiply and
/// at most two corrections, exact for every `n` (the estimate
/// `n * floor(2^64 / d) / 2^64` is at most one below the quotient).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Divisor {
    d: u64,
    m: u64,
}

impl Divisor {
    const fn new(d: u64) -> Divisor {
        let m = if d > 1 {
            (u64::MAX as u128 + 1) / d as u128
        } else {
            0
        };
        Divisor { d, m: m as u64 }
    }

    /// `(n / d, n % d)`; `d` must not be 0.
    fn div_rem(self, n: u64) -> (u64, u64) {
        if self.d == 1 {
            return (n, 0);
        }
        let mut q = ((u128::from(n) * u128::from(self.m)) >> 64) as u64;
        let mut r = n - q * self.d;
        if r >= self.d {
            q += 1;
            r -= self.d;
        }
        (q, r)
    }
}

/// A [`Timer`] with its divisions prepared: the same conversions, to the
/// nanosecond and the tick, with no division at run time while the
/// product fits 64 bits (some four minutes of ticks at 75 MHz). A bridge
/// converts several times per op, and a 64-bit division costs a Cortex-M33
/// some 240 cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FastTimer {
    timer: Timer,
    by_hz: Divisor,
}

impl FastTimer {
    pub fn new(timer: Timer) -> FastTimer {
        FastTimer {
            timer,
            by_hz: Divisor::new(timer.hz.max(1)),
        }
    }

    pub fn timer(&self) -> Timer {
        self.timer
    }

    /// [`Timer::to_ticks`] (which divides by a constant, prepared).
    pub fn to_ticks(&self, ns: u64) -> u64 {
        self.timer.to_ticks(ns)
    }

    /// [`Timer::to_nanos`].
    pub fn to_nanos(&self, ticks: u64) -> u64 {
        match ticks.checked_mul(NANOS_PER_S) {
            Some(n) if self.timer.hz != 0 && self.timer.hz != Timer::NANOS.hz => {
                self.by_hz.div_rem(n).0
            }
            _ => self.timer.to_nanos(ticks),
        }
    }

    /// [`Timer::to_nanos_up`].
    pub fn to_nanos_up(&self, ticks: u64) -> u64 {
        match ticks.checked_mul(NANOS_PER_S) {
            Some(n) if self.timer.hz != 0 && self.timer.hz != Timer::NANOS.hz => {
                let (q, r) = self.by_hz.div_rem(n);
                q + u64::from(r != 0)
            }
            _ => self.timer.to_nanos_up(ticks),
        }
    }

    /// [`Timer::edge_tolerance`].
    pub fn edge_tolerance(&self) -> Duration {
        self.timer.edge_tolerance()
    }
}

const NANOS_PER_S: u64 = 1_000_000_000;

/// Division by a second's nanoseconds, prepared.
const BY_SECOND: Divisor = Divisor::new(NANOS_PER_S);

/// `whole * per + part`, or `u64::MAX` where it does not fit: the
/// conversions above split a value into whole seconds and the rest, so
/// that none needs a 128-bit division (a loop of some thousand cycles on
/// a Cortex-M33, where the bridge converts several times per op).
fn whole_then(whole: u64, per: u64, part: u64) -> u64 {
    whole
        .checked_mul(per)
        .and_then(|w| w.checked_add(part))
        .unwrap_or(u64::MAX)
}

#[derive(Debug)]
pub(super) struct W(pub(super) Vec<u8>, pub(super) Timer);

impl W {
    pub(super) fn dur(&mut self, d: Duration) {
        let t = self.1.to_ticks(d.as_nanos());
        self.u64(t);
    }
    pub(super) fn time(&mut self, i: Instant) {
        let t = self.1.to_ticks(i.as_nanos());
        self.u64(t);
    }
    /// A bound, as `u32` ticks rounded up (saturating).
    pub(super) fn bound(&mut self, d: Duration) {
        let t = self.1.to_ticks_up(d.as_nanos());
        self.u32(u32::try_from(t).unwrap_or(u32::MAX));
    }
    pub(super) fn opt_dur(&mut self, d: Option<Duration>) {
        let v = d.map(|d| self.1.to_ticks(d.as_nanos()));
        self.opt(v);
    }
    pub(super) fn opt_time(&mut self, i: Option<Instant>) {
        let v = i.map(|i| self.1.to_ticks(i.as_nanos()));
        self.opt(v);
    }
    pub(super) fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub(super) fn u16(&mut self, v: u16) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(super) fn opt(&mut self, v: Option<u64>) {
        match v {
            Some(x) => {
                self.u8(1);
                self.u64(x);
            }
            None => self.u8(0),
        }
    }
    pub(super) fn str(&mut self, s: &str) {
        let b = s.as_bytes();
        let n = b.len().min(255);
        self.u8(n as u8);
        self.0.extend_from_slice(&b[..n]);
    }
}

pub(super) struct R<'a> {
    pub(super) b: &'a [u8],
    pub(super) at: usize,
    pub(super) timer: Timer,
}

impl<'a> R<'a> {
    pub(super) fn new(b: &'a [u8], timer: Timer) -> Self {
        R { b, at: 0, timer }
    }
    pub(super) fn dur(&mut self) -> Result<Duration, WireError> {
        let t = self.u64()?;
        Ok(Duration::from_nanos(self.timer.to_nanos(t)))
    }
    /// A bound written by [`W::bound`], in nanoseconds rounded up.
    pub(super) fn bound(&mut self) -> Result<Duration, WireError> {
        let t = self.u32()?;
        Ok(Duration::from_nanos(self.timer.to_nanos_up(u64::from(t))))
    }
    pub(super) fn time(&mut self) -> Result<Instant, WireError> {
        let t = self.u64()?;
        Ok(Instant::from_nanos(self.timer.to_nanos(t)))
    }
    pub(super) fn opt_dur(&mut self) -> Result<Option<Duration>, WireError> {
        let t = self.timer;
        Ok(self.opt()?.map(|v| Duration::from_nanos(t.to_nanos(v))))
    }
    pub(super) fn opt_time(&mut self) -> Result<Option<Instant>, WireError> {
        let t = self.timer;
        Ok(self.opt()?.map(|v| Instant::from_nanos(t.to_nanos(v))))
    }
    pub(super) fn take(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        if self.b.len() - self.at < n {
            return Err(WireError::Truncated {
                at: self.at,
                wanted: n - (self.b.len() - self.at),
            });
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    pub(super) fn u8(&mut self) -> Result<u8, WireError> {
        Ok(self.take(1)?[0])
    }
    pub(super) fn u16(&mut self) -> Result<u16, WireError> {
        let s = self.take(2)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    pub(super) fn u32(&mut self) -> Result<u32, WireError> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    pub(super) fn u64(&mut self) -> Result<u64, WireError> {
        let s = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(u64::from_le_bytes(a))
    }
    pub(super) fn bool(&mut self, field: &'static str) -> Result<bool, WireError> {
        let at = self.at;
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(WireError::BadValue {
                at,
                field,
                value: u64::from(v),
            }),
        }
    }
    pub(super) fn opt(&mut self) -> Result<Option<u64>, WireError> {
        Ok(if self.bool("option flag")? {
            Some(self.u64()?)
        } else {
            None
        })
    }
    pub(super) fn str(&mut self) -> Result<String, WireError> {
        let n = usize::from(self.u8()?);
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    pub(super) fn peek(&self) -> Option<u8> {
        self.b.get(self.at).copied()
    }
    /// A sample count: 2..=MAX_SAMPLES.
    pub(super) fn samples(&mut self) -> Result<usize, WireError> {
        let at = self.at;
        let n = usize::from(self.u16()?);
        if !(2..=MAX_SAMPLES).contains(&n) {
            return Err(WireError::BadValue {
                at,
                field: "sample count",
                value: n as u64,
            });
        }
        Ok(n)
    }
    /// A `count` u16 of entries that follow, each at least `min_item`
    /// bytes on the wire: a count that promises more entries than the
    /// bytes left could hold is refused before anything is allocated for
    /// them, so a lying count costs nothing (`Vec::with_capacity(count)`
    /// is safe after it).
    pub(super) fn count(&mut self, min_item: usize) -> Result<usize, WireError> {
        let at = self.at;
        let n = usize::from(self.u16()?);
        if n.saturating_mul(min_item.max(1)) > self.b.len() - self.at {
            return Err(WireError::BadValue {
                at,
                field: "count",
                value: n as u64,
            });
        }
        Ok(n)
    }
    pub(super) fn end(&self) -> Result<(), WireError> {
        match self.b.len() - self.at {
            0 => Ok(()),
            n => Err(WireError::Trailing(n)),
        }
    }
    pub(super) fn dir(&mut self) -> Result<Direction, WireError> {
        Ok(Direction::from_bit(self.bool("direction")?))
    }
    pub(super) fn input(&mut self) -> Result<Input, WireError> {
        let at = self.at;
        let i = self.u8()?;
        Input::ALL
            .get(usize::from(i))
            .copied()
            .ok_or(WireError::BadValue {
                at,
                field: "input",
                value: u64::from(i),
            })
    }
}

#[cfg(test)]
mod divisor_tests {
    use super::Divisor;

    #[test]
    fn a_prepared_divisor_divides_exactly_at_the_edges() {
        for d in [
            2,
            3,
            7,
            40,
            75_000_000,
            1_000_000_000,
            u64::MAX - 1,
            u64::MAX,
        ] {
            let v = Divisor::new(d);
            for n in [
                0,
                1,
                d - 1,
                d,
                d.saturating_add(1),
                d.saturating_mul(2) - 1,
                u64::MAX - 1,
                u64::MAX,
            ] {
                assert_eq!(v.div_rem(n), (n / d, n % d), "{n} / {d}");
            }
        }
        assert_eq!(Divisor::new(1).div_rem(u64::MAX), (u64::MAX, 0));
    }
}
