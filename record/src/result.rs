//! One scenario's result in a run record ([`ScenarioRecord`]), and what it
//! is made of: its [`Status`], the device's failure, the error that kept
//! it from a verdict, its attempts, whom a capture's judge blames; and a
//! scenario's repeated runs counted under `--repeat` ([`RepeatedRecord`]).
//!
//! Everything here is owned and plain: every producer (a run, a
//! comparison, a capture's judge, a soak) writes it, every report reads it.

use crate::deviation::Deviation;
use crate::figures::Figures;
use crate::measurement::{Grade, Measurement};
use crate::tally::{Status, Tally};
use serde::{Deserialize, Deserializer, Serialize};

/// Whose problem an error or a "not run" is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// The harness, the scenario, a golden file: not the board, not the
    /// link.
    Harness,
    /// The target could not be reached or was lost: not the board.
    Infrastructure,
    /// The run was stopped before the scenario (SIGINT, SIGTERM).
    Interrupted,
    /// A capture that cannot be judged (`ppmc judge`).
    Capture,
}

impl ErrorKind {
    /// Its one spelling in the record and in JUnit's `type`.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Harness => "harness",
            ErrorKind::Infrastructure => "infrastructure",
            ErrorKind::Interrupted => "interrupted",
            ErrorKind::Capture => "capture",
        }
    }
}

/// Why the harness could not judge, as fields.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorRecord {
    pub kind: ErrorKind,
    pub message: String,
}

/// What the device did wrong, as fields.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FailureRecord {
    pub expectation: String,
    pub expected: String,
    pub got: String,
    pub at_ns: u64,
    /// By how much, where the check has a magnitude (a time, a count).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deviation: Option<Deviation>,
}

/// The party a result judged from a capture blames (`ppmc judge`): the
/// board, the host firmware driving it, or the capture itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Blame {
    Board,
    Host,
    Capture,
}

impl Blame {
    /// Its one spelling in the record.
    pub fn name(self) -> &'static str {
        match self {
            Blame::Board => "board",
            Blame::Host => "host",
            Blame::Capture => "capture",
        }
    }
}

/// The host firmware using the chip against chapter 3, found in a capture.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct HostFindingRecord {
    pub at_ns: u64,
    pub section: String,
    pub what: String,
}

/// An attempt before a scenario's last, when it was tried again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AttemptRecord {
    /// Never `flaky`.
    pub verdict: Status,
    pub detail: Option<String>,
    #[serde(default)]
    pub error: Option<ErrorRecord>,
    #[serde(default)]
    pub elapsed_ns: u64,
    #[serde(default)]
    pub wall_s: f64,
}

/// One scenario's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioRecord {
    pub name: String,
    /// Its pass, from 1, when the run repeats.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pass: Option<u64>,
    /// The board it ran on (`run.boards[].name`); null if none took it.
    pub board: Option<String>,
    pub section: String,
    #[serde(default)]
    pub tags: Vec<String>,
    pub verdict: Status,
    /// The verdict's one-line reason (a judged capture's: the judge's
    /// line).
    pub detail: Option<String>,
    pub failure: Option<FailureRecord>,
    pub error: Option<ErrorRecord>,
    /// Virtual time on the target.
    pub elapsed_ns: u64,
    /// Wall-clock time the harness spent on it.
    #[serde(default)]
    pub wall_s: f64,
    pub measurements: Vec<Measurement>,
    /// Judged from a capture (absent otherwise): whom the verdict blames;
    /// `null` when it passed.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "present"
    )]
    pub blame: Option<Option<Blame>>,
    /// On the result that judges the host firmware: its findings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host_findings: Option<Vec<HostFindingRecord>>,
    /// The attempts before the last, when the scenario was tried again.
    #[serde(default)]
    pub attempts: Vec<AttemptRecord>,
    /// What the HTML report draws: each move's pulse runs (the board's and
    /// the golden's), the pins around the failure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub figures: Option<Figures>,
    /// The files saved for it (`--artifacts`), as the run named them:
    /// JUnit's attachments, the JSON record's `artifacts`.
    #[serde(default, rename = "artifacts", skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<String>,
    /// What a capture's judge says after its verdict: what was not judged,
    /// what was compared, each finding. JUnit's text; not in the JSON
    /// record, whose `run.source` holds the same facts.
    #[serde(skip)]
    pub notes: Vec<String>,
}

/// A field that is present is `Some`, even when it is `null`.
fn present<'de, D, T>(d: D) -> Result<Option<Option<T>>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<T>::deserialize(d).map(Some)
}

impl ScenarioRecord {
    /// A result with no measurement, attempt, figure or note, of a
    /// scenario `name` in `section`.
    pub fn new(name: &str, section: &str, verdict: Status) -> ScenarioRecord {
        ScenarioRecord {
            name: name.to_string(),
            pass: None,
            board: None,
            section: section.to_string(),
            tags: Vec::new(),
            verdict,
            detail: None,
            failure: None,
            error: None,
            elapsed_ns: 0,
            wall_s: 0.0,
            measurements: Vec::new(),
            blame: None,
            host_findings: None,
            attempts: Vec::new(),
            figures: None,
            attachments: Vec::new(),
            notes: Vec::new(),
        }
    }
}

/// Most results after the first pass that did not pass a soak run
/// (`--repeat`) lists one by one; those past it are counted in their
/// scenario's [`RepeatedRecord`].
pub const MAX_LISTED: usize = 1_000;

/// One measurement over a scenario's repeated runs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RangeRecord {
    pub name: String,
    pub count: u64,
    pub min_ns: u64,
    pub mean_ns: u64,
    pub max_ns: u64,
    /// The worst grade any run got.
    pub worst_grade: Grade,
}

/// A scenario's runs on one board after the first pass that are not listed
/// one by one (`--repeat`), counted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepeatedRecord {
    pub name: String,
    pub board: Option<String>,
    pub section: String,
    #[serde(default)]
    pub tags: Vec<String>,
    pub first_pass: usize,
    pub last_pass: usize,
    pub runs: usize,
    pub summary: Tally,
    /// Of `summary.not_run`, those an interrupted run never reached.
    pub interrupted: usize,
    pub elapsed_ns: u64,
    pub wall_s: f64,
    pub measurements: Vec<RangeRecord>,
}
