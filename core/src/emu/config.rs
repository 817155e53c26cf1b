//! Model parameters that a real board may show differently.
//!
//! Every latency is given at the 16 MHz reference system clock, as Table 3-3
//! is, and scaled by the emulator to the board's system clock. The defaults
//! sit on the datasheet figure where it gives one, and inside its band where
//! it gives a range; `docs/datasheet-notes.md` says where each default comes
//! from.

use super::board::BoardFaults;
use super::hooks::Faults;
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
    pub faults: Faults,
    /// Deliberate faults on the board's data bus, applied around the model
    /// by [`super::Board`]; none by default.
    pub board: BoardFaults,
}

impl Default for ModelConfig {
    fn default() -> Self {
        let us = Duration::from_micros;
        ModelConfig {
            byte_pickup: us(6),
            obf_ready: us(20),
            obf_next: us(10),
            busy_rise: us(60),
            init_outputs: us(44),
            init_time_min: us(16_500),
            init_time_max: us(162_800),
            accel_first_pout: us(200),
            accel_first_pout_triangle_max: us(1_100),
            constant_first_pout: us(194),
            single_step_pout: us(86),
            single_step_done: us(112),
            decel_stop: us(17),
            hs_limit_accel: us(12),
            hs_limit_cruise: us(17),
            remaining_calc: us(180),
            interrupt_delay: us(26),
            next_command: us(156),
            hold_on: us(3_400),
            aux_switch: us(14),
            aux_output: us(14),
            excitation_off: us(18),
            switching_on: us(65),
            switching_off: Duration::from_nanos(108_750),
            accel_curve: AccelCurve::LinearSpeed,
            faults: Faults::default(),
            board: BoardFaults::default(),
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
