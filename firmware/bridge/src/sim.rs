//! A cycle-counting interpreter of one PIO state machine, for the tests:
//! the instructions and options the bridge's programs use, as the RP2350
//! datasheet's PIO chapter defines them (one instruction per cycle plus its
//! delay; a blocking `pull` or `push` stalls; `jmp x--` tests X before
//! decrementing it; `out` shifts right, `in` shifts left, as the firmware
//! configures them).

extern crate std;

use pio::{
    InSource, Instruction, InstructionOperands, JmpCondition, MovDestination, MovOperation,
    MovSource, OutDestination, Program, SetDestination,
};
use std::collections::VecDeque;

/// How the state machine's pins are mapped.
#[derive(Debug, Clone, Copy)]
pub struct Pins {
    pub out_base: u32,
    pub out_count: u32,
    pub in_base: u32,
    pub set_base: u32,
    pub set_count: u32,
    pub jmp_pin: u32,
}

#[derive(Debug)]
pub struct Sm<'p> {
    program: &'p Program<{ crate::programs::SIZE }>,
    map: Pins,
    pc: u8,
    pub x: u32,
    pub y: u32,
    isr: u32,
    isr_count: u32,
    osr: u32,
    osr_count: u32,
    pub tx: VecDeque<u32>,
    pub rx: VecDeque<u32>,
    /// Output levels and directions of all 48 GPIOs, as the machine drives
    /// them.
    pub levels: u64,
    pub dirs: u64,
    /// Cycles run so far.
    pub cycle: u64,
    delay: u8,
}

fn mask(bits: u32) -> u32 {
    if bits >= 32 {
        u32::MAX
    } else {
        (1 << bits) - 1
    }
}

impl<'p> Sm<'p> {
    pub fn new(program: &'p Program<{ crate::programs::SIZE }>, map: Pins) -> Sm<'p> {
        Sm {
            program,
            map,
            pc: 0,
            x: 0,
            y: 0,
            isr: 0,
            isr_count: 0,
            osr: 0,
            osr_count: 32,
            tx: VecDeque::new(),
            rx: VecDeque::new(),
            levels: 0,
            dirs: 0,
            cycle: 0,
            delay: 0,
        }
    }

    fn write_pins(&mut self, base: u32, count: u32, value: u32, dirs: bool) {
        for i in 0..count {
            let pin = u64::from((base + i) % 48);
            let bit = u64::from(value >> i & 1);
            let reg = if dirs {
                &mut self.dirs
            } else {
                &mut self.levels
            };
            *reg = (*reg & !(1 << pin)) | bit << pin;
        }
    }

    fn read_pins(&self, inputs: u64, base: u32) -> u32 {
        // What the pins read: inputs where not driven, else our levels.
        let seen = (inputs & !self.dirs) | (self.levels & self.dirs);
        (0..32).fold(0, |v, i| {
            v | (((seen >> ((base + i) % 48)) & 1) as u32) << i
        })
    }

    fn next_pc(&self) -> u8 {
        if self.pc == self.program.wrap.source {
            self.program.wrap.target
        } else {
            self.pc + 1
        }
    }

    /// Runs one cycle with the GPIOs reading `inputs`; returns whether the
    /// machine stalled (a blocking `pull` on an empty FIFO, a `push` on a
    /// full one).
    pub fn step(&mut self, inputs: u64) -> bool {
        self.cycle += 1;
        if self.delay > 0 {
            self.delay -= 1;
            return false;
        }
        let word = self.program.code[usize::from(self.pc)];
        let ins = Instruction::decode(word, self.program.side_set).expect("a valid instruction");
        let mut next = self.next_pc();
        match ins.operands {
            InstructionOperands::JMP { condition, address } => {
                let take = match condition {
                    JmpCondition::Always => true,
                    JmpCondition::XIsZero => self.x == 0,
                    JmpCondition::XDecNonZero => {
                        let t = self.x != 0;
                        self.x = self.x.wrapping_sub(1);
                        t
                    }
                    JmpCondition::YIsZero => self.y == 0,
                    JmpCondition::YDecNonZero => {
                        let t = self.y != 0;
                        self.y = self.y.wrapping_sub(1);
                        t
                    }
                    JmpCondition::XNotEqualY => self.x != self.y,
                    JmpCondition::PinHigh => self.read_pins(inputs, self.map.jmp_pin) & 1 == 1,
                    JmpCondition::OutputShiftRegisterNotEmpty => self.osr_count < 32,
                };
                if take {
                    next = address;
                }
            }
            InstructionOperands::PULL { block, .. } => match self.tx.pop_front() {
                Some(w) => {
                    self.osr = w;
                    self.osr_count = 0;
                }
                None if block => return true,
                None => {
                    self.osr = self.x;
                    self.osr_count = 0;
                }
            },
            InstructionOperands::PUSH { block, .. } => {
                if self.rx.len() >= 4 {
                    if block {
                        return true;
                    }
                } else {
                    self.rx.push_back(self.isr);
                }
                self.isr = 0;
                self.isr_count = 0;
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
                let v = self.osr & mask(n);
                self.osr = if n == 32 { 0 } else { self.osr >> n };
                self.osr_count = (self.osr_count + n).min(32);
                match destination {
                    OutDestination::PINS => {
                        self.write_pins(self.map.out_base, n.min(self.map.out_count), v, false)
                    }
                    OutDestination::PINDIRS => {
                        self.write_pins(self.map.out_base, n.min(self.map.out_count), v, true)
                    }
                    OutDestination::X => self.x = v,
                    OutDestination::Y => self.y = v,
                    OutDestination::NULL => {}
                    other => panic!("out {other:?} is not simulated"),
                }
            }
            InstructionOperands::IN { source, bit_count } => {
                let n = if bit_count == 0 {
                    32
                } else {
                    u32::from(bit_count)
                };
                let v = match source {
                    InSource::PINS => self.read_pins(inputs, self.map.in_base),
                    InSource::X => self.x,
                    InSource::Y => self.y,
                    InSource::NULL => 0,
                    other => panic!("in {other:?} is not simulated"),
                } & mask(n);
                self.isr = if n == 32 { v } else { (self.isr << n) | v };
                self.isr_count = (self.isr_count + n).min(32);
            }
            InstructionOperands::MOV {
                destination,
                op,
                source,
            } => {
                let v = match source {
                    MovSource::PINS => self.read_pins(inputs, self.map.in_base),
                    MovSource::X => self.x,
                    MovSource::Y => self.y,
                    MovSource::NULL => 0,
                    MovSource::ISR => self.isr,
                    MovSource::OSR => self.osr,
                    MovSource::STATUS => panic!("mov from status is not simulated"),
                };
                let v = match op {
                    MovOperation::None => v,
                    MovOperation::Invert => !v,
                    MovOperation::BitReverse => v.reverse_bits(),
                };
                match destination {
                    MovDestination::X => self.x = v,
                    MovDestination::Y => self.y = v,
                    MovDestination::ISR => {
                        self.isr = v;
                        self.isr_count = 0;
                    }
                    MovDestination::OSR => {
                        self.osr = v;
                        self.osr_count = 0;
                    }
                    MovDestination::PINS => {
                        self.write_pins(self.map.out_base, self.map.out_count, v, false)
                    }
                    MovDestination::PINDIRS => {
                        self.write_pins(self.map.out_base, self.map.out_count, v, true)
                    }
                    other => panic!("mov to {other:?} is not simulated"),
                }
            }
            InstructionOperands::SET { destination, data } => match destination {
                SetDestination::X => self.x = u32::from(data),
                SetDestination::Y => self.y = u32::from(data),
                SetDestination::PINS => self.write_pins(
                    self.map.set_base,
                    self.map.set_count,
                    u32::from(data),
                    false,
                ),
                SetDestination::PINDIRS => {
                    self.write_pins(self.map.set_base, self.map.set_count, u32::from(data), true)
                }
            },
            other => panic!("{other:?} is not simulated"),
        }
        self.delay = ins.delay;
        self.pc = next;
        false
    }
}
