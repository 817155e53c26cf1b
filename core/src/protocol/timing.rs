//! Table 3-3, "Time required for processing commands", as data.
//!
//! Each row gives the figures the datasheet prints, at the 16 MHz reference
//! system clock. Rows with one figure are held as `typ`; the datasheet's
//! footnote says all figures were measured on an emulator and may be off by
//! 1 % from the real chip ([`DATASHEET_TOLERANCE_PERMILLE`]). Where a column
//! had to be guessed from the flattened table, `docs/datasheet-notes.md` N20
//! says why.

use super::rates::Straps;
use crate::time::Duration;

/// The footnote of Table 3-3: "there may be an error of 1%".
pub const DATASHEET_TOLERANCE_PERMILLE: u64 = 10;

/// One row of Table 3-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TimingRow {
    pub id: TimingId,
    /// The "Command process" column.
    pub process: &'static str,
    /// The "Conditions or tendency" column, shortened.
    pub condition: &'static str,
    pub min: Option<Duration>,
    pub typ: Option<Duration>,
    pub max: Option<Duration>,
}

/// A figure of a row: the min, typ or max column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Figure {
    Min,
    Typ,
    Max,
}

impl TimingRow {
    /// The row's figure `f`, if the datasheet prints one.
    pub fn figure(&self, f: Figure) -> Option<Duration> {
        match f {
            Figure::Min => self.min,
            Figure::Typ => self.typ,
            Figure::Max => self.max,
        }
    }
}

/// Figure `f` of row `id` in `table` ([`TABLE_3_3`], or a copy of it with
/// a row corrected): what the model's defaults take
/// (`crate::emu::ModelConfig::from_table`).
pub fn figure(table: &[TimingRow], id: TimingId, f: Figure) -> Option<Duration> {
    table.iter().find(|r| r.id == id)?.figure(f)
}

/// Names for the rows of Table 3-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TimingId {
    /// Initialization processing time; grows with the acceleration pulses.
    InitProcessing,
    /// From the final initialization data byte to the phase outputs being set.
    InitOutputsSet,
    /// Accel/decel operation: final data byte to first POUT (trapezoid = min,
    /// triangle grows with the steps).
    AccelFirstPout,
    /// Remaining-pulse calculation after a stop by command or limit, during an
    /// accel/decel operation only.
    AbnormalTermination,
    /// Processing of a Decelerating Stop command.
    DecelStopProcessing,
    /// High-speed limit detection during acceleration.
    HighSpeedLimitAccel,
    /// High-speed limit detection during high-speed operation.
    HighSpeedLimitCruise,
    /// AUX* ON.
    AuxOn,
    /// AUX* OFF.
    AuxOff,
    /// Single step, from the command write to the end of all processing.
    SingleStep,
    /// Constant speed operation: final data byte to first POUT.
    ConstantFirstPout,
    /// Normal termination: final POUT to acceptance of the next command.
    NextCommand,
    /// Normal termination: final POUT to interrupt output.
    InterruptOutput,
    /// Normal termination: final POUT to HOLD ON.
    HoldOn,
    /// Excitation OFF (software reset).
    ExcitationOff,
    /// Final command write to BUSY = 1.
    BusyRise,
}

const fn us(n: u64) -> Option<Duration> {
    Some(Duration::from_nanos(n * 1_000))
}

/// Table 3-3, row by row, in the datasheet's order.
pub const TABLE_3_3: &[TimingRow] = &[
    TimingRow {
        id: TimingId::InitProcessing,
        process: "Initialization",
        condition: "the more acceleration/deceleration pulses, the more time",
        min: us(16_500),
        typ: None,
        max: us(162_800),
    },
    TimingRow {
        id: TimingId::InitOutputsSet,
        process: "Initialization",
        condition: "final data written to phase excitation signals determined",
        min: None,
        typ: us(44),
        max: None,
    },
    TimingRow {
        id: TimingId::AccelFirstPout,
        process: "Acceleration/Deceleration Operation",
        condition: "command data written to first P-OUT; min in trapezoidal drive",
        min: us(200),
        typ: None,
        max: us(1_100),
    },
    TimingRow {
        id: TimingId::AbnormalTermination,
        process: "Abnormal termination",
        condition: "stop by command or limit, accel/decel operation only",
        min: None,
        typ: None,
        max: us(200),
    },
    TimingRow {
        id: TimingId::DecelStopProcessing,
        process: "Decelerating Stop command",
        condition: "processing of a Decelerating Stop",
        min: None,
        typ: us(17),
        max: None,
    },
    TimingRow {
        id: TimingId::HighSpeedLimitAccel,
        process: "High-speed limit signal detection",
        condition: "during acceleration",
        min: None,
        typ: us(12),
        max: None,
    },
    TimingRow {
        id: TimingId::HighSpeedLimitCruise,
        process: "High-speed limit signal detection",
        condition: "during high speed operation",
        min: None,
        typ: us(17),
        max: None,
    },
    TimingRow {
        id: TimingId::AuxOn,
        process: "Auxiliary Output Control",
        condition: "AUX* ON",
        min: None,
        typ: us(14),
        max: None,
    },
    TimingRow {
        id: TimingId::AuxOff,
        process: "Auxiliary Output Control",
        condition: "AUX* OFF",
        min: None,
        typ: us(14),
        max: None,
    },
    TimingRow {
        id: TimingId::SingleStep,
        process: "Single Step",
        condition: "command written to completion of all processes",
        min: None,
        typ: us(112),
        max: None,
    },
    TimingRow {
        id: TimingId::ConstantFirstPout,
        process: "Constant Speed Operation",
        condition: "command data written to first P-OUT",
        min: None,
        typ: us(194),
        max: None,
    },
    TimingRow {
        id: TimingId::NextCommand,
        process: "Normal Termination",
        condition: "final P-OUT to acceptance of the next command",
        min: None,
        typ: us(156),
        max: None,
    },
    TimingRow {
        id: TimingId::InterruptOutput,
        process: "Normal Termination",
        condition: "final P-OUT to interrupt output",
        min: None,
        typ: us(26),
        max: None,
    },
    TimingRow {
        id: TimingId::HoldOn,
        process: "Normal Termination",
        condition: "final P-OUT to HOLD ON",
        min: None,
        typ: us(3_400),
        max: None,
    },
    TimingRow {
        id: TimingId::ExcitationOff,
        process: "Excitation OFF",
        condition: "software reset to phase outputs off",
        min: None,
        typ: us(18),
        max: None,
    },
    TimingRow {
        id: TimingId::BusyRise,
        process: "Busy Status",
        condition: "final command write to BUSY = 1",
        min: us(27),
        typ: None,
        max: us(112),
    },
];

impl TimingId {
    pub const ALL: [TimingId; 16] = [
        TimingId::InitProcessing,
        TimingId::InitOutputsSet,
        TimingId::AccelFirstPout,
        TimingId::AbnormalTermination,
        TimingId::DecelStopProcessing,
        TimingId::HighSpeedLimitAccel,
        TimingId::HighSpeedLimitCruise,
        TimingId::AuxOn,
        TimingId::AuxOff,
        TimingId::SingleStep,
        TimingId::ConstantFirstPout,
        TimingId::NextCommand,
        TimingId::InterruptOutput,
        TimingId::HoldOn,
        TimingId::ExcitationOff,
        TimingId::BusyRise,
    ];

    /// The name used in traces and reports.
    pub fn name(self) -> &'static str {
        match self {
            TimingId::InitProcessing => "init_processing",
            TimingId::InitOutputsSet => "init_outputs_set",
            TimingId::AccelFirstPout => "accel_first_pout",
            TimingId::AbnormalTermination => "abnormal_termination",
            TimingId::DecelStopProcessing => "decel_stop_processing",
            TimingId::HighSpeedLimitAccel => "high_speed_limit_accel",
            TimingId::HighSpeedLimitCruise => "high_speed_limit_cruise",
            TimingId::AuxOn => "aux_on",
            TimingId::AuxOff => "aux_off",
            TimingId::SingleStep => "single_step",
            TimingId::ConstantFirstPout => "constant_first_pout",
            TimingId::NextCommand => "next_command",
            TimingId::InterruptOutput => "interrupt_output",
            TimingId::HoldOn => "hold_on",
            TimingId::ExcitationOff => "excitation_off",
            TimingId::BusyRise => "busy_rise",
        }
    }

    pub fn from_name(s: &str) -> Option<TimingId> {
        TimingId::ALL.into_iter().find(|t| t.name() == s)
    }

    /// The row of Table 3-3 with this id.
    pub fn row(self) -> &'static TimingRow {
        // Every id has exactly one row; the unit test below proves it.
        TABLE_3_3
            .iter()
            .find(|r| r.id == self)
            .unwrap_or(&TABLE_3_3[0])
    }
}

impl TimingRow {
    /// The band a measurement must fall in, before the 1 % footnote is
    /// applied: `[min, max]` where both are given, `[0, max]` for a max-only
    /// row, `[min, inf)` for a min-only row, `[typ, typ]` for a typ-only row.
    pub fn band(&self) -> (Duration, Duration) {
        match (self.min, self.typ, self.max) {
            (Some(lo), _, Some(hi)) => (lo, hi),
            (None, _, Some(hi)) => (Duration::ZERO, hi),
            (Some(lo), _, None) => (lo, Duration::MAX),
            (None, Some(t), None) => (t, t),
            (None, None, None) => (Duration::ZERO, Duration::MAX),
        }
    }

    /// [`Self::band`] widened by the datasheet's 1 % on each side, at the
    /// 16 MHz reference clock.
    pub fn band_with_tolerance(&self) -> (Duration, Duration) {
        self.band_for(&Straps::default())
    }

    /// The band on a board with `straps`: the figures scaled from 16 MHz to
    /// its system clock as firmware times are (notes N10), widened by 1 %.
    pub fn band_for(&self, straps: &Straps) -> (Duration, Duration) {
        let (lo, hi) = self.band();
        let lo = straps.firmware_time(lo);
        let hi = if hi == Duration::MAX {
            hi
        } else {
            straps.firmware_time(hi)
        };
        let lo = lo.saturating_sub(lo.scale(DATASHEET_TOLERANCE_PERMILLE, 1_000));
        let hi = if hi == Duration::MAX {
            hi
        } else {
            hi + hi.scale(DATASHEET_TOLERANCE_PERMILLE, 1_000)
        };
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_id_has_exactly_one_row() {
        for row in TABLE_3_3 {
            assert_eq!(TABLE_3_3.iter().filter(|r| r.id == row.id).count(), 1);
            assert_eq!(row.id.row().id, row.id);
        }
        assert_eq!(TABLE_3_3.len(), 16);
        for id in TimingId::ALL {
            assert_eq!(TimingId::from_name(id.name()), Some(id));
        }
    }

    #[test]
    fn s3_6_busy_rise_band_is_27_to_112_us() {
        let (lo, hi) = TimingId::BusyRise.row().band();
        assert_eq!(
            (lo, hi),
            (Duration::from_micros(27), Duration::from_micros(112))
        );
        let (lo, hi) = TimingId::BusyRise.row().band_with_tolerance();
        assert_eq!(lo, Duration::from_nanos(26_730));
        assert_eq!(hi, Duration::from_nanos(113_120));
    }

    #[test]
    fn s3_6_bands_scale_with_the_system_clock() {
        let fast = Straps {
            sysclk_hz: 20_000_000,
            ..Straps::default()
        };
        let (lo, hi) = TimingId::ConstantFirstPout.row().band_for(&fast);
        assert_eq!(
            (lo, hi),
            (Duration::from_nanos(153_648), Duration::from_nanos(156_752))
        );
    }

    #[test]
    fn s3_6_single_figure_rows_are_points() {
        let (lo, hi) = TimingId::ConstantFirstPout.row().band();
        assert_eq!(lo, hi);
        assert_eq!(lo, Duration::from_micros(194));
    }
}
