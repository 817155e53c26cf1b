//! Replays every committed fuzz input (seed corpus and regressions) through
//! the target bodies in `ppmc::fuzzing::targets`, on stable.

use ppmc_test_support as common;

use std::fs;
use std::path::Path;

fn replay(target: &str, body: fn(&[u8])) -> usize {
    let inputs = common::fuzz_inputs(target);
    for (f, data) in &inputs {
        let ok = std::panic::catch_unwind(|| body(data));
        assert!(ok.is_ok(), "{} fails", f.display());
    }
    inputs.len()
}

/// The fuzz targets reuse one checker, reset, for input after input: a
/// reset checker (chip, board and judge) runs every committed input to the
/// state a fresh one reaches, whatever it ran before, on a plain board and
/// on one whose outputs are miswired (the board keeps a record of its own).
#[test]
fn a_reset_checker_runs_as_a_fresh_one() {
    use ppmc::bus_program;
    use ppmc::emu::{ModelConfig, WiringFaults};
    use ppmc::invariants::oracle::Checker;
    let inputs = common::fuzz_inputs("bus_bytes");
    assert!(inputs.len() > 50, "the corpus is there");
    for cfg in [
        ModelConfig::default(),
        ModelConfig {
            board: WiringFaults {
                dir_inverted: true,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        },
    ] {
        let mut reused = Checker::new(cfg.clone()).expect("a valid configuration");
        for (f, data) in &inputs {
            let ops = bus_program::decode(data);
            let run = |c: &mut Checker| (c.run(ops.iter().copied()), format!("{c:?}"));
            let mut fresh = Checker::new(cfg.clone()).expect("a valid configuration");
            reused.reset();
            assert_eq!(run(&mut reused), run(&mut fresh), "{}", f.display());
        }
    }
}

/// Time advanced in one step or in many uneven ones is the same time: every
/// committed bus_bytes input, with each advance cut into pieces, puts out
/// the same pulses and pin changes and reads the same bytes. The model
/// batches the pulses due within one advance (a constant stretch, ramp
/// stretches up to the next decision); this holds it to putting out what
/// it would pulse by pulse, wherever an advance ends (Section 3-3: the
/// pulses follow the rate and step counts, not the host's polling).
#[test]
fn advancing_in_pieces_changes_nothing() {
    use ppmc::bus_program::{self, BusOp};
    use ppmc::emu::{Board, ModelConfig};
    use ppmc::protocol::capture::{MoveStart, OutputRecord, PulseRun};
    use ppmc::protocol::Straps;
    use ppmc::time::Duration;

    // The record with each move's runs cut as pushing its pulses one at a
    // time cuts them: how the pulses group into runs follows where the
    // model batched them (a stretch is a run of its own), and only the
    // pulses are the same whatever the batching. Compare reads runs pulse
    // by pulse (`compare::compare_pulses`), so the grouping is not part
    // of what a trace says.
    let canonical = |r: &OutputRecord| {
        let mut c = OutputRecord {
            pins: r.pins.clone(),
            overwritten_bytes: r.overwritten_bytes,
            ..OutputRecord::default()
        };
        let before = r.moves.first().map_or(r.runs.len(), |m| m.first_run);
        let push = |c: &mut OutputRecord, runs: &[PulseRun], new_move: bool| {
            for (i, run) in runs.iter().enumerate() {
                let step = run.interval();
                c.push_pulses_singly(run.start, step, run.count, run.dir, new_move && i == 0);
            }
        };
        push(&mut c, &r.runs[..before.min(r.runs.len())], false);
        for k in 0..r.moves.len() {
            c.moves.push(MoveStart {
                first_run: c.runs.len(),
                ..r.moves[k]
            });
            push(&mut c, r.runs_of_move(k), true);
        }
        c
    };
    let run = |ops: &[BusOp]| {
        let mut board = Board::new(Straps::default(), ModelConfig::default()).expect("board");
        let reads: Vec<Option<u8>> = ops
            .iter()
            .map(|op| bus_program::apply(&mut board, *op))
            .collect();
        (
            reads,
            canonical(board.record()),
            board.read_status(),
            board.now(),
        )
    };
    let inputs = common::fuzz_inputs("bus_bytes");
    assert!(inputs.len() > 50, "the corpus is there");
    let mut cut = 0;
    for (f, data) in &inputs {
        let ops = bus_program::decode(data);
        // Each advance in up to 13 pieces of growing length, the piece ends
        // falling anywhere relative to the pulses; a read between the
        // pieces stands for the op's read.
        let mut pieces = Vec::new();
        let mut map = Vec::new();
        for op in &ops {
            if let BusOp::Advance(d) = op {
                let ns = d.as_nanos();
                let mut done = 0;
                for k in 1..=13u64 {
                    let to = ns * k * (k + 1) / (13 * 14);
                    if to > done {
                        pieces.push(BusOp::Advance(Duration::from_nanos(to - done)));
                        done = to;
                        cut += 1;
                    }
                }
            } else {
                pieces.push(*op);
            }
            map.push(pieces.len());
        }
        let (reads, record, status, now) = run(&ops);
        let (piece_reads, piece_record, piece_status, piece_now) = run(&pieces);
        let piece_reads: Vec<Option<u8>> = map
            .iter()
            .zip(&ops)
            .map(|(end, op)| match op {
                BusOp::Advance(_) => None,
                _ => piece_reads[end - 1],
            })
            .collect();
        assert_eq!(piece_reads, reads, "{}: reads", f.display());
        assert_eq!(piece_record, record, "{}: capture", f.display());
        assert_eq!((piece_status, piece_now), (status, now), "{}", f.display());
    }
    assert!(cut > 1000, "advances were cut ({cut} pieces)");
}

#[test]
fn frame_decoder_corpus_replays() {
    let n = replay("frame_decoder", ppmc::fuzzing::targets::frame_decoder);
    assert!(n >= 8, "the seed corpus is there ({n} inputs)");
}

#[test]
fn bus_bytes_corpus_replays() {
    let n = replay("bus_bytes", ppmc::fuzzing::targets::bus_bytes);
    assert!(n >= 90, "the seed corpus is there ({n} inputs)");
}

/// Every scenario's bus traffic, replayed as raw fuzz ops on a fresh chip,
/// keeps every invariant: the oracle raises no false alarm on the clean
/// model across the conformance suite's states.
#[test]
fn the_suite_as_fuzz_ops_keeps_every_invariant() {
    use ppmc::bus_program;
    use ppmc::emu::ModelConfig;
    use ppmc::invariants::oracle;
    for (name, trace) in suite_traces() {
        let ops = bus_program::from_trace(&trace);
        assert!(!ops.is_empty(), "{name}");
        let v = oracle::check(&ops, ModelConfig::default()).expect("chip");
        assert_eq!(v, None, "{name}");
    }
}

fn suite_traces() -> Vec<(&'static str, ppmc::trace::Trace)> {
    common::suite_in_process()
        .into_iter()
        .filter_map(|r| Some((r.name, r.trace?)))
        .collect()
}

#[test]
fn typed_actions_corpus_replays() {
    let n = replay("typed_actions", ppmc::fuzzing::targets::typed_actions);
    assert!(n >= 16, "the seed corpus is there ({n} inputs)");
}

#[test]
fn trace_text_corpus_replays() {
    let n = replay("trace_text", ppmc::fuzzing::targets::trace_text);
    assert!(n >= 14, "the seed corpus is there ({n} inputs)");
}

/// The typed seeds reach the deep states the target exists for: moves
/// that end, and moves stopped early (a remaining-pulses read of a
/// stopped move is judged by the oracle).
#[test]
fn typed_seeds_move_the_motor() {
    use ppmc::emu::ModelConfig;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/typed_actions");
    let mut moving = 0;
    for e in fs::read_dir(root)
        .expect("typed seeds")
        .filter_map(Result::ok)
    {
        let data = fs::read(e.path()).expect("seed");
        let acts = ppmc::fuzzing::actions::typed_program(&data);
        let (ops, found) = ppmc::fuzzing::actions::lower(&acts, ModelConfig::default());
        assert_eq!(found, None, "{}", e.path().display());
        let mut c = ppmc::invariants::oracle::Checker::new(ModelConfig::default()).expect("chip");
        for op in ops {
            c.apply(op).expect("no break");
        }
        if c.board().record().pulse_count() > 0 {
            moving += 1;
        }
    }
    assert!(moving >= 8, "{moving} typed seeds move the motor");
}

/// The committed seed corpora are what the seed writers make
/// (`ppmc::fuzzing::seeds`; `ppmc fuzz seeds` writes them): a protocol or
/// scenario change that moves a seed shows here, not as a corpus that
/// quietly stops exercising what it was made for.
#[test]
fn the_committed_seeds_are_what_the_writers_make() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
    let suite = suite_traces();
    let seeds = ppmc::fuzzing::seeds::all(&suite).expect("the seeds are made");
    assert!(seeds.len() > 100, "{} seeds", seeds.len());
    let stale: Vec<String> = seeds
        .iter()
        .filter(|(target, name, bytes)| {
            fs::read(root.join(target).join(name)).ok().as_deref() != Some(&bytes[..])
        })
        .map(|(target, name, _)| format!("{target}/{name}"))
        .collect();
    assert!(
        stale.is_empty(),
        "committed seeds that differ from what `ppmc fuzz seeds` writes (run it): {stale:?}"
    );
}
