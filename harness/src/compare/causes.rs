//! What a change the chip made is timed from in a compare: what made the
//! chip make it (its last input, its last pulse), never a bridge's pace;
//! and how a change timed so is judged, for an output pin and for a flag a
//! wait saw.

use super::rule::{fit, First, Fit};
use super::Tolerances;
use crate::protocol::{Pin, PulseRun};
use crate::time::{Duration, Instant};
use crate::trace::BusEvent;

/// One of the chip's inputs (a write, a data read, an input's change, or
/// its reset), as a cause a change is timed from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Input {
    pub(super) at: Instant,
    pub(super) name: &'static str,
    /// Its number among the trace's inputs the compare pairs: the same
    /// input on both sides has the same number.
    pub(super) n: u64,
    /// A write that waited for IBF = 0: on a bridge, stamped at a strobe
    /// it makes after its wait by its own pace, so what the chip did when
    /// it became ready for the byte may lie before the stamp.
    pub(super) strobe: bool,
}

/// What a trace's times are taken from, at a point in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Anchor {
    /// The start of the move in progress or last made, or the chip's
    /// reset when there was no move since: a move's pulses are timed from
    /// it.
    pub(super) at: Instant,
    /// The chip's last input, and the one before it.
    pub(super) input: Input,
    pub(super) before: Option<Input>,
    /// Inputs counted so far ([`Anchor::input`]).
    pub(super) inputs: u64,
    /// The last bus access that read the status register (a status read,
    /// a wait for a flag, a flowchart write's or read's wait): a bridge
    /// sees BUSY change there, and a change it stamps long after it lies
    /// anywhere between ([`Causes::looked`]).
    pub(super) looked: Instant,
    /// The last run of pulses so far.
    pub(super) run: Option<PulseRun>,
}

impl Default for Anchor {
    /// A trace's start: a trace that starts without a reset (a capture's)
    /// has no input before its first changes.
    fn default() -> Anchor {
        Anchor {
            at: Instant::ZERO,
            input: Input {
                at: Instant::ZERO,
                name: "the trace's start",
                n: 0,
                strobe: false,
            },
            before: None,
            inputs: 0,
            looked: Instant::ZERO,
            run: None,
        }
    }
}

impl Anchor {
    /// The chip took an input at `at`; `counted` where the compare pairs
    /// it with the other side's (its view keeps it), so that the n-th
    /// counted input on one side is the n-th on the other.
    pub(super) fn input(&mut self, at: Instant, name: &'static str, strobe: bool, counted: bool) {
        let n = match counted {
            true => {
                self.inputs += 1;
                self.inputs
            }
            // Matched with no other input by its number.
            false => u64::MAX,
        };
        self.before = Some(self.input);
        self.input = Input {
            at,
            name,
            n,
            strobe,
        };
    }

    /// What a change the chip made at `at` (a flag a wait saw, an output
    /// pin) may be timed from: what made the chip make it, never a
    /// bridge's pace. The chip acts on its inputs (the write before it,
    /// the data read that cleared OBF and INT, an input pin, its reset)
    /// and on its own time since its last pulse (a move's end, INT, the
    /// next command taken: Table 3-3).
    pub(super) fn causes(&self, at: Instant) -> Causes {
        let pulse = self.run.filter(|r| r.start <= at).map(|r| {
            if r.last() <= at || r.count < 2 {
                r.last().min(at)
            } else {
                // The run's last pulse at or before `at`.
                let k = u128::from(at.saturating_since(r.start).as_nanos())
                    * u128::from(r.count - 1)
                    / u128::from(r.span.as_nanos().max(1));
                r.at(u32::try_from(k).unwrap_or(r.count - 1))
            }
        });
        Causes {
            input: self.input,
            before: self.before,
            pulse,
            looked: self.looked,
        }
    }
}

/// What a change the chip made may be timed from ([`Anchor::causes`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Causes {
    input: Input,
    before: Option<Input>,
    pulse: Option<Instant>,
    /// The last access that read the status register before the change.
    pub(super) looked: Instant,
}

impl Default for Input {
    fn default() -> Input {
        Anchor::default().input
    }
}

/// A change timed on both sides from one cause.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Timing {
    pub(super) golden: Duration,
    pub(super) got: Duration,
    pub(super) from: &'static str,
    /// Whether each side's cause was a waited write (golden, got)
    /// ([`Input::strobe`]).
    pub(super) strobes: (bool, bool),
}

impl Causes {
    /// A change at `g` (golden, from `gc`) and at `o` (got, from `oc`),
    /// timed from each cause the two share, the chip's last input first.
    /// The same input on both sides: where a change came between two
    /// inputs on one side and after the second on the other (a bridge
    /// whose writes follow IBF's fall later than the emulator's do), both
    /// are timed from the first.
    pub(super) fn timings(g: Instant, gc: Causes, o: Instant, oc: Causes) -> Vec<Timing> {
        let same = |a: Option<Input>, b: Input| a.filter(|a| a.n == b.n);
        let (gi, oi) = if gc.input.n == oc.input.n {
            (gc.input, oc.input)
        } else if let Some(gb) = same(gc.before, oc.input) {
            (gb, oc.input)
        } else if let Some(ob) = same(oc.before, gc.input) {
            (gc.input, ob)
        } else {
            (gc.input, oc.input)
        };
        let mut t = vec![Timing {
            golden: g.saturating_since(gi.at),
            got: o.saturating_since(oi.at),
            from: gi.name,
            strobes: (gi.strobe, oi.strobe),
        }];
        if let (Some(gp), Some(op)) = (gc.pulse, oc.pulse) {
            t.push(Timing {
                golden: g.saturating_since(gp),
                got: o.saturating_since(op),
                from: "the last pulse before it",
                strobes: (false, false),
            });
        }
        t
    }
}

/// How far a pin's change may lie from where a side's trace puts it,
/// where that side's times are not exact: a time judged as a range.
#[derive(Debug, Clone, Copy)]
pub(super) struct PinSlack {
    /// A change timed from a waited write may be up to a poll's pass and
    /// an access longer than timed: the chip may have acted when it
    /// became ready for the byte, which a bridge's write follows by its
    /// own pace (golden, got; [`Timing::strobes`] says where it applies).
    lag: (Duration, Duration),
    /// BUSY's change, on a side that finds it by reading the status
    /// register, is stamped at the first read that saw it: where that read
    /// came longer than a poll's pass after the one before (a bridge reads
    /// no status while it waits out a delay), the change lies anywhere
    /// between the two (`docs/bridge-protocol.md` section 4), up to this
    /// much earlier.
    gaps: (Duration, Duration),
}

impl PinSlack {
    /// The slack of `pin`'s change at `g` and `o` (with their causes),
    /// on sides whose lag after a waited write is `lag`
    /// ([`super::rule::Unsure::strobe_lag`]; also a poll's pass).
    pub(super) fn of(
        pin: Pin,
        (g, gc): (Instant, &Causes),
        (o, oc): (Instant, &Causes),
        lag: (Duration, Duration),
    ) -> PinSlack {
        let gap = |stamp: Instant, c: &Causes, pass: Duration| {
            let gap = stamp.saturating_since(c.looked);
            match pin == Pin::Busy && pass > Duration::ZERO && gap > pass {
                true => gap,
                false => Duration::ZERO,
            }
        };
        PinSlack {
            lag,
            gaps: (gap(g, gc, lag.0), gap(o, oc, lag.1)),
        }
    }

    fn lags(&self, t: &Timing) -> (Duration, Duration) {
        let on = |strobe: bool, lag: Duration| match strobe {
            true => lag,
            false => Duration::ZERO,
        };
        (on(t.strobes.0, self.lag.0), on(t.strobes.1, self.lag.1))
    }

    /// Whether `t` is a point on both sides (then graded as ever).
    pub(super) fn exact(&self, t: &Timing) -> bool {
        let zero = (Duration::ZERO, Duration::ZERO);
        self.lags(t) == zero && self.gaps == zero
    }

    /// Whether `t` lies outside `band` (the golden's point's), with the
    /// got side's uncertainty `u`: a range passes where it meets the band.
    pub(super) fn out(&self, t: &Timing, (lo, hi): (Duration, Duration), u: Duration) -> bool {
        if self.exact(t) {
            return fit(t.got, (lo, hi), u) == Fit::Out;
        }
        let (lag_g, lag_o) = self.lags(t);
        let (lo, hi) = (lo.saturating_sub(self.gaps.0), hi + lag_g);
        t.got + lag_o + u < lo || t.got.saturating_sub(self.gaps.1 + u) > hi
    }
}

/// Judges a change the chip made, timed from each cause the two sides
/// share (`timings`, [`Causes::timings`]), each within the tolerance of
/// the nearest cause: no divergence where one of them agrees (by `out`,
/// given the band; graded MARGINAL by `u` where `graded`), else the
/// divergence timed from the cause it misses least.
#[allow(clippy::too_many_arguments)]
pub(super) fn judge_change(
    first: &mut First,
    at: Instant,
    quantity: &str,
    timings: &[Timing],
    tol: &Tolerances,
    u: Duration,
    graded: impl Fn(&Timing) -> bool,
    out: impl Fn(&Timing, (Duration, Duration)) -> bool,
) -> bool {
    // Each cause held to the tolerance of the nearest one: timed from a
    // cause milliseconds back, 1 % would let through what the nearest
    // cause catches.
    let nearest = timings
        .iter()
        .map(|t| t.golden)
        .min()
        .unwrap_or(Duration::ZERO);
    let slack = tol.band(nearest, tol.latency_bp).1.saturating_sub(nearest);
    let band = |gd: Duration| (gd.saturating_sub(slack), gd.saturating_add(slack));
    let named = |from: &str| format!("{quantity}, from {from}");
    match timings.iter().find(|t| !out(t, band(t.golden))) {
        Some(t) => {
            let (gd, od, from) = (t.golden, t.got, t.from);
            if graded(t) {
                // MARGINAL where it straddles a limit.
                first.check(at, || named(from), gd, od, band(gd), u);
            }
            false
        }
        None => {
            // The nearest miss, and of misses as near, the nearest cause:
            // the one the change is timed from best.
            let miss = |t: &&Timing| {
                let (lo, hi) = band(t.golden);
                (
                    lo.saturating_sub(t.got).max(t.got.saturating_sub(hi)),
                    t.golden,
                )
            };
            let Some(&Timing {
                golden: gd,
                got: od,
                from,
                ..
            }) = timings.iter().min_by_key(miss)
            else {
                return false;
            };
            first.diverge(at, named(from), gd, od, band(gd), u);
            true
        }
    }
}

/// One side of a wait for a flag: when it ended, what the chip's change
/// may be timed from, and whether the end is the change seen as it came
/// (else only a bound: the change came at or before it).
#[derive(Debug, Clone, Copy)]
pub(super) struct Wait {
    end: Instant,
    causes: Causes,
    saw: bool,
}

impl Wait {
    /// A wait that ended at `end` after `waited`, on a trace whose
    /// shortest wait is `first_look` and whose polled flags are as sure as
    /// `polled`. One no longer than both found its flag already changed,
    /// and only bounds the change. A write or read that waited (`strobe`)
    /// is stamped at its strobe, which a bridge makes after its wait by
    /// its own pace: a bound too, but on a trace whose times are exact
    /// (the emulator's, `polled` zero).
    pub(super) fn of(
        end: Instant,
        causes: Causes,
        waited: Duration,
        (first_look, polled): (Duration, Duration),
        strobe: bool,
    ) -> Wait {
        let exact = polled == Duration::ZERO;
        Wait {
            end,
            causes,
            saw: waited > first_look + polled && (exact || !strobe),
        }
    }
}

/// The shortest wait for a flag among a trace's `bus` transactions: what a
/// wait that found its flag on its first look costs this target (zero on
/// the emulator, 2.4 us on the RP2350 image).
pub(super) fn first_look<'a>(bus: impl Iterator<Item = &'a BusEvent>) -> Duration {
    bus.filter_map(|b| match *b {
        BusEvent::Await { waited, .. }
        | BusEvent::WriteCommand { waited, .. }
        | BusEvent::WriteData { waited, .. }
        | BusEvent::ReadData { waited, .. } => waited,
        _ => None,
    })
    .min()
    .unwrap_or(Duration::ZERO)
}

/// Whether the chip's change of a flag, as the two sides' waits saw it,
/// diverges (offered to `first`). Compared is when the chip changed the
/// flag, not how long a side waited: a bridge whose ops take longer starts
/// its waits later, and waits less, for the same chip. A side that saw the
/// change gives its moment; one that found the flag already changed only
/// bounds it. Two bounds say nothing; a bound and a moment diverge only
/// where the bound lies wholly on the wrong side of the band.
pub(super) fn wait_diverges(
    first: &mut First,
    quantity: &str,
    (g, o): (Wait, Wait),
    tol: &Tolerances,
    u: Duration,
) -> bool {
    let timings = Causes::timings(g.end, g.causes, o.end, o.causes);
    let graded = g.saw && o.saw;
    judge_change(
        first,
        o.end,
        quantity,
        &timings,
        tol,
        u,
        |_| graded,
        |t, band| {
            let od = t.got;
            match (g.saw, o.saw) {
                (true, true) => fit(od, band, u) == Fit::Out,
                (false, false) => false,
                // The board's change came at or before `od`: too early only
                // if `od` itself is.
                (true, false) => od.saturating_add(u) < band.0,
                // The golden change came at or before its time: the board's
                // is too late only past all of the golden's band.
                (false, true) => od.saturating_sub(u) > band.1,
            }
        },
    )
}

/// The golden side's BUSY changes as a side that finds BUSY by reading
/// the status register can see them: a rise and the fall after it with no
/// status read of that side between them (a read, or a wait on a flag)
/// leave no change in its capture, and are dropped. A move short enough
/// to begin and end between two reads (a single step's 112 us, Table 3-3,
/// in a wait of milliseconds) is found by its pulses, not by BUSY.
pub(super) fn busy_seen_by_reads(
    gs: &[(Instant, u8, Causes)],
    reads: &[(Instant, BusEvent, Causes)],
) -> Vec<(Instant, u8, Causes)> {
    let read_between = |from: Instant, to: Instant| {
        reads.iter().any(|(t, e, _)| {
            matches!(e, BusEvent::ReadStatus(_) | BusEvent::Await { .. }) && *t >= from && *t <= to
        })
    };
    let mut kept = Vec::with_capacity(gs.len());
    let mut i = 0;
    while i < gs.len() {
        if let (Some(rise), Some(fall)) = (gs.get(i), gs.get(i + 1)) {
            if rise.1 == 1 && fall.1 == 0 && !read_between(rise.0, fall.0) {
                i += 2;
                continue;
            }
        }
        kept.push(gs[i]);
        i += 1;
    }
    kept
}
