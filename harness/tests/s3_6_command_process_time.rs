//! Section 3-6, Table 3-3: every row measured on the model, in virtual time,
//! against the row's band widened by the table's 1 % footnote.

mod common;

use common::*;
use ppmc::protocol::{Direction, InitData, Input, MoveCommand, MoveKind, Pin, Status, TimingId};
use ppmc::time::{Duration, Instant};
use rstest::rstest;

fn assert_in_row(id: TimingId, measured: Duration) {
    let (lo, hi) = id.row().band_with_tolerance();
    assert!(
        measured >= lo && measured <= hi,
        "{id:?}: measured {measured}, Table 3-3 allows {lo}..={hi}"
    );
}

fn ready() -> Host {
    let mut h = Host::new();
    h.init_example();
    h
}

/// Time from the final initialization byte until the chip takes the next
/// command.
fn init_time(pa: u16) -> Duration {
    let mut h = Host::new();
    let t = h.send(
        init_4ph(),
        &InitData {
            rl: 200,
            rh: 20,
            pa,
        }
        .to_bytes(),
    );
    h.wc(0x81);
    h.await_flag(Status::IBF, false, Duration::from_secs(1))
        .expect("taken after initialization");
    h.now().saturating_since(t)
}

#[test]
fn s3_6_initialization_time_grows_with_pa_within_16_5_to_162_8_ms() {
    let times: Vec<Duration> = [4u16, 100, 5_000, 11_220]
        .iter()
        .map(|pa| init_time(*pa))
        .collect();
    for t in &times {
        assert_in_row(TimingId::InitProcessing, *t);
    }
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    assert!(within(times[0], MS(16) + US(500), 10));
    assert!(within(times[3], US(162_800), 10));
}

#[test]
fn s3_6_initialization_sets_the_outputs_44_us_after_the_final_byte() {
    let mut h = Host::new();
    let t = h.send(init_4ph(), &EXAMPLE_INIT.to_bytes());
    h.wait(MS(1));
    let set = h.pin_event(Pin::Phases, 0b11000, t).expect("phases set");
    assert_in_row(TimingId::InitOutputsSet, set.saturating_since(t));
}

#[rstest]
#[case::trapezoid(1_000)]
#[case::just_trapezoid(200)]
#[case::triangle(199)]
#[case::small_triangle(10)]
fn s3_6_accel_first_pout_is_0_2_to_1_1_ms(#[case] steps: u32) {
    let mut h = ready();
    let t = h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(steps),
    );
    h.run_to_end();
    let d = h.first_pulse().saturating_since(t);
    assert_in_row(TimingId::AccelFirstPout, d);
    if steps >= 200 {
        assert_eq!(d, US(200), "minimum in trapezoidal drive");
    } else {
        assert!(d > US(200), "triangles take longer: {d}");
    }
}

#[test]
fn s3_6_accel_first_pout_grows_with_the_triangle() {
    let first = |pa: u16, steps: u32| {
        let mut h = Host::new();
        h.init(
            init_4ph(),
            InitData {
                rl: 200,
                rh: 20,
                pa,
            },
        );
        let t = h.start(
            MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
            None,
            Some(steps),
        );
        h.run_to_end();
        h.first_pulse().saturating_since(t)
    };
    let small = first(11_220, 100);
    let large = first(11_220, 22_000);
    assert!(small < large, "{small} < {large}");
    assert_in_row(TimingId::AccelFirstPout, large);
}

#[rstest]
#[case::immediate_stop(0)]
#[case::limit(1)]
fn s3_6_abnormal_termination_within_0_2_ms(#[case] how: usize) {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(5_000),
    );
    h.wait(MS(12));
    let t = if how == 0 {
        h.wc(0x40)
    } else {
        h.set(Input::L1, true);
        h.now()
    };
    h.await_idle();
    assert_in_row(TimingId::AbnormalTermination, h.now().saturating_since(t));
}

/// Total pulses of a 5,000-step accel/decel move when `trigger` acts
/// `before` ahead of the `k`-th pulse after `settle`. The pulse count shows
/// which pulse the deceleration started from.
fn decel_count(settle: Duration, k: u32, before: Duration, trigger: fn(&mut Host)) -> (u32, u32) {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(5_000),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(settle);
    // Find pulse index and time of the k-th next pulse on a copy.
    let mut probe = Host { t: h.t.clone() };
    let done = probe.chip().record().pulse_count() as u32;
    probe.wait(MS(20));
    let times = probe.pulse_times();
    let target = times[(done + k) as usize];
    h.wait(target.saturating_since(h.now()).saturating_sub(before));
    trigger(&mut h);
    h.await_idle();
    (h.pulses() as u32, done + k)
}

fn decel_stop(h: &mut Host) {
    h.wc_now(0x41);
}

fn high_speed_limit(h: &mut Host) {
    h.set(Input::L3, true);
}

/// The latency lies in (before_short, before_long] when a trigger that much
/// ahead of pulse `k` decelerates from pulse k+1 and from pulse k.
fn assert_latency(
    id: TimingId,
    settle: Duration,
    trigger: fn(&mut Host),
    pa_part: impl Fn(u32) -> u32,
) {
    let (lo, hi) = id.row().band_with_tolerance();
    let (late, k) = decel_count(settle, 3, lo, trigger);
    let (early, _) = decel_count(settle, 3, hi, trigger);
    // Decelerating from pulse j makes the move j + pa_part(j) pulses long.
    assert_eq!(
        late,
        k + 1 + pa_part(k + 1),
        "{id:?}: not yet started {lo} ahead"
    );
    assert_eq!(early, k + pa_part(k), "{id:?}: started within {hi}");
}

#[test]
fn s3_6_decelerating_stop_is_processed_in_17_us() {
    // At high speed: the pulse being timed and PA - 1 more.
    assert_latency(TimingId::DecelStopProcessing, MS(12), decel_stop, |_| 100);
}

#[test]
fn s3_6_high_speed_limit_is_detected_in_17_us_at_high_speed() {
    assert_latency(
        TimingId::HighSpeedLimitCruise,
        MS(12),
        high_speed_limit,
        |_| 100,
    );
}

#[test]
fn s3_6_high_speed_limit_is_detected_in_12_us_while_accelerating() {
    // From speed index j - 1 at pulse j, the ramp down takes j more pulses.
    assert_latency(
        TimingId::HighSpeedLimitAccel,
        MS(2),
        high_speed_limit,
        |j| j,
    );
}

#[rstest]
#[case::aux_on(0xC1, true, TimingId::AuxOn)]
#[case::aux_off(0xC2, false, TimingId::AuxOff)]
fn s3_6_aux_on_off_take_14_us(#[case] code: u8, #[case] on: bool, #[case] id: TimingId) {
    let mut h = Host::new();
    if !on {
        h.wc(0xC1);
        h.wait(MS(1));
    }
    let t = h.wc(code);
    h.wait(MS(1));
    let at = h
        .pin_event(Pin::Aux, u8::from(on), t)
        .expect("AUX* changed");
    assert_in_row(id, at.saturating_since(t));
}

#[test]
fn s3_6_single_step_takes_112_us() {
    let mut h = ready();
    let t = h.start(
        MoveCommand::new(MoveKind::SingleStep, Direction::Cw, true),
        None,
        None,
    );
    h.run_to_end();
    assert_in_row(TimingId::SingleStep, h.now().saturating_since(t));
    // The next command is taken at once.
    let w = h.wc(0x81);
    h.await_flag(Status::IBF, false, MS(1)).expect("taken");
    assert!(h.now().saturating_since(w) <= US(6));
}

#[rstest]
#[case::constant(MoveKind::Constant)]
#[case::continuous(MoveKind::ContinuousConstant)]
#[case::origin(MoveKind::OriginSearch)]
fn s3_6_constant_speed_first_pout_is_194_us(#[case] kind: MoveKind) {
    let mut h = ready();
    let steps = (kind == MoveKind::Constant).then_some(10);
    let t = h.start(MoveCommand::new(kind, Direction::Cw, true), Some(50), steps);
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wait(MS(1));
    assert_in_row(
        TimingId::ConstantFirstPout,
        h.first_pulse().saturating_since(t),
    );
}

fn finished_move() -> Host {
    let mut h = ready();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(300),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h
}

#[test]
fn s3_6_next_command_is_accepted_156_us_after_the_final_pout() {
    let mut h = finished_move();
    h.await_idle();
    h.wc_now(0x81);
    h.await_flag(Status::IBF, false, MS(1)).expect("taken");
    assert_in_row(
        TimingId::NextCommand,
        h.now().saturating_since(h.last_pulse()),
    );
}

#[test]
fn s3_6_interrupt_is_output_26_us_after_the_final_pout() {
    let mut h = finished_move();
    let t = h.now();
    h.await_idle();
    let int = h.pin_event(Pin::Int, 1, t).expect("INT asserted");
    assert_in_row(
        TimingId::InterruptOutput,
        int.saturating_since(h.last_pulse()),
    );
    assert_eq!(
        h.pin_event(Pin::Busy, 0, t),
        Some(int),
        "BUSY falls with INT"
    );
}

#[test]
fn s3_6_hold_turns_on_3_4_ms_after_the_final_pout() {
    let mut h = finished_move();
    let t = h.now();
    h.await_idle();
    h.wait(MS(5));
    let hold = h.pin_event(Pin::Hold, 1, t).expect("HOLD on");
    assert_in_row(TimingId::HoldOn, hold.saturating_since(h.last_pulse()));
}

#[test]
fn s3_6_excitation_off_takes_18_us() {
    let mut h = ready();
    let t = h.wc(0xC0);
    h.wait(MS(1));
    let off = h.pin_event(Pin::Phases, 0, t).expect("phases off");
    assert_in_row(TimingId::ExcitationOff, off.saturating_since(t));
}

#[rstest]
#[case::single_step(MoveKind::SingleStep)]
#[case::accel(MoveKind::AccelDecel)]
#[case::constant(MoveKind::Constant)]
#[case::continuous(MoveKind::ContinuousConstant)]
#[case::continuous_high(MoveKind::ContinuousHigh)]
#[case::origin(MoveKind::OriginSearch)]
fn s3_6_busy_rises_27_to_112_us_after_the_final_write(#[case] kind: MoveKind) {
    let mut h = ready();
    let (rate, steps) = match kind {
        MoveKind::SingleStep | MoveKind::ContinuousHigh => (None, None),
        MoveKind::AccelDecel => (None, Some(10)),
        MoveKind::Constant => (Some(50), Some(10)),
        _ => (Some(50), None),
    };
    let t: Instant = h.start(MoveCommand::new(kind, Direction::Cw, true), rate, steps);
    let waited = h.await_flag(Status::BUSY, true, MS(1)).expect("BUSY rises");
    assert_in_row(TimingId::BusyRise, h.now().saturating_since(t));
    assert_eq!(waited, h.now().saturating_since(t));
}
