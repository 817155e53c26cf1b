//! The host firmware's use of the chip, judged from the accesses a
//! capture shows: the rules of chapter 3 a host must keep (3-1-1's
//! handshake, ...). A broken rule is a [`HostFinding`], about the firmware
//! driving the chip, never a failure of the board: the model beside the
//! capture says what the chip's registers held when the host acted.

use crate::emu::Board;
use crate::logic::decode::{Access, Transaction};

/// The host firmware using the chip against chapter 3.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostFinding {
    pub at_ps: u64,
    /// The datasheet section it breaks.
    pub section: &'static str,
    pub what: String,
}

/// The rules, and what they remember of the accesses so far.
#[derive(Debug, Default)]
pub(super) struct HostRules {}

impl HostRules {
    /// An access `t`, with `board` (the model) as the chip was when its
    /// strobe ended, before the access took effect.
    pub(super) fn before(&mut self, t: &Transaction, board: &Board, out: &mut Vec<HostFinding>) {
        let status = board.read_status();
        match t.access {
            Access::WriteCommand | Access::WriteData if status.ibf() => out.push(HostFinding {
                at_ps: t.end_ps,
                section: "3-1-1",
                what: format!(
                    "`{t}` written while IBF was 1: the chip had not taken the byte before, and this one replaces it"
                ),
            }),
            Access::ReadData if !status.obf() => out.push(HostFinding {
                at_ps: t.end_ps,
                section: "3-1-1",
                what: "a data read before OBF was 1: no byte was waiting".into(),
            }),
            _ => {}
        }
    }

    /// The same access, once it has taken effect in `board`.
    pub(super) fn after(&mut self, _t: &Transaction, _board: &Board, _out: &mut Vec<HostFinding>) {}

    /// The capture's end, at `end_ps`: what the host left undone.
    pub(super) fn finish(&mut self, _end_ps: u64, _board: &Board, _out: &mut Vec<HostFinding>) {}
}
