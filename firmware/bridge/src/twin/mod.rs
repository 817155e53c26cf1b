//! The board twin: the RP2350 image's board code ([`crate::board`]) on a
//! model of the RP2350's PIO blocks and GPIOs ([`pio`]) wired pin by pin to
//! the reference chip model ([`chip`]).
//!
//! [`Twin`] is the hardware layer ([`Hal`]): it boots the PIO blocks as
//! the image does, from the same programs and register values
//! ([`crate::programs`], [`crate::pioregs`]), and each call the board code
//! makes costs the CPU some cycles, during which the state machines and
//! the chip run. The cost is fixed ([`Twin::cpu_cycles`]), plus random
//! gaps when asked ([`Twin::with_gaps`]), so that FIFO limits are met for
//! real.

pub mod chip;
pub mod pio;
#[cfg(test)]
mod tests;

use crate::bus::BusTiming;
use crate::hal::{Counter, Hal};
use crate::pins;
use crate::pioregs::{self, block, fdebug, START_COUNTERS, STOP_COUNTERS};
use crate::programs::{self, Loaded};
use chip::ChipSide;
use pio::{Func, World};
use ppmc_core::emu::{Board as Model, ModelConfig};
use ppmc_core::protocol::Straps;
use std::format;
use std::string::String;

/// The RP2350's system clock in the twin, as embassy-rp sets it up.
pub const SYSCLK_HZ: u32 = 150_000_000;

/// Cycles one hardware-layer call costs the CPU by default: a PAC
/// register access and the loop around it.
pub const CPU_CYCLES: u64 = 12;

/// Cycles a reading of the bridge's clock costs the RP2350 image
/// (`Hal::cycles`: the cycle counter, extended): some 6.
pub const CLOCK_CYCLES: u64 = 6;

/// Cycles setting the clock right costs (`Hal::resync`: interrupts off,
/// the cycle counter, the 1 MHz timer's two words, the clock's 64-bit
/// arithmetic): some 64.
pub const RESYNC_CYCLES: u64 = 64;

/// The twin's hardware: the RP2350's PIO and GPIOs, the board around it.
#[derive(Debug)]
pub struct Twin {
    pub world: World,
    pub chip: ChipSide,
    layout: [Loaded; 3],
    /// Cycles each call costs.
    pub cpu_cycles: u64,
    /// Random extra cycles per call: (state, at most).
    gaps: Option<(u64, u64)>,
    /// Clock readings not yet paid for: the world runs them off at the next
    /// call that spends.
    owed: core::cell::Cell<u64>,
    /// Cycles a pass of [`Hal::idle`]'s loop takes (read the pins and the
    /// capture FIFOs' levels, compare): how late after a change it returns.
    pub idle_step: u64,
}

impl Twin {
    /// The twin with a chip of `straps` and `cfg`, booted as the RP2350
    /// image boots: programs loaded, state machines configured, pins set
    /// (levels before directions), the buffers enabled.
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Twin, String> {
        let model = Model::new(straps, cfg).map_err(|e| format!("{e}"))?;
        let mut t = Twin {
            world: World::new(),
            chip: ChipSide::new(model, SYSCLK_HZ),
            layout: programs::layout(),
            cpu_cycles: CPU_CYCLES,
            gaps: None,
            idle_step: 2 * CPU_CYCLES,
            owed: core::cell::Cell::new(0),
        };
        t.boot().map_err(|e| format!("{e:?}"))?;
        Ok(t)
    }

    /// Adds a random gap of up to `max` cycles to every call (seeded).
    pub fn with_gaps(mut self, seed: u64, max: u64) -> Twin {
        self.gaps = Some((seed | 1, max));
        self
    }

    fn boot(&mut self) -> Result<(), std::boxed::Box<dyn core::fmt::Debug>> {
        let w = &mut self.world;
        for (b, p) in self.layout.iter().enumerate() {
            w.blocks[b]
                .set_gpiobase(block::GPIOBASE[b])
                .map_err(|e| std::boxed::Box::new(e) as _)?;
            w.blocks[b]
                .load(p.words(), 0)
                .map_err(|e| std::boxed::Box::new(e) as _)?;
        }
        // SIO outputs: levels first, then directions (issue 28): the chip's
        // inputs released, RESET* high, the buffers off until all is set.
        let mut sio_pins: u64 = 1 << pins::RESET | 1 << pins::CAPTURE_OE | 1 << pins::DRIVE_EN;
        for g in pins::INPUTS {
            sio_pins |= 1 << g;
        }
        let released: u64 = sio_pins & !(1 << pins::DRIVE_EN) & !(1 << pins::CAPTURE_OE);
        w.sio_out = released | 1 << pins::CAPTURE_OE;
        for g in 0..48 {
            if sio_pins >> g & 1 == 1 {
                w.func[g] = Func::Sio;
            }
        }
        w.sio_oe = sio_pins;
        // The bus player: idle levels, then directions, then the config.
        let player = pioregs::bus_player(&self.layout[0]);
        w.blocks[0]
            .configure(0, &player)
            .map_err(|e| std::boxed::Box::new(e) as _)?;
        let bus_mask: u64 = (1 << pins::BUS_COUNT) - 1;
        let idle = u64::from(crate::bus::IDLE >> 8) << pins::A0;
        w.blocks[0].force_pins(bus_mask, idle, 0);
        w.blocks[0].force_pins(bus_mask, idle, bus_mask);
        for g in 0..pins::BUS_COUNT {
            w.func[g as usize] = Func::Pio(0);
        }
        w.write_ctrl(0, 1);
        // The buffers: the chip's outputs in, then the bridge's out.
        w.sio_out &= !(1 << pins::CAPTURE_OE);
        w.sio_out |= 1 << pins::DRIVE_EN;
        let chip = &mut self.chip;
        w.cpu_wrote(chip);
        w.run_until(w.cycle + 4, chip);
        Ok(())
    }

    /// Spends `n` CPU cycles (plus a gap, if any): the hardware runs.
    fn spend(&mut self, n: u64) {
        let mut n = n + self.owed.take();
        if let Some((s, max)) = self.gaps.as_mut() {
            *s ^= *s << 13;
            *s ^= *s >> 7;
            *s ^= *s << 17;
            if *max > 0 {
                n += *s % (*max + 1);
            }
        }
        let until = self.world.cycle + n;
        self.world.run_until(until, &mut self.chip);
    }

    /// Stops the bus player, as a stuck state machine would (a test of the
    /// board code's deadlines).
    pub fn stop_bus_player(&mut self) {
        self.world.write_ctrl(0, 0);
    }
}

impl Hal for Twin {
    fn sysclk_hz(&self) -> u32 {
        SYSCLK_HZ
    }

    fn cycles(&self) -> u64 {
        // The reading costs its cycles; it says the time at its end.
        let owed = self.owed.get() + CLOCK_CYCLES;
        self.owed.set(owed);
        self.world.cycle + owed
    }

    fn resync(&mut self) {
        self.spend(RESYNC_CYCLES);
    }

    fn bus_tx_full(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].tx_full(0)
    }

    fn bus_push(&mut self, word: u32) -> u64 {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].txf_write(0, word);
        self.world.cycle
    }

    fn bus_tx_empty(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        self.world.blocks[block::BUS].tx_empty(0)
    }

    fn bus_pull(&mut self) -> Option<u32> {
        self.spend(self.cpu_cycles);
        let b = &mut self.world.blocks[block::BUS];
        (b.rx_level(0) > 0).then(|| b.rxf_read(0)).flatten()
    }

    fn capture_pull(&mut self, c: Counter) -> Option<u32> {
        self.spend(self.cpu_cycles);
        let (b, s) = pioregs::counter_sm(c);
        let b = &mut self.world.blocks[b];
        (b.rx_level(s) > 0).then(|| b.rxf_read(s)).flatten()
    }

    fn capture_stalled(&mut self) -> bool {
        self.spend(self.cpu_cycles);
        let mut stalled = false;
        for b in [block::POUT, block::PINS] {
            let mask = pioregs::COUNTERS[b] << fdebug::RXSTALL;
            stalled |= self.world.blocks[b].fdebug() & mask != 0;
            self.world.blocks[b].clear_fdebug(mask);
        }
        stalled
    }

    fn start_counters(&mut self) -> u64 {
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(block::POUT, STOP_COUNTERS);
        let pads = self.world.pads();
        let level = |g: u32| pads >> g & 1 == 1;
        let pout = pioregs::pout_counter(&self.layout[1], level(pins::POUT));
        let others = pioregs::pin_counters(
            &self.layout[2],
            [pins::INT, pins::HOLD, pins::AUX].map(level),
        );
        for (b, s, regs) in [
            (block::POUT, 0, pout),
            (block::PINS, 0, others[0]),
            (block::PINS, 1, others[1]),
            (block::PINS, 2, others[2]),
        ] {
            // FJOIN_RX flipped and back: the FIFOs flushed.
            let blk = &mut self.world.blocks[b];
            blk.write_shiftctrl(s, regs.shiftctrl ^ 1 << pioregs::shiftctrl::FJOIN_RX);
            blk.write_shiftctrl(s, regs.shiftctrl);
            // Refused configurations are a bug of ours: the tests catch it.
            self.world.blocks[b]
                .configure(s, &regs)
                .unwrap_or_else(|e| panic!("the counters' configuration: {e:?}"));
        }
        for b in [block::POUT, block::PINS] {
            // Internal state cleared, as the image does; then the stalls.
            self.world.write_ctrl(b, pioregs::restart_counters(b));
            self.world.blocks[b].clear_fdebug(pioregs::COUNTERS[b] << fdebug::RXSTALL);
        }
        self.spend(self.cpu_cycles);
        self.world.write_ctrl(block::POUT, START_COUNTERS);
        self.world.cycle
    }

    fn set_input(&mut self, i: usize, high: bool) {
        self.spend(self.cpu_cycles);
        let g = pins::INPUTS[i];
        self.world.sio_out = (self.world.sio_out & !(1 << g)) | u64::from(high) << g;
        self.world.cpu_wrote(&mut self.chip);
    }

    fn set_reset(&mut self, high: bool) {
        self.spend(self.cpu_cycles);
        let g = pins::RESET;
        self.world.sio_out = (self.world.sio_out & !(1 << g)) | u64::from(high) << g;
        self.world.cpu_wrote(&mut self.chip);
    }

    fn read_high_pins(&mut self) -> u16 {
        self.spend(self.cpu_cycles);
        (self.world.pads() >> 32) as u16
    }

    fn idle(&mut self, until: u64) -> u64 {
        // The CPU's loop looks every `idle_step` cycles: it sees the next
        // thing the outside does (a POUT edge, a pin change) on its first
        // pass after, and the pass before saw nothing yet. Or it is `until`.
        use pio::Outside;
        self.spend(0);
        let now = self.world.cycle;
        let step = self.idle_step.max(1);
        let next = self.chip.next_change(now).unwrap_or(u64::MAX);
        let seen = now.saturating_add(next.saturating_sub(now).div_ceil(step).saturating_mul(step));
        let to = until.min(seen).max(now + 1);
        self.world.run_until(to, &mut self.chip);
        if to == seen {
            to - step
        } else {
            to
        }
    }
}

/// The board code on the twin: what `firmware/run-twin` serves.
pub type TwinBoard = crate::board::Board<Twin>;

/// The board code on a fresh twin with the default bus timing.
pub fn board(straps: Straps, cfg: ModelConfig) -> Result<TwinBoard, String> {
    Ok(crate::board::Board::new(
        Twin::new(straps, cfg)?,
        BusTiming::DEFAULT,
        straps,
    ))
}
