//! The board around the twin's RP2350: the level shifters and buffers of
//! `docs/bridge-hardware.md`, and the reference chip model behind them,
//! pin by pin.
//!
//! - Towards the chip, the 74AHCT244s pass A0, CS*, RD*, WR*, the inputs and
//!   RESET* only while DRIVE_EN is high; otherwise the chip side's pulls
//!   hold CS*, RD*, WR* and the inputs high and RESET* low. A line the
//!   RP2350 leaves undriven while the buffers pass it floats: counted in
//!   [`ChipSide::floating`].
//! - D0-D7 pass the 74LVC8T245 in the direction its DIR pin (GPIO 10)
//!   sets. Both sides driving one side of it is counted in
//!   [`ChipSide::contention`].
//! - The chip takes a write on WR*'s rising edge with CS* low (A0 high:
//!   the command register), and drives D0-D7 from RD*'s falling edge with
//!   CS* low until RD* or CS* rises (A0 high: status), Section 3-1.
//! - The chip's outputs reach GPIO 32-45 through the 74LVC245s while
//!   CAPTURE_OE is low; while it is high (or undriven: pulled up) they are
//!   cut off, and TEST_GEN drives the POUT and INT* nets through the
//!   74LVC2G126 that CAPTURE_OE enables and 1 kOhm each (low while TEST_GEN
//!   is undriven: its pull-down).
//! - POUT pulses are 1 us wide (the chapter does not give their width;
//!   the edge counters only need a few cycles of each level).

use super::pio::Outside;
use crate::pins;
use ppmc_core::emu::Board as Model;
use ppmc_core::protocol::{Direction, Input, Straps};
use ppmc_core::time::Instant;
use std::collections::VecDeque;

/// POUT's pulse width in the twin.
const POUT_WIDTH_NS: u64 = 1_000;

/// The board around the RP2350, and the chip on it.
#[derive(Debug)]
pub struct ChipSide {
    model: Model,
    sysclk_hz: u32,
    /// The cycle of the chip's time zero (its last reset's release).
    epoch: u64,
    in_reset: bool,
    /// Chip-side levels of CS*, RD*, WR*, the last cycle.
    cs: bool,
    rd: bool,
    wr: bool,
    inputs_high: u16,
    /// The byte the chip drives on D0-D7 during a read strobe.
    driving: Option<u8>,
    /// The chip's D0-D7 as the shifter's A side last showed them.
    a_side: u8,
    /// The next cycle the model has something to do at.
    due: u64,
    /// Pulses seen in the record: the run, and pulses of it taken.
    run: usize,
    taken: u32,
    /// POUT's rising edges to come (cycle), and when the current pulse
    /// ends.
    rises: VecDeque<u64>,
    pout_until: u64,
    /// What the chip's outputs other than POUT, and the straps, drive onto
    /// GPIO 32-47, as levels: taken from the model whenever it changed.
    outputs: u64,
    /// Cycles (settles) on which both sides drove one side of the shifter.
    pub contention: u64,
    /// Settles on which a buffered line was left floating.
    pub floating: u64,
    /// Bus writes and reads the chip took, and the cycle of the last of
    /// each (WR*'s rise, RD*'s fall).
    pub writes: u64,
    pub reads: u64,
    pub last_write: u64,
    pub last_read: u64,
}

fn bit(v: u64, g: u32) -> bool {
    v >> g & 1 == 1
}

impl ChipSide {
    pub fn new(model: Model, sysclk_hz: u32) -> ChipSide {
        let mut c = ChipSide {
            model,
            sysclk_hz,
            epoch: 0,
            in_reset: false,
            cs: true,
            rd: true,
            wr: true,
            inputs_high: 0x3FF,
            driving: None,
            a_side: 0,
            due: u64::MAX,
            run: 0,
            taken: 0,
            rises: VecDeque::new(),
            pout_until: 0,
            outputs: 0,
            contention: 0,
            floating: 0,
            writes: 0,
            reads: 0,
            last_write: 0,
            last_read: 0,
        };
        c.outputs = c.pin_levels();
        c
    }

    /// The chip model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn straps(&self) -> Straps {
        *self.model.straps()
    }

    /// The chip's time at `cycle`.
    fn time(&self, cycle: u64) -> Instant {
        let c = u128::from(cycle.saturating_sub(self.epoch));
        Instant::from_nanos((c * 1_000_000_000 / u128::from(self.sysclk_hz)) as u64)
    }

    /// The first cycle at or after the chip's time `t`.
    fn cycle_of(&self, t: Instant) -> u64 {
        let ns = u128::from(t.as_nanos());
        let c = (ns * u128::from(self.sysclk_hz)).div_ceil(1_000_000_000);
        self.epoch + c as u64
    }

    /// Runs the model to `cycle` and takes what it output.
    fn advance(&mut self, cycle: u64) {
        if self.in_reset {
            return;
        }
        let t = self.time(cycle);
        self.model.advance_to(t);
        self.harvest(cycle);
    }

    fn harvest(&mut self, cycle: u64) {
        // New pulses: each rises at its time (never before now).
        let runs = &self.model.record().runs;
        while self.run < runs.len() {
            let r = runs[self.run];
            while self.taken < r.count {
                let i = u64::from(self.taken);
                let n = u64::from(r.count.saturating_sub(1)).max(1);
                let at = r.start + ppmc_core::time::Duration::from_nanos(r.span.as_nanos() * i / n);
                let rise = self.cycle_of(at).max(cycle);
                self.rises.push_back(rise);
                self.taken += 1;
            }
            if self.run + 1 < runs.len() {
                self.run += 1;
                self.taken = 0;
            } else {
                break;
            }
        }
        self.due = self.next_due(cycle);
        self.outputs = self.pin_levels();
    }

    fn next_due(&self, cycle: u64) -> u64 {
        let pulse = self
            .model
            .predict_pulse(self.model.move_pulses() + 1)
            .map(|t| self.cycle_of(t));
        let poll = self.model.poll_at().map(|t| self.cycle_of(t));
        // Stop switching chops S1..S5 with no event of the model's.
        let chop = self.model.next_pin_change().map(|t| self.cycle_of(t));
        [pulse, poll, chop]
            .into_iter()
            .flatten()
            .map(|c| c.max(cycle + 1))
            .min()
            .unwrap_or(u64::MAX)
    }

    /// The levels of GPIO 33-47 the chip's outputs (POUT aside) and
    /// straps give.
    fn pin_levels(&self) -> u64 {
        let p = self.model.pins();
        let mut v = 0u64;
        let mut set = |g: u32, high: bool| v |= u64::from(high) << g;
        set(pins::DIR, p.dir == Direction::Ccw);
        set(pins::INT, !p.int);
        set(pins::HOLD, p.hold);
        set(pins::AUX, !p.aux);
        for (i, g) in pins::S.iter().enumerate() {
            set(*g, p.phase_levels >> (4 - i) & 1 == 1);
        }
        for (i, g) in pins::AUXO.iter().enumerate() {
            set(*g, p.auxo >> i & 1 == 0);
        }
        let straps = self.model.straps();
        set(pins::CSEL, straps.csel_high);
        set(pins::VSEL, straps.vsel_high);
        v
    }

    fn reset(&mut self, cycle: u64) {
        self.model.reset();
        self.epoch = cycle;
        self.run = 0;
        self.taken = 0;
        self.rises.clear();
        self.pout_until = 0;
        self.driving = None;
        // The fresh model's inputs are released: levels on its pins that
        // say otherwise are applied again from the next cycle.
        self.inputs_high = 0x3FF;
        self.due = self.next_due(cycle);
        self.outputs = self.pin_levels();
    }
}

impl Outside for ChipSide {
    fn drive(&mut self, cycle: u64, out: u64, oe: u64) -> (u64, u64) {
        // What the 74AHCT244s pass to the chip.
        let drive_en = bit(oe, pins::DRIVE_EN) && bit(out, pins::DRIVE_EN);
        let buffered = |g: u32, safe: bool, floating: &mut u64| -> bool {
            if !drive_en {
                return safe;
            }
            if !bit(oe, g) {
                *floating += 1;
                return true;
            }
            bit(out, g)
        };
        let mut floating = 0;
        let cs = buffered(pins::CS, true, &mut floating);
        let rd = buffered(pins::RD, true, &mut floating);
        let wr = buffered(pins::WR, true, &mut floating);
        let a0 = buffered(pins::A0, true, &mut floating);
        let reset = buffered(pins::RESET, false, &mut floating);
        let mut inputs_high = 0u16;
        for (i, g) in pins::INPUTS.iter().enumerate() {
            inputs_high |= u16::from(buffered(*g, true, &mut floating)) << i;
        }
        if floating > 0 {
            self.floating += 1;
        }
        // The shifter: DIR high passes the RP2350's D0-D7 to the chip.
        let towards_chip = bit(oe, pins::SHIFT_DIR) && bit(out, pins::SHIFT_DIR);
        let bridge_drives_d = oe & 0xFF != 0;
        let chip_reads = !cs && !rd;
        if (!towards_chip && bridge_drives_d)
            || (towards_chip && chip_reads && self.driving.is_some())
        {
            self.contention += 1;
        }
        let d = (out & 0xFF) as u8;

        // Reset.
        if !reset && !self.in_reset {
            self.in_reset = true;
        } else if reset && self.in_reset {
            self.in_reset = false;
            self.reset(cycle);
        }
        if !self.in_reset && cycle >= self.due {
            self.advance(cycle);
        }
        // Inputs.
        if inputs_high != self.inputs_high && !self.in_reset {
            self.advance(cycle);
            for (i, input) in Input::ALL.iter().enumerate() {
                let was = self.inputs_high >> i & 1 == 1;
                let is = inputs_high >> i & 1 == 1;
                if was != is {
                    self.model.set_input(*input, !is);
                }
            }
            self.harvest(cycle);
        }
        self.inputs_high = inputs_high;
        // Strobes, Section 3-1.
        if !self.in_reset {
            if !self.wr && wr && !self.cs {
                self.advance(cycle);
                let byte = if towards_chip { d } else { self.a_side };
                if a0 {
                    self.model.write_command(byte);
                } else {
                    self.model.write_data(byte);
                }
                self.writes += 1;
                self.last_write = cycle;
                self.harvest(cycle);
            }
            if self.rd && !rd && !cs {
                self.advance(cycle);
                let byte = if a0 {
                    self.model.read_status().0
                } else {
                    self.model.read_data()
                };
                self.driving = Some(byte);
                self.reads += 1;
                self.last_read = cycle;
                self.harvest(cycle);
            }
        }
        if rd || cs {
            self.driving = None;
        }
        (self.cs, self.rd, self.wr) = (cs, rd, wr);

        // POUT.
        if cycle >= self.pout_until {
            if let Some(&r) = self.rises.front() {
                if r <= cycle {
                    self.rises.pop_front();
                    let w = (u128::from(POUT_WIDTH_NS) * u128::from(self.sysclk_hz))
                        .div_ceil(1_000_000_000) as u64;
                    self.pout_until = cycle + w;
                }
            }
        }
        // What the outside drives onto the RP2350's pins.
        let mut levels = 0u64;
        let mut driven = 0u64;
        if !towards_chip {
            if let Some(b) = self.driving {
                self.a_side = b;
            }
            levels |= u64::from(self.a_side);
            driven |= 0xFF;
        }
        let capture_on = bit(oe, pins::CAPTURE_OE) && !bit(out, pins::CAPTURE_OE);
        let chip_nets: u64 = (0x3FFF << pins::POUT) | 1 << pins::CSEL | 1 << pins::VSEL;
        if capture_on {
            let pout = u64::from(cycle < self.pout_until) << pins::POUT;
            levels |= (self.outputs | pout) & chip_nets;
            driven |= chip_nets;
        } else {
            // The 74LVC2G126 is on: it passes TEST_GEN, or the low its
            // pull-down holds when the RP2350 does not drive it.
            let g = bit(oe, pins::TEST_GEN) && bit(out, pins::TEST_GEN);
            let nets = 1u64 << pins::POUT | 1 << pins::INT;
            if g {
                levels |= nets;
            }
            driven |= nets;
        }
        (levels, driven)
    }

    fn next_change(&mut self, cycle: u64) -> Option<u64> {
        let mut next = self.due;
        if self.pout_until > cycle {
            next = next.min(self.pout_until);
        }
        if let Some(&r) = self.rises.front() {
            next = next.min(r.max(cycle + 1));
        }
        (next != u64::MAX).then_some(next)
    }
}
