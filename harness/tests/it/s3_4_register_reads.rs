//! Section 3-4 behaviour the scenarios do not check: the excitation
//! sequence of every motor type read back through output status bits 7-3
//! (the scenarios follow it on the phase pins). The register reads
//! themselves (finish status and its polling flag, INT* release, input,
//! output and auxiliary input status, remaining pulses lower byte first)
//! are proven by the scenarios in `scenarios/src/s3_4_register_reads.rs`.

use ppmc_test_support as common;

use common::*;
use ppmc::protocol::{Direction, MotorType, MoveCommand, MoveKind, Register};
use ppmc::scenario::Init;
use rstest::rstest;

/// Section 3-2-1 excitation sequences, through output status bits 7-3,
/// for every motor type and excitation method, both directions.
#[rstest]
#[case::three_2ph(Init::new(MotorType::ThreePhase), vec![0b11000, 0b01100, 0b10100])]
#[case::three_1_2ph(Init::new(MotorType::ThreePhase).half_step(), vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b10100])]
#[case::four_2ph(Init::new(MotorType::FourPhase), vec![0b11000, 0b01100, 0b00110, 0b10010])]
#[case::four_1_2ph(Init::new(MotorType::FourPhase).half_step(), vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b00110, 0b00010, 0b10010])]
#[case::five_2ph(Init::new(MotorType::FivePhase), vec![0b11000, 0b01100, 0b00110, 0b00011, 0b10001])]
#[case::five_2_3ph(Init::new(MotorType::FivePhase).half_step(), vec![0b11000, 0b11100, 0b01100, 0b01110, 0b00110, 0b00111, 0b00011, 0b10011, 0b10001, 0b11001])]
fn s3_4_3_phase_outputs_step_once_per_pulse(#[case] init: Init, #[case] cycle: Vec<u8>) {
    // Positive logic so that output status levels equal the energized set.
    let mut h = Host::new();
    h.init(init.positive_logic().code(), EXAMPLE_INIT);
    let read_phases = |h: &mut Host| h.read_reg(Register::OutputSignals.code(), 1)[0] >> 3;
    assert_eq!(read_phases(&mut h), cycle[0]);
    let n = cycle.len();
    for k in 1..=n + 1 {
        h.start(
            MoveCommand::new(MoveKind::SingleStep, Direction::Cw, true),
            None,
            None,
        );
        h.run_to_end();
        assert_eq!(read_phases(&mut h), cycle[k % n], "CW step {k}");
    }
    // A multi-pulse move advances by exactly its pulse count.
    h.accel_move(Direction::Ccw, 1_000 + 2);
    let back = (n + 1 + n * 1_000 - 1_002) % n;
    assert_eq!(read_phases(&mut h), cycle[back], "after 1,002 CCW steps");
}
