//! Section 3-2 behaviour the scenarios do not check: Equations 3-1 to 3-4
//! against periods worked out by hand for every CSEL / VSEL strapping, the
//! exact shape of the ramp, an unclocked move that never ends even when
//! waited for without limit, where in the deceleration an over-speed chip
//! takes the host's byte again, the speed limit by mode, and stop switching
//! held back until the first initialization is processed. The rest of
//! Section 3-2 (phase outputs set by the first initialization, the frozen
//! winding, new rates without a reset, processing times, boundary rates,
//! the external clock, the over-speed lock-out) is proven by the scenarios
//! in `scenarios/src/s3_2_initialization.rs` and `s3_2_excitation.rs`.

use ppmc_test_support as common;

use common::*;
use ppmc::emu::ModelConfig;
use ppmc::protocol::{
    Command, Direction, ErrorCode, InitData, MoveCommand, MoveKind, OpFlags, Pin, Register, Status,
    Straps,
};
use ppmc::scenario::Init;
use ppmc::time::Duration;
use rstest::rstest;

/// Equations 3-1..3-4 seen in the pulse train of a constant-speed move.
#[rstest]
#[case::csel_high_vsel_high(true, true, 20, 42_000)]
#[case::csel_low_vsel_high(false, true, 9, 80_000)]
#[case::csel_high_vsel_low(true, false, 20, 49_500)]
#[case::csel_low_vsel_low(false, false, 9, 87_500)]
fn s3_2_2_equations_3_1_to_3_4_in_the_pulse_train(
    #[case] csel_high: bool,
    #[case] vsel_high: bool,
    #[case] rate: u8,
    #[case] period_ns: u64,
) {
    let straps = Straps {
        csel_high,
        vsel_high,
        ..Straps::default()
    };
    let mut h = Host::with(straps, ModelConfig::default());
    h.init_example();
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(rate),
        Some(50),
    );
    h.run_to_end();
    let s = h.chip().record().last_move_pulses();
    assert_eq!(s.count, 50);
    assert_eq!(s.min_interval, Some(Duration::from_nanos(period_ns)));
    assert_eq!(s.max_interval, Some(Duration::from_nanos(period_ns)));
}

#[test]
fn s3_2_1_external_clock_sets_tclock() {
    let straps = Straps {
        ext_clock_hz: Some(1_000_000),
        ..Straps::default()
    };
    let mut h = Host::with(straps, ModelConfig::default());
    h.init(Init::four_phase().external_clock().code(), EXAMPLE_INIT);
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(99),
        Some(10),
    );
    h.run_to_end();
    assert_eq!(
        h.chip().record().last_move_pulses().min_interval,
        Some(US(100))
    );
}

#[test]
fn s3_2_1_external_clock_without_a_clock_never_pulses() {
    let mut h = Host::new();
    h.init(Init::four_phase().external_clock().code(), EXAMPLE_INIT);
    h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(99),
        Some(10),
    );
    assert!(h.await_flag(Status::BUSY, true, MS(1)).is_some());
    assert!(
        h.await_flag(Status::BUSY, false, MS(500)).is_none(),
        "stuck busy"
    );
    assert_eq!(h.pulses(), 0);
    // Even waiting to the end of time ends, with no pulse.
    assert!(h.await_flag(Status::BUSY, false, Duration::MAX).is_none());
    assert_eq!(h.pulses(), 0);
}

#[test]
fn s3_2_2_acceleration_ramps_from_rl_to_rh_in_pa_pulses() {
    let mut h = Host::new();
    h.init_example();
    h.accel_move(Direction::Cw, 1_000);
    let times = h.pulse_times();
    let gaps: Vec<u64> = times
        .windows(2)
        .map(|w| w[1].saturating_since(w[0]).as_nanos())
        .collect();
    assert_eq!(
        gaps[0], 202_000,
        "first period at RL = 100: (100 + 1) x 2 us"
    );
    assert!(
        gaps[..100].windows(2).all(|w| w[1] <= w[0]),
        "speed never falls while accelerating"
    );
    assert!(
        gaps[..100].iter().all(|g| *g >= 42_000),
        "never faster than RH"
    );
    assert!(
        gaps[..50].iter().all(|g| *g > 42_000),
        "still accelerating halfway"
    );
    assert!(
        gaps[100..899].iter().all(|g| *g == 42_000),
        "high speed from pulse PA on"
    );
    let mut mirrored = gaps.clone();
    mirrored.reverse();
    assert_eq!(gaps, mirrored, "deceleration mirrors acceleration");
}

#[test]
fn s3_2_2_over_speed_stops_host_commands_while_pulsing() {
    // RH = 10: 22 us per pulse = 45 kpps, over the 27 kpps limit.
    let mut h = Host::new();
    h.init(
        Init::four_phase().code(),
        InitData {
            rl: 100,
            rh: 10,
            pa: 100,
        },
    );
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(5_000),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(20)); // well into high speed
    h.wc_now(Command::ImmediateStop(OpFlags::PLAIN).encode()); // cannot get in
    assert!(
        h.await_flag(Status::IBF, false, MS(50)).is_none(),
        "IBF stays 1 at high speed"
    );
    // The byte is taken once the deceleration is back under the limit.
    h.await_flag(Status::IBF, false, MS(100))
        .expect("taken during deceleration");
    let taken = h.now();
    h.await_idle();
    // The byte was taken at the first pulse after which the period being
    // timed is back under the limit; the stop then cut that period short.
    let times = h.pulse_times();
    let last = times[times.len() - 1];
    assert_eq!(last, taken, "taken at a pulse");
    let gap_before = last.saturating_since(times[times.len() - 2]);
    assert!(
        gap_before < Duration::from_nanos(37_037),
        "over the limit just before: {gap_before}"
    );
    let n = h.pulses();
    assert!(
        n > 4_900 && n < 5_000,
        "stopped during the deceleration: {n}"
    );
    assert_eq!(h.finish_status(), 0xC3, "stopped by the command");
}

#[rstest]
#[case::phase_mode_over_limit(false, 13, true)]
#[case::pout_mode_within_limit(true, 13, false)]
#[case::pout_mode_over_limit(true, 11, true)]
#[case::phase_mode_within_limit(false, 18, false)]
fn s3_2_2_speed_limit_depends_on_mode(#[case] pout: bool, #[case] rh: u8, #[case] locked: bool) {
    let mut h = Host::new();
    h.init(
        Init::four_phase().code(),
        InitData {
            rl: 100,
            rh,
            pa: 100,
        },
    );
    let cmd = if pout {
        MoveCommand::pout(MoveKind::AccelDecel, Direction::Cw, true)
    } else {
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true)
    };
    h.start(cmd, None, Some(5_000));
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(20));
    h.wc_now(Register::InputSignals.code()); // error 1 if taken while BUSY
    let taken = h.await_flag(Status::IBF, false, MS(5)).is_some();
    assert_eq!(taken, !locked);
    if taken {
        assert_eq!(h.status().error(), Some(ErrorCode::NotAllowedWhileBusy));
    }
}

#[test]
fn s3_2_1_switching_does_not_run_before_the_first_initialization_completes() {
    let mut h = Host::new();
    h.send(
        Init::four_phase().stop_switching().code(),
        &EXAMPLE_INIT.to_bytes(),
    );
    let t = h.now();
    h.wait(MS(5));
    assert_eq!(
        h.chip()
            .record()
            .pins
            .iter()
            .filter(|e| e.pin == Pin::Switching)
            .count(),
        0
    );
    h.wait(MS(200));
    let on = h.pin_event(Pin::Switching, 1, t).expect("switching starts");
    assert!(
        on.saturating_since(t) >= MS(16),
        "only after initialization processing"
    );
}
