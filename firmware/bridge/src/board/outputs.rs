//! The outputs the CPU samples (S1..S5, AUXO0..3, DIR) as pin changes in
//! the record, stop switching told from steps, and the pins as a pin
//! read reports them.

use super::Board;
use crate::hal::{Counter, Hal};
use crate::pins;
use ppmc_core::protocol::{Direction, OutputLogic, Pin, Pins};
use ppmc_core::time::Instant;

/// Phases that go off and on again within this (ticks at 75 MHz: 1 ms)
/// are being chopped (stop switching), not switched.
const CHOP_TICKS: u64 = 75_000;

/// S1..S5 (S1 in bit 4), AUXO0..3 asserted (bit i: AUXOi) and DIR, from
/// [`Hal::read_high_pins`]'s word.
fn sampled_levels(word: u16) -> (u8, u8, bool) {
    let s = pins::S
        .iter()
        .fold(0u8, |v, g| v << 1 | u8::from(high(word, *g)));
    let auxo = pins::AUXO
        .iter()
        .enumerate()
        .fold(0u8, |v, (i, g)| v | u8::from(!high(word, *g)) << i);
    (s, auxo, high(word, pins::DIR))
}

/// GPIO `g` (32-47) in [`Hal::read_high_pins`]'s word.
fn high(word: u16, g: u32) -> bool {
    word >> (g - 32) & 1 == 1
}

impl<H: Hal> Board<H> {
    /// Records changes of the outputs the CPU samples.
    ///
    /// S1..S5 change with every step of a move; the protocol records their
    /// pattern only when it changes otherwise (initialization, excitation
    /// off), so a change with pulses since the last sample is a step and
    /// is not recorded (`stepped`: the capture took pulses since the last
    /// sample). Stop switching chops the phases off and on while
    /// stopped: toggles closer than 1 ms are recorded as SWITCHING on, and
    /// a millisecond without one as SWITCHING off. (A heuristic of the
    /// firmware, not yet checked on hardware: docs/bridge-hardware.md.)
    pub(super) fn sample(&mut self, word: u16, at: Instant, now: u64, stepped: bool) {
        let (s, auxo, dir) = sampled_levels(word);
        if s != self.last_s {
            let (was, is) = (self.energized(self.last_s), self.energized(s));
            let toggle = was == 0 || is == 0;
            // Only an initialization that asked for it makes the chip
            // chop (Section 3-2, bit 5), never before the first one.
            // A toggle before the last chip reset is no partner: the
            // phases an initialization right after a reset turns on are
            // not chopping.
            let chopping = toggle
                && self.tracker.stop_switching()
                && self
                    .last_toggle
                    .is_some_and(|t| now.saturating_sub(t) < CHOP_TICKS);
            // A toggle while the chip was not asked to chop (before the
            // initialization that asks, after a software reset) is no
            // partner either.
            if toggle {
                self.last_toggle = self.tracker.stop_switching().then_some(now);
            }
            self.last_s = s;
            if chopping {
                if !self.switching {
                    self.switching = true;
                    self.pin(at, Pin::Switching, 1);
                }
            } else if !stepped && self.hal.capture_peek(Counter::Pout, 0).is_none() {
                // Not a step unless a POUT word came since the drain: a CPU
                // as quick as the RP2350's reads the outputs before the
                // pulse's word is in its ring.
                self.pin(at, Pin::Phases, is);
            }
        } else if self.switching
            && self
                .last_toggle
                .is_none_or(|t| now.saturating_sub(t) >= CHOP_TICKS)
        {
            self.switching = false;
            self.pin(at, Pin::Switching, 0);
        }
        if auxo != self.last_auxo {
            self.last_auxo = auxo;
            self.pin(at, Pin::Auxo, auxo);
        }
        if dir != self.last_dir {
            self.last_dir = dir;
            self.pin(at, Pin::Dir, u8::from(dir));
        }
    }

    /// S1..S5 levels as the energized pattern, by the logic the
    /// initialization chose (negative until one did).
    pub(super) fn energized(&self, levels: u8) -> u8 {
        match self.tracker.logic() {
            Some(OutputLogic::Positive) => levels,
            _ => !levels & 0x1F,
        }
    }

    pub(super) fn pins(&mut self) -> Pins {
        self.refresh();
        let phases = self.energized(self.last_s);
        Pins {
            int: self.sm_level(Pin::Int),
            hold: self.sm_level(Pin::Hold),
            aux: self.sm_level(Pin::Aux),
            auxo: self.last_auxo,
            phases,
            phase_levels: self.last_s,
            dir: Direction::from_bit(self.last_dir),
            busy: self.busy,
        }
    }

    /// The pins as GPIO 32-47 show them in `word`, read just now.
    pub(super) fn pins_from(&self, word: u16) -> Pins {
        let (s, auxo, dir) = sampled_levels(word);
        Pins {
            int: !high(word, pins::INT),
            hold: high(word, pins::HOLD),
            aux: !high(word, pins::AUX),
            auxo,
            phases: self.energized(s),
            phase_levels: s,
            dir: Direction::from_bit(dir),
            busy: self.busy,
        }
    }

    /// The level of a PIO-captured pin: its last change.
    fn sm_level(&self, pin: Pin) -> bool {
        self.pending
            .iter()
            .rev()
            .chain(self.record.pins.iter().rev())
            .find(|p| p.pin == pin)
            .is_some_and(|p| p.value == 1)
    }
}
