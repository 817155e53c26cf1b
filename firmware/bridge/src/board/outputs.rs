//! The outputs the CPU samples (S1..S5, AUXO0..3, DIR) as pin changes in
//! the record, stop switching told from steps, and the pins as a pin
//! read reports them.

use super::Board;
use crate::hal::{Counter, Hal};
use crate::pins;
use ppmc_core::protocol::{Direction, OutputLogic, Pin, PinEvent, Pins, SWITCHING_WINDOW};
use ppmc_core::time::Instant;

/// Stop switching ends when no toggle comes for [`SWITCHING_WINDOW`]
/// (ticks at 75 MHz).
const CHOP_TICKS: u64 = SWITCHING_WINDOW.as_nanos() * 3 / 40;

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
    /// Records changes of the outputs the CPU samples: `word` now (tick
    /// `now`; a change in it stamped `at`), and `sighted`, other levels
    /// seen between this sample and the last (a status wait looks at the
    /// outputs at every pass and samples them only now and then).
    ///
    /// S1..S5 change with every step of a move; the protocol records their
    /// pattern only when it changes otherwise (initialization, excitation
    /// off), so a change with pulses since the last sample is a step and
    /// is not recorded (`stepped`: the capture took pulses since the last
    /// sample). Stop switching chops the phases off and on while the
    /// motor is stopped: from HOLD ON until BUSY rises, after an
    /// initialization that asked for it (Section 3-2, bit 5; 3-5-1). A
    /// toggle then is recorded as SWITCHING on, and HOLD off or
    /// [`SWITCHING_WINDOW`] without one as SWITCHING off. (Not yet checked
    /// on hardware: docs/bridge-hardware.md.)
    pub(super) fn sample(
        &mut self,
        word: u16,
        at: Instant,
        now: u64,
        stepped: bool,
        sighted: Option<u16>,
    ) {
        let (s, auxo, dir) = sampled_levels(word);
        // A toggle: the phases all off, or back on from it. One sighted
        // between samples counts too: sampled every 200 us, a chopping of
        // 174 us (Diagram 3-5's default) shows the sample its levels
        // changing only as the two beat, some 12 ms apart.
        let dark = |levels: u8| self.energized(levels) == 0;
        let toggled = |levels: u8| levels != self.last_s && (dark(levels) || dark(self.last_s));
        let toggle = toggled(s) || sighted.is_some_and(|w| toggled(sampled_levels(w).0));
        // HOLD's level is looked up in the record only where it matters: a
        // sample between toggles, with no chopping seen, costs no more
        // than before (the image samples in every wait).
        let may_chop =
            (toggle || self.switching) && self.tracker.stop_switching() && self.sm_level(Pin::Hold);
        if toggle && may_chop {
            self.last_toggle = Some(now);
            if !self.switching {
                self.switching = true;
                self.pin(at, Pin::Switching, 1);
            }
        } else {
            if self.switching && !may_chop {
                // Where HOLD went off (a move began, a software reset).
                let off = self.last_change(Pin::Hold).map_or(at, |p| p.at);
                self.switching_off(off.min(at));
            }
            if s != self.last_s
                && !self.switching
                && !stepped
                && self.hal.capture_peek(Counter::Pout, 0).is_none()
                && self.energized(s) != self.recorded_s
            {
                // Not a step unless a POUT word came since the drain: a
                // CPU as quick as the RP2350's reads the outputs before
                // the pulse's word is in its ring.
                self.recorded_s = self.energized(s);
                self.pin(at, Pin::Phases, self.recorded_s);
            }
        }
        self.last_s = s;
        let quiet = self
            .last_toggle
            .is_none_or(|t| now.saturating_sub(t) >= CHOP_TICKS);
        if self.switching && quiet {
            // The chopping stopped (an initialization is being processed)
            // up to a window ago.
            self.switching_off(at);
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

    /// `pin`'s last change, as far as the record and the changes on their
    /// way to it say.
    fn last_change(&self, pin: Pin) -> Option<&PinEvent> {
        self.pending
            .iter()
            .rev()
            .chain(self.record.pins.iter().rev())
            .find(|p| p.pin == pin)
    }

    /// Records SWITCHING off at `at`, or where the record already is, if
    /// later: the record stays in time order.
    fn switching_off(&mut self, at: Instant) {
        let floor = self.record.pins.last().map_or(at, |p| p.at);
        self.switching = false;
        self.last_toggle = None;
        self.pin(at.max(floor), Pin::Switching, 0);
    }

    /// The level of a PIO-captured pin: its last change.
    fn sm_level(&self, pin: Pin) -> bool {
        self.last_change(pin).is_some_and(|p| p.value == 1)
    }
}
