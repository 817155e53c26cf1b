//! Fuzz target bodies. Each `fuzz/fuzz_targets/*.rs` is one line calling a
//! function here, so that `cargo test` on stable replays every committed
//! input in `fuzz/corpus/<target>/` and `fuzz/regressions/<target>/`
//! through the same code (`harness/tests/fuzz_corpus.rs`).

pub mod bus;
pub mod oracle;

use crate::bridge::frame::{self, FrameDecoder};
use crate::bridge::wire::{Request, Response, Timer};
use crate::emu::ModelConfig;

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

/// Bus byte stream (see [`bus`]) into a fresh emulator; every invariant of
/// `docs/invariants.md` checked after every op. A break panics with the
/// invariant's id first, so libFuzzer's crash message buckets it.
pub fn bus_bytes(data: &[u8]) {
    bus_bytes_with(data, ModelConfig::default());
}

/// [`bus_bytes`] on a model with a configuration (e.g. an injected fault).
pub fn bus_bytes_with(data: &[u8], cfg: ModelConfig) {
    let ops = bus::decode(data);
    match oracle::check(&ops, cfg) {
        Ok(None) => {}
        Ok(Some(v)) => panic!("invariant {v}"),
        Err(e) => panic!("the model refused its configuration: {e}"),
    }
}
