//! Facts about a run that every report carries: [`RunInfo`], its boards
//! ([`BoardInfo`]) and the options it was made with ([`RunOptions`]).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::SystemTime;

/// The selection and settings a run was made with, for the record.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunOptions {
    #[serde(default)]
    pub filter: Option<String>,
    #[serde(default)]
    pub tags: Vec<String>,
    #[serde(default)]
    pub skip_tags: Vec<String>,
    /// Scenarios left out by name (`--skip`).
    #[serde(default)]
    pub skip: Vec<String>,
    /// `I/N`, when the run is one shard of the suite.
    #[serde(default)]
    pub shard: Option<String>,
    #[serde(default)]
    pub repeat: u32,
    /// The golden directory compared against, if any.
    pub golden: Option<String>,
    /// Width of the MARGINAL zone, percent of each limit.
    pub marginal_pct: f64,
    /// The golden comparison's tolerances.
    #[serde(default)]
    pub latency_tol_pct: f64,
    pub interval_tol_pct: f64,
    pub time_floor_ns: u64,
    /// `--retries`, `--retry-failures`, `--flaky-is-failure`.
    #[serde(default)]
    pub retries: u32,
    #[serde(default)]
    pub retry_failures: bool,
    #[serde(default)]
    pub flaky_is_failure: bool,
}

/// A board of a run: what the reports call it and what is known of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoardInfo {
    /// The board's label: the `--target` given, or its `name=`.
    pub name: String,
    /// The target as reached: `serial:/dev/ttyACM0`, or
    /// `labgrid:rig1 (rfc2217://lab:2001)`.
    pub target: String,
    #[serde(default)]
    pub target_details: BTreeMap<String, String>,
    /// The board revision label (`rev=` or `--board-rev`).
    pub board_rev: Option<String>,
    /// The board's serial number (`board-serial=` or `--board-serial`).
    #[serde(default)]
    pub board_serial: Option<String>,
    /// The bus bridge's firmware version, when the target is a board.
    pub bridge_firmware: Option<String>,
    /// The bus bridge's serial number, where it is known: what its HELLO
    /// gives (an RP2350's chip ID), else the USB serial number the
    /// operating system read from the device.
    #[serde(default)]
    pub bridge_serial: Option<String>,
    /// What the link to the bridge cost over the run (round trips,
    /// retransmissions, corrupt frames, reopens); none for the emulator.
    #[serde(default)]
    pub link: Option<BTreeMap<String, u64>>,
    /// Why the board took no part in the run, or left it early.
    pub error: Option<String>,
}

impl BoardInfo {
    /// A board that was reached: its label, the target as reached, what the
    /// target says of itself (`details`: its straps, then facts such as
    /// `bridge_firmware`) and its revision label.
    pub fn new(
        name: String,
        target: String,
        details: Vec<(String, String)>,
        board_rev: Option<String>,
    ) -> BoardInfo {
        let bridge_firmware = details
            .iter()
            .find(|(k, _)| k == "bridge_firmware")
            .map(|(_, v)| v.clone());
        BoardInfo {
            name,
            target,
            target_details: details.into_iter().collect(),
            board_rev,
            board_serial: None,
            bridge_firmware,
            bridge_serial: None,
            link: None,
            error: None,
        }
    }

    /// A board that could not be reached: nothing is known of it but its
    /// name, the address it was tried at (`target`) and why.
    pub fn unreached(
        name: String,
        target: String,
        board_rev: Option<String>,
        why: String,
    ) -> BoardInfo {
        BoardInfo {
            target,
            name,
            target_details: BTreeMap::new(),
            board_rev,
            board_serial: None,
            bridge_firmware: None,
            bridge_serial: None,
            link: None,
            error: Some(why),
        }
    }
}

/// The longest board label (name, revision, serial) ppmc keeps.
pub const MAX_LABEL: usize = 200;

/// Checks a board's label (`name=`, `rev=`, `board-serial=` and their
/// flags) as the reports and the results store keep it: printable text
/// (no control character: a line break or a terminal's escape would garble
/// every listing), at most [`MAX_LABEL`] characters, not empty and not
/// `(none)`, which the reports write for a board given no label.
pub fn check_label(label: &str) -> Result<(), String> {
    if label.is_empty() {
        return Err("an empty label: give one, or leave the option out".into());
    }
    if label == "(none)" {
        return Err("`(none)` is what the reports write for no label: give another".into());
    }
    if let Some(c) = label.chars().find(|c| c.is_control()) {
        return Err(format!(
            "the label holds the control character {}: a label is printable text",
            c.escape_default()
        ));
    }
    let n = label.chars().count();
    if n > MAX_LABEL {
        return Err(format!("a label of {n} characters: at most {MAX_LABEL}"));
    }
    Ok(())
}

/// Facts about a run that every report carries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// The run's own name, made when it starts (a random UUID): a results
    /// store keeps a run once under it, however often its record is sent
    /// (`ppmc store push`). Absent from records of an older ppmc.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<String>,
    pub harness_version: String,
    pub git_revision: String,
    /// The boards, in the order of `--target`; results name them by name.
    pub boards: Vec<BoardInfo>,
    /// `one` (a single board), `share` (each scenario on one of several
    /// boards) or `each` (every scenario on every board).
    #[serde(default = "one")]
    pub spread: String,
    /// When the run started, UTC, RFC 3339.
    pub started: String,
    /// Wall-clock duration of the whole run, seconds.
    pub wall_s: f64,
    /// The machine the harness ran on.
    pub host: String,
    pub options: RunOptions,
    /// What the results were judged from when it is no run of boards: a
    /// logic-analyzer capture (`ppmc judge`). Absent from a run's record.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<CaptureSource>,
}

fn one() -> String {
    "one".into()
}

/// A logic-analyzer capture a board was judged from (`ppmc judge`), and
/// what of it was judged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaptureSource {
    /// Always `capture`.
    pub kind: String,
    pub path: String,
    /// What the file is, in words: `VCD (ppmc)`, `sigrok session (.sr,
    /// version 2)`.
    pub format: String,
    /// The channels' names, as the capture gives them.
    pub channels: Vec<String>,
    /// The sample rate of a sampled capture; `None` for a VCD.
    pub sample_rate_hz: Option<u64>,
    /// No edge is known closer than this.
    pub resolution_ps: u64,
    /// The register accesses decoded, the POUT pulses and the changes of
    /// the other outputs compared.
    pub accesses: u64,
    pub pulses: u64,
    pub changes: u64,
    /// What could not be judged, and why (a signal with no channel).
    pub not_judged: Vec<String>,
}

impl RunInfo {
    /// A run starting now on this machine, by the harness of `version` and
    /// `git_revision`, on `boards` spread as `spread` says.
    pub fn new(version: &str, git_revision: &str, boards: Vec<BoardInfo>, spread: &str) -> RunInfo {
        RunInfo {
            id: Some(uuid::Uuid::new_v4().to_string()),
            harness_version: version.to_string(),
            git_revision: git_revision.to_string(),
            boards,
            spread: spread.to_string(),
            started: rfc3339(SystemTime::now()),
            wall_s: 0.0,
            host: hostname(),
            options: RunOptions::default(),
            source: None,
        }
    }

    /// The label of board `b`, or `(none)` for a result no board took.
    pub fn board_name(&self, b: Option<usize>) -> &str {
        b.and_then(|b| self.boards.get(b))
            .map_or("(none)", |b| b.name.as_str())
    }

    /// The board named `name`, as a result names it: an index into
    /// `boards`.
    pub fn board_index(&self, name: Option<&str>) -> Option<usize> {
        name.and_then(|n| self.boards.iter().position(|b| b.name == n))
    }
}

/// The machine's name, as far as it can be learned without privileges.
fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// `t` as `YYYY-MM-DDTHH:MM:SSZ` (UTC).
pub fn rfc3339(t: SystemTime) -> String {
    let secs = t
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3_600,
        rem % 3_600 / 60,
        rem % 60
    )
}
