//! Every message and op through bytes and back, and what does not decode.

use super::bytes::W;
use super::message::*;
use super::ops::{op, put_reply};
use super::*;
use crate::bus::{Op, Reply, SelfTestPlan, SelfTestReply, Uncertainty};
use crate::protocol::capture::MoveStart;
use crate::protocol::{
    Direction, Input, MoveKind, Pin, PinEvent, Pins, PulseRun, PulseSummary, Status, Straps,
    Winding,
};
use crate::time::{Duration, Instant};
use alloc::boxed::Box;
use alloc::vec;
use alloc::vec::Vec;
use proptest::prelude::*;

const T: Timer = Timer::NANOS;

#[test]
fn ticks_survive_the_trip_through_nanoseconds() {
    for hz in [
        1_000_000,
        16_000_000,
        48_000_000,
        72_000_000,
        84_000_000,
        168_000_000,
        480_000_000,
    ] {
        let t = Timer { hz };
        for k in (0..2_000).chain([u64::from(u32::MAX), 1 << 40]) {
            assert_eq!(t.to_ticks(t.to_nanos(k)), k, "{hz} Hz, {k} ticks");
        }
    }
}

#[test]
fn a_16mhz_timer_converts_both_ways() {
    let t = Timer { hz: 16_000_000 };
    let ops = Request::Batch(vec![Op::Delay(Duration::from_micros(250))]);
    let bytes = ops.encode(1, t);
    // 250 us = 4,000 ticks of 62.5 ns.
    assert_eq!(&bytes[5..13], &4_000u64.to_le_bytes());
    assert_eq!(Request::decode(&bytes, t), Ok((1, ops)));
}

fn sample_ops() -> Vec<Op> {
    vec![
        Op::WriteCommand {
            byte: 0x43,
            wait_ibf: Some(Duration::from_secs(1)),
        },
        Op::WriteData {
            byte: 0xE7,
            wait_ibf: None,
        },
        Op::ReadStatus,
        Op::ReadData {
            wait_obf: Some(Duration::from_millis(100)),
        },
        Op::Delay(Duration::from_micros(250)),
        Op::AwaitStatus {
            mask: 4,
            value: 0,
            timeout: Duration::from_secs(2),
        },
        Op::SetInput {
            input: Input::Auxi3,
            asserted: true,
        },
        Op::ReadPins,
        Op::ReadPulses,
        Op::AwaitPulses {
            count: 500,
            timeout: Duration::from_secs(60),
        },
        Op::Reset,
    ]
}

/// Section 7: a run's jitter is a bound, so it is rounded up on the
/// way to ticks and back, and grows by the two nanoseconds that start
/// and span may each lose when a tick is not a whole number of them;
/// a run of no pulses, or a single pulse that spans time, is refused.
#[test]
fn run_bounds_survive_a_timer_that_is_not_in_nanoseconds() {
    let t = Timer { hz: 133_333_333 }; // 7.5 ns a tick
    let run = PulseRun {
        start: Instant::from_nanos(t.to_nanos(1_000)),
        count: 1_000,
        dir: Direction::Cw,
        span: Duration::from_nanos(t.to_nanos(266_667)),
        jitter: Duration::from_nanos(8),
    };
    let two = PulseRun::exact(
        run.start,
        Duration::from_nanos(t.to_nanos(267)),
        2,
        Direction::Ccw,
    );
    let cap = Response::Capture(CaptureChunk {
        runs: vec![run, two],
        ..CaptureChunk::default()
    });
    let Ok((_, Response::Capture(back))) = Response::decode(&cap.encode(1, t), t) else {
        panic!("decodes");
    };
    assert_eq!(
        (back.runs[0].start, back.runs[0].span),
        (run.start, run.span)
    );
    // 8 ns is 1.07 ticks: 2 ticks up, 15.0000004 ns: 16 ns up, and 2 ns
    // for the conversion.
    assert_eq!(back.runs[0].jitter, Duration::from_nanos(18));
    // Two pulses are both measured: nothing between them to be off.
    assert_eq!(back.runs[1], two);
    for bad in [PulseRun { count: 0, ..two }, PulseRun { count: 1, ..two }] {
        let cap = Response::Capture(CaptureChunk {
            runs: vec![bad],
            ..CaptureChunk::default()
        });
        assert!(
            matches!(
                Response::decode(&cap.encode(1, t), t),
                Err(WireError::BadValue { .. })
            ),
            "{bad:?}"
        );
    }
}

#[test]
fn every_op_round_trips() {
    let req = Request::Batch(sample_ops());
    assert_eq!(Request::decode(&req.encode(7, T), T), Ok((7, req)));
    let h = Request::Hello {
        version: PROTOCOL_VERSION,
        host: 0x1234_5678,
    };
    assert_eq!(Request::decode(&h.encode(0, T), T), Ok((0, h)));
}

/// Another version's HELLO is read as far as its version, whatever
/// follows, so that the bridge can answer VERSION (section 3).
#[test]
fn a_hello_of_another_version_is_read_for_its_version() {
    // A version 6 host's HELLO: no host session.
    assert_eq!(
        Request::decode(&[3, kind::HELLO, 6, 0], T),
        Ok((
            3,
            Request::Hello {
                version: 6,
                host: 0
            }
        ))
    );
    // A later version's, with fields this one does not know.
    assert_eq!(
        Request::decode(&[3, kind::HELLO, 10, 0, 1, 2, 3, 4, 5, 6, 7], T),
        Ok((
            3,
            Request::Hello {
                version: 10,
                host: 0
            }
        ))
    );
    // This version's must carry the host session.
    assert!(Request::decode(&[3, kind::HELLO, PROTOCOL_VERSION as u8, 0], T).is_err());
}

#[test]
fn every_reply_round_trips() {
    let at = Instant::from_nanos(123_456);
    let pins = Pins {
        int: true,
        hold: false,
        aux: true,
        auxo: 0b1010,
        phases: 0b11000,
        phase_levels: 0b00111,
        dir: Direction::Ccw,
        busy: true,
    };
    let replies = vec![
        Reply::Written {
            at,
            waited: Duration::from_micros(6),
        },
        Reply::WriteTimedOut {
            at,
            status: Status(0x06),
        },
        Reply::Status {
            at,
            status: Status(0x84),
        },
        Reply::Data {
            at,
            byte: 0x83,
            waited: Duration::from_micros(20),
        },
        Reply::ReadTimedOut {
            at,
            status: Status(0),
        },
        Reply::Delayed { at },
        Reply::Awaited {
            at,
            waited: Duration::from_micros(60),
            status: Status(4),
        },
        Reply::AwaitTimedOut {
            at,
            status: Status(4),
        },
        Reply::InputSet { at },
        Reply::Pins { at, pins },
        Reply::Pulses {
            at,
            summary: PulseSummary {
                count: 10,
                cw: 10,
                ccw: 0,
                first: Some(at),
                last: None,
                min_interval: Some(Duration::from_micros(42)),
                max_interval: None,
                interval_bound: Duration::from_nanos(37),
            },
        },
        Reply::PulsesReached { at },
        Reply::PulsesTimedOut { at, count: 3 },
        Reply::ResetDone { at },
    ];
    // Each reply fits the worst case of the op it answers.
    let ops = sample_ops();
    let answers = |r: &Reply| -> Vec<&Op> {
        ops.iter()
            .filter(|o| {
                matches!(
                    (o, r),
                    (
                        Op::WriteCommand { .. } | Op::WriteData { .. },
                        Reply::Written { .. } | Reply::WriteTimedOut { .. }
                    ) | (Op::ReadStatus, Reply::Status { .. })
                        | (
                            Op::ReadData { .. },
                            Reply::Data { .. } | Reply::ReadTimedOut { .. }
                        )
                        | (Op::Delay(_), Reply::Delayed { .. })
                        | (
                            Op::AwaitStatus { .. },
                            Reply::Awaited { .. } | Reply::AwaitTimedOut { .. }
                        )
                        | (Op::SetInput { .. }, Reply::InputSet { .. })
                        | (Op::ReadPins, Reply::Pins { .. })
                        | (Op::ReadPulses, Reply::Pulses { .. })
                        | (
                            Op::AwaitPulses { .. },
                            Reply::PulsesReached { .. } | Reply::PulsesTimedOut { .. }
                        )
                        | (Op::Reset, Reply::ResetDone { .. })
                )
            })
            .collect()
    };
    for r in &replies {
        let mut w = W(Vec::new(), T);
        put_reply(&mut w, r);
        let ops = answers(r);
        assert!(!ops.is_empty(), "{r:?}");
        for o in ops {
            assert!(
                w.0.len() <= worst_reply_len(core::slice::from_ref(o)),
                "{r:?}"
            );
        }
    }
    let resp = Response::Batch(replies);
    assert_eq!(Response::decode(&resp.encode(9, T), T), Ok((9, resp)));
}

#[test]
fn hello_capture_and_error_round_trip() {
    let hello = Response::Hello(Box::new(Hello {
        version: 1,
        session: 0xDEAD_BEEF,
        timer_hz: 1_000_000_000,
        max_batch_ops: 256,
        max_payload: 4096,
        capture_capacity: 65_536,
        inputs_wired: 0x3FF,
        virtual_time: true,
        firmware: "ppmc-bridge-sim 0.1.0".into(),
        straps: Straps {
            sysclk_hz: 12_288_000,
            csel_high: false,
            vsel_high: true,
            ext_clock_hz: Some(500_000),
        },
        resumed: true,
        serial: "E6614C311B4E5A2F".into(),
        uncertainty: Uncertainty {
            edge: Duration::from_nanos(14),
            sampled: Duration::from_nanos(2_500),
            access: Duration::from_nanos(14),
            polled: Duration::from_nanos(1_000),
        },
    }));
    assert_eq!(Response::decode(&hello.encode(1, T), T), Ok((1, hello)));
    let working = Response::Working {
        elapsed: Duration::from_nanos(123_456_789),
    };
    assert_eq!(Response::decode(&working.encode(7, T), T), Ok((7, working)));
    let cap = Response::Capture(CaptureChunk {
        runs: vec![
            PulseRun::exact(
                Instant::from_nanos(5),
                Duration::from_nanos(42_000),
                1_000,
                Direction::Cw,
            ),
            PulseRun {
                start: Instant::from_nanos(50_000_000),
                count: 16_777_216,
                dir: Direction::Ccw,
                span: Duration::from_nanos(167_772_151_234),
                jitter: Duration::from_nanos(13),
            },
        ],
        pins: vec![PinEvent {
            at: Instant::from_nanos(9),
            pin: Pin::Switching,
            value: 1,
        }],
        moves: vec![MoveStart {
            at: Instant::from_nanos(1),
            kind: MoveKind::OriginSearch,
            dir: Direction::Ccw,
            pout: false,
            steps: 1 << 24,
            first_run: 3,
            phase_index: 7,
            winding: Winding::from_name("5ph-23"),
        }],
        overwritten_bytes: 2,
        more: true,
    });
    assert_eq!(Response::decode(&cap.encode(2, T), T), Ok((2, cap)));
    let err = Response::Error {
        code: BridgeErrorCode::CaptureOverrun,
        detail: "full".into(),
    };
    assert_eq!(Response::decode(&err.encode(3, T), T), Ok((3, err)));
}

#[test]
fn long_replies_fragment_and_reassemble() {
    let payload: Vec<u8> = (0..130u16).map(|i| i as u8).collect();
    let frags = fragment(&payload, FRAGMENT_DATA);
    assert_eq!(frags.len(), 3);
    let mut whole = Vec::new();
    for (i, f) in frags.iter().enumerate() {
        let (seq, idx, n, data) = parse_fragment(f).expect("a fragment");
        assert_eq!((seq, usize::from(idx), n), (0, i, 3));
        whole.extend_from_slice(data);
    }
    assert_eq!(whole, payload);
    assert_eq!(fragment(&[5, 1, 2], FRAGMENT_DATA), vec![vec![5, 1, 2]]);
    // Smaller fragments for a noisy line; never below the minimum, and
    // never more than 255 of them.
    let small = fragment(&payload, 10);
    assert_eq!(small.len(), 13);
    assert!(small.iter().all(|f| f.len() <= 4 + 10));
    assert_eq!(
        fragment(&payload, 1).len(),
        130_usize.div_ceil(MIN_FRAGMENT_DATA)
    );
    let long = vec![7u8; MAX_REPLY];
    assert_eq!(fragment(&long, MIN_FRAGMENT_DATA).len(), 255);
    let link = Request::Link {
        fragment: 12,
        pad: 64,
    };
    assert_eq!(Request::decode(&link.encode(6, T), T), Ok((6, link)));
    let set = Response::Link {
        fragment: 12,
        pad: 64,
    };
    assert_eq!(Response::decode(&set.encode(6, T), T), Ok((6, set)));
    let r = Request::Resend {
        fragments: vec![0, 2],
    };
    assert_eq!(Request::decode(&r.encode(4, T), T), Ok((4, r)));
    // SELF_TEST, in a bridge's ticks (75 MHz), and its reply.
    let t = Timer { hz: 75_000_000 };
    let plan = SelfTestPlan {
        count: 100,
        high: Duration::from_nanos(5_000),
        low: Duration::from_nanos(5_000),
        bursts: 3,
        gap: Duration::from_micros(200),
    };
    let st = Request::SelfTest(plan);
    assert_eq!(Request::decode(&st.encode(7, t), t), Ok((7, st)));
    let zero = Request::SelfTest(SelfTestPlan { count: 0, ..plan });
    assert!(matches!(
        Request::decode(&zero.encode(7, t), t),
        Err(WireError::BadValue {
            field: "self-test pulse count",
            ..
        })
    ));
    let none = Request::SelfTest(SelfTestPlan { bursts: 0, ..plan });
    assert!(Request::decode(&none.encode(7, t), t).is_err());
    let done = Response::SelfTest(SelfTestReply {
        starts: vec![Instant::from_nanos(120), Instant::from_nanos(1_200_040)],
        high: Duration::from_nanos(5_000),
        low: Duration::from_nanos(5_000),
    });
    assert_eq!(Response::decode(&done.encode(7, t), t), Ok((7, done)));
    // A count of starts the bytes cannot hold is refused, not allocated.
    let mut lying = Response::SelfTest(SelfTestReply {
        starts: vec![],
        high: Duration::ZERO,
        low: Duration::ZERO,
    })
    .encode(7, t);
    let n = lying.len();
    lying[n - 2..].copy_from_slice(&u16::MAX.to_le_bytes());
    assert!(Response::decode(&lying, t).is_err());
    let c = Request::Capture {
        runs: 1,
        pins: 2,
        moves: 3,
        max: 40,
    };
    assert_eq!(Request::decode(&c.encode(5, T), T), Ok((5, c)));
    let bc = Request::BatchCapture {
        ops: sample_ops(),
        runs: 4,
        pins: 5,
        moves: 6,
        max: 60,
    };
    assert_eq!(Request::decode(&bc.encode(6, T), T), Ok((6, bc)));
    let reply = Response::BatchCapture {
        replies: vec![Reply::Delayed {
            at: Instant::from_nanos(77),
        }],
        capture: CaptureChunk {
            runs: vec![],
            pins: vec![PinEvent {
                at: Instant::from_nanos(9),
                pin: Pin::Busy,
                value: 1,
            }],
            moves: vec![],
            overwritten_bytes: 0,
            more: false,
        },
    };
    assert_eq!(Response::decode(&reply.encode(6, T), T), Ok((6, reply)));
}

#[test]
fn bad_messages_say_where() {
    assert_eq!(
        Request::decode(&[1], T),
        Err(WireError::Truncated { at: 1, wanted: 1 })
    );
    assert_eq!(
        Request::decode(&[1, 0x77], T),
        Err(WireError::UnknownKind(0x77))
    );
    assert_eq!(
        Request::decode(&[1, kind::BATCH, 1, 0, 0x99], T),
        Err(WireError::UnknownCode { at: 4, code: 0x99 })
    );
    let mut ok = Request::Hello {
        version: PROTOCOL_VERSION,
        host: 1,
    }
    .encode(1, T);
    ok.push(0);
    assert_eq!(Request::decode(&ok, T), Err(WireError::Trailing(1)));
    // A count that promises more than the bytes could hold.
    assert!(matches!(
        Response::decode(&[1, kind::BATCH_REPLY, 0xFF, 0xFF], T),
        Err(WireError::BadValue { field: "count", .. })
    ));
}

fn pins(phases: u8) -> Pins {
    Pins {
        int: false,
        hold: true,
        aux: false,
        auxo: 0,
        phases,
        phase_levels: !phases & 0x1F,
        dir: Direction::Cw,
        busy: true,
    }
}

#[test]
fn pin_samples_go_as_sample_ops_and_samples_entries() {
    let step = Duration::from_nanos(250);
    let mut ops = vec![Op::Reset];
    for _ in 0..1500 {
        ops.extend([Op::ReadPins, Op::Delay(step)]);
    }
    ops.push(Op::ReadPins);
    // 1,500 samples: two SAMPLEs of the most, one of the rest; the lone
    // read at the end stays a PINS op.
    assert_eq!(
        wire_ops(&ops),
        vec![1, 2 * MAX_SAMPLES, 2 * MAX_SAMPLES, 2 * 476, 1]
    );
    let req = Request::Batch(ops);
    let bytes = req.encode(3, T);
    assert!(bytes.len() < 40, "{} bytes", bytes.len());
    assert_eq!(Request::decode(&bytes, T), Ok((3, req)));

    // Replies on one grid: the phases change every 7 samples.
    let mut replies = vec![Reply::ResetDone {
        at: Instant::from_nanos(10),
    }];
    for i in 0..1500u64 {
        let at = Instant::from_nanos(10 + 250 * i);
        let p = pins(1 << ((i / 7) % 4));
        replies.extend([
            Reply::Pins { at, pins: p },
            Reply::Delayed {
                at: Instant::from_nanos(10 + 250 * (i + 1)),
            },
        ]);
    }
    let resp = Response::Batch(replies.clone());
    let bytes = resp.encode(3, T);
    // 215 runs of 6 bytes, not 3,000 entries of 9 to 13.
    assert!(bytes.len() < 1_400, "{} bytes", bytes.len());
    assert_eq!(Response::decode(&bytes, T), Ok((3, resp)));

    // Off the grid (a read late by 1 ns), the run stops there and the
    // rest still comes back exact.
    if let Some(Reply::Pins { at, .. }) = replies.get_mut(2 * 700 + 1) {
        *at = Instant::from_nanos(at.as_nanos() + 1);
    }
    let resp = Response::Batch(replies);
    assert_eq!(Response::decode(&resp.encode(4, T), T), Ok((4, resp)));
}

#[test]
fn a_sample_count_out_of_range_is_refused() {
    for n in [0u16, 1, MAX_SAMPLES as u16 + 1] {
        let mut b = vec![1, kind::BATCH, 1, 0, op::SAMPLE];
        b.extend(n.to_le_bytes());
        b.extend(250u64.to_le_bytes());
        assert!(matches!(
            Request::decode(&b, T),
            Err(WireError::BadValue {
                field: "sample count",
                ..
            })
        ));
    }
}

fn arb_op() -> impl Strategy<Value = Op> {
    prop_oneof![
        Just(Op::ReadPins),
        Just(Op::ReadStatus),
        (0u64..3).prop_map(|d| Op::Delay(Duration::from_nanos(250 * d))),
    ]
}

fn arb_reply() -> impl Strategy<Value = Reply> {
    prop_oneof![
        (0u64..4, 0u8..3).prop_map(|(t, p)| Reply::Pins {
            at: Instant::from_nanos(100 * t),
            pins: pins(p),
        }),
        (0u64..4).prop_map(|t| Reply::Delayed {
            at: Instant::from_nanos(100 * t)
        }),
        (0u64..4).prop_map(|t| Reply::Status {
            at: Instant::from_nanos(100 * t),
            status: Status(0),
        }),
    ]
}

proptest! {
    #[test]
    fn any_batch_round_trips(ops in prop::collection::vec(arb_op(), 0..400)) {
        let req = Request::Batch(ops);
        prop_assert_eq!(Request::decode(&req.encode(1, T), T), Ok((1, req)));
    }

    #[test]
    fn any_reply_list_round_trips(
        mut replies in prop::collection::vec(arb_reply(), 0..400),
        grid in 0usize..200,
    ) {
        // Lay a stretch on a grid, so that SAMPLES entries occur.
        for (j, r) in replies.iter_mut().skip(grid).take(150).enumerate() {
            let k = (j / 2) as u64;
            *r = if j % 2 == 0 {
                Reply::Pins {
                    at: Instant::from_nanos(1_000 + 100 * k),
                    pins: pins((j / 10) as u8 % 3),
                }
            } else {
                Reply::Delayed { at: Instant::from_nanos(1_000 + 100 * (k + 1)) }
            };
        }
        let resp = Response::Batch(replies);
        prop_assert_eq!(Response::decode(&resp.encode(1, T), T), Ok((1, resp)));
    }
}

proptest! {
    #[test]
    fn arbitrary_payloads_never_panic(b in prop::collection::vec(any::<u8>(), 0..300)) {
        let _ = Request::decode(&b, T);
        let _ = Response::decode(&b, T);
    }
}

/// The conversions as one 128-bit expression each: what `Timer`'s split
/// arithmetic must equal, to the nanosecond and the tick, so that traces
/// stay byte-identical.
fn wide(x: u128) -> u64 {
    u64::try_from(x).unwrap_or(u64::MAX)
}

proptest! {
    #[test]
    fn the_split_conversions_equal_the_128_bit_ones(
        hz in prop_oneof![
            Just(75_000_000u64),
            Just(16_000_000u64),
            Just(133_333_333u64),
            Just(1_000_000_000u64),
            Just(u64::from(u32::MAX)),
            1u64..=20_000_000_000,
        ],
        v in prop_oneof![0u64..4_000_000_000, any::<u64>()],
    ) {
        let t = Timer { hz };
        let (v1, h) = (u128::from(v), u128::from(hz));
        let g = 1_000_000_000u128;
        prop_assert_eq!(t.to_ticks(v), wide((v1 * h + g / 2) / g));
        prop_assert_eq!(t.to_ticks_up(v), wide((v1 * h).div_ceil(g)));
        prop_assert_eq!(t.to_nanos(v), wide(v1 * g / h));
        prop_assert_eq!(t.to_nanos_up(v), wide((v1 * g).div_ceil(h)));
        // The prepared divisions give the same, to the tick and the
        // nanosecond.
        let f = FastTimer::new(t);
        prop_assert_eq!(f.to_ticks(v), t.to_ticks(v));
        prop_assert_eq!(f.to_nanos(v), t.to_nanos(v));
        prop_assert_eq!(f.to_nanos_up(v), t.to_nanos_up(v));
    }
}
