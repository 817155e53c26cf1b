//! Section 3-1 behaviour the scenarios do not check: back-to-back writes
//! that overwrite each other in the input buffer, a data read before OBF,
//! status bit 3 sampled through a move, a command that abandons an
//! unfinished one, a rejected initialization that changes nothing, and the
//! two Table 3-2 situations no scenario provokes (data after a command's
//! last parameter; PA = 0xFFFF), with the error number read from the raw
//! status bits as an independent check of the typed status register. The
//! rest of Section 3-1 and Table 3-2 is proven by the scenarios in
//! `scenarios/src/s3_1_host_interface.rs`.

use ppmc_test_support as common;

use common::*;
use ppmc::protocol::{
    Command, Direction, ErrorCode, InitData, MoveCommand, MoveKind, OpFlags, Register, StatusField,
};
use rstest::rstest;

#[test]
fn s3_1_1_back_to_back_data_bytes_arrive_as_one() {
    let mut h = Host::new();
    h.wc(init_4ph());
    // Three writes without waiting for IBF: each replaces the one before,
    // so the chip takes only the last and expects three more.
    h.wd(100);
    h.wd_now(20);
    h.wd_now(21);
    assert_eq!(h.settled_status().field(), StatusField::ParamsRemaining(3));
    assert_eq!(h.chip().record().overwritten_bytes, 2);
}

#[test]
fn s3_1_2_reading_with_obf_0_gives_stale_data() {
    let mut h = Host::new();
    h.wc(Register::AuxInputs.code());
    assert_eq!(h.rd(), 0x0F);
    h.wc(Register::InputSignals.code());
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
fn s3_1_3_a_new_command_abandons_an_unfinished_one() {
    let mut h = Host::new();
    h.wc(init_4ph());
    h.wd(100);
    h.wc(Register::InputSignals.code());
    assert_eq!(h.settled_status().field(), StatusField::ParamsRemaining(0));
    assert_eq!(h.rd(), 0x3F);
    assert!(!h.chip().initialized());
}

#[test]
fn s3_2_2_a_rejected_initialization_changes_nothing() {
    let mut h = Host::new();
    h.send(
        init_4ph(),
        &InitData {
            rl: 20,
            rh: 100,
            pa: 100,
        }
        .to_bytes(),
    );
    h.wait(MS(1));
    assert!(!h.chip().initialized());
    h.wc(Command::Move(MoveCommand::new(MoveKind::SingleStep, Direction::Ccw, true)).encode());
    assert_eq!(h.settled_status().error(), Some(ErrorCode::NotInitialized));
}

/// Table 3-2 errors 3 and 4 in the situations no scenario provokes.
#[rstest]
#[case::e3_extra_data_after_command(ErrorCode::TooManyParameters)]
#[case::e4_pa_65535(ErrorCode::AccelPulsesTooMany)]
fn s3_1_1_table_3_2_error_codes(#[case] code: ErrorCode) {
    let mut h = Host::new();
    match code {
        ErrorCode::TooManyParameters => {
            h.init_example();
            let continuous = MoveCommand::new(MoveKind::ContinuousConstant, Direction::Cw, true);
            h.send(Command::Move(continuous).encode(), &[100]);
            h.wait(US(10));
            h.wc(Command::ImmediateStop(OpFlags::PLAIN).encode());
            h.wait(MS(1));
            h.wait_ready();
            h.wd(5); // one byte more than any command wanted
        }
        _ => {
            let data = InitData {
                rl: 100,
                rh: 20,
                pa: 0xFFFF,
            };
            h.send(init_4ph(), &data.to_bytes());
        }
    }
    let s = h.settled_status();
    assert!(s.error_flag(), "error flag set: {s:?}");
    assert_eq!(s.error(), Some(code), "{s:?}");
    // Diagram 3-1: bit 7 the error flag, bits 6-4 the error number.
    assert_eq!(s.0 & 0x80, 0x80);
    assert_eq!(s.0 >> 4 & 0b111, code.number());
}
