//! Section 3-4: the internal register read commands.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_4_1_polling_flag_set_at_stop_cleared_by_read(),
        s3_4_1_finish_read_releases_int(),
        s3_4_2_input_status_l1_l2(),
        s3_4_2_input_status_l3_l4(),
        s3_4_2_input_status_alm_cnp(),
        s3_4_5_aux_input_status(),
        s3_4_3_output_status_dir_hold_phases(),
        s3_4_4_remaining_reads_one_less(),
        s3_4_4_remainder_of_one_reads_zero(),
    ]
}

fn ready(d: &mut Driver) -> Outcome {
    d.init_and_wait(Init::four_phase())?;
    Ok(())
}

/// finish status bit 7 is set when a move stops and cleared by reading it
#[scenario(tags("read", "finish-status"))]
fn s3_4_1_polling_flag_set_at_stop_cleared_by_read(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.expect_finish(0x00)?;
    d.run(Move::accel(Cw, 10))?;
    d.expect_finish(0x83)?;
    d.expect_finish(0x03)?;
    d.run(Move::constant(Ccw, 60, 10))?;
    d.expect_finish(0x84)
}

/// INT* stays asserted until the finish status is read
#[scenario(tags("read", "finish-status", "interrupt"))]
fn s3_4_1_finish_read_releases_int(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.run(Move::accel(Cw, 10))?;
    d.expect_pins(Some(true), None, None, None)?;
    d.read_register(Register::InputSignals)?;
    d.expect_pins(Some(true), None, None, None)?;
    d.read_register(Register::FinishStatus)?;
    d.expect_pins(Some(false), None, None, None)
}

/// input status reads L1 and L2 as pin levels (asserted = 0)
#[scenario(tags("read", "input", "limit"))]
fn s3_4_2_input_status_l1_l2(d: &mut Driver) -> Outcome {
    d.expect_input_status(0x3F)?;
    d.set(Input::L1, true)?;
    d.expect_input_status(0x37)?;
    d.set(Input::L2, true)?;
    d.expect_input_status(0x33)?;
    d.set(Input::L1, false)?;
    d.expect_input_status(0x3B)
}

/// input status bits 0 and 1 are the high-speed limits L4 and L3
#[scenario(tags("read", "input", "hs-limit"))]
fn s3_4_2_input_status_l3_l4(d: &mut Driver) -> Outcome {
    d.set(Input::L4, true)?;
    d.expect_input_status(0x3E)?;
    d.set(Input::L3, true)?;
    d.expect_input_status(0x3C)
}

/// input status bits 4 and 5 are ALM and CNP
#[scenario(tags("read", "input", "alarm"))]
fn s3_4_2_input_status_alm_cnp(d: &mut Driver) -> Outcome {
    d.set(Input::Alm, true)?;
    d.expect_input_status(0x2F)?;
    d.set(Input::Cnp, true)?;
    d.expect_input_status(0x0F)?;
    // The auxiliary inputs are not in this register.
    d.set(Input::Auxi0, true)?;
    d.expect_input_status(0x0F)
}

/// AUXI0..3 read in bits 0..3 as pin levels; bits 7-4 read 0
#[scenario(tags("read", "input", "aux"))]
fn s3_4_5_aux_input_status(d: &mut Driver) -> Outcome {
    d.expect_aux_inputs(0x0F)?;
    d.set(Input::Auxi0, true)?;
    d.expect_aux_inputs(0x0E)?;
    d.set(Input::Auxi2, true)?;
    d.expect_aux_inputs(0x0A)?;
    d.set(Input::Auxi3, true)?;
    d.set(Input::Auxi1, true)?;
    d.expect_aux_inputs(0x00)?;
    d.set(Input::L1, true)?;
    d.expect_aux_inputs(0x00)
}

/// output status: direction of the last move, HOLD 3.4 ms after it, phase levels
#[scenario(tags("read", "output", "hold", "phases", "timing"))]
fn s3_4_3_output_status_dir_hold_phases(d: &mut Driver) -> Outcome {
    ready(d)?;
    // Stopped since initialization: HOLD, S1 S2 energized (negative logic).
    d.expect_output_status(0b0011_1100)?;
    d.run(Move::accel(Ccw, 3))?;
    d.expect_output_status(0b1001_1010)?;
    let hold = d.fw(ms(4));
    d.wait(hold)?;
    d.expect_latency(TimingId::HoldOn)?;
    d.expect_output_status(0b1001_1110)
}

/// after a limit stop the remaining pulses read one less than the remainder
#[scenario(tags("read", "remaining", "limit"))]
fn s3_4_4_remaining_reads_one_less(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 50, 300))?;
    d.after_pulses(123)?;
    d.set(Input::L1, true)?;
    d.wait_idle()?;
    d.expect_pulses(123, Cw)?;
    d.expect_finish(0x94)?;
    d.expect_remaining(300 - 123 - 1)
}

/// a true remainder of 1 reads 0; finish status bits 3-6 tell it from a complete move
#[scenario(tags("read", "remaining", "boundary"))]
fn s3_4_4_remainder_of_one_reads_zero(d: &mut Driver) -> Outcome {
    ready(d)?;
    d.start(Move::constant(Cw, 50, 3))?;
    d.after_pulses(2)?;
    d.set(Input::L1, true)?;
    d.wait_idle()?;
    d.expect_pulses(2, Cw)?;
    d.expect_remaining(0)?;
    d.expect_finish(0x94)
}
