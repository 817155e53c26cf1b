//! Command codes of datasheet chapter 3, as typed values.
//!
//! [`Command::decode`] is total: every byte decodes to some [`Command`], with
//! [`Command::Undefined`] keeping the raw byte of a code the chip rejects with
//! error 0. [`Command::encode`] gives back exactly the byte that was decoded,
//! including "don't care" bits, so a byte stream survives a round trip.
//!
//! Bit positions are interpreted from the flattened diagrams; see
//! `docs/datasheet-notes.md` (N1 to N4) for the reasoning.

use core::fmt;

/// Direction of motor rotation: operation command bit 3 (Diagram 3-6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    Cw,
    Ccw,
}

impl Direction {
    pub fn from_bit(bit: bool) -> Self {
        if bit {
            Direction::Ccw
        } else {
            Direction::Cw
        }
    }

    pub fn bit(self) -> bool {
        self == Direction::Ccw
    }

    pub fn name(self) -> &'static str {
        match self {
            Direction::Cw => "cw",
            Direction::Ccw => "ccw",
        }
    }
}

/// The flag bits 3 to 5 shared by every operation-type command (Diagram 3-6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OpFlags {
    /// Bit 3: 0 = CW, 1 = CCW.
    pub direction: Direction,
    /// Bit 4, inverted: `true` when the termination interrupt is output
    /// (bit 4 = 0), `false` when it is masked (bit 4 = 1).
    pub interrupt: bool,
    /// Bit 5: shown as `x` (don't care) in Diagram 3-6; kept so the byte
    /// round-trips.
    pub spare: bool,
}

impl OpFlags {
    /// CW, interrupt on, spare bit clear: what the datasheet asks for on the
    /// stop and auxiliary commands.
    pub const PLAIN: OpFlags = OpFlags {
        direction: Direction::Cw,
        interrupt: true,
        spare: false,
    };

    pub fn new(direction: Direction, interrupt: bool) -> Self {
        OpFlags {
            direction,
            interrupt,
            spare: false,
        }
    }

    fn from_byte(b: u8) -> Self {
        OpFlags {
            direction: Direction::from_bit(b & 0x08 != 0),
            interrupt: b & 0x10 == 0,
            spare: b & 0x20 != 0,
        }
    }

    fn bits(self) -> u8 {
        (u8::from(self.direction.bit()) << 3)
            | (u8::from(!self.interrupt) << 4)
            | (u8::from(self.spare) << 5)
    }
}

/// Motor type code, initialization command bits 1-0 (Section 3-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotorType {
    ThreePhase,
    FourPhase,
    FivePhase,
}

impl MotorType {
    /// Number of phase outputs S1.. the motor uses.
    pub fn phases(self) -> u8 {
        match self {
            MotorType::ThreePhase => 3,
            MotorType::FourPhase => 4,
            MotorType::FivePhase => 5,
        }
    }

    fn code(self) -> u8 {
        match self {
            MotorType::ThreePhase => 0b01,
            MotorType::FourPhase => 0b10,
            MotorType::FivePhase => 0b11,
        }
    }
}

/// Excitation method, initialization command bit 2 (Section 3-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Excitation {
    /// 2-phase excitation.
    TwoPhase,
    /// 1-2 phase excitation; 2-3 phase excitation on a 5-phase motor.
    HalfStep,
}

/// Level of the excitation outputs S1..S5, initialization command bit 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OutputLogic {
    /// An energized phase is driven low.
    Negative,
    /// An energized phase is driven high.
    Positive,
}

impl OutputLogic {
    /// The levels of S1..S5 (S1 in bit 4) that drive the `energized`
    /// phases (Section 3-2-1, Diagram 3-4).
    pub fn levels(self, energized: u8) -> u8 {
        match self {
            OutputLogic::Positive => energized & 0x1F,
            OutputLogic::Negative => !energized & 0x1F,
        }
    }
}

/// Base clock source, initialization command bit 4 (Section 3-2-1 (1)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClockSource {
    /// 1/32 (CSEL high) or 1/128 (CSEL low) of the system clock.
    Internal,
    /// The CLOCK pin (pin 54).
    External,
}

/// The initialization command code (Section 3-2, byte 1 of Diagram 3-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct InitCommand {
    pub motor: MotorType,
    pub excitation: Excitation,
    pub logic: OutputLogic,
    pub clock: ClockSource,
    /// Bit 5: chop the excitation outputs while the motor is stopped.
    pub stop_switching: bool,
}

impl InitCommand {
    fn decode(b: u8) -> Option<Self> {
        let motor = match b & 0b11 {
            0b01 => MotorType::ThreePhase,
            0b10 => MotorType::FourPhase,
            0b11 => MotorType::FivePhase,
            _ => return None,
        };
        Some(InitCommand {
            motor,
            excitation: if b & 0x04 != 0 {
                Excitation::HalfStep
            } else {
                Excitation::TwoPhase
            },
            logic: if b & 0x08 != 0 {
                OutputLogic::Positive
            } else {
                OutputLogic::Negative
            },
            clock: if b & 0x10 != 0 {
                ClockSource::External
            } else {
                ClockSource::Internal
            },
            stop_switching: b & 0x20 != 0,
        })
    }

    fn encode(self) -> u8 {
        self.motor.code()
            | (u8::from(self.excitation == Excitation::HalfStep) << 2)
            | (u8::from(self.logic == OutputLogic::Positive) << 3)
            | (u8::from(self.clock == ClockSource::External) << 4)
            | (u8::from(self.stop_switching) << 5)
    }
}

/// The motor-moving operations (Sections 3-3-3 to 3-3-8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MoveKind {
    /// Code 010, Section 3-3-3.
    SingleStep,
    /// Code 011, Section 3-3-4.
    AccelDecel,
    /// Code 100, Section 3-3-5.
    Constant,
    /// Code 101, Section 3-3-6.
    ContinuousConstant,
    /// Code 110, Section 3-3-7.
    ContinuousHigh,
    /// Code 111, Section 3-3-8.
    OriginSearch,
}

impl MoveKind {
    pub const ALL: [MoveKind; 6] = [
        MoveKind::SingleStep,
        MoveKind::AccelDecel,
        MoveKind::Constant,
        MoveKind::ContinuousConstant,
        MoveKind::ContinuousHigh,
        MoveKind::OriginSearch,
    ];

    /// The 3-bit operation code, as also reported in finish status bits 2-0.
    pub fn code(self) -> u8 {
        match self {
            MoveKind::SingleStep => 0b010,
            MoveKind::AccelDecel => 0b011,
            MoveKind::Constant => 0b100,
            MoveKind::ContinuousConstant => 0b101,
            MoveKind::ContinuousHigh => 0b110,
            MoveKind::OriginSearch => 0b111,
        }
    }

    /// Number of data bytes that follow the command code.
    pub fn param_count(self) -> u8 {
        match self {
            MoveKind::SingleStep | MoveKind::ContinuousHigh => 0,
            MoveKind::AccelDecel => 3,
            MoveKind::Constant => 4,
            MoveKind::ContinuousConstant | MoveKind::OriginSearch => 1,
        }
    }

    /// Whether the move follows the acceleration/deceleration ramp set at
    /// initialization (as opposed to one constant pulse rate).
    pub fn ramped(self) -> bool {
        matches!(self, MoveKind::AccelDecel | MoveKind::ContinuousHigh)
    }

    /// Whether POUT mode exists for this move (expansion codes 011 and 110).
    pub fn has_pout_mode(self) -> bool {
        self.ramped()
    }

    pub fn name(self) -> &'static str {
        match self {
            MoveKind::SingleStep => "single-step",
            MoveKind::AccelDecel => "accel-decel",
            MoveKind::Constant => "constant",
            MoveKind::ContinuousConstant => "continuous-constant",
            MoveKind::ContinuousHigh => "continuous-high",
            MoveKind::OriginSearch => "origin-search",
        }
    }
}

/// An operation command that moves the motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MoveCommand {
    pub kind: MoveKind,
    pub flags: OpFlags,
    /// POUT mode (bit 7): only POUT is output, the phase outputs hold.
    pub pout: bool,
}

impl MoveCommand {
    pub fn new(kind: MoveKind, direction: Direction, interrupt: bool) -> Self {
        MoveCommand {
            kind,
            flags: OpFlags::new(direction, interrupt),
            pout: false,
        }
    }

    /// The POUT-mode variant. Only [`MoveKind::AccelDecel`] and
    /// [`MoveKind::ContinuousHigh`] have one; for other kinds the encoded
    /// byte is an undefined expansion code.
    pub fn pout(kind: MoveKind, direction: Direction, interrupt: bool) -> Self {
        MoveCommand {
            pout: true,
            ..MoveCommand::new(kind, direction, interrupt)
        }
    }
}

/// The five internal register reads (Section 3-4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Register {
    /// 0x80, Section 3-4-1: one byte.
    FinishStatus,
    /// 0x81, Section 3-4-2: one byte.
    InputSignals,
    /// 0x82, Section 3-4-3: one byte.
    OutputSignals,
    /// 0x83, Section 3-4-4: three bytes, lower first.
    RemainingPulses,
    /// 0x85, Section 3-4-5: one byte.
    AuxInputs,
}

impl Register {
    pub const ALL: [Register; 5] = [
        Register::FinishStatus,
        Register::InputSignals,
        Register::OutputSignals,
        Register::RemainingPulses,
        Register::AuxInputs,
    ];

    pub fn code(self) -> u8 {
        match self {
            Register::FinishStatus => 0x80,
            Register::InputSignals => 0x81,
            Register::OutputSignals => 0x82,
            Register::RemainingPulses => 0x83,
            Register::AuxInputs => 0x85,
        }
    }

    /// How many bytes the host reads after the command code.
    pub fn byte_count(self) -> usize {
        match self {
            Register::RemainingPulses => 3,
            _ => 1,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Register::FinishStatus => "finish-status",
            Register::InputSignals => "input-signals",
            Register::OutputSignals => "output-signals",
            Register::RemainingPulses => "remaining-pulses",
            Register::AuxInputs => "aux-inputs",
        }
    }
}

/// A byte written to the command register, decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// Section 3-2: followed by 4 data bytes (RL, RH, PA low, PA high).
    Init(InitCommand),
    /// Sections 3-3-3 to 3-3-8.
    Move(MoveCommand),
    /// 0x40, Section 3-3-1.
    ImmediateStop(OpFlags),
    /// 0x41, Section 3-3-2.
    DecelStop(OpFlags),
    /// 0xC0, Section 3-5-4 (expansion code 000, "Excitation OFF").
    SoftwareReset(OpFlags),
    /// 0xC1, Section 3-5-2.
    AuxOn(OpFlags),
    /// 0xC2, Section 3-5-2.
    AuxOff(OpFlags),
    /// 0x80-0x83, 0x85, Section 3-4.
    Read(Register),
    /// 0x84, Section 3-5-1: followed by Pon and Poff.
    SwitchingParams,
    /// 0x86, Section 3-5-3: followed by one data byte.
    AuxOutput,
    /// Any other byte: the chip answers with error 0 (Table 3-2).
    Undefined(u8),
}

impl Command {
    /// Decodes a command-register byte. Never fails: unknown codes become
    /// [`Command::Undefined`].
    pub fn decode(b: u8) -> Command {
        match b >> 6 {
            0b00 => InitCommand::decode(b).map_or(Command::Undefined(b), Command::Init),
            0b01 => {
                let flags = OpFlags::from_byte(b);
                match b & 0b111 {
                    0b000 => Command::ImmediateStop(flags),
                    0b001 => Command::DecelStop(flags),
                    code => Command::Move(MoveCommand {
                        kind: kind_from_code(code),
                        flags,
                        pout: false,
                    }),
                }
            }
            0b10 => match b {
                0x80 => Command::Read(Register::FinishStatus),
                0x81 => Command::Read(Register::InputSignals),
                0x82 => Command::Read(Register::OutputSignals),
                0x83 => Command::Read(Register::RemainingPulses),
                0x84 => Command::SwitchingParams,
                0x85 => Command::Read(Register::AuxInputs),
                0x86 => Command::AuxOutput,
                _ => Command::Undefined(b),
            },
            _ => {
                let flags = OpFlags::from_byte(b);
                match b & 0b111 {
                    0b000 => Command::SoftwareReset(flags),
                    0b001 => Command::AuxOn(flags),
                    0b010 => Command::AuxOff(flags),
                    0b011 => Command::Move(MoveCommand {
                        kind: MoveKind::AccelDecel,
                        flags,
                        pout: true,
                    }),
                    0b110 => Command::Move(MoveCommand {
                        kind: MoveKind::ContinuousHigh,
                        flags,
                        pout: true,
                    }),
                    _ => Command::Undefined(b),
                }
            }
        }
    }

    /// The byte that encodes this command.
    pub fn encode(self) -> u8 {
        match self {
            Command::Init(c) => c.encode(),
            Command::Move(m) => (u8::from(m.pout) << 7) | 0x40 | m.flags.bits() | m.kind.code(),
            Command::ImmediateStop(f) => 0x40 | f.bits(),
            Command::DecelStop(f) => 0x41 | f.bits(),
            Command::SoftwareReset(f) => 0xC0 | f.bits(),
            Command::AuxOn(f) => 0xC1 | f.bits(),
            Command::AuxOff(f) => 0xC2 | f.bits(),
            Command::Read(r) => r.code(),
            Command::SwitchingParams => 0x84,
            Command::AuxOutput => 0x86,
            Command::Undefined(b) => b,
        }
    }

    /// Number of data bytes the chip expects after this command code.
    pub fn param_count(self) -> u8 {
        match self {
            Command::Init(_) => 4,
            Command::Move(m) => m.kind.param_count(),
            Command::SwitchingParams => 2,
            Command::AuxOutput => 1,
            _ => 0,
        }
    }

    /// Whether the byte is an operation command code in the sense of
    /// Diagram 3-6 (moves and both stops).
    pub fn is_operation(self) -> bool {
        matches!(
            self,
            Command::Move(_) | Command::ImmediateStop(_) | Command::DecelStop(_)
        )
    }
}

fn kind_from_code(code: u8) -> MoveKind {
    match code & 0b111 {
        0b010 => MoveKind::SingleStep,
        0b011 => MoveKind::AccelDecel,
        0b100 => MoveKind::Constant,
        0b101 => MoveKind::ContinuousConstant,
        0b110 => MoveKind::ContinuousHigh,
        // 0b111; 000 and 001 are the stops and never reach here.
        _ => MoveKind::OriginSearch,
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Command::Init(c) => write!(
                f,
                "init {:?} {:?} {:?} {:?}{}",
                c.motor,
                c.excitation,
                c.logic,
                c.clock,
                if c.stop_switching { " switching" } else { "" }
            ),
            Command::Move(m) => write!(
                f,
                "{}{} {}{}",
                if m.pout { "pout-" } else { "" },
                m.kind.name(),
                m.flags.direction.name(),
                if m.flags.interrupt { "" } else { " no-int" }
            ),
            Command::ImmediateStop(_) => f.write_str("immediate-stop"),
            Command::DecelStop(_) => f.write_str("decel-stop"),
            Command::SoftwareReset(_) => f.write_str("software-reset"),
            Command::AuxOn(_) => f.write_str("aux-on"),
            Command::AuxOff(_) => f.write_str("aux-off"),
            Command::Read(r) => write!(f, "read {}", r.name()),
            Command::SwitchingParams => f.write_str("switching-params"),
            Command::AuxOutput => f.write_str("aux-output"),
            Command::Undefined(b) => write!(f, "undefined 0x{b:02X}"),
        }
    }
}

/// Number of operation pulses of Diagram 3-14: the number of steps to move,
/// 1 ..= 16,777,216, written to the chip as `steps - 1`, lower byte first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PulseCount(u32);

impl PulseCount {
    /// 16,777,216 steps: FFFFFF, the count the continuous modes use.
    pub const MAX: PulseCount = PulseCount(1 << 24);

    /// `None` when `steps` is 0 or above 16,777,216.
    pub fn new(steps: u32) -> Option<Self> {
        (1..=1 << 24).contains(&steps).then_some(PulseCount(steps))
    }

    /// From the three data bytes as written (lower byte first).
    pub fn from_bytes(b: [u8; 3]) -> Self {
        PulseCount(u32::from_le_bytes([b[0], b[1], b[2], 0]) + 1)
    }

    pub fn steps(self) -> u32 {
        self.0
    }

    /// The three data bytes to write: `steps - 1`, lower byte first.
    pub fn to_bytes(self) -> [u8; 3] {
        let [lo, mid, hi, _] = (self.0 - 1).to_le_bytes();
        [lo, mid, hi]
    }
}

/// The four initialization data bytes of Diagram 3-2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct InitData {
    /// Start-up pulse rate RL.
    pub rl: u8,
    /// High speed pulse rate RH.
    pub rh: u8,
    /// Number of acceleration/deceleration pulses PA.
    pub pa: u16,
}

impl InitData {
    pub fn from_bytes(b: [u8; 4]) -> Self {
        InitData {
            rl: b[0],
            rh: b[1],
            pa: u16::from_le_bytes([b[2], b[3]]),
        }
    }

    pub fn to_bytes(self) -> [u8; 4] {
        let [lo, hi] = self.pa.to_le_bytes();
        [self.rl, self.rh, lo, hi]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rstest::rstest;

    proptest! {
        /// Every byte decodes to something that encodes back to itself.
        #[test]
        fn every_byte_round_trips(b in any::<u8>()) {
            prop_assert_eq!(Command::decode(b).encode(), b);
        }

        #[test]
        fn pulse_count_round_trips(steps in 1u32..=1 << 24) {
            let c = PulseCount::new(steps).expect("in range");
            prop_assert_eq!(PulseCount::from_bytes(c.to_bytes()), c);
        }

        #[test]
        fn init_data_round_trips(b in any::<[u8; 4]>()) {
            prop_assert_eq!(InitData::from_bytes(b).to_bytes(), b);
        }
    }

    // Literal bytes taken from the datasheet diagrams, to check the typed
    // definitions above against an independent source.
    #[rstest]
    #[case::s3_3_1_immediate_stop_diagram_3_7(0x40, Command::ImmediateStop(OpFlags::PLAIN))]
    #[case::s3_3_2_decel_stop_diagram_3_9(0x41, Command::DecelStop(OpFlags::PLAIN))]
    #[case::s3_4_1_finish_status_read(0x80, Command::Read(Register::FinishStatus))]
    #[case::s3_4_2_input_status_read(0x81, Command::Read(Register::InputSignals))]
    #[case::s3_4_3_output_status_read(0x82, Command::Read(Register::OutputSignals))]
    #[case::s3_4_4_remaining_read(0x83, Command::Read(Register::RemainingPulses))]
    #[case::s3_5_1_switching(0x84, Command::SwitchingParams)]
    #[case::s3_4_5_aux_input_read(0x85, Command::Read(Register::AuxInputs))]
    #[case::s3_5_3_aux_output(0x86, Command::AuxOutput)]
    #[case::s3_5_4_software_reset(0xC0, Command::SoftwareReset(OpFlags::PLAIN))]
    #[case::s3_5_2_aux_on(0xC1, Command::AuxOn(OpFlags::PLAIN))]
    #[case::s3_5_2_aux_off(0xC2, Command::AuxOff(OpFlags::PLAIN))]
    #[case::s3_3_4_accel_cw(
        0x43,
        Command::Move(MoveCommand::new(MoveKind::AccelDecel, Direction::Cw, true))
    )]
    #[case::s3_3_4_pout_accel(
        0xC3,
        Command::Move(MoveCommand::pout(MoveKind::AccelDecel, Direction::Cw, true))
    )]
    #[case::s3_3_7_pout_high(
        0xDE,
        Command::Move(MoveCommand::pout(MoveKind::ContinuousHigh, Direction::Ccw, false))
    )]
    #[case::s3_3_3_single_step_ccw(
        0x4A,
        Command::Move(MoveCommand::new(MoveKind::SingleStep, Direction::Ccw, true))
    )]
    fn decodes_datasheet_bytes(#[case] byte: u8, #[case] cmd: Command) {
        assert_eq!(Command::decode(byte), cmd);
        assert_eq!(cmd.encode(), byte);
    }

    #[rstest]
    #[case::s3_2_motor_type_00(0x00)]
    #[case::s3_2_motor_type_00_with_bits(0x3C)]
    #[case::s3_4_unused_read_code(0x87)]
    #[case::s3_4_high_read_range(0xBF)]
    #[case::s3_3_expansion_100(0xC4)]
    #[case::s3_3_expansion_101(0xC5)]
    #[case::s3_3_expansion_111(0xC7)]
    fn undefined_codes_keep_their_byte(#[case] byte: u8) {
        assert_eq!(Command::decode(byte), Command::Undefined(byte));
    }

    #[test]
    fn s3_2_init_0x02_is_four_phase_two_phase_negative_internal() {
        let Command::Init(c) = Command::decode(0x02) else {
            panic!("0x02 is an initialization command");
        };
        assert_eq!(c.motor, MotorType::FourPhase);
        assert_eq!(c.excitation, Excitation::TwoPhase);
        assert_eq!(c.logic, OutputLogic::Negative);
        assert_eq!(c.clock, ClockSource::Internal);
        assert!(!c.stop_switching);
    }

    #[test]
    fn s3_3_4_thousand_steps_is_0003e7_lower_byte_first() {
        let c = PulseCount::new(1000).expect("in range");
        assert_eq!(c.to_bytes(), [0xE7, 0x03, 0x00]);
        assert_eq!(
            PulseCount::from_bytes([0xFF, 0xFF, 0xFF]).steps(),
            16_777_216
        );
        assert_eq!(PulseCount::new(0), None);
        assert_eq!(PulseCount::new((1 << 24) + 1), None);
    }
}
