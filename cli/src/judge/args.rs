//! `ppmc judge`'s arguments.

use crate::args::ReportArgs;
use crate::args::{ChipArgs, ToleranceArgs};
use crate::capture_args::CaptureArgs;
use clap::Args;
use std::path::PathBuf;

/// Judge a board from a capture of its bus and pins: the captured writes
/// replayed into the reference model, the chip's answers, pulses and
/// outputs compared (docs/capture.md). Exit status: 0 passed; 1 the board
/// diverged; 3 the board passed but the host firmware broke a rule of
/// chapter 3; 4 the capture cannot be judged (a channel missing, a sample
/// rate too low for the bus, nothing on the bus); 2 a file that does not
/// read, or bad usage.
#[derive(Debug, Args)]
pub struct JudgeArgs {
    #[command(flatten)]
    pub(crate) capture: CaptureArgs,
    #[command(flatten)]
    pub(crate) chip: ChipArgs,
    #[command(flatten)]
    pub(crate) tolerance: ToleranceArgs,
    #[command(flatten)]
    pub(crate) reports: ReportArgs,
    /// The board's serial number, for the reports and the store.
    #[arg(long, value_name = "SERIAL", value_parser = crate::args::label)]
    pub(crate) board_serial: Option<String>,
    /// The board's revision label, for the reports and the store.
    #[arg(long, value_name = "REV", value_parser = crate::args::label)]
    pub(crate) board_rev: Option<String>,
    /// Also write the capture as a trace in our format, `DIR/<scenario>.snap`
    /// (never replacing a file there), for `ppmc compare GOLDEN --traces
    /// DIR`: the writes and data reads, the moves they started, the pulses
    /// and the outputs the capture has (docs/capture.md).
    #[arg(long, value_name = "DIR")]
    pub(crate) trace: Option<PathBuf>,
    /// With --trace: the name of the trace it writes, the scenario the
    /// capture records (default: the capture file's name without its
    /// extension). The judging itself needs no scenario: it replays the
    /// accesses the capture holds.
    #[arg(long, value_name = "NAME")]
    pub(crate) scenario: Option<String>,
    /// Judge what the capture holds though it is not whole: it ends
    /// mid-line, during a register access or while the board is still
    /// moving, or it has no channel for POUT while the chip pulses. The
    /// verdict then says what was not judged. Without it such a capture
    /// is the capture's problem (exit 4), never a pass.
    #[arg(long)]
    pub(crate) partial: bool,
}
