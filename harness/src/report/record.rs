//! A JSON run record read back ([`Record`]): what `ppmc report` draws,
//! and what the results store keeps. It reads every format this ppmc has
//! written (`ppmc-run-record/3` and `/4`), taking what it knows and
//! leaving the rest, so an older record still draws (without what it did
//! not hold: figures, attempts).

use super::figures::Figures;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The record formats this ppmc reads.
pub const FORMATS: [&str; 2] = ["ppmc-run-record/3", "ppmc-run-record/4"];

/// Largest run record read (a soak's record lists at most 1,000 runs past
/// its first pass).
pub const MAX_RECORD_BYTES: u64 = 512 << 20;

#[derive(Debug, Clone, Deserialize)]
pub struct Record {
    pub format: String,
    pub run: RunFacts,
    pub summary: Summary,
    pub scenarios: Vec<ScenarioRecord>,
}

#[derive(Debug, Clone, Default, Deserialize)]
pub struct Summary {
    pub passed: u64,
    pub marginal: u64,
    pub failed: u64,
    pub error: u64,
    pub not_run: u64,
    /// Passed only on a retry (format 4).
    #[serde(default)]
    pub flaky: u64,
}

#[derive(Debug, Clone, Deserialize)]
pub struct RunFacts {
    pub harness_version: String,
    pub git_revision: String,
    pub boards: Vec<BoardFacts>,
    pub started: String,
    pub wall_s: f64,
    pub host: String,
    pub options: OptionFacts,
    /// A capture judged in place of a board (`ppmc judge`).
    #[serde(default)]
    pub source: Option<serde_json::Value>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct OptionFacts {
    pub golden: Option<String>,
    pub marginal_pct: f64,
    pub interval_tol_pct: f64,
    pub time_floor_ns: u64,
    #[serde(default)]
    pub retries: u32,
}

#[derive(Debug, Clone, Deserialize)]
pub struct BoardFacts {
    pub name: String,
    pub target: String,
    #[serde(default)]
    pub target_details: BTreeMap<String, String>,
    pub board_rev: Option<String>,
    #[serde(default)]
    pub board_serial: Option<String>,
    pub bridge_firmware: Option<String>,
    #[serde(default)]
    pub bridge_serial: Option<String>,
    #[serde(default)]
    pub link: Option<BTreeMap<String, u64>>,
    pub error: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct FailureFacts {
    pub expectation: String,
    pub expected: String,
    pub got: String,
    pub at_ns: u64,
}

#[derive(Debug, Clone, Deserialize)]
pub struct ErrorFacts {
    pub kind: String,
    pub message: String,
}

#[derive(Debug, Clone, Deserialize)]
pub struct MeasurementRecord {
    pub name: String,
    pub value_ns: u64,
    pub lo_ns: u64,
    pub hi_ns: Option<u64>,
    pub marginal_lo_ns: u64,
    pub marginal_hi_ns: Option<u64>,
    /// The uncertainty (±); 0 in records written before it was kept.
    #[serde(default)]
    pub u_ns: u64,
    pub grade: String,
    pub at_ns: u64,
}

/// One attempt of a scenario that was tried again (format 4).
#[derive(Debug, Clone, Deserialize)]
pub struct AttemptRecord {
    pub verdict: String,
    pub detail: Option<String>,
    #[serde(default)]
    pub error: Option<ErrorFacts>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct ScenarioRecord {
    pub name: String,
    #[serde(default)]
    pub pass: Option<u64>,
    pub board: Option<String>,
    pub section: String,
    /// `passed`, `marginal`, `flaky`, `failed`, `error`, `not_run`.
    pub verdict: String,
    pub detail: Option<String>,
    pub failure: Option<FailureFacts>,
    pub error: Option<ErrorFacts>,
    pub elapsed_ns: u64,
    pub measurements: Vec<MeasurementRecord>,
    #[serde(default)]
    pub blame: Option<String>,
    #[serde(default)]
    pub figures: Option<Figures>,
    #[serde(default)]
    pub attempts: Vec<AttemptRecord>,
}

/// A run record that could not be read: the file, and why.
#[derive(Debug)]
pub struct RecordError {
    /// Empty when `why` names the file itself.
    pub path: String,
    pub why: String,
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.path.is_empty() {
            true => f.write_str(&self.why),
            false => write!(f, "{}: {}", self.path, self.why),
        }
    }
}

impl std::error::Error for RecordError {}

/// `text` safe to print on a terminal: control characters (an escape
/// sequence a hostile file plants) shown as escapes, not sent.
pub fn printable(text: &str) -> String {
    text.chars()
        .flat_map(|c| match c.is_control() {
            true => c.escape_default().collect::<Vec<_>>(),
            false => vec![c],
        })
        .collect()
}

impl Record {
    /// The run record in `text`; `path` names it in an error.
    pub fn parse(text: &str, path: &str) -> Result<Record, RecordError> {
        // A byte-order mark, as some editors write one: not JSON, but no
        // reason to refuse the record.
        let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
        let err = |why: String| RecordError {
            path: path.to_string(),
            why,
        };
        // The format first: a file that is no run record says so, not
        // which field it lacks.
        #[derive(Deserialize)]
        struct Format {
            format: Option<String>,
        }
        let f: Format =
            serde_json::from_str(text).map_err(|e| err(format!("not a JSON run record: {e}")))?;
        match f.format.as_deref() {
            Some(v) if FORMATS.contains(&v) => {}
            Some(v) if v.starts_with("ppmc-run-record/") => {
                let why = match v["ppmc-run-record/".len()..].parse::<u32>() {
                    Ok(n) if n < 3 => "older than this ppmc reads",
                    Ok(_) => "newer than this ppmc reads: update ppmc",
                    Err(_) => "not a format of ppmc's",
                };
                return Err(err(format!(
                    "run record format {} is {why} (it reads {})",
                    printable(v),
                    FORMATS.join(", ")
                )));
            }
            _ => {
                return Err(err(
                    "not a ppmc run record (no `format: ppmc-run-record/N`)".into(),
                ))
            }
        }
        serde_json::from_str(text).map_err(|e| err(format!("run record does not read: {e}")))
    }

    /// The run record in the file at `path`.
    pub fn read(path: &Path) -> Result<Record, RecordError> {
        let name = path.display().to_string();
        // The file error names the path itself.
        let text = crate::files::read_text(path, MAX_RECORD_BYTES).map_err(|e| RecordError {
            path: String::new(),
            why: e.to_string(),
        })?;
        Record::parse(&text, &name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terminal_escapes_are_shown_not_sent() {
        assert_eq!(printable("A\u{1b}]0;x\u{7}\r"), "A\\u{1b}]0;x\\u{7}\\r");
        assert_eq!(printable("rev B"), "rev B");
    }

    #[test]
    fn formats_are_told_apart() {
        let says = |f: &str| {
            Record::parse(&format!(r#"{{"format":"{f}"}}"#), "r")
                .expect_err("refused")
                .to_string()
        };
        assert!(says("ppmc-run-record/2").contains("older than this ppmc reads"));
        assert!(says("ppmc-run-record/99").contains("newer than this ppmc reads"));
        assert!(says("ppmc-run-record/x").contains("not a format of ppmc's"));
        assert!(says("something").contains("not a ppmc run record"));
        // A byte-order mark is no reason to refuse a record.
        assert!(
            Record::parse("\u{FEFF}{\"format\":\"ppmc-run-record/99\"}", "r")
                .expect_err("refused")
                .to_string()
                .contains("newer")
        );
    }
}
