//! A trace's word on how sure its times are: the `uncertainty` detail a
//! trace from an instrument that is not exact carries, and its events as
//! an exact instrument would give them.

use super::{Event, EventKind, Trace};
use crate::bus::Uncertainty;
use crate::time::Duration;

/// The detail a trace from an instrument that is not exact carries (a
/// bridge): each path's uncertainty as the target declared it
/// ([`crate::backend::Target::uncertainty`]), `edge=14ns sampled=5000ns
/// access=134ns polled=1000ns`. A trace without it is exact (the
/// emulator's, every golden trace). A compare widens each comparison by
/// it (`crate::compare`).
pub const UNCERTAINTY: &str = "uncertainty";

/// The `uncertainty` detail's text for `u`.
pub fn uncertainty_detail(u: &Uncertainty) -> String {
    format!(
        "edge={}ns sampled={}ns access={}ns polled={}ns",
        u.edge.as_nanos(),
        u.sampled.as_nanos(),
        u.access.as_nanos(),
        u.polled.as_nanos()
    )
}

/// The `uncertainty` detail of a trace whose times are as sure as `u`:
/// its name and text, as a trace's details hold them.
pub fn uncertainty_entry(u: &Uncertainty) -> (String, String) {
    (UNCERTAINTY.to_string(), uncertainty_detail(u))
}

/// Reads an `uncertainty` detail's text.
pub(super) fn parse_uncertainty(text: &str) -> Result<Uncertainty, String> {
    let mut u = Uncertainty::ZERO;
    let mut seen = [false; 4];
    for part in text.split_whitespace() {
        let bad = || {
            format!("bad `uncertainty` detail `{part}`: expected `edge=14ns sampled=5000ns access=134ns polled=1000ns`")
        };
        let (k, v) = part.split_once('=').ok_or_else(bad)?;
        let ns: u64 = v
            .strip_suffix("ns")
            .and_then(|n| n.parse().ok())
            .ok_or_else(bad)?;
        let (slot, i) = match k {
            "edge" => (&mut u.edge, 0),
            "sampled" => (&mut u.sampled, 1),
            "access" => (&mut u.access, 2),
            "polled" => (&mut u.polled, 3),
            _ => return Err(bad()),
        };
        if seen[i] {
            return Err(format!("`{k}` twice in the `uncertainty` detail"));
        }
        seen[i] = true;
        *slot = Duration::from_nanos(ns);
    }
    if seen.contains(&false) {
        return Err(format!("the `uncertainty` detail `{text}` lacks a path: it needs edge, sampled, access and polled"));
    }
    Ok(u)
}

impl Trace {
    /// How unsure the trace's times are, path by path: its `uncertainty`
    /// detail, or exact without one.
    pub fn uncertainty(&self) -> Uncertainty {
        self.details
            .iter()
            .find(|(k, _)| k == UNCERTAINTY)
            .and_then(|(_, v)| parse_uncertainty(v).ok())
            .unwrap_or(Uncertainty::ZERO)
    }

    /// The events with each measurement's value and without its
    /// uncertainty (`±`): what two runs of one scenario, through an exact
    /// instrument and one that is not, have in common.
    pub fn values(&self) -> Vec<Event> {
        self.events
            .iter()
            .cloned()
            .map(|mut e| {
                if let EventKind::Measure { u, .. } = &mut e.kind {
                    *u = Duration::ZERO;
                }
                e
            })
            .collect()
    }
}
