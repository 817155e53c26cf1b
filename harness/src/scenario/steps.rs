//! What a driver queues: a [`Step`] (an op and how its reply is judged),
//! the [`Role`] it plays for the measurements that follow, and what it
//! gave back, [`Done`].

use crate::protocol::{Flag, Input, Pins, Status};
use crate::time::Duration;

/// One step: an op and how its reply is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Step {
    Write {
        byte: u8,
        command: bool,
        wait: bool,
    },
    Status,
    ReadData,
    /// `must`: a timeout fails the scenario.
    Await {
        flag: Flag,
        value: bool,
        timeout: Duration,
        must: bool,
    },
    Delay(Duration),
    Set {
        input: Input,
        on: bool,
    },
    AwaitPulses {
        count: u64,
        timeout: Duration,
    },
    Reset,
    Pins,
}

/// What a step gave back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Done {
    At,
    Status(Status),
    Byte(u8),
    Waited(Option<Duration>),
    Pins(Pins),
}

/// What the batch marks of a step once it has run: the times the
/// driver's measurements start from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Role {
    Plain,
    /// The final byte of an initialization.
    InitWrite,
    /// The final byte of an operation command: the anchor of measurements.
    Anchor,
    /// A stop, an input edge or an auxiliary command: the trigger of
    /// latency measurements.
    Trigger,
}
