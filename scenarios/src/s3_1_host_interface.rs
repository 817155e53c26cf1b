//! Section 3-1: host interface registers, and every error code of Table 3-2.

use ppmc::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        s3_1_1_status_is_idle_after_reset(),
        s3_1_1_ibf_clears_when_the_chip_takes_a_byte(),
        s3_1_1_parameter_count_counts_down(),
        s3_1_1_write_while_ibf_loses_the_earlier_byte(),
        s3_1_2_obf_rises_with_data_and_falls_on_read(),
        s3_1_1_error_flag_stays_until_the_next_command(),
        e0_undefined_command_code(),
        e0_motor_type_code_00(),
        e0_immediate_stop_while_stopped(),
        e0_decel_stop_while_stopped(),
        e1_operation_command_while_busy(),
        e1_register_read_while_busy(),
        e1_initialization_while_busy(),
        e2_move_before_initialization(),
        e2_move_after_software_reset(),
        e3_data_without_a_command(),
        e4_accel_pulses_11221(),
        e5_rh_above_rl(),
        e5_rh_equal_rl(),
        e5_accel_pulses_3(),
        e5_rh_zero_and_rl_255(),
        e6_data_while_busy(),
        e7_decel_stop_during_final_deceleration(),
        e7_second_decel_stop(),
    ]
}

/// the status register reads 0x00 after a hardware reset
#[scenario(tags("host-interface", "status"))]
fn s3_1_1_status_is_idle_after_reset(d: &mut Driver) -> Outcome {
    d.expect_status(0xFF, 0x00)
}

/// IBF = 1 after a write, 0 once taken; the parameter field then counts 4
#[scenario(tags("host-interface", "status"))]
fn s3_1_1_ibf_clears_when_the_chip_takes_a_byte(d: &mut Driver) -> Outcome {
    d.raw_command(Init::four_phase().code())?;
    d.expect_status(0x02, 0x02)?;
    d.expect_flag(Flag::Ibf, false, us(100))?;
    d.expect_status(0xFF, 0x40)
}

/// bits 6-4 count the initialization data bytes still wanted: 4, 3, 2, 1, 0
#[scenario(tags("host-interface", "status", "init"))]
fn s3_1_1_parameter_count_counts_down(d: &mut Driver) -> Outcome {
    let init = Init::four_phase();
    d.command(init.code())?;
    d.expect_params_remaining(4)?;
    for (i, b) in init.data.to_bytes().into_iter().enumerate() {
        d.data(b)?;
        d.expect_params_remaining(3 - i as u8)?;
    }
    d.expect_no_error()
}

/// a command written while IBF = 1 replaces the waiting one
#[scenario(tags("host-interface", "raw"))]
fn s3_1_1_write_while_ibf_loses_the_earlier_byte(d: &mut Driver) -> Outcome {
    d.raw_command(Init::four_phase().code())?;
    d.raw_command(Register::InputSignals.code())?;
    d.expect_params_remaining(0)?;
    d.expect_flag(Flag::Obf, true, ms(1))?;
    let b = d.read_data()?;
    d.check("input status from the read that replaced the initialization", 0x3F, b)
}

/// OBF = 1 once register data is ready, 0 after the read
#[scenario(tags("host-interface", "status", "read"))]
fn s3_1_2_obf_rises_with_data_and_falls_on_read(d: &mut Driver) -> Outcome {
    d.command(Register::AuxInputs.code())?;
    d.expect_status(0x01, 0x00)?;
    d.expect_flag(Flag::Obf, true, ms(1))?;
    d.read_data()?;
    d.expect_status(0x01, 0x00)
}

/// an error stays in the status register until a new command code is taken
#[scenario(tags("host-interface", "error"))]
fn s3_1_1_error_flag_stays_until_the_next_command(d: &mut Driver) -> Outcome {
    d.command(0x87)?;
    d.expect_error(ErrorCode::UndefinedCommand)?;
    d.wait(ms(20))?;
    d.expect_error(ErrorCode::UndefinedCommand)?;
    d.command(Register::InputSignals.code())?;
    d.expect_no_error()
}

/// Table 3-2 error 0: an undefined command code (0x87)
#[scenario(section = "3-1-1", tags("error"))]
fn e0_undefined_command_code(d: &mut Driver) -> Outcome {
    d.command(0x87)?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

/// Table 3-2 error 0: initialization with motor type code 00
#[scenario(section = "3-2", tags("error", "init"))]
fn e0_motor_type_code_00(d: &mut Driver) -> Outcome {
    d.command(0x00)?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

/// Table 3-2 error 0: Immediate Stop while the motor is stopped
#[scenario(section = "3-3-1", tags("error", "stop"))]
fn e0_immediate_stop_while_stopped(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.immediate_stop()?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

/// Table 3-2 error 0: Decelerating Stop while the motor is stopped
#[scenario(section = "3-3-2", tags("error", "stop"))]
fn e0_decel_stop_while_stopped(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

fn long_move(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.start(Move::accel(Cw, 5_000))?;
    Ok(())
}

/// Table 3-2 error 1: an operation command during BUSY
#[scenario(section = "3-1-1", tags("error", "busy"))]
fn e1_operation_command_while_busy(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Move::accel(Cw, 10).code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

/// Table 3-2 error 1: register reads only while the motor is stopped
#[scenario(section = "3-4", tags("error", "busy", "read"))]
fn e1_register_read_while_busy(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Register::FinishStatus.code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

/// Table 3-2 error 1: initialization during BUSY
#[scenario(section = "3-1-1", tags("error", "busy", "init"))]
fn e1_initialization_while_busy(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Init::four_phase().code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

/// Table 3-2 error 2: a move before any initialization
#[scenario(section = "3-1-1", tags("error", "init"))]
fn e2_move_before_initialization(d: &mut Driver) -> Outcome {
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

/// Table 3-2 error 2: software reset cancels the initialization
#[scenario(section = "3-5-4", tags("error", "reset"))]
fn e2_move_after_software_reset(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.run(Move::single_step(Cw))?;
    d.command(0xC0)?;
    d.wait(us(100))?;
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

/// Table 3-2 error 3: a data byte nobody asked for
#[scenario(section = "3-1-1", tags("error", "raw"))]
fn e3_data_without_a_command(d: &mut Driver) -> Outcome {
    d.data(0x12)?;
    d.expect_error(ErrorCode::TooManyParameters)
}

fn init_error(d: &mut Driver, init: Init, code: ErrorCode) -> Outcome {
    d.init(init)?;
    d.expect_error(code)?;
    // The rejected initialization leaves the chip uninitialized.
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

/// Table 3-2 error 4: PA = 11,221 is over the limit
#[scenario(section = "3-2-2", tags("error", "init", "boundary"))]
fn e4_accel_pulses_11221(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().accel_pulses(11_221), ErrorCode::AccelPulsesTooMany)
}

/// Table 3-2 error 5: RH > RL
#[scenario(section = "3-2-2", tags("error", "init"))]
fn e5_rh_above_rl(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(20, 100), ErrorCode::BadRateData)
}

/// Table 3-2 error 5: RH = RL breaks 255 > RL > RH > 0
#[scenario(section = "3-2-2", tags("error", "init", "boundary"))]
fn e5_rh_equal_rl(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(50, 50), ErrorCode::BadRateData)
}

/// Table 3-2 error 5: fewer than 4 acceleration pulses
#[scenario(section = "3-2-2", tags("error", "init", "boundary"))]
fn e5_accel_pulses_3(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().accel_pulses(3), ErrorCode::BadRateData)
}

/// Table 3-2 error 5: RH = 0 and RL = 255 are outside 255 > RL > RH > 0
#[scenario(section = "3-2-2", tags("error", "init", "boundary"))]
fn e5_rh_zero_and_rl_255(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(100, 0), ErrorCode::BadRateData)?;
    init_error(d, Init::four_phase().rates(255, 20), ErrorCode::BadRateData)
}

/// Table 3-2 error 6: a data byte during BUSY
#[scenario(section = "3-1-1", tags("error", "busy"))]
fn e6_data_while_busy(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.data(0x10)?;
    d.expect_error(ErrorCode::DataWhileBusy)
}

/// Table 3-2 error 7: Decelerating Stop while the move decelerates to its end
#[scenario(section = "3-3-2", tags("error", "stop"))]
fn e7_decel_stop_during_final_deceleration(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.start(Move::accel(Cw, 400))?;
    // Pulses 300..399 are the final deceleration.
    d.after_pulses(320)?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::DecelStopDuringDecel)?;
    d.wait_idle()?;
    d.expect_pulses(400, Cw)
}

/// Table 3-2 error 7: a second Decelerating Stop while the first decelerates
#[scenario(section = "3-3-2", tags("error", "stop"))]
fn e7_second_decel_stop(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.after_pulses(300)?;
    d.decel_stop()?;
    d.expect_no_error()?;
    d.after_pulses(330)?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::DecelStopDuringDecel)
}
