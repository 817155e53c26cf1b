//! Phase excitation sequences for S1..S5 (Section 3-2-1, notes N15).
//!
//! A pattern is a 5-bit value with S1 in bit 4 and S5 in bit 0, 1 meaning
//! the phase is energized (independent of the output logic level). CW steps
//! forward through the sequence, CCW backward.

use super::command::{Direction, Excitation, MotorType, OutputLogic};
use crate::time::{Duration, Instant};

/// Stop switching's chopping (Sections 3-2-1 (2) and 3-5-1, Diagram 3-5):
/// from `since`, the energized phases are on for `on`, then off for
/// `off`, and again, until the motor moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Chop {
    pub since: Instant,
    pub on: Duration,
    pub off: Duration,
}

impl Chop {
    fn cycle(&self) -> u64 {
        (self.on + self.off).as_nanos().max(1)
    }

    /// Whether the phases are on at `t` (on from `since`).
    pub fn is_on(&self, t: Instant) -> bool {
        t.saturating_since(self.since).as_nanos() % self.cycle() < self.on.as_nanos()
    }

    /// The energized phases at `t` of `pattern` under `chop`, where
    /// stop switching chops them (off in its OFF time).
    pub fn energized(chop: Option<Chop>, pattern: u8, t: Instant) -> u8 {
        match chop {
            Some(c) if !c.is_on(t) => 0,
            _ => pattern,
        }
    }

    /// The first time after `t` at which the phases turn on or off.
    pub fn next_edge(&self, t: Instant) -> Instant {
        let cycle = self.cycle();
        let elapsed = t.saturating_since(self.since).as_nanos();
        let start = elapsed - elapsed % cycle;
        let next = if elapsed % cycle < self.on.as_nanos() {
            start + self.on.as_nanos()
        } else {
            start + cycle
        };
        self.since + Duration::from_nanos(next)
    }
}

/// What sets the levels of S1..S5 beside the step position: the output
/// logic (and since when: an initialization after a software reset may set
/// another), and the ON and OFF times stop switching chops with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhaseOutputs {
    pub logic: OutputLogic,
    pub logic_since: Instant,
    pub on: Duration,
    pub off: Duration,
}

/// The winding configuration frozen by the first initialization.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Winding {
    pub motor: MotorType,
    pub excitation: Excitation,
}

impl Winding {
    /// Number of distinct steps before the sequence repeats.
    pub fn steps_per_cycle(self) -> u32 {
        let n = u32::from(self.motor.phases());
        match self.excitation {
            Excitation::TwoPhase => n,
            Excitation::HalfStep => 2 * n,
        }
    }

    /// Energized phases at step `index` (taken modulo the cycle).
    pub fn pattern(self, index: u32) -> u8 {
        let n = u32::from(self.motor.phases());
        let i = index % self.steps_per_cycle();
        let phases: &[u32] = match (self.excitation, self.motor) {
            // Two adjacent phases: S1S2, S2S3, ...
            (Excitation::TwoPhase, _) => &[i, i + 1],
            // 2-3 phase on a 5-phase motor: S1S2, S1S2S3, S2S3, S2S3S4, ...
            (Excitation::HalfStep, MotorType::FivePhase) => {
                if i % 2 == 0 {
                    &[i / 2, i / 2 + 1]
                } else {
                    &[i / 2, i / 2 + 1, i / 2 + 2]
                }
            }
            // 1-2 phase: S1, S1S2, S2, S2S3, ...
            (Excitation::HalfStep, _) => {
                if i % 2 == 0 {
                    &[i / 2]
                } else {
                    &[i / 2, i / 2 + 1]
                }
            }
        };
        phases
            .iter()
            .fold(0u8, |acc, p| acc | (0b1_0000 >> (p % n)))
    }

    /// Short name used in traces: `3ph-2`, `4ph-12`, `5ph-23`, ...
    pub fn name(self) -> &'static str {
        match (self.motor, self.excitation) {
            (MotorType::ThreePhase, Excitation::TwoPhase) => "3ph-2",
            (MotorType::ThreePhase, Excitation::HalfStep) => "3ph-12",
            (MotorType::FourPhase, Excitation::TwoPhase) => "4ph-2",
            (MotorType::FourPhase, Excitation::HalfStep) => "4ph-12",
            (MotorType::FivePhase, Excitation::TwoPhase) => "5ph-2",
            (MotorType::FivePhase, Excitation::HalfStep) => "5ph-23",
        }
    }

    /// Every motor type and excitation method, in the order of their wire
    /// codes 1..=6 (`docs/bridge-protocol.md` section 7).
    pub const ALL: [Winding; 6] = [
        Winding {
            motor: MotorType::ThreePhase,
            excitation: Excitation::TwoPhase,
        },
        Winding {
            motor: MotorType::ThreePhase,
            excitation: Excitation::HalfStep,
        },
        Winding {
            motor: MotorType::FourPhase,
            excitation: Excitation::TwoPhase,
        },
        Winding {
            motor: MotorType::FourPhase,
            excitation: Excitation::HalfStep,
        },
        Winding {
            motor: MotorType::FivePhase,
            excitation: Excitation::TwoPhase,
        },
        Winding {
            motor: MotorType::FivePhase,
            excitation: Excitation::HalfStep,
        },
    ];

    /// Inverse of [`Winding::name`].
    pub fn from_name(s: &str) -> Option<Winding> {
        Winding::ALL.into_iter().find(|w| w.name() == s)
    }

    /// The step index after `count` steps in `dir` from `index`.
    pub fn advance(self, index: u32, dir: Direction, count: u64) -> u32 {
        let cycle = u64::from(self.steps_per_cycle());
        let k = count % cycle;
        let i = u64::from(index) % cycle;
        let next = match dir {
            Direction::Cw => (i + k) % cycle,
            Direction::Ccw => (i + cycle - k) % cycle,
        };
        next as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use rstest::rstest;

    fn seq(motor: MotorType, excitation: Excitation) -> Vec<u8> {
        let w = Winding { motor, excitation };
        (0..w.steps_per_cycle()).map(|i| w.pattern(i)).collect()
    }

    #[rstest]
    #[case::three_phase_2ph(MotorType::ThreePhase, Excitation::TwoPhase, vec![0b11000, 0b01100, 0b10100])]
    #[case::three_phase_1_2ph(MotorType::ThreePhase, Excitation::HalfStep,
        vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b10100])]
    #[case::four_phase_2ph(MotorType::FourPhase, Excitation::TwoPhase,
        vec![0b11000, 0b01100, 0b00110, 0b10010])]
    #[case::four_phase_1_2ph(MotorType::FourPhase, Excitation::HalfStep,
        vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b00110, 0b00010, 0b10010])]
    #[case::five_phase_2ph(MotorType::FivePhase, Excitation::TwoPhase,
        vec![0b11000, 0b01100, 0b00110, 0b00011, 0b10001])]
    #[case::five_phase_2_3ph(MotorType::FivePhase, Excitation::HalfStep,
        vec![0b11000, 0b11100, 0b01100, 0b01110, 0b00110, 0b00111, 0b00011, 0b10011, 0b10001, 0b11001])]
    fn s3_2_1_excitation_sequences(
        #[case] motor: MotorType,
        #[case] excitation: Excitation,
        #[case] expected: Vec<u8>,
    ) {
        assert_eq!(seq(motor, excitation), expected);
    }

    #[test]
    fn advance_wraps_both_ways() {
        let w = Winding {
            motor: MotorType::FourPhase,
            excitation: Excitation::TwoPhase,
        };
        assert_eq!(w.advance(0, Direction::Cw, 5), 1);
        assert_eq!(w.advance(0, Direction::Ccw, 1), 3);
        assert_eq!(w.advance(2, Direction::Ccw, 16_777_216), 2);
    }
}
