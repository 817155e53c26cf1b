//! The emulator against the plain model ([`super::chip`]): the same bus
//! ops on both, and everything a host or a logic analyser could see
//! compared after every op. The first difference is a [`Disagreement`];
//! which model is right is then a question for the datasheet
//! (`docs/datasheet-notes.md` records each one decided).
//!
//! Compared: the byte every status and data register read returns, the
//! output pins after every op (INT*, HOLD, AUX*, AUXO0..3, the phases
//! as energized and as pin levels, DIR, BUSY), every pulse (its time to
//! the nanosecond and its direction) and every change of a pin outside
//! pulse stepping, with its time.
//!
//! The `model_twin` fuzz target runs [`check`] on every input
//! ([`crate::fuzzing::targets::model_twin`]); a disagreement is shrunk by
//! [`crate::fuzzing::finding::minimize_disagreement`] (`ppmc fuzz twin`).

use super::chip::PlainChip;
use crate::bus_program::{self, BusOp};
use crate::emu::{Board, ModelConfig};
use crate::protocol::{Direction, Pin, PinEvent, PulseRun, Straps};
use crate::time::Instant;
use std::fmt;

/// Where the two models first differ.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Disagreement {
    /// Index of the op after which they differ.
    pub op: usize,
    /// The op itself.
    pub what_op: BusOp,
    /// What differs: the emulator's side first, then the plain model's.
    pub detail: String,
}

impl fmt::Display for Disagreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "after op {} ({}): {}",
            self.op + 1,
            self.what_op,
            self.detail
        )
    }
}

/// How far a check got.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Agreement {
    /// Ops compared.
    pub ops: usize,
    /// Pulses compared.
    pub pulses: usize,
    /// Pin changes compared.
    pub pin_changes: usize,
    /// The plain model reached its pulse budget and the check stopped
    /// there.
    pub cut_short: bool,
}

/// Runs `ops` on the emulator (on a fault-free board) and on the plain
/// model, both with `cfg`'s latencies, comparing after every op.
pub fn check(ops: &[BusOp], straps: Straps, cfg: &ModelConfig) -> Result<Agreement, Disagreement> {
    let cfg = ModelConfig {
        faults: Default::default(),
        board: Default::default(),
        ..cfg.clone()
    };
    check_against(ops, straps, &cfg, &cfg)
}

/// [`check`] with a configuration for each side: the emulator's may carry
/// deliberate faults (the plain model has none), which is how a test shows
/// that the check catches a wrong emulator.
pub fn check_against(
    ops: &[BusOp],
    straps: Straps,
    emulator: &ModelConfig,
    plain: &ModelConfig,
) -> Result<Agreement, Disagreement> {
    let Ok(mut fast) = Board::new(straps, emulator.clone()) else {
        // Straps or a config the emulator refuses: nothing to compare.
        return Ok(Agreement::default());
    };
    let mut plain = PlainChip::new(straps, plain.clone());
    let mut seen = Agreement::default();
    // The emulator's next unread pulse: run index and pulse within it.
    let mut cursor = (0usize, 0u32);
    let mut fast_pins = Changes::default();
    let mut plain_pins = Changes::default();
    for (i, &op) in ops.iter().enumerate() {
        let disagree = |detail: String| Disagreement {
            op: i,
            what_op: op,
            detail,
        };
        let a = bus_program::apply(&mut fast, op);
        let b = apply(&mut plain, op);
        if plain.exhausted() {
            seen.cut_short = true;
            return Ok(seen);
        }
        if a != b {
            return Err(disagree(format!(
                "the read returned {} on the emulator, {} on the plain model",
                byte(a),
                byte(b)
            )));
        }
        if fast.now() != plain.now() {
            return Err(disagree(format!(
                "clocks at {} and {}",
                fast.now(),
                plain.now()
            )));
        }
        let (pa, pb) = (fast.pins(), plain.pins());
        if pa != pb {
            fast_pins.add(&fast.record().pins);
            plain_pins.add(plain.pin_events());
            return Err(disagree(format!(
                "pins {pa:?} against {pb:?}; the last pin changes: {} against {}",
                fast_pins.last(3),
                plain_pins.last(3)
            )));
        }
        let pulses = fresh_pulses(&fast.record().runs, &mut cursor);
        let theirs = &plain.pulses()[seen.pulses.min(plain.pulses().len())..];
        for (k, (x, y)) in pulses.iter().zip(theirs).enumerate() {
            if x != y {
                return Err(disagree(format!(
                    "pulse {} at {} {:?} against {} {:?}",
                    seen.pulses + k + 1,
                    x.0,
                    x.1,
                    y.0,
                    y.1
                )));
            }
        }
        if pulses.len() != theirs.len() {
            return Err(disagree(format!(
                "{} pulses against {}",
                seen.pulses + pulses.len(),
                seen.pulses + theirs.len()
            )));
        }
        seen.pulses += pulses.len();
        fast_pins.add(&fast.record().pins);
        plain_pins.add(plain.pin_events());
        let n = fast_pins.changes.len().min(plain_pins.changes.len());
        for k in seen.pin_changes..n {
            let (x, y) = (fast_pins.changes[k], plain_pins.changes[k]);
            if x != y {
                return Err(disagree(format!(
                    "pin change {}: {} against {}",
                    k + 1,
                    change(x),
                    change(y)
                )));
            }
        }
        if fast_pins.changes.len() != plain_pins.changes.len() {
            let (longer, which) = if fast_pins.changes.len() > n {
                (&fast_pins.changes, "the emulator")
            } else {
                (&plain_pins.changes, "the plain model")
            };
            return Err(disagree(format!(
                "only {} shows pin change {}: {}",
                which,
                n + 1,
                change(longer[n])
            )));
        }
        seen.pin_changes = n;
        seen.ops = i + 1;
    }
    Ok(seen)
}

/// The pulses of `runs` from `cursor` on, one by one, and the cursor moved
/// past them. Only the last run of a record grows, so what came before
/// the cursor is never read again: a check costs time linear in its
/// pulses, not quadratic.
fn fresh_pulses(runs: &[PulseRun], cursor: &mut (usize, u32)) -> Vec<(Instant, Direction)> {
    let mut out = Vec::new();
    while let Some(r) = runs.get(cursor.0) {
        out.extend((cursor.1..r.count).map(|i| (r.at(i), r.dir)));
        if cursor.0 + 1 == runs.len() {
            cursor.1 = r.count;
            break;
        }
        *cursor = (cursor.0 + 1, 0);
    }
    out
}

/// Applies one op to the plain model; the byte a read returned.
pub fn apply(chip: &mut PlainChip, op: BusOp) -> Option<u8> {
    match op {
        BusOp::Command(b) => chip.write_command(b),
        BusOp::Data(b) => chip.write_data(b),
        BusOp::ReadStatus => return Some(chip.read_status()),
        BusOp::ReadData => return Some(chip.read_data()),
        BusOp::Input { input, asserted } => chip.set_input(input, asserted),
        BusOp::Advance(d) => chip.advance_to(chip.now() + d),
    }
    None
}

fn byte(b: Option<u8>) -> String {
    b.map_or("nothing".into(), |b| format!("0x{b:02X}"))
}

fn change(e: PinEvent) -> String {
    format!("{} = {} at {}", e.pin.name(), e.value, e.at)
}

/// The pin events of a record that change a level, in order.
#[derive(Default)]
struct Changes {
    read: usize,
    level: [u8; Pin::ALL.len()],
    changes: Vec<PinEvent>,
}

impl Changes {
    fn last(&self, n: usize) -> String {
        let from = self.changes.len().saturating_sub(n);
        let list: Vec<String> = self.changes[from..].iter().map(|e| change(*e)).collect();
        format!("[{}]", list.join(", "))
    }

    fn add(&mut self, events: &[PinEvent]) {
        for e in &events[self.read.min(events.len())..] {
            let slot = &mut self.level[e.pin as usize];
            if *slot != e.value {
                *slot = e.value;
                self.changes.push(*e);
            }
        }
        self.read = events.len();
    }
}
