//! The invariants by name: one [`Invariant`] per row of
//! `docs/invariants.md`, with its stable id (the text a finding is
//! bucketed by: crash messages, reproducers, triage tables, the names of
//! regression scenarios) and the datasheet section it comes from. A test
//! holds the enum and the document to each other, so neither can gain an
//! invariant the other lacks.

use std::fmt;
use std::str::FromStr;

/// An invariant of `docs/invariants.md`. [`Invariant::as_str`] (and
/// `Display`) is its id there; `FromStr` reads the id back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Invariant {
    /// `status-bit3`: bit 3 of the status register reads 0.
    StatusBit3,
    /// `status-params`: without an error, bits 6-4 count at most four
    /// parameter bytes still due.
    StatusParams,
    /// `busy-status-matches`: the BUSY bit read equals the BUSY line.
    BusyStatusMatches,
    /// `remaining-pulses`: a remaining-pulses read is requested - output - 1.
    RemainingPulses,
    /// `finish-flag-once`: the polling flag is set once per move ended.
    FinishFlagOnce,
    /// `busy-covers-pulses`: no pulse while the BUSY line is 0.
    BusyCoversPulses,
    /// `int-mask`: INT* only at the end of a move that asked for it.
    IntMask,
    /// `int-release`: INT* released only by a finish status read.
    IntRelease,
    /// `phase-pattern`: each pulse steps the phases once, move to move.
    PhasePattern,
    /// `min-interval`: no pulse interval shorter than the move's rate.
    MinInterval,
    /// `time-monotonic`: the chip's clock never goes backward.
    TimeMonotonic,
    /// `record-ordered`: the capture comes in time order.
    RecordOrdered,
}

impl Invariant {
    /// Every invariant, in the order of `docs/invariants.md`.
    pub const ALL: [Invariant; 12] = [
        Invariant::StatusBit3,
        Invariant::StatusParams,
        Invariant::BusyStatusMatches,
        Invariant::RemainingPulses,
        Invariant::FinishFlagOnce,
        Invariant::BusyCoversPulses,
        Invariant::IntMask,
        Invariant::IntRelease,
        Invariant::PhasePattern,
        Invariant::MinInterval,
        Invariant::TimeMonotonic,
        Invariant::RecordOrdered,
    ];

    /// The invariant's id in `docs/invariants.md`, e.g. `status-bit3`.
    pub fn as_str(self) -> &'static str {
        match self {
            Invariant::StatusBit3 => "status-bit3",
            Invariant::StatusParams => "status-params",
            Invariant::BusyStatusMatches => "busy-status-matches",
            Invariant::RemainingPulses => "remaining-pulses",
            Invariant::FinishFlagOnce => "finish-flag-once",
            Invariant::BusyCoversPulses => "busy-covers-pulses",
            Invariant::IntMask => "int-mask",
            Invariant::IntRelease => "int-release",
            Invariant::PhasePattern => "phase-pattern",
            Invariant::MinInterval => "min-interval",
            Invariant::TimeMonotonic => "time-monotonic",
            Invariant::RecordOrdered => "record-ordered",
        }
    }

    /// The datasheet section the invariant comes from (`model` for the
    /// model's own).
    pub fn section(self) -> &'static str {
        match self {
            Invariant::StatusBit3 | Invariant::StatusParams | Invariant::BusyStatusMatches => {
                "3-1-1"
            }
            Invariant::RemainingPulses => "3-4-4",
            Invariant::FinishFlagOnce => "3-4-1",
            Invariant::BusyCoversPulses => "3-1-1",
            Invariant::IntMask => "3-3-1",
            Invariant::IntRelease => "3-4-1",
            Invariant::PhasePattern => "3-2-1",
            Invariant::MinInterval => "3-2-2",
            Invariant::TimeMonotonic | Invariant::RecordOrdered => "model",
        }
    }
}

impl fmt::Display for Invariant {
    /// The id, as [`Invariant::as_str`].
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A text that is no invariant's id.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not an invariant of docs/invariants.md")]
pub struct UnknownInvariant(pub String);

impl FromStr for Invariant {
    type Err = UnknownInvariant;

    /// The invariant whose id is `s`, exactly.
    fn from_str(s: &str) -> Result<Invariant, UnknownInvariant> {
        Invariant::ALL
            .into_iter()
            .find(|i| i.as_str() == s)
            .ok_or_else(|| UnknownInvariant(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of the invariants table of `docs/invariants.md` (the one
    /// headed `| id | invariant | checked | datasheet |`) that name an id:
    /// the id and the datasheet cell.
    fn documented() -> Vec<(String, String)> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/invariants.md");
        let text = std::fs::read_to_string(&path).expect("docs/invariants.md");
        let mut rows = Vec::new();
        let mut in_table = false;
        for line in text.lines() {
            if line.starts_with("| id | invariant |") {
                in_table = true;
                continue;
            }
            if !in_table || line.starts_with("|---") {
                continue;
            }
            if !line.starts_with('|') {
                break;
            }
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            // `| id | invariant | checked | datasheet |`: cells 1 to 4. A
            // row whose first cell is not an id in backticks (`(panic)`)
            // names no invariant.
            let Some(id) = cells[1].strip_prefix('`').and_then(|c| c.strip_suffix('`')) else {
                continue;
            };
            rows.push((id.to_string(), cells[4].to_string()));
        }
        assert!(
            in_table,
            "docs/invariants.md has no `| id | invariant |` table"
        );
        rows
    }

    /// `docs/invariants.md` and the enum list the same invariants, in the
    /// same order, each with its datasheet section in the doc's row.
    #[test]
    fn the_enum_and_docs_invariants_md_list_the_same_invariants() {
        let doc = documented();
        let ids: Vec<&str> = doc.iter().map(|(id, _)| id.as_str()).collect();
        let variants: Vec<&str> = Invariant::ALL.iter().map(|i| i.as_str()).collect();
        for id in &ids {
            assert!(
                id.parse::<Invariant>().is_ok(),
                "docs/invariants.md lists `{id}`, which is no Invariant variant"
            );
        }
        for v in &variants {
            assert!(
                ids.contains(v),
                "Invariant `{v}` is not in docs/invariants.md's table"
            );
        }
        assert_eq!(ids, variants, "the same order in both");
        for (id, datasheet) in &doc {
            let section = id.parse::<Invariant>().expect("checked above").section();
            assert!(
                datasheet.contains(section),
                "`{id}`: the doc's datasheet cell `{datasheet}` does not cite {section}"
            );
        }
    }

    #[test]
    fn ids_read_back_to_their_invariant() {
        for i in Invariant::ALL {
            assert_eq!(i.as_str().parse::<Invariant>(), Ok(i));
            assert_eq!(i.to_string(), i.as_str());
        }
        assert_eq!(
            "status-bit4".parse::<Invariant>(),
            Err(UnknownInvariant("status-bit4".into()))
        );
    }
}
