//! The plain model's command decoding, its own: a byte written to the
//! command register as Section 3 and notes N2-N4 lay the codes out, and
//! the parameter bytes each command takes.

/// An operation command's operation (bits 2-0, Section 3-3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Op {
    ImmediateStop,
    DecelStop,
    SingleStep,
    AccelDecel,
    Constant,
    ContinuousConstant,
    ContinuousHigh,
    OriginSearch,
}

impl Op {
    pub(super) fn code(self) -> u8 {
        match self {
            Op::ImmediateStop => 0,
            Op::DecelStop => 1,
            Op::SingleStep => 2,
            Op::AccelDecel => 3,
            Op::Constant => 4,
            Op::ContinuousConstant => 5,
            Op::ContinuousHigh => 6,
            Op::OriginSearch => 7,
        }
    }

    pub(super) fn ramped(self) -> bool {
        matches!(self, Op::AccelDecel | Op::ContinuousHigh)
    }
}

/// A command code as Section 3 and notes N2-N4 lay it out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Cmd {
    Init(u8),
    Move {
        op: Op,
        ccw: bool,
        masked: bool,
        pout: bool,
    },
    Read(u8),
    Switching,
    AuxOutput,
    SoftReset,
    AuxOn,
    AuxOff,
    Undefined,
}

/// The command a byte written to the command register is.
pub(super) fn decode(b: u8) -> Cmd {
    if b & 0xC0 == 0 {
        return if b & 0x03 == 0 {
            Cmd::Undefined
        } else {
            Cmd::Init(b)
        };
    }
    if b & 0xC0 == 0x80 {
        return match b {
            0x80..=0x83 | 0x85 => Cmd::Read(b),
            0x84 => Cmd::Switching,
            0x86 => Cmd::AuxOutput,
            _ => Cmd::Undefined,
        };
    }
    let ccw = b & 0x08 != 0;
    let masked = b & 0x10 != 0;
    if b & 0x80 == 0 {
        let op = match b & 0x07 {
            0 => Op::ImmediateStop,
            1 => Op::DecelStop,
            2 => Op::SingleStep,
            3 => Op::AccelDecel,
            4 => Op::Constant,
            5 => Op::ContinuousConstant,
            6 => Op::ContinuousHigh,
            _ => Op::OriginSearch,
        };
        return Cmd::Move {
            op,
            ccw,
            masked,
            pout: false,
        };
    }
    match b & 0x07 {
        0 => Cmd::SoftReset,
        1 => Cmd::AuxOn,
        2 => Cmd::AuxOff,
        3 => Cmd::Move {
            op: Op::AccelDecel,
            ccw,
            masked,
            pout: true,
        },
        6 => Cmd::Move {
            op: Op::ContinuousHigh,
            ccw,
            masked,
            pout: true,
        },
        _ => Cmd::Undefined,
    }
}

/// The parameter bytes a command takes.
pub(super) fn params(cmd: Cmd) -> u8 {
    match cmd {
        Cmd::Init(_)
        | Cmd::Move {
            op: Op::Constant, ..
        } => 4,
        Cmd::Move {
            op: Op::AccelDecel, ..
        } => 3,
        Cmd::Move {
            op: Op::ContinuousConstant | Op::OriginSearch,
            ..
        } => 1,
        Cmd::Switching => 2,
        Cmd::AuxOutput => 1,
        _ => 0,
    }
}
