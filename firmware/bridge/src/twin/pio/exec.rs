//! The state machines' instructions, cycle by cycle, as the silicon runs
//! them (the rules listed in `twin/pio/mod.rs`), and whether a state
//! machine is quiet: stalled on a FIFO, or in a loop of `jmp`s that only
//! counts X down, so that time may skip ahead.

use super::block::{Block, Core, Sm};
use crate::pioregs::{fdebug, pinctrl, shiftctrl};
use pio::{
    InSource, Instruction, InstructionOperands, JmpCondition, MovDestination, MovOperation,
    MovSource, OutDestination, SetDestination, WaitSource,
};

impl Block {
    fn read_window(&self, seen: u64, base: u32) -> u32 {
        (0..32).fold(0u32, |v, i| {
            v | ((seen >> self.gpio(base + i) & 1) as u32) << i
        })
    }

    fn write_window(&mut self, base: u32, count: u32, value: u32, dirs: bool) {
        for i in 0..count {
            let g = u64::from(self.gpio(base + i));
            let bit = u64::from(value >> i & 1);
            let reg = if dirs { &mut self.oe } else { &mut self.out };
            *reg = (*reg & !(1 << g)) | bit << g;
        }
    }

    /// One cycle of state machine `s`, the pins reading `seen`.
    pub(super) fn step(&mut self, s: usize, seen: u64) {
        let sm = &mut self.sm[s];
        if !sm.enabled {
            return;
        }
        if sm.core.delay > 0 {
            sm.core.delay -= 1;
            return;
        }
        let word = self.instr[usize::from(sm.core.pc)];
        self.run_instr(s, word, seen, false);
    }

    /// Executes `word` on `s`: its effects, the next PC and the delay, or
    /// a stall (nothing changes, the same instruction runs next cycle).
    pub(super) fn run_instr(&mut self, s: usize, word: u16, seen: u64, forced: bool) {
        let ins = Instruction::decode(word, self.sm[s].side_set()).unwrap_or_else(|| {
            panic!(
                "PIO{} SM{s}: word {word:#06x} is not an instruction",
                self.index
            )
        });
        let shiftctrl = self.sm[s].shiftctrl;
        let out_right = shiftctrl >> shiftctrl::OUT_SHIFTDIR & 1 == 1;
        let in_right = shiftctrl >> shiftctrl::IN_SHIFTDIR & 1 == 1;
        let pinctrl_ = self.sm[s].pinctrl;
        let out_base = Sm::field(pinctrl_, pinctrl::OUT_BASE, 5);
        let out_count = Sm::field(pinctrl_, pinctrl::OUT_COUNT, 6);
        let set_base = Sm::field(pinctrl_, pinctrl::SET_BASE, 5);
        let set_count = Sm::field(pinctrl_, pinctrl::SET_COUNT, 3);
        let in_pins = {
            let sm = &self.sm[s];
            let n = sm.in_count();
            let mask = if n >= 32 { u32::MAX } else { (1 << n) - 1 };
            self.read_window(seen, sm.in_base()) & mask
        };
        let jmp_level = seen >> self.gpio(self.sm[s].jmp_pin()) & 1 == 1;
        let pc = self.sm[s].core.pc;
        let mut next = self.sm[s].next_pc(pc);
        let mut stall = false;
        match ins.operands {
            InstructionOperands::JMP { condition, address } => {
                let pull_thresh = Self::thresh(shiftctrl, shiftctrl::PULL_THRESH);
                if jump(&mut self.sm[s].core, condition, jmp_level, pull_thresh) {
                    next = address;
                }
            }
            InstructionOperands::WAIT {
                polarity,
                source,
                index,
                relative,
            } => {
                assert!(!relative, "wait rel is not modelled");
                let level = match source {
                    WaitSource::GPIO => seen >> index & 1 == 1,
                    WaitSource::PIN => in_pins >> index & 1 == 1,
                    WaitSource::JMPPIN => jmp_level,
                    WaitSource::IRQ => panic!("wait irq is not modelled"),
                };
                stall = level != (polarity == 1);
            }
            InstructionOperands::IN { source, bit_count } => {
                let n = if bit_count == 0 {
                    32
                } else {
                    u32::from(bit_count)
                };
                let c = &mut self.sm[s].core;
                let v = match source {
                    InSource::PINS => in_pins,
                    InSource::X => c.x,
                    InSource::Y => c.y,
                    InSource::NULL => 0,
                    InSource::ISR => c.isr,
                    InSource::OSR => c.osr,
                } & mask(n);
                c.isr = if n == 32 {
                    v
                } else if in_right {
                    c.isr >> n | v << (32 - n)
                } else {
                    c.isr << n | v
                };
                c.isr_count = (c.isr_count + n).min(32);
            }
            InstructionOperands::OUT {
                destination,
                bit_count,
            } => {
                let n = if bit_count == 0 {
                    32
                } else {
                    u32::from(bit_count)
                };
                let c = &mut self.sm[s].core;
                let v = if out_right {
                    c.osr & mask(n)
                } else {
                    c.osr >> (32 - n)
                };
                c.osr = if n == 32 {
                    0
                } else if out_right {
                    c.osr >> n
                } else {
                    c.osr << n
                };
                c.osr_count = (c.osr_count + n).min(32);
                // A 32-bit value, the bits shifted out and zeroes above
                // them, goes to all OUT_COUNT pins (11.4.5.2, 11.5.6):
                // `out pindirs, 8` with 13 OUT pins makes the top 5 inputs.
                match destination {
                    OutDestination::PINS => self.write_window(out_base, out_count, v, false),
                    OutDestination::PINDIRS => self.write_window(out_base, out_count, v, true),
                    OutDestination::X => self.sm[s].core.x = v,
                    OutDestination::Y => self.sm[s].core.y = v,
                    OutDestination::NULL => {}
                    OutDestination::PC => next = (v % 32) as u8,
                    OutDestination::ISR => {
                        self.sm[s].core.isr = v;
                        self.sm[s].core.isr_count = n;
                    }
                    OutDestination::EXEC => panic!("out exec is not modelled"),
                }
            }
            InstructionOperands::PUSH { if_full, block } => {
                let sm = &mut self.sm[s];
                let full_enough = !if_full
                    || sm.core.isr_count >= Self::thresh(shiftctrl, shiftctrl::PUSH_THRESH);
                if full_enough {
                    if sm.rx.len() >= sm.rx_depth() {
                        // Blocking or not, a push to a full FIFO sets
                        // RXSTALL; `noblock` goes on, the word lost and
                        // the ISR cleared (11.4.6.2).
                        self.fdebug |= 1 << (fdebug::RXSTALL + s as u32);
                        if block {
                            stall = true;
                        } else {
                            sm.core.isr = 0;
                            sm.core.isr_count = 0;
                        }
                    } else {
                        sm.rx.push_back(sm.core.isr);
                        sm.pushed += 1;
                        sm.core.isr = 0;
                        sm.core.isr_count = 0;
                    }
                }
            }
            InstructionOperands::PULL { if_empty, block } => {
                let sm = &mut self.sm[s];
                let empty_enough = !if_empty
                    || sm.core.osr_count >= Self::thresh(shiftctrl, shiftctrl::PULL_THRESH);
                if empty_enough {
                    match sm.tx.pop_front() {
                        Some(w) => {
                            sm.core.osr = w;
                            sm.core.osr_count = 0;
                        }
                        None if block => {
                            stall = true;
                            self.fdebug |= 1 << (fdebug::TXSTALL + s as u32);
                        }
                        None => {
                            sm.core.osr = sm.core.x;
                            sm.core.osr_count = 0;
                        }
                    }
                }
            }
            InstructionOperands::MOV {
                destination,
                op,
                source,
            } => {
                let c = self.sm[s].core;
                let v = match source {
                    MovSource::PINS => in_pins,
                    MovSource::X => c.x,
                    MovSource::Y => c.y,
                    MovSource::NULL => 0,
                    MovSource::ISR => c.isr,
                    MovSource::OSR => c.osr,
                    MovSource::STATUS => panic!("mov from status is not modelled"),
                };
                let v = match op {
                    MovOperation::None => v,
                    MovOperation::Invert => !v,
                    MovOperation::BitReverse => v.reverse_bits(),
                };
                let c = &mut self.sm[s].core;
                match destination {
                    MovDestination::X => c.x = v,
                    MovDestination::Y => c.y = v,
                    MovDestination::ISR => {
                        c.isr = v;
                        c.isr_count = 0;
                    }
                    MovDestination::OSR => {
                        c.osr = v;
                        c.osr_count = 0;
                    }
                    MovDestination::PC => next = (v % 32) as u8,
                    MovDestination::PINS => self.write_window(out_base, out_count, v, false),
                    MovDestination::PINDIRS => self.write_window(out_base, out_count, v, true),
                    MovDestination::EXEC => panic!("mov exec is not modelled"),
                }
            }
            InstructionOperands::SET { destination, data } => {
                let v = u32::from(data);
                match destination {
                    SetDestination::X => self.sm[s].core.x = v,
                    SetDestination::Y => self.sm[s].core.y = v,
                    SetDestination::PINS => self.write_window(set_base, set_count, v, false),
                    SetDestination::PINDIRS => self.write_window(set_base, set_count, v, true),
                }
            }
            other => panic!("PIO{} SM{s}: {other:?} is not modelled", self.index),
        }
        // The side-set, over any OUT or SET to the same pins, stalled or not.
        if let Some(v) = ins.side_set {
            let (base, count, dirs) = self.sm[s].side_pins();
            self.write_window(base, count, u32::from(v), dirs);
        }
        let sm = &mut self.sm[s];
        sm.stalled = stall;
        if stall {
            return;
        }
        sm.core.pc = next;
        if !forced {
            sm.core.delay = ins.delay;
        }
    }

    /// Whether side-setting `v` on state machine `s` leaves its pins as
    /// they are.
    fn side_set_holds(&self, s: usize, v: u8) -> bool {
        let (base, count, dirs) = self.sm[s].side_pins();
        let reg = if dirs { self.oe } else { self.out };
        (0..count).all(|i| reg >> self.gpio(base + i) & 1 == u64::from(v >> i & 1))
    }

    fn thresh(shiftctrl: u32, at: u32) -> u32 {
        match Sm::field(shiftctrl, at, 5) {
            0 => 32,
            n => n,
        }
    }

    /// Whether state machine `s`, with the pins reading `seen` from now
    /// on, is stalled (and stays so until the CPU acts), or runs a loop of
    /// `jmp`s that only counts X down: `(cycles a turn, X less a turn)`.
    /// `None` when it does anything else within a few turns.
    pub(super) fn quiet(&self, s: usize, seen: u64) -> Option<(u64, u32)> {
        let sm = &self.sm[s];
        if !sm.enabled {
            return Some((1, 0));
        }
        if sm.stalled && sm.core.delay == 0 {
            // A stall on a FIFO lasts until the CPU acts, if it still holds.
            let word = self.instr[usize::from(sm.core.pc)];
            let ins = Instruction::decode(word, sm.side_set())?;
            return match ins.operands {
                InstructionOperands::PULL { block: true, .. } if sm.tx.is_empty() => Some((1, 0)),
                InstructionOperands::PUSH { block: true, .. } if sm.rx.len() >= sm.rx_depth() => {
                    Some((1, 0))
                }
                _ => None,
            };
        }
        let start = sm.core;
        let mut c = start;
        for cycles in 1..=64u64 {
            if c.delay > 0 {
                c.delay -= 1;
            } else {
                let word = self.instr[usize::from(c.pc)];
                let ins = Instruction::decode(word, sm.side_set())?;
                let InstructionOperands::JMP { condition, address } = ins.operands else {
                    return None;
                };
                // A side-set that would change a pin: not a loop to skip.
                if let Some(v) = ins.side_set {
                    if !self.side_set_holds(s, v) {
                        return None;
                    }
                }
                match condition {
                    // The loop's exit: not a loop to skip.
                    JmpCondition::XDecNonZero if c.x == 0 => return None,
                    JmpCondition::Always
                    | JmpCondition::XDecNonZero
                    | JmpCondition::PinHigh
                    | JmpCondition::YIsZero => {}
                    // X read otherwise, Y changed, the OSR: not pure.
                    _ => return None,
                }
                let level = seen >> self.gpio(sm.jmp_pin()) & 1 == 1;
                let take = jump(&mut c, condition, level, 32);
                c.pc = if take { address } else { sm.next_pc(c.pc) };
                c.delay = ins.delay;
            }
            if (Core { x: start.x, ..c }) == start {
                return Some((cycles, start.x.wrapping_sub(c.x)));
            }
        }
        None
    }
}

/// Whether a `jmp` on `condition` jumps, the JMP pin reading `jmp_level`:
/// `x--` and `y--` test, then decrement (wrapping from 0).
fn jump(c: &mut Core, condition: JmpCondition, jmp_level: bool, pull_thresh: u32) -> bool {
    match condition {
        JmpCondition::Always => true,
        JmpCondition::XIsZero => c.x == 0,
        JmpCondition::XDecNonZero => {
            let t = c.x != 0;
            c.x = c.x.wrapping_sub(1);
            t
        }
        JmpCondition::YIsZero => c.y == 0,
        JmpCondition::YDecNonZero => {
            let t = c.y != 0;
            c.y = c.y.wrapping_sub(1);
            t
        }
        JmpCondition::XNotEqualY => c.x != c.y,
        JmpCondition::PinHigh => jmp_level,
        JmpCondition::OutputShiftRegisterNotEmpty => c.osr_count < pull_thresh,
    }
}

fn mask(bits: u32) -> u32 {
    if bits >= 32 {
        u32::MAX
    } else {
        (1 << bits) - 1
    }
}
