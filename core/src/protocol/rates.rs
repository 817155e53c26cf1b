//! Board straps and the rate and time equations of Sections 3-2-1, 3-2-2 and
//! 3-5-1 (Equations 3-1 to 3-8).
//!
//! The datasheet writes `10^6` as "610" in the extracted text; the
//! equations here use it as 10^6 pulses per second per microsecond.

use super::command::ClockSource;
use crate::time::Duration;
use alloc::string::{String, ToString};

/// The system clock the datasheet's timing figures were taken at (Diagram
/// 3-5 "16MHz default"); firmware times scale with `16 MHz / SysClk`.
pub const REFERENCE_SYSCLK_HZ: u32 = 16_000_000;

/// Maximum pulse rate in phase-excitation mode at 16 MHz (Section 3-2-2).
pub const MAX_SPEED_EXCITATION_PPS: u32 = 27_000;
/// Maximum pulse rate in POUT mode at 16 MHz (Section 3-2-2).
pub const MAX_SPEED_POUT_PPS: u32 = 40_000;

/// How the chip is strapped on its board: what a real board fixes with
/// resistors and an oscillator, and the emulator takes as options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Straps {
    /// System clock frequency in Hz (16 MHz on the reference design).
    pub sysclk_hz: u32,
    /// CSEL high or open: internal clock = SysClk / 32; low: SysClk / 128.
    pub csel_high: bool,
    /// VSEL high or open: Equations 3-1, 3-2, 3-5, 3-6; low: 3-3, 3-4, 3-7, 3-8.
    pub vsel_high: bool,
    /// Frequency on the CLOCK pin (pin 54) in Hz, if one is fitted.
    pub ext_clock_hz: Option<u32>,
}

impl Default for Straps {
    /// 16 MHz, CSEL and VSEL high: a 500 kHz internal clock, Tclock = 2 us.
    fn default() -> Self {
        Straps {
            sysclk_hz: REFERENCE_SYSCLK_HZ,
            csel_high: true,
            vsel_high: true,
            ext_clock_hz: None,
        }
    }
}

impl core::fmt::Display for Straps {
    /// `SysClk 16 MHz, CSEL high, VSEL high, no external clock`: how a
    /// person names a board's straps.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let level = |high| if high { "high" } else { "low" };
        write!(
            f,
            "SysClk {} MHz, CSEL {}, VSEL {}, ",
            f64::from(self.sysclk_hz) / 1e6,
            level(self.csel_high),
            level(self.vsel_high)
        )?;
        match self.ext_clock_hz {
            Some(hz) => write!(f, "external clock {} kHz", f64::from(hz) / 1e3),
            None => f.write_str("no external clock"),
        }
    }
}

/// Why a set of straps cannot describe a working board.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StrapsError {
    /// The system clock must be between 1 MHz and 40 MHz.
    #[error("system clock {0} Hz is outside 1..=40 MHz")]
    SysClk(u32),
    /// The external clock must be between 1 kHz and the datasheet's 1 MHz
    /// (at 16 MHz; it scales with the system clock).
    #[error("external clock {hz} Hz is outside 1 kHz..={max} Hz")]
    ExtClock { hz: u32, max: u32 },
}

/// The keys of [`Straps::fields`], in order.
pub const STRAP_KEYS: [&str; 4] = ["sysclk_hz", "csel", "vsel", "ext_clock_hz"];

/// Why `key value` fields do not describe straps.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StrapFieldError {
    /// A strap is not given.
    #[error("strap `{0}` is missing")]
    Missing(&'static str),
    /// A strap is given twice.
    #[error("strap `{0}` is given twice")]
    Repeated(&'static str),
    /// A key that is no strap.
    #[error("`{0}` is not a strap (sysclk_hz, csel, vsel, ext_clock_hz)")]
    UnknownKey(String),
    /// A value the strap cannot take (`csel` is `high` or `low`, clocks are
    /// whole hertz, `ext_clock_hz` may be `none`).
    #[error("strap `{key}` cannot be `{value}`")]
    BadValue { key: &'static str, value: String },
}

impl Straps {
    pub fn validate(&self) -> Result<(), StrapsError> {
        if !(1_000_000..=40_000_000).contains(&self.sysclk_hz) {
            return Err(StrapsError::SysClk(self.sysclk_hz));
        }
        if let Some(hz) = self.ext_clock_hz {
            let max = (u64::from(self.sysclk_hz) / 16) as u32;
            if !(1_000..=max).contains(&hz) {
                return Err(StrapsError::ExtClock { hz, max });
            }
        }
        Ok(())
    }

    /// The straps as `key value` fields, in this order: how traces and
    /// reports show them (`sysclk_hz 16000000`, `csel high`, `vsel high`,
    /// `ext_clock_hz none`).
    pub fn fields(&self) -> [(&'static str, String); 4] {
        let level = |high: bool| String::from(if high { "high" } else { "low" });
        [
            (STRAP_KEYS[0], self.sysclk_hz.to_string()),
            (STRAP_KEYS[1], level(self.csel_high)),
            (STRAP_KEYS[2], level(self.vsel_high)),
            (
                STRAP_KEYS[3],
                self.ext_clock_hz
                    .map_or_else(|| String::from("none"), |h| h.to_string()),
            ),
        ]
    }

    /// Straps back from their [`Straps::fields`]: every key once, each with
    /// a value it can take; anything else is refused, never defaulted.
    pub fn from_fields<'a>(
        fields: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<Straps, StrapFieldError> {
        let mut seen = [None::<&str>; 4];
        for (k, v) in fields {
            let i = STRAP_KEYS
                .iter()
                .position(|key| *key == k)
                .ok_or_else(|| StrapFieldError::UnknownKey(k.into()))?;
            if seen[i].replace(v).is_some() {
                return Err(StrapFieldError::Repeated(STRAP_KEYS[i]));
            }
        }
        let get = |i: usize| seen[i].ok_or(StrapFieldError::Missing(STRAP_KEYS[i]));
        let bad = |i: usize, v: &str| StrapFieldError::BadValue {
            key: STRAP_KEYS[i],
            value: v.into(),
        };
        let level = |i: usize| -> Result<bool, StrapFieldError> {
            match get(i)? {
                "high" => Ok(true),
                "low" => Ok(false),
                v => Err(bad(i, v)),
            }
        };
        let sysclk = get(0)?;
        let ext = get(3)?;
        Ok(Straps {
            sysclk_hz: sysclk.parse().map_err(|_| bad(0, sysclk))?,
            csel_high: level(1)?,
            vsel_high: level(2)?,
            ext_clock_hz: match ext {
                "none" => None,
                v => Some(v.parse().map_err(|_| bad(3, v))?),
            },
        })
    }

    /// Base clock period Tclock for a clock source, rounded to 1 ns (see
    /// notes N9). `None` when the external clock is selected but no clock is
    /// fitted: the chip then never produces a pulse.
    pub fn tclock(&self, source: ClockSource) -> Option<Duration> {
        let hz = match source {
            ClockSource::Internal => {
                let div = if self.csel_high { 32 } else { 128 };
                return Some(Duration::from_nanos(
                    (div * 1_000_000_000u64 + u64::from(self.sysclk_hz) / 2)
                        / u64::from(self.sysclk_hz),
                ));
            }
            ClockSource::External => self.ext_clock_hz?,
        };
        Some(Duration::from_nanos(
            (1_000_000_000u64 + u64::from(hz) / 2) / u64::from(hz),
        ))
    }

    /// The constant added to the pulse period when VSEL is low: 7.5 us for
    /// Tclock up to 8 us, 0 from 9 us, linear in between (notes N8).
    pub fn vsel_offset(&self, tclock: Duration) -> Duration {
        if self.vsel_high {
            return Duration::ZERO;
        }
        let t = tclock.as_nanos();
        match t {
            0..=8_000 => Duration::from_nanos(7_500),
            9_000.. => Duration::ZERO,
            _ => Duration::from_nanos(7_500 * (9_000 - t) / 1_000),
        }
    }

    /// Period of one pulse at pulse-rate value `rate`: the reciprocal of
    /// Equations 3-1 to 3-4, `(rate + 1) x Tclock (+ 7.5 us)`.
    pub fn pulse_interval(&self, rate: u8, tclock: Duration) -> Duration {
        tclock.saturating_mul(u64::from(rate) + 1) + self.vsel_offset(tclock)
    }

    /// Speed in pulses per second for a rate value (Equations 3-1 to 3-4).
    pub fn speed_pps(&self, rate: u8, tclock: Duration) -> f64 {
        1e9 / self.pulse_interval(rate, tclock).as_nanos() as f64
    }

    /// The speed limit of Section 3-2-2: `Max speed x SysClk / 16`.
    pub fn speed_limit_pps(&self, pout: bool) -> u64 {
        let max = if pout {
            MAX_SPEED_POUT_PPS
        } else {
            MAX_SPEED_EXCITATION_PPS
        };
        u64::from(max) * u64::from(self.sysclk_hz) / u64::from(REFERENCE_SYSCLK_HZ)
    }

    /// The shortest pulse period that stays within the speed limit. A period
    /// strictly shorter than this is over the limit.
    pub fn min_interval(&self, pout: bool) -> Duration {
        let pps = self.speed_limit_pps(pout).max(1);
        Duration::from_nanos(1_000_000_000u64.div_ceil(pps))
    }

    /// Scales a firmware time given for the 16 MHz reference to this board's
    /// system clock (notes N10).
    pub fn firmware_time(&self, at_16mhz: Duration) -> Duration {
        at_16mhz.scale(u64::from(REFERENCE_SYSCLK_HZ), u64::from(self.sysclk_hz))
    }

    /// A time limit given for the reference board (16 MHz, CSEL high, no
    /// external clock), stretched for this one: by as many times as its
    /// firmware (16 MHz / SysClk) or its slowest pulse clock (Tclock over
    /// the reference 2 us, internal or external) is slower, never
    /// shortened. Timeouts and budgets written for the reference board
    /// hold on every board the straps allow.
    pub fn stretch(&self, at_reference: Duration) -> Duration {
        let reference_tclock = 2_000u64;
        let mut out = at_reference.max(self.firmware_time(at_reference));
        for source in [ClockSource::Internal, ClockSource::External] {
            if let Some(t) = self.tclock(source) {
                out = out.max(at_reference.scale(t.as_nanos(), reference_tclock));
            }
        }
        out
    }

    /// Switching ON time (Equations 3-5 and 3-7).
    pub fn switching_on_time(&self, pon: u8) -> Duration {
        let base = if self.vsel_high { 27_000 } else { 25_000 };
        self.firmware_time(Duration::from_nanos(u64::from(pon) * 3_000 + base))
    }

    /// Switching OFF time (Equations 3-6 and 3-8).
    pub fn switching_off_time(&self, poff: u8) -> Duration {
        let base = if self.vsel_high { 33_000 } else { 28_750 };
        self.firmware_time(Duration::from_nanos(u64::from(poff) * 3_000 + base))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rstest::rstest;

    #[test]
    fn a_reference_time_limit_stretches_for_a_slower_board_and_never_shrinks() {
        let second = Duration::from_secs(1);
        assert_eq!(Straps::default().stretch(second), second);
        let fast = Straps {
            sysclk_hz: 40_000_000,
            ..Straps::default()
        };
        assert_eq!(fast.stretch(second), second);
        // 1 MHz: firmware 16 times slower, Tclock 32 us (16 times).
        let slow = Straps {
            sysclk_hz: 1_000_000,
            ..Straps::default()
        };
        assert_eq!(slow.stretch(second), Duration::from_secs(16));
        // CSEL low at 1 MHz: Tclock 128 us, 64 times the reference.
        let slowest = Straps {
            csel_high: false,
            ..slow
        };
        assert_eq!(slowest.stretch(second), Duration::from_secs(64));
        // A 1 kHz external clock: Tclock 1 ms, 500 times.
        let ext = Straps {
            ext_clock_hz: Some(1_000),
            ..Straps::default()
        };
        assert_eq!(ext.stretch(second), Duration::from_secs(500));
    }

    #[test]
    fn straps_read_as_a_person_names_them() {
        use alloc::format;
        assert_eq!(
            format!("{}", Straps::default()),
            "SysClk 16 MHz, CSEL high, VSEL high, no external clock"
        );
        let s = Straps {
            sysclk_hz: 12_288_000,
            csel_high: false,
            vsel_high: false,
            ext_clock_hz: Some(250_000),
        };
        assert_eq!(
            format!("{s}"),
            "SysClk 12.288 MHz, CSEL low, VSEL low, external clock 250 kHz"
        );
    }

    #[test]
    fn strap_fields_round_trip_and_a_typo_is_refused_not_defaulted() {
        let s = Straps {
            sysclk_hz: 12_288_000,
            csel_high: false,
            vsel_high: true,
            ext_clock_hz: Some(250_000),
        };
        let f = s.fields();
        assert_eq!(
            Straps::from_fields(f.iter().map(|(k, v)| (*k, v.as_str()))),
            Ok(s)
        );
        let with = |k: &'static str, v: &'static str| {
            Straps::default()
                .fields()
                .iter()
                .map(|(key, val)| {
                    if *key == k {
                        (k, v.to_string())
                    } else {
                        (*key, val.clone())
                    }
                })
                .collect::<alloc::vec::Vec<_>>()
        };
        let parse =
            |f: &[(&str, String)]| Straps::from_fields(f.iter().map(|(k, v)| (*k, v.as_str())));
        assert_eq!(
            parse(&with("csel", "hgih")),
            Err(StrapFieldError::BadValue {
                key: "csel",
                value: "hgih".into()
            })
        );
        assert!(parse(&with("sysclk_hz", "16MHz")).is_err());
        assert_eq!(parse(&with("ext_clock_hz", "none")), Ok(Straps::default()));
        assert_eq!(
            Straps::from_fields([
                ("sysclk_hz", "16000000"),
                ("csel", "high"),
                ("vsel", "high")
            ]),
            Err(StrapFieldError::Missing("ext_clock_hz"))
        );
        assert_eq!(
            Straps::from_fields([("sysclk_hz", "1"), ("sysclk_hz", "2")]),
            Err(StrapFieldError::Repeated("sysclk_hz"))
        );
    }

    #[test]
    fn s3_2_1_internal_clock_is_500khz_or_125khz_at_16mhz() {
        let high = Straps::default();
        assert_eq!(
            high.tclock(ClockSource::Internal),
            Some(Duration::from_micros(2))
        );
        let low = Straps {
            csel_high: false,
            ..Straps::default()
        };
        assert_eq!(
            low.tclock(ClockSource::Internal),
            Some(Duration::from_micros(8))
        );
        assert_eq!(high.tclock(ClockSource::External), None);
        let ext = Straps {
            ext_clock_hz: Some(1_000_000),
            ..Straps::default()
        };
        assert_eq!(
            ext.tclock(ClockSource::External),
            Some(Duration::from_micros(1))
        );
    }

    /// Equation 3-1 with RH = 20 at Tclock = 2 us: 10^6 / 42 = 23,809.5 pps.
    #[test]
    fn s3_2_2_equation_3_1_example() {
        let s = Straps::default();
        let t = Duration::from_micros(2);
        assert_eq!(s.pulse_interval(20, t), Duration::from_micros(42));
        assert!((s.speed_pps(20, t) - 23_809.52).abs() < 0.01);
    }

    /// Equations 3-3/3-4: VSEL low adds 7.5 us below Tclock 8 us, 0 above 9 us.
    #[rstest]
    #[case(2_000, 7_500)]
    #[case(8_000, 7_500)]
    #[case(8_500, 3_750)]
    #[case(9_000, 0)]
    #[case(10_000, 0)]
    fn s3_2_2_equation_3_3_offset(#[case] tclock_ns: u64, #[case] offset_ns: u64) {
        let s = Straps {
            vsel_high: false,
            ..Straps::default()
        };
        assert_eq!(
            s.vsel_offset(Duration::from_nanos(tclock_ns)),
            Duration::from_nanos(offset_ns)
        );
    }

    proptest! {
        /// Equations 3-1..3-4 for every rate: speed x period = 1 s, and
        /// speed falls strictly as the rate value grows.
        #[test]
        fn rate_equations_hold_for_all_rates(rate in 0u8..255, vsel: bool, csel: bool) {
            let s = Straps { vsel_high: vsel, csel_high: csel, ..Straps::default() };
            let t = s.tclock(ClockSource::Internal).expect("internal clock");
            let period_us = (f64::from(rate) + 1.0) * t.as_micros_f64()
                + if vsel { 0.0 } else { 7.5 };
            let expected = 1e6 / period_us;
            prop_assert!((s.speed_pps(rate, t) - expected).abs() < 1e-6 * expected);
            prop_assert!(s.speed_pps(rate + 1, t) < s.speed_pps(rate, t));
        }

        /// Equations 3-5..3-8 at 16 MHz.
        #[test]
        fn switching_equations(p: u8, vsel: bool) {
            let s = Straps { vsel_high: vsel, ..Straps::default() };
            let p3 = u64::from(p) * 3_000;
            let (on, off) = if vsel { (27_000, 33_000) } else { (25_000, 28_750) };
            prop_assert_eq!(s.switching_on_time(p), Duration::from_nanos(p3 + on));
            prop_assert_eq!(s.switching_off_time(p), Duration::from_nanos(p3 + off));
        }
    }

    #[test]
    fn s3_2_2_speed_limit_scales_with_sysclk() {
        let s = Straps::default();
        assert_eq!(s.speed_limit_pps(false), 27_000);
        assert_eq!(s.speed_limit_pps(true), 40_000);
        assert_eq!(s.min_interval(true), Duration::from_nanos(25_000));
        let fast = Straps {
            sysclk_hz: 32_000_000,
            ..Straps::default()
        };
        assert_eq!(fast.speed_limit_pps(false), 54_000);
    }

    #[test]
    fn straps_are_validated() {
        assert!(Straps::default().validate().is_ok());
        let bad = Straps {
            sysclk_hz: 100,
            ..Straps::default()
        };
        assert_eq!(bad.validate(), Err(StrapsError::SysClk(100)));
        let bad_ext = Straps {
            ext_clock_hz: Some(2_000_000),
            ..Straps::default()
        };
        assert!(matches!(
            bad_ext.validate(),
            Err(StrapsError::ExtClock { .. })
        ));
    }
}
