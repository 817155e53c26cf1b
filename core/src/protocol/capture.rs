//! What the chip did on its output pins, recorded compactly: the capture
//! format every target produces (the emulator directly, a board through the
//! bus bridge's timestamped capture).
//!
//! Pulses are stored as runs of equally spaced pulses in one direction, so a
//! constant-rate stretch of any length costs one entry; acceleration ramps
//! cost one entry per change of period. [`Record::pulses`] expands the runs
//! into single pulses on request.

use super::command::{Direction, MoveKind};
use super::phase::Winding;
use crate::time::{Duration, Instant};
use alloc::vec::Vec;

/// `count` pulses in `dir`, the first at `start`, each `interval` after the
/// previous one (`interval` is zero when `count` is 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PulseRun {
    pub start: Instant,
    pub interval: Duration,
    pub count: u32,
    pub dir: Direction,
}

impl PulseRun {
    /// Time of the last pulse in the run.
    pub fn last(&self) -> Instant {
        self.start
            + self
                .interval
                .saturating_mul(u64::from(self.count.saturating_sub(1)))
    }
}

/// An output pin or output group whose level changed outside of pulse
/// stepping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Pin {
    /// Status BUSY bit (1 = pulse output in progress).
    Busy,
    /// INT* (value 1 = asserted, pin low).
    Int,
    /// HOLD (1 = on).
    Hold,
    /// AUX* (1 = asserted, pin low).
    Aux,
    /// AUXO0..3 (bit set = asserted, pin low).
    Auxo,
    /// DIR (0 = CW, 1 = CCW).
    Dir,
    /// S1..S5 energized pattern, S1 in bit 4, set outside stepping (at
    /// initialization and excitation off).
    Phases,
    /// Stop switching (chopping) of the phase outputs: 1 = active.
    Switching,
}

impl Pin {
    pub const ALL: [Pin; 8] = [
        Pin::Busy,
        Pin::Int,
        Pin::Hold,
        Pin::Aux,
        Pin::Auxo,
        Pin::Dir,
        Pin::Phases,
        Pin::Switching,
    ];

    pub fn from_name(s: &str) -> Option<Pin> {
        Pin::ALL.into_iter().find(|p| p.name() == s)
    }

    pub fn name(self) -> &'static str {
        match self {
            Pin::Busy => "busy",
            Pin::Int => "int",
            Pin::Hold => "hold",
            Pin::Aux => "aux",
            Pin::Auxo => "auxo",
            Pin::Dir => "dir",
            Pin::Phases => "s",
            Pin::Switching => "switching",
        }
    }
}

/// The levels of the output pins at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pins {
    /// INT* asserted (low).
    pub int: bool,
    /// HOLD on.
    pub hold: bool,
    /// AUX* asserted (low).
    pub aux: bool,
    /// AUXO0..3 asserted (low), AUXO0 in bit 0.
    pub auxo: u8,
    /// Energized phases, S1 in bit 4 .. S5 in bit 0.
    pub phases: u8,
    /// S1..S5 pin levels after the output logic, S1 in bit 4.
    pub phase_levels: u8,
    /// DIR output.
    pub dir: Direction,
    /// Status BUSY.
    pub busy: bool,
}

/// A change of an output pin at a point in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PinEvent {
    pub at: Instant,
    pub pin: Pin,
    pub value: u8,
}

/// The start of a move: which operation, and where the pulse record of this
/// move begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MoveStart {
    /// When the final byte of the command was written (as seen by the chip).
    pub at: Instant,
    pub kind: MoveKind,
    pub dir: Direction,
    pub pout: bool,
    /// Number of steps requested (16,777,216 for the continuous modes).
    pub steps: u32,
    /// Index into [`Record::runs`] of this move's first run.
    pub first_run: usize,
    /// Phase step index before the first pulse.
    pub phase_index: u32,
    /// The excitation sequence the pulses step through; `None` in POUT mode
    /// (the phases hold) or before any initialization.
    pub winding: Option<Winding>,
}

/// Summary of a stretch of pulses, as the console's `pulses` prints it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PulseSummary {
    pub count: u64,
    pub cw: u64,
    pub ccw: u64,
    pub first: Option<Instant>,
    pub last: Option<Instant>,
    /// Shortest and longest interval between consecutive pulses.
    pub min_interval: Option<Duration>,
    pub max_interval: Option<Duration>,
}

impl PulseSummary {
    fn add_run(&mut self, run: &PulseRun) {
        if run.count == 0 {
            return;
        }
        let n = u64::from(run.count);
        self.count += n;
        match run.dir {
            Direction::Cw => self.cw += n,
            Direction::Ccw => self.ccw += n,
        }
        if let Some(prev) = self.last {
            self.add_interval(run.start.saturating_since(prev));
        }
        if run.count > 1 {
            self.add_interval(run.interval);
        }
        self.first.get_or_insert(run.start);
        self.last = Some(run.last());
    }

    fn add_interval(&mut self, d: Duration) {
        self.min_interval = Some(self.min_interval.map_or(d, |m| m.min(d)));
        self.max_interval = Some(self.max_interval.map_or(d, |m| m.max(d)));
    }
}

/// Everything observable on the output side since reset.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Record {
    pub runs: Vec<PulseRun>,
    pub pins: Vec<PinEvent>,
    pub moves: Vec<MoveStart>,
    /// Bytes the host wrote while IBF was 1, which replaced an earlier byte
    /// that the chip never saw (Section 3-1-1 (2)).
    pub overwritten_bytes: u64,
}

impl Record {
    /// Appends `count` pulses spaced `interval` apart starting at `start`,
    /// merging with the previous run when the spacing continues it.
    pub fn push_pulses(
        &mut self,
        start: Instant,
        interval: Duration,
        count: u32,
        dir: Direction,
        new_move: bool,
    ) {
        if count == 0 {
            return;
        }
        let interval = if count == 1 { Duration::ZERO } else { interval };
        if !new_move {
            if let Some(last) = self.runs.last_mut() {
                if last.dir == dir {
                    let gap = start.saturating_since(last.last());
                    let spacing_matches = last.count == 1 || last.interval == gap;
                    let continues = count == 1 || interval == gap;
                    if spacing_matches && continues && gap > Duration::ZERO {
                        if last.count == 1 {
                            last.interval = gap;
                        }
                        last.count += count;
                        return;
                    }
                }
            }
        }
        self.runs.push(PulseRun {
            start,
            interval,
            count,
            dir,
        });
    }

    pub fn pin(&mut self, at: Instant, pin: Pin, value: u8) {
        self.pins.push(PinEvent { at, pin, value });
    }

    /// Summary of the pulses of the most recent move (all pulses if no move
    /// has started).
    pub fn last_move_pulses(&self) -> PulseSummary {
        let from = self.moves.last().map_or(0, |m| m.first_run);
        self.summarize(from)
    }

    /// Summary of all pulses from run index `from` on.
    pub fn summarize(&self, from: usize) -> PulseSummary {
        let mut s = PulseSummary::default();
        for run in self.runs.iter().skip(from) {
            s.add_run(run);
        }
        s
    }

    /// The record as it stood at `t`: the pulses, pin changes and moves up
    /// to and including `t`, a pulse run cut at its last pulse by then.
    pub fn until(&self, t: Instant) -> Record {
        let runs = self
            .runs
            .iter()
            .filter(|r| r.start <= t)
            .map(|r| {
                let mut r = *r;
                if r.last() > t {
                    // `last` is after `start`, so the interval is not zero.
                    let on_time =
                        t.saturating_since(r.start).as_nanos() / r.interval.as_nanos().max(1) + 1;
                    r.count = u32::try_from(on_time).unwrap_or(r.count).min(r.count);
                    if r.count == 1 {
                        r.interval = Duration::ZERO;
                    }
                }
                r
            })
            .collect();
        Record {
            runs,
            pins: self.pins.iter().filter(|p| p.at <= t).copied().collect(),
            moves: self.moves.iter().filter(|m| m.at <= t).copied().collect(),
            overwritten_bytes: self.overwritten_bytes,
        }
    }

    /// Total number of pulses recorded.
    pub fn pulse_count(&self) -> u64 {
        self.runs.iter().map(|r| u64::from(r.count)).sum()
    }

    /// Every pulse, one by one: `(time, direction)`.
    pub fn pulses(&self) -> impl Iterator<Item = (Instant, Direction)> + '_ {
        self.runs.iter().flat_map(|r| {
            (0..r.count).map(move |i| (r.start + r.interval.saturating_mul(u64::from(i)), r.dir))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(us: u64) -> Instant {
        Instant::from_nanos(us * 1_000)
    }

    #[test]
    fn equal_spacing_merges_into_one_run() {
        let mut r = Record::default();
        let d = Duration::from_micros(10);
        r.push_pulses(t(0), d, 1, Direction::Cw, true);
        r.push_pulses(t(10), d, 1, Direction::Cw, false);
        r.push_pulses(t(20), d, 100, Direction::Cw, false);
        assert_eq!(r.runs.len(), 1);
        assert_eq!(r.runs[0].count, 102);
        assert_eq!(r.runs[0].last(), t(1010));
        // A different spacing starts a new run; so does a new move.
        r.push_pulses(t(1030), d, 1, Direction::Cw, false);
        r.push_pulses(t(1040), d, 1, Direction::Cw, true);
        assert_eq!(r.runs.len(), 3);
        assert_eq!(r.pulse_count(), 104);
        assert_eq!(r.pulses().count(), 104);
    }

    #[test]
    fn until_cuts_the_record_at_an_instant() {
        let mut r = Record::default();
        let d = Duration::from_micros(10);
        r.push_pulses(t(0), d, 100, Direction::Cw, true);
        r.push_pulses(t(2000), d, 5, Direction::Ccw, true);
        r.pin(t(995), Pin::Busy, 0);
        r.pin(t(1500), Pin::Int, 1);
        // Pulses at 0, 10, ..., 500: 51 of them, the one at 500 included.
        let cut = r.until(t(500));
        assert_eq!(cut.runs.len(), 1);
        assert_eq!(cut.pulse_count(), 51);
        assert_eq!(cut.runs[0].last(), t(500));
        assert!(cut.pins.is_empty());
        let cut = r.until(t(1999));
        assert_eq!((cut.pulse_count(), cut.pins.len()), (100, 2));
        // One pulse left of a run: its interval is zero, as for any
        // one-pulse run.
        let cut = r.until(t(2005));
        assert_eq!(cut.runs[1].count, 1);
        assert_eq!(cut.runs[1].interval, Duration::ZERO);
        assert_eq!(r.until(t(10_000)), r);
    }

    #[test]
    fn summary_counts_intervals_across_runs() {
        let mut r = Record::default();
        r.push_pulses(t(0), Duration::from_micros(50), 3, Direction::Ccw, true);
        r.push_pulses(t(130), Duration::from_micros(30), 2, Direction::Ccw, false);
        let s = r.summarize(0);
        assert_eq!(s.count, 5);
        assert_eq!(s.ccw, 5);
        assert_eq!(s.first, Some(t(0)));
        assert_eq!(s.last, Some(t(160)));
        assert_eq!(s.min_interval, Some(Duration::from_micros(30)));
        assert_eq!(s.max_interval, Some(Duration::from_micros(50)));
    }
}
