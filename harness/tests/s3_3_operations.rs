//! Section 3-3: the operation commands, their stops and the input signals.

mod common;

use common::*;
use ppmc::protocol::{Direction, Input, MoveCommand, MoveKind, Pin, Status};
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
        .flat_map(|r| (0..r.count).map(move |i| r.start + r.interval.saturating_mul(u64::from(i))))
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
fn s3_3_4_ffffff_moves_16777216_steps() {
    let mut h = ready();
    h.wait_ready();
    h.send(0x43, &[0xFF, 0xFF, 0xFF]);
    h.run_to_end();
    assert_eq!(h.pulses(), 16_777_216);
    assert_eq!(
        h.chip().record().last_move_pulses().min_interval,
        Some(US(42))
    );
}

#[test]
fn s3_3_4_short_moves_are_triangular() {
    let mut h = ready();
    h.accel_move(Direction::Cw, 150); // < 2 x PA = 200
    let s = h.chip().record().last_move_pulses();
    assert!(
        s.min_interval.expect("pulsed") > US(42),
        "never reaches high speed"
    );
    h.accel_move(Direction::Cw, 400);
    assert_eq!(
        h.chip().record().last_move_pulses().min_interval,
        Some(US(42))
    );
}

#[rstest]
#[case::cw(Direction::Cw)]
#[case::ccw(Direction::Ccw)]
fn s3_3_4_direction_bit_sets_dir_and_pulse_direction(#[case] dir: Direction) {
    let mut h = ready();
    h.accel_move(dir, 20);
    let s = h.chip().record().last_move_pulses();
    let (cw, ccw) = if dir == Direction::Cw {
        (20, 0)
    } else {
        (0, 20)
    };
    assert_eq!((s.cw, s.ccw), (cw, ccw));
    assert_eq!(h.chip().pins().dir, dir);
    let out = h.read_reg(0x82, 1)[0];
    assert_eq!(
        out & 0x02 != 0,
        dir == Direction::Ccw,
        "output status bit 1"
    );
}

#[rstest]
#[case::interrupt_output(true)]
#[case::interrupt_masked(false)]
fn s3_3_4_termination_interrupt_follows_the_mask_bit(#[case] interrupt: bool) {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, interrupt),
        None,
        Some(10),
    );
    h.run_to_end();
    assert_eq!(h.chip().pins().int, interrupt);
}

#[test]
fn s3_3_4_pout_mode_outputs_pulses_only() {
    let mut h = ready();
    let before = h.chip().pins().phases;
    h.start(
        MoveCommand::pout(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(7),
    );
    h.run_to_end();
    assert_eq!(h.pulses(), 7);
    assert_eq!(
        h.chip().pins().phases,
        before,
        "phase outputs hold in POUT mode"
    );
    assert_eq!(
        h.finish_status(),
        0x83,
        "finish status carries the operation code 011"
    );
    // The same move in phase mode steps the outputs.
    h.accel_move(Direction::Cw, 7);
    assert_ne!(h.chip().pins().phases, before);
}

#[test]
fn s3_3_2_decelerating_stop_at_high_speed_takes_pa_more_pulses() {
    let mut h = ready();
    h.start(accel(Direction::Cw), None, Some(5_000));
    h.wait(MS(12)); // at high speed
    let t = h.wc(0x41);
    h.await_idle();
    // The pulse already being timed and PA - 1 = 99 more: PA pulses.
    assert_eq!(pulses_after(&h, t + US(17)), 100);
    let n = h.pulses() as u32;
    assert_eq!(h.finish_status(), 0xC3);
    assert_eq!(h.remaining_read(), 5_000 - n - 1);
}

#[test]
fn s3_3_2_decelerating_stop_during_acceleration_ramps_down_symmetrically() {
    let mut h = ready();
    h.start(accel(Direction::Cw), None, Some(5_000));
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(2)); // a few pulses into the ramp
    h.wc(0x41);
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

#[test]
fn s3_3_1_immediate_stop_cuts_the_pulse_train() {
    let mut h = ready();
    h.start(accel(Direction::Cw), None, Some(5_000));
    h.wait(MS(12));
    let t = h.wc(0x40);
    h.await_idle();
    assert_eq!(
        pulses_after(&h, t + US(6)),
        0,
        "nothing after the stop is taken"
    );
    let n = h.pulses() as u32;
    assert_eq!(h.finish_status(), 0xC3);
    assert_eq!(h.remaining_read(), 5_000 - n - 1);
}

#[test]
fn s3_3_1_a_constant_move_stopped_at_once_can_be_resumed() {
    let mut h = ready();
    let cmd = MoveCommand::new(MoveKind::Constant, Direction::Cw, true);
    h.start(cmd, Some(50), Some(300));
    h.wait(MS(10));
    h.wc(0x40);
    h.await_idle();
    let done = h.pulses();
    let left = h.remaining_read() + 1;
    assert_eq!(done + u64::from(left), 300);
    // Section 3-4-4: the value read is written back as it stands (N - 1).
    h.start(cmd, Some(50), Some(left));
    h.run_to_end();
    assert_eq!(done + h.pulses(), 300);
}

#[test]
fn s3_3_5_constant_speed_moves_n_steps_at_the_given_rate() {
    let mut h = ready();
    let t = h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Ccw, true),
        Some(50),
        Some(100),
    );
    h.run_to_end();
    let s = h.chip().record().last_move_pulses();
    assert_eq!((s.count, s.ccw), (100, 100));
    assert_eq!(
        (s.min_interval, s.max_interval),
        (Some(US(102)), Some(US(102)))
    );
    assert_eq!(h.first_pulse().saturating_since(t), US(194));
    assert_eq!(h.finish_status(), 0x84);
}

#[rstest]
#[case::l1_stops_cw(Direction::Cw, Input::L1, true)]
#[case::l2_stops_ccw(Direction::Ccw, Input::L2, true)]
#[case::l2_ignored_cw(Direction::Cw, Input::L2, false)]
#[case::l1_ignored_ccw(Direction::Ccw, Input::L1, false)]
fn s3_3_6_limits_stop_only_their_own_direction(
    #[case] dir: Direction,
    #[case] limit: Input,
    #[case] stops: bool,
) {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::Constant, dir, true),
        Some(50),
        Some(300),
    );
    h.wait(MS(10));
    let t = h.now();
    h.set(limit, true);
    h.await_idle();
    assert_eq!(pulses_after(&h, t) == 0, stops);
    let fs = h.finish_status();
    if stops {
        assert_eq!(fs, 0x94, "finish bit 4: limit");
        assert!(h.pulses() < 300);
    } else {
        assert_eq!(fs, 0x84);
        assert_eq!(h.pulses(), 300);
    }
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

#[test]
fn s3_3_3_single_step_moves_one_step() {
    let mut h = ready();
    for dir in [Direction::Cw, Direction::Ccw, Direction::Ccw] {
        h.start(
            MoveCommand::new(MoveKind::SingleStep, dir, true),
            None,
            None,
        );
        h.run_to_end();
        let s = h.chip().record().last_move_pulses();
        assert_eq!(s.count, 1);
        assert_eq!(s.ccw == 1, dir == Direction::Ccw);
        assert_eq!(h.finish_status(), 0x82);
    }
    assert_eq!(
        h.chip().pins().phases,
        0b10010,
        "one step back from the start: S4 S1"
    );
}

#[test]
fn s3_3_6_continuous_constant_runs_until_a_limit_and_reports_the_distance() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::ContinuousConstant, Direction::Cw, true),
        Some(50),
        None,
    );
    h.wait(MS(50));
    h.set(Input::L2, true); // other direction: ignored
    h.wait(MS(50));
    h.set(Input::L1, true);
    h.await_idle();
    let n = h.pulses() as u32;
    assert!(n > 900);
    assert_eq!(h.finish_status(), 0x95);
    // FFFFFF was the count: the position is 16,777,216 - remaining.
    assert_eq!(h.remaining_read(), 16_777_216 - n - 1);
}

#[test]
fn s3_3_7_continuous_high_speed_decelerates_at_the_high_speed_limit() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::ContinuousHigh, Direction::Ccw, true),
        None,
        None,
    );
    h.wait(MS(30));
    let t = h.now();
    h.set(Input::L4, true);
    h.wait(MS(1));
    h.set(Input::L4, false); // deceleration continues with the limit off
    h.await_idle();
    assert_eq!(pulses_after(&h, t + US(17)), 100);
    assert_eq!(h.finish_status(), 0x8E, "bit 3: high-speed limit, code 110");
}

#[test]
fn s3_3_7_high_speed_limit_during_acceleration_decelerates() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::ContinuousHigh, Direction::Cw, true),
        None,
        None,
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(3));
    h.set(Input::L3, true);
    h.await_idle();
    let s = h.chip().record().last_move_pulses();
    assert!(
        s.min_interval.expect("pulsed") > US(42),
        "never reached high speed"
    );
    assert_eq!(h.finish_status(), 0x8E);
}

#[test]
fn s3_3_4_pout_mode_ignores_the_high_speed_limit_while_accelerating() {
    let mut h = ready();
    h.start(
        MoveCommand::pout(MoveKind::ContinuousHigh, Direction::Cw, true),
        None,
        None,
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(3));
    h.set(Input::L3, true); // held: seen once high speed is reached
    h.await_idle();
    let s = h.chip().record().last_move_pulses();
    assert_eq!(
        s.min_interval,
        Some(US(42)),
        "accelerated to high speed regardless"
    );
    // Pulses 0..=99 ramp up (the period after pulse 99 is the first at
    // high speed, where the limit is looked at); pulse 100 was already being
    // timed when the deceleration began 17 us later: it and 99 more.
    assert_eq!(s.count, 200);
    assert_eq!(h.finish_status(), 0x8E);
}

#[test]
fn s3_3_4_high_speed_limit_of_the_other_direction_is_ignored() {
    let mut h = ready();
    h.start(accel(Direction::Cw), None, Some(1_000));
    h.wait(MS(12));
    h.set(Input::L4, true);
    h.await_idle();
    assert_eq!(h.pulses(), 1_000);
    assert_eq!(h.finish_status(), 0x83);
}

#[test]
fn s3_3_8_origin_search_stops_at_the_origin_signal() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::OriginSearch, Direction::Ccw, true),
        Some(30),
        None,
    );
    h.wait(MS(20));
    let t = h.now();
    h.set(Input::Cnp, true);
    h.await_idle();
    assert_eq!(pulses_after(&h, t), 0);
    let n = h.pulses() as u32;
    assert_eq!(
        h.finish_status(),
        0x87,
        "origin found: no cause bits (notes N14)"
    );
    assert_eq!(h.remaining_read(), 16_777_216 - n - 1);
}

#[test]
fn s3_3_8_origin_signal_is_ignored_by_other_moves() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(30),
        Some(200),
    );
    h.wait(MS(2));
    h.set(Input::Cnp, true);
    h.await_idle();
    assert_eq!(h.pulses(), 200);
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

#[test]
fn s3_3_2_decelerating_stop_on_a_constant_move_stops_at_once() {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(50),
        Some(500),
    );
    h.wait(MS(10));
    let t = h.wc(0x41);
    h.await_idle();
    assert_eq!(pulses_after(&h, t + US(6)), 0);
    assert_eq!(h.finish_status(), 0xC4);
}

#[test]
fn s3_3_busy_rises_before_the_first_pulse_and_falls_after_the_last() {
    let mut h = ready();
    let t = h.start(accel(Direction::Cw), None, Some(30));
    h.run_to_end();
    let rise = h.pin_event(Pin::Busy, 1, t).expect("busy rose");
    let fall = h.pin_event(Pin::Busy, 0, t).expect("busy fell");
    assert!(rise < h.first_pulse() && fall > h.last_pulse());
}
