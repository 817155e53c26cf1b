//! Running a suite: choosing scenarios, running them one after another on
//! a target, and keeping going when one fails or errors.

use crate::backend::{Op, Target};
use crate::scenario::{run_scenario, DriverOptions, NotRun, Scenario, ScenarioResult, Verdict};
use crate::time::Duration;

/// Which scenarios a run takes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    /// Substring of the scenario name.
    pub filter: Option<String>,
    /// Every listed tag must be present.
    pub tags: Vec<String>,
    /// No listed tag may be present.
    pub skip_tags: Vec<String>,
    /// `(i, n)`: the i-th (1-based) of n interleaved shards.
    pub shard: Option<(usize, usize)>,
}

impl Selection {
    pub fn select(&self, all: &[Scenario]) -> Vec<Scenario> {
        self.matching(all)
            .into_iter()
            .enumerate()
            .filter(|(i, _)| self.shard.is_none_or(|(k, n)| i % n == k - 1))
            .map(|(_, s)| s)
            .collect()
    }

    /// The scenarios the filter and tags take, before sharding.
    pub fn matching(&self, all: &[Scenario]) -> Vec<Scenario> {
        all.iter()
            .filter(|s| {
                self.filter
                    .as_ref()
                    .is_none_or(|f| s.name.contains(f.as_str()))
            })
            .filter(|s| self.tags.iter().all(|t| s.has_tag(t)))
            .filter(|s| !self.skip_tags.iter().any(|t| s.has_tag(t)))
            .copied()
            .collect()
    }
}

/// Why a `--shard` value does not read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    #[error("shard `{0}` should be I/N, e.g. 2/4")]
    NotIOverN(String),
    #[error("shard index `{0}` is not a number")]
    BadIndex(String),
    #[error("shard count `{0}` is not a number")]
    BadCount(String),
    #[error("shard {i}/{n}: need 1 <= I <= N")]
    OutOfRange { i: usize, n: usize },
}

/// Parses `I/N` (1 <= I <= N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), ShardError> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| ShardError::NotIOverN(s.into()))?;
    let i: usize = i.parse().map_err(|_| ShardError::BadIndex(i.into()))?;
    let n: usize = n.parse().map_err(|_| ShardError::BadCount(n.into()))?;
    if n == 0 || i == 0 || i > n {
        return Err(ShardError::OutOfRange { i, n });
    }
    Ok((i, n))
}

/// A suite that breaks the rules every suite keeps.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SuiteError {
    /// Names are the golden files' and the reports' keys.
    #[error("two scenarios are named `{0}`")]
    DuplicateName(&'static str),
    #[error("scenario `{0}` names no datasheet section")]
    NoSection(&'static str),
}

/// Checks the suite's invariants: unique names, a section on each.
pub fn validate_suite(all: &[Scenario]) -> Result<(), SuiteError> {
    let mut names: Vec<&'static str> = all.iter().map(|s| s.name).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(SuiteError::DuplicateName(w[0]));
    }
    if let Some(s) = all.iter().find(|s| s.section.is_empty()) {
        return Err(SuiteError::NoSection(s.name));
    }
    Ok(())
}

/// Runs `scenarios` `repeat` times on `target`, calling `on_result` after
/// each (it may amend the result, e.g. with a golden comparison). After a harness error the target gets a health check (a reset);
/// if that fails too the link is taken as dead and the scenarios left are
/// reported as not run, so a broken cable does not read as a bad board.
pub fn run_suite(
    target: &mut dyn Target,
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    on_result: impl FnMut(&mut ScenarioResult),
) -> Vec<ScenarioResult> {
    run_suite_until(target, scenarios, repeat, opts, || false, on_result)
}

/// [`run_suite`] that asks `stop` before each scenario: once it says yes
/// (SIGINT, a closed output), the scenarios left in this pass are reported
/// as not run, interrupted, and no further pass starts.
pub fn run_suite_until(
    target: &mut dyn Target,
    scenarios: &[Scenario],
    repeat: usize,
    opts: DriverOptions,
    stop: impl Fn() -> bool,
    mut on_result: impl FnMut(&mut ScenarioResult),
) -> Vec<ScenarioResult> {
    let mut results = Vec::new();
    let mut dead: Option<String> = None;
    let mut interrupted = false;
    for _ in 0..repeat.max(1) {
        if interrupted {
            break;
        }
        for s in scenarios {
            interrupted = interrupted || stop();
            let not_run = |why| ScenarioResult {
                name: s.name,
                section: s.section,
                tags: s.tags,
                verdict: Verdict::NotRun(why),
                measurements: Vec::new(),
                trace: None,
                elapsed: Duration::ZERO,
                wall: std::time::Duration::ZERO,
            };
            let mut r = match &dead {
                _ if interrupted => not_run(NotRun::Interrupted),
                Some(why) => not_run(NotRun::TargetLost(why.clone())),
                None => {
                    let r = run_scenario(target, s, opts);
                    if matches!(r.verdict, Verdict::Error(_)) {
                        if let Err(e) = target.execute(&[Op::Reset]) {
                            dead = Some(e.to_string());
                        }
                    }
                    r
                }
            };
            on_result(&mut r);
            results.push(r);
        }
    }
    results
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{TargetError, TargetErrorKind};
    use crate::scenario::{Driver, HarnessError, Outcome};

    fn ok(_: &mut Driver) -> Outcome {
        Ok(())
    }

    fn suite() -> Vec<Scenario> {
        vec![
            Scenario::new("a_one", "3-1", "", &["x"], ok),
            Scenario::new("b_two", "3-2", "", &["x", "y"], ok),
            Scenario::new("c_three", "3-3", "", &["y"], ok),
            Scenario::new("d_four", "3-4", "", &[], ok),
        ]
    }

    fn names(v: Vec<Scenario>) -> Vec<&'static str> {
        v.into_iter().map(|s| s.name).collect()
    }

    #[test]
    fn selection_by_filter_tag_and_shard() {
        let all = suite();
        let sel = |f: Option<&str>, tags: &[&str], shard| Selection {
            filter: f.map(String::from),
            tags: tags.iter().map(|t| t.to_string()).collect(),
            skip_tags: Vec::new(),
            shard,
        };
        assert_eq!(
            names(sel(Some("t"), &[], None).select(&all)),
            vec!["b_two", "c_three"]
        );
        assert_eq!(
            names(sel(None, &["x", "y"], None).select(&all)),
            vec!["b_two"]
        );
        assert_eq!(
            names(sel(None, &[], Some((1, 2))).select(&all)),
            vec!["a_one", "c_three"]
        );
        let skip_y = Selection {
            skip_tags: vec!["y".into()],
            ..Selection::default()
        };
        assert_eq!(names(skip_y.select(&all)), vec!["a_one", "d_four"]);
        // A shard past the end of a small suite is empty, not an error.
        assert!(sel(None, &[], Some((7, 9))).select(&all).is_empty());
        assert_eq!(
            names(sel(None, &[], Some((2, 2))).select(&all)),
            vec!["b_two", "d_four"]
        );
    }

    #[test]
    fn shard_syntax() {
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        assert!(parse_shard("0/4").is_err());
        assert!(parse_shard("5/4").is_err());
        assert!(parse_shard("x").is_err());
    }

    fn panics(_: &mut Driver) -> Outcome {
        panic!("scenario bug")
    }

    fn runs_forever(d: &mut Driver) -> Outcome {
        d.init(crate::scenario::Init::four_phase())?;
        d.start(crate::scenario::Move::continuous(
            crate::protocol::Direction::Cw,
            50,
        ))?;
        loop {
            d.wait(crate::time::Duration::from_secs(1))?;
        }
    }

    fn fails(d: &mut Driver) -> Outcome {
        d.check("something", 1, 2)
    }

    #[test]
    fn a_panic_or_an_overrun_fails_that_scenario_alone() {
        let suite = vec![
            Scenario::new("a_panics", "3-1", "", &[], panics),
            Scenario::new("b_overruns", "3-1", "", &[], runs_forever)
                .budget(crate::time::Duration::from_secs(5)),
            Scenario::new("c_fails", "3-1", "", &[], fails),
            Scenario::new("d_passes", "3-1", "", &[], ok),
        ];
        let mut t = crate::backend::EmuTarget::new(Default::default(), Default::default())
            .expect("emulator");
        let r = run_suite(&mut t, &suite, 1, DriverOptions::default(), |_| {});
        let v: Vec<&str> = r.iter().map(|r| r.verdict.label()).collect();
        assert_eq!(v, vec!["error", "error", "failed", "passed"]);
        assert!(r[0]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("panicked: scenario bug"));
        assert!(r[1]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("time budget"));
        assert!(r[2]
            .verdict
            .detail()
            .unwrap_or_default()
            .contains("expected 1, got 2"));
    }

    #[test]
    fn duplicate_names_are_refused() {
        let mut all = suite();
        all.push(Scenario::new("a_one", "3-1", "", &[], ok));
        assert_eq!(
            validate_suite(&all),
            Err(SuiteError::DuplicateName("a_one"))
        );
    }

    /// A target whose cable was pulled before the run.
    #[derive(Debug)]
    struct Gone;

    impl Target for Gone {
        fn info(&self) -> crate::backend::TargetInfo {
            crate::backend::TargetInfo {
                name: "gone".into(),
                straps: crate::protocol::Straps::default(),
                extra: Vec::new(),
            }
        }
        fn capture(&mut self) -> Result<crate::protocol::Record, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
        fn execute(&mut self, _: &[Op]) -> Result<Vec<crate::backend::Reply>, TargetError> {
            Err(TargetError::new(TargetErrorKind::Link, "cable pulled"))
        }
    }

    #[test]
    fn after_a_target_is_lost_the_rest_are_not_run_and_blame_the_target() {
        let results = run_suite(&mut Gone, &suite(), 1, DriverOptions::default(), |_| {});
        assert!(
            matches!(
                &results[0].verdict,
                Verdict::Error(HarnessError::Target {
                    kind: TargetErrorKind::Link,
                    ..
                })
            ),
            "{:?}",
            results[0].verdict
        );
        for r in &results[1..] {
            assert_eq!(
                r.verdict,
                Verdict::NotRun(NotRun::TargetLost("cable pulled".into())),
                "{}",
                r.name
            );
        }
        assert_eq!(
            results[1].verdict.detail().as_deref(),
            Some("not run: the target stopped answering (cable pulled)")
        );
    }
}
