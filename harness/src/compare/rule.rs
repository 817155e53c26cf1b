//! The decision rule of `docs/conformance.md`, as a compare applies it:
//! each timing the compared trace holds is as unsure as the instrument
//! that took it says (its `uncertainty` detail, [`crate::trace::UNCERTAINTY`];
//! a measurement its own `±`), and so is the golden trace's (exact when it
//! is the emulator's). A timing whose interval `got ± U` lies wholly inside
//! its band passes; wholly outside, it is the divergence; straddling a
//! limit, it is MARGINAL: within the instruments' uncertainty of it.
//! With `U` = 0 (two emulator traces) this is the band alone, as it was.

use super::Divergence;
use crate::bus::Uncertainty;
use crate::protocol::Pin;
use crate::time::{Duration, Instant, Limit};
use crate::trace::Trace;

/// Where a value lies against its band, `± u`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Fit {
    In,
    Marginal,
    Out,
}

pub(super) fn fit(got: Duration, (lo, hi): (Duration, Duration), u: Duration) -> Fit {
    let (low, high) = (got.saturating_sub(u), got.saturating_add(u));
    if high < lo || low > hi {
        Fit::Out
    } else if low < lo || high > hi {
        Fit::Marginal
    } else {
        Fit::In
    }
}

/// The value as compared: `25.650us`, or `25.650us ±0.134us`.
pub(super) fn shown(got: Duration, u: Duration) -> String {
    if u == Duration::ZERO {
        got.to_string()
    } else {
        format!("{got} ±{u}")
    }
}

/// The two traces' uncertainty, each kind of timing a compare makes as
/// unsure as its two ends on both sides.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Unsure {
    golden: Uncertainty,
    got: Uncertainty,
}

impl Unsure {
    pub(super) fn of(golden: &Trace, got: &Trace) -> Unsure {
        Unsure {
            golden: golden.uncertainty(),
            got: got.uncertainty(),
        }
    }

    fn both(&self, f: impl Fn(&Uncertainty) -> Duration) -> Duration {
        f(&self.golden) + f(&self.got)
    }

    /// How sure each side's sight of a status flag is (golden, got): a
    /// wait no longer than this found the flag already changed.
    pub(super) fn polled(&self) -> (Duration, Duration) {
        (self.golden.polled, self.got.polled)
    }

    /// How much earlier than a waited write's stamp the chip may have
    /// become ready for its byte (golden, got): a bridge finds IBF's fall
    /// by polling (a pass is up to twice `polled`) and then makes its
    /// strobe (an access). Zero on an exact trace, whose writes come as
    /// IBF falls.
    pub(super) fn strobe_lag(&self) -> (Duration, Duration) {
        (self.golden.poll_pass(), self.got.poll_pass())
    }

    /// A wait for a flag: from an access to the poll that saw it.
    pub(super) fn wait(&self) -> Duration {
        self.both(|u| u.access + u.polled)
    }

    /// A move's first pulse, from the write that started it.
    pub(super) fn first_pulse(&self) -> Duration {
        self.both(|u| u.access + u.edge)
    }

    /// An interval between two pulses.
    pub(super) fn interval(&self) -> Duration {
        self.both(|u| u.edge + u.edge)
    }

    /// Whether a side reports stop switching (SWITCHING) by inference
    /// from S1..S5 sampled by its CPU (its sampled outputs less sure than
    /// its edges), as a board's bridge does: reported up to two
    /// [`crate::protocol::SWITCHING_WINDOW`]s late, and not at all for a
    /// stretch that ends before the chopping's first edge. Such a
    /// SWITCHING is not compared change by change (`docs/conformance.md`).
    pub(super) fn infers_switching(&self) -> bool {
        let infers = |u: &Uncertainty| u.sampled > u.edge;
        infers(&self.golden) || infers(&self.got)
    }

    /// Whether the compared side finds BUSY by reading the status
    /// register ([`Uncertainty::polls_busy`]).
    pub(super) fn got_polls_busy(&self) -> bool {
        self.got.polls_busy()
    }

    /// A pin's change, from the write that started the move.
    pub(super) fn pin(&self, pin: Pin) -> Duration {
        self.both(|u| u.access + u.of_pin(pin))
    }
}

/// A comparison whose value lies within the traces' uncertainty of its
/// band's limit: neither proven inside nor outside.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MarginalComparison {
    /// When, on the compared trace's clock.
    pub at: Instant,
    /// What: `pulse 42 interval`, `pin busy change 2: time from the move's
    /// start`.
    pub quantity: String,
    pub golden: Duration,
    pub got: Duration,
    /// The band, and the uncertainty (±) of the value.
    pub lo: Duration,
    pub hi: Duration,
    pub u: Duration,
}

impl std::fmt::Display for MarginalComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "at {}: {}: golden {}, got {} ±{} (allowed {}..={}): within the instruments' uncertainty of a limit",
            self.at, self.quantity, self.golden, self.got, self.u, self.lo, self.hi
        )
    }
}

/// What a compare that found no divergence says besides: the comparisons
/// that were MARGINAL, how many and the first in time.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Graded {
    pub marginal: u64,
    pub first: Option<MarginalComparison>,
}

impl Graded {
    pub(super) fn note(&mut self, m: MarginalComparison) {
        self.marginal += 1;
        if self.first.as_ref().is_none_or(|f| m.at < f.at) {
            self.first = Some(m);
        }
    }
}

/// Keeps the earliest divergence, and the comparisons that were MARGINAL.
#[derive(Debug, Default)]
pub(super) struct First(pub(super) Option<Divergence>, pub(super) Graded);

impl First {
    pub(super) fn offer(&mut self, d: Divergence) {
        if self.0.as_ref().is_none_or(|cur| d.at < cur.at) {
            self.0 = Some(d);
        }
    }

    /// Judges the timing `got` (± `u`) against `band` by the decision
    /// rule: `true` where it is the divergence (offered).
    pub(super) fn check(
        &mut self,
        at: Instant,
        quantity: impl FnOnce() -> String,
        golden: Duration,
        got: Duration,
        band: (Duration, Duration),
        u: Duration,
    ) -> bool {
        match fit(got, band, u) {
            Fit::In => false,
            Fit::Marginal => {
                self.1.note(MarginalComparison {
                    at,
                    quantity: quantity(),
                    golden,
                    got,
                    lo: band.0,
                    hi: band.1,
                    u,
                });
                false
            }
            Fit::Out => {
                self.diverge(at, quantity(), golden, got, band, u);
                true
            }
        }
    }

    /// Offers the divergence of `got` (± `u`) from `golden`, outside `band`.
    pub(super) fn diverge(
        &mut self,
        at: Instant,
        quantity: String,
        golden: Duration,
        got: Duration,
        band: (Duration, Duration),
        u: Duration,
    ) {
        self.offer(Divergence {
            at,
            quantity,
            golden: golden.to_string(),
            got: shown(got, u),
            allowed: format!("{}..={}", band.0, Limit(band.1)),
        });
    }

    /// Whether anything at or after `at` can still be the first.
    pub(super) fn beaten_by(&self, at: Instant) -> bool {
        self.0.as_ref().is_some_and(|cur| cur.at <= at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_with_no_uncertainty_is_the_band_alone() {
        let us = Duration::from_micros;
        let band = (us(10), us(20));
        assert_eq!(fit(us(10), band, Duration::ZERO), Fit::In);
        assert_eq!(fit(us(20), band, Duration::ZERO), Fit::In);
        assert_eq!(fit(us(21), band, Duration::ZERO), Fit::Out);
        // Within U of a limit, either side of it: MARGINAL.
        assert_eq!(fit(us(21), band, us(2)), Fit::Marginal);
        assert_eq!(fit(us(19), band, us(2)), Fit::Marginal);
        assert_eq!(fit(us(23), band, us(2)), Fit::Out);
        assert_eq!(fit(us(15), band, us(2)), Fit::In);
    }
}
