//! Section 3-2-1: every motor type and excitation method steps S1..S5
//! through its sequence, one step per pulse, both ways, in both logics.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_2_1_three_phase_two_phase_excitation(),
        s3_2_1_three_phase_one_two_excitation(),
        s3_2_1_four_phase_two_phase_excitation(),
        s3_2_1_four_phase_one_two_excitation(),
        s3_2_1_five_phase_two_phase_excitation(),
        s3_2_1_five_phase_two_three_excitation(),
        s3_2_1_positive_logic_levels(),
    ]
}

/// Initializes `init`, checks the starting pattern, steps CW through one
/// cycle and one more, then moves CCW 1,002 steps in one move.
fn sequence(d: &mut Driver, init: Init, cycle: &[u8]) -> Outcome {
    d.init_and_wait(init)?;
    d.expect_phases(cycle[0])?;
    let n = cycle.len();
    for k in 1..=n + 1 {
        d.run(Move::single_step(Cw))?;
        d.expect_phases(cycle[k % n])?;
    }
    d.run(Move::accel(Ccw, 1_002))?;
    d.expect_pulses(1_002, Ccw)?;
    let back = (n + 1 + n * 1_002 - 1_002) % n;
    d.expect_phases(cycle[back])
}

/// 3-phase, 2-phase excitation: S1S2, S2S3, S3S1
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_three_phase_two_phase_excitation(d: &mut Driver) -> Outcome {
    sequence(d, Init::new(MotorType::ThreePhase), &[0b11000, 0b01100, 0b10100])
}

/// 3-phase, 1-2 phase excitation: six steps
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_three_phase_one_two_excitation(d: &mut Driver) -> Outcome {
    sequence(
        d,
        Init::new(MotorType::ThreePhase).half_step(),
        &[0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b10100],
    )
}

/// 4-phase, 2-phase excitation: four steps
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_four_phase_two_phase_excitation(d: &mut Driver) -> Outcome {
    sequence(d, Init::four_phase(), &[0b11000, 0b01100, 0b00110, 0b10010])
}

/// 4-phase, 1-2 phase excitation: eight steps
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_four_phase_one_two_excitation(d: &mut Driver) -> Outcome {
    sequence(
        d,
        Init::four_phase().half_step(),
        &[0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b00110, 0b00010, 0b10010],
    )
}

/// 5-phase, 2-phase excitation: five steps
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_five_phase_two_phase_excitation(d: &mut Driver) -> Outcome {
    sequence(
        d,
        Init::new(MotorType::FivePhase),
        &[0b11000, 0b01100, 0b00110, 0b00011, 0b10001],
    )
}

/// 5-phase, 2-3 phase excitation: ten steps
#[scenario(tags("init", "phases", "excitation"))]
fn s3_2_1_five_phase_two_three_excitation(d: &mut Driver) -> Outcome {
    sequence(
        d,
        Init::new(MotorType::FivePhase).half_step(),
        &[
            0b11000, 0b11100, 0b01100, 0b01110, 0b00110, 0b00111, 0b00011, 0b10011, 0b10001,
            0b11001,
        ],
    )
}

/// positive logic drives energized phases high in the output status
#[scenario(tags("init", "phases", "logic", "read"))]
fn s3_2_1_positive_logic_levels(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::new(MotorType::FivePhase).positive_logic())?;
    // S1 S2 energized and high; HOLD on; CW.
    d.expect_output_status(0b1100_0100)?;
    d.run(Move::single_step(Ccw))?;
    // S5 S1 energized: levels 10001; HOLD off right after; CCW.
    d.expect_output_status(0b1000_1010)
}
