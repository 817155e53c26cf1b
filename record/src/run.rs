//! A run record ([`RunRecord`]), written as JSON and read back: what
//! `ppmc report` draws, and what the results store keeps. It reads every
//! format this ppmc has written (`ppmc-run-record/3` and `/4`), so an
//! older record still draws (without what it did not hold: figures,
//! attempts).

use crate::info::RunInfo;
use crate::result::{RepeatedRecord, ScenarioRecord};
use crate::tally::Tally;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The format this ppmc writes.
pub const FORMAT: &str = "ppmc-run-record/4";

/// The record formats this ppmc reads.
pub const FORMATS: [&str; 2] = ["ppmc-run-record/3", FORMAT];

/// Largest run record read (a soak's record lists at most 1,000 runs past
/// its first pass).
pub const MAX_RECORD_BYTES: u64 = 512 << 20;

/// A run: its facts, its tally and its results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    pub format: String,
    pub run: RunInfo,
    /// Every verdict of the run, listed or not.
    pub summary: Tally,
    /// The results listed one by one.
    pub scenarios: Vec<ScenarioRecord>,
    /// Under `--repeat`: each scenario's runs after the first pass that
    /// are not in `scenarios`, counted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeated: Option<Vec<RepeatedRecord>>,
}

impl RunRecord {
    /// The record of a run whose results are all listed: `summary` counts
    /// them.
    pub fn new(run: RunInfo, scenarios: Vec<ScenarioRecord>) -> RunRecord {
        RunRecord {
            format: FORMAT.to_string(),
            summary: Tally::of(scenarios.iter().map(|s| s.verdict)),
            run,
            scenarios,
            repeated: None,
        }
    }

    /// The record as JSON (`--json`; its schema is
    /// `docs/run-record.schema.json`).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }
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

impl RunRecord {
    /// The run record in `text`; `path` names it in an error.
    pub fn parse(text: &str, path: &str) -> Result<RunRecord, RecordError> {
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
        let record: RunRecord = serde_json::from_str(text)
            .map_err(|e| err(format!("run record does not read: {e}")))?;
        // Its labels as ppmc would have taken them: a store and every
        // listing keep them (an unknown verdict is refused above, by
        // serde, naming the verdicts there are).
        for (i, b) in record.run.boards.iter().enumerate() {
            let labels = [
                ("name", Some(&b.name)),
                ("board_rev", b.board_rev.as_ref()),
                ("board_serial", b.board_serial.as_ref()),
            ];
            for (field, label) in labels {
                if let Some(label) = label {
                    crate::check_label(label).map_err(|why| {
                        err(format!(
                            "run.boards[{i}].{field} `{}`: {why}",
                            printable(label)
                        ))
                    })?;
                }
            }
        }
        Ok(record)
    }

    /// The run record in the file at `path`.
    pub fn read(path: &Path) -> Result<RunRecord, RecordError> {
        let name = path.display().to_string();
        // The file error names the path itself.
        let text = ppmc_files::read_text(path, MAX_RECORD_BYTES).map_err(|e| RecordError {
            path: String::new(),
            why: e.to_string(),
        })?;
        RunRecord::parse(&text, &name)
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
            RunRecord::parse(&format!(r#"{{"format":"{f}"}}"#), "r")
                .expect_err("refused")
                .to_string()
        };
        assert!(says("ppmc-run-record/2").contains("older than this ppmc reads"));
        assert!(says("ppmc-run-record/99").contains("newer than this ppmc reads"));
        assert!(says("ppmc-run-record/x").contains("not a format of ppmc's"));
        assert!(says("something").contains("not a ppmc run record"));
        // A byte-order mark is no reason to refuse a record.
        assert!(
            RunRecord::parse("\u{FEFF}{\"format\":\"ppmc-run-record/99\"}", "r")
                .expect_err("refused")
                .to_string()
                .contains("newer")
        );
    }
}

/// What a scenario that did not pass says of itself, in the words every
/// report uses for its first lines ([`RunRecord::not_passed`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Shortfall {
    /// The check that failed, or the kind of error.
    pub check: String,
    /// What was expected (empty for an error).
    pub expected: String,
    /// What was measured, or the error's message.
    pub got: String,
    /// By how much ([`crate::Deviation::describe`]), where the check has a
    /// magnitude.
    pub by: Option<String>,
    /// When, on the target's clock (a failure's).
    pub at_ns: Option<u64>,
}

impl RunRecord {
    /// The scenarios that did not pass cleanly (neither passed nor
    /// MARGINAL), the board's failures first, then errors, flaky passes
    /// and those not run, each kind in run order: what a report shows
    /// first. Each with its index in [`RunRecord::scenarios`].
    pub fn not_passed(&self) -> Vec<(usize, &ScenarioRecord)> {
        let rank = |sc: &ScenarioRecord| match sc.verdict {
            crate::Status::Failed => 0,
            crate::Status::Error => 1,
            crate::Status::Flaky => 2,
            _ => 3,
        };
        let mut rows: Vec<(usize, &ScenarioRecord)> = self
            .scenarios
            .iter()
            .enumerate()
            .filter(|(_, sc)| !sc.passed_cleanly())
            .collect();
        rows.sort_by_key(|(k, sc)| (rank(sc), *k));
        rows
    }
}

impl ScenarioRecord {
    /// Whether it passed, MARGINAL or not, on its first attempt: a report
    /// shows everything else first.
    pub fn passed_cleanly(&self) -> bool {
        matches!(
            self.verdict,
            crate::Status::Passed | crate::Status::Marginal
        )
    }

    /// What did not pass, in a report's words: the failure's check,
    /// expectation, measured value and deviation; or the error's kind and
    /// message; or the detail.
    pub fn shortfall(&self) -> Shortfall {
        match (&self.failure, &self.error) {
            (Some(f), _) => Shortfall {
                check: f.expectation.clone(),
                expected: f.expected.clone(),
                got: f.got.clone(),
                by: f.deviation.as_ref().map(|d| d.describe()),
                at_ns: Some(f.at_ns),
            },
            (None, Some(e)) => Shortfall {
                check: format!("{} error", e.kind.name()),
                expected: String::new(),
                got: e.message.clone(),
                by: None,
                at_ns: None,
            },
            (None, None) => Shortfall {
                check: self.detail.clone().unwrap_or_default(),
                expected: String::new(),
                got: String::new(),
                by: None,
                at_ns: None,
            },
        }
    }
}
