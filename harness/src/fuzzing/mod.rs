//! Fuzz target bodies. Each `fuzz/fuzz_targets/*.rs` is one line calling a
//! function here, so that `cargo test` on stable replays every committed
//! input in `fuzz/corpus/<target>/` and `fuzz/regressions/<target>/`
//! through the same code (`harness/tests/fuzz_corpus.rs`).

pub mod actions;
pub mod bus;
pub mod campaign;
pub mod differential;
pub mod finding;
pub mod oracle;
pub mod plain;
pub mod replay;
pub mod twin;

use crate::bridge::frame::{self, FrameDecoder};
use crate::bridge::wire::{Request, Response, Timer};
use crate::emu::ModelConfig;
use crate::time::Duration;

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
    match oracle::check_ops(bus::ops(data), cfg) {
        Ok(None) => {}
        Ok(Some(v)) => panic!("invariant {v}"),
        Err(e) => panic!("the model refused its configuration: {e}"),
    }
}

/// Structure-aware target: the input's bytes as typed [`actions::Action`]s
/// (derive `Arbitrary`) after a valid initialization, run with the
/// flowchart's waits on a fresh emulator under the same oracle as
/// [`bus_bytes`].
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

/// The actions a `typed_actions` input runs: a valid initialization, then
/// whatever its bytes decode to.
pub fn typed_program(data: &[u8]) -> Vec<actions::Action> {
    let mut acts = vec![actions::Action::default_init()];
    acts.extend(actions::decode(data));
    acts
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
    let Ok(mut chip) =
        crate::emu::Board::new(crate::protocol::Straps::default(), ModelConfig::default())
    else {
        return;
    };
    for op in bus::decode(data) {
        bus::apply(&mut chip, op);
    }
    let t = Trace::new(
        "fuzz",
        "-",
        "emu",
        crate::protocol::Straps::default(),
        Vec::new(),
    )
    .assemble(Vec::new(), chip.record(), Vec::new());
    round_trip(&t);
}

/// Runs typed actions under the oracle and returns the bus ops that ran
/// (the flowchart's waits become the time that passed, to the
/// microsecond), with the first invariant break. The ops replay as a
/// `bus_bytes` input, so every finding has one bus-level form.
pub fn lower(
    acts: &[actions::Action],
    cfg: ModelConfig,
) -> (Vec<bus::BusOp>, Option<oracle::Violation>) {
    use crate::console::Stmt;
    use crate::protocol::Status;
    let mut ops = Vec::new();
    let Ok(mut c) = oracle::Checker::new(cfg) else {
        return (ops, None);
    };
    let run = |c: &mut oracle::Checker, op: bus::BusOp, ops: &mut Vec<bus::BusOp>| {
        ops.push(op);
        c.apply(op)
    };
    // Lets time pass until `ready` holds or `timeout` is spent.
    let wait = |c: &mut oracle::Checker,
                ops: &mut Vec<bus::BusOp>,
                ready: &dyn Fn(Status) -> bool,
                timeout: Duration|
     -> Result<(), oracle::Violation> {
        let deadline = c.board().now() + timeout;
        while !ready(c.board().read_status()) && c.board().now() < deadline {
            let now = c.board().now();
            let next = c.board().poll_at().unwrap_or(deadline).min(deadline);
            let us = next.saturating_since(now).as_nanos().div_ceil(1_000).max(1);
            for op in bus::advances(Duration::from_micros(us)) {
                ops.push(op);
                c.apply(op)?;
            }
        }
        Ok(())
    };
    let second = Duration::from_secs(1);
    let result = (|| {
        for a in acts {
            for s in a.stmts() {
                match s {
                    Stmt::WriteCommand { byte, wait: w } | Stmt::WriteData { byte, wait: w } => {
                        if w {
                            wait(&mut c, &mut ops, &|s| !s.ibf(), second)?;
                        }
                        let op = if matches!(s, Stmt::WriteCommand { .. }) {
                            bus::BusOp::Command(byte)
                        } else {
                            bus::BusOp::Data(byte)
                        };
                        run(&mut c, op, &mut ops)?;
                    }
                    Stmt::ReadData { wait: w } => {
                        if w {
                            wait(&mut c, &mut ops, &|s| s.obf(), second)?;
                        }
                        run(&mut c, bus::BusOp::ReadData, &mut ops)?;
                    }
                    Stmt::Await {
                        flag,
                        value,
                        timeout,
                    } => {
                        let mask = flag.mask();
                        let want = if value { mask } else { 0 };
                        let t = timeout.unwrap_or(second);
                        wait(&mut c, &mut ops, &|s| s.0 & mask == want, t)?;
                        run(&mut c, bus::BusOp::ReadStatus, &mut ops)?;
                    }
                    Stmt::ReadStatus => run(&mut c, bus::BusOp::ReadStatus, &mut ops)?,
                    Stmt::Wait(d) => {
                        for op in bus::advances(d) {
                            run(&mut c, op, &mut ops)?;
                        }
                    }
                    Stmt::Set { input, asserted } => {
                        run(&mut c, bus::BusOp::Input { input, asserted }, &mut ops)?
                    }
                    Stmt::AwaitPulse { count, timeout } => {
                        // Time passes to that pulse (to the microsecond
                        // after it), or not at all if the move will not
                        // reach it in time.
                        let deadline = c.board().now() + timeout.unwrap_or(second);
                        while c.board().move_pulses() < count {
                            let now = c.board().now();
                            let Some(at) = c.board().predict_pulse(count) else {
                                break;
                            };
                            if at > deadline {
                                break;
                            }
                            let us = at.saturating_since(now).as_nanos().div_ceil(1_000).max(1);
                            for op in bus::advances(Duration::from_micros(us)) {
                                run(&mut c, op, &mut ops)?;
                            }
                        }
                    }
                    Stmt::Pins | Stmt::Pulses | Stmt::Now => {}
                }
            }
        }
        c.finish()
    })();
    (ops, result.err())
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
    use crate::backend::EmuTarget;
    use crate::console;
    use crate::emu::WiringFaults;
    use crate::protocol::Straps;
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
            board: WiringFaults {
                status_stuck_high: 0x08,
                ..WiringFaults::default()
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
