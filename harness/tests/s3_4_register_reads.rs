//! Section 3-4: the internal register reads, and the phase outputs they show.

mod common;

use common::*;
use ppmc::protocol::{Direction, Input, MoveCommand, MoveKind};
use rstest::rstest;

fn ready() -> Host {
    let mut h = Host::new();
    h.init_example();
    h
}

#[test]
fn s3_4_1_polling_flag_is_set_at_the_stop_and_cleared_by_the_read() {
    let mut h = ready();
    assert_eq!(h.finish_status(), 0x00, "nothing has run yet");
    h.accel_move(Direction::Cw, 10);
    assert_eq!(h.finish_status(), 0x83);
    assert_eq!(h.finish_status(), 0x03, "bit 7 cleared by the first read");
    h.accel_move(Direction::Cw, 10);
    assert_eq!(h.finish_status(), 0x83, "set again by the next stop");
}

#[test]
fn s3_4_1_reading_finish_status_releases_int() {
    let mut h = ready();
    h.accel_move(Direction::Cw, 10);
    assert!(h.chip().pins().int);
    h.wc(0x81); // another register read does not release it
    h.rd();
    assert!(h.chip().pins().int);
    h.finish_status();
    assert!(!h.chip().pins().int);
}

#[test]
fn s3_4_1_operation_code_survives_stop_commands() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::ContinuousConstant, Direction::Cw, true),
        Some(50),
        None,
    );
    h.wait(MS(5));
    h.wc(0x40);
    h.await_idle();
    assert_eq!(
        h.finish_status() & 0x07,
        0b101,
        "the move's code, not the stop's"
    );
}

#[rstest]
#[case::none(&[], 0x3F)]
#[case::l4(&[Input::L4], 0x3E)]
#[case::l3(&[Input::L3], 0x3D)]
#[case::l2(&[Input::L2], 0x3B)]
#[case::l1(&[Input::L1], 0x37)]
#[case::alm(&[Input::Alm], 0x2F)]
#[case::cnp(&[Input::Cnp], 0x1F)]
#[case::aux_inputs_not_here(&[Input::Auxi0, Input::Auxi3], 0x3F)]
#[case::all(&[Input::L1, Input::L2, Input::L3, Input::L4, Input::Alm, Input::Cnp], 0x00)]
fn s3_4_2_input_status_reads_the_pins_as_they_are(
    #[case] asserted: &[Input],
    #[case] expected: u8,
) {
    let mut h = Host::new();
    for i in asserted {
        h.set(*i, true);
    }
    assert_eq!(h.read_reg(0x81, 1)[0], expected);
}

#[rstest]
#[case::none(&[], 0x0F)]
#[case::auxi0(&[Input::Auxi0], 0x0E)]
#[case::auxi1_auxi2(&[Input::Auxi1, Input::Auxi2], 0x09)]
#[case::auxi3(&[Input::Auxi3], 0x07)]
#[case::limits_not_here(&[Input::L1, Input::Alm], 0x0F)]
fn s3_4_5_aux_input_status_reads_auxi0_to_3(#[case] asserted: &[Input], #[case] expected: u8) {
    let mut h = Host::new();
    for i in asserted {
        h.set(*i, true);
    }
    assert_eq!(h.read_reg(0x85, 1)[0], expected);
}

#[test]
fn s3_4_3_output_status_shows_direction_hold_and_phases() {
    let mut h = ready();
    // Stopped since initialization: HOLD on, S1 S2 energized (negative
    // logic: low), CW.
    assert_eq!(h.read_reg(0x82, 1)[0], 0b0011_1100);
    h.accel_move(Direction::Ccw, 3);
    // Just stopped: HOLD not yet on; three steps back: S2 S3 energized.
    assert_eq!(h.read_reg(0x82, 1)[0], 0b1001_1010);
    h.wait(MS(4));
    assert_eq!(
        h.read_reg(0x82, 1)[0],
        0b1001_1110,
        "HOLD on 3.4 ms after the last pulse"
    );
}

/// Section 3-2-1 excitation sequences, through output status bits 7-3,
/// for every motor type and excitation method, both directions.
#[rstest]
#[case::three_2ph(0x01, vec![0b11000, 0b01100, 0b10100])]
#[case::three_1_2ph(0x05, vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b10100])]
#[case::four_2ph(0x02, vec![0b11000, 0b01100, 0b00110, 0b10010])]
#[case::four_1_2ph(0x06, vec![0b10000, 0b11000, 0b01000, 0b01100, 0b00100, 0b00110, 0b00010, 0b10010])]
#[case::five_2ph(0x03, vec![0b11000, 0b01100, 0b00110, 0b00011, 0b10001])]
#[case::five_2_3ph(0x07, vec![0b11000, 0b11100, 0b01100, 0b01110, 0b00110, 0b00111, 0b00011, 0b10011, 0b10001, 0b11001])]
fn s3_4_3_phase_outputs_step_once_per_pulse(#[case] init: u8, #[case] cycle: Vec<u8>) {
    // Positive logic so that output status levels equal the energized set.
    let mut h = Host::new();
    h.init(init | 0x08, EXAMPLE_INIT);
    let read_phases = |h: &mut Host| h.read_reg(0x82, 1)[0] >> 3;
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

#[test]
fn s3_4_4_remaining_pulses_read_one_less_than_the_remainder() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(50),
        Some(300),
    );
    h.wait(MS(10));
    h.set(Input::L1, true);
    h.await_idle();
    let done = h.pulses() as u32;
    assert_eq!(h.remaining_read(), 300 - done - 1);
}

#[test]
fn s3_4_4_remaining_is_zero_after_a_complete_move() {
    let mut h = ready();
    h.accel_move(Direction::Cw, 77);
    assert_eq!(h.remaining_read(), 0);
}

#[test]
fn s3_4_4_a_true_remainder_of_one_reads_zero_and_finish_status_tells_them_apart() {
    let mut h = ready();
    // Constant move of 3 pulses at 102 us: stop between pulse 2 and 3.
    let t = h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(50),
        Some(3),
    );
    h.wait((t + US(194 + 102 + 50)).saturating_since(h.now()));
    h.wc_now(0x40);
    h.await_idle();
    assert_eq!(h.pulses(), 2);
    let fs = h.finish_status();
    assert_eq!(h.remaining_read(), 0);
    assert_ne!(fs & 0x78, 0, "abnormal stop: the real remainder is 1");
}

#[test]
fn s3_4_4_remaining_pulses_come_lower_byte_first() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::ContinuousConstant, Direction::Cw, true),
        Some(50),
        None,
    );
    h.wait(MS(1));
    h.set(Input::L1, true);
    h.await_idle();
    let n = h.pulses() as u32;
    let v = 16_777_216 - n - 1;
    assert_eq!(h.read_reg(0x83, 3), v.to_le_bytes()[..3].to_vec());
}
