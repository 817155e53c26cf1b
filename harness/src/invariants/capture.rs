//! The invariants a capture shows alone, whatever the host did: the BUSY
//! line at an instant, every pulse inside BUSY (`busy-covers-pulses`), a
//! move's shortest pulse interval (for `min-interval`), the phases from
//! move to move (`phase-pattern`) and the record's own order
//! (`record-ordered`). The rules ([`super::rules`]) call them.

use crate::protocol::capture::{OutputRecord, Pin, PulseRun};
use crate::time::{Duration, Instant};

/// The level of the recorded BUSY line at `t` (changes at `t` included).
pub(crate) fn busy_level(rec: &OutputRecord, t: Instant) -> bool {
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
pub(super) fn pulse_outside_busy(rec: &OutputRecord) -> Option<String> {
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

/// The first interval among `runs` (one move's pulses) that is surely
/// shorter than `bound`: within a run, its mean interval less what its
/// jitter leaves unknown; between runs, the gap less both runs' jitter.
pub(super) fn shortest_interval_below(runs: &[PulseRun], bound: Duration) -> Option<String> {
    let mut prev: Option<&PulseRun> = None;
    for r in runs {
        if let Some(p) = prev {
            let gap = r.start.saturating_since(p.last());
            if gap + p.jitter + r.jitter < bound {
                return Some(format!(
                    "pulses at {} and {}, {gap} apart,",
                    p.last(),
                    r.start
                ));
            }
        }
        if r.count > 1 {
            let spread = if r.is_exact() {
                Duration::ZERO
            } else {
                r.jitter.saturating_mul(2) + Duration::from_nanos(1)
            };
            if r.interval() + spread < bound {
                return Some(format!(
                    "{} pulses from {} every {}",
                    r.count,
                    r.start,
                    r.interval()
                ));
            }
        }
        prev = Some(r);
    }
    None
}

/// Section 3-2-1 (the excitation sequences) and 3-3: each pulse of a move
/// in phase excitation mode steps the phases once, in the move's
/// direction, so a move starts where the one before left the phases: its
/// start index is the last one's advanced by that move's pulses. Moves in
/// POUT mode hold the phases. Where the phases were set outside stepping
/// between two moves (initialization, excitation off), the move starts at
/// the pattern last set, which must be a step of its sequence. No claim
/// for a move written before the one before it put out its last pulse, or
/// while the phases were still being set (a change after its command and
/// before its first pulse), nor for the move after it.
pub(super) fn phase_breaks(rec: &OutputRecord) -> Option<String> {
    let mut pins = rec.pins.iter().filter(|p| p.pin == Pin::Phases).peekable();
    // Where the last stepping move left the phases: its winding, index and
    // last pulse.
    let mut left: Option<(crate::protocol::Winding, u32, Instant)> = None;
    let mut set: Option<u8> = None;
    for (k, m) in rec.moves.iter().enumerate() {
        while let Some(p) = pins.next_if(|p| p.at <= m.at) {
            set = Some(p.value);
            left = None;
        }
        let runs = rec.runs_of_move(k);
        let horizon = runs.first().map_or(m.at, |r| r.start);
        let mut unsettled = false;
        while let Some(p) = pins.next_if(|p| p.at <= horizon) {
            set = Some(p.value);
            unsettled = true;
        }
        if let Some(r) = runs.iter().find(|r| r.dir != m.dir) {
            return Some(format!(
                "the {} move written at {} is commanded {}, but its pulses from {} go {}",
                m.kind.name(),
                m.at,
                m.dir.name(),
                r.start,
                r.dir.name()
            ));
        }
        let Some(w) = m.winding else {
            continue; // POUT mode: the phases hold
        };
        if unsettled {
            left = None;
            set = None;
            continue;
        }
        let start = m.phase_index % w.steps_per_cycle();
        if let Some(v) = set.take().filter(|v| *v != 0) {
            if w.pattern(start) != v {
                let legal = (0..w.steps_per_cycle()).any(|i| w.pattern(i) == v);
                return Some(format!(
                    "the {} move written at {} starts at step {start} of {} ({:05b}), but the phases were last set to {v:05b}{}",
                    m.kind.name(),
                    m.at,
                    w.name(),
                    w.pattern(start),
                    if legal { "" } else { ", which is no step of that sequence" }
                ));
            }
        } else if let Some((_, index, last)) = left.filter(|(lw, ..)| *lw == w) {
            if last <= m.at && start != index {
                return Some(format!(
                    "the {} move written at {} starts at step {start} of {}, but the pulses before it left the phases at step {index}",
                    m.kind.name(),
                    m.at,
                    w.name()
                ));
            }
        }
        let mut index = start;
        let mut last = m.at;
        for r in runs {
            index = w.advance(index, r.dir, u64::from(r.count));
            last = r.last();
        }
        left = Some((w, index, last));
    }
    None
}

/// Pulse runs do not overlap and come in time order; pin changes and move
/// starts come in time order.
pub(super) fn record_breaks(rec: &OutputRecord) -> Option<String> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::capture::MoveStart;
    use crate::protocol::MoveKind;

    /// Section 3-2-1: a move starts at the pattern the phases were set to;
    /// a pattern of no step of the sequence breaks `phase-pattern`.
    #[test]
    fn phases_set_to_no_step_of_the_sequence_are_caught() {
        use crate::protocol::{Direction, Excitation, MotorType, Winding};
        let w = Winding {
            motor: MotorType::FourPhase,
            excitation: Excitation::TwoPhase,
        };
        let mut rec = OutputRecord::default();
        rec.pin(Instant::from_nanos(1_000), Pin::Phases, 0b11000);
        rec.moves.push(MoveStart {
            at: Instant::from_nanos(5_000),
            kind: MoveKind::SingleStep,
            dir: Direction::Cw,
            pout: false,
            steps: 1,
            first_run: 0,
            phase_index: 0,
            winding: Some(w),
        });
        assert_eq!(phase_breaks(&rec), None);
        rec.pins[0].value = 0b10100;
        let d = phase_breaks(&rec).expect("a break");
        assert!(d.contains("no step of that sequence"), "{d}");
    }

    #[test]
    fn pulses_outside_busy_are_found() {
        use crate::protocol::{Direction, PinEvent};
        let mut rec = OutputRecord::default();
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
