//! The fuzz target bodies: one function per target, named after it. Each
//! `fuzz/fuzz_targets/<target>.rs` is one line calling
//! `ppmc::fuzzing::targets::<target>`, so that `cargo test` on stable
//! replays every committed input in `fuzz/corpus/<target>/` and
//! `fuzz/regressions/<target>/` through the same code
//! (`harness/tests/it/fuzz_corpus.rs`, `harness/tests/it/model_twin.rs`).

use super::actions::{lower, typed_program};
use crate::bridge::frame::{self, FrameDecoder};
use crate::bridge::wire::{Request, Response, Timer};
use crate::bus_program;
use crate::emu::ModelConfig;
use crate::invariants::oracle;
use crate::plain_model::twin;
use crate::protocol::Straps;

/// The bridge link's frame decoder and message decoders on arbitrary
/// bytes: never a panic; every frame that decodes re-encodes to the same
/// payload; every message that decodes re-encodes to bytes that decode to
/// the same message.
pub fn frame_decoder(data: &[u8]) {
    let mut d = FrameDecoder::new();
    // Feed in two pieces, as a serial port would deliver them.
    let cut = data.first().map_or(0, |b| usize::from(*b)).min(data.len());
    d.extend(&data[..cut]);
    let mut frames = Vec::new();
    for piece in [&data[cut..], &[][..]] {
        d.extend(piece);
        for _ in 0..=data.len() {
            match d.decode() {
                Ok(Some(p)) => frames.push(p),
                Ok(None) => break,
                Err(_) => {}
            }
        }
    }
    for p in frames {
        let mut again = FrameDecoder::new();
        again.extend(&frame::encode(&p));
        assert_eq!(again.decode(), Ok(Some(p.clone())), "frame round trip");
        for timer in [Timer::NANOS, Timer { hz: 16_000_000 }] {
            if let Ok((seq, req)) = Request::decode(&p, timer) {
                assert_eq!(
                    Request::decode(&req.encode(seq, timer), timer),
                    Ok((seq, req))
                );
            }
            if let Ok((seq, resp)) = Response::decode(&p, Timer::NANOS) {
                let bytes = resp.encode(seq, Timer::NANOS);
                assert_eq!(Response::decode(&bytes, Timer::NANOS), Ok((seq, resp)));
            }
        }
    }
}

/// Bus byte stream (see [`crate::bus_program`]) into a fresh emulator; every invariant of
/// `docs/invariants.md` checked after every op. A break panics with the
/// invariant's id first, so libFuzzer's crash message buckets it.
pub fn bus_bytes(data: &[u8]) {
    verdict(oracle::check_ops_default(bus_program::ops(data)));
}

/// [`bus_bytes()`] on a model with a configuration (e.g. an injected fault).
pub fn bus_bytes_with(data: &[u8], cfg: ModelConfig) {
    verdict(oracle::check_ops(bus_program::ops(data), cfg));
}

/// A `bus_bytes` input's verdict: a panic on a break.
fn verdict(v: Result<Option<crate::invariants::rules::Violation>, crate::emu::ChipError>) {
    match v {
        Ok(None) => {}
        Ok(Some(v)) => panic!("invariant {v}"),
        Err(e) => panic!("the model refused its configuration: {e}"),
    }
}

/// Structure-aware target: the input's bytes as typed
/// [`Action`](super::actions::Action)s
/// (derive `Arbitrary`) after a valid initialization, run with the
/// flowchart's waits on a fresh emulator under the same oracle as
/// [`bus_bytes()`].
pub fn typed_actions(data: &[u8]) {
    typed_actions_with(data, ModelConfig::default());
}

/// [`typed_actions`] on a model with a configuration.
pub fn typed_actions_with(data: &[u8], cfg: ModelConfig) {
    let (_, found) = lower(&typed_program(data), cfg);
    if let Some(v) = found {
        panic!("invariant {v}");
    }
}

/// The trace format, both ways. An input that starts like a trace
/// (`ppmc-trace`) is text for the parser: never a panic, and a text that
/// parses renders to a text that parses to the same trace and renders to
/// the same bytes. Any other input is a `bus_bytes` input run on a fresh
/// emulator, whose trace must render to text that parses back to the same
/// trace, byte for byte: the check that every emulator trace round-trips,
/// which the `bus_bytes` target used to pay for on every input.
pub fn trace_text(data: &[u8]) {
    use crate::trace::Trace;
    let round_trip = |t: &Trace| {
        let once = t.render();
        let again = Trace::parse(&once).expect("a rendered trace parses");
        assert_eq!(again.render(), once, "trace render round trip");
    };
    if data.starts_with(b"ppmc-trace") {
        if let Ok(Ok(t)) = std::str::from_utf8(data).map(Trace::parse) {
            round_trip(&t);
        }
        return;
    }
    let Ok(mut chip) = crate::emu::Board::new(Straps::default(), ModelConfig::default()) else {
        return;
    };
    for op in bus_program::decode(data) {
        bus_program::apply(&mut chip, op);
    }
    let t = Trace::new("fuzz", "-", "emu", Straps::default(), Vec::new()).assemble(
        Vec::new(),
        chip.record(),
        Vec::new(),
    );
    round_trip(&t);
}

/// The emulator against the plain model ([`twin::check`]) on one input
/// in the bus-byte format ([`crate::bus_program::decode`]), at the default straps and
/// model. Inputs are cut at [`MODEL_TWIN_MAX_OPS`] ops, so that each runs
/// in bounded time.
pub fn model_twin(data: &[u8]) {
    let ops = bus_program::decode(data);
    let ops = &ops[..ops.len().min(MODEL_TWIN_MAX_OPS)];
    if let Err(d) = twin::check(ops, Straps::default(), &ModelConfig::default()) {
        panic!("model-twin: {d}");
    }
}

/// Ops of one input the `model_twin` target compares.
pub const MODEL_TWIN_MAX_OPS: usize = 64;
