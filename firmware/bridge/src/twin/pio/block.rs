//! A PIO block as the CPU sees it: 32 words of instruction memory shared
//! by its programs, GPIOBASE, its four state machines' registers and
//! FIFOs (depths from the join bits), FDEBUG, and the forced instructions
//! the firmware starts a state machine with.

use crate::pioregs::{execctrl, fdebug, pinctrl, shiftctrl, SmRegs};
use pio::{Instruction, InstructionOperands, SideSet};
use std::collections::VecDeque;
use std::string::String;

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
pub(super) struct Core {
    pub(super) pc: u8,
    pub(super) x: u32,
    pub(super) y: u32,
    pub(super) isr: u32,
    pub(super) isr_count: u32,
    pub(super) osr: u32,
    pub(super) osr_count: u32,
    pub(super) delay: u8,
}

/// One state machine.
#[derive(Debug, Clone)]
pub struct Sm {
    pub(super) core: Core,
    pub enabled: bool,
    execctrl: u32,
    pub(super) shiftctrl: u32,
    pub(super) pinctrl: u32,
    pub(super) tx: VecDeque<u32>,
    pub(super) rx: VecDeque<u32>,
    /// Stalled on the last cycle it ran.
    pub stalled: bool,
    /// Words pushed into the RX FIFO, ever: each a pulse of its DREQ
    /// (`dma.rs`).
    pub pushed: u64,
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
            pushed: 0,
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

    pub(super) fn field(reg: u32, at: u32, bits: u32) -> u32 {
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

    pub(super) fn rx_depth(&self) -> usize {
        self.depths().1
    }

    fn wrap_top(&self) -> u8 {
        Self::field(self.execctrl, execctrl::WRAP_TOP, 5) as u8
    }

    fn wrap_bottom(&self) -> u8 {
        Self::field(self.execctrl, execctrl::WRAP_BOTTOM, 5) as u8
    }

    pub(super) fn jmp_pin(&self) -> u32 {
        Self::field(self.execctrl, execctrl::JMP_PIN, 5)
    }

    /// The side-set configuration instructions are decoded with
    /// (PINCTRL.SIDESET_COUNT, EXECCTRL.SIDE_PINDIR).
    pub(super) fn side_set(&self) -> SideSet {
        let count = Self::field(self.pinctrl, pinctrl::SIDESET_COUNT, 3) as u8;
        let pindirs = Self::field(self.execctrl, execctrl::SIDE_PINDIR, 1) == 1;
        SideSet::new(false, count, pindirs)
    }

    pub(super) fn in_base(&self) -> u32 {
        Self::field(self.pinctrl, pinctrl::IN_BASE, 5)
    }

    pub(super) fn in_count(&self) -> u32 {
        match Self::field(self.shiftctrl, shiftctrl::IN_COUNT, 5) {
            0 => 32,
            n => n,
        }
    }

    /// Side-set pins: (base, count, to directions).
    pub(super) fn side_pins(&self) -> (u32, u32, bool) {
        let ss = self.side_set();
        (
            Self::field(self.pinctrl, pinctrl::SIDESET_BASE, 5),
            u32::from(ss.bits()),
            ss.pindirs(),
        )
    }

    pub(super) fn next_pc(&self, pc: u8) -> u8 {
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
    pub(super) instr: [u16; WORDS],
    used: u32,
    gpiobase: u32,
    pub sm: [Sm; 4],
    pub(super) fdebug: u32,
    /// Output levels and enables of the GPIOs, as this block drives them
    /// (absolute GPIO numbers).
    pub(super) out: u64,
    pub(super) oe: u64,
}

impl Block {
    pub(super) fn new(index: usize) -> Block {
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

    pub(super) fn gpio(&self, index: u32) -> u32 {
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

    /// Puts `word` in the RX FIFO of `s` as a `push` would (a DREQ pulse
    /// with it): for tests of what takes words from it.
    pub fn push_rx(&mut self, s: usize, word: u32) {
        self.sm[s].rx.push_back(word);
        self.sm[s].pushed += 1;
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
}
