//! [`DriverOptions`]: the timeouts, budget and grading a driver runs a
//! scenario with.

use crate::time::Duration;
use ppmc_record::Grading;

/// Timeouts and limits of a [`Driver`](super::driver::Driver), given for
/// the reference board (16 MHz, CSEL high): the driver stretches each for
/// a slower board ([`Straps::stretch`](crate::protocol::Straps::stretch)),
/// so a scenario's limits hold at every clock the straps allow.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriverOptions {
    /// Flowchart writes wait at most this long for IBF = 0.
    pub ibf_timeout: Duration,
    /// Flowchart reads wait at most this long for OBF = 1.
    pub obf_timeout: Duration,
    /// An operation command must raise BUSY within this.
    pub busy_timeout: Duration,
    /// [`Driver::wait_idle`](super::driver::Driver::wait_idle) waits at
    /// most this long for BUSY = 0.
    pub idle_timeout: Duration,
    /// Virtual time one scenario may use before it is stopped as an error.
    pub budget: Duration,
    pub grading: Grading,
    /// When the runner tries a scenario again (the driver itself never
    /// does).
    pub retry: super::verdict::Retry,
    /// The longest one scenario may take on the wall clock (`ppmc run
    /// --timeout`): past it, a board's host tells the bridge to stop
    /// (ABORT) and the scenario is an error naming the limit. `None`: no
    /// limit but the scenario's own (its virtual-time budget).
    pub timeout: Option<std::time::Duration>,
}

impl Default for DriverOptions {
    fn default() -> Self {
        DriverOptions {
            ibf_timeout: Duration::from_secs(1),
            obf_timeout: Duration::from_millis(100),
            busy_timeout: Duration::from_millis(5),
            idle_timeout: Duration::from_secs(60),
            budget: Duration::from_secs(120),
            grading: Grading::default(),
            retry: super::verdict::Retry::default(),
            timeout: None,
        }
    }
}
