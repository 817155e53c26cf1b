//! What a scenario body returns and why it stops: [`Outcome`], [`Stop`],
//! the device's [`Failure`] (with [`Shown`], how a value appears in one)
//! and the harness's [`HarnessError`].

use crate::backend::{TargetError, TargetErrorKind};
use crate::time::{Duration, Instant};
use ppmc_record::{Deviation, DeviationUnit, Reference};
use std::fmt;

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
    /// The target did an op too far from the moment the scenario aimed it
    /// at for the check to mean what it says (a latency probe's trigger
    /// placed on the other side of its band's edge): the instrument's
    /// miss, which says nothing about the device.
    #[error("{0}")]
    Aim(String),
    /// The board hung under the scenario (its bridge silent past the
    /// link's bounds, or its chip BUSY after a chip reset) and was brought
    /// back by power, so the scenario cannot be judged; the run went on.
    #[error("the board hung: {hang}; {recovery}, and the run went on")]
    Hung { hang: String, recovery: String },
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
    /// By how much, where the check has a magnitude.
    pub deviation: Option<Deviation>,
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

/// A value [`Driver::check`](super::driver::Driver::check) compares, as a
/// failure report shows it to a person: `true`, `42`, `0x3F` for a
/// register byte, `120.000us`, `none`.
pub trait Shown {
    fn shown(&self) -> String;
}

macro_rules! shown_as_text {
    ($($t:ty),*) => {$(
        impl Shown for $t {
            fn shown(&self) -> String {
                self.to_string()
            }
        }
    )*};
}

shown_as_text!(bool, u16, u32, u64, usize, i32, i64, Instant, Duration, String, &str);

impl Shown for u8 {
    fn shown(&self) -> String {
        format!("0x{self:02X}")
    }
}

impl<T: Shown> Shown for Option<T> {
    fn shown(&self) -> String {
        match self {
            Some(v) => v.shown(),
            None => "none".into(),
        }
    }
}

/// A failed expectation: what was expected, what came, and when.
pub(super) fn fail(
    expectation: impl Into<String>,
    expected: impl ToString,
    got: impl ToString,
    at: Instant,
) -> Stop {
    let (expected, got) = (expected.to_string(), got.to_string());
    Stop::Failed(Failure {
        expectation: expectation.into(),
        deviation: deviation_of(&expected, &got, Reference::Expected),
        expected,
        got,
        at,
    })
}

/// A value `got` outside the band `lo` to `hi`, all of `unit`, with its
/// uncertainty `u`: its deviation from the limit it fell outside.
pub(super) fn outside(lo: i64, hi: i64, got: i64, unit: DeviationUnit, u: u64) -> Deviation {
    Deviation {
        unit,
        measured: got,
        reference: if got > hi { hi } else { lo },
        reference_is: Reference::Limit,
        u,
        bound: None,
    }
}

/// [`fail`] of a value outside a band, with its [`outside`] deviation.
pub(super) fn fail_outside(
    expectation: impl Into<String>,
    expected: impl ToString,
    got: impl ToString,
    at: Instant,
    deviation: Deviation,
) -> Stop {
    Stop::Failed(Failure {
        expectation: expectation.into(),
        expected: expected.to_string(),
        got: got.to_string(),
        at,
        deviation: Some(deviation),
    })
}

/// The deviation of `got` from `expected` where both are one number of
/// the same kind as [`Shown`] writes it: two counts (`100`, `99`) or two
/// times (`120.000us`); `None` for anything else (a register byte, a
/// flag, a range), which has no magnitude to subtract.
pub fn deviation_of(expected: &str, got: &str, reference_is: Reference) -> Option<Deviation> {
    let count = |s: &str| s.trim().parse::<i64>().ok();
    let time = |s: &str| {
        s.trim()
            .parse::<Duration>()
            .ok()
            .and_then(|d| i64::try_from(d.as_nanos()).ok())
    };
    let (unit, measured, reference) = match (count(got), count(expected)) {
        (Some(g), Some(e)) => (DeviationUnit::Count, g, e),
        _ => (DeviationUnit::Ns, time(got)?, time(expected)?),
    };
    Some(Deviation {
        unit,
        measured,
        reference,
        reference_is,
        u: 0,
        bound: None,
    })
}

/// The time `t` a measurement starts from, or a scenario bug if the
/// scenario has not done `what` that sets it.
pub(super) fn need(what: &str, t: Option<Instant>) -> Outcome<Instant> {
    t.ok_or_else(|| {
        Stop::Error(HarnessError::Scenario(format!(
            "scenario bug: measuring needs {what}, which this scenario has not done"
        )))
    })
}
