//! The invariant oracle: runs bus ops on a fresh emulator and checks,
//! after every op, the invariants of `docs/invariants.md` ([`Checker`],
//! [`check`]), with the rules of [`super::rules`]. Each invariant has a
//! stable id; a finding is bucketed by it.

use super::rules::{Rules, Seen, Violation};
use crate::bus_program::{self, BusOp};
use crate::emu::{Board, ChipError, ModelConfig};
use crate::protocol::{Status, Straps};
use std::cell::Cell;

/// Runs `ops` on a fresh chip and returns the first invariant break.
pub fn check(ops: &[BusOp], cfg: ModelConfig) -> Result<Option<Violation>, ChipError> {
    check_ops(ops.iter().copied(), cfg)
}

/// [`check`] on ops as they come (a fuzz input's, as they are decoded).
pub fn check_ops(
    ops: impl IntoIterator<Item = BusOp>,
    cfg: ModelConfig,
) -> Result<Option<Violation>, ChipError> {
    // A fuzz target checks an input after another on one thread: the
    // checker of the last one, reset, keeps the memory it grew (and stays
    // off the stack, where AddressSanitizer's fake stack makes a large
    // frame costly).
    thread_local! {
        static SPARE: Cell<Option<Box<Checker>>> = const { Cell::new(None) };
    }
    let mut c = match SPARE.take() {
        Some(mut c) if *c.board.chip().config() == cfg => {
            c.reset();
            c
        }
        _ => Box::new(Checker::new(cfg)?),
    };
    let verdict = c.run(ops);
    SPARE.set(Some(c));
    Ok(verdict)
}

/// [`check_ops`] on the default model ([`ModelConfig::default`]), as the
/// `bus_bytes` fuzz target runs every input. Its checker is made once per
/// thread and only reset between inputs: no configuration is built,
/// compared or validated per input, work (and coverage counters, each a
/// feature libFuzzer collects after every run) that told nothing about
/// the input.
pub fn check_ops_default(
    ops: impl IntoIterator<Item = BusOp>,
) -> Result<Option<Violation>, ChipError> {
    thread_local! {
        static DEFAULT: Cell<Option<Box<Checker>>> = const { Cell::new(None) };
    }
    let mut c = match DEFAULT.take() {
        Some(mut c) => {
            c.reset();
            c
        }
        None => Box::new(Checker::new(ModelConfig::default())?),
    };
    let verdict = c.run(ops);
    DEFAULT.set(Some(c));
    Ok(verdict)
}

/// The oracle on the emulator: a fresh chip, fed one op at a time, each
/// judged as it goes; [`Checker::finish`] judges the whole record.
#[derive(Debug)]
pub struct Checker {
    /// The model on its board: the oracle reads status as a host does.
    board: Board,
    judge: Rules,
    /// The status register after the last op (none before the first).
    status: Option<Status>,
}

impl Checker {
    pub fn new(cfg: ModelConfig) -> Result<Checker, ChipError> {
        Ok(Checker {
            board: Board::new(Straps::default(), cfg)?,
            judge: Rules::new(Straps::default()),
            status: None,
        })
    }

    /// The chip under test, on its board.
    pub fn board(&self) -> &Board {
        &self.board
    }

    /// Ops applied so far.
    pub fn ops(&self) -> usize {
        self.judge.ops
    }

    /// Back to a fresh chip and judge, keeping the memory they grew.
    pub fn reset(&mut self) {
        self.board.reset();
        self.judge.reset();
        self.status = None;
    }

    /// Applies every op, judging each, then the whole record: the first
    /// invariant broken.
    pub fn run(&mut self, ops: impl IntoIterator<Item = BusOp>) -> Option<Violation> {
        for op in ops {
            if let Err(v) = self.apply(op) {
                return Some(v);
            }
        }
        self.finish().err()
    }

    /// Applies one op and judges it.
    pub fn apply(&mut self, op: BusOp) -> Result<(), Violation> {
        let chip = &mut self.board;
        // Nothing happens between two ops, and reading the status register
        // has no side effect (Section 3-1-1): the status after one op is
        // the status before the next.
        let before = self.status.unwrap_or_else(|| chip.read_status());
        let value = bus_program::apply(chip, op);
        // A status read's own value is the status after it.
        let after = match (op, value) {
            (BusOp::ReadStatus, Some(v)) => Status(v),
            _ => chip.read_status(),
        };
        self.status = Some(after);
        let seen = Seen {
            before,
            after,
            value,
            at: chip.now(),
        };
        self.judge.op(op, seen, chip.record())
    }

    /// The record's own invariants, checked once at the end.
    pub fn finish(&self) -> Result<(), Violation> {
        self.judge.finish(self.board.record())
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::bus_program::BusOp::*;
    use crate::emu::{Chip, WiringFaults};
    use crate::invariants::ids::Invariant;
    use crate::time::Duration;

    /// Initialization (Section 3-2, the values of `capture_comes_in_chunks`)
    /// then a single step, with status reads between.
    fn init_and_step() -> Vec<BusOp> {
        let gap = Advance(Duration::from_millis(1));
        vec![
            Command(0x06),
            gap,
            Data(100),
            gap,
            Data(20),
            gap,
            Data(100),
            gap,
            Data(0),
            Advance(Duration::from_millis(200)),
            ReadStatus,
            Command(0x4A),
            Advance(Duration::from_millis(5)),
            ReadStatus,
            Advance(Duration::from_millis(5)),
            ReadStatus,
        ]
    }

    /// The sequence is a real one: the chip accepts it without error and
    /// the step comes out.
    #[test]
    fn the_sample_sequence_initializes_and_steps() {
        let mut chip = Chip::new(Straps::default(), ModelConfig::default()).expect("chip");
        for op in init_and_step() {
            match op {
                Command(b) => chip.write_command(b),
                Data(b) => chip.write_data(b),
                ReadStatus => assert_eq!(chip.read_status().0 & 0x80, 0, "no error"),
                Advance(d) => chip.advance_to(chip.now() + d),
                _ => {}
            }
        }
        assert_eq!(chip.record().pulse_count(), 1);
    }

    #[test]
    fn the_clean_model_keeps_every_invariant() {
        let r = check(&init_and_step(), ModelConfig::default()).expect("chip");
        assert_eq!(r, None);
    }

    /// Section 3-1-1: a data line stuck high on bit 3 is an invariant break.
    #[test]
    fn a_stuck_status_bit_is_caught() {
        let cfg = ModelConfig {
            board: WiringFaults {
                status_stuck_high: 0x08,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!((v.invariant, v.op), (Invariant::StatusBit3, 10));
    }

    #[test]
    fn parameter_counts_beyond_four_are_caught() {
        let cfg = ModelConfig {
            board: WiringFaults {
                status_stuck_high: 0x50,
                ..WiringFaults::default()
            },
            ..ModelConfig::default()
        };
        let v = check(&init_and_step(), cfg)
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, Invariant::StatusParams);
    }

    /// `init_and_step` with the step's termination interrupt masked
    /// (0x5A: bit 4 = 1, Section 3-3-8).
    fn init_and_masked_step() -> Vec<BusOp> {
        init_and_step()
            .into_iter()
            .map(|op| {
                if op == Command(0x4A) {
                    Command(0x5A)
                } else {
                    op
                }
            })
            .collect()
    }

    /// Section 3-3 (bit 4 of an operation command): a board that asserts
    /// INT* at the end of a masked move breaks `int-mask`; the clean model
    /// keeps it, masked or not.
    #[test]
    fn int_asserted_despite_the_mask_is_caught() {
        assert_eq!(
            check(&init_and_masked_step(), ModelConfig::default()).expect("chip"),
            None
        );
        let v = check(&init_and_masked_step(), faulty("int-ignores-mask"))
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, Invariant::IntMask, "{v}");
        assert!(v.detail.contains("masks the termination interrupt"), "{v}");
        // Unmasked, the same board asserts INT* rightly.
        assert_eq!(
            check(&init_and_step(), faulty("int-ignores-mask")).expect("chip"),
            None
        );
    }

    /// `init_and_step`, then a second single step.
    fn init_and_two_steps() -> Vec<BusOp> {
        let mut ops = init_and_step();
        ops.extend([Command(0x4A), Advance(Duration::from_millis(5)), ReadStatus]);
        ops
    }

    /// Section 3-2-1: each pulse steps the phases once, so the second step
    /// (0x4A: CCW, 1-2 phase on a 4-phase motor, 8 steps a cycle) starts
    /// where the first left them, one step back from 0. A board whose phases miss the
    /// first step of every move breaks `phase-pattern` at the second.
    #[test]
    fn a_skipped_phase_step_is_caught_at_the_next_move() {
        assert_eq!(
            check(&init_and_two_steps(), ModelConfig::default()).expect("chip"),
            None
        );
        let v = check(&init_and_two_steps(), faulty("phase-step-skipped"))
            .expect("chip")
            .expect("a break");
        assert_eq!(v.invariant, Invariant::PhasePattern, "{v}");
        assert!(
            v.detail.contains("starts at step 0 of 4ph-12")
                && v.detail.contains("left the phases at step 7"),
            "{v}"
        );
        // One move alone shows nothing: the skip shows where the next
        // move starts.
        assert_eq!(
            check(&init_and_step(), faulty("phase-step-skipped")).expect("chip"),
            None
        );
    }

    /// `init_and_step`, then a register read: command, wait, its bytes.
    pub(in crate::invariants) fn then_read(register: u8, bytes: usize) -> Vec<BusOp> {
        let mut ops = init_and_step();
        ops.push(Command(register));
        for _ in 0..bytes {
            ops.push(Advance(Duration::from_micros(50)));
            ops.push(ReadData);
        }
        ops
    }

    fn faulty(name: &str) -> ModelConfig {
        crate::faults::find(name).expect("in the catalogue").model()
    }

    /// Section 3-4-4: a constant-speed move of 101 steps (count 100)
    /// stopped by L1;
    /// the remaining pulses read one less than the remainder. A board
    /// reading the remainder itself breaks the invariant.
    #[test]
    fn remaining_pulses_off_by_one_is_caught_at_the_third_byte() {
        use crate::protocol::{Command as C, Direction, Input as In, MoveCommand, MoveKind};
        let mut ops = init_and_step();
        let constant = C::Move(MoveCommand::new(MoveKind::Constant, Direction::Cw, false));
        ops.push(Command(constant.encode()));
        for b in [60, 100, 0, 0] {
            ops.extend([Advance(Duration::from_micros(50)), Data(b)]);
        }
        ops.push(Advance(Duration::from_millis(3)));
        ops.push(Input {
            input: In::L1,
            asserted: true,
        });
        ops.push(Advance(Duration::from_millis(5)));
        ops.push(Command(0x83));
        for _ in 0..3 {
            ops.extend([Advance(Duration::from_micros(50)), ReadData]);
        }
        assert_eq!(check(&ops, ModelConfig::default()).expect("chip"), None);
        let v = check(&ops, faulty("remaining-off-by-one"))
            .expect("chip")
            .expect("a break");
        assert_eq!(
            (v.invariant, v.op),
            (Invariant::RemainingPulses, ops.len() - 1)
        );
        assert!(v.detail.contains("after a move of 101 steps"), "{v}");
    }

    /// Section 3-4-1: the polling flag is set once per stop; a second read
    /// with no move in between must show it cleared.
    #[test]
    fn a_sticky_polling_flag_is_caught_on_the_second_read() {
        let mut ops = then_read(0x80, 1);
        ops.push(Command(0x80));
        ops.push(Advance(Duration::from_micros(50)));
        ops.push(ReadData);
        assert_eq!(check(&ops, ModelConfig::default()).expect("chip"), None);
        let v = check(&ops, faulty("finish-flag-sticky"))
            .expect("chip")
            .expect("a break");
        assert_eq!(
            (v.invariant, v.op),
            (Invariant::FinishFlagOnce, ops.len() - 1)
        );
    }

    /// A read command lost to a later write (IBF = 1) says nothing about
    /// the bytes that follow: stale output is not taken for its answer.
    #[test]
    fn bytes_of_a_lost_read_command_are_not_judged() {
        let mut ops = then_read(0x83, 1);
        // A remaining-pulses read, overwritten at once by a data byte: the
        // chip never takes it, and the stale bytes are not its answer.
        ops.extend([Command(0x83), Data(0), Advance(Duration::from_micros(50))]);
        ops.extend([ReadData, ReadData, ReadData]);
        let cfg = faulty("remaining-off-by-one");
        let v = check(&ops, cfg).expect("chip");
        assert_eq!(v, None);
    }
}
