//! The host firmware's use of the chip, judged from the accesses a
//! capture shows: the rules of chapter 3 a host must keep. A broken rule
//! is a [`HostFinding`], about the firmware driving the chip, never a
//! failure of the board: the model beside the capture says what the
//! chip's registers held when the host acted, and what the chip answered.
//!
//! The rules (`docs/capture.md` has them as a table):
//!
//! - 3-1-1: a byte written while IBF is 1 (it replaces the waiting one);
//!   a data read before OBF is 1 (no byte is waiting);
//! - 3-1-4: a command code written while the chip still awaits parameter
//!   bytes of the command before (status bits 6-4 not 0): that command is
//!   dropped unfinished (notes N35);
//! - 3-5-4: a software reset written while BUSY is 1: it is taken as
//!   AUX ON, the motor is not freed;
//! - every error of Table 3-2 the chip answers a host's byte with, which
//!   3-1-1 (4) calls "an error in the command code given by the host",
//!   under the section that forbids what the host did: 3-1-1 (3) a command
//!   or data byte while the motor runs (errors 1, 6), 3-4 a register read
//!   then (error 1), 3-2 a move before initialization (error 2), 3-1-4 a
//!   data byte no command asked for (error 3), 3-2-2 initialization data
//!   out of bounds (errors 4, 5), 3-3-1 and 3-3-2 a stop while stopped
//!   (error 0), 3-3-2 a Decelerating Stop while decelerating (error 7),
//!   Table 3-2 an undefined command code (error 0). The chip's answer is
//!   judged once it has taken the byte (IBF back to 0), from the model:
//!   notes N54.

use ppmc::emu::Board;
use ppmc::protocol::{Command, ErrorCode, StatusField};
use ppmc_logic::decode::{Access, Transaction};

/// The host firmware using the chip against chapter 3.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostFinding {
    pub at_ps: u64,
    /// The datasheet section it breaks.
    pub section: &'static str,
    pub what: String,
}

/// The rules, and what they remember of the accesses so far.
#[derive(Debug, Default, Clone)]
pub(super) struct HostRules {
    /// The last byte written, until the chip has taken it: what the chip
    /// answered it with is judged then.
    written: Option<Transaction>,
}

impl HostRules {
    /// An access `t`, with `board` (the model) as the chip was when its
    /// strobe ended, before the access took effect.
    pub(super) fn before(&mut self, t: &Transaction, board: &Board, out: &mut Vec<HostFinding>) {
        self.settle(board, out);
        let status = board.read_status();
        let finding = |section, what| HostFinding {
            at_ps: t.end_ps,
            section,
            what,
        };
        match t.access {
            Access::WriteCommand | Access::WriteData if status.ibf() => out.push(finding(
                "3-1-1",
                format!(
                    "`{t}` written while IBF was 1: the chip had not taken the byte before, and this one replaces it"
                ),
            )),
            Access::ReadData if !status.obf() => out.push(finding(
                "3-1-1",
                "a data read before OBF was 1: no byte was waiting".into(),
            )),
            Access::WriteCommand => {
                // The chip has taken every byte before this one (IBF 0):
                // its parameter count is the host's to finish.
                if let StatusField::ParamsRemaining(n @ 1..) = board.chip().read_status().field() {
                    out.push(finding(
                        "3-1-4",
                        format!(
                            "`{t}` written while the chip still awaited {n} parameter byte{} of the command before (status bits 6-4): that command is dropped unfinished",
                            if n == 1 { "" } else { "s" }
                        ),
                    ));
                }
                if matches!(Command::decode(t.byte), Command::SoftwareReset(_)) && status.busy() {
                    out.push(finding(
                        "3-5-4",
                        format!(
                            "`{t}`, a software reset, written while BUSY was 1: it is effective only when the motor is stopped, and the chip takes it as AUX ON"
                        ),
                    ));
                }
            }
            _ => {}
        }
    }

    /// The same access, once it has taken effect in `board`.
    pub(super) fn after(&mut self, t: &Transaction, _board: &Board, _out: &mut Vec<HostFinding>) {
        if matches!(t.access, Access::WriteCommand | Access::WriteData) {
            // A byte still waiting is replaced: only this one is taken.
            self.written = Some(*t);
        }
    }

    /// The capture's end, at `end_ps`: what the host left undone.
    pub(super) fn finish(&mut self, _end_ps: u64, board: &Board, out: &mut Vec<HostFinding>) {
        self.settle(board, out);
    }

    /// Once the chip has taken the last byte written, the error it
    /// answered with, if any: every error of Table 3-2 is raised on the
    /// byte that causes it and stays until the next command code is taken
    /// (notes N6), and a data byte taken while an error shows raises its
    /// own, so an error showing now is this byte's.
    fn settle(&mut self, board: &Board, out: &mut Vec<HostFinding>) {
        let Some(w) = self.written else { return };
        let status = board.chip().read_status();
        if status.ibf() {
            return;
        }
        self.written = None;
        if let Some(e) = status.error() {
            out.push(refused(&w, e));
        }
    }
}

/// The finding for `w`, which the chip answered with error `e`.
fn refused(w: &Transaction, e: ErrorCode) -> HostFinding {
    let cmd = (w.access == Access::WriteCommand).then(|| Command::decode(w.byte));
    let (section, why) = match e {
        ErrorCode::UndefinedCommand => match cmd {
            Some(Command::ImmediateStop(_)) => (
                "3-3-1",
                "an Immediate Stop while the motor was stopped: it has effect only while BUSY is 1",
            ),
            Some(Command::DecelStop(_)) => (
                "3-3-2",
                "a Decelerating Stop while the motor was stopped: like Immediate Stop, it has effect only while BUSY is 1",
            ),
            _ => ("Table 3-2", "a command code the chip does not define"),
        },
        ErrorCode::NotAllowedWhileBusy => match cmd {
            Some(Command::Read(_)) => (
                "3-4",
                "a register read while the motor was running (BUSY 1): data can be read only when it is stopped",
            ),
            _ => (
                "3-1-1 (3)",
                "a command while the motor was running (BUSY 1): only Immediate Stop, Decelerating Stop and the auxiliary output commands are accepted then",
            ),
        },
        ErrorCode::NotInitialized => (
            "3-2",
            "a move before the initialization command, which must be issued first after reset and after a software reset",
        ),
        ErrorCode::TooManyParameters => (
            "3-1-4",
            "a data byte no command asked for: data follow the command code that wants them, as many as it wants",
        ),
        ErrorCode::AccelPulsesTooMany | ErrorCode::BadRateData => (
            "3-2-2",
            "initialization data out of bounds (255 > RL > RH > 0, 4 to 11,220 acceleration pulses)",
        ),
        ErrorCode::DataWhileBusy => (
            "3-1-1 (3)",
            "a data byte while the motor was running (BUSY 1): data are not accepted during pulse output",
        ),
        ErrorCode::DecelStopDuringDecel => (
            "3-3-2",
            "a Decelerating Stop while the motor was already decelerating",
        ),
    };
    HostFinding {
        at_ps: w.end_ps,
        section,
        what: format!("`{w}`: {why}; the chip answered {e}"),
    }
}
