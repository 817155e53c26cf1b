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

/// A `bus_bytes` input as a bus script in the console language
/// (`docs/console.md`): a header naming the invariant it breaks on the
/// emulator (or saying it breaks none), then one op per line. The script
/// replays in `ppmc console` on the emulator.
pub fn reproducer(data: &[u8], source: &str) -> (String, Option<oracle::Violation>) {
    reproducer_with(data, source, ModelConfig::default())
}

/// [`reproducer`], judged on a model with a configuration.
pub fn reproducer_with(
    data: &[u8],
    source: &str,
    cfg: ModelConfig,
) -> (String, Option<oracle::Violation>) {
    let ops = bus::decode(data);
    let found = oracle::check(&ops, cfg).ok().flatten();
    let mut out = format!(
        "# reproducer of {source}: {} bytes, {} ops (fuzz target bus_bytes)\n",
        data.len(),
        ops.len()
    );
    match &found {
        Some(v) => out.push_str(&format!("# breaks: invariant {v}\n")),
        None => out.push_str("# breaks no invariant\n"),
    }
    for (i, op) in ops.iter().enumerate() {
        out.push_str(&format!("{op}"));
        if found.as_ref().is_some_and(|v| v.op == i) {
            out.push_str("  # <- the break is seen after this op");
        }
        out.push('\n');
    }
    (out, found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::console;
    use crate::emu::Faults;
    use crate::protocol::Straps;
    use crate::target::EmuTarget;
    use crate::time::Duration;
    use bus::BusOp::*;

    fn sample() -> Vec<bus::BusOp> {
        vec![
            Command(0x06),
            Advance(Duration::from_micros(40)),
            Data(100),
            Advance(Duration::from_millis(3)),
            ReadStatus,
            Input {
                input: crate::protocol::Input::L1,
                asserted: true,
            },
            ReadData,
            Advance(Duration::from_secs(2)),
            ReadStatus,
        ]
    }

    /// The printed script parses as console input, op for op, and its
    /// status reads on the emulator give the same bytes as the oracle's
    /// chip saw (the console runs the same model through the target).
    #[test]
    fn a_reproducer_replays_in_the_console() {
        let data = bus::encode(&sample());
        let (script, found) = reproducer(&data, "crash-1");
        assert_eq!(found, None);
        assert!(script.starts_with("# reproducer of crash-1"));
        let lines = console::parse_script(&script).expect("the script parses");
        assert_eq!(lines.len(), sample().len());
        let mut t = EmuTarget::new(Straps::default(), ModelConfig::default()).expect("emulator");
        let mut out = Vec::new();
        console::run(
            &mut t,
            &lines,
            &console::ConsoleOptions::default(),
            &mut out,
        )
        .expect("the script runs");
        let printed = String::from_utf8(out).expect("utf-8");
        let statuses: Vec<&str> = printed.lines().filter(|l| l.starts_with("rs ")).collect();
        assert_eq!(statuses.len(), 2, "{printed}");
    }

    #[test]
    fn a_reproducer_names_the_break_and_marks_its_op() {
        let data = bus::encode(&sample());
        let cfg = ModelConfig {
            faults: Faults {
                status_stuck_high: 0x08,
                ..Faults::default()
            },
            ..ModelConfig::default()
        };
        let (script, found) = reproducer_with(&data, "x", cfg);
        let v = found.expect("a break");
        assert_eq!((v.invariant, v.op), ("status-bit3", 4));
        assert!(script.contains("# breaks: invariant status-bit3 after op 4"));
        let marked: Vec<&str> = script.lines().filter(|l| l.contains("# <-")).collect();
        assert_eq!(marked, vec!["rs  # <- the break is seen after this op"]);
        // On the clean emulator the same input breaks nothing, and says so.
        let (script, _) = reproducer(&data, "x");
        assert!(script.contains("breaks no invariant"));
    }
}
