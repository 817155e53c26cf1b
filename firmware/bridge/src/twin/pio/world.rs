//! The RP2350's PIO blocks and GPIOs together ([`World`]): each GPIO's
//! FUNCSEL, the pads settled against what the board drives from outside
//! ([`Outside`]), the inputs' synchroniser, the DMA channels that move
//! the counters' words into rings ([`Dma`]), and the run to a cycle,
//! skipping ahead where nothing can change.

use super::block::Block;
use super::dma::Dma;
use crate::pioregs::{ctrl, SmRegs};
use std::vec::Vec;

/// GPIOs of an RP2350B.
pub const GPIOS: u32 = 48;

/// The pads whose floating the twin models: those the board code reads
/// (the capture inputs, GPIO 32-46, and VSEL's, GPIO 27). A pad nobody
/// reads (GPIO 28-31, 47) is left at its level, as if held: what it reads
/// changes nothing.
pub const READ_PADS: u64 = 0x7FFF << 32 | 1 << 27;

/// Cycles a floating pad keeps a level: it then reads a level of its own,
/// drawn afresh every such span (a model's choice: the datasheet gives no
/// rate for a floating input's drift, RP2350-E9, only that it is not
/// held).
pub const DRIFT_CYCLES: u64 = 1 << 14;

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

/// The RP2350's PIO blocks and GPIOs, and the cycle count.
#[derive(Debug, Clone)]
pub struct World {
    pub blocks: [Block; 3],
    /// The DMA block: channels from RX FIFOs to rings (`dma.rs`).
    pub dma: Dma,
    pub func: [Func; GPIOS as usize],
    pub sio_out: u64,
    pub sio_oe: u64,
    /// The pads' pull-ups and pull-downs (PADS_BANK0 GPIOx PUE, PDE): a
    /// pad nothing drives reads its pull, floats with none, and keeps
    /// its level with both (the bus keeper).
    pub pull_up: u64,
    pub pull_down: u64,
    /// The pads that float now (no driver, no pull, read by the board).
    floating: u64,
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
            dma: Dma::new(),
            func: [Func::Null; GPIOS as usize],
            sio_out: 0,
            sio_oe: 0,
            pull_up: 0,
            pull_down: 0,
            floating: 0,
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
        // A pad nobody drives reads its pull, keeps its level with both
        // pulls (the bus keeper) or when nobody reads it, and floats
        // otherwise; one both sides drive reads what the RP2350 drives
        // (the outside reports the contention itself).
        let undriven = !oe & !ext_driven;
        let up = undriven & self.pull_up & !self.pull_down;
        let kept = undriven & (self.pull_up & self.pull_down | !READ_PADS);
        self.floating = undriven & !self.pull_up & !self.pull_down & READ_PADS;
        let drift = if self.floating != 0 { self.drift() } else { 0 };
        let pads = (out & oe)
            | (ext & ext_driven & !oe)
            | up
            | (self.pads & kept)
            | (drift & self.floating);
        if pads != self.pads {
            self.steady = 0;
        }
        self.pads = pads;
    }

    /// What each floating pad reads in this span of [`DRIFT_CYCLES`]:
    /// drawn from the pad's number and the span's (a hash), so that runs
    /// repeat.
    fn drift(&self) -> u64 {
        let span = self.cycle / DRIFT_CYCLES;
        let mut x = span.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 29;
        x
    }

    /// The next cycle at which a floating pad may read another level.
    fn next_drift(&self) -> Option<u64> {
        (self.floating != 0).then(|| (self.cycle / DRIFT_CYCLES + 1) * DRIFT_CYCLES)
    }

    /// One system clock cycle.
    pub fn step(&mut self, outside: &mut dyn Outside) {
        let seen = self.sync2;
        for b in 0..3 {
            for s in 0..4 {
                self.blocks[b].step(s, seen);
            }
        }
        self.dma.step(&mut self.blocks);
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
                // A floating pad drifts at a span's end.
                let horizon = self.next_drift().map_or(horizon, |d| d.min(horizon));
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
        // A word a DMA channel has yet to move, a DREQ to count.
        if !self.dma.quiet(&self.blocks) {
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
