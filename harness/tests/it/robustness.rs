//! Random bus traffic never panics, hangs or breaks the basic invariants of
//! Section 3-1-1. (The full invariant oracle and the cargo-fuzz targets come
//! with the fuzzing issue; this guards the model meanwhile.)

use ppmc::emu::{Chip, ModelConfig};
use ppmc::protocol::{Input, StatusField, Straps};
use ppmc::time::{Duration, Instant};
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Step {
    Command(u8),
    Data(u8),
    Read,
    Wait(u64),
    Input(usize, bool),
    Init,
    /// A whole, well-formed move: command code and its data bytes.
    Move(u8, Vec<u8>),
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        // Command bytes biased towards defined codes.
        prop_oneof![
            any::<u8>(),
            prop::sample::select(vec![
                0x02u8, 0x40, 0x41, 0x43, 0x44, 0x45, 0x46, 0x47, 0x4A, 0x80, 0x83, 0xC0, 0xC3,
                0xC6
            ]),
        ]
        .prop_map(Step::Command),
        any::<u8>().prop_map(Step::Data),
        Just(Step::Read),
        // Mostly short waits, so that checks land inside moves and between
        // a command and its first pulse; some long ones to finish moves.
        (0u64..300_000).prop_map(Step::Wait),
        (0u64..300_000).prop_map(Step::Wait),
        (0u64..20_000_000).prop_map(Step::Wait),
        (0usize..10, any::<bool>()).prop_map(|(i, b)| Step::Input(i, b)),
        Just(Step::Init),
        (
            prop::sample::select(vec![
                (0x43u8, 3usize),
                (0x44, 4),
                (0x45, 1),
                (0x46, 0),
                (0x47, 1),
                (0x4A, 0),
                (0xC3, 3),
                (0xC6, 0),
                (0x5B, 3),
                (0x4E, 0),
            ]),
            any::<u8>(),
            0u8..3,
            1u8..255,
        )
            .prop_map(|((code, n), lo, mid, rate)| {
                let params = match n {
                    3 => vec![lo, mid, 0],
                    4 => vec![rate, lo, mid, 0],
                    1 => vec![rate],
                    _ => vec![],
                };
                Step::Move(code, params)
            }),
        Just(Step::Move(0x40, vec![])),
        Just(Step::Move(0x41, vec![])),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn s3_1_1_random_traffic_keeps_the_status_register_legal(steps in prop::collection::vec(step(), 1..60)) {
        let mut chip = Chip::new(Straps::default(), ModelConfig::default()).expect("chip");
        let mut last_time = Instant::ZERO;
        let mut last_pulses = 0;
        for s in steps {
            match s {
                Step::Command(b) => chip.write_command(b),
                Step::Data(b) => chip.write_data(b),
                Step::Read => { chip.read_data(); }
                Step::Wait(ns) => {
                    let to = chip.now() + Duration::from_nanos(ns);
                    chip.advance_to(to);
                }
                Step::Input(i, b) => chip.set_input(Input::ALL[i], b),
                Step::Move(code, params) => {
                    chip.write_command(code);
                    for b in params {
                        let to = chip.now() + Duration::from_micros(10);
                        chip.advance_to(to);
                        chip.write_data(b);
                    }
                }
                Step::Init => {
                    for (k, b) in [0x02u8, 100, 20, 100, 0].into_iter().enumerate() {
                        if k == 0 { chip.write_command(b) } else { chip.write_data(b) }
                        let to = chip.now() + Duration::from_millis(200);
                        chip.advance_to(to);
                    }
                }
            }
            let st = chip.read_status();
            prop_assert!(!st.reserved(), "bit 3 set: {st:?}");
            if let StatusField::ParamsRemaining(n) = st.field() {
                prop_assert!(n <= 4, "parameter count {n}");
            }
            prop_assert!(chip.now() >= last_time);
            last_time = chip.now();
            let pulses = chip.record().pulse_count();
            prop_assert!(pulses >= last_pulses);
            last_pulses = pulses;
            if let Some(next) = chip.poll_at() {
                prop_assert!(next >= chip.now(), "poll_at in the past");
                // poll_at is honest: nothing observable changes before it.
                if next > chip.now() + Duration::from_nanos(1) {
                    let mut probe = chip.clone();
                    let (s0, p0) = (probe.read_status(), probe.pins());
                    probe.advance_to(next - Duration::from_nanos(1));
                    let (s1, p1) = (probe.read_status(), probe.pins());
                    prop_assert_eq!(s0, s1, "status changed before poll_at {}", next);
                    prop_assert_eq!((p0.int, p0.hold, p0.aux, p0.auxo, p0.busy, p0.dir), (p1.int, p1.hold, p1.aux, p1.auxo, p1.busy, p1.dir), "pins changed before poll_at {}", next);
                }
            }
        }
        // Pulse times never go backward.
        let times: Vec<Instant> = chip.record().pulses().map(|(t, _)| t).take(100_000).collect();
        prop_assert!(times.windows(2).all(|w| w[0] < w[1]));
        // Waiting as long as possible terminates.
        chip.advance_to(chip.now() + Duration::from_secs(10));
    }
}
