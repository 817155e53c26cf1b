//! What a fuzzing session shows besides code coverage: findings bucketed by
//! the invariant that broke, and the domain coverage of a corpus (which
//! commands in which chip state, which error codes, finish causes and
//! inputs it reached), so that a user sees what was not exercised.

use crate::bus_program::BusOp;
use crate::emu::ModelConfig;
use crate::invariants::ids::Invariant;
use crate::invariants::oracle::Checker;
use crate::invariants::rules::Violation;
use crate::protocol::{Command, ErrorCode, Input, MoveKind, OutputRecord, Register, StatusField};
use crate::time::Duration;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One bucket of findings: every input that broke one invariant.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Bucket {
    pub invariant: Invariant,
    /// Names of the inputs, in the order given.
    pub inputs: Vec<String>,
    /// The input with the fewest ops, and its break: the one to minimize.
    pub smallest: (String, usize, Violation),
}

/// Buckets `(name, ops)` inputs by the invariant each breaks on `cfg`;
/// also returns the names of those that break none.
pub fn triage(inputs: &[(String, Vec<BusOp>)], cfg: &ModelConfig) -> (Vec<Bucket>, Vec<String>) {
    // Keyed by the id's text: the buckets come in its alphabetical order.
    let mut buckets: BTreeMap<&'static str, Bucket> = BTreeMap::new();
    let mut clean = Vec::new();
    for (name, ops) in inputs {
        let Some(v) = super::finding::first_break(ops, cfg) else {
            clean.push(name.clone());
            continue;
        };
        let b = buckets
            .entry(v.invariant.as_str())
            .or_insert_with(|| Bucket {
                invariant: v.invariant,
                inputs: Vec::new(),
                smallest: (name.clone(), ops.len(), v.clone()),
            });
        b.inputs.push(name.clone());
        if ops.len() < b.smallest.1 {
            b.smallest = (name.clone(), ops.len(), v);
        }
    }
    (buckets.into_values().collect(), clean)
}

/// The chip state a command meets, as the datasheet's error rules see it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ChipState {
    /// Not initialized (after reset or software reset).
    Uninitialized,
    /// Initialized, no move.
    Idle,
    /// A move under way (BUSY = 1).
    Moving,
}

impl ChipState {
    pub const ALL: [ChipState; 3] = [ChipState::Uninitialized, ChipState::Idle, ChipState::Moving];

    pub fn name(self) -> &'static str {
        match self {
            ChipState::Uninitialized => "uninitialized",
            ChipState::Idle => "idle",
            ChipState::Moving => "moving",
        }
    }
}

/// The command classes the report counts (one per chapter-3 command).
fn command_class(byte: u8) -> String {
    match Command::decode(byte) {
        Command::Init(_) => "initialization".into(),
        Command::Move(m) => m.kind.name().to_string(),
        Command::ImmediateStop(_) => "immediate stop".into(),
        Command::DecelStop(_) => "decelerating stop".into(),
        Command::SoftwareReset(_) => "software reset".into(),
        Command::AuxOn(_) => "aux on".into(),
        Command::AuxOff(_) => "aux off".into(),
        Command::Read(r) => format!("read {}", r.name()),
        Command::SwitchingParams => "switching parameters".into(),
        Command::AuxOutput => "aux output".into(),
        Command::Undefined(_) => "undefined code".into(),
    }
}

/// Every command class, for listing what was never reached.
fn all_command_classes() -> Vec<String> {
    let mut v: Vec<String> = (0..=255u8).map(command_class).collect();
    v.sort();
    v.dedup();
    v
}

/// Domain coverage of a corpus.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Coverage {
    pub inputs: usize,
    /// (command class, state it was written in) -> count.
    pub commands: BTreeMap<(String, ChipState), u64>,
    /// Error numbers seen in the status register.
    pub errors: BTreeMap<u8, u64>,
    /// (move kind, how it ended) -> count; from the finish status the
    /// model keeps.
    pub finishes: BTreeMap<(String, String), u64>,
    /// Inputs asserted while a move was under way.
    pub inputs_while_moving: BTreeMap<&'static str, u64>,
    /// (command class before, command class) -> count: each command
    /// written after another (the order the chip's state depends on).
    pub pairs: BTreeMap<(String, String), u64>,
    /// (command class, error number) -> count: an error the status
    /// register first showed after that command.
    pub errors_by_command: BTreeMap<(String, u8), u64>,
    /// (command class or input, ramp phase) -> count: what was written
    /// or asserted during a move, by where its ramp was (3-4-2).
    pub during_ramp: BTreeMap<(String, &'static str), u64>,
    /// Finish status reads (3-4-1: the command taken, then its byte
    /// read), by what the register held for them: a finish to report (the
    /// polling flag set), a finish read already (the flag cleared by the
    /// read before), or none yet.
    pub finish_reads: BTreeMap<&'static str, u64>,
}

/// What a finish status read found in the register (3-4-1): a finish
/// to report (the polling flag set), a finish read already (the flag
/// cleared by the read before), no move ended yet.
const FINISH_READS: [&str; 3] = [
    "with a finish to report",
    "again after a finish",
    "before any finish",
];

/// A walk of one input on the clean model, op by op, counting what each
/// reached into a [`Coverage`]: what [`Coverage::of`] does for a whole
/// input, for a stream that comes an op at a time.
#[derive(Debug)]
pub struct Walk {
    k: Checker,
    /// Pin events already looked at: only new ones can be a move's end.
    pins_seen: usize,
    /// The class of the last command written.
    last_command: Option<String>,
    /// The error number the status register showed after the last op.
    last_error: Option<u8>,
    /// A move has ended since the reset.
    a_move_ended: bool,
    /// What the last finish status read command found to load, until
    /// its byte is read.
    finish_read: Option<&'static str>,
}

impl Walk {
    /// A walk from a chip straight out of reset; `None` if the clean model
    /// cannot be made (it always can).
    pub fn new() -> Option<Walk> {
        Some(Walk {
            k: Checker::new(ModelConfig::default()).ok()?,
            pins_seen: 0,
            last_command: None,
            last_error: None,
            a_move_ended: false,
            finish_read: None,
        })
    }

    /// Applies `op` and counts what it reached into `c`.
    pub fn step(&mut self, c: &mut Coverage, op: BusOp) {
        let board = self.k.board();
        // The state as the host sees it (through the board), and the
        // model's own view of whether it was initialized.
        let state = if board.read_status().busy() {
            ChipState::Moving
        } else if board.chip().initialized() {
            ChipState::Idle
        } else {
            ChipState::Uninitialized
        };
        let phase = match state {
            ChipState::Moving => Some(ramp_phase(board.record())),
            _ => None,
        };
        match op {
            BusOp::Command(b) => {
                let class = command_class(b);
                *c.commands.entry((class.clone(), state)).or_default() += 1;
                if let Some(p) = phase {
                    *c.during_ramp.entry((class.clone(), p)).or_default() += 1;
                }
                let reads_finish = Command::decode(b) == Command::Read(Register::FinishStatus);
                self.finish_read = (reads_finish && state != ChipState::Moving).then(|| {
                    match (board.chip().finish_status().polling(), self.a_move_ended) {
                        (true, _) => FINISH_READS[0],
                        (false, true) => FINISH_READS[1],
                        (false, false) => FINISH_READS[2],
                    }
                });
                let before = self.last_command.replace(class.clone());
                *c.pairs
                    .entry((before.unwrap_or_else(|| "reset".into()), class))
                    .or_default() += 1;
            }
            // The byte a finish status read loaded, read.
            BusOp::ReadData => {
                if let Some(what) = self.finish_read.take() {
                    *c.finish_reads.entry(what).or_default() += 1;
                }
            }
            BusOp::Input {
                input,
                asserted: true,
            } if state == ChipState::Moving => {
                *c.inputs_while_moving.entry(input.name()).or_default() += 1;
                if let Some(p) = phase {
                    *c.during_ramp
                        .entry((input.name().to_string(), p))
                        .or_default() += 1;
                }
            }
            _ => {}
        }
        // Oracle breaks are the fuzz targets' business, not coverage's.
        let _ = self.k.apply(op);
        let board = self.k.board();
        let error = match board.read_status().field() {
            StatusField::Error(e) => Some(e.number()),
            _ => None,
        };
        if let Some(e) = error {
            *c.errors.entry(e).or_default() += 1;
            if self.last_error != Some(e) {
                let by = self.last_command.clone().unwrap_or_else(|| "reset".into());
                *c.errors_by_command.entry((by, e)).or_default() += 1;
            }
        }
        self.last_error = error;
        let pins = &board.record().pins;
        let ended = pins
            .get(self.pins_seen..)
            .unwrap_or_default()
            .iter()
            .any(|p| p.pin == crate::protocol::Pin::Busy && p.value == 0);
        self.pins_seen = pins.len();
        if ended {
            self.a_move_ended = true;
            let f = board.chip().finish_status();
            let kind = MoveKind::ALL
                .iter()
                .find(|m| m.code() == f.op_code())
                .map_or("?", |m| m.name());
            let cause = if f.alarm() {
                "alarm"
            } else if f.limit() {
                "limit"
            } else if f.high_speed_limit() {
                "high-speed limit"
            } else if f.stop_command() {
                "stop command"
            } else {
                "completed"
            };
            *c.finishes
                .entry((kind.to_string(), cause.to_string()))
                .or_default() += 1;
        }
    }
}

/// Where the ramp of the move under way is, from the pulses it has put
/// out (3-4-2): none yet, its intervals shrinking (accelerating), even
/// (at speed) or growing (decelerating). The record merges evenly spaced
/// pulses into one run, so the last two runs' spacings tell.
fn ramp_phase(record: &OutputRecord) -> &'static str {
    let started = record.moves.last().map(|m| m.at);
    let runs: Vec<&crate::protocol::PulseRun> = record
        .runs
        .iter()
        .rev()
        .take_while(|r| started.is_none_or(|s| r.start >= s))
        .take(2)
        .collect();
    let spacing = |i: usize| -> Option<Duration> {
        let r = runs.get(i)?;
        match r.count {
            0 | 1 => runs.get(i + 1).map(|p| r.start.saturating_since(p.last())),
            n => Some(r.span.scale(1, u64::from(n - 1))),
        }
    };
    match (runs.first(), spacing(0), spacing(1)) {
        (None, _, _) => "before its first pulse",
        (Some(r), _, _) if r.count >= 3 => "at speed",
        (_, Some(last), Some(before)) if last < before => "accelerating",
        (_, Some(last), Some(before)) if last > before => "decelerating",
        _ => "at speed",
    }
}

impl Coverage {
    /// Runs every input on the clean model and counts what it reached.
    pub fn of(inputs: &[Vec<BusOp>]) -> Coverage {
        let mut c = Coverage {
            inputs: inputs.len(),
            ..Coverage::default()
        };
        for ops in inputs {
            let Some(mut w) = Walk::new() else {
                continue;
            };
            for op in ops {
                w.step(&mut c, *op);
            }
        }
        c
    }

    /// Every cell reached, one name each: the features a guided campaign
    /// is fed ([`super::guided`]), and how two campaigns' coverage
    /// compares.
    pub fn cells(&self) -> std::collections::BTreeSet<String> {
        let mut f = std::collections::BTreeSet::new();
        f.extend(
            self.commands
                .keys()
                .map(|(class, state)| format!("command {class} while {}", state.name())),
        );
        f.extend(self.errors.keys().map(|e| format!("error {e}")));
        f.extend(
            self.finishes
                .keys()
                .map(|(kind, cause)| format!("{kind} ended by {cause}")),
        );
        f.extend(
            self.inputs_while_moving
                .keys()
                .map(|i| format!("{i} during a move")),
        );
        f.extend(
            self.pairs
                .keys()
                .map(|(a, b)| format!("command {b} after {a}")),
        );
        f.extend(
            self.errors_by_command
                .keys()
                .map(|(c, e)| format!("error {e} after command {c}")),
        );
        f.extend(
            self.during_ramp
                .keys()
                .map(|(what, phase)| format!("{what} during a move {phase}")),
        );
        f.extend(
            self.finish_reads
                .keys()
                .map(|what| format!("finish status read {what}")),
        );
        f
    }

    /// The report, with what was never reached listed after each table.
    pub fn render(&self) -> String {
        let mut s = format!("# Domain coverage of {} inputs\n\n", self.inputs);
        s.push_str("## Commands by chip state\n\n| command | uninitialized | idle | moving |\n|---|---:|---:|---:|\n");
        let mut never = Vec::new();
        for class in all_command_classes() {
            let counts: Vec<u64> = ChipState::ALL
                .iter()
                .map(|st| {
                    self.commands
                        .get(&(class.clone(), *st))
                        .copied()
                        .unwrap_or(0)
                })
                .collect();
            for (st, n) in ChipState::ALL.iter().zip(&counts) {
                if *n == 0 {
                    never.push(format!("{class} while {}", st.name()));
                }
            }
            let _ = writeln!(
                s,
                "| {class} | {} | {} | {} |",
                counts[0], counts[1], counts[2]
            );
        }
        let _ = writeln!(s, "\nNever reached: {}.\n", list(&never));
        s.push_str(
            "## Error codes (Table 3-2)\n\n| error | status reads showing it |\n|---|---:|\n",
        );
        let mut never = Vec::new();
        for e in ErrorCode::ALL {
            let n = self.errors.get(&e.number()).copied().unwrap_or(0);
            if n == 0 {
                never.push(e.number().to_string());
            }
            let _ = writeln!(s, "| {} | {n} |", e.number());
        }
        let _ = writeln!(s, "\nNever reached: {}.\n", list(&never));
        s.push_str("## How moves ended (finish status, 3-4-1)\n\n| move | ended by | count |\n|---|---|---:|\n");
        for ((kind, cause), n) in &self.finishes {
            let _ = writeln!(s, "| {kind} | {cause} | {n} |");
        }
        let never: Vec<String> = MoveKind::ALL
            .iter()
            .filter(|m| !self.finishes.keys().any(|(k, _)| k == m.name()))
            .map(|m| m.name().to_string())
            .collect();
        let _ = writeln!(s, "\nMoves never ended: {}.\n", list(&never));
        s.push_str("## Inputs asserted during a move\n\n| input | count |\n|---|---:|\n");
        let mut never = Vec::new();
        for i in Input::ALL {
            let n = self.inputs_while_moving.get(i.name()).copied().unwrap_or(0);
            if n == 0 {
                never.push(i.name().to_string());
            }
            let _ = writeln!(s, "| {} | {n} |", i.name());
        }
        let _ = writeln!(s, "\nNever reached: {}.\n", list(&never));
        s.push_str("## Finish status reads (3-4-1)\n\n| the register held | reads |\n|---|---:|\n");
        let mut never = Vec::new();
        for what in FINISH_READS {
            let n = self.finish_reads.get(what).copied().unwrap_or(0);
            if n == 0 {
                never.push(what.to_string());
            }
            let _ = writeln!(s, "| {what} | {n} |");
        }
        let _ = writeln!(s, "\nNever reached: {}.", list(&never));
        s
    }
}

fn list(v: &[String]) -> String {
    if v.is_empty() {
        "nothing".into()
    } else {
        v.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus_program;
    use crate::faults;

    fn seeds() -> Vec<(String, Vec<BusOp>)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/bus_bytes");
        let mut v: Vec<(String, Vec<BusOp>)> = std::fs::read_dir(dir)
            .expect("corpus")
            .filter_map(Result::ok)
            .map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                (
                    name,
                    bus_program::decode(&std::fs::read(e.path()).expect("seed")),
                )
            })
            .collect();
        v.sort_by(|a, b| a.0.cmp(&b.0));
        v
    }

    /// Many inputs breaking one invariant are one bucket, represented by
    /// the shortest; inputs that break nothing are listed apart.
    #[test]
    fn findings_are_bucketed_by_invariant() {
        let cfg = faults::find("remaining-off-by-one").expect("fault").model();
        let (buckets, clean) = triage(&seeds(), &cfg);
        assert_eq!(buckets.len(), 1, "{buckets:?}");
        let b = &buckets[0];
        assert_eq!(b.invariant, Invariant::RemainingPulses);
        assert!(b.inputs.len() >= 5, "{}", b.inputs.len());
        assert!(b.inputs.contains(&b.smallest.0));
        assert_eq!(b.inputs.len() + clean.len(), seeds().len());
        let (none, all_clean) = triage(&seeds(), &ModelConfig::default());
        assert!(none.is_empty());
        assert_eq!(all_clean.len(), seeds().len());
    }

    /// The suite's traffic reaches every move kind, ended, and errors; the
    /// report lists what it never reached.
    #[test]
    fn the_seed_corpus_coverage_report() {
        let ops: Vec<Vec<BusOp>> = seeds().into_iter().map(|(_, o)| o).collect();
        let c = Coverage::of(&ops);
        assert_eq!(c.inputs, ops.len());
        for m in MoveKind::ALL {
            assert!(
                c.finishes.keys().any(|(k, _)| k == m.name()),
                "{}",
                m.name()
            );
        }
        assert!(c.errors.len() >= 6, "{:?}", c.errors);
        assert!(c
            .commands
            .contains_key(&("initialization".to_string(), ChipState::Uninitialized)));
        let text = c.render();
        assert!(text.contains("## Commands by chip state"));
        assert!(text.contains("Never reached:"));
        // Empty corpus: everything is listed as never reached.
        let empty = Coverage::of(&[]).render();
        assert!(
            empty.contains("Never reached: 0, 1, 2, 3, 4, 5, 6, 7."),
            "{empty}"
        );
    }
}
