//! One conformance scenario ([`Scenario`]) and how it runs on a target
//! from a hardware reset ([`run_scenario`]).

use super::driver::Driver;
use super::options::DriverOptions;
use super::outcome::{HarnessError, Outcome, Stop};
use super::verdict::{NotRun, ScenarioResult, Verdict};
use crate::backend::{Target, TargetErrorKind};
use crate::bus::Uncertainty;
use crate::time::{Duration, Instant};
use crate::trace::{Event, EventKind, Trace};
use ppmc_record::Grade;
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// One conformance scenario.
#[derive(Clone, Copy)]
pub struct Scenario {
    /// Unique, `snake_case`, starting with the section: `s3_3_5_...`.
    pub name: &'static str,
    /// The datasheet section it proves, e.g. `3-3-5`.
    pub section: &'static str,
    /// One line on what it checks.
    pub summary: &'static str,
    pub tags: &'static [&'static str],
    /// Virtual time the scenario may use.
    pub budget: Duration,
    pub body: fn(&mut Driver) -> Outcome,
}

impl fmt::Debug for Scenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Scenario")
            .field("name", &self.name)
            .field("section", &self.section)
            .finish_non_exhaustive()
    }
}

impl Scenario {
    pub const fn new(
        name: &'static str,
        section: &'static str,
        summary: &'static str,
        tags: &'static [&'static str],
        body: fn(&mut Driver) -> Outcome,
    ) -> Scenario {
        Scenario {
            name,
            section,
            summary,
            tags,
            budget: Duration::from_secs(120),
            body,
        }
    }

    /// Allows more virtual time (for moves of millions of steps).
    pub const fn budget(mut self, budget: Duration) -> Scenario {
        self.budget = budget;
        self
    }

    pub fn has_tag(&self, tag: &str) -> bool {
        self.tags.contains(&tag)
    }
}

/// Runs one scenario from a hardware reset. A panic in the scenario body
/// becomes an error verdict; the caller's run goes on.
pub fn run_scenario(
    target: &mut dyn Target,
    scenario: &Scenario,
    opts: DriverOptions,
) -> ScenarioResult {
    let opts = DriverOptions {
        budget: scenario.budget,
        ..opts
    };
    let started = std::time::Instant::now();
    target.set_deadline(opts.timeout.map(|limit| started + limit));
    let info = target.info();
    let uncertainty = target.uncertainty();
    let mut driver = Driver::new(target, opts);
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        driver.reset()?;
        (scenario.body)(&mut driver)?;
        // Deferred steps and checks still to run and judge; the capture
        // comes back with them.
        driver.finish()
    }));
    let outcome = match outcome {
        Ok(o) => o,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            Err(Stop::Error(HarnessError::Scenario(format!(
                "scenario panicked: {msg}"
            ))))
        }
    };
    // The capture the scenario left is fetched whatever its deadline
    // did; the health check and the next scenario have limits of their
    // own.
    driver.lift_deadline();
    let elapsed = driver.clock().saturating_since(Instant::ZERO);
    let capture = driver.capture().cloned();
    let (bus, measurements) = driver.into_parts();
    let verdict = match (outcome, &capture) {
        // Without the capture the run cannot be shown or compared: the link
        // failed, whatever the expectations said.
        (Ok(()), Err(Stop::Error(e))) => Verdict::Error(e.clone()),
        (Ok(()), _) if measurements.iter().any(|m| m.grade == Grade::Marginal) => Verdict::Marginal,
        (Ok(()), _) => Verdict::Passed,
        (Err(Stop::Failed(f)), _) => Verdict::Failed(f),
        (Err(Stop::Error(e)), _) => Verdict::Error(e),
    };
    // Stopped on request while waiting on the target: no verdict.
    let verdict = match verdict {
        Verdict::Error(HarnessError::Target {
            kind: TargetErrorKind::Interrupted,
            ..
        }) => Verdict::NotRun(NotRun::Interrupted),
        v => v,
    };
    let capture = capture.ok();
    let measures: Vec<Event> = measurements
        .iter()
        .map(|m| Event {
            at: m.at,
            // A trace from an exact target (the emulator) writes no `±`, so
            // that golden traces stay as they were: a chopping stretch's
            // sampling resolution is in its measurement, not its trace.
            kind: EventKind::Measure {
                name: m.name.clone(),
                value: m.value,
                u: if uncertainty == Uncertainty::ZERO {
                    Duration::ZERO
                } else {
                    m.u
                },
            },
        })
        .collect();
    // An instrument that is not exact says how unsure its times are.
    let mut details = info.extra.clone();
    if uncertainty != Uncertainty::ZERO {
        details.push(crate::trace::uncertainty_entry(&uncertainty));
    }
    let trace = capture.map(|c| {
        Trace::new(
            scenario.name,
            scenario.section,
            &info.name,
            info.straps,
            details,
        )
        .assemble(bus, &c, measures)
    });
    ScenarioResult {
        name: scenario.name,
        section: scenario.section,
        tags: scenario.tags,
        verdict,
        measurements,
        trace,
        elapsed,
        wall: started.elapsed(),
        attempts: Vec::new(),
    }
}
