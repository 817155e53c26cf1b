//! Every run's result sink: what the reports keep of a run as its
//! results stream in, in constant memory however many passes a soak
//! (`--repeat`) makes.
//!
//! The first pass is kept whole, as is every result after it that did not
//! pass (failed, error, not run), up to [`MAX_LISTED`] of them; every other
//! result of a later pass is counted into its scenario's [`Repeated`]
//! (per board): how many runs, their verdicts, the virtual and wall time,
//! and each measurement's count, minimum, mean, maximum and worst grade.
//! What is held grows with the suite and the cap, never with the passes.
//! A listed result is held as its record ([`ScenarioRecord`]); the run's
//! record is [`Sink::record`].

use crate::runner::BoardResult;
use crate::scenario::{Grade, NotRun, ScenarioResult, Verdict};
use crate::time::Duration;
use ppmc_record::{
    Figures, RangeRecord, RepeatedRecord, RunInfo, RunRecord, ScenarioRecord, Tally, FORMAT,
};
use std::collections::BTreeMap;

pub use ppmc_record::MAX_LISTED;

/// A result the reports list one by one.
#[derive(Debug)]
pub struct Listed {
    /// Its place in the run (results are listed in this order).
    pub slot: usize,
    /// Its pass, from 1.
    pub pass: usize,
    pub record: ScenarioRecord,
}

/// What a run keeps of a result beside it, for the reports: listed with
/// the result, dropped with it when the soak only counts it.
#[derive(Debug, Default)]
pub struct Kept {
    /// The files saved for it (`--artifacts`).
    pub attachments: Vec<String>,
    pub figures: Option<Figures>,
}

/// One measurement of a scenario over many runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeasureRange {
    pub name: String,
    pub count: u64,
    pub min: Duration,
    pub max: Duration,
    sum: u128,
    /// The worst grade any run got.
    pub worst: Grade,
}

impl MeasureRange {
    /// The mean value, to the nanosecond below.
    pub fn mean(&self) -> Duration {
        let n = u128::from(self.count.max(1));
        Duration::from_nanos(u64::try_from(self.sum / n).unwrap_or(u64::MAX))
    }
}

fn rank(g: Grade) -> u8 {
    match g {
        Grade::Pass => 0,
        Grade::Marginal => 1,
        Grade::Fail => 2,
    }
}

/// The runs of one scenario on one board after the first pass that are not
/// listed one by one.
#[derive(Debug, Clone, PartialEq)]
pub struct Repeated {
    pub name: &'static str,
    pub section: &'static str,
    pub tags: &'static [&'static str],
    /// An index into the run's boards; `None` when no board took them.
    pub board: Option<usize>,
    /// The first and last pass they come from.
    pub first_pass: usize,
    pub last_pass: usize,
    /// Their verdicts: passed and marginal, and those that did not pass
    /// once [`MAX_LISTED`] were listed.
    pub tally: Tally,
    /// Of `tally.not_run`, those an interrupted run never reached.
    pub interrupted: usize,
    /// Virtual time on the device and wall time, summed.
    pub elapsed: Duration,
    pub wall: std::time::Duration,
    /// Each measurement's range, in the order the scenario first gave them.
    pub measurements: Vec<MeasureRange>,
}

impl Repeated {
    /// How many runs these are.
    pub fn runs(&self) -> usize {
        self.tally.runs()
    }

    /// As a run record counts them, on the board named `board` (`(none)`
    /// for runs no board took).
    pub fn record(&self, board: &str) -> RepeatedRecord {
        RepeatedRecord {
            name: self.name.to_string(),
            board: self.board.map(|_| board.to_string()),
            section: self.section.to_string(),
            tags: self.tags.iter().map(|t| t.to_string()).collect(),
            first_pass: self.first_pass,
            last_pass: self.last_pass,
            runs: self.runs(),
            summary: self.tally,
            interrupted: self.interrupted,
            elapsed_ns: self.elapsed.as_nanos(),
            wall_s: self.wall.as_secs_f64(),
            measurements: self
                .measurements
                .iter()
                .map(|m| RangeRecord {
                    name: m.name.clone(),
                    count: m.count,
                    min_ns: m.min.as_nanos(),
                    mean_ns: m.mean().as_nanos(),
                    max_ns: m.max.as_nanos(),
                    worst_grade: m.worst,
                })
                .collect(),
        }
    }

    fn add(&mut self, pass: usize, r: &ScenarioResult) {
        self.first_pass = self.first_pass.min(pass);
        self.last_pass = self.last_pass.max(pass);
        self.tally.add(r.status());
        if r.verdict == Verdict::NotRun(NotRun::Interrupted) {
            self.interrupted += 1;
        }
        self.elapsed += r.elapsed;
        self.wall += r.wall;
        for m in &r.measurements {
            let v = m.value;
            match self.measurements.iter_mut().find(|x| x.name == m.name) {
                Some(x) => {
                    x.count += 1;
                    x.min = x.min.min(v);
                    x.max = x.max.max(v);
                    x.sum += u128::from(v.as_nanos());
                    if rank(m.grade) > rank(x.worst) {
                        x.worst = m.grade;
                    }
                }
                None => self.measurements.push(MeasureRange {
                    name: m.name.clone(),
                    count: 1,
                    min: v,
                    max: v,
                    sum: u128::from(v.as_nanos()),
                    worst: m.grade,
                }),
            }
        }
    }
}

/// Takes a run's results as they stream in and keeps what the reports
/// need (see the module's doc).
#[derive(Debug)]
pub struct Sink {
    /// Scenarios in a pass.
    per_pass: usize,
    /// Slots in one queue of the run (`per_pass * repeat`): a board's with
    /// `--each`, else the run's.
    per_queue: usize,
    listed: Vec<Listed>,
    /// Results after the first pass that did not pass and were listed.
    listed_later: usize,
    repeated: BTreeMap<(Option<usize>, usize), Repeated>,
    tally: Tally,
    boards: BTreeMap<Option<usize>, Tally>,
}

impl Sink {
    /// For a run of `per_pass` scenarios `repeat` times.
    pub fn new(per_pass: usize, repeat: usize) -> Sink {
        Sink {
            per_pass: per_pass.max(1),
            per_queue: (per_pass * repeat.max(1)).max(1),
            listed: Vec::new(),
            listed_later: 0,
            repeated: BTreeMap::new(),
            tally: Tally::default(),
            boards: BTreeMap::new(),
        }
    }

    /// The pass (from 1) of the result in `slot`.
    pub fn pass_of(&self, slot: usize) -> usize {
        slot % self.per_queue / self.per_pass + 1
    }

    /// Takes one result: `board` is its board as the reports name it (an
    /// index into the run's boards, named by `names`), `kept` what the
    /// run keeps beside it.
    pub fn add(&mut self, r: BoardResult, board: Option<usize>, names: &[String], kept: Kept) {
        let pass = self.pass_of(r.slot);
        self.tally.add(r.result.status());
        self.boards.entry(board).or_default().add(r.result.status());
        let listed = pass == 1 || {
            let more =
                (!r.result.verdict.ok() || r.result.flaky()) && self.listed_later < MAX_LISTED;
            self.listed_later += usize::from(more);
            more
        };
        if listed {
            let name = board.and_then(|b| names.get(b)).map(String::as_str);
            let record = ScenarioRecord {
                pass: (self.repeats()).then_some(pass as u64),
                attachments: kept.attachments,
                figures: kept.figures,
                ..r.result.record(name)
            };
            self.listed.push(Listed {
                slot: r.slot,
                pass,
                record,
            });
            return;
        }
        let s = &r.result;
        self.repeated
            .entry((board, r.slot % self.per_pass))
            .or_insert_with(|| Repeated {
                name: s.name,
                section: s.section,
                tags: s.tags,
                board,
                first_pass: pass,
                last_pass: pass,
                tally: Tally::default(),
                interrupted: 0,
                elapsed: Duration::ZERO,
                wall: std::time::Duration::ZERO,
                measurements: Vec::new(),
            })
            .add(pass, s);
    }

    /// Whether the run repeats its scenarios.
    fn repeats(&self) -> bool {
        self.per_queue > self.per_pass
    }

    /// Every verdict so far.
    pub fn tally(&self) -> Tally {
        self.tally
    }

    /// Every verdict of board `b` so far (`None`: the results no board took).
    pub fn board_tally(&self, b: Option<usize>) -> Tally {
        self.boards.get(&b).copied().unwrap_or_default()
    }

    /// Results held one by one so far: the first pass and at most
    /// [`MAX_LISTED`] more.
    pub fn listed_len(&self) -> usize {
        self.listed.len()
    }

    /// Results that did not pass and are counted, not listed.
    pub fn unlisted(&self) -> usize {
        self.repeated
            .values()
            .map(|r| r.tally.failed + r.tally.errors + r.tally.not_run)
            .sum()
    }

    /// What the reports list: the results one by one in the run's order,
    /// and the scenarios' repeated runs, board by board in the suite's
    /// order.
    pub fn finish(mut self) -> (Vec<Listed>, Vec<Repeated>) {
        self.listed.sort_by_key(|l| l.slot);
        (self.listed, self.repeated.into_values().collect())
    }

    /// The run's record: `summary` counts every run; under `--repeat`
    /// each listed result carries its `pass`, and `repeated` holds each
    /// scenario's other runs after the first pass, counted, with each
    /// measurement's range (board by board, named as `run` names them).
    pub fn record(self, run: RunInfo) -> RunRecord {
        let repeats = self.repeats();
        let summary = self.tally;
        let (listed, repeated) = self.finish();
        let repeated = repeats.then(|| {
            repeated
                .iter()
                .map(|r| r.record(run.board_name(r.board)))
                .collect()
        });
        RunRecord {
            format: FORMAT.to_string(),
            summary,
            scenarios: listed.into_iter().map(|l| l.record).collect(),
            repeated,
            run,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::{stream_on_boards, Spread};
    use crate::scenario::{Driver, DriverOptions, Outcome, Scenario};

    fn ok(_: &mut Driver) -> Outcome {
        Ok(())
    }

    fn fails(d: &mut Driver) -> Outcome {
        d.check("something", 1, 2)
    }

    /// A soak of 300 passes holds the first pass and the capped failures,
    /// however many passes run: the rest are counts.
    #[test]
    fn a_soak_holds_the_first_pass_and_the_capped_failures_only() {
        let suite = vec![
            Scenario::new("a_passes", "3-1", "", &[], ok),
            Scenario::new("b_fails", "3-1", "", &[], fails),
            Scenario::new("c_passes", "3-1", "", &[], ok),
        ];
        let passes = MAX_LISTED + 300;
        let mut boards: Vec<Box<dyn crate::backend::Target>> = vec![Box::new(
            crate::backend::EmuTarget::new(Default::default(), Default::default())
                .expect("emulator"),
        )];
        let mut soak = Sink::new(suite.len(), passes);
        let mut most = 0;
        stream_on_boards(
            &mut boards,
            &mut [],
            &suite,
            passes,
            DriverOptions::default(),
            Spread::Share,
            || false,
            |_, _, _| {},
            |r| {
                soak.add(r, Some(0), &["emu".to_string()], Kept::default());
                most = most.max(soak.listed_len());
            },
        );
        assert_eq!(most, suite.len() + MAX_LISTED, "held at most");
        let t = soak.tally();
        assert_eq!((t.passed, t.failed), (2 * passes, passes));
        assert_eq!(soak.unlisted(), passes - 1 - MAX_LISTED);
        let (listed, repeated) = soak.finish();
        assert_eq!(listed.len(), suite.len() + MAX_LISTED);
        assert!(listed.windows(2).all(|w| w[0].slot < w[1].slot));
        assert_eq!(listed[3].pass, 2);
        assert_eq!(listed[3].record.name, "b_fails");
        assert_eq!(listed[3].record.pass, Some(2));
        assert_eq!(listed[3].record.board.as_deref(), Some("emu"));
        // One entry per scenario: the passes' counts, and the failures
        // past the cap.
        let runs: Vec<(&str, usize, usize)> = repeated
            .iter()
            .map(|r| (r.name, r.runs(), r.tally.failed))
            .collect();
        assert_eq!(
            runs,
            [
                ("a_passes", passes - 1, 0),
                ("b_fails", passes - 1 - MAX_LISTED, passes - 1 - MAX_LISTED),
                ("c_passes", passes - 1, 0)
            ]
        );
        assert_eq!((repeated[0].first_pass, repeated[0].last_pass), (2, passes));
    }

    /// Later passes keep each measurement's count, minimum, mean, maximum
    /// and worst grade; the first pass is listed as it is.
    #[test]
    fn measurements_keep_their_range() {
        let s = Scenario::new("a", "3-1", "", &[], ok);
        let mut soak = Sink::new(1, 4);
        let values = [
            (7, Grade::Pass),
            (5, Grade::Pass),
            (9, Grade::Marginal),
            (4, Grade::Pass),
        ];
        for (slot, (v, grade)) in values.into_iter().enumerate() {
            let mut result = crate::runner::not_run(&s, NotRun::Interrupted);
            result.verdict = Verdict::Passed;
            result.measurements = vec![crate::scenario::Measurement {
                name: "busy_rise".into(),
                value: Duration::from_nanos(v),
                lo: Duration::ZERO,
                hi: Duration::MAX,
                marginal_lo: Duration::ZERO,
                marginal_hi: Duration::MAX,
                u: Duration::ZERO,
                grade,
                at: crate::time::Instant::ZERO,
            }];
            let r = BoardResult {
                board: Some(0),
                slot,
                result,
            };
            soak.add(r, Some(0), &["emu".to_string()], Kept::default());
        }
        let (listed, repeated) = soak.finish();
        assert_eq!(listed.len(), 1);
        let x = &repeated[0].measurements[0];
        let ns = Duration::from_nanos;
        assert_eq!((x.count, x.min, x.mean(), x.max), (3, ns(4), ns(6), ns(9)));
        assert_eq!(x.worst, Grade::Marginal);
    }
}
