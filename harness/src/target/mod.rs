//! One bus abstraction, many backends.
//!
//! Everything that drives a chip (the console, later the scenario runner
//! and the fuzzer) talks to a [`Target`] through batches of [`Op`]s. A batch
//! runs back to back on the target's own clock and comes back as one
//! [`Reply`] per op, each stamped with the target's time. On the emulator a
//! batch costs nothing; on a board behind the serial bus bridge it costs one
//! round trip, which is why waiting (for IBF, OBF, BUSY) is an op the target
//! performs, never a host-side polling loop.

mod emu;
mod serial;

pub use self::emu::EmuTarget;
pub use self::serial::{
    parse_spec, Link, LinkStats, SerialError, SerialLink, SerialOptions, SerialTarget,
};

use crate::protocol::{Flag, Input, Pins, PulseSummary, Record, Status};
use crate::time::{Duration, Instant};
use std::fmt;

/// One bus-level operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// Write the command register. With `wait_ibf`, first wait up to that
    /// long for IBF = 0 as the datasheet flowcharts do, and skip the write
    /// if IBF stays 1; without, write at once.
    WriteCommand {
        byte: u8,
        wait_ibf: Option<Duration>,
    },
    /// Write the data register; `wait_ibf` as for [`Op::WriteCommand`].
    WriteData {
        byte: u8,
        wait_ibf: Option<Duration>,
    },
    /// Read the status register.
    ReadStatus,
    /// Read the data register. With `wait_obf`, first wait up to that long
    /// for OBF = 1 and skip the read if it stays 0.
    ReadData { wait_obf: Option<Duration> },
    /// Let time pass.
    Delay(Duration),
    /// Wait until `status & mask == value`, at most `timeout`.
    AwaitStatus {
        mask: u8,
        value: u8,
        timeout: Duration,
    },
    /// Drive an input: `asserted` = the active-low pin pulled low.
    SetInput { input: Input, asserted: bool },
    /// Sample the output pins.
    ReadPins,
    /// Summarize the pulses of the most recent move.
    ReadPulses,
    /// Wait until the most recent move has output `count` pulses (at most
    /// `timeout`), so that the next op acts right after that pulse: how a
    /// scenario drives a limit switch "after N pulses" on the target's own
    /// clock.
    AwaitPulses { count: u64, timeout: Duration },
    /// Hardware reset of the chip (the RESET pin): registers, inputs and the
    /// capture start over, and the target's clock restarts at zero.
    Reset,
}

impl Op {
    /// Wait until a status flag has `value`, at most `timeout`.
    pub fn await_flag(flag: Flag, value: bool, timeout: Duration) -> Op {
        Op::AwaitStatus {
            mask: flag.mask(),
            value: if value { flag.mask() } else { 0 },
            timeout,
        }
    }
}

/// The outcome of one [`Op`], stamped with the target's time when it ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    /// A write happened at `at`, after waiting `waited` for IBF = 0 (zero
    /// for a write without a wait).
    Written {
        at: Instant,
        waited: Duration,
    },
    /// IBF stayed 1 for the whole wait; nothing was written.
    WriteTimedOut {
        at: Instant,
        status: Status,
    },
    Status {
        at: Instant,
        status: Status,
    },
    /// A data register read at `at`, after waiting `waited` for OBF = 1.
    Data {
        at: Instant,
        byte: u8,
        waited: Duration,
    },
    /// OBF stayed 0 for the whole wait; nothing was read.
    ReadTimedOut {
        at: Instant,
        status: Status,
    },
    Delayed {
        at: Instant,
    },
    /// The condition held after `waited`.
    Awaited {
        at: Instant,
        waited: Duration,
        status: Status,
    },
    AwaitTimedOut {
        at: Instant,
        status: Status,
    },
    InputSet {
        at: Instant,
    },
    Pins {
        at: Instant,
        pins: Pins,
    },
    Pulses {
        at: Instant,
        summary: PulseSummary,
    },
    /// The pulse count was reached; `at` is the time of that pulse.
    PulsesReached {
        at: Instant,
    },
    /// The move ended or the timeout passed first; `count` pulses were seen.
    PulsesTimedOut {
        at: Instant,
        count: u64,
    },
    ResetDone {
        at: Instant,
    },
}

impl Reply {
    /// The target time at which the op completed.
    pub fn at(&self) -> Instant {
        match *self {
            Reply::Written { at, .. }
            | Reply::WriteTimedOut { at, .. }
            | Reply::Status { at, .. }
            | Reply::Data { at, .. }
            | Reply::ReadTimedOut { at, .. }
            | Reply::Delayed { at }
            | Reply::Awaited { at, .. }
            | Reply::AwaitTimedOut { at, .. }
            | Reply::InputSet { at }
            | Reply::Pins { at, .. }
            | Reply::Pulses { at, .. }
            | Reply::PulsesReached { at }
            | Reply::PulsesTimedOut { at, .. }
            | Reply::ResetDone { at } => at,
        }
    }
}

/// What kind of failure a target error is, so that generic code can tell a
/// broken link from a misbehaving device (embedded-hal's `ErrorKind` idea).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TargetErrorKind {
    /// The connection to the target failed: port gone, no answer, corrupt
    /// frames. Not the device's fault.
    Link,
    /// The target refused the request (unsupported op, bad argument).
    Unsupported,
    /// Anything else inside the harness.
    Other,
}

/// A failure to run a batch on a target.
#[derive(Debug, thiserror::Error)]
pub struct TargetError {
    pub kind: TargetErrorKind,
    pub message: String,
}

impl fmt::Display for TargetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// What a target says about itself, for reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TargetInfo {
    /// `emu`, or `serial:/dev/ttyACM0`.
    pub name: String,
    /// Free-form details: straps, model parameters, bridge firmware.
    pub details: Vec<(String, String)>,
}

/// A chip the harness can drive.
pub trait Target: Send {
    fn info(&self) -> TargetInfo;

    /// Everything captured on the output side since the last reset: pulse
    /// runs with the target's timestamps, pin changes, move starts.
    fn capture(&mut self) -> Result<Record, TargetError>;

    /// Runs `ops` back to back and returns one reply per op, in order.
    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError>;

    /// Runs `ops`, then returns the capture too: one round trip on a board
    /// where a caller needs both.
    fn execute_then_capture(&mut self, ops: &[Op]) -> Result<(Vec<Reply>, Record), TargetError> {
        let replies = self.execute(ops)?;
        Ok((replies, self.capture()?))
    }

    /// Runs one op.
    fn execute_one(&mut self, op: Op) -> Result<Reply, TargetError> {
        let mut replies = self.execute(std::slice::from_ref(&op))?;
        replies.pop().ok_or_else(|| TargetError {
            kind: TargetErrorKind::Other,
            message: format!("target returned no reply to {op:?}"),
        })
    }
}
