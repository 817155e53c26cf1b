//! The invariant oracle: runs bus ops on a fresh emulator and checks,
//! after every op, the invariants of `docs/invariants.md`. Each invariant
//! has a stable id; a finding is bucketed by it.

use super::bus::BusOp;
use crate::emu::{Chip, ChipError, ModelConfig};
use crate::protocol::capture::{Pin, Record};
use crate::protocol::{Status, StatusField, Straps};
use crate::time::Instant;
use crate::trace::Trace;
use std::fmt;

/// Largest number of parameter bytes any command takes (Initialization,
/// Section 3-2): the most bits 6-4 can show without an error.
const MAX_PARAMS: u8 = 4;

/// An invariant break: which invariant, after which op, and what was seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The invariant's id in `docs/invariants.md`, e.g. `status-bit3`.
    pub invariant: &'static str,
    /// Index of the op after which it was seen.
    pub op: usize,
    pub detail: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} after op {}: {}",
            self.invariant, self.op, self.detail
        )
    }
}

/// Runs `ops` on a fresh chip and returns the first invariant break.
pub fn check(ops: &[BusOp], cfg: ModelConfig) -> Result<Option<Violation>, ChipError> {
    let mut chip = Chip::new(Straps::default(), cfg)?;
    let mut last_now = chip.now();
    for (i, op) in ops.iter().enumerate() {
        let fail = |invariant, detail: String| {
            Ok(Some(Violation {
                invariant,
                op: i,
                detail,
            }))
        };
        match *op {
            BusOp::Command(b) => {
                chip.write_command(b);
            }
            BusOp::Data(b) => {
                chip.write_data(b);
            }
            BusOp::ReadStatus => {
                let s = chip.read_status();
                if let Some(v) = status_breaks(s) {
                    return fail(v.0, v.1);
                }
                let line = busy_level(chip.record(), chip.now());
                if s.busy() != line {
                    return fail(
                        "busy-status-matches",
                        format!(
                            "status 0x{:02X} reads BUSY={} at {} while the BUSY line is {}",
                            s.0,
                            u8::from(s.busy()),
                            chip.now(),
                            u8::from(line)
                        ),
                    );
                }
            }
            BusOp::ReadData => {
                chip.read_data();
            }
            BusOp::Input { input, asserted } => chip.set_input(input, asserted),
            BusOp::Advance(d) => chip.advance_to(chip.now() + d),
        }
        if chip.now() < last_now {
            return fail(
                "time-monotonic",
                format!("the clock went from {last_now} back to {}", chip.now()),
            );
        }
        last_now = chip.now();
    }
    // The record only grows, so its own invariants are checked once, at
    // the end (per op they would cost time quadratic in its length).
    let last = ops.len().saturating_sub(1);
    let at_end = |invariant, detail| {
        Ok(Some(Violation {
            invariant,
            op: last,
            detail,
        }))
    };
    if let Some(d) = pulse_outside_busy(chip.record()) {
        return at_end("busy-covers-pulses", d);
    }
    if let Some(d) = record_breaks(chip.record()) {
        return at_end("record-ordered", d);
    }
    if let Some(d) = trace_round_trip(chip.record()) {
        return at_end("trace-round-trip", d);
    }
    Ok(None)
}

/// Section 3-1-1, Diagram 3-1: bit 3 reads 0; without an error, bits 6-4
/// count parameter bytes still due, never more than a command takes.
fn status_breaks(s: Status) -> Option<(&'static str, String)> {
    if s.reserved() {
        return Some(("status-bit3", format!("status 0x{:02X} has bit 3 set", s.0)));
    }
    match s.field() {
        StatusField::ParamsRemaining(n) if n > MAX_PARAMS => Some((
            "status-params",
            format!(
                "status 0x{:02X} asks for {n} more parameter bytes; no command takes more than {MAX_PARAMS}",
                s.0
            ),
        )),
        _ => None,
    }
}

/// The level of the recorded BUSY line at `t` (changes at `t` included).
fn busy_level(rec: &Record, t: Instant) -> bool {
    rec.pins
        .iter()
        .rev()
        .filter(|p| p.pin == Pin::Busy && p.at <= t)
        .map(|p| p.value != 0)
        .next()
        .unwrap_or(false)
}

/// Section 3-1-1 (3): BUSY is 1 "in the middle of pulse output", so every
/// pulse lies in an interval where the BUSY line is 1.
fn pulse_outside_busy(rec: &Record) -> Option<String> {
    let mut busy = rec.pins.iter().filter(|p| p.pin == Pin::Busy).peekable();
    let mut level = false;
    let mut since = Instant::ZERO;
    for r in &rec.runs {
        // The BUSY line as it stands at the run's first pulse.
        while let Some(p) = busy.next_if(|p| p.at <= r.start) {
            level = p.value != 0;
            since = p.at;
        }
        if !level {
            return Some(format!(
                "a pulse at {} while the BUSY line is 0 (since {since})",
                r.start
            ));
        }
        // It must not fall before the run's last pulse.
        if let Some(p) = busy.peek().filter(|p| p.at < r.last() && p.value == 0) {
            return Some(format!(
                "the BUSY line fell at {} with pulses until {}",
                p.at,
                r.last()
            ));
        }
    }
    None
}

/// Pulse runs do not overlap and come in time order; pin changes and move
/// starts come in time order.
fn record_breaks(rec: &Record) -> Option<String> {
    for w in rec.runs.windows(2) {
        if w[1].start <= w[0].last() {
            return Some(format!(
                "pulse run at {} starts before the previous one ends at {}",
                w[1].start,
                w[0].last()
            ));
        }
    }
    for w in rec.pins.windows(2) {
        if w[1].at < w[0].at {
            return Some(format!(
                "pin change at {} recorded after one at {}",
                w[1].at, w[0].at
            ));
        }
    }
    for w in rec.moves.windows(2) {
        if w[1].at < w[0].at {
            return Some(format!(
                "move start at {} recorded after one at {}",
                w[1].at, w[0].at
            ));
        }
    }
    None
}

/// A trace's text parses back to the same trace and renders to the same
/// bytes.
fn trace_round_trip(rec: &Record) -> Option<String> {
    let t = Trace::assemble("fuzz", "-", "emu", Vec::new(), Vec::new(), rec, Vec::new());
    let text = t.render();
    match Trace::parse(&text) {
        Ok(back) if back.render() == text => None,
        Ok(_) => Some("the trace re-renders differently after parsing".into()),
        Err(e) => Some(format!("the trace's own text does not parse: {e}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::Faults;
    use crate::fuzzing::bus::BusOp::*;
    use crate::time::Duration;

    /// Initialization (Section 3-2, the values of `capture_comes_in_chunks`)
    /// then a single step, with status reads between.
    fn init_and_step() -> Vec<BusOp> {
        let gap = Advance(Duration::from_millis(1));
        vec![
            Command(0x06),
            gap,
            Data(100),
            gap,
            Data(20),
            gap,
            Data(100),
            gap,
            Data(0),
            Advance(Duration::from_millis(200)),
            ReadStatus,
            Command(0x4A),
            Advance(Duration::from_millis(5)),
            ReadStatus,
            Advance(Duration::from_millis(5)),
            ReadStatus,
        ]
    }

    /// The sequence is a real one: the chip accepts it without error and
    /// the step comes out.
    #[test]
    fn the_sample_sequence_initializes_and_steps() {
        let mut chip = Chip::new(Straps::default(), ModelConfig::default()).expect("chip");
        for op in init_and_step() {
            match op {
                Command(b) => chip.write_command(b),
                Data(b) => chip.write_data(b),
                ReadStatus => assert_eq!(chip.read_status().0 & 0x80, 0, "no error"),
                Advance(d) => chip.advance_to(chip.now() + d),
                _ => {}
            }
        }
        assert_eq!(chip.record().pulse_count(), 1);
    }

    #[test]
    fn the_clean_model_keeps_every_invariant() {
        let r = check(&init_and_step(), ModelConfig::default()).expect("chip");
        assert_eq!(r, None);
    }

    /// Section 3-1-1: a data line stuck high on bit 3 is an invariant break.
    #[test]
    fn a_stuck_status_bit_is_caught() {
        let cfg = ModelConfig {
            faults: Faults {
                status_stuck_high: 0x08,
                ..Faults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!((v.invariant, v.op), ("status-bit3", 10));
    }

    #[test]
    fn parameter_counts_beyond_four_are_caught() {
        let cfg = ModelConfig {
            faults: Faults {
                status_stuck_high: 0x50,
                ..Faults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, "status-params");
    }

    #[test]
    fn pulses_outside_busy_are_found() {
        use crate::protocol::{Direction, PinEvent};
        let mut rec = Record::default();
        let busy = |at, value| PinEvent {
            at: Instant::from_nanos(at),
            pin: Pin::Busy,
            value,
        };
        rec.pins.push(busy(900, 1));
        rec.pins.push(busy(1_500, 0));
        rec.push_pulses(
            Instant::from_nanos(1_000),
            Duration::from_nanos(100),
            5,
            Direction::Cw,
            true,
        );
        assert_eq!(pulse_outside_busy(&rec), None);
        assert!(busy_level(&rec, Instant::from_nanos(1_000)));
        assert!(!busy_level(&rec, Instant::from_nanos(1_500)));
        // BUSY falling before the run ends.
        rec.pins[1] = busy(1_300, 0);
        assert!(pulse_outside_busy(&rec).is_some_and(|d| d.contains("fell at")));
        // A later run with BUSY at 0.
        rec.pins[1] = busy(1_500, 0);
        rec.push_pulses(
            Instant::from_nanos(2_000),
            Duration::from_nanos(100),
            1,
            Direction::Cw,
            true,
        );
        assert!(pulse_outside_busy(&rec).is_some_and(|d| d.contains("BUSY line is 0")));
    }
}
