//! What a scenario writes to the chip, built up the way the datasheet
//! draws it: the initialization command and data (Diagram 3-2) and the
//! operation commands with their data (Sections 3-3-3 to 3-3-8).

use crate::protocol::{
    ClockSource, Command, Direction, Excitation, InitCommand, InitData, MotorType, MoveCommand,
    MoveKind, OutputLogic, PulseCount,
};

/// The initialization command and data, built up like the datasheet's
/// Diagram 3-2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Init {
    pub cmd: InitCommand,
    pub data: InitData,
}

impl Init {
    /// A motor with 2-phase excitation, negative logic, the internal clock,
    /// no stop switching, RL = 100, RH = 20, PA = 100.
    pub fn new(motor: MotorType) -> Init {
        Init {
            cmd: InitCommand {
                motor,
                excitation: Excitation::TwoPhase,
                logic: OutputLogic::Negative,
                clock: ClockSource::Internal,
                stop_switching: false,
            },
            data: InitData {
                rl: 100,
                rh: 20,
                pa: 100,
            },
        }
    }

    /// The reference set-up of the suite: 4-phase, RL 100, RH 20, PA 100.
    pub fn four_phase() -> Init {
        Init::new(MotorType::FourPhase)
    }

    pub fn half_step(mut self) -> Init {
        self.cmd.excitation = Excitation::HalfStep;
        self
    }

    pub fn positive_logic(mut self) -> Init {
        self.cmd.logic = OutputLogic::Positive;
        self
    }

    pub fn external_clock(mut self) -> Init {
        self.cmd.clock = ClockSource::External;
        self
    }

    pub fn stop_switching(mut self) -> Init {
        self.cmd.stop_switching = true;
        self
    }

    pub fn rates(mut self, rl: u8, rh: u8) -> Init {
        self.data.rl = rl;
        self.data.rh = rh;
        self
    }

    pub fn accel_pulses(mut self, pa: u16) -> Init {
        self.data.pa = pa;
        self
    }

    pub fn code(&self) -> u8 {
        Command::Init(self.cmd).encode()
    }
}

/// A move to issue: the command code and its data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Move {
    pub cmd: MoveCommand,
    pub rate: Option<u8>,
    pub steps: Option<PulseCount>,
}

impl Move {
    fn new(kind: MoveKind, dir: Direction, rate: Option<u8>, steps: Option<u32>) -> Move {
        Move {
            cmd: MoveCommand::new(kind, dir, true),
            rate,
            // Out-of-range counts are a scenario bug; clamp into 1..=2^24.
            steps: steps.map(|n| PulseCount::new(n.clamp(1, 1 << 24)).unwrap_or(PulseCount::MAX)),
        }
    }

    /// Section 3-3-4: `steps` with the initialization's ramp.
    pub fn accel(dir: Direction, steps: u32) -> Move {
        Move::new(MoveKind::AccelDecel, dir, None, Some(steps))
    }

    /// Section 3-3-5: `steps` at pulse rate `rate`.
    pub fn constant(dir: Direction, rate: u8, steps: u32) -> Move {
        Move::new(MoveKind::Constant, dir, Some(rate), Some(steps))
    }

    /// Section 3-3-6: at `rate` until a limit.
    pub fn continuous(dir: Direction, rate: u8) -> Move {
        Move::new(MoveKind::ContinuousConstant, dir, Some(rate), None)
    }

    /// Section 3-3-7: ramp up and run at high speed until a limit.
    pub fn high_speed(dir: Direction) -> Move {
        Move::new(MoveKind::ContinuousHigh, dir, None, None)
    }

    /// Section 3-3-8: at `rate` until the origin signal.
    pub fn origin(dir: Direction, rate: u8) -> Move {
        Move::new(MoveKind::OriginSearch, dir, Some(rate), None)
    }

    /// Section 3-3-3: one step.
    pub fn single_step(dir: Direction) -> Move {
        Move::new(MoveKind::SingleStep, dir, None, None)
    }

    /// POUT mode (Sections 3-3-4, 3-3-7): pulses only, phases hold.
    pub fn pout(mut self) -> Move {
        self.cmd.pout = true;
        self
    }

    /// Termination interrupt masked (bit 4 = 1).
    pub fn masked(mut self) -> Move {
        self.cmd.flags.interrupt = false;
        self
    }

    pub fn code(&self) -> u8 {
        Command::Move(self.cmd).encode()
    }

    /// The data bytes in flowchart order.
    pub fn params(&self) -> Vec<u8> {
        let mut v = Vec::new();
        v.extend(self.rate);
        if let Some(n) = self.steps {
            v.extend(n.to_bytes());
        }
        v
    }
}
