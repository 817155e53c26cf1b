//! Section 3-5: switching parameters, AUX* ON/OFF, auxiliary outputs and the
//! software reset.

mod common;

use common::*;
use ppmc::protocol::{Direction, ErrorCode, MoveCommand, MoveKind, Pin, Status};
use ppmc::time::{Duration, Instant};

/// Samples the energized phases every `step` for `span` and returns the
/// lengths of the ON and OFF stretches seen (after the first full cycle).
fn chopping(h: &mut Host, step: Duration, span: Duration) -> (Vec<u64>, Vec<u64>) {
    let mut samples = Vec::new();
    let end = h.now() + span;
    while h.now() < end {
        samples.push(h.chip().pins().phases != 0);
        h.wait(step);
    }
    let mut on = Vec::new();
    let mut off = Vec::new();
    let mut run = 0u64;
    for w in samples.windows(2) {
        run += step.as_nanos();
        if w[0] != w[1] {
            if w[0] {
                on.push(run)
            } else {
                off.push(run)
            }
            run = 0;
        }
    }
    // Drop the first (partial) stretch of each kind.
    (
        on.into_iter().skip(1).collect(),
        off.into_iter().skip(1).collect(),
    )
}

#[test]
fn s3_5_1_default_switching_is_65_us_on_108_75_us_off() {
    let mut h = Host::new();
    h.init(INIT_4PH | 0x20, EXAMPLE_INIT);
    let (on, off) = chopping(&mut h, Duration::from_nanos(250), MS(2));
    assert!(!on.is_empty() && !off.is_empty());
    assert!(on.iter().all(|d| d.abs_diff(65_000) <= 250), "{on:?}");
    assert!(off.iter().all(|d| d.abs_diff(108_750) <= 250), "{off:?}");
}

#[test]
fn s3_5_1_switching_parameters_follow_equations_3_5_and_3_6() {
    let mut h = Host::new();
    h.send(0x84, &[10, 20]); // Ton = 10 x 3 + 27 = 57 us, Toff = 20 x 3 + 33 = 93 us
    assert_eq!(h.settled_status().error(), None);
    h.init(INIT_4PH | 0x20, EXAMPLE_INIT);
    let (on, off) = chopping(&mut h, Duration::from_nanos(500), MS(2));
    assert!(on.iter().all(|d| d.abs_diff(57_000) <= 500), "{on:?}");
    assert!(off.iter().all(|d| d.abs_diff(93_000) <= 500), "{off:?}");
}

#[test]
fn s3_5_1_no_switching_without_the_init_bit_and_none_while_moving() {
    let mut h = Host::new();
    h.init_example();
    let (on, off) = chopping(&mut h, US(5), MS(1));
    assert!(on.is_empty() && off.is_empty(), "steady when bit 5 = 0");

    let mut h = Host::new();
    h.init(INIT_4PH | 0x20, EXAMPLE_INIT);
    let t = h.start(
        MoveCommand::new(MoveKind::Constant, Direction::Cw, true),
        Some(50),
        Some(100),
    );
    h.run_to_end();
    let off = h
        .pin_event(Pin::Switching, 0, t)
        .expect("switching stops for the move");
    let on = h.pin_event(Pin::Switching, 1, t);
    assert!(off <= h.first_pulse());
    assert!(
        on.is_none(),
        "not yet: HOLD comes 3.4 ms after the last pulse"
    );
    h.wait(MS(4));
    let on = h
        .pin_event(Pin::Switching, 1, t)
        .expect("switching resumes at HOLD");
    assert_eq!(on.saturating_since(h.last_pulse()), US(3_400));
}

#[test]
fn s3_5_2_aux_on_off_work_before_initialization() {
    let mut h = Host::new();
    assert!(!h.chip().pins().aux, "AUX* high after reset");
    h.wc(0xC1);
    h.wait(US(20));
    assert!(h.chip().pins().aux);
    assert_eq!(h.status().error(), None);
    h.wc(0xC2);
    h.wait(US(20));
    assert!(!h.chip().pins().aux);
}

#[test]
fn s3_5_2_aux_on_is_accepted_while_busy() {
    let mut h = Host::new();
    h.init_example();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(500),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wc(0xC1);
    h.wait(US(20));
    assert!(h.chip().pins().aux);
    assert_eq!(h.status().error(), None);
    h.await_idle();
    assert_eq!(h.pulses(), 500, "the move is not disturbed");
}

#[test]
fn s3_5_3_aux_output_drives_auxo_low_for_each_1_bit_even_while_busy() {
    let mut h = Host::new();
    assert_eq!(h.chip().pins().auxo, 0, "all high after reset");
    h.send(0x86, &[0b0101]);
    h.wait(US(20));
    assert_eq!(h.chip().pins().auxo, 0b0101);
    h.init_example();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(500),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.send(0x86, &[0xFA]); // upper nibble ignored
    h.wait(US(20));
    assert_eq!(h.chip().pins().auxo, 0b1010);
    assert_eq!(h.status().error(), None);
}

#[test]
fn s3_5_4_software_reset_turns_the_phases_off_and_cancels_initialization() {
    let mut h = Host::new();
    h.init_example();
    assert_ne!(h.chip().pins().phases, 0);
    let t = h.wc(0xC0);
    h.wait(US(30));
    assert_eq!(h.chip().pins().phases, 0, "motor freed");
    let off = h.pin_event(Pin::Phases, 0, t).expect("phases off");
    assert_eq!(off.saturating_since(t), US(18));
    h.wc(0x4A);
    assert_eq!(h.settled_status().error(), Some(ErrorCode::NotInitialized));
    // A new initialization, with another excitation, is accepted.
    h.init(0x06, EXAMPLE_INIT);
    assert_eq!(
        h.chip().pins().phases,
        0b10000,
        "1-2 phase excitation starts at S1"
    );
}

#[test]
fn s3_5_4_software_reset_while_busy_is_taken_as_aux_on() {
    let mut h = Host::new();
    h.init_example();
    h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(500),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    h.wc(0xC0);
    h.await_idle();
    assert!(h.chip().pins().aux, "AUX* turned on");
    assert_eq!(h.pulses(), 500);
    assert!(h.chip().initialized(), "no reset happened");
    assert_ne!(h.chip().pins().phases, 0);
}

#[test]
fn s3_5_hold_is_off_during_a_move() {
    let mut h = Host::new();
    h.init_example();
    assert!(h.chip().pins().hold);
    let t: Instant = h.start(
        MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true),
        None,
        Some(50),
    );
    h.await_flag(Status::BUSY, true, MS(1)).expect("busy");
    assert!(!h.chip().pins().hold);
    h.await_idle();
    assert!(h.pin_event(Pin::Hold, 0, t).is_some());
}
