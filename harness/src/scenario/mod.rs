//! Conformance scenarios: plain Rust functions over a [`Driver`].
//!
//! A scenario names the datasheet section it covers, carries tags, and
//! either returns `Ok(())` or stops at the first expectation that failed.
//! [`run_scenario`] runs one on a target from a hardware reset and returns
//! its [`ScenarioResult`]: the verdict, the graded measurements and the
//! trace.

mod builders;
pub mod driver;
pub mod grade;
mod measure;
mod queue;

pub use builders::{Init, Move};
pub use driver::{Driver, DriverOptions};
pub use grade::{Grade, Grading, Measurement};
/// Declares a scenario where it is written; see the `ppmc-macros` crate.
pub use ppmc_macros::scenario;

use crate::backend::{Target, TargetError, TargetErrorKind};
use crate::time::{Duration, Instant};
use crate::trace::{Event, EventKind, Trace};
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// What a scenario body returns.
pub type Outcome<T = ()> = Result<T, Stop>;

/// Why a scenario stopped before its end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Stop {
    /// The device did something the datasheet does not allow.
    Failed(Failure),
    /// The harness or the link failed: not the device's fault.
    Error(HarnessError),
}

/// Why a scenario could not be judged: never the device's fault. The kind
/// says whose it is; the text is for people.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HarnessError {
    /// The target could not run a batch: the link, the bridge, the port.
    #[error("target: {message}")]
    Target {
        kind: TargetErrorKind,
        message: String,
    },
    /// The target's replies do not fit the ops sent (a backend or bridge
    /// bug).
    #[error("{0}")]
    Reply(String),
    /// The scenario used more virtual time than its budget.
    #[error("scenario exceeded its time budget of {0} (virtual time)")]
    Budget(Duration),
    /// The capture did not come back, so the run cannot be judged, shown
    /// or compared.
    #[error("{0}")]
    Capture(String),
    /// The scenario's own code is wrong: it panicked, or asked for
    /// something it had not set up.
    #[error("{0}")]
    Scenario(String),
    /// A golden trace is missing, unreadable or could not be used.
    #[error("{0}")]
    Golden(String),
}

impl HarnessError {
    /// A target failure, with its kind.
    pub fn target(e: &TargetError) -> HarnessError {
        HarnessError::Target {
            kind: e.kind,
            message: e.to_string(),
        }
    }
}

/// An expectation that did not hold.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    pub expectation: String,
    pub expected: String,
    pub got: String,
    /// When it happened, on the target's clock.
    pub at: Instant,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "at {}: {}: expected {}, got {}",
            self.at, self.expectation, self.expected, self.got
        )
    }
}

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

/// How a scenario ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    Passed,
    /// Passed, with at least one measurement near a limit.
    Marginal,
    /// The device did something wrong.
    Failed(Failure),
    /// The harness or the link failed.
    Error(HarnessError),
    /// Never started (the run stopped before it).
    NotRun(NotRun),
}

/// Why a scenario was never started: the infrastructure, never the device.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NotRun {
    /// The target could not be reached or was not healthy before the run
    /// began (the text says why).
    #[error("{0}")]
    Unreachable(String),
    /// The target stopped answering during the run (after a harness error,
    /// the health check failed too).
    #[error("not run: the target stopped answering ({0})")]
    TargetLost(String),
    /// The run was stopped before it (SIGINT, SIGTERM, or its output
    /// closed).
    #[error("not run: the run was interrupted")]
    Interrupted,
}

impl Verdict {
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Passed => "passed",
            Verdict::Marginal => "marginal",
            Verdict::Failed(_) => "failed",
            Verdict::Error(_) => "error",
            Verdict::NotRun(_) => "not run",
        }
    }

    /// Whether the verdict lets a run pass (passed or marginal).
    pub fn ok(&self) -> bool {
        matches!(self, Verdict::Passed | Verdict::Marginal)
    }

    /// The one-line reason, for reports.
    pub fn detail(&self) -> Option<String> {
        match self {
            Verdict::Passed => None,
            Verdict::Marginal => Some("a measurement is near its limit".into()),
            Verdict::Failed(f) => Some(f.to_string()),
            Verdict::Error(e) => Some(e.to_string()),
            Verdict::NotRun(why) => Some(why.to_string()),
        }
    }
}

/// Everything a run learned about one scenario.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    pub name: &'static str,
    pub section: &'static str,
    pub tags: &'static [&'static str],
    pub verdict: Verdict,
    pub measurements: Vec<Measurement>,
    /// `None` when the target could not deliver a capture.
    pub trace: Option<Trace>,
    /// Virtual time the scenario took on the target.
    pub elapsed: Duration,
    /// Wall-clock time the harness spent on it.
    pub wall: std::time::Duration,
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
    let info = target.info();
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
            kind: EventKind::Measure {
                name: m.name.clone(),
                value: m.value,
            },
        })
        .collect();
    let trace = capture.map(|c| {
        Trace::new(
            scenario.name,
            scenario.section,
            &info.name,
            info.straps,
            info.extra.clone(),
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
    }
}

/// What scenario files import.
pub mod prelude {
    pub use super::{scenario, Driver, Init, Move, Outcome, Scenario};
    pub use crate::protocol::Direction::{Ccw, Cw};
    pub use crate::protocol::{
        ClockSource, Direction, ErrorCode, Flag, Input, MotorType, Register, TimingId,
    };
    pub use crate::time::Duration;

    /// Microseconds.
    pub const fn us(n: u64) -> Duration {
        Duration::from_micros(n)
    }

    /// Milliseconds.
    pub const fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }
}
