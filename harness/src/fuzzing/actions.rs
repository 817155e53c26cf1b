//! Typed, protocol-respecting actions: what a host program does with the
//! chip, one command (with its parameter bytes and the flowchart's waits)
//! at a time. The structure-aware fuzz target (`typed_actions`) and the
//! differential runs (`ppmc fuzz --target`) are made of them, so both reach
//! the deep states a byte stream rarely finds: initialized, moving,
//! decelerating, stopped by each cause.
//!
//! Values are folded into range rather than rejected (rates made valid,
//! step counts kept short), so that almost every input does something.
//!
//! [`lower`] runs actions under the invariant oracle and gives the bus ops
//! that ran, so that every finding of `typed_actions` has one bus-level
//! form.

use crate::bus_program;
use crate::console::Stmt;
use crate::emu::{ModelConfig, PA_MIN};
use crate::invariants::oracle;
use crate::invariants::rules::Violation;
use crate::protocol::{
    ClockSource, Command, Direction, Excitation, Flag, InitCommand, Input, MotorType, MoveCommand,
    MoveKind, OpFlags, OutputLogic, PulseCount, Register, Status,
};
use crate::time::Duration;
use arbitrary::{Arbitrary, Unstructured};
use std::fmt;

/// Longest `await busy=0` an action waits for a move to end.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(2);

/// One host action.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Arbitrary)]
pub enum Action {
    /// Initialization (Section 3-2) with RL > RH > 0 and PA from 4 to 259.
    Init {
        motor: u8,
        half_step: bool,
        positive_logic: bool,
        stop_switching: bool,
        rl: u8,
        rh: u8,
        pa: u8,
    },
    /// An operation command (Sections 3-3-3 to 3-3-8) with its parameters:
    /// 1 to 1,000 steps where the move takes a count.
    Move {
        kind: u8,
        ccw: bool,
        interrupt: bool,
        pout: bool,
        rate: u8,
        steps: u16,
    },
    /// Immediate Stop (3-3-1) or Decelerating Stop (3-3-2).
    Stop { decel: bool },
    /// Drive an input pin.
    Input { input: u8, asserted: bool },
    /// Let 0 to 25.5 ms pass.
    Wait { tenths_ms: u8 },
    /// Let 0 to 2.55 s pass.
    WaitLong { centis: u8 },
    /// Wait for BUSY = 0, at most [`IDLE_TIMEOUT`].
    AwaitIdle,
    /// A register read (Section 3-4): the command, then each byte.
    Read { register: u8 },
    /// A status register read.
    Status,
    /// Software reset (3-5-4).
    SoftwareReset,
    /// AUX ON / AUX OFF (3-5-2).
    Aux { on: bool },
    /// Auxiliary output data (3-5-3).
    AuxOutput { bits: u8 },
    /// Stop switching parameters (3-5-1).
    Switching { on: u8, off: u8 },
    /// Any byte to the command register, as a buggy host might.
    RawCommand(u8),
    /// Any byte to the data register.
    RawData(u8),
    /// A stop placed against the pulse train: wait for pulse `1 + pulse %
    /// 1000` of the move, then `micros` us, then Immediate or Decelerating
    /// Stop. Placed so that the stop's latency decides which pulse it
    /// acts after (Table 3-3's 17 us; see [`super::differential`]).
    StopNearPulse { decel: bool, pulse: u16, micros: u8 },
}

fn wc(byte: u8) -> Stmt {
    Stmt::WriteCommand { byte, wait: true }
}

fn wd(byte: u8) -> Stmt {
    Stmt::WriteData { byte, wait: true }
}

impl Action {
    /// The action as console statements (`docs/console.md`), flowchart
    /// waits included.
    pub fn stmts(&self) -> Vec<Stmt> {
        match *self {
            Action::Init {
                motor,
                half_step,
                positive_logic,
                stop_switching,
                rl,
                rh,
                pa,
            } => {
                let motor = [
                    MotorType::ThreePhase,
                    MotorType::FourPhase,
                    MotorType::FivePhase,
                ][usize::from(motor % 3)];
                let cmd = Command::Init(InitCommand {
                    motor,
                    excitation: if half_step {
                        Excitation::HalfStep
                    } else {
                        Excitation::TwoPhase
                    },
                    logic: if positive_logic {
                        OutputLogic::Positive
                    } else {
                        OutputLogic::Negative
                    },
                    clock: ClockSource::Internal,
                    stop_switching,
                });
                let rl = 2 + rl % 253; // 2..=254
                let rh = 1 + rh % (rl - 1); // 1..rl
                let [lo, hi] = (PA_MIN + u16::from(pa)).to_le_bytes();
                vec![wc(cmd.encode()), wd(rl), wd(rh), wd(lo), wd(hi)]
            }
            Action::Move {
                kind,
                ccw,
                interrupt,
                pout,
                rate,
                steps,
            } => {
                let kind = MoveKind::ALL[usize::from(kind) % MoveKind::ALL.len()];
                let dir = Direction::from_bit(ccw);
                let m = if pout && kind.has_pout_mode() {
                    MoveCommand::pout(kind, dir, interrupt)
                } else {
                    MoveCommand::new(kind, dir, interrupt)
                };
                let count = PulseCount::new(1 + u32::from(steps) % 1_000)
                    .unwrap_or(PulseCount::MAX)
                    .to_bytes();
                let rate = rate.max(1);
                let params: Vec<u8> = match kind {
                    MoveKind::SingleStep | MoveKind::ContinuousHigh => Vec::new(),
                    MoveKind::AccelDecel => count.to_vec(),
                    MoveKind::Constant => [rate, count[0], count[1], count[2]].to_vec(),
                    MoveKind::ContinuousConstant | MoveKind::OriginSearch => vec![rate],
                };
                let mut v = vec![wc(Command::Move(m).encode())];
                v.extend(params.into_iter().map(wd));
                v
            }
            Action::Stop { decel } => {
                let c = if decel {
                    Command::DecelStop(OpFlags::PLAIN)
                } else {
                    Command::ImmediateStop(OpFlags::PLAIN)
                };
                vec![wc(c.encode())]
            }
            Action::Input { input, asserted } => vec![Stmt::Set {
                input: Input::ALL[usize::from(input) % Input::ALL.len()],
                asserted,
            }],
            Action::Wait { tenths_ms } => {
                vec![Stmt::Wait(Duration::from_micros(
                    100 * u64::from(tenths_ms),
                ))]
            }
            Action::WaitLong { centis } => {
                vec![Stmt::Wait(Duration::from_millis(10 * u64::from(centis)))]
            }
            Action::AwaitIdle => vec![Stmt::Await {
                flag: Flag::Busy,
                value: false,
                timeout: Some(IDLE_TIMEOUT),
            }],
            Action::Read { register } => {
                let r = Register::ALL[usize::from(register) % Register::ALL.len()];
                let mut v = vec![wc(Command::Read(r).encode())];
                v.extend((0..r.byte_count()).map(|_| Stmt::ReadData { wait: true }));
                v
            }
            Action::Status => vec![Stmt::ReadStatus],
            Action::SoftwareReset => vec![wc(Command::SoftwareReset(OpFlags::PLAIN).encode())],
            Action::Aux { on } => vec![wc(if on {
                Command::AuxOn(OpFlags::PLAIN).encode()
            } else {
                Command::AuxOff(OpFlags::PLAIN).encode()
            })],
            Action::AuxOutput { bits } => vec![wc(Command::AuxOutput.encode()), wd(bits & 0x0F)],
            Action::Switching { on, off } => {
                vec![wc(Command::SwitchingParams.encode()), wd(on), wd(off)]
            }
            Action::StopNearPulse {
                decel,
                pulse,
                micros,
            } => {
                let mut v = vec![
                    Stmt::AwaitPulse {
                        count: 1 + u64::from(pulse % 1_000),
                        timeout: Some(IDLE_TIMEOUT),
                    },
                    Stmt::Wait(Duration::from_micros(u64::from(micros))),
                ];
                v.extend(Action::Stop { decel }.stmts());
                v
            }
            Action::RawCommand(b) => vec![wc(b)],
            Action::RawData(b) => vec![wd(b)],
        }
    }

    /// A valid initialization: the first action of every generated program,
    /// so that moves do something.
    pub fn default_init() -> Action {
        Action::Init {
            motor: 1,
            half_step: false,
            positive_logic: false,
            stop_switching: false,
            rl: 98,
            rh: 19,
            pa: 96,
        }
    }
}

impl fmt::Display for Action {
    /// The action's statements, `; `-separated, in the console language.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.stmts().iter().enumerate() {
            if i > 0 {
                f.write_str("; ")?;
            }
            write!(f, "{s}")?;
        }
        Ok(())
    }
}

/// The actions an input's bytes decode to (as many as the bytes hold).
pub fn decode(data: &[u8]) -> Vec<Action> {
    let mut u = Unstructured::new(data);
    let mut out = Vec::new();
    while !u.is_empty() {
        match Action::arbitrary(&mut u) {
            Ok(a) => out.push(a),
            Err(_) => break,
        }
    }
    out
}

/// The actions a `typed_actions` input runs: a valid initialization, then
/// whatever its bytes decode to.
pub fn typed_program(data: &[u8]) -> Vec<Action> {
    let mut acts = vec![Action::default_init()];
    acts.extend(decode(data));
    acts
}

/// Runs typed actions under the oracle and returns the bus ops that ran
/// (the flowchart's waits become the time that passed, to the
/// microsecond), with the first invariant break. The ops replay as a
/// `bus_bytes` input, so every finding has one bus-level form.
pub fn lower(acts: &[Action], cfg: ModelConfig) -> (Vec<bus_program::BusOp>, Option<Violation>) {
    let mut ops = Vec::new();
    let Ok(mut c) = oracle::Checker::new(cfg) else {
        return (ops, None);
    };
    let run =
        |c: &mut oracle::Checker, op: bus_program::BusOp, ops: &mut Vec<bus_program::BusOp>| {
            ops.push(op);
            c.apply(op)
        };
    // Lets time pass until `ready` holds or `timeout` is spent.
    let wait = |c: &mut oracle::Checker,
                ops: &mut Vec<bus_program::BusOp>,
                ready: &dyn Fn(Status) -> bool,
                timeout: Duration|
     -> Result<(), Violation> {
        let deadline = c.board().now() + timeout;
        while !ready(c.board().read_status()) && c.board().now() < deadline {
            let now = c.board().now();
            let next = c.board().poll_at().unwrap_or(deadline).min(deadline);
            let us = next.saturating_since(now).as_nanos().div_ceil(1_000).max(1);
            for op in bus_program::advances(Duration::from_micros(us)) {
                ops.push(op);
                c.apply(op)?;
            }
        }
        Ok(())
    };
    let second = Duration::from_secs(1);
    let result = (|| {
        for a in acts {
            for s in a.stmts() {
                match s {
                    Stmt::WriteCommand { byte, wait: w } | Stmt::WriteData { byte, wait: w } => {
                        if w {
                            wait(&mut c, &mut ops, &|s| !s.ibf(), second)?;
                        }
                        let op = if matches!(s, Stmt::WriteCommand { .. }) {
                            bus_program::BusOp::Command(byte)
                        } else {
                            bus_program::BusOp::Data(byte)
                        };
                        run(&mut c, op, &mut ops)?;
                    }
                    Stmt::ReadData { wait: w } => {
                        if w {
                            wait(&mut c, &mut ops, &|s| s.obf(), second)?;
                        }
                        run(&mut c, bus_program::BusOp::ReadData, &mut ops)?;
                    }
                    Stmt::Await {
                        flag,
                        value,
                        timeout,
                    } => {
                        let mask = flag.mask();
                        let want = if value { mask } else { 0 };
                        let t = timeout.unwrap_or(second);
                        wait(&mut c, &mut ops, &|s| s.0 & mask == want, t)?;
                        run(&mut c, bus_program::BusOp::ReadStatus, &mut ops)?;
                    }
                    Stmt::ReadStatus => run(&mut c, bus_program::BusOp::ReadStatus, &mut ops)?,
                    Stmt::Wait(d) => {
                        for op in bus_program::advances(d) {
                            run(&mut c, op, &mut ops)?;
                        }
                    }
                    Stmt::WaitAt(t) => {
                        let d = t.saturating_since(c.board().now());
                        for op in bus_program::advances(d) {
                            run(&mut c, op, &mut ops)?;
                        }
                    }
                    Stmt::Set { input, asserted } => run(
                        &mut c,
                        bus_program::BusOp::Input { input, asserted },
                        &mut ops,
                    )?,
                    Stmt::AwaitPulse { count, timeout } => {
                        // Time passes to that pulse (to the microsecond
                        // after it), or not at all if the move will not
                        // reach it in time.
                        let deadline = c.board().now() + timeout.unwrap_or(second);
                        while c.board().move_pulses() < count {
                            let now = c.board().now();
                            let Some(at) = c.board().predict_pulse(count) else {
                                break;
                            };
                            if at > deadline {
                                break;
                            }
                            let us = at.saturating_since(now).as_nanos().div_ceil(1_000).max(1);
                            for op in bus_program::advances(Duration::from_micros(us)) {
                                run(&mut c, op, &mut ops)?;
                            }
                        }
                    }
                    Stmt::Pins | Stmt::Pulses | Stmt::Now => {}
                }
            }
        }
        c.finish()
    })();
    (ops, result.err())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn init_is_always_valid_rates_and_pa() {
        for rl in [0u8, 1, 2, 254, 255] {
            for rh in [0u8, 1, 200, 255] {
                let a = Action::Init {
                    motor: 7,
                    half_step: true,
                    positive_logic: true,
                    stop_switching: true,
                    rl,
                    rh,
                    pa: 255,
                };
                let s = a.stmts();
                let byte = |i: usize| match s[i] {
                    Stmt::WriteData { byte, .. } => byte,
                    ref other => panic!("{other:?}"),
                };
                let (rl, rh) = (byte(1), byte(2));
                assert!(0 < rh && rh < rl && rl < 255, "rl {rl} rh {rh}");
                let pa = u16::from_le_bytes([byte(3), byte(4)]);
                assert!((PA_MIN..=PA_MIN + 255).contains(&pa));
            }
        }
    }

    #[test]
    fn moves_carry_the_parameter_count_their_command_takes() {
        for kind in 0..6u8 {
            let a = Action::Move {
                kind,
                ccw: kind % 2 == 0,
                interrupt: true,
                pout: true,
                rate: 0,
                steps: u16::MAX,
            };
            let s = a.stmts();
            let Stmt::WriteCommand { byte, .. } = s[0] else {
                panic!("{s:?}")
            };
            assert_eq!(Command::decode(byte).param_count() as usize, s.len() - 1);
        }
    }

    #[test]
    fn decoding_takes_every_action_the_bytes_hold_and_prints_them() {
        let acts = decode(&[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15]);
        assert!(!acts.is_empty());
        let text = Action::Read { register: 3 }.to_string();
        assert_eq!(text, "wc 0x83; rd; rd; rd");
    }
}
