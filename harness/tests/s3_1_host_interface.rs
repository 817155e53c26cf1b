//! Section 3-1: the host interface registers, and Table 3-2's error codes.

mod common;

use common::*;
use ppmc::protocol::{Direction, ErrorCode, InitData, MoveCommand, MoveKind, Status, StatusField};
use rstest::rstest;

#[test]
fn s3_1_1_status_is_idle_after_reset() {
    let h = Host::new();
    assert_eq!(h.status().0, 0x00);
}

#[test]
fn s3_1_1_ibf_is_set_by_a_write_and_cleared_when_the_chip_takes_it() {
    let mut h = Host::new();
    h.wc_now(INIT_4PH);
    assert!(h.status().ibf(), "IBF = 1 right after the write");
    let waited = h
        .await_flag(Status::IBF, false, US(100))
        .expect("IBF clears");
    assert!(waited > ppmc::time::Duration::ZERO);
    assert_eq!(h.status().0, 0x40, "IBF = 0, four parameters expected");
}

#[test]
fn s3_1_1_parameter_count_counts_down_through_initialization() {
    let mut h = Host::new();
    h.wc(INIT_4PH);
    let mut counts = vec![h.settled_status().field()];
    for b in EXAMPLE_INIT.to_bytes() {
        h.wd(b);
        counts.push(h.settled_status().field());
    }
    let expected: Vec<StatusField> = (0..=4u8).rev().map(StatusField::ParamsRemaining).collect();
    assert_eq!(counts, expected);
}

#[test]
fn s3_1_1_writing_while_ibf_is_1_loses_the_earlier_byte() {
    let mut h = Host::new();
    h.wc_now(INIT_4PH);
    // Overwrites the initialization code before the chip took it.
    h.wc_now(0x81);
    let s = h.settled_status();
    assert_eq!(
        s.field(),
        StatusField::ParamsRemaining(0),
        "the init code never arrived"
    );
    assert_eq!(h.chip().record().overwritten_bytes, 1);
    assert_eq!(h.rd(), 0x3F, "the input status read that replaced it ran");
}

#[test]
fn s3_1_1_back_to_back_data_bytes_arrive_as_one() {
    let mut h = Host::new();
    h.wc(INIT_4PH);
    // Three writes without waiting for IBF: each replaces the one before,
    // so the chip takes only the last and expects three more.
    h.wd(100);
    h.wd_now(20);
    h.wd_now(21);
    assert_eq!(h.settled_status().field(), StatusField::ParamsRemaining(3));
    assert_eq!(h.chip().record().overwritten_bytes, 2);
}

#[test]
fn s3_1_2_obf_is_set_when_data_is_ready_and_cleared_by_reading() {
    let mut h = Host::new();
    h.wc(0x81);
    assert!(!h.status().obf(), "not ready at the write");
    h.await_flag(Status::OBF, true, US(100)).expect("OBF rises");
    assert_eq!(h.rd(), 0x3F);
    assert!(!h.status().obf());
}

#[test]
fn s3_1_2_reading_with_obf_0_gives_stale_data() {
    let mut h = Host::new();
    h.wc(0x85);
    assert_eq!(h.rd(), 0x0F);
    h.wc(0x81);
    // Read at once, before OBF: the latch still holds the previous byte.
    let stale = h.t.chip_mut().read_data();
    assert_eq!(stale, 0x0F);
}

#[test]
fn s3_1_1_status_bit_3_is_always_zero_during_a_move() {
    let mut h = Host::new();
    h.init_example();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(300),
    );
    for _ in 0..200 {
        h.wait(US(97));
        assert!(!h.status().reserved());
    }
}

#[test]
fn s3_1_1_error_flag_stays_until_the_next_command() {
    let mut h = Host::new();
    h.wc(0x87);
    assert_eq!(
        h.settled_status().error(),
        Some(ErrorCode::UndefinedCommand)
    );
    h.wait(MS(50));
    assert_eq!(h.status().error(), Some(ErrorCode::UndefinedCommand));
    h.wc(0x81);
    assert_eq!(h.settled_status().error(), None);
}

#[test]
fn s3_1_3_a_new_command_abandons_an_unfinished_one() {
    let mut h = Host::new();
    h.wc(INIT_4PH);
    h.wd(100);
    h.wc(0x81);
    assert_eq!(h.settled_status().field(), StatusField::ParamsRemaining(0));
    assert_eq!(h.rd(), 0x3F);
    assert!(!h.chip().initialized());
}

// ----- Table 3-2: every error code, in the situations the text names ------

fn provoke(code: ErrorCode, how: usize) -> Host {
    let mut h = Host::new();
    let accel = MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true);
    let long_move = |h: &mut Host| {
        h.init_example();
        h.start(accel, None, Some(5_000));
        h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    };
    match (code, how) {
        (ErrorCode::UndefinedCommand, 0) => {
            h.wc(0x87);
        }
        (ErrorCode::UndefinedCommand, 1) => {
            h.init_example();
            h.wc(0x40); // Immediate Stop while stopped (3-3-1)
        }
        (ErrorCode::UndefinedCommand, 2) => {
            h.init_example();
            h.wc(0x41); // Decelerating Stop while stopped (3-3-2)
        }
        (ErrorCode::UndefinedCommand, 3) => {
            h.wc(0x00); // motor type code 00
        }
        (ErrorCode::NotAllowedWhileBusy, 0) => {
            long_move(&mut h);
            h.wc(0x43);
        }
        (ErrorCode::NotAllowedWhileBusy, 1) => {
            long_move(&mut h);
            h.wc(0x80); // register reads only when stopped (3-4)
        }
        (ErrorCode::NotAllowedWhileBusy, 2) => {
            long_move(&mut h);
            h.wc(INIT_4PH);
        }
        (ErrorCode::NotAllowedWhileBusy, 3) => {
            long_move(&mut h);
            h.wc(0x84);
        }
        (ErrorCode::NotInitialized, 0) => {
            h.wc(0x43);
        }
        (ErrorCode::NotInitialized, 1) => {
            h.init_example();
            h.wc(0xC0); // software reset cancels the initialization (3-5-4)
            h.wait(US(100));
            h.wc(0x4A);
        }
        (ErrorCode::TooManyParameters, 0) => {
            h.wd(0x12);
        }
        (ErrorCode::TooManyParameters, 1) => {
            h.init_example();
            h.send(0x45, &[100]);
            h.wait(US(10));
            h.wc(0x40); // stop the continuous move
            h.wait(MS(1));
            h.wait_ready();
            h.wd(5); // one byte more than any command wanted
        }
        (ErrorCode::AccelPulsesTooMany, 0) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 100,
                    rh: 20,
                    pa: 11_221,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::AccelPulsesTooMany, 1) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 100,
                    rh: 20,
                    pa: 0xFFFF,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::BadRateData, 0) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 20,
                    rh: 100,
                    pa: 100,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::BadRateData, 1) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 50,
                    rh: 50,
                    pa: 100,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::BadRateData, 2) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 100,
                    rh: 20,
                    pa: 3,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::BadRateData, 3) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 100,
                    rh: 0,
                    pa: 100,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::BadRateData, 4) => {
            h.send(
                INIT_4PH,
                &InitData {
                    rl: 255,
                    rh: 20,
                    pa: 100,
                }
                .to_bytes(),
            );
        }
        (ErrorCode::DataWhileBusy, 0) => {
            long_move(&mut h);
            h.wd(0x10);
        }
        (ErrorCode::DecelStopDuringDecel, 0) => {
            h.init_example();
            h.start(accel, None, Some(400));
            h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
            // Into the final deceleration: the last 100 pulses start about
            // 17 ms after the write (8.3 ms ramp, 8.4 ms at high speed).
            h.wait(MS(20));
            h.wc(0x41);
        }
        (ErrorCode::DecelStopDuringDecel, 1) => {
            long_move(&mut h);
            h.wait(MS(10));
            h.wc(0x41);
            h.wait(MS(1));
            h.wc(0x41); // a second one while the first deceleration runs
        }
        _ => unreachable!("no such case"),
    }
    h
}

#[rstest]
#[case::e0_undefined_code(ErrorCode::UndefinedCommand, 0)]
#[case::e0_immediate_stop_while_stopped(ErrorCode::UndefinedCommand, 1)]
#[case::e0_decel_stop_while_stopped(ErrorCode::UndefinedCommand, 2)]
#[case::e0_motor_type_00(ErrorCode::UndefinedCommand, 3)]
#[case::e1_operation_while_busy(ErrorCode::NotAllowedWhileBusy, 0)]
#[case::e1_register_read_while_busy(ErrorCode::NotAllowedWhileBusy, 1)]
#[case::e1_init_while_busy(ErrorCode::NotAllowedWhileBusy, 2)]
#[case::e1_switching_params_while_busy(ErrorCode::NotAllowedWhileBusy, 3)]
#[case::e2_move_before_init(ErrorCode::NotInitialized, 0)]
#[case::e2_move_after_software_reset(ErrorCode::NotInitialized, 1)]
#[case::e3_data_without_command(ErrorCode::TooManyParameters, 0)]
#[case::e3_extra_data_after_command(ErrorCode::TooManyParameters, 1)]
#[case::e4_pa_11221(ErrorCode::AccelPulsesTooMany, 0)]
#[case::e4_pa_65535(ErrorCode::AccelPulsesTooMany, 1)]
#[case::e5_rh_above_rl(ErrorCode::BadRateData, 0)]
#[case::e5_rh_equal_rl(ErrorCode::BadRateData, 1)]
#[case::e5_pa_3(ErrorCode::BadRateData, 2)]
#[case::e5_rh_0(ErrorCode::BadRateData, 3)]
#[case::e5_rl_255(ErrorCode::BadRateData, 4)]
#[case::e6_data_while_busy(ErrorCode::DataWhileBusy, 0)]
#[case::e7_decel_stop_in_final_deceleration(ErrorCode::DecelStopDuringDecel, 0)]
#[case::e7_decel_stop_twice(ErrorCode::DecelStopDuringDecel, 1)]
fn s3_1_1_table_3_2_error_codes(#[case] code: ErrorCode, #[case] how: usize) {
    let mut h = provoke(code, how);
    let s = h.settled_status();
    assert!(s.error_flag(), "error flag set: {s:?}");
    assert_eq!(s.error(), Some(code), "{s:?}");
    assert_eq!(s.0 >> 4 & 0b111, code.number());
}

#[rstest]
#[case::pa_4_lower_bound(InitData { rl: 100, rh: 20, pa: 4 })]
#[case::pa_11220_upper_bound(InitData { rl: 100, rh: 20, pa: 11_220 })]
#[case::rl_254_rh_1(InitData { rl: 254, rh: 1, pa: 100 })]
#[case::rh_just_below_rl(InitData { rl: 21, rh: 20, pa: 100 })]
fn s3_2_2_boundary_values_are_accepted(#[case] data: InitData) {
    let mut h = Host::new();
    h.send(INIT_4PH, &data.to_bytes());
    assert_eq!(h.settled_status().error(), None);
    assert!(h.chip().initialized());
}

#[test]
fn s3_2_2_a_rejected_initialization_changes_nothing() {
    let mut h = Host::new();
    h.send(
        INIT_4PH,
        &InitData {
            rl: 20,
            rh: 100,
            pa: 100,
        }
        .to_bytes(),
    );
    h.wait(MS(1));
    assert!(!h.chip().initialized());
    h.wc(0x4A);
    assert_eq!(h.settled_status().error(), Some(ErrorCode::NotInitialized));
}
