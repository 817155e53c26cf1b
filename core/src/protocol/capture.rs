//! What the chip did on its output pins, recorded compactly: the capture
//! format every target produces (the emulator directly, a board through the
//! bus bridge's timestamped capture).
//!
//! Pulses are stored as runs of equally spaced pulses in one direction, so a
//! constant-rate stretch of any length costs one entry; acceleration ramps
//! cost one entry per change of period. [`OutputRecord::pulses`] expands the runs
//! into single pulses on request.

use super::command::{Direction, MoveKind};
use super::phase::Winding;
use crate::time::{Duration, Instant};
use alloc::vec::Vec;

/// `count` pulses in `dir`: the first at `start`, the last `span` later,
/// the others on the straight line between them, each within `jitter` of
/// its place on that line.
///
/// A run from the emulator, or from a bridge whose timer is locked to the
/// chip's clock, is exact: `jitter` is zero and the pulses are equally
/// spaced, `span / (count - 1)` apart. A bridge whose timer is not locked to
/// the chip sees each edge up to a tick late, so its intervals wobble by a
/// tick; it merges pulses into one run as long as every pulse stays within
/// its tolerance of the line, and says so in `jitter`
/// ([`EdgeRuns`], `docs/bridge-protocol.md` section 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PulseRun {
    pub start: Instant,
    pub count: u32,
    pub dir: Direction,
    /// From the first pulse to the last (zero for a single pulse).
    pub span: Duration,
    /// Bound on how far any pulse of the run lies from its place on the
    /// line from the first pulse to the last.
    pub jitter: Duration,
}

impl PulseRun {
    /// `count` pulses exactly `interval` apart.
    pub fn exact(start: Instant, interval: Duration, count: u32, dir: Direction) -> PulseRun {
        PulseRun {
            start,
            count,
            dir,
            span: interval.saturating_mul(u64::from(count.saturating_sub(1))),
            jitter: Duration::ZERO,
        }
    }

    /// Time of the last pulse in the run.
    pub fn last(&self) -> Instant {
        self.start + self.span
    }

    /// The interval between consecutive pulses: exact for an exact run, the
    /// mean (to the nanosecond below) otherwise; zero for a single pulse.
    pub fn interval(&self) -> Duration {
        match self.count {
            0 | 1 => Duration::ZERO,
            n => Duration::from_nanos(self.span.as_nanos() / u64::from(n - 1)),
        }
    }

    /// Whether the pulses are exactly `interval` apart (always, for a single
    /// pulse): [`PulseRun::is_exact`] with that [`PulseRun::interval`],
    /// without a division.
    pub fn spaced(&self, interval: Duration) -> bool {
        self.jitter == Duration::ZERO
            && match self.count {
                0 => interval == Duration::ZERO,
                1 => true,
                n => {
                    interval.as_nanos().checked_mul(u64::from(n - 1)) == Some(self.span.as_nanos())
                }
            }
    }

    /// Whether the pulses are equally spaced to the nanosecond.
    pub fn is_exact(&self) -> bool {
        self.jitter == Duration::ZERO
            && (self.count < 2 || self.span.as_nanos() % u64::from(self.count - 1) == 0)
    }

    /// Where pulse `k` (from 0) lies on the line from the first pulse to
    /// the last: its time for an exact run, within `jitter` of it
    /// otherwise.
    pub fn at(&self, k: u32) -> Instant {
        match self.count {
            0 | 1 => self.start,
            n => {
                let off = u128::from(self.span.as_nanos()) * u128::from(k) / u128::from(n - 1);
                self.start + Duration::from_nanos(u64::try_from(off).unwrap_or(u64::MAX))
            }
        }
    }

    /// How many pulses of the run lie at or before `t` on the line from the
    /// first pulse to the last.
    pub fn count_until(&self, t: Instant) -> u32 {
        if self.start > t {
            return 0;
        }
        if self.count < 2 || self.span == Duration::ZERO {
            return self.count;
        }
        let since = u128::from(t.saturating_since(self.start).as_nanos());
        let k = since * u128::from(self.count - 1) / u128::from(self.span.as_nanos()) + 1;
        u32::try_from(k).map_or(self.count, |k| k.min(self.count))
    }

    /// The first `n` pulses of the run (`n` at least 1, at most `count`).
    pub fn first(&self, n: u32) -> PulseRun {
        let n = n.clamp(1, self.count.max(1));
        PulseRun {
            count: n,
            span: self.at(n - 1).saturating_since(self.start),
            jitter: if n > 1 { self.jitter } else { Duration::ZERO },
            ..*self
        }
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
    /// A bridge that samples S1..S5 infers it from the chopping it sees
    /// ([`SWITCHING_WINDOW`]).
    Switching,
}

/// How late a bridge that samples S1..S5 with its CPU may report stop
/// switching (`docs/bridge-protocol.md`, pin code 7): it reports the
/// chopping from its first edge, Diagram 3-5's ON stretch after it began
/// (at most about 0.8 ms at 16 MHz, Equations 3-5 and 3-6), and its end
/// when this long passes with no edge. A stretch of stop switching that
/// ends before its first edge shows nothing to see.
pub const SWITCHING_WINDOW: crate::time::Duration = crate::time::Duration::from_micros(1000);

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
    /// When the final byte of the command was written: the write a bridge
    /// sees (N47). The move runs from when the chip took that byte, which
    /// is later when the byte waited in the input buffer (a command written
    /// during a move the chip finishes first); its pulses are its runs
    /// from `first_run`, whenever they come.
    pub at: Instant,
    pub kind: MoveKind,
    pub dir: Direction,
    pub pout: bool,
    /// Number of steps requested (16,777,216 for the continuous modes).
    pub steps: u32,
    /// Index into [`OutputRecord::runs`] of this move's first run.
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
    /// How far the true shortest and longest interval may be from
    /// `min_interval` and `max_interval`: zero when every run is exact; for
    /// a run with jitter, whose mean interval stands for its intervals,
    /// twice its jitter plus the nanosecond the mean is rounded by.
    pub interval_bound: Duration,
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
            // On a run with jitter, the intervals' spread is not known:
            // its mean stands for them, within the bound.
            self.add_interval(run.interval());
            if !run.is_exact() {
                let spread = run.jitter.saturating_mul(2) + Duration::from_nanos(1);
                self.interval_bound = self.interval_bound.max(spread);
            }
        }
        self.first.get_or_insert(run.start);
        self.last = Some(run.last());
    }

    fn add_interval(&mut self, d: Duration) {
        self.min_interval = Some(self.min_interval.map_or(d, |m| m.min(d)));
        self.max_interval = Some(self.max_interval.map_or(d, |m| m.max(d)));
    }
}

/// A point in an [`OutputRecord`]: how many runs, pin changes and moves it held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OutputMark {
    pub runs: usize,
    pub pins: usize,
    pub moves: usize,
}

impl OutputMark {
    /// Both counted together: a mark past what was dropped.
    pub fn plus(self, o: OutputMark) -> OutputMark {
        OutputMark {
            runs: self.runs + o.runs,
            pins: self.pins + o.pins,
            moves: self.moves + o.moves,
        }
    }

    /// `self` counted from `o` on (0 where it lies before `o`).
    pub fn minus(self, o: OutputMark) -> OutputMark {
        OutputMark {
            runs: self.runs.saturating_sub(o.runs),
            pins: self.pins.saturating_sub(o.pins),
            moves: self.moves.saturating_sub(o.moves),
        }
    }

    /// Whether `self` lies before `o` in any kind of record.
    pub fn before(self, o: OutputMark) -> bool {
        self.runs < o.runs || self.pins < o.pins || self.moves < o.moves
    }
}

/// Everything observable on the output side since reset.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct OutputRecord {
    pub runs: Vec<PulseRun>,
    pub pins: Vec<PinEvent>,
    pub moves: Vec<MoveStart>,
    /// Bytes the host wrote while IBF was 1, which replaced an earlier byte
    /// that the chip never saw (Section 3-1-1 (2)).
    pub overwritten_bytes: u64,
}

impl OutputRecord {
    /// Empties the record, keeping the memory it had.
    pub fn clear(&mut self) {
        self.runs.clear();
        self.pins.clear();
        self.moves.clear();
        self.overwritten_bytes = 0;
    }

    /// Appends `count` pulses spaced exactly `interval` apart starting at
    /// `start`, merging with the previous run when the spacing continues
    /// it.
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
        let run = PulseRun::exact(start, interval, count, dir);
        if !new_move {
            if let Some(last) = self.runs.last_mut() {
                let gap = start.saturating_since(last.last());
                if last.dir == dir && last.spaced(gap) {
                    let continues = count == 1 || interval == gap;
                    if continues && gap > Duration::ZERO {
                        last.count += count;
                        last.span = run.last().saturating_since(last.start);
                        return;
                    }
                }
            }
        }
        self.runs.push(run);
    }

    /// Appends `count` pulses spaced exactly `interval` apart as
    /// [`OutputRecord::push_pulses`] would record them pushed one at a time: the
    /// first may join the previous run, the rest join it too if they keep
    /// its spacing, else they are a run of their own. Costs O(1).
    pub fn push_pulses_singly(
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
        self.push_pulses(start, interval, 1, dir, new_move);
        if count == 1 {
            return;
        }
        let rest = count - 1;
        if let Some(last) = self.runs.last_mut() {
            if interval > Duration::ZERO && last.spaced(interval) {
                last.count += rest;
                last.span += interval.saturating_mul(u64::from(rest));
                return;
            }
        }
        // The second pulse starts a run; every later one keeps its spacing.
        self.runs
            .push(PulseRun::exact(start + interval, interval, rest, dir));
    }

    pub fn pin(&mut self, at: Instant, pin: Pin, value: u8) {
        self.pins.push(PinEvent { at, pin, value });
    }

    /// How far the record reaches: where [`OutputRecord::since`] starts.
    pub fn mark(&self) -> OutputMark {
        OutputMark {
            runs: self.runs.len(),
            pins: self.pins.len(),
            moves: self.moves.len(),
        }
    }

    /// Drops what came before `mark` (a mark of this record), as far as
    /// it may go: the last move and its pulse runs stay (the last run may
    /// still grow, and the pulses of the last move are still read). A run
    /// that has compared what came before keeps only a window so, and its
    /// memory does not grow with its length. Returns what was dropped: a
    /// mark taken before counts from the new start once it is subtracted.
    pub fn forget_before(&mut self, mark: OutputMark) -> OutputMark {
        let moves = mark.moves.min(self.moves.len().saturating_sub(1));
        let runs = mark
            .runs
            .min(self.runs.len().saturating_sub(1))
            .min(self.moves.get(moves).map_or(usize::MAX, |m| m.first_run));
        let dropped = OutputMark {
            runs,
            pins: mark.pins.min(self.pins.len()),
            moves,
        };
        self.drop_front(dropped);
        dropped
    }

    /// Drops the first `n.runs` runs, `n.pins` pin changes and `n.moves`
    /// moves (each at most what there is); the moves left count their
    /// runs from the new first.
    pub fn drop_front(&mut self, n: OutputMark) {
        let runs = n.runs.min(self.runs.len());
        self.runs.drain(..runs);
        self.pins.drain(..n.pins.min(self.pins.len()));
        self.moves.drain(..n.moves.min(self.moves.len()));
        for m in &mut self.moves {
            m.first_run = m.first_run.saturating_sub(runs);
        }
    }

    /// The record from `mark` on: the runs, pin changes and moves added
    /// since (a move's `first_run` counted from the mark's first run).
    pub fn since(&self, mark: OutputMark) -> OutputRecord {
        OutputRecord {
            runs: self.runs.get(mark.runs..).unwrap_or_default().to_vec(),
            pins: self.pins.get(mark.pins..).unwrap_or_default().to_vec(),
            moves: self
                .moves
                .get(mark.moves..)
                .unwrap_or_default()
                .iter()
                .map(|m| MoveStart {
                    first_run: m.first_run.saturating_sub(mark.runs),
                    ..*m
                })
                .collect(),
            overwritten_bytes: self.overwritten_bytes,
        }
    }

    /// The last move whose final command byte was written by `at`, with
    /// its pulse runs (up to the next move's first).
    pub fn move_written_by(&self, at: Instant) -> Option<(&MoveStart, &[PulseRun])> {
        let k = self.moves.iter().rposition(|m| m.at <= at)?;
        Some((&self.moves[k], self.runs_of_move(k)))
    }

    /// The pulse runs of move `k` (of [`OutputRecord::moves`]): from its first
    /// run up to the next move's first; none for a move not recorded.
    pub fn runs_of_move(&self, k: usize) -> &[PulseRun] {
        let Some(m) = self.moves.get(k) else {
            return &[];
        };
        let end = self
            .moves
            .get(k + 1)
            .map_or(self.runs.len(), |n| n.first_run)
            .min(self.runs.len());
        &self.runs[m.first_run.min(end)..end]
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
    pub fn until(&self, t: Instant) -> OutputRecord {
        let runs = self
            .runs
            .iter()
            .filter(|r| r.start <= t)
            .map(|r| r.first(r.count_until(t)))
            .collect();
        OutputRecord {
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
        self.runs
            .iter()
            .flat_map(|r| (0..r.count).map(move |i| (r.at(i), r.dir)))
    }
}

/// Builds pulse runs from edges timestamped one at a time by a timer that
/// is not locked to the chip's clock, as a bridge does.
///
/// Such a timer sees a train of equally spaced pulses with intervals that
/// wobble by a tick, so runs cannot merge on equal intervals. Instead a
/// pulse joins the current run when every pulse of the run stays within
/// `tolerance` of the straight line from the run's first pulse to the new
/// one; the run's `jitter` is then `tolerance` (zero while the pulses are
/// equally spaced to the nanosecond). A constant-rate train of any length
/// stays one run when `tolerance` covers the timer's resolution; each step
/// of an acceleration ramp starts a new run, as it does on the emulator.
///
/// Each pulse costs O(1): the run keeps the range of slopes, as fractions,
/// that the line may still take (the slopes that keep every pulse so far
/// within `tolerance`), and the new pulse joins when the line to it has a
/// slope in that range.
#[derive(Debug, Clone)]
pub struct EdgeRuns {
    tolerance: Duration,
    /// Lowest slope, nanoseconds per pulse as `(num, den)`.
    lo: (u64, u64),
    /// Highest slope; `den` 0 when there is no bound yet.
    hi: (u64, u64),
    /// Whether the record's last run is this builder's to extend.
    open: bool,
}

impl EdgeRuns {
    pub fn new(tolerance: Duration) -> EdgeRuns {
        EdgeRuns {
            tolerance,
            lo: (0, 1),
            hi: (0, 0),
            open: false,
        }
    }

    pub fn tolerance(&self) -> Duration {
        self.tolerance
    }

    /// The next pulse starts a new run (after a chip reset, or when the
    /// record was started over).
    pub fn reset(&mut self) {
        self.open = false;
    }

    /// Records a pulse at `at` in `dir` into `rec`; `new_move` when it is
    /// the first pulse of a move (a run holds one move's pulses only).
    pub fn push(&mut self, rec: &mut OutputRecord, at: Instant, dir: Direction, new_move: bool) {
        if !new_move && self.open {
            if let Some(last) = rec.runs.last_mut() {
                if last.dir == dir && at > last.last() && last.count < u32::MAX {
                    if let Some(joined) = self.join(last, at) {
                        *last = joined;
                        return;
                    }
                }
            }
        }
        rec.runs.push(PulseRun::exact(at, Duration::ZERO, 1, dir));
        self.lo = (0, 1);
        self.hi = (0, 0);
        self.open = true;
    }

    /// `run` with a pulse at `at` added, if the pulse keeps the run within
    /// the tolerance.
    fn join(&mut self, run: &PulseRun, at: Instant) -> Option<PulseRun> {
        let n = u64::from(run.count); // the new pulse's index in the run
        let d = at.saturating_since(run.start).as_nanos(); // the line's slope: d / n
        let (wide_d, wide_n) = (u128::from(d), u128::from(n));
        let above_lo = u128::from(self.lo.0) * wide_n <= wide_d * u128::from(self.lo.1);
        let below_hi =
            self.hi.1 == 0 || wide_d * u128::from(self.hi.1) <= u128::from(self.hi.0) * wide_n;
        if !(above_lo && below_hi) {
            return None;
        }
        let e = self.tolerance.as_nanos();
        let lo = (d.saturating_sub(e), n);
        if u128::from(lo.0) * u128::from(self.lo.1) > u128::from(self.lo.0) * u128::from(lo.1) {
            self.lo = lo;
        }
        let hi = (d.saturating_add(e), n);
        if self.hi.1 == 0
            || u128::from(hi.0) * u128::from(self.hi.1) < u128::from(self.hi.0) * u128::from(hi.1)
        {
            self.hi = hi;
        }
        let exact =
            run.is_exact() && (run.count == 1 || at.saturating_since(run.last()) == run.interval());
        Some(PulseRun {
            count: run.count + 1,
            span: Duration::from_nanos(d),
            jitter: if exact {
                Duration::ZERO
            } else {
                self.tolerance
            },
            ..*run
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(us: u64) -> Instant {
        Instant::from_nanos(us * 1_000)
    }

    /// Forgetting keeps the last move and its runs (the model still reads
    /// its pulses), whatever the mark asks; the moves left count their runs
    /// from the new first, and the last move's pulses read as before.
    #[test]
    fn forgetting_keeps_the_last_move_and_rebases_it() {
        let mut rec = OutputRecord::default();
        for k in 0..3u32 {
            rec.moves.push(MoveStart {
                at: t(u64::from(k) * 100),
                kind: MoveKind::Constant,
                dir: Direction::Cw,
                pout: false,
                steps: 4,
                first_run: rec.runs.len(),
                phase_index: 0,
                winding: None,
            });
            rec.push_pulses(
                t(u64::from(k) * 100 + 1),
                Duration::from_micros(1),
                2,
                Direction::Cw,
                true,
            );
            rec.push_pulses(
                t(u64::from(k) * 100 + 10),
                Duration::from_micros(2),
                2,
                Direction::Cw,
                false,
            );
            rec.pin(t(u64::from(k) * 100 + 20), Pin::Busy, 0);
        }
        let last = rec.last_move_pulses();
        let everything = rec.mark();
        let dropped = rec.forget_before(everything);
        assert_eq!(
            dropped,
            OutputMark {
                runs: 4,
                pins: 3,
                moves: 2
            }
        );
        assert_eq!((rec.runs.len(), rec.pins.len(), rec.moves.len()), (2, 0, 1));
        assert_eq!(rec.moves[0].first_run, 0);
        assert_eq!(rec.last_move_pulses(), last);
        // A mark short of that drops only what lies before it.
        let mut again = rec.clone();
        assert_eq!(
            again.forget_before(OutputMark::default()),
            OutputMark::default()
        );
        assert_eq!(again, rec);
    }

    proptest::proptest! {
        /// `push_pulses_singly` records what pushing the pulses one at a
        /// time records, whatever runs came before.
        #[test]
        fn pushing_singly_is_one_at_a_time(
            before in proptest::collection::vec((1u64..5, 1u32..4), 0..4),
            gap in 1u64..5,
            interval in 1u64..5,
            count in 1u32..6,
            new_move: bool,
        ) {
            let mut rec = OutputRecord::default();
            let mut at = 0;
            for (i, (dt, n)) in before.iter().enumerate() {
                at += 10;
                rec.push_pulses(t(at), Duration::from_micros(*dt), *n, Direction::Cw, i == 0);
                at += dt * u64::from(n - 1);
            }
            let start = t(at + gap);
            let d = Duration::from_micros(interval);
            let mut one_by_one = rec.clone();
            for k in 0..count {
                one_by_one.push_pulses(start + d.saturating_mul(u64::from(k)), d, 1, Direction::Cw, new_move && k == 0);
            }
            rec.push_pulses_singly(start, d, count, Direction::Cw, new_move);
            proptest::prop_assert_eq!(rec, one_by_one);
        }
    }

    #[test]
    fn equal_spacing_merges_into_one_run() {
        let mut r = OutputRecord::default();
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
        let mut r = OutputRecord::default();
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
        assert_eq!(cut.runs[1].span, Duration::ZERO);
        assert_eq!(r.until(t(10_000)), r);
    }

    #[test]
    fn summary_counts_intervals_across_runs() {
        let mut r = OutputRecord::default();
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

    /// Each of `times` within its run's jitter of its place on the run's
    /// line, in order, and none lost.
    fn assert_within_jitter(r: &OutputRecord, times: &[u64]) {
        assert_eq!(r.pulse_count(), times.len() as u64);
        let mut k = 0;
        for run in &r.runs {
            for i in 0..run.count {
                let got = times[k];
                let line = run.at(i).as_nanos();
                assert!(
                    got.abs_diff(line) <= run.jitter.as_nanos(),
                    "pulse {k} at {got} ns, {line} ns on its run's line, jitter {}",
                    run.jitter
                );
                k += 1;
            }
            assert_eq!(
                run.last().as_nanos(),
                times[k - 1],
                "a run ends on its last pulse"
            );
        }
    }

    /// Pulses at `times`, all one move, through an `EdgeRuns`.
    fn edge_record(times: &[u64], tolerance: u64) -> OutputRecord {
        let mut r = OutputRecord::default();
        let mut e = EdgeRuns::new(Duration::from_nanos(tolerance));
        for (i, t) in times.iter().enumerate() {
            e.push(&mut r, Instant::from_nanos(*t), Direction::Cw, i == 0);
        }
        r
    }

    /// Times of a pulse train every `interval_ps` picoseconds, seen by a
    /// timer of `hz` (each edge at the nearest tick, in whole nanoseconds).
    fn seen_by(hz: u64, interval_ps: u64, count: u64) -> Vec<u64> {
        (0..count)
            .map(|k| {
                let ps = 1_000_000 + k * interval_ps;
                let tick = (u128::from(ps) * u128::from(hz) + 500_000_000_000) / 1_000_000_000_000;
                (tick * 1_000_000_000 / u128::from(hz)) as u64
            })
            .collect()
    }

    #[test]
    fn a_constant_rate_seen_by_an_unlocked_timer_is_one_run() {
        // 10.0003 us between pulses, a 150 MHz timer: the intervals wobble
        // by a tick, and a tick plus a nanosecond of tolerance keeps them
        // one run, every pulse within the bound.
        let times = seen_by(150_000_000, 10_000_300, 200_000);
        let r = edge_record(&times, 6_667 / 1_000 + 2);
        assert_eq!(r.runs.len(), 1, "{:?}", &r.runs[..r.runs.len().min(3)]);
        assert_eq!(r.runs[0].jitter, Duration::from_nanos(8));
        assert_within_jitter(&r, &times);
        // Equal intervals would have needed a run per wobble.
        let mut exact = OutputRecord::default();
        for (i, w) in times.windows(2).enumerate() {
            exact.push_pulses(
                Instant::from_nanos(w[0]),
                Duration::from_nanos(w[1] - w[0]),
                1,
                Direction::Cw,
                i == 0,
            );
        }
        assert!(exact.runs.len() > 1_000, "{} runs", exact.runs.len());
    }

    #[test]
    fn equally_spaced_edges_stay_exact_and_a_new_rate_starts_a_run() {
        let mut times: Vec<u64> = (0..50).map(|k| 1_000 + k * 2_500).collect();
        let end = *times.last().unwrap_or(&0);
        times.extend((1..30).map(|k| end + k * 2_000));
        let r = edge_record(&times, 10);
        assert_eq!(r.runs.len(), 2);
        assert!(r.runs.iter().all(PulseRun::is_exact));
        assert_eq!(
            (r.runs[0].interval(), r.runs[1].interval()),
            (Duration::from_nanos(2_500), Duration::from_nanos(2_000))
        );
        assert_eq!((r.runs[0].count, r.runs[1].count), (50, 29));
        assert_within_jitter(&r, &times);
    }

    #[test]
    fn wobbling_edges_never_leave_their_bound() {
        // Pulses with random wobble of up to `w` ns around a steady rate,
        // merged with tolerances below, at and above the wobble: whatever
        // the runs, every pulse is within its run's jitter of the line.
        let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for w in [0u64, 1, 3, 20] {
            for tolerance in [0u64, 1, 2, 5, 40] {
                let times: Vec<u64> = (0..5_000u64)
                    .map(|k| 10_000 + k * 997 + next() % (w + 1))
                    .collect();
                let r = edge_record(&times, tolerance);
                assert_within_jitter(&r, &times);
                if tolerance >= 2 * w {
                    assert_eq!(r.runs.len(), 1, "wobble {w}, tolerance {tolerance}");
                }
            }
        }
    }

    #[test]
    fn a_run_cut_short_keeps_its_line() {
        let times = seen_by(150_000_000, 3_333_300, 1_000);
        let r = edge_record(&times, 8);
        let run = r.runs[0];
        let t = Instant::from_nanos(times[500]);
        assert_eq!(run.count_until(t), 501);
        let cut = run.first(501);
        assert_eq!((cut.count, cut.jitter), (501, run.jitter));
        assert_eq!(cut.at(250), run.at(250));
        assert_eq!(run.first(1).jitter, Duration::ZERO);
    }
}
