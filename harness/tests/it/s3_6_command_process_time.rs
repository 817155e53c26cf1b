//! Section 3-6, Table 3-3, where the scenarios measure a row once and these
//! sweep it: the initialization time growing with PA across its band, the
//! first POUT growing with the triangle, the 194 us first POUT for every
//! constant-speed kind of move, and BUSY rising within 27-112 us for every
//! kind of move. Every row of Table 3-3 is measured and graded by a
//! scenario (`scenarios/src/*.rs`, `expect_latency`).

use ppmc_test_support as common;

use common::*;
use ppmc::protocol::{Direction, InitData, MoveCommand, MoveKind, Register, Status, TimingId};
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
    h.wc(Register::InputSignals.code());
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
