//! From a fuzz finding to a regression test: read a crash file of any
//! target as bus ops, shrink it op-aware while the same invariant still
//! breaks (or, for a `model_twin` finding, while the two models still
//! disagree), print it as a console script (the reproducer), and write it
//! as a Rust scenario file.

use super::actions::{lower, typed_program};
use crate::bus_program::{self, BusOp};
use crate::emu::ModelConfig;
use crate::invariants::ids::Invariant;
use crate::invariants::oracle;
use crate::invariants::rules::Violation;
use crate::plain_model::twin::{self, Disagreement};
use crate::protocol::Straps;
use crate::time::Duration;
use std::fmt::Write as _;

/// The fuzz targets whose inputs are bus programs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A `bus_bytes` input: ops separated by `FUZZ`.
    BusBytes,
    /// A `typed_actions` input: typed actions (derive `Arbitrary`).
    TypedActions,
}

/// The bus ops an input runs on a model with `cfg`.
pub fn ops_of(data: &[u8], kind: InputKind, cfg: &ModelConfig) -> Vec<BusOp> {
    match kind {
        InputKind::BusBytes => bus_program::decode(data),
        InputKind::TypedActions => lower(&typed_program(data), cfg.clone()).0,
    }
}

/// The first break of `ops` on a model with `cfg`.
pub fn first_break(ops: &[BusOp], cfg: &ModelConfig) -> Option<Violation> {
    oracle::check(ops, cfg.clone()).ok().flatten()
}

/// How a minimization went.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Minimized {
    pub ops: Vec<BusOp>,
    pub violation: Violation,
    /// Oracle runs spent.
    pub tries: usize,
}

/// Shrinks `ops` while `invariant` still breaks on `cfg`: cut what follows
/// the break, drop chunks of ops (halving the chunk size down to single
/// ops), merge neighbouring waits, shorten each wait (binary search) and
/// zero data bytes, until a whole pass changes nothing. `None` when `ops`
/// does not break `invariant` to begin with.
pub fn minimize(ops: &[BusOp], cfg: &ModelConfig, invariant: Invariant) -> Option<Minimized> {
    minimize_by(ops, invariant, |ops| first_break(ops, cfg))
}

/// [`minimize`] by any judge: `judge` runs ops (on the emulator, or on a
/// board) and says the first invariant they break, if any. Each call is
/// one try.
pub fn minimize_by(
    ops: &[BusOp],
    invariant: Invariant,
    mut judge: impl FnMut(&[BusOp]) -> Option<Violation>,
) -> Option<Minimized> {
    let (ops, violation, tries) = minimize_while(
        ops,
        |ops| judge(ops).filter(|v| v.invariant == invariant),
        |v| Some(v.op),
    )?;
    Some(Minimized {
        ops,
        violation,
        tries,
    })
}

/// Shrinks `ops` as [`minimize`] does while `judge` finds what it looks
/// for (`Some`), whatever that is: an invariant's break, a departure from
/// the model. `shows_at` is the op where a find shows, if known: nothing
/// after it is kept. The ops, the last find, and the tries.
pub fn minimize_while<T>(
    ops: &[BusOp],
    mut judge: impl FnMut(&[BusOp]) -> Option<T>,
    shows_at: impl Fn(&T) -> Option<usize>,
) -> Option<(Vec<BusOp>, T, usize)> {
    let mut tries = 0;
    let mut breaks = |ops: &[BusOp]| -> Option<T> {
        tries += 1;
        judge(ops)
    };
    let mut best = ops.to_vec();
    let mut v = breaks(&best)?;
    loop {
        let before = best.clone();
        // Nothing after the op where the break shows matters.
        if let Some(op) = shows_at(&v) {
            best.truncate(op + 1);
        }
        drop_chunks(&mut best, |cand| {
            v = breaks(&cand)?;
            Some(cand)
        });
        // Merge neighbouring waits.
        let merged = merge_waits(&best);
        if merged != best {
            if let Some(nv) = breaks(&merged) {
                best = merged;
                v = nv;
            }
        }
        // Shorten each wait, and zero data bytes.
        for i in 0..best.len() {
            match best[i] {
                BusOp::Advance(d) => {
                    let (mut lo, mut hi) = (0u64, d.as_nanos() / 1_000);
                    while lo < hi {
                        let mid = lo + (hi - lo) / 2;
                        let mut cand = best.clone();
                        cand[i] = BusOp::Advance(Duration::from_micros(mid));
                        match breaks(&cand) {
                            Some(nv) => {
                                hi = mid;
                                best = cand;
                                v = nv;
                            }
                            None => lo = mid + 1,
                        }
                    }
                }
                BusOp::Data(b) if b != 0 => {
                    let mut cand = best.clone();
                    cand[i] = BusOp::Data(0);
                    if let Some(nv) = breaks(&cand) {
                        best = cand;
                        v = nv;
                    }
                }
                _ => {}
            }
        }
        // Waits shortened to nothing are dropped.
        let cand: Vec<BusOp> = best
            .iter()
            .copied()
            .filter(|op| *op != BusOp::Advance(Duration::ZERO))
            .collect();
        if cand != best {
            if let Some(nv) = breaks(&cand) {
                best = cand;
                v = nv;
            }
        }
        if best == before {
            break;
        }
    }
    Some((best, v, tries))
}

/// Shrinks `ops` while the two models still disagree: drops chunks of
/// ops, then single ops, halving the chunk each round (ddmin-style). The
/// disagreement found at the end may differ in detail from the first; it
/// is returned with the ops.
pub fn minimize_disagreement(
    ops: &[BusOp],
    straps: Straps,
    cfg: &ModelConfig,
) -> Option<(Vec<BusOp>, Disagreement)> {
    let mut best = ops.to_vec();
    let mut found = twin::check(&best, straps, cfg).err()?;
    // Nothing after the op where they first differ matters.
    best.truncate(found.op + 1);
    drop_chunks(&mut best, |mut trial| {
        let d = twin::check(&trial, straps, cfg).err()?;
        trial.truncate(d.op + 1);
        found = d;
        Some(trial)
    });
    Some((best, found))
}

/// Drops chunks of `ops`, largest first (half the ops, then halving the
/// chunk down to single ops): each candidate goes to `keep`, which gives
/// back what to keep when the candidate still fails (the candidate, or a
/// cut of it), `None` when it does not. Shared by the oracle's minimizer
/// and the two-model one ([`minimize_disagreement`]).
fn drop_chunks(ops: &mut Vec<BusOp>, mut keep: impl FnMut(Vec<BusOp>) -> Option<Vec<BusOp>>) {
    let mut chunk = ops.len().div_ceil(2).max(1);
    loop {
        let mut i = 0;
        while i < ops.len() {
            let mut cand = ops.clone();
            cand.drain(i..(i + chunk).min(cand.len()));
            match keep(cand) {
                Some(kept) => *ops = kept,
                None => i += chunk,
            }
        }
        if chunk == 1 {
            break;
        }
        chunk = chunk.div_ceil(2);
    }
}

/// Neighbouring waits as one.
fn merge_waits(ops: &[BusOp]) -> Vec<BusOp> {
    let mut out: Vec<BusOp> = Vec::with_capacity(ops.len());
    for op in ops {
        match (out.last_mut(), op) {
            (Some(BusOp::Advance(a)), BusOp::Advance(b)) => *a += *b,
            _ => out.push(*op),
        }
    }
    out
}

/// A `bus_bytes` input as a bus script in the console language
/// (`docs/console.md`): a header naming the invariant it breaks on the
/// emulator (or saying it breaks none), then one op per line. The script
/// replays in `ppmc console` on the emulator.
pub fn reproducer(data: &[u8], source: &str) -> (String, Option<Violation>) {
    reproducer_with(data, source, ModelConfig::default())
}

/// [`reproducer`], judged on a model with a configuration.
pub fn reproducer_with(data: &[u8], source: &str, cfg: ModelConfig) -> (String, Option<Violation>) {
    let ops = bus_program::decode(data);
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

/// The ops as a `bus_bytes` input (long waits split so each op holds its
/// wait exactly).
pub fn to_bytes(ops: &[BusOp]) -> Vec<u8> {
    let split: Vec<BusOp> = ops
        .iter()
        .flat_map(|op| match op {
            BusOp::Advance(d) => bus_program::advances(*d),
            other => vec![*other],
        })
        .collect();
    bus_program::encode(&split)
}

/// A scenario name for a break of `invariant`: `fuzz_<invariant>_<n>`.
pub fn scenario_stem(invariant: Invariant, n: usize) -> String {
    format!("fuzz_{}_{n}", invariant.as_str().replace('-', "_"))
}

/// A Rust scenario file (for `scenarios/`) that replays `ops` and fails
/// while `v` still breaks: the body of `ppmc fuzz to-scenario`.
pub fn scenario_file(stem: &str, ops: &[BusOp], v: &Violation, source: &str) -> String {
    let section = v.invariant.section();
    let source = comment_safe(source);
    let detail = comment_safe(&v.detail);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "//! Regression scenario from a fuzz finding: invariant `{}` (Section {section},\n\
         //! docs/invariants.md) broke after op {}: {}.\n\
         //! Written by `ppmc fuzz to-scenario` from {source}.\n\
         //! It fails while the bug is there; once fixed, record its golden trace\n\
         //! (`ppmc record --filter {stem}`).\n",
        v.invariant, v.op, detail,
    );
    s.push_str("use ppmc::bus_program::BusOp::{self, *};\n");
    s.push_str("use ppmc::invariants::replay::regression;\n");
    s.push_str("use ppmc::scenario::prelude::*;\n\n");
    let _ = writeln!(
        s,
        "pub fn scenarios() -> Vec<Scenario> {{\n    vec![{stem}()]\n}}\n"
    );
    let _ = writeln!(s, "/// fuzz finding: {} must hold", v.invariant);
    let _ = writeln!(
        s,
        "#[scenario(section = {section:?}, tags(\"fuzz\", \"regression\"))]"
    );
    let _ = writeln!(
        s,
        "fn {stem}(d: &mut Driver) -> Outcome {{\n    regression(d, OPS)\n}}\n"
    );
    s.push_str("/// The minimized bus script, one op per line (console form in comments).\n");
    s.push_str("const OPS: &[BusOp] = &[\n");
    for op in &merge_waits(ops) {
        let code = match *op {
            BusOp::Command(b) => format!("Command(0x{b:02X})"),
            BusOp::Data(b) => format!("Data(0x{b:02X})"),
            BusOp::ReadStatus => "ReadStatus".into(),
            BusOp::ReadData => "ReadData".into(),
            // Qualified: the prelude's `Input` (the pin) and the op's
            // variant share a name.
            BusOp::Input { input, asserted } => format!(
                "BusOp::Input {{ input: ppmc::protocol::Input::{input:?}, asserted: {asserted} }}"
            ),
            BusOp::Advance(d) => format!("Advance(Duration::from_nanos({}))", d.as_nanos()),
        };
        let _ = writeln!(s, "    {code}, // {op}");
    }
    s.push_str("];\n");
    s
}

/// `text` as it may appear in a generated source comment: printable ASCII
/// as it is, everything else (a newline, a control or bidirectional
/// character from a file name) escaped, so no text from outside can add a
/// line of code or hide one.
fn comment_safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c == ' ' || c.is_ascii_graphic() {
                c.to_string()
            } else {
                c.escape_unicode().to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::EmuTarget;
    use crate::console;
    use crate::emu::WiringFaults;
    use crate::faults;

    fn noisy_remaining_finding() -> Vec<BusOp> {
        // A seed of the suite whose traffic reads the remaining pulses after
        // a stop, with noise ops around.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../fuzz/corpus/bus_bytes/s3_3_1_immediate_stop_and_resume.bin");
        bus_program::decode(&std::fs::read(dir).expect("seed"))
    }

    /// The minimizer keeps the break, and shrinks a 40-odd op seed to a
    /// handful: the injected remaining-pulses bug needs an initialization,
    /// a move, a stop and a read.
    #[test]
    fn minimizing_keeps_the_invariant_and_shrinks_the_input() {
        let cfg = faults::find("remaining-off-by-one").expect("fault").model();
        let ops = noisy_remaining_finding();
        let v = first_break(&ops, &cfg).expect("the fault breaks it");
        assert_eq!(v.invariant, Invariant::RemainingPulses);
        let m = minimize(&ops, &cfg, Invariant::RemainingPulses).expect("minimized");
        assert_eq!(m.violation.invariant, Invariant::RemainingPulses);
        assert!(
            m.ops.len() < ops.len() / 2,
            "{} of {}",
            m.ops.len(),
            ops.len()
        );
        assert_eq!(
            first_break(&m.ops, &cfg).map(|v| v.invariant),
            Some(Invariant::RemainingPulses)
        );
        // The clean model keeps the invariant on the minimized input.
        assert_eq!(first_break(&m.ops, &ModelConfig::default()), None);
        // As bytes it is the same program.
        assert_eq!(
            merge_waits(&bus_program::decode(&to_bytes(&m.ops))),
            merge_waits(&m.ops)
        );
        // An input that breaks nothing cannot be minimized for it.
        assert_eq!(
            minimize(&ops, &ModelConfig::default(), Invariant::RemainingPulses),
            None
        );
    }

    #[test]
    fn no_text_from_a_file_name_reaches_the_generated_code_unescaped() {
        let v = Violation {
            invariant: Invariant::RemainingPulses,
            op: 0,
            detail: "read 5\nfn evil() {}".into(),
        };
        let source = "crash\npub fn injected() {}\u{202E}";
        let text = scenario_file("fuzz_x_1", &[BusOp::Command(0x83)], &v, source);
        for line in text.lines() {
            let code = line.trim_start();
            assert!(
                !code.starts_with("pub fn injected") && !code.starts_with("fn evil"),
                "{text}"
            );
        }
        assert!(
            text.contains("crash\\u{a}pub fn injected() {}\\u{202e}"),
            "{text}"
        );
        assert!(!text.contains('\u{202E}'));
    }

    #[test]
    fn the_scenario_file_names_the_invariant_and_lists_every_op() {
        let v = Violation {
            invariant: Invariant::RemainingPulses,
            op: 1,
            detail: "read 5".into(),
        };
        let ops = [
            BusOp::Command(0x83),
            BusOp::Advance(Duration::from_micros(3)),
            BusOp::Input {
                input: crate::protocol::Input::L2,
                asserted: true,
            },
        ];
        let stem = scenario_stem(v.invariant, 2);
        assert_eq!(stem, "fuzz_remaining_pulses_2");
        let text = scenario_file(&stem, &ops, &v, "crash-1");
        assert!(text.contains("section = \"3-4-4\""), "{text}");
        assert!(text.contains("Command(0x83), // wc! 0x83"), "{text}");
        assert!(text.contains("Advance(Duration::from_nanos(3000)), // wait 3us"));
        assert!(text.contains(
            "BusOp::Input { input: ppmc::protocol::Input::L2, asserted: true }, // set l2 on"
        ));
        assert!(text.contains("regression(d, OPS)"));
        assert!(text.contains("fn fuzz_remaining_pulses_2(d: &mut Driver)"));
    }

    fn sample() -> Vec<BusOp> {
        use BusOp::*;
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
        let data = bus_program::encode(&sample());
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
        let data = bus_program::encode(&sample());
        let cfg = ModelConfig {
            board: WiringFaults {
                status_stuck_high: 0x08,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        };
        let (script, found) = reproducer_with(&data, "x", cfg);
        let v = found.expect("a break");
        assert_eq!((v.invariant, v.op), (Invariant::StatusBit3, 4));
        assert!(script.contains("# breaks: invariant status-bit3 after op 4"));
        let marked: Vec<&str> = script.lines().filter(|l| l.contains("# <-")).collect();
        assert_eq!(marked, vec!["rs  # <- the break is seen after this op"]);
        // On the clean emulator the same input breaks nothing, and says so.
        let (script, _) = reproducer(&data, "x");
        assert!(script.contains("breaks no invariant"));
    }
}
