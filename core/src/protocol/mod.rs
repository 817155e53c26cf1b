//! The chip's host protocol as pure data: command codes, register bytes,
//! error numbers, rate and time equations, and Table 3-3.
//!
//! Nothing here touches a clock, a file or a port.

pub mod capture;
pub mod command;
pub mod phase;
pub mod rates;
pub mod registers;
pub mod timing;

pub use capture::{
    EdgeRuns, MoveStart, OutputMark, OutputRecord, Pin, PinEvent, Pins, PulseRun, PulseSummary,
    SWITCHING_WINDOW,
};
pub use command::{
    ClockSource, Command, Direction, Excitation, InitCommand, InitData, MotorType, MoveCommand,
    MoveKind, OpFlags, OutputLogic, PulseCount, Register,
};
pub use phase::{Chop, PhaseOutputs, Winding};
pub use rates::{StrapFieldError, Straps, StrapsError, STRAP_KEYS};
pub use registers::{
    AuxInputStatus, ErrorCode, FinishStatus, Flag, Input, InputSet, InputStatus, OutputStatus,
    Status, StatusField, StopCause,
};
pub use timing::{TimingId, TimingRow, TABLE_3_3};
