//! Conformance scenarios: plain Rust functions over a [`Driver`].
//!
//! A scenario names the datasheet section it covers, carries tags, and
//! either returns `Ok(())` or stops at the first expectation that failed.
//! [`run_scenario`] runs one on a target from a hardware reset and returns
//! its [`ScenarioResult`]: the verdict, the graded measurements and the
//! trace.

mod batch;
mod builders;
mod check;
pub mod driver;
mod measure;
mod options;
mod outcome;
mod record;
mod run;
mod steps;
mod verdict;

pub use builders::{Init, Move};
pub use driver::Driver;
pub use options::DriverOptions;
pub use outcome::{deviation_of, Failure, HarnessError, Outcome, Stop};
/// Declares a scenario where it is written; see the `ppmc-macros` crate.
pub use ppmc_macros::scenario;
pub use ppmc_record::{Grade, Grading, Measurement};
pub use run::{run_scenario, Scenario};
pub use verdict::{Attempt, NotRun, Retry, ScenarioResult, Verdict};

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
