//! What a change the chip made is timed from in a compare: what made the
//! chip make it (its last input, its last pulse), never a bridge's pace;
//! and how a change timed so is judged, for an output pin and for a flag a
//! wait saw.

use super::rule::{fit, First, Fit};
use super::Tolerances;
use crate::protocol::PulseRun;
use crate::time::{Duration, Instant};
use crate::trace::BusEvent;

/// What a trace's times are taken from, at a point in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Anchor {
    /// The start of the move in progress or last made, or the chip's
    /// reset when there was no move since: a move's pulses are timed from
    /// it.
    pub(super) at: Instant,
    /// The chip's last input (a write, a data read, an input's change, or
    /// its reset) and its name.
    pub(super) input: (Instant, &'static str),
    /// The last run of pulses so far.
    pub(super) run: Option<PulseRun>,
}

impl Default for Anchor {
    /// A trace's start: a trace that starts without a reset (a capture's)
    /// has no input before its first changes.
    fn default() -> Anchor {
        Anchor {
            at: Instant::ZERO,
            input: (Instant::ZERO, "the trace's start"),
            run: None,
        }
    }
}

impl Anchor {
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
            pulse,
        }
    }
}

/// What a change the chip made may be timed from ([`Anchor::causes`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Causes {
    input: (Instant, &'static str),
    pulse: Option<Instant>,
}

impl Causes {
    /// A change at `g` (golden, from `gc`) and at `o` (got, from `oc`),
    /// timed from each cause the two share: (golden, got, the cause's
    /// name), the chip's last input first.
    pub(super) fn timings(
        g: Instant,
        gc: Causes,
        o: Instant,
        oc: Causes,
    ) -> Vec<(Duration, Duration, &'static str)> {
        let mut t = vec![(
            g.saturating_since(gc.input.0),
            o.saturating_since(oc.input.0),
            gc.input.1,
        )];
        if let (Some(gp), Some(op)) = (gc.pulse, oc.pulse) {
            t.push((
                g.saturating_since(gp),
                o.saturating_since(op),
                "the last pulse before it",
            ));
        }
        t
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
    timings: &[(Duration, Duration, &'static str)],
    tol: &Tolerances,
    u: Duration,
    graded: bool,
    out: impl Fn(Duration, (Duration, Duration)) -> bool,
) -> bool {
    // Each cause held to the tolerance of the nearest one: timed from a
    // cause milliseconds back, 1 % would let through what the nearest
    // cause catches.
    let nearest = timings.iter().map(|t| t.0).min().unwrap_or(Duration::ZERO);
    let slack = tol.band(nearest, tol.latency_bp).1.saturating_sub(nearest);
    let band = |gd: Duration| (gd.saturating_sub(slack), gd.saturating_add(slack));
    let named = |from: &str| format!("{quantity}, from {from}");
    match timings.iter().find(|&&(gd, od, _)| !out(od, band(gd))) {
        Some(&(gd, od, from)) => {
            if graded {
                // MARGINAL where it straddles a limit.
                first.check(at, || named(from), gd, od, band(gd), u);
            }
            false
        }
        None => {
            // The nearest miss, and of misses as near, the nearest cause:
            // the one the change is timed from best.
            let miss = |&&(gd, od, _): &&(Duration, Duration, &str)| {
                let (lo, hi) = band(gd);
                (lo.saturating_sub(od).max(od.saturating_sub(hi)), gd)
            };
            let Some(&(gd, od, from)) = timings.iter().min_by_key(miss) else {
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
        graded,
        |od, band| {
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
