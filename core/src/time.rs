//! Virtual time: [`Instant`] and [`Duration`] in whole nanoseconds.
//!
//! Every timestamp in this crate is virtual time measured by the target's own
//! clock (the emulator's event clock, or the bus bridge's capture timer), never
//! the host's wall clock. Both types are plain `u64` nanosecond counts wrapped
//! so that a time and a length of time cannot be mixed up.

use alloc::string::String;
use alloc::string::ToString;
use core::fmt;
use core::ops::{Add, AddAssign, Sub};
use core::str::FromStr;

/// A point in virtual time, in nanoseconds since the target was reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Instant(u64);

/// A length of virtual time, in nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Duration(u64);

impl Instant {
    /// The moment the target came out of reset.
    pub const ZERO: Instant = Instant(0);

    pub const fn from_nanos(ns: u64) -> Self {
        Instant(ns)
    }

    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    /// The time elapsed since `earlier`, or zero if `earlier` is later.
    pub fn saturating_since(self, earlier: Instant) -> Duration {
        Duration(self.0.saturating_sub(earlier.0))
    }

    /// Microseconds as a float, for display and reports only.
    pub fn as_micros_f64(self) -> f64 {
        self.0 as f64 / 1_000.0
    }
}

impl Duration {
    pub const ZERO: Duration = Duration(0);
    pub const MAX: Duration = Duration(u64::MAX);

    pub const fn from_nanos(ns: u64) -> Self {
        Duration(ns)
    }

    pub const fn from_micros(us: u64) -> Self {
        Duration(us * 1_000)
    }

    pub const fn from_millis(ms: u64) -> Self {
        Duration(ms * 1_000_000)
    }

    pub const fn from_secs(s: u64) -> Self {
        Duration(s * 1_000_000_000)
    }

    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    pub fn as_micros_f64(self) -> f64 {
        self.0 as f64 / 1_000.0
    }

    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 / 1e9
    }

    /// `self * n`, saturating at [`Duration::MAX`].
    pub fn saturating_mul(self, n: u64) -> Duration {
        Duration(self.0.saturating_mul(n))
    }

    /// Scales by a ratio `num / den`, rounding to the nearest nanosecond.
    pub fn scale(self, num: u64, den: u64) -> Duration {
        if den == 0 {
            return Duration::MAX;
        }
        // Most products fit in 64 bits, where division is cheap.
        if let Some(half_up) = self.0.checked_mul(num).and_then(|p| p.checked_add(den / 2)) {
            return Duration(half_up / den);
        }
        let wide = (self.0 as u128 * num as u128 + den as u128 / 2) / den as u128;
        Duration(u64::try_from(wide).unwrap_or(u64::MAX))
    }

    pub fn saturating_add(self, other: Duration) -> Duration {
        Duration(self.0.saturating_add(other.0))
    }

    pub fn saturating_sub(self, other: Duration) -> Duration {
        Duration(self.0.saturating_sub(other.0))
    }

    /// How far apart two durations are.
    pub fn abs_diff(self, other: Duration) -> Duration {
        Duration(self.0.abs_diff(other.0))
    }
}

impl Add<Duration> for Instant {
    type Output = Instant;
    fn add(self, d: Duration) -> Instant {
        Instant(self.0.saturating_add(d.0))
    }
}

impl AddAssign<Duration> for Instant {
    fn add_assign(&mut self, d: Duration) {
        *self = *self + d;
    }
}

impl Sub<Duration> for Instant {
    type Output = Instant;
    fn sub(self, d: Duration) -> Instant {
        Instant(self.0.saturating_sub(d.0))
    }
}

impl Add for Duration {
    type Output = Duration;
    fn add(self, d: Duration) -> Duration {
        Duration(self.0.saturating_add(d.0))
    }
}

impl AddAssign for Duration {
    fn add_assign(&mut self, d: Duration) {
        *self = *self + d;
    }
}

/// Writes nanoseconds as microseconds with exactly three decimals, using
/// integer arithmetic so that output is identical on every platform.
fn write_micros(f: &mut fmt::Formatter<'_>, ns: u64) -> fmt::Result {
    write!(f, "{}.{:03}us", ns / 1_000, ns % 1_000)
}

impl fmt::Display for Instant {
    /// `1234.567us`: the console's and the traces' time format.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_micros(f, self.0)
    }
}

impl fmt::Display for Duration {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_micros(f, self.0)
    }
}

/// An upper limit for display: the duration, or `inf` for
/// [`Duration::MAX`] (no limit), as timing bands print their top.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limit(pub Duration);

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == Duration::MAX {
            f.write_str("inf")
        } else {
            self.0.fmt(f)
        }
    }
}

/// Why a duration string did not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParseDurationError {
    /// The text is empty.
    #[error("empty duration")]
    Empty,
    /// The unit is missing or is not one of ns, us, ms, s.
    #[error("duration `{0}` needs a unit: ns, us, ms or s (e.g. 250us, 1.5s)")]
    BadUnit(String),
    /// The number part is not a decimal number.
    #[error("`{0}` is not a number")]
    BadNumber(String),
    /// The value is finer than one nanosecond.
    #[error("duration `{0}` is finer than 1 ns")]
    TooFine(String),
    /// The value does not fit in 64 bits of nanoseconds (about 584 years).
    #[error("duration `{0}` is too long")]
    TooLong(String),
}

impl FromStr for Duration {
    type Err = ParseDurationError;

    /// Parses `800ns`, `250us`, `3ms`, `1.5s` exactly (no floating point).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        if s.is_empty() {
            return Err(ParseDurationError::Empty);
        }
        let split = s
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .ok_or_else(|| ParseDurationError::BadUnit(s.to_string()))?;
        let (num, unit) = s.split_at(split);
        let scale_digits: u32 = match unit {
            "ns" => 0,
            "us" | "µs" => 3,
            "ms" => 6,
            "s" => 9,
            _ => return Err(ParseDurationError::BadUnit(s.to_string())),
        };
        let (int_part, frac_part) = match num.split_once('.') {
            Some((i, f)) => (i, f),
            None => (num, ""),
        };
        if (int_part.is_empty() && frac_part.is_empty())
            || !int_part.chars().all(|c| c.is_ascii_digit())
            || !frac_part.chars().all(|c| c.is_ascii_digit())
        {
            return Err(ParseDurationError::BadNumber(num.to_string()));
        }
        let frac_trimmed = frac_part.trim_end_matches('0');
        if frac_trimmed.len() as u32 > scale_digits {
            return Err(ParseDurationError::TooFine(s.to_string()));
        }
        let too_long = || ParseDurationError::TooLong(s.to_string());
        let int: u64 = if int_part.is_empty() {
            0
        } else {
            int_part.parse().map_err(|_| too_long())?
        };
        let unit_ns = 10u64.pow(scale_digits);
        let mut ns = int.checked_mul(unit_ns).ok_or_else(too_long)?;
        if !frac_trimmed.is_empty() {
            let frac: u64 = frac_trimmed.parse().map_err(|_| too_long())?;
            let frac_ns = frac * 10u64.pow(scale_digits - frac_trimmed.len() as u32);
            ns = ns.checked_add(frac_ns).ok_or_else(too_long)?;
        }
        Ok(Duration(ns))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_limit_shows_inf_for_no_limit() {
        assert_eq!(Limit(Duration::MAX).to_string(), "inf");
        assert_eq!(Limit(Duration::from_micros(17)).to_string(), "17.000us");
    }
    use rstest::rstest;

    #[rstest]
    #[case("800ns", 800)]
    #[case("250us", 250_000)]
    #[case("3ms", 3_000_000)]
    #[case("1.5s", 1_500_000_000)]
    #[case("0.001us", 1)]
    #[case("12.250ms", 12_250_000)]
    #[case(".5ms", 500_000)]
    fn parses_console_durations(#[case] text: &str, #[case] ns: u64) {
        assert_eq!(text.parse::<Duration>(), Ok(Duration::from_nanos(ns)));
    }

    #[rstest]
    #[case("", ParseDurationError::Empty)]
    #[case("250", ParseDurationError::BadUnit("250".into()))]
    #[case("3 hours", ParseDurationError::BadUnit("3 hours".into()))]
    #[case("1.2.3ms", ParseDurationError::BadNumber("1.2.3".into()))]
    #[case("0.5ns", ParseDurationError::TooFine("0.5ns".into()))]
    #[case("99999999999999s", ParseDurationError::TooLong("99999999999999s".into()))]
    fn rejects_bad_durations(#[case] text: &str, #[case] err: ParseDurationError) {
        assert_eq!(text.parse::<Duration>(), Err(err));
    }

    #[test]
    fn displays_microseconds_with_three_decimals() {
        assert_eq!(Instant::from_nanos(42_000).to_string(), "42.000us");
        assert_eq!(Duration::from_nanos(1_234_567).to_string(), "1234.567us");
        assert_eq!(Duration::from_nanos(7).to_string(), "0.007us");
    }

    #[test]
    fn scale_rounds_to_nearest() {
        assert_eq!(
            Duration::from_nanos(10).scale(1, 3),
            Duration::from_nanos(3)
        );
        assert_eq!(
            Duration::from_nanos(20).scale(1, 3),
            Duration::from_nanos(7)
        );
        assert_eq!(Duration::from_nanos(5).scale(1, 0), Duration::MAX);
    }

    #[test]
    fn scale_past_64_bits_rounds_the_same_and_saturates() {
        // The product overflows 64 bits: the wide division, same rounding.
        assert_eq!(
            Duration::from_nanos(u64::MAX / 2).scale(3, 2),
            Duration::from_nanos(13_835_058_055_282_163_711)
        );
        // Only the half added for rounding overflows.
        assert_eq!(
            Duration::from_nanos(u64::MAX).scale(1, 2),
            Duration::from_nanos(1 << 63)
        );
        assert_eq!(Duration::MAX.scale(2, 1), Duration::MAX);
    }
}
