//! A chip on a board: the reference model behind what the board's wiring
//! does to the host's view of it. Faults of the board itself (a data bus
//! line, an input wire, an output line) live here, outside the model, which
//! stays only the datasheet; `ppmc::faults` names them. The faults that need
//! the model's insides are its hooks ([`super::hooks`]).

use super::{Chip, ChipError, ModelConfig};
use crate::protocol::{
    Direction, ErrorCode, Input, InputSet, OutputMark, OutputRecord, Pin, PinEvent, Pins, PulseRun,
    Status, Straps,
};
use crate::time::Instant;

/// Faults of the board around the chip: its data bus, seen in every status
/// register read (by the host, and by a bridge waiting on a flag), and its
/// pin wiring, seen by the chip (inputs) or by whatever captures its outputs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WiringFaults {
    /// Status register bits that read 1 whatever the chip says (a data bus
    /// line stuck high).
    pub status_stuck_high: u8,
    /// The status shows the second error number where the chip reports the
    /// first (two crossed lines on bits 6-4).
    pub swap_error: Option<(ErrorCode, ErrorCode)>,
    /// Inputs whose wire to the chip is open: the chip never sees them
    /// asserted, in a move or in the signal status register.
    pub inputs_cut: InputSet,
    /// An inverter on the DIR line: the pin, and the direction sampled with
    /// every pulse, read the opposite of what the chip drives.
    pub dir_inverted: bool,
    /// The HOLD line stuck off.
    pub hold_stuck_off: bool,
    /// AUXO0..3 wired in reverse order.
    pub auxo_reversed: bool,
}

impl WiringFaults {
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

    /// Whether any output line is miswired, so that what a capture sees
    /// differs from what the chip drives.
    fn outputs_miswired(&self) -> bool {
        self.dir_inverted || self.hold_stuck_off || self.auxo_reversed
    }

    fn dir(&self, d: Direction) -> Direction {
        match (d, self.dir_inverted) {
            (d, false) => d,
            (Direction::Cw, true) => Direction::Ccw,
            (Direction::Ccw, true) => Direction::Cw,
        }
    }

    fn auxo(&self, bits: u8) -> u8 {
        if self.auxo_reversed {
            (bits & 0x0F).reverse_bits() >> 4
        } else {
            bits
        }
    }

    /// The output pins as they arrive at the board's connector.
    pub fn pins(&self, p: Pins) -> Pins {
        Pins {
            hold: p.hold && !self.hold_stuck_off,
            auxo: self.auxo(p.auxo),
            dir: self.dir(p.dir),
            ..p
        }
    }

    /// A pin change as a capture at the connector sees it; `None` when the
    /// line does not move.
    pub fn pin_event(&self, e: PinEvent) -> Option<PinEvent> {
        let value = match e.pin {
            Pin::Hold if self.hold_stuck_off => return None,
            Pin::Auxo => self.auxo(e.value),
            Pin::Dir if self.dir_inverted => e.value ^ 1,
            _ => e.value,
        };
        Some(PinEvent { value, ..e })
    }

    /// A run of pulses as a capture at the connector sees it (DIR sampled at
    /// each edge).
    pub fn run(&self, r: PulseRun) -> PulseRun {
        PulseRun {
            dir: self.dir(r.dir),
            ..r
        }
    }
}

/// The reference model as a host reaches it through a board with the
/// [`WiringFaults`] of [`ModelConfig::board`]: every status read, every input
/// and every output passes the board. The chip's own state is
/// [`Board::chip`].
#[derive(Debug, Clone)]
pub struct Board {
    chip: Chip,
    faults: WiringFaults,
    /// The chip's record as seen at the connector, kept only when an output
    /// line is miswired (the chip's own record is the board's otherwise).
    seen: Option<Seen>,
}

/// The record at the connector, and how much of the chip's record it has
/// taken in. The chip's record only grows, except that its last pulse run
/// may take more pulses.
#[derive(Debug, Clone, Default)]
struct Seen {
    record: OutputRecord,
    runs: usize,
    pins: usize,
}

impl Seen {
    fn take_in(&mut self, chip: &OutputRecord, f: &WiringFaults) {
        // The last run taken in may have grown since.
        let from = self.runs.saturating_sub(1);
        self.record.runs.truncate(from);
        self.record
            .runs
            .extend(chip.runs[from..].iter().map(|r| f.run(*r)));
        self.runs = chip.runs.len();
        self.record.pins.extend(
            chip.pins[self.pins..]
                .iter()
                .filter_map(|e| f.pin_event(*e)),
        );
        self.pins = chip.pins.len();
        // Move records index the runs, which stay one to one.
        let moves = self.record.moves.len();
        self.record.moves.extend_from_slice(&chip.moves[moves..]);
        self.record.overwritten_bytes = chip.overwritten_bytes;
    }
}

impl Board {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Board, ChipError> {
        let faults = cfg.board;
        let seen = faults.outputs_miswired().then(Seen::default);
        Ok(Board {
            chip: Chip::new(straps, cfg)?,
            faults,
            seen,
        })
    }

    /// Back to the board [`Board::new`] made, keeping the memory of the
    /// chip's record and timers ([`Chip::reset`]).
    pub fn reset(&mut self) {
        self.chip.reset();
        if let Some(seen) = self.seen.as_mut() {
            let mut record = core::mem::take(&mut seen.record);
            record.clear();
            *seen = Seen {
                record,
                ..Seen::default()
            };
        }
    }

    /// The model itself, without the board.
    pub fn chip(&self) -> &Chip {
        &self.chip
    }

    /// The model itself, for a test that drives it past the board: what it
    /// does there reaches [`Board::record`] at the board's next operation.
    pub fn chip_mut(&mut self) -> &mut Chip {
        &mut self.chip
    }

    /// Brings the record at the connector up to the chip's.
    fn take_in(&mut self) {
        if let Some(seen) = self.seen.as_mut() {
            seen.take_in(self.chip.record(), &self.faults);
        }
    }

    /// Host read of the status register, through the board.
    pub fn read_status(&self) -> Status {
        self.faults.status(self.chip.read_status())
    }

    pub fn write_command(&mut self, byte: u8) {
        self.chip.write_command(byte);
        self.take_in();
    }

    pub fn write_data(&mut self, byte: u8) {
        self.chip.write_data(byte);
        self.take_in();
    }

    pub fn read_data(&mut self) -> u8 {
        let byte = self.chip.read_data();
        self.take_in();
        byte
    }

    /// An input driven at the board's connector; the chip sees it unless
    /// its wire is cut.
    pub fn set_input(&mut self, input: Input, asserted: bool) {
        let reaches = asserted && !self.faults.inputs_cut.contains(input);
        self.chip.set_input(input, reaches);
        self.take_in();
    }

    pub fn straps(&self) -> &Straps {
        self.chip.straps()
    }

    pub fn now(&self) -> Instant {
        self.chip.now()
    }

    /// Everything on the output side since reset, as a capture at the
    /// board's connector sees it.
    pub fn record(&self) -> &OutputRecord {
        match &self.seen {
            Some(seen) => &seen.record,
            None => self.chip.record(),
        }
    }

    /// Drops [`Board::record`] before `mark` (a mark of it) as far as the
    /// chip allows ([`Chip::forget_record_before`]); what was dropped of
    /// it.
    pub fn forget_record_before(&mut self, mark: OutputMark) -> OutputMark {
        let Some(seen) = self.seen.as_mut() else {
            return self.chip.forget_record_before(mark);
        };
        // Runs and moves at the connector are the chip's one to one; the
        // chip's pin changes taken in are all behind the connector's.
        let chip = self.chip.forget_record_before(OutputMark {
            runs: mark.runs.min(seen.runs),
            pins: seen.pins,
            moves: mark.moves,
        });
        seen.runs -= chip.runs;
        seen.pins -= chip.pins;
        let dropped = OutputMark {
            pins: mark.pins.min(seen.record.pins.len()),
            ..chip
        };
        seen.record.drop_front(dropped);
        dropped
    }

    /// The output pins at the board's connector.
    pub fn pins(&self) -> Pins {
        self.faults.pins(self.chip.pins())
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

    /// [`Chip::phase_outputs`].
    pub fn phase_outputs(&self) -> crate::protocol::PhaseOutputs {
        self.chip.phase_outputs()
    }

    /// [`Chip::next_pin_change`].
    pub fn next_pin_change(&self) -> Option<Instant> {
        self.chip.next_pin_change()
    }

    pub fn advance_to(&mut self, until: Instant) {
        self.chip.advance_to(until);
        self.take_in();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::StatusField;
    use alloc::vec::Vec;

    #[test]
    fn a_stuck_line_and_crossed_error_lines_change_only_what_the_host_reads() {
        let error2 = Status::new(
            false,
            false,
            false,
            StatusField::Error(ErrorCode::NotInitialized),
        );
        let bus = WiringFaults {
            status_stuck_high: 0x08,
            swap_error: Some((ErrorCode::NotInitialized, ErrorCode::TooManyParameters)),
            ..WiringFaults::default()
        };
        // Diagram 3-1: error flag bit 7, number in bits 6-4; bit 3 stuck.
        assert_eq!(bus.status(error2).0, 0x80 | 3 << 4 | 0x08);
        let idle = Status::new(false, false, false, StatusField::ParamsRemaining(0));
        assert_eq!(bus.status(idle).0, 0x08);
        assert_eq!(WiringFaults::default().status(error2), error2);
    }

    fn miswired() -> WiringFaults {
        WiringFaults {
            dir_inverted: true,
            hold_stuck_off: true,
            auxo_reversed: true,
            ..WiringFaults::default()
        }
    }

    #[test]
    fn miswired_outputs_change_the_pins_and_the_capture_not_the_chip() {
        let f = miswired();
        let chip = Pins {
            int: true,
            hold: true,
            aux: false,
            auxo: 0b0001,
            phases: 0b11000,
            phase_levels: 0b11000,
            dir: Direction::Cw,
            busy: true,
        };
        let seen = f.pins(chip);
        assert_eq!(
            (seen.hold, seen.auxo, seen.dir),
            (false, 0b1000, Direction::Ccw)
        );
        assert_eq!((seen.int, seen.phases, seen.busy), (true, 0b11000, true));
        let at = Instant::ZERO;
        let ev = |pin, value| PinEvent { at, pin, value };
        assert_eq!(f.pin_event(ev(Pin::Hold, 1)), None);
        assert_eq!(f.pin_event(ev(Pin::Dir, 1)), Some(ev(Pin::Dir, 0)));
        assert_eq!(
            f.pin_event(ev(Pin::Auxo, 0b0011)),
            Some(ev(Pin::Auxo, 0b1100))
        );
        assert_eq!(f.pin_event(ev(Pin::Int, 1)), Some(ev(Pin::Int, 1)));
    }

    #[test]
    fn the_record_at_the_connector_follows_a_growing_last_run() {
        let f = miswired();
        let mut chip = OutputRecord::default();
        let mut seen = Seen::default();
        let us = crate::time::Duration::from_micros;
        chip.push_pulses(Instant::ZERO + us(10), us(5), 3, Direction::Cw, true);
        chip.pin(Instant::ZERO + us(1), Pin::Hold, 0);
        seen.take_in(&chip, &f);
        // The chip's run takes two more pulses, then a new run starts.
        chip.push_pulses(Instant::ZERO + us(25), us(5), 2, Direction::Cw, false);
        chip.pin(Instant::ZERO + us(40), Pin::Dir, 1);
        chip.push_pulses(Instant::ZERO + us(50), us(7), 4, Direction::Ccw, true);
        chip.overwritten_bytes = 2;
        seen.take_in(&chip, &f);
        let expect: Vec<_> = chip.runs.iter().map(|r| f.run(*r)).collect();
        assert_eq!(seen.record.runs, expect);
        assert_eq!(seen.record.runs[0].count, 5);
        assert_eq!(seen.record.runs[0].dir, Direction::Ccw);
        assert_eq!(seen.record.pins.len(), 1, "the HOLD change is not seen");
        assert_eq!(seen.record.pins[0].value, 0, "DIR inverted");
        assert_eq!(seen.record.overwritten_bytes, 2);
        // Nothing new: taking in again changes nothing.
        let before = seen.record.clone();
        seen.take_in(&chip, &f);
        assert_eq!(seen.record, before);
    }

    #[test]
    fn a_cut_input_never_reaches_the_chip() {
        let mut inputs_cut = InputSet::default();
        inputs_cut.set(Input::Alm, true);
        let cfg = ModelConfig {
            board: WiringFaults {
                inputs_cut,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        };
        let mut board = Board::new(Straps::default(), cfg).expect("default straps are valid");
        board.set_input(Input::Alm, true);
        board.set_input(Input::L1, true);
        // Section 3-3-2: ALM stops a move; this chip never sees it.
        assert!(!board.chip().inputs().contains(Input::Alm));
        assert!(board.chip().inputs().contains(Input::L1));
    }
}

#[cfg(test)]
mod chop_tests {
    use super::*;
    use crate::time::Duration;

    /// Section 3-5-1: with stop switching, the phases go on and off by
    /// themselves; `next_pin_change` says when, so that a harness that
    /// follows the pins in time (the board twin) sees every edge.
    #[test]
    fn next_pin_change_names_every_chop_edge() {
        let mut b = Board::new(Straps::default(), ModelConfig::default()).expect("model");
        // 4-phase, stop switching (bit 5), RL 100, RH 20, PA 4.
        b.write_command(0x22);
        for byte in [100, 20, 4, 0] {
            b.advance_to(b.chip().now() + Duration::from_micros(10));
            b.write_data(byte);
        }
        b.advance_to(b.chip().now() + Duration::from_millis(40));
        assert!(b.next_pin_change().is_some(), "chopping");
        let mut edges = 0;
        let mut last = b.pins().phases;
        for _ in 0..6 {
            let t = b.next_pin_change().expect("still chopping");
            // Just before: unchanged; at it: changed.
            b.advance_to(t - Duration::from_nanos(1));
            assert_eq!(b.pins().phases, last, "no edge before {t}");
            b.advance_to(t);
            let now = b.pins().phases;
            assert_ne!(now, last, "an edge at {t}");
            last = now;
            edges += 1;
        }
        assert_eq!(edges, 6);
    }
}
