//! Section 3-5 behaviour the scenarios cannot see or do not check: the
//! stop-switching and HOLD pin edges against the move, sampled inside the
//! model. The rest of Section 3-5 (switching times, Equations 3-5 and 3-6,
//! AUX* ON / OFF, AUXO, software reset and recovery) is proven by the
//! scenarios in `scenarios/src/s3_5_auxiliary.rs`, on the emulator and on
//! any board.

use ppmc_test_support as common;

use common::*;
use ppmc::protocol::{Direction, MoveCommand, MoveKind, Pin, Status};
use ppmc::scenario::Init;
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
fn s3_5_1_no_switching_without_the_init_bit_and_none_while_moving() {
    let mut h = Host::new();
    h.init_example();
    let (on, off) = chopping(&mut h, US(5), MS(1));
    assert!(on.is_empty() && off.is_empty(), "steady when bit 5 = 0");

    let mut h = Host::new();
    h.init(Init::four_phase().stop_switching().code(), EXAMPLE_INIT);
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
