//! Section 3-3 behaviour the scenarios do not check: the step count over a
//! sweep of lengths around the triangle boundary, the exact mirror of a
//! ramp cut short by a Decelerating Stop, ALM against every kind of move,
//! and ALM already asserted when a move starts. The rest of Section 3-3
//! (every command and direction, the stops, the limits, high-speed limits,
//! origin search, POUT mode, the termination interrupt, resuming from the
//! remaining count) is proven by the scenarios in
//! `scenarios/src/s3_3_operations.rs`.

use ppmc_test_support as common;

use common::*;
use ppmc::protocol::{Command, Direction, Input, MoveCommand, MoveKind, OpFlags, Status};
use ppmc::time::Instant;
use rstest::rstest;

fn accel(dir: Direction) -> MoveCommand {
    MoveCommand::new(MoveKind::AccelDecel, dir, true)
}

fn ready() -> Host {
    let mut h = Host::new();
    h.init_example();
    h
}

/// Pulses of the last move strictly after `t`.
fn pulses_after(h: &Host, t: Instant) -> usize {
    let from = h.chip().record().moves.last().map_or(0, |m| m.first_run);
    h.chip().record().runs[from..]
        .iter()
        .flat_map(|r| (0..r.count).map(move |i| r.at(i)))
        .filter(|p| *p > t)
        .count()
}

#[rstest]
#[case(1)]
#[case(2)]
#[case(5)]
#[case(199)]
#[case(200)]
#[case(201)]
#[case(1_000)]
fn s3_3_4_accel_decel_moves_exactly_n_steps_written_as_n_minus_1(#[case] n: u32) {
    let mut h = ready();
    h.accel_move(Direction::Cw, n);
    assert_eq!(h.pulses(), u64::from(n));
    assert_eq!(h.finish_status(), 0x83);
    assert_eq!(h.remaining_read(), 0);
}

#[test]
fn s3_3_2_decelerating_stop_during_acceleration_ramps_down_symmetrically() {
    let mut h = ready();
    h.start(accel(Direction::Cw), None, Some(5_000));
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(2)); // a few pulses into the ramp
    h.wc(Command::DecelStop(OpFlags::PLAIN).encode());
    h.await_idle();
    let times = h.pulse_times();
    let gaps: Vec<_> = times
        .windows(2)
        .map(|w| w[1].saturating_since(w[0]))
        .collect();
    let mut mirrored = gaps.clone();
    mirrored.reverse();
    assert_eq!(gaps, mirrored);
    assert!(times.len() < 40);
}

#[rstest]
#[case::accel_decel(MoveKind::AccelDecel, Direction::Ccw)]
#[case::constant(MoveKind::Constant, Direction::Cw)]
#[case::continuous(MoveKind::ContinuousConstant, Direction::Ccw)]
#[case::continuous_high(MoveKind::ContinuousHigh, Direction::Cw)]
#[case::origin(MoveKind::OriginSearch, Direction::Ccw)]
fn s3_3_4_alarm_stops_every_move_in_either_direction(
    #[case] kind: MoveKind,
    #[case] dir: Direction,
) {
    let mut h = ready();
    let (rate, steps) = match kind {
        MoveKind::AccelDecel => (None, Some(5_000)),
        MoveKind::Constant => (Some(50), Some(5_000)),
        MoveKind::ContinuousHigh => (None, None),
        _ => (Some(50), None),
    };
    h.start(MoveCommand::new(kind, dir, true), rate, steps);
    h.wait(MS(10));
    let t = h.now();
    h.set(Input::Alm, true);
    h.await_idle();
    assert_eq!(pulses_after(&h, t), 0);
    assert_eq!(h.finish_status(), 0xA0 | kind.code());
}

#[rstest]
#[case::limit_at_start(Input::L1, 0x94)]
#[case::alarm_at_start(Input::Alm, 0xA4)]
fn s3_3_5_an_input_asserted_before_the_move_stops_it_before_any_pulse(
    #[case] input: Input,
    #[case] finish: u8,
) {
    let mut h = ready();
    h.set(input, true);
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(30),
        Some(200),
    );
    h.run_to_end();
    assert_eq!(h.pulses(), 0);
    assert_eq!(h.finish_status(), finish);
    assert_eq!(h.remaining_read(), 199);
}
