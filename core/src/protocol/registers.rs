//! The status register and the bytes read back by the register read commands.
//!
//! Each type is a transparent view of the raw byte: any `u8` is a valid value
//! and the accessors never panic. Field positions cite the datasheet diagram
//! they come from; `docs/datasheet-notes.md` N1 explains how the bit order was
//! recovered from the flattened diagrams.

use super::command::{Direction, MoveKind};
use core::fmt;

/// Error numbers of Table 3-2, reported in status bits 6-4 with bit 7 set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ErrorCode {
    /// 0: undefined command code was received.
    UndefinedCommand = 0,
    /// 1: a command code that cannot be processed was received during BUSY.
    NotAllowedWhileBusy = 1,
    /// 2: initialization has not been executed.
    NotInitialized = 2,
    /// 3: too many parameters (data not preceded by a command code).
    TooManyParameters = 3,
    /// 4: the number of acceleration/deceleration steps is greater than 11,220.
    AccelPulsesTooMany = 4,
    /// 5: rate data abnormal (RH > RL) or fewer than 4 acceleration pulses.
    BadRateData = 5,
    /// 6: data were received while BUSY.
    DataWhileBusy = 6,
    /// 7: Decelerating Stop received during deceleration.
    DecelStopDuringDecel = 7,
}

impl ErrorCode {
    pub const ALL: [ErrorCode; 8] = [
        ErrorCode::UndefinedCommand,
        ErrorCode::NotAllowedWhileBusy,
        ErrorCode::NotInitialized,
        ErrorCode::TooManyParameters,
        ErrorCode::AccelPulsesTooMany,
        ErrorCode::BadRateData,
        ErrorCode::DataWhileBusy,
        ErrorCode::DecelStopDuringDecel,
    ];

    /// From the 3-bit error number. Total: all eight values are defined.
    pub fn from_number(n: u8) -> ErrorCode {
        ErrorCode::ALL[usize::from(n & 0b111)]
    }

    pub fn number(self) -> u8 {
        self as u8
    }

    pub fn describe(self) -> &'static str {
        match self {
            ErrorCode::UndefinedCommand => "undefined command code",
            ErrorCode::NotAllowedWhileBusy => "command not allowed while BUSY",
            ErrorCode::NotInitialized => "initialization not executed",
            ErrorCode::TooManyParameters => "too many parameters",
            ErrorCode::AccelPulsesTooMany => "acceleration pulses greater than 11,220",
            ErrorCode::BadRateData => "rate data abnormal or fewer than 4 acceleration pulses",
            ErrorCode::DataWhileBusy => "data received while BUSY",
            ErrorCode::DecelStopDuringDecel => "decelerating stop during deceleration",
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "error {} ({})", self.number(), self.describe())
    }
}

/// Status register (Section 3-1-1, Diagram 3-1).
///
/// | bit | meaning |
/// |-----|---------|
/// | 7   | error flag |
/// | 6-4 | error number if bit 7 = 1, else parameter bytes still expected |
/// | 3   | unused, reads 0 |
/// | 2   | BUSY: pulse output in progress |
/// | 1   | IBF: input buffer full, do not write |
/// | 0   | OBF: output buffer full, data may be read |
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Status(pub u8);

/// What status bits 6-4 mean, depending on bit 7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StatusField {
    /// Bit 7 = 0: number of parameter bytes remaining to be transmitted.
    ParamsRemaining(u8),
    /// Bit 7 = 1: the error number.
    Error(ErrorCode),
}

impl Status {
    pub const OBF: u8 = 0x01;
    pub const IBF: u8 = 0x02;
    pub const BUSY: u8 = 0x04;
    pub const ERROR: u8 = 0x80;

    pub fn new(obf: bool, ibf: bool, busy: bool, field: StatusField) -> Status {
        let (flag, num) = match field {
            StatusField::ParamsRemaining(n) => (false, n & 0b111),
            StatusField::Error(e) => (true, e.number()),
        };
        Status(
            u8::from(obf)
                | (u8::from(ibf) << 1)
                | (u8::from(busy) << 2)
                | (num << 4)
                | (u8::from(flag) << 7),
        )
    }

    pub fn obf(self) -> bool {
        self.0 & Self::OBF != 0
    }

    pub fn ibf(self) -> bool {
        self.0 & Self::IBF != 0
    }

    pub fn busy(self) -> bool {
        self.0 & Self::BUSY != 0
    }

    pub fn error_flag(self) -> bool {
        self.0 & Self::ERROR != 0
    }

    /// Bit 3, which the datasheet marks `x`; the model always reads it as 0.
    pub fn reserved(self) -> bool {
        self.0 & 0x08 != 0
    }

    pub fn field(self) -> StatusField {
        let n = (self.0 >> 4) & 0b111;
        if self.error_flag() {
            StatusField::Error(ErrorCode::from_number(n))
        } else {
            StatusField::ParamsRemaining(n)
        }
    }

    pub fn error(self) -> Option<ErrorCode> {
        match self.field() {
            StatusField::Error(e) => Some(e),
            StatusField::ParamsRemaining(_) => None,
        }
    }
}

impl fmt::Debug for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Status(0x{:02X} {:?}", self.0, self.field())?;
        for (set, name) in [
            (self.busy(), "BUSY"),
            (self.ibf(), "IBF"),
            (self.obf(), "OBF"),
        ] {
            if set {
                write!(f, " {name}")?;
            }
        }
        f.write_str(")")
    }
}

/// A status register flag that a host can wait on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flag {
    Ibf,
    Obf,
    Busy,
    Err,
}

impl Flag {
    pub fn mask(self) -> u8 {
        match self {
            Flag::Ibf => Status::IBF,
            Flag::Obf => Status::OBF,
            Flag::Busy => Status::BUSY,
            Flag::Err => Status::ERROR,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Flag::Ibf => "ibf",
            Flag::Obf => "obf",
            Flag::Busy => "busy",
            Flag::Err => "err",
        }
    }

    pub fn from_name(s: &str) -> Option<Flag> {
        match s {
            "ibf" => Some(Flag::Ibf),
            "obf" => Some(Flag::Obf),
            "busy" => Some(Flag::Busy),
            "err" => Some(Flag::Err),
            _ => None,
        }
    }
}

/// Why pulse output ended: finish status bits 6-3 (Section 3-4-1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StopCause {
    /// Bits 6-3 all 0: all pulses output (or origin found, see notes N14).
    Completed,
    /// Bit 3: stopped after detecting a high-speed limit (L3*, L4*).
    HighSpeedLimit,
    /// Bit 4: stopped after detecting a limit (L1*, L2*).
    Limit,
    /// Bit 5: stopped by the ALM* signal.
    Alarm,
    /// Bit 6: stopped by the Immediate Stop or Decelerating Stop command.
    StopCommand,
}

impl StopCause {
    pub fn bits(self) -> u8 {
        match self {
            StopCause::Completed => 0,
            StopCause::HighSpeedLimit => 0x08,
            StopCause::Limit => 0x10,
            StopCause::Alarm => 0x20,
            StopCause::StopCommand => 0x40,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            StopCause::Completed => "completed",
            StopCause::HighSpeedLimit => "high-speed-limit",
            StopCause::Limit => "limit",
            StopCause::Alarm => "alarm",
            StopCause::StopCommand => "stop-command",
        }
    }
}

/// Finish status byte (Section 3-4-1, Diagram 3-29).
///
/// Bits 2-0: operation code of the last move; bit 3: high-speed limit;
/// bit 4: limit; bit 5: alarm; bit 6: stop command; bit 7: polling flag,
/// set when the operation stops and cleared by reading this register.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FinishStatus(pub u8);

impl FinishStatus {
    pub fn new(kind: MoveKind, cause: StopCause, polling: bool) -> Self {
        FinishStatus(kind.code() | cause.bits() | (u8::from(polling) << 7))
    }

    pub fn op_code(self) -> u8 {
        self.0 & 0b111
    }

    pub fn high_speed_limit(self) -> bool {
        self.0 & 0x08 != 0
    }

    pub fn limit(self) -> bool {
        self.0 & 0x10 != 0
    }

    pub fn alarm(self) -> bool {
        self.0 & 0x20 != 0
    }

    pub fn stop_command(self) -> bool {
        self.0 & 0x40 != 0
    }

    pub fn polling(self) -> bool {
        self.0 & 0x80 != 0
    }

    /// Whether bits 3 to 6 say the operation did not stop normally, in
    /// which case a remaining-pulses reading of 0 means 1 (Section 3-4-4).
    pub fn abnormal(self) -> bool {
        self.0 & 0x78 != 0
    }

    pub fn without_polling(self) -> Self {
        FinishStatus(self.0 & 0x7F)
    }
}

impl fmt::Debug for FinishStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "FinishStatus(0x{:02X})", self.0)
    }
}

/// The input pins, each active low (Sections 3-3-6, 3-4-2, 3-4-5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Input {
    /// CW limit L1*.
    L1,
    /// CCW limit L2*.
    L2,
    /// CW high-speed limit L3*.
    L3,
    /// CCW high-speed limit L4*.
    L4,
    /// Alarm ALM*.
    Alm,
    /// Origin CNP*.
    Cnp,
    /// Auxiliary inputs AUXI0..3.
    Auxi0,
    Auxi1,
    Auxi2,
    Auxi3,
}

impl Input {
    pub const ALL: [Input; 10] = [
        Input::L1,
        Input::L2,
        Input::L3,
        Input::L4,
        Input::Alm,
        Input::Cnp,
        Input::Auxi0,
        Input::Auxi1,
        Input::Auxi2,
        Input::Auxi3,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Input::L1 => "l1",
            Input::L2 => "l2",
            Input::L3 => "l3",
            Input::L4 => "l4",
            Input::Alm => "alm",
            Input::Cnp => "cnp",
            Input::Auxi0 => "auxi0",
            Input::Auxi1 => "auxi1",
            Input::Auxi2 => "auxi2",
            Input::Auxi3 => "auxi3",
        }
    }

    pub fn from_name(s: &str) -> Option<Input> {
        Input::ALL.into_iter().find(|i| i.name() == s)
    }

    /// Bit index in the set of all inputs ([`InputSet`]).
    pub fn index(self) -> u8 {
        self as u8
    }

    /// The limit that stops a move in `dir` at once (Section 3-3-6).
    pub fn limit_for(dir: Direction) -> Input {
        match dir {
            Direction::Cw => Input::L1,
            Direction::Ccw => Input::L2,
        }
    }

    /// The high-speed limit that decelerates a move in `dir` (Section 3-3-4).
    pub fn high_speed_limit_for(dir: Direction) -> Input {
        match dir {
            Direction::Cw => Input::L3,
            Direction::Ccw => Input::L4,
        }
    }
}

/// Which inputs are asserted (the active-low pin pulled low).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct InputSet(u16);

impl InputSet {
    pub fn contains(self, i: Input) -> bool {
        self.0 & (1 << i.index()) != 0
    }

    pub fn set(&mut self, i: Input, asserted: bool) {
        if asserted {
            self.0 |= 1 << i.index();
        } else {
            self.0 &= !(1 << i.index());
        }
    }

    pub fn bits(self) -> u16 {
        self.0
    }
}

/// Input signal status byte (Section 3-4-2, Diagram 3-31): pin levels as
/// read, so an asserted (low) input reads 0.
///
/// Bit 0: L4*, bit 1: L3*, bit 2: L2*, bit 3: L1*, bit 4: ALM*, bit 5: CNP*;
/// bits 7-6 unused, read 0.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct InputStatus(pub u8);

impl InputStatus {
    const ORDER: [Input; 6] = [
        Input::L4,
        Input::L3,
        Input::L2,
        Input::L1,
        Input::Alm,
        Input::Cnp,
    ];

    pub fn from_inputs(set: InputSet) -> Self {
        let mut b = 0u8;
        for (bit, input) in Self::ORDER.iter().enumerate() {
            if !set.contains(*input) {
                b |= 1 << bit;
            }
        }
        InputStatus(b)
    }

    /// Whether `input` reads as asserted (pin low). `None` for the AUXI
    /// inputs, which this register does not carry.
    pub fn asserted(self, input: Input) -> Option<bool> {
        let bit = Self::ORDER.iter().position(|i| *i == input)?;
        Some(self.0 & (1 << bit) == 0)
    }
}

impl fmt::Debug for InputStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "InputStatus(0x{:02X})", self.0)
    }
}

/// Output signal status byte (Section 3-4-3, Diagram 3-33).
///
/// Bit 0 unused (0); bit 1: direction of the previous operation (1 = CCW);
/// bit 2: HOLD; bits 7..3: the levels of S1..S5 (S1 in bit 7).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct OutputStatus(pub u8);

impl OutputStatus {
    /// `phase_levels` holds S1..S5 as pin levels in bits 4..0 (S1 in bit 4).
    pub fn new(direction: Direction, hold: bool, phase_levels: u8) -> Self {
        OutputStatus(
            (u8::from(direction.bit()) << 1) | (u8::from(hold) << 2) | ((phase_levels & 0x1F) << 3),
        )
    }

    pub fn direction(self) -> Direction {
        Direction::from_bit(self.0 & 0x02 != 0)
    }

    pub fn hold(self) -> bool {
        self.0 & 0x04 != 0
    }

    /// S1..S5 pin levels, S1 in bit 4.
    pub fn phase_levels(self) -> u8 {
        self.0 >> 3
    }
}

impl fmt::Debug for OutputStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "OutputStatus(0x{:02X})", self.0)
    }
}

/// Auxiliary input status byte (Section 3-4-5, Diagram 3-46): AUXI0..3 pin
/// levels in bits 0..3 (asserted = low = 0); bits 7-4 read 0.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AuxInputStatus(pub u8);

impl AuxInputStatus {
    const ORDER: [Input; 4] = [Input::Auxi0, Input::Auxi1, Input::Auxi2, Input::Auxi3];

    pub fn from_inputs(set: InputSet) -> Self {
        let mut b = 0u8;
        for (bit, input) in Self::ORDER.iter().enumerate() {
            if !set.contains(*input) {
                b |= 1 << bit;
            }
        }
        AuxInputStatus(b)
    }
}

impl fmt::Debug for AuxInputStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AuxInputStatus(0x{:02X})", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn status_fields_round_trip(obf: bool, ibf: bool, busy: bool, err: bool, n in 0u8..8) {
            let field = if err {
                StatusField::Error(ErrorCode::from_number(n))
            } else {
                StatusField::ParamsRemaining(n)
            };
            let s = Status::new(obf, ibf, busy, field);
            prop_assert_eq!((s.obf(), s.ibf(), s.busy(), s.field()), (obf, ibf, busy, field));
            prop_assert!(!s.reserved());
        }

        #[test]
        fn any_status_byte_decodes(b: u8) {
            let s = Status(b);
            // Re-encoding the decoded fields loses only bit 3.
            prop_assert_eq!(Status::new(s.obf(), s.ibf(), s.busy(), s.field()).0, b & !0x08);
        }
    }

    #[test]
    fn s3_1_1_status_bit_positions() {
        // Independent literal: error 5 with BUSY and IBF set is 1101_0110.
        let s = Status::new(
            false,
            true,
            true,
            StatusField::Error(ErrorCode::BadRateData),
        );
        assert_eq!(s.0, 0b1101_0110);
        // Four parameters expected (initialization), IBF clear: 0100_0000.
        assert_eq!(
            Status::new(false, false, false, StatusField::ParamsRemaining(4)).0,
            0x40
        );
    }

    #[test]
    fn s3_4_1_finish_status_example_0x83() {
        let f = FinishStatus::new(MoveKind::AccelDecel, StopCause::Completed, true);
        assert_eq!(f.0, 0x83);
        assert!(f.polling() && !f.abnormal());
        let f = FinishStatus::new(MoveKind::Constant, StopCause::Limit, true);
        assert_eq!(f.0, 0x94);
        assert!(f.limit() && f.abnormal());
    }

    #[test]
    fn s3_4_2_input_status_reads_pin_levels() {
        let mut set = InputSet::default();
        assert_eq!(InputStatus::from_inputs(set).0, 0x3F);
        set.set(Input::L3, true);
        set.set(Input::Cnp, true);
        let s = InputStatus::from_inputs(set);
        assert_eq!(s.0, 0b0001_1101);
        assert_eq!(s.asserted(Input::L3), Some(true));
        assert_eq!(s.asserted(Input::L4), Some(false));
        assert_eq!(s.asserted(Input::Auxi0), None);
    }

    #[test]
    fn s3_4_3_output_status_layout() {
        let s = OutputStatus::new(Direction::Ccw, true, 0b10000);
        assert_eq!(s.0, 0b1000_0110);
        assert_eq!(s.direction(), Direction::Ccw);
        assert!(s.hold());
        assert_eq!(s.phase_levels(), 0b10000);
    }

    #[test]
    fn s3_4_5_aux_inputs_low_nibble() {
        let mut set = InputSet::default();
        set.set(Input::Auxi2, true);
        assert_eq!(AuxInputStatus::from_inputs(set).0, 0b0000_1011);
    }
}
