//! Section 3-1: host interface registers, and every error code of Table 3-2.

use crate::scenario::prelude::*;

pub fn scenarios() -> Vec<Scenario> {
    vec![
        Scenario::new("s3_1_1_status_is_idle_after_reset", "3-1-1",
            "the status register reads 0x00 after a hardware reset",
            &["host-interface", "status"], status_idle),
        Scenario::new("s3_1_1_ibf_clears_when_the_chip_takes_a_byte", "3-1-1",
            "IBF = 1 after a write, 0 once taken; the parameter field then counts 4",
            &["host-interface", "status"], ibf_clears),
        Scenario::new("s3_1_1_parameter_count_counts_down", "3-1-1",
            "bits 6-4 count the initialization data bytes still wanted: 4, 3, 2, 1, 0",
            &["host-interface", "status", "init"], param_count),
        Scenario::new("s3_1_1_write_while_ibf_loses_the_earlier_byte", "3-1-1",
            "a command written while IBF = 1 replaces the waiting one",
            &["host-interface", "raw"], overwrite),
        Scenario::new("s3_1_2_obf_rises_with_data_and_falls_on_read", "3-1-2",
            "OBF = 1 once register data is ready, 0 after the read",
            &["host-interface", "status", "read"], obf),
        Scenario::new("s3_1_1_error_flag_stays_until_the_next_command", "3-1-1",
            "an error stays in the status register until a new command code is taken",
            &["host-interface", "error"], error_persists),
        Scenario::new("e0_undefined_command_code", "3-1-1",
            "Table 3-2 error 0: an undefined command code (0x87)",
            &["error"], e0_undefined),
        Scenario::new("e0_motor_type_code_00", "3-2",
            "Table 3-2 error 0: initialization with motor type code 00",
            &["error", "init"], e0_motor_type_00),
        Scenario::new("e0_immediate_stop_while_stopped", "3-3-1",
            "Table 3-2 error 0: Immediate Stop while the motor is stopped",
            &["error", "stop"], e0_immediate_stop),
        Scenario::new("e0_decel_stop_while_stopped", "3-3-2",
            "Table 3-2 error 0: Decelerating Stop while the motor is stopped",
            &["error", "stop"], e0_decel_stop),
        Scenario::new("e1_operation_command_while_busy", "3-1-1",
            "Table 3-2 error 1: an operation command during BUSY",
            &["error", "busy"], e1_operation),
        Scenario::new("e1_register_read_while_busy", "3-4",
            "Table 3-2 error 1: register reads only while the motor is stopped",
            &["error", "busy", "read"], e1_read),
        Scenario::new("e1_initialization_while_busy", "3-1-1",
            "Table 3-2 error 1: initialization during BUSY",
            &["error", "busy", "init"], e1_init),
        Scenario::new("e2_move_before_initialization", "3-1-1",
            "Table 3-2 error 2: a move before any initialization",
            &["error", "init"], e2_before_init),
        Scenario::new("e2_move_after_software_reset", "3-5-4",
            "Table 3-2 error 2: software reset cancels the initialization",
            &["error", "reset"], e2_after_reset),
        Scenario::new("e3_data_without_a_command", "3-1-1",
            "Table 3-2 error 3: a data byte nobody asked for",
            &["error", "raw"], e3_data),
        Scenario::new("e4_accel_pulses_11221", "3-2-2",
            "Table 3-2 error 4: PA = 11,221 is over the limit",
            &["error", "init", "boundary"], e4_pa),
        Scenario::new("e5_rh_above_rl", "3-2-2",
            "Table 3-2 error 5: RH > RL",
            &["error", "init"], e5_rh_above_rl),
        Scenario::new("e5_rh_equal_rl", "3-2-2",
            "Table 3-2 error 5: RH = RL breaks 255 > RL > RH > 0",
            &["error", "init", "boundary"], e5_rh_equal_rl),
        Scenario::new("e5_accel_pulses_3", "3-2-2",
            "Table 3-2 error 5: fewer than 4 acceleration pulses",
            &["error", "init", "boundary"], e5_pa_3),
        Scenario::new("e5_rh_zero_and_rl_255", "3-2-2",
            "Table 3-2 error 5: RH = 0 and RL = 255 are outside 255 > RL > RH > 0",
            &["error", "init", "boundary"], e5_rate_edges),
        Scenario::new("e6_data_while_busy", "3-1-1",
            "Table 3-2 error 6: a data byte during BUSY",
            &["error", "busy"], e6_data),
        Scenario::new("e7_decel_stop_during_final_deceleration", "3-3-2",
            "Table 3-2 error 7: Decelerating Stop while the move decelerates to its end",
            &["error", "stop"], e7_final_decel),
        Scenario::new("e7_second_decel_stop", "3-3-2",
            "Table 3-2 error 7: a second Decelerating Stop while the first decelerates",
            &["error", "stop"], e7_twice),
    ]
}

fn status_idle(d: &mut Driver) -> Outcome {
    d.expect_status(0xFF, 0x00)
}

fn ibf_clears(d: &mut Driver) -> Outcome {
    d.raw_command(Init::four_phase().code())?;
    d.expect_status(0x02, 0x02)?;
    d.expect_flag(Flag::Ibf, false, us(100))?;
    d.expect_status(0xFF, 0x40)
}

fn param_count(d: &mut Driver) -> Outcome {
    let init = Init::four_phase();
    d.command(init.code())?;
    d.expect_params_remaining(4)?;
    for (i, b) in init.data.to_bytes().into_iter().enumerate() {
        d.data(b)?;
        d.expect_params_remaining(3 - i as u8)?;
    }
    d.expect_no_error()
}

fn overwrite(d: &mut Driver) -> Outcome {
    d.raw_command(Init::four_phase().code())?;
    d.raw_command(Register::InputSignals.code())?;
    d.expect_params_remaining(0)?;
    d.expect_flag(Flag::Obf, true, ms(1))?;
    let b = d.read_data()?;
    d.check("input status from the read that replaced the initialization", 0x3F, b)
}

fn obf(d: &mut Driver) -> Outcome {
    d.command(Register::AuxInputs.code())?;
    d.expect_status(0x01, 0x00)?;
    d.expect_flag(Flag::Obf, true, ms(1))?;
    d.read_data()?;
    d.expect_status(0x01, 0x00)
}

fn error_persists(d: &mut Driver) -> Outcome {
    d.command(0x87)?;
    d.expect_error(ErrorCode::UndefinedCommand)?;
    d.wait(ms(20))?;
    d.expect_error(ErrorCode::UndefinedCommand)?;
    d.command(Register::InputSignals.code())?;
    d.expect_no_error()
}

fn e0_undefined(d: &mut Driver) -> Outcome {
    d.command(0x87)?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

fn e0_motor_type_00(d: &mut Driver) -> Outcome {
    d.command(0x00)?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

fn e0_immediate_stop(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.immediate_stop()?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

fn e0_decel_stop(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::UndefinedCommand)
}

fn long_move(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.start(Move::accel(Cw, 5_000))?;
    Ok(())
}

fn e1_operation(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Move::accel(Cw, 10).code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

fn e1_read(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Register::FinishStatus.code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

fn e1_init(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.command(Init::four_phase().code())?;
    d.expect_error(ErrorCode::NotAllowedWhileBusy)
}

fn e2_before_init(d: &mut Driver) -> Outcome {
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

fn e2_after_reset(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.run(Move::single_step(Cw))?;
    d.command(0xC0)?;
    d.wait(us(100))?;
    d.command(Move::single_step(Cw).code())?;
    d.expect_error(ErrorCode::NotInitialized)
}

fn e3_data(d: &mut Driver) -> Outcome {
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

fn e4_pa(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().accel_pulses(11_221), ErrorCode::AccelPulsesTooMany)
}

fn e5_rh_above_rl(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(20, 100), ErrorCode::BadRateData)
}

fn e5_rh_equal_rl(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(50, 50), ErrorCode::BadRateData)
}

fn e5_pa_3(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().accel_pulses(3), ErrorCode::BadRateData)
}

fn e5_rate_edges(d: &mut Driver) -> Outcome {
    init_error(d, Init::four_phase().rates(100, 0), ErrorCode::BadRateData)?;
    init_error(d, Init::four_phase().rates(255, 20), ErrorCode::BadRateData)
}

fn e6_data(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.data(0x10)?;
    d.expect_error(ErrorCode::DataWhileBusy)
}

fn e7_final_decel(d: &mut Driver) -> Outcome {
    d.init(Init::four_phase())?;
    d.start(Move::accel(Cw, 400))?;
    // Pulses 300..399 are the final deceleration.
    d.after_pulses(320)?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::DecelStopDuringDecel)?;
    d.wait_idle()?;
    d.expect_pulses(400, Cw)
}

fn e7_twice(d: &mut Driver) -> Outcome {
    long_move(d)?;
    d.after_pulses(300)?;
    d.decel_stop()?;
    d.expect_no_error()?;
    d.after_pulses(330)?;
    d.decel_stop()?;
    d.expect_error(ErrorCode::DecelStopDuringDecel)
}
