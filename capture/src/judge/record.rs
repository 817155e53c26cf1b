//! A judgement as a run record holds it (`ppmc judge --junit/--json/
//! --store`): the capture stands as the board; one result for the board
//! (`judge.<file>`), failed when it diverged, an error when the capture
//! cannot be judged; and one for the host firmware
//! (`judge.<file>.host-firmware`), failed when it broke a rule of chapter
//! 3, there whenever the capture was judged or a finding made. Each result
//! says whom its verdict blames. The one place a judgement becomes
//! results.

use super::{CaptureVerdict, HostFinding, JudgeOptions, Judgement};
use ppmc::scenario::{Failure, HarnessError, Verdict as ScenarioVerdict};
use ppmc::time::Instant;
use ppmc_logic::source::LogicInfo;
use ppmc_record::{
    Blame, CaptureSource, ErrorKind, HostFindingRecord, RunOptions, RunRecord, ScenarioRecord,
};
use std::path::Path;

impl Judgement {
    /// What was compared, in one line.
    pub fn counts_line(&self) -> String {
        format!(
            "{} register accesses, {} POUT pulses compared, {} changes of the other outputs compared",
            self.accesses, self.pulses, self.changes
        )
    }

    /// The comparisons within the capture's uncertainty of their limits,
    /// in one line, if any.
    pub fn marginal_line(&self) -> Option<String> {
        let m = &self.marginal;
        (m.count > 0).then(|| {
            format!(
                "{} comparison{} within the capture's uncertainty of {} limit (docs/conformance.md), the first: {}",
                m.count,
                if m.count == 1 { "" } else { "s" },
                if m.count == 1 { "its" } else { "their" },
                m.first.as_deref().unwrap_or("-")
            )
        })
    }

    /// The run record of this judgement of the capture at `path` (read as
    /// `info` says), judged with `opts`, in `wall` time.
    pub fn record(
        &self,
        path: &Path,
        info: &LogicInfo,
        opts: &JudgeOptions,
        wall: std::time::Duration,
    ) -> RunRecord {
        let shown = path.display().to_string();
        let file = path
            .file_name()
            .map_or_else(|| shown.clone(), |f| f.to_string_lossy().into_owned());
        let details = opts
            .straps
            .fields()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        let board =
            ppmc_record::BoardInfo::new(shown.clone(), format!("capture:{shown}"), details, None);
        let mut run = ppmc::runner::run_info(vec![board], "one");
        let tol = &opts.tolerances;
        run.options = RunOptions {
            repeat: 1,
            latency_tol_pct: tol.latency_bp as f64 / 100.0,
            interval_tol_pct: tol.interval_bp as f64 / 100.0,
            time_floor_ns: tol.floor.as_nanos(),
            ..Default::default()
        };
        run.wall_s = wall.as_secs_f64();
        run.source = Some(CaptureSource {
            kind: "capture".into(),
            path: shown.clone(),
            format: info.format.clone(),
            channels: info.channels.clone(),
            sample_rate_hz: info.sample_rate_hz,
            resolution_ps: info.resolution_ps,
            accesses: self.accesses,
            pulses: self.pulses,
            changes: self.changes,
            not_judged: self.not_judged.clone(),
        });
        let mut notes: Vec<String> = self
            .not_judged
            .iter()
            .map(|n| format!("not judged: {n}"))
            .collect();
        notes.push(self.counts_line());
        notes.extend(self.hints.iter().map(|h| format!("hint: {h}")));
        notes.extend(self.marginal_line());
        let (verdict, blame, message) = match &self.verdict {
            CaptureVerdict::Passed if self.marginal.count > 0 => {
                (ScenarioVerdict::Marginal, None, None)
            }
            CaptureVerdict::Passed => (ScenarioVerdict::Passed, None, None),
            CaptureVerdict::Failed(d) => (
                ScenarioVerdict::Failed(Failure {
                    expectation: d.what.clone(),
                    expected: d.model.clone(),
                    got: d.board.clone(),
                    at: Instant::from_nanos(d.at_ps / 1000),
                    deviation: ppmc::scenario::deviation_of(
                        &d.model,
                        &d.board,
                        ppmc_record::Reference::Expected,
                    ),
                }),
                Some(Blame::Board),
                Some(d.to_string()),
            ),
            CaptureVerdict::Capture(why) => (
                ScenarioVerdict::Error(HarnessError::Capture(why.clone())),
                Some(Blame::Capture),
                Some(why.clone()),
            ),
        };
        let on = Some(shown.as_str());
        let mut results = vec![ScenarioRecord {
            notes,
            wall_s: wall.as_secs_f64(),
            ..judged(&format!("judge.{file}"), "3", &verdict, blame, message, on)
        }];
        let captured = !matches!(self.verdict, CaptureVerdict::Capture(_));
        if captured || !self.host.is_empty() {
            results.push(self.host_result(&file, on));
        }
        RunRecord::new(run, results)
    }

    /// The host firmware's result: failed at its first finding.
    fn host_result(&self, file: &str, board: Option<&str>) -> ScenarioRecord {
        let host = &self.host;
        let mut sections: Vec<&str> = host.iter().map(|h| h.section).collect();
        sections.sort_unstable();
        sections.dedup();
        let section = match sections.is_empty() {
            true => "3".to_string(),
            false => sections.join(", "),
        };
        let (verdict, blame, message) = match host.first() {
            None => (ScenarioVerdict::Passed, None, None),
            Some(first) => (
                ScenarioVerdict::Failed(Failure {
                    expectation: "the host firmware keeps the rules of chapter 3".into(),
                    expected: "no access against them".into(),
                    got: format!(
                        "{} findings, the first (section {}): {}",
                        host.len(),
                        first.section,
                        first.what
                    ),
                    at: Instant::from_nanos(first.at_ps / 1000),
                    deviation: None,
                }),
                Some(Blame::Host),
                Some(format!(
                    "the host firmware broke chapter 3's rules {} times",
                    host.len()
                )),
            ),
        };
        let name = format!("judge.{file}.host-firmware");
        ScenarioRecord {
            notes: host.iter().map(HostFinding::line).collect(),
            host_findings: Some(
                host.iter()
                    .map(|f| HostFindingRecord {
                        at_ns: f.at_ps / 1000,
                        section: f.section.to_string(),
                        what: f.what.clone(),
                    })
                    .collect(),
            ),
            ..judged(&name, &section, &verdict, blame, message, board)
        }
    }
}

impl HostFinding {
    /// The finding, in one line.
    pub fn line(&self) -> String {
        format!(
            "host firmware (section {}): at {}: {}",
            self.section,
            Instant::from_nanos(self.at_ps / 1000),
            self.what
        )
    }
}

/// A result judged from a capture: the verdict's fields, `message` (the
/// judge's line) in place of its own words, and whom it blames (an error
/// that blames the capture is of the capture's kind).
fn judged(
    name: &str,
    section: &str,
    verdict: &ScenarioVerdict,
    blame: Option<Blame>,
    message: Option<String>,
    board: Option<&str>,
) -> ScenarioRecord {
    ScenarioRecord {
        board: board.map(str::to_string),
        tags: vec!["capture".to_string()],
        detail: message.or_else(|| verdict.detail()),
        failure: match verdict {
            ScenarioVerdict::Failed(f) => Some(f.record()),
            _ => None,
        },
        error: verdict.error_record().map(|mut e| {
            if blame == Some(Blame::Capture) {
                e.kind = ErrorKind::Capture;
            }
            e
        }),
        blame: Some(blame),
        ..ScenarioRecord::new(name, section, verdict.status(false))
    }
}
