//! The seed corpora of the fuzz targets (`fuzz/corpus/<target>/`), made
//! from what each target exercises: every message of the bridge protocol
//! framed (`frame_decoder`), the bus traffic of every conformance scenario
//! as fuzz ops (`bus_bytes`), seeded random typed programs
//! (`typed_actions`), suite traces as text and as ops (`trace_text`).
//! Deterministic: `ppmc fuzz seeds` writes them after a protocol or
//! scenario change, and a test holds the committed corpora to them.

use crate::backend::{EmuTarget, Op};
use crate::bridge::sim::engine;
use crate::protocol::{Input, Straps};
use crate::time::Duration;
use crate::trace::Trace;
use ppmc_core::bridge::frame::encode;
use ppmc_core::bridge::wire::{fragment, Request, Timer};

/// A seed: the target's corpus folder name, the file's name, its bytes.
pub type Seed = (&'static str, String, Vec<u8>);

/// Every target's seeds; `suite` is each scenario's name and trace on
/// the emulator (the suite's traffic seeds `bus_bytes` and `trace_text`).
pub fn all(suite: &[(&str, Trace)]) -> Result<Vec<Seed>, String> {
    let mut seeds: Vec<Seed> = Vec::new();
    let mut add = |target: &'static str, list: Vec<(String, Vec<u8>)>| {
        seeds.extend(list.into_iter().map(|(name, bytes)| (target, name, bytes)));
    };
    add("frame_decoder", frame_decoder()?);
    add("bus_bytes", bus_bytes(suite));
    add("typed_actions", typed_actions());
    add("trace_text", trace_text(suite));
    Ok(seeds)
}

/// One framed message of every kind and the bridge's answer to each, long
/// replies in fragments, and some line noise.
pub fn frame_decoder() -> Result<Vec<(String, Vec<u8>)>, String> {
    let t = Timer::NANOS;
    let ops = vec![
        Op::Reset,
        Op::WriteCommand {
            byte: 0x02,
            wait_ibf: Some(Duration::from_secs(1)),
        },
        Op::WriteData {
            byte: 100,
            wait_ibf: None,
        },
        Op::ReadStatus,
        Op::ReadData {
            wait_obf: Some(Duration::from_millis(100)),
        },
        Op::Delay(Duration::from_millis(200)),
        Op::AwaitStatus {
            mask: 4,
            value: 4,
            timeout: Duration::from_millis(5),
        },
        Op::SetInput {
            input: Input::L1,
            asserted: true,
        },
        Op::ReadPins,
        Op::ReadPulses,
        Op::AwaitPulses {
            count: 10,
            timeout: Duration::from_secs(1),
        },
    ];
    let requests = [
        Request::Hello {
            version: ppmc_core::bridge::wire::PROTOCOL_VERSION,
            host: 0x5EED_0001,
        },
        Request::Batch(ops.clone()),
        // Pin samples: a SAMPLE op, answered with a SAMPLES entry.
        Request::Batch(
            (0..40)
                .flat_map(|_| [Op::ReadPins, Op::Delay(Duration::from_micros(7))])
                .collect(),
        ),
        Request::Capture {
            runs: 0,
            pins: 0,
            moves: 0,
            max: 40,
        },
        Request::Resend {
            fragments: vec![0, 2],
        },
        Request::Link {
            fragment: 12,
            pad: 64,
        },
    ];
    let emu = EmuTarget::new(Straps::default(), Default::default()).map_err(|e| e.to_string())?;
    let mut server = engine(emu, 1, true);
    let mut seeds = Vec::new();
    let mut put = |name: &str, bytes: &[u8]| seeds.push((name.to_string(), bytes.to_vec()));
    for (i, r) in requests.iter().enumerate() {
        let frame = encode(&r.encode(i as u8 + 1, t));
        put(&format!("request-{i}"), &frame);
        // The bridge's answer: whole or in fragments.
        let answer = server.on_bytes(&frame);
        put(&format!("response-{i}"), &answer);
    }
    let big: Vec<u8> = (0..300u16).map(|x| x as u8).collect();
    let frags: Vec<u8> = fragment(&big, ppmc_core::bridge::wire::FRAGMENT_DATA)
        .iter()
        .flat_map(|f| encode(f))
        .collect();
    put("fragments", &frags);
    let mut bad = encode(
        &Request::Hello {
            version: 1,
            host: 0,
        }
        .encode(9, t),
    );
    bad[2] ^= 0x10;
    put("bad-crc", &bad);
    put(
        "noise-then-frame",
        &[&[0x13, 0x77, 0x00][..], &encode(b"\x01\x01\x01\x00")].concat(),
    );
    put("empty-frames", &[0, 0, 0]);
    Ok(seeds)
}

/// The bus traffic of every conformance scenario, as fuzz ops.
pub fn bus_bytes(suite: &[(&str, Trace)]) -> Vec<(String, Vec<u8>)> {
    suite
        .iter()
        .map(|(name, trace)| {
            let ops = crate::bus_program::from_trace(trace);
            (format!("{name}.bin"), crate::bus_program::encode(&ops))
        })
        .collect()
}

/// The bus traffic of every scenario of `suite` as it runs on the
/// emulator: the seeds of a campaign against a board.
pub fn suite_traffic(suite: &[crate::scenario::Scenario]) -> Result<Vec<Vec<u8>>, String> {
    let mut emu =
        EmuTarget::new(Straps::default(), Default::default()).map_err(|e| e.to_string())?;
    let results = crate::runner::run_suite(&mut emu, suite, 1, Default::default(), |_| {});
    let traces: Vec<_> = results
        .into_iter()
        .filter_map(|r| Some((r.name, r.trace?)))
        .collect();
    Ok(bus_bytes(&traces).into_iter().map(|(_, b)| b).collect())
}

/// Seeded random bytes, each decoding to a few dozen typed actions.
pub fn typed_actions() -> Vec<(String, Vec<u8>)> {
    use rand::{Rng, SeedableRng};
    (0..24u64)
        .map(|seed| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let len = rng.random_range(64..384);
            let bytes: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            (format!("random-{seed:02}.bin"), bytes)
        })
        .collect()
}

/// A few suite traces as text, and a few scenarios' bus traffic as ops,
/// whose emulator traces the target round-trips.
pub fn trace_text(suite: &[(&str, Trace)]) -> Vec<(String, Vec<u8>)> {
    let text = suite
        .iter()
        .step_by(10)
        .map(|(name, trace)| (format!("{name}.trace"), trace.render().into_bytes()));
    let ops = suite.iter().skip(5).step_by(16).map(|(name, trace)| {
        let ops = crate::bus_program::from_trace(trace);
        (format!("ops-{name}.bin"), crate::bus_program::encode(&ops))
    });
    text.chain(ops).collect()
}
