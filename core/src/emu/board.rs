//! A chip on a board: the reference model behind what the board's wiring
//! does to the host's view of it. Faults that act on the data bus live here,
//! outside the model, which stays only the datasheet; `ppmc::faults` names
//! them. The faults that need the model's insides are its hooks
//! ([`super::hooks`]).

use super::{Chip, ChipError, ModelConfig};
use crate::protocol::{ErrorCode, Input, Pins, Record, Status, Straps};
use crate::time::Instant;

/// Faults on the board's data bus, seen in every status register read (by
/// the host, and by a bridge waiting on a flag).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BusFaults {
    /// Status register bits that read 1 whatever the chip says (a data bus
    /// line stuck high).
    pub status_stuck_high: u8,
    /// The status shows the second error number where the chip reports the
    /// first (two crossed lines on bits 6-4).
    pub swap_error: Option<(ErrorCode, ErrorCode)>,
}

impl BusFaults {
    /// The status byte as the host reads it through this board.
    pub fn status(&self, s: Status) -> Status {
        let mut b = s.0;
        if let Some((from, to)) = self.swap_error {
            if s.error() == Some(from) {
                b = (b & !0x70) | (to.number() << 4);
            }
        }
        Status(b | self.status_stuck_high)
    }
}

/// The reference model as a host reaches it through a board: every status
/// read passes the board's [`BusFaults`] ([`ModelConfig::board`]). Everything
/// else is the chip's own.
#[derive(Debug, Clone)]
pub struct Board {
    chip: Chip,
    bus: BusFaults,
}

impl Board {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Board, ChipError> {
        let bus = cfg.board;
        Ok(Board {
            chip: Chip::new(straps, cfg)?,
            bus,
        })
    }

    /// The model itself, without the board.
    pub fn chip(&self) -> &Chip {
        &self.chip
    }

    pub fn chip_mut(&mut self) -> &mut Chip {
        &mut self.chip
    }

    /// Host read of the status register, through the board.
    pub fn read_status(&self) -> Status {
        self.bus.status(self.chip.read_status())
    }

    pub fn write_command(&mut self, byte: u8) {
        self.chip.write_command(byte)
    }

    pub fn write_data(&mut self, byte: u8) {
        self.chip.write_data(byte)
    }

    pub fn read_data(&mut self) -> u8 {
        self.chip.read_data()
    }

    pub fn set_input(&mut self, input: Input, asserted: bool) {
        self.chip.set_input(input, asserted)
    }

    pub fn straps(&self) -> &Straps {
        self.chip.straps()
    }

    pub fn now(&self) -> Instant {
        self.chip.now()
    }

    pub fn record(&self) -> &Record {
        self.chip.record()
    }

    pub fn pins(&self) -> Pins {
        self.chip.pins()
    }

    pub fn move_pulses(&self) -> u64 {
        self.chip.move_pulses()
    }

    pub fn predict_pulse(&self, n: u64) -> Option<Instant> {
        self.chip.predict_pulse(n)
    }

    pub fn poll_at(&self) -> Option<Instant> {
        self.chip.poll_at()
    }

    pub fn advance_to(&mut self, until: Instant) {
        self.chip.advance_to(until)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::StatusField;

    #[test]
    fn a_stuck_line_and_crossed_error_lines_change_only_what_the_host_reads() {
        let error2 = Status::new(
            false,
            false,
            false,
            StatusField::Error(ErrorCode::NotInitialized),
        );
        let bus = BusFaults {
            status_stuck_high: 0x08,
            swap_error: Some((ErrorCode::NotInitialized, ErrorCode::TooManyParameters)),
        };
        // Diagram 3-1: error flag bit 7, number in bits 6-4; bit 3 stuck.
        assert_eq!(bus.status(error2).0, 0x80 | 3 << 4 | 0x08);
        let idle = Status::new(false, false, false, StatusField::ParamsRemaining(0));
        assert_eq!(bus.status(idle).0, 0x08);
        assert_eq!(BusFaults::default().status(error2), error2);
    }
}
