//! Model parameters that a real board may show differently.
//!
//! Every latency is given at the 16 MHz reference system clock, as Table 3-3
//! is, and scaled by the emulator to the board's system clock. The defaults
//! sit on the datasheet figure where it gives one, and inside its band where
//! it gives a range; `docs/datasheet-notes.md` says where each default comes
//! from.

use super::board::WiringFaults;
use super::hooks::ModelFaults;
use crate::protocol::timing::{figure, Figure, TimingId, TimingRow, TABLE_3_3};
use crate::time::Duration;

/// Shape of the acceleration ramp from the start-up rate RL to the high
/// speed rate RH over PA pulses. The datasheet defers the curve to chapter 1,
/// which we do not have (notes N16).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum AccelCurve {
    /// Speed rises linearly with the step number (constant acceleration per
    /// step), each period rounded to the nearest rate value. The default.
    #[default]
    LinearSpeed,
    /// The rate value falls linearly from RL to RH with the step number.
    LinearRate,
}

/// The emulator's timing and behaviour parameters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelConfig {
    /// Host write to the firmware taking the byte (IBF back to 0) when the
    /// firmware is idle. Not in Table 3-3 (notes N11).
    pub byte_pickup: Duration,
    /// Register read command written to OBF = 1 (notes N11).
    pub obf_ready: Duration,
    /// Data register read to OBF = 1 for the next byte of a multi-byte read.
    pub obf_next: Duration,
    /// Final command write to BUSY = 1; Table 3-3 band 27..112 us.
    pub busy_rise: Duration,
    /// Final initialization byte to phase outputs set; Table 3-3: 44 us.
    pub init_outputs: Duration,
    /// Initialization processing time at PA = 4; Table 3-3 min 16.5 ms.
    pub init_time_min: Duration,
    /// Initialization processing time at PA = 11,220; Table 3-3 max 162.8 ms.
    pub init_time_max: Duration,
    /// Accel/decel operation, final byte to first POUT in trapezoidal drive;
    /// Table 3-3 min 0.2 ms.
    pub accel_first_pout: Duration,
    /// Accel/decel operation, final byte to first POUT for the longest
    /// triangle (2 x 11,220 steps); Table 3-3 max 1.1 ms (notes N17).
    pub accel_first_pout_triangle_max: Duration,
    /// Constant speed operations, final byte to first POUT; Table 3-3: 194 us.
    pub constant_first_pout: Duration,
    /// Single step, command write to its POUT (notes N18).
    pub single_step_pout: Duration,
    /// Single step, command write to the end of processing; Table 3-3: 112 us.
    pub single_step_done: Duration,
    /// Decelerating Stop command write to the start of deceleration;
    /// Table 3-3: 17 us.
    pub decel_stop: Duration,
    /// High-speed limit asserted to deceleration, while accelerating;
    /// Table 3-3: 12 us.
    pub hs_limit_accel: Duration,
    /// High-speed limit asserted to deceleration, at high speed;
    /// Table 3-3: 17 us.
    pub hs_limit_cruise: Duration,
    /// Stop command or L1/L2 during an accel/decel-type operation to BUSY = 0
    /// (the remaining-pulse calculation); Table 3-3 max 0.2 ms.
    pub remaining_calc: Duration,
    /// Final POUT to INT* and BUSY = 0; Table 3-3: 26 us.
    pub interrupt_delay: Duration,
    /// Final POUT to the next command being accepted; Table 3-3: 156 us.
    pub next_command: Duration,
    /// Final POUT to HOLD ON; Table 3-3: 3.4 ms.
    pub hold_on: Duration,
    /// AUX ON / AUX OFF command write to the AUX* pin changing;
    /// Table 3-3: 14 us.
    pub aux_switch: Duration,
    /// Auxiliary output data write to AUXO0..3 changing (notes N11).
    pub aux_output: Duration,
    /// Software reset write to the phase outputs off; Table 3-3: 18 us.
    pub excitation_off: Duration,
    /// Default stop-switching ON time (Diagram 3-5: 65 us).
    pub switching_on: Duration,
    /// Default stop-switching OFF time (Diagram 3-5: 108.75 us).
    pub switching_off: Duration,
    /// Shape of the acceleration ramp.
    pub accel_curve: AccelCurve,
    /// Deliberate faults inside the model; none by default.
    pub faults: ModelFaults,
    /// Deliberate faults on the board's data bus, applied around the model
    /// by [`super::Board`]; none by default.
    pub board: WiringFaults,
}

impl Default for ModelConfig {
    /// Every Table 3-3 figure from [`TABLE_3_3`], once
    /// ([`ModelConfig::from_table`]); the rest as `docs/datasheet-notes.md`
    /// says.
    fn default() -> Self {
        Self::from_table(TABLE_3_3).expect("Table 3-3 prints every figure the model takes")
    }
}

impl ModelConfig {
    /// The default model with the Table 3-3 figures of `table`: a row
    /// corrected in [`TABLE_3_3`] moves the model (and the faults, which
    /// scale these) with it; `None` if `table` lacks a figure the model
    /// takes. The latencies Table 3-3 does not print, or prints only as a
    /// band the model picks a point in, are given here, each with its
    /// note.
    pub fn from_table(table: &[TimingRow]) -> Option<ModelConfig> {
        use Figure::{Max, Min, Typ};
        use TimingId::*;
        let t = |id, f| figure(table, id, f);
        let us = Duration::from_micros;
        Some(ModelConfig {
            // Not in Table 3-3, or a point the model picks inside a band it
            // prints (docs/datasheet-notes.md): N11 (byte pickup, OBF), N19
            // (BUSY's rise, inside the BusyRise band), N18 (single step's
            // POUT), N22 (the remaining-pulse calculation, inside the
            // AbnormalTermination bound), N39 (stop switching).
            byte_pickup: us(6),
            obf_ready: us(20),
            obf_next: us(10),
            busy_rise: us(60),
            single_step_pout: us(86),
            remaining_calc: us(180),
            switching_on: us(65),
            switching_off: Duration::from_nanos(108_750),
            init_outputs: t(InitOutputsSet, Typ)?,
            init_time_min: t(InitProcessing, Min)?,
            init_time_max: t(InitProcessing, Max)?,
            accel_first_pout: t(AccelFirstPout, Min)?,
            accel_first_pout_triangle_max: t(AccelFirstPout, Max)?,
            constant_first_pout: t(ConstantFirstPout, Typ)?,
            single_step_done: t(SingleStep, Typ)?,
            decel_stop: t(DecelStopProcessing, Typ)?,
            hs_limit_accel: t(HighSpeedLimitAccel, Typ)?,
            hs_limit_cruise: t(HighSpeedLimitCruise, Typ)?,
            interrupt_delay: t(InterruptOutput, Typ)?,
            next_command: t(NextCommand, Typ)?,
            hold_on: t(HoldOn, Typ)?,
            // AUX ON and OFF print the same figure; AUXO's data takes it
            // too (notes N11).
            aux_switch: t(AuxOn, Typ)?,
            aux_output: t(AuxOn, Typ)?,
            excitation_off: t(ExcitationOff, Typ)?,
            accel_curve: AccelCurve::LinearSpeed,
            faults: ModelFaults::default(),
            board: WiringFaults::default(),
        })
    }
}

impl ModelConfig {
    /// The configuration with every latency passed through `f`: the chip
    /// keeps its latencies in its board's firmware time
    /// ([`crate::protocol::Straps::firmware_time`]), scaled once when it is
    /// made rather than at every use.
    pub fn map_latencies(&self, f: impl Fn(Duration) -> Duration) -> ModelConfig {
        let ModelConfig {
            byte_pickup,
            obf_ready,
            obf_next,
            busy_rise,
            init_outputs,
            init_time_min,
            init_time_max,
            accel_first_pout,
            accel_first_pout_triangle_max,
            constant_first_pout,
            single_step_pout,
            single_step_done,
            decel_stop,
            hs_limit_accel,
            hs_limit_cruise,
            remaining_calc,
            interrupt_delay,
            next_command,
            hold_on,
            aux_switch,
            aux_output,
            excitation_off,
            switching_on,
            switching_off,
            accel_curve,
            faults,
            board,
        } = self.clone();
        ModelConfig {
            byte_pickup: f(byte_pickup),
            obf_ready: f(obf_ready),
            obf_next: f(obf_next),
            busy_rise: f(busy_rise),
            init_outputs: f(init_outputs),
            init_time_min: f(init_time_min),
            init_time_max: f(init_time_max),
            accel_first_pout: f(accel_first_pout),
            accel_first_pout_triangle_max: f(accel_first_pout_triangle_max),
            constant_first_pout: f(constant_first_pout),
            single_step_pout: f(single_step_pout),
            single_step_done: f(single_step_done),
            decel_stop: f(decel_stop),
            hs_limit_accel: f(hs_limit_accel),
            hs_limit_cruise: f(hs_limit_cruise),
            remaining_calc: f(remaining_calc),
            interrupt_delay: f(interrupt_delay),
            next_command: f(next_command),
            hold_on: f(hold_on),
            aux_switch: f(aux_switch),
            aux_output: f(aux_output),
            excitation_off: f(excitation_off),
            switching_on: f(switching_on),
            switching_off: f(switching_off),
            accel_curve,
            faults,
            board,
        }
    }
}

/// A model configuration whose latencies contradict each other.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// `earlier` must be strictly shorter than `later`.
    #[error(
        "model config: {earlier} ({earlier_value}) must be shorter than {later} ({later_value})"
    )]
    Order {
        earlier: &'static str,
        earlier_value: Duration,
        later: &'static str,
        later_value: Duration,
    },
    /// The byte pickup time must be at least 1 ns.
    #[error("model config: byte_pickup must be at least 1 ns")]
    ZeroPickup,
}

impl ModelConfig {
    /// Checks the orderings the model relies on: BUSY rises before the first
    /// pulse, the firmware takes a byte before it acts on it, and so on.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.byte_pickup == Duration::ZERO {
            return Err(ConfigError::ZeroPickup);
        }
        let pairs: [(&'static str, Duration, &'static str, Duration); 9] = [
            ("byte_pickup", self.byte_pickup, "busy_rise", self.busy_rise),
            (
                "busy_rise",
                self.busy_rise,
                "single_step_pout",
                self.single_step_pout,
            ),
            (
                "busy_rise",
                self.busy_rise,
                "constant_first_pout",
                self.constant_first_pout,
            ),
            (
                "busy_rise",
                self.busy_rise,
                "accel_first_pout",
                self.accel_first_pout,
            ),
            (
                "single_step_pout",
                self.single_step_pout,
                "single_step_done",
                self.single_step_done,
            ),
            (
                "interrupt_delay",
                self.interrupt_delay,
                "next_command",
                self.next_command,
            ),
            (
                "init_outputs",
                self.init_outputs,
                "init_time_min",
                self.init_time_min,
            ),
            (
                "accel_first_pout",
                self.accel_first_pout,
                "accel_first_pout_triangle_max",
                self.accel_first_pout_triangle_max + Duration::from_nanos(1),
            ),
            (
                "init_time_min",
                self.init_time_min,
                "init_time_max",
                self.init_time_max + Duration::from_nanos(1),
            ),
        ];
        for (earlier, ev, later, lv) in pairs {
            if ev >= lv {
                return Err(ConfigError::Order {
                    earlier,
                    earlier_value: ev,
                    later,
                    later_value: lv,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::string::ToString;

    #[test]
    fn every_table_3_3_figure_the_model_takes_moves_it_and_no_other() {
        // Issue 29: Table 3-3 written once. Each figure bumped by 1 us in a
        // copy of the table moves the model's defaults, but for the bands
        // the model only places a point in or that only judge a target.
        use crate::protocol::timing::{Figure, TimingId};
        let base = ModelConfig::from_table(TABLE_3_3).expect("every figure");
        assert_eq!(base, ModelConfig::default());
        let mut unused = alloc::vec::Vec::new();
        for (i, row) in TABLE_3_3.iter().enumerate() {
            for f in [Figure::Min, Figure::Typ, Figure::Max] {
                let Some(v) = row.figure(f) else { continue };
                let mut table = TABLE_3_3.to_vec();
                let bumped = Some(v + Duration::from_micros(1));
                match f {
                    Figure::Min => table[i].min = bumped,
                    Figure::Typ => table[i].typ = bumped,
                    Figure::Max => table[i].max = bumped,
                }
                let moved = ModelConfig::from_table(&table).expect("every figure");
                if moved == base {
                    unused.push((row.id, f));
                }
            }
        }
        assert_eq!(
            unused,
            [
                // Judged only: the bound of a stop's BUSY fall (N22), the
                // band BUSY rises in (N19), AUX OFF's figure (AUX ON's).
                (TimingId::AbnormalTermination, Figure::Max),
                (TimingId::AuxOff, Figure::Typ),
                (TimingId::BusyRise, Figure::Min),
                (TimingId::BusyRise, Figure::Max),
            ]
        );
        // A table that lacks a figure the model takes gives no model.
        let mut table = TABLE_3_3.to_vec();
        table.retain(|r| r.id != TimingId::NextCommand);
        assert_eq!(ModelConfig::from_table(&table), None);
    }

    #[test]
    fn default_config_is_valid() {
        assert_eq!(ModelConfig::default().validate(), Ok(()));
    }

    #[test]
    fn contradictory_config_is_rejected_with_names() {
        let cfg = ModelConfig {
            busy_rise: Duration::from_micros(300),
            ..ModelConfig::default()
        };
        let err = cfg.validate().expect_err("busy after first pulse");
        assert!(err.to_string().contains("busy_rise"), "{err}");
        let zero = ModelConfig {
            byte_pickup: Duration::ZERO,
            ..ModelConfig::default()
        };
        assert_eq!(zero.validate(), Err(ConfigError::ZeroPickup));
    }
}
