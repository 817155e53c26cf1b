//! A model of the RP2350's PIO blocks and GPIOs that holds the bridge's
//! code to the silicon's rules (RP2350 datasheet, PIO chapter), cycle by
//! cycle:
//!
//! - 32 instruction words per block, shared by every program loaded into
//!   it: loading past them fails, as embassy-rp's `load_program` panics;
//! - FIFO depths from the join bits: 4 + 4, or 8 for a joined direction; a
//!   write to a full TX FIFO is lost and sets FDEBUG.TXOVER; a `push block`
//!   on a full RX FIFO stalls the state machine and sets FDEBUG.RXSTALL; a
//!   `pull block` on an empty one stalls it (FDEBUG.TXSTALL);
//! - every pin field (IN, OUT, SET bases, the JMP pin) indexes the block's
//!   32-GPIO window from GPIOBASE (0 or 16), wrapping within it;
//! - inputs pass a 2-flip-flop synchroniser: a state machine sees a pin's
//!   level of two cycles before;
//! - `jmp x--` tests X, then decrements it, wrapping from 0 to all ones;
//! - an OUT to PINS or PINDIRS writes all OUT_COUNT pins, zeroes above the
//!   bits shifted out; a side-set (to pins or, with SIDE_PINDIR, to
//!   directions) takes precedence over them on the same cycle, and takes
//!   effect even when its instruction stalls;
//! - one CTRL write enables state machines of a block and, through
//!   NEXT_PIO_MASK, of the next block, on the same cycle.
//!
//! The instructions are decoded by the `pio` crate. What the bridge does
//! not use (optional side-set, autopush and autopull, IRQs, the RX FIFO as
//! registers, clock dividers other than 1) is refused when configured,
//! not modelled approximately.
//!
//! Time skips ahead when nothing can change: every running state machine
//! stalled on a FIFO, or in a loop of `jmp`s whose only effect is counting
//! X down, with no input changing ([`World::run_until`]).

use crate::pioregs::{ctrl, execctrl, fdebug, pinctrl, shiftctrl, SmRegs};
use pio::{
    InSource, Instruction, InstructionOperands, JmpCondition, MovDestination, MovOperation,
    MovSource, OutDestination, SetDestination, SideSet, WaitSource,
};
use std::collections::VecDeque;
use std::string::String;
use std::vec::Vec;

/// GPIOs of an RP2350B.
pub const GPIOS: u32 = 48;
/// Instruction words per block.
pub const WORDS: usize = 32;

/// Why a program could not be loaded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LoadError {
    /// More words than the block has free at that address.
    NoSpace {
        block: usize,
        origin: u8,
        words: usize,
    },
}

/// A configuration the model does not model (and the bridge must not use).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported(pub String);

/// The state a `jmp`-only loop probe compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Core {
    pc: u8,
    x: u32,
    y: u32,
    isr: u32,
    isr_count: u32,
    osr: u32,
    osr_count: u32,
    delay: u8,
}

/// One state machine.
#[derive(Debug, Clone)]
pub struct Sm {
    core: Core,
    pub enabled: bool,
    execctrl: u32,
    shiftctrl: u32,
    pinctrl: u32,
    tx: VecDeque<u32>,
    rx: VecDeque<u32>,
    /// Stalled on the last cycle it ran.
    pub stalled: bool,
}

impl Sm {
    fn new() -> Sm {
        Sm {
            core: Core {
                pc: 0,
                x: 0,
                y: 0,
                isr: 0,
                isr_count: 0,
                osr: 0,
                osr_count: 32,
                delay: 0,
            },
            enabled: false,
            // Reset values: wrap top 31, bottom 0; shift right both ways.
            execctrl: 31 << execctrl::WRAP_TOP,
            shiftctrl: 1 << shiftctrl::IN_SHIFTDIR | 1 << shiftctrl::OUT_SHIFTDIR,
            pinctrl: 5 << pinctrl::SET_COUNT,
            tx: VecDeque::new(),
            rx: VecDeque::new(),
            stalled: false,
        }
    }

    pub fn x(&self) -> u32 {
        self.core.x
    }

    /// Sets X, as the CPU can with forced instructions (tests start a
    /// counter near zero this way).
    pub fn set_x(&mut self, x: u32) {
        self.core.x = x;
    }

    pub fn pc(&self) -> u8 {
        self.core.pc
    }

    fn field(reg: u32, at: u32, bits: u32) -> u32 {
        reg >> at & ((1 << bits) - 1)
    }

    /// (TX, RX) FIFO depths from the join bits: 4 + 4, or 8 + 0.
    fn depths(&self) -> (usize, usize) {
        match (
            self.shiftctrl >> shiftctrl::FJOIN_TX & 1,
            self.shiftctrl >> shiftctrl::FJOIN_RX & 1,
        ) {
            (0, 0) => (4, 4),
            (1, 0) => (8, 0),
            (0, 1) => (0, 8),
            _ => (0, 0),
        }
    }

    fn tx_depth(&self) -> usize {
        self.depths().0
    }

    fn rx_depth(&self) -> usize {
        self.depths().1
    }

    fn wrap_top(&self) -> u8 {
        Self::field(self.execctrl, execctrl::WRAP_TOP, 5) as u8
    }

    fn wrap_bottom(&self) -> u8 {
        Self::field(self.execctrl, execctrl::WRAP_BOTTOM, 5) as u8
    }

    fn jmp_pin(&self) -> u32 {
        Self::field(self.execctrl, execctrl::JMP_PIN, 5)
    }

    /// The side-set configuration instructions are decoded with
    /// (PINCTRL.SIDESET_COUNT, EXECCTRL.SIDE_PINDIR).
    fn side_set(&self) -> SideSet {
        let count = Self::field(self.pinctrl, pinctrl::SIDESET_COUNT, 3) as u8;
        let pindirs = Self::field(self.execctrl, execctrl::SIDE_PINDIR, 1) == 1;
        SideSet::new(false, count, pindirs)
    }

    fn in_base(&self) -> u32 {
        Self::field(self.pinctrl, pinctrl::IN_BASE, 5)
    }

    fn in_count(&self) -> u32 {
        match Self::field(self.shiftctrl, shiftctrl::IN_COUNT, 5) {
            0 => 32,
            n => n,
        }
    }

    /// Side-set pins: (base, count, to directions).
    fn side_pins(&self) -> (u32, u32, bool) {
        let ss = self.side_set();
        (
            Self::field(self.pinctrl, pinctrl::SIDESET_BASE, 5),
            u32::from(ss.bits()),
            ss.pindirs(),
        )
    }

    fn next_pc(&self, pc: u8) -> u8 {
        if pc == self.wrap_top() {
            self.wrap_bottom()
        } else {
            (pc + 1) % WORDS as u8
        }
    }
}

/// One PIO block: its instruction memory, window and state machines.
#[derive(Debug, Clone)]
pub struct Block {
    pub index: usize,
    instr: [u16; WORDS],
    used: u32,
    gpiobase: u32,
    pub sm: [Sm; 4],
    fdebug: u32,
    /// Output levels and enables of the GPIOs, as this block drives them
    /// (absolute GPIO numbers).
    out: u64,
    oe: u64,
}

impl Block {
    fn new(index: usize) -> Block {
        Block {
            index,
            instr: [0; WORDS],
            used: 0,
            gpiobase: 0,
            sm: [Sm::new(), Sm::new(), Sm::new(), Sm::new()],
            fdebug: 0,
            out: 0,
            oe: 0,
        }
    }

    /// Loads `words` at `origin`, as embassy-rp's `load_program` does,
    /// without relocating: the bridge loads each program at 0.
    pub fn load(&mut self, words: &[u16], origin: u8) -> Result<(), LoadError> {
        let refuse = LoadError::NoSpace {
            block: self.index,
            origin,
            words: words.len(),
        };
        let mut mask = 0u32;
        for i in 0..words.len() {
            let at = usize::from(origin) + i;
            if at >= WORDS || self.used >> at & 1 == 1 {
                return Err(refuse);
            }
            mask |= 1 << at;
        }
        for (i, w) in words.iter().enumerate() {
            self.instr[usize::from(origin) + i] = *w;
        }
        self.used |= mask;
        Ok(())
    }

    /// Words of instruction memory in use.
    pub fn words_used(&self) -> u32 {
        self.used.count_ones()
    }

    /// GPIOBASE: 0 or 16.
    pub fn set_gpiobase(&mut self, base: u32) -> Result<(), Unsupported> {
        if base != 0 && base != 16 {
            return Err(Unsupported(std::format!("GPIOBASE {base}")));
        }
        self.gpiobase = base;
        Ok(())
    }

    fn gpio(&self, index: u32) -> u32 {
        self.gpiobase + index % 32
    }

    /// Writes SMx_CLKDIV, SMx_EXECCTRL, SMx_SHIFTCTRL and SMx_PINCTRL of
    /// state machine `s`, then runs the forced instructions that set X and
    /// jump to the start ([`SmRegs::start_instructions`]), as the firmware
    /// does.
    pub fn configure(&mut self, s: usize, regs: &SmRegs) -> Result<(), Unsupported> {
        if regs.clkdiv != crate::pioregs::CLKDIV_1 {
            return Err(Unsupported(std::format!(
                "clock divider {:#x}",
                regs.clkdiv
            )));
        }
        let side = Sm::field(regs.pinctrl, pinctrl::SIDESET_COUNT, 3);
        let side_en = Sm::field(regs.execctrl, execctrl::SIDE_EN, 1);
        let auto = regs.shiftctrl & (1 << shiftctrl::AUTOPUSH | 1 << shiftctrl::AUTOPULL);
        let rx_as_regs = regs.shiftctrl & (0b11 << 14);
        if side > 5 || side_en != 0 || auto != 0 || rx_as_regs != 0 {
            return Err(Unsupported(
                "optional side-set, autopush/autopull or RX FIFO registers".into(),
            ));
        }
        let sm = &mut self.sm[s];
        sm.execctrl = regs.execctrl;
        // Changing FJOIN flushes both FIFOs.
        if (sm.shiftctrl ^ regs.shiftctrl) >> shiftctrl::FJOIN_TX & 0b11 != 0 {
            sm.tx.clear();
            sm.rx.clear();
        }
        sm.shiftctrl = regs.shiftctrl;
        sm.pinctrl = regs.pinctrl;
        for word in regs.start_instructions() {
            self.exec(s, word, 0);
        }
        Ok(())
    }

    /// SMx_INSTR: runs `word` on state machine `s` now (X, Y, the pins).
    pub fn exec(&mut self, s: usize, word: u16, seen: u64) {
        let pc = self.sm[s].core.pc;
        let jumps = matches!(
            Instruction::decode(word, self.sm[s].side_set()).map(|i| i.operands),
            Some(InstructionOperands::JMP { .. })
        );
        self.run_instr(s, word, seen, true);
        // A forced instruction other than a jump leaves the PC.
        if !jumps {
            self.sm[s].core.pc = pc;
        }
        self.sm[s].core.delay = 0;
    }

    /// Sets GPIOs `mask` (absolute) to `levels` and `dirs` as driven by this
    /// block: what the firmware does with forced `set` instructions.
    pub fn force_pins(&mut self, mask: u64, levels: u64, dirs: u64) {
        self.out = (self.out & !mask) | (levels & mask);
        self.oe = (self.oe & !mask) | (dirs & mask);
    }

    /// The CPU writes the TX FIFO of `s`: lost if full (FDEBUG.TXOVER).
    pub fn txf_write(&mut self, s: usize, word: u32) {
        let sm = &mut self.sm[s];
        if sm.tx.len() >= sm.tx_depth() {
            self.fdebug |= 1 << (fdebug::TXOVER + s as u32);
        } else {
            sm.tx.push_back(word);
        }
    }

    /// The CPU reads the RX FIFO of `s`: `None` when empty (FDEBUG.RXUNDER).
    pub fn rxf_read(&mut self, s: usize) -> Option<u32> {
        let w = self.sm[s].rx.pop_front();
        if w.is_none() {
            self.fdebug |= 1 << (fdebug::RXUNDER + s as u32);
        }
        w
    }

    /// FSTAT.TXFULL of `s`.
    pub fn tx_full(&self, s: usize) -> bool {
        self.sm[s].tx.len() >= self.sm[s].tx_depth()
    }

    /// FSTAT.TXEMPTY of `s`.
    pub fn tx_empty(&self, s: usize) -> bool {
        self.sm[s].tx.is_empty()
    }

    /// Words waiting in the RX FIFO of `s` (FLEVEL).
    /// How many words state machine `s`'s RX FIFO holds (by its join).
    pub fn rx_capacity(&self, s: usize) -> usize {
        self.sm[s].rx_depth()
    }

    pub fn rx_level(&self, s: usize) -> usize {
        self.sm[s].rx.len()
    }

    /// FDEBUG.
    pub fn fdebug(&self) -> u32 {
        self.fdebug
    }

    /// Clears FDEBUG bits (write 1 to clear).
    pub fn clear_fdebug(&mut self, bits: u32) {
        self.fdebug &= !bits;
    }

    /// Drains both FIFOs of `s`: what writing SHIFTCTRL with FJOIN_RX
    /// flipped, then back, does (the firmware's way).
    pub fn flush(&mut self, s: usize) {
        self.sm[s].tx.clear();
        self.sm[s].rx.clear();
    }

    /// Writes SMx_SHIFTCTRL alone (FJOIN changes flush the FIFOs).
    pub fn write_shiftctrl(&mut self, s: usize, value: u32) {
        let sm = &mut self.sm[s];
        if (sm.shiftctrl ^ value) >> shiftctrl::FJOIN_TX & 0b11 != 0 {
            sm.tx.clear();
            sm.rx.clear();
        }
        sm.shiftctrl = value;
    }

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
    fn step(&mut self, s: usize, seen: u64) {
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
    fn run_instr(&mut self, s: usize, word: u16, seen: u64, forced: bool) {
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
                        if block {
                            stall = true;
                            self.fdebug |= 1 << (fdebug::RXSTALL + s as u32);
                        } else {
                            sm.core.isr = 0;
                            sm.core.isr_count = 0;
                        }
                    } else {
                        sm.rx.push_back(sm.core.isr);
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
    fn quiet(&self, s: usize, seen: u64) -> Option<(u64, u32)> {
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

/// What a GPIO's output comes from (its FUNCSEL).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// Not connected to anything inside the chip: an input only.
    Null,
    /// The CPU's SIO.
    Sio,
    /// PIO block `n`.
    Pio(usize),
}

/// What drives the GPIOs from outside: the board around the RP2350.
pub trait Outside {
    /// The outside's levels and which GPIOs it drives, at `cycle`, given
    /// the levels and enables the RP2350 drives (after this cycle's
    /// instructions).
    fn drive(&mut self, cycle: u64, out: u64, oe: u64) -> (u64, u64);
    /// The next cycle after `cycle` at which the outside may change what it
    /// drives with the RP2350's pins unchanged.
    fn next_change(&mut self, cycle: u64) -> Option<u64>;
}

/// A DMA channel that moves each word a state machine pushes from its RX
/// FIFO into a ring, endlessly (`crate::ring`): a word a cycle, the
/// cycle after it was pushed (its DREQ).
#[derive(Debug, Clone)]
pub struct RingDma {
    pub block: usize,
    pub sm: usize,
    pub ring: std::vec::Vec<u32>,
    /// Where it writes next (`WRITE_ADDR`, as an index).
    pub write: usize,
}

/// The RP2350's PIO blocks and GPIOs, and the cycle count.
#[derive(Debug, Clone)]
pub struct World {
    pub blocks: [Block; 3],
    /// DMA channels from RX FIFOs to rings.
    pub dma: std::vec::Vec<RingDma>,
    pub func: [Func; GPIOS as usize],
    pub sio_out: u64,
    pub sio_oe: u64,
    /// Pad levels now, and one and two cycles ago (the synchroniser).
    pads: u64,
    sync1: u64,
    sync2: u64,
    /// Cycles run.
    pub cycle: u64,
    /// Cycles the pads have been unchanged.
    steady: u64,
    /// Cycles skipped ahead and cycles stepped one by one.
    pub skipped: u64,
    pub stepped: u64,
}

impl Default for World {
    fn default() -> Self {
        World::new()
    }
}

impl World {
    pub fn new() -> World {
        World {
            blocks: [Block::new(0), Block::new(1), Block::new(2)],
            dma: std::vec::Vec::new(),
            func: [Func::Null; GPIOS as usize],
            sio_out: 0,
            sio_oe: 0,
            pads: 0,
            sync1: 0,
            sync2: 0,
            cycle: 0,
            steady: 0,
            skipped: 0,
            stepped: 0,
        }
    }

    /// The levels and enables the RP2350 drives, by each GPIO's FUNCSEL.
    pub fn driven(&self) -> (u64, u64) {
        let mut out = 0u64;
        let mut oe = 0u64;
        for (g, f) in self.func.iter().enumerate() {
            let (o, e) = match f {
                Func::Null => (0, 0),
                Func::Sio => (self.sio_out, self.sio_oe),
                Func::Pio(b) => (self.blocks[*b].out, self.blocks[*b].oe),
            };
            out |= o & 1 << g;
            oe |= e & 1 << g;
        }
        (out, oe)
    }

    /// The pads' levels now (what the CPU's SIO reads, unsynchronised).
    pub fn pads(&self) -> u64 {
        self.pads
    }

    /// What the state machines read this cycle: the pads two cycles ago.
    pub fn seen(&self) -> u64 {
        self.sync2
    }

    /// CTRL of block `b`: enables and disables its state machines and,
    /// through NEXT_PIO_MASK, the next block's, on the same cycle; restarts
    /// those it is told to.
    pub fn write_ctrl(&mut self, b: usize, value: u32) {
        let en = value >> ctrl::SM_ENABLE & 0xF;
        let restart = value >> ctrl::SM_RESTART & 0xF;
        for s in 0..4 {
            self.blocks[b].sm[s].enabled = en >> s & 1 == 1;
            if restart >> s & 1 == 1 {
                let c = &mut self.blocks[b].sm[s].core;
                c.isr = 0;
                c.isr_count = 0;
                c.osr_count = 32;
                c.delay = 0;
                self.blocks[b].sm[s].stalled = false;
            }
        }
        let next = (b + 1) % 3;
        let mask = value >> ctrl::NEXT_PIO_MASK & 0xF;
        let enable = value >> ctrl::NEXTPREV_SM_ENABLE & 1 == 1;
        let disable = value >> ctrl::NEXTPREV_SM_DISABLE & 1 == 1;
        for s in 0..4 {
            if mask >> s & 1 == 1 {
                if disable {
                    self.blocks[next].sm[s].enabled = false;
                } else if enable {
                    self.blocks[next].sm[s].enabled = true;
                }
            }
        }
    }

    fn settle(&mut self, outside: &mut dyn Outside) {
        let (out, oe) = self.driven();
        let (ext, ext_driven) = outside.drive(self.cycle, out, oe);
        // A pad nobody drives keeps its level (bus hold); one both sides
        // drive reads what the RP2350 drives (the outside reports the
        // contention itself).
        let pads = (out & oe) | (ext & ext_driven & !oe) | (self.pads & !oe & !ext_driven);
        if pads != self.pads {
            self.steady = 0;
        }
        self.pads = pads;
    }

    /// One system clock cycle.
    pub fn step(&mut self, outside: &mut dyn Outside) {
        let seen = self.sync2;
        for b in 0..3 {
            for s in 0..4 {
                self.blocks[b].step(s, seen);
            }
        }
        for d in &mut self.dma {
            let b = &mut self.blocks[d.block];
            if b.rx_level(d.sm) > 0 {
                if let Some(w) = b.rxf_read(d.sm) {
                    let n = d.ring.len().max(1);
                    d.ring[d.write % n] = w;
                    d.write = (d.write + 1) % n;
                }
            }
        }
        self.cycle += 1;
        self.stepped += 1;
        self.sync2 = self.sync1;
        self.sync1 = self.pads;
        self.steady += 1;
        self.settle(outside);
    }

    /// The pads after the CPU changed the SIO outputs or a block's pins.
    pub fn cpu_wrote(&mut self, outside: &mut dyn Outside) {
        self.settle(outside);
    }

    /// Runs to cycle `until`, skipping ahead where nothing can change.
    pub fn run_until(&mut self, until: u64, outside: &mut dyn Outside) {
        while self.cycle < until {
            if self.steady >= 2 {
                let horizon = outside
                    .next_change(self.cycle)
                    .map_or(until, |c| c.min(until));
                if horizon > self.cycle + 8 && self.skip(horizon - self.cycle) {
                    self.settle(outside);
                    continue;
                }
            }
            self.step(outside);
        }
    }

    /// Skips up to `room` cycles if every state machine is quiet.
    fn skip(&mut self, room: u64) -> bool {
        let seen = self.sync2;
        // A word a DMA channel has yet to move.
        if self
            .dma
            .iter()
            .any(|d| self.blocks[d.block].rx_level(d.sm) > 0)
        {
            return false;
        }
        let mut loops: Vec<(usize, usize, u64, u32)> = Vec::new();
        let mut period = 1u64;
        for b in 0..3 {
            for s in 0..4 {
                match self.blocks[b].quiet(s, seen) {
                    None => return false,
                    Some((k, dx)) => {
                        if self.blocks[b].sm[s].enabled && !self.blocks[b].sm[s].stalled {
                            period = lcm(period, k);
                            loops.push((b, s, k, dx));
                        }
                    }
                }
            }
        }
        let mut turns = room / period;
        for &(b, s, k, dx) in &loops {
            let per = u64::from(dx) * (period / k);
            // Every `jmp x--` skipped must see X non-zero.
            let x = u64::from(self.blocks[b].sm[s].core.x);
            if let Some(t) = x.saturating_sub(1).checked_div(per) {
                turns = turns.min(t);
            }
        }
        if turns == 0 {
            return false;
        }
        let cycles = turns * period;
        for &(b, s, k, dx) in &loops {
            let n = u64::from(dx) * (cycles / k);
            let c = &mut self.blocks[b].sm[s].core;
            c.x = c.x.wrapping_sub(n as u32);
        }
        self.cycle += cycles;
        self.skipped += cycles;
        self.steady += cycles;
        true
    }
}

/// An outside given by a function of (cycle, levels, enables) that may
/// change on any cycle: for tests of one program.
#[derive(Debug)]
pub struct Inputs<F>(pub F);

impl<F: FnMut(u64, u64, u64) -> (u64, u64)> Outside for Inputs<F> {
    fn drive(&mut self, cycle: u64, out: u64, oe: u64) -> (u64, u64) {
        (self.0)(cycle, out, oe)
    }
    fn next_change(&mut self, cycle: u64) -> Option<u64> {
        Some(cycle + 1)
    }
}

impl World {
    /// A world with `words` loaded at address 0 of block `b` (GPIOBASE
    /// `gpiobase`), its state machine `s` configured with `regs` and
    /// enabled, its OUT pins given to the block: for tests of one program.
    pub fn with_program(b: usize, gpiobase: u32, words: &[u16], s: usize, regs: &SmRegs) -> World {
        let mut w = World::new();
        w.blocks[b].set_gpiobase(gpiobase).expect("0 or 16");
        w.blocks[b].load(words, 0).expect("fits");
        w.blocks[b].configure(s, regs).expect("modelled");
        for g in 0..GPIOS as usize {
            w.func[g] = Func::Pio(b);
        }
        w.write_ctrl(b, 1 << s);
        w
    }

    /// Reads the RX FIFO of state machine `s` of block `b`.
    pub fn pull(&mut self, b: usize, s: usize) -> Option<u32> {
        (self.blocks[b].rx_level(s) > 0)
            .then(|| self.blocks[b].rxf_read(s))
            .flatten()
    }
}

fn lcm(a: u64, b: u64) -> u64 {
    fn gcd(a: u64, b: u64) -> u64 {
        if b == 0 {
            a
        } else {
            gcd(b, a % b)
        }
    }
    a / gcd(a, b) * b
}
