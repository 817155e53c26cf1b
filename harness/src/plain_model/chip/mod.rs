//! The plain model of one chip: its types, its public API (the host's
//! side of the bus, Section 3-1, and the output pins), its clock and the
//! events it fires (`mod.rs`); the firmware taking bytes, the command
//! parser and its errors, initialization, software reset and register
//! reads (`host.rs`); moves, stops, inputs and the pulse train
//! (`moves.rs`). The split follows the emulator's (`ppmc_core::emu::chip`),
//! the code does not.

use crate::emu::ModelConfig;
use crate::plain_model::commands::{Cmd, Op};
use crate::protocol::{Direction, Input, Pin, PinEvent, Pins, Straps};
use crate::time::{Duration, Instant};
use std::collections::VecDeque;

mod host;
mod moves;

/// Pulses the model puts out before it gives up on an input: a fuzz input
/// that starts a 16,777,216-step move and waits for it would otherwise run
/// for minutes. [`PlainChip::exhausted`] says when it was reached; the
/// differential check then stops comparing.
pub const PULSE_BUDGET: u64 = 200_000;

const MOTOR_PHASES: [u32; 4] = [0, 3, 4, 5];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Event {
    /// The move's next pulse.
    Pulse {
        id: u64,
    },
    BusyRise {
        id: u64,
    },
    /// BUSY falls (and INT* asserts, unless masked) after a move.
    BusyFall {
        id: u64,
    },
    /// A deceleration (Decelerating Stop, L3/L4) begins.
    Decelerate {
        id: u64,
        limit: bool,
    },
    HoldOn {
        epoch: u64,
    },
    /// Initialization sets the phase outputs.
    PhasesSet {
        epoch: u64,
    },
    /// The first initialization is complete: HOLD on, switching may run.
    InitDone {
        epoch: u64,
    },
    /// The next output byte is in the data register.
    ObfReady,
    Aux(bool),
    Auxo(u8),
    ExcitationOff {
        epoch: u64,
    },
}

/// What an initialization set up (Section 3-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Setup {
    rl: u8,
    rh: u8,
    pa: u32,
    external: bool,
    switching: bool,
}

/// The part of an initialization frozen until software reset (3-2-1 (3)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Winding {
    phases: u32,
    half: bool,
    positive: bool,
}

impl Winding {
    fn steps(self) -> u32 {
        if self.half {
            2 * self.phases
        } else {
            self.phases
        }
    }

    /// Energized phases at a step, S1 in bit 4 (notes N15).
    fn pattern(self, step: u32) -> u8 {
        let n = self.phases;
        let s = step % self.steps();
        let bit = |i: u32| 0b1_0000u8 >> (i % n);
        if !self.half {
            bit(s) | bit(s + 1)
        } else if n == 5 {
            // 2-3 phase: S1S2, S1S2S3, S2S3, ...
            let base = bit(s / 2) | bit(s / 2 + 1);
            if s % 2 == 0 {
                base
            } else {
                base | bit(s / 2 + 2)
            }
        } else if s % 2 == 0 {
            bit(s / 2)
        } else {
            bit(s / 2) | bit(s / 2 + 1)
        }
    }
}

#[derive(Debug, Clone)]
struct Move {
    id: u64,
    op: Op,
    ccw: bool,
    masked: bool,
    pout: bool,
    /// Steps asked for.
    steps: u32,
    /// Where the move will end, in pulses: `steps` unless a deceleration
    /// brought it closer.
    end: u32,
    emitted: u32,
    /// Ramped moves: the speed index of the interval being timed (-1
    /// before the first pulse).
    index: i64,
    /// Constant-rate moves: their period.
    constant: Option<u64>,
    tclock: Option<u64>,
    /// A deceleration is pending or running (error 7, notes N6).
    decelerating: bool,
    /// Why it stopped, in finish-status bits 3-6.
    cause: u8,
    /// When its final byte was written (the firmware's time base).
    base: u64,
    last_pulse: Option<u64>,
    /// No more pulses: it waits for BUSY to fall.
    over: bool,
}

/// The plain model of one chip, from power-on reset.
#[derive(Debug, Clone)]
pub struct PlainChip {
    straps: Straps,
    cfg: ModelConfig,
    now: u64,
    events: Vec<(u64, u64, Event)>,
    seq: u64,

    // Host interface (3-1).
    /// The byte in the input buffer: value, is it a command, written when.
    inbuf: Option<(u8, bool, u64)>,
    /// When the firmware takes the waiting byte (if not starved).
    take_at: Option<u64>,
    /// The firmware is busy until then (notes N12).
    free_at: u64,
    /// The firmware cannot serve the host: the period being timed is over
    /// the speed limit (notes N7).
    starved: bool,
    /// Status bits 7-4.
    field: u8,
    /// The command waiting for data bytes, and the bytes so far.
    pending: Option<(Cmd, Vec<u8>)>,
    out: VecDeque<u8>,
    obf: bool,
    latch: u8,

    // Initialization (3-2).
    setup: Option<Setup>,
    winding: Option<Winding>,
    /// The winding the phase outputs show (a software reset cancels the
    /// winding before the phases go off, notes N36).
    shown: Option<Winding>,
    positive: bool,
    epoch: u64,
    /// An initialization is being processed (no stop switching).
    initializing: bool,
    ton: u64,
    toff: u64,

    // Outputs.
    busy: bool,
    int: bool,
    hold: bool,
    hold_epoch: u64,
    aux: bool,
    auxo: u8,
    ccw: bool,
    step: u32,
    energized: bool,
    switching_since: Option<u64>,

    // Inputs and results.
    inputs: u16,
    finish: u8,
    remaining: u32,
    mv: Option<Move>,
    move_seq: u64,

    pulses: Vec<(Instant, Direction)>,
    pins: Vec<PinEvent>,
    exhausted: bool,
}

impl PlainChip {
    pub fn new(straps: Straps, cfg: ModelConfig) -> PlainChip {
        let ton = straps.firmware_time(cfg.switching_on).as_nanos();
        let toff = straps.firmware_time(cfg.switching_off).as_nanos();
        PlainChip {
            straps,
            cfg,
            now: 0,
            events: Vec::new(),
            seq: 0,
            inbuf: None,
            take_at: None,
            free_at: 0,
            starved: false,
            field: 0,
            pending: None,
            out: VecDeque::new(),
            obf: false,
            latch: 0,
            setup: None,
            winding: None,
            shown: None,
            positive: false,
            epoch: 0,
            initializing: false,
            ton,
            toff,
            busy: false,
            int: false,
            hold: false,
            hold_epoch: 0,
            aux: false,
            auxo: 0,
            ccw: false,
            step: 0,
            energized: false,
            switching_since: None,
            inputs: 0,
            finish: 0,
            remaining: 0,
            mv: None,
            move_seq: 0,
            pulses: Vec::new(),
            pins: Vec::new(),
            exhausted: false,
        }
    }

    pub fn now(&self) -> Instant {
        Instant::from_nanos(self.now)
    }

    /// Every pulse so far, one by one.
    pub fn pulses(&self) -> &[(Instant, Direction)] {
        &self.pulses
    }

    /// Every change of an output pin outside pulse stepping, in the
    /// emulator's [`Pin`] terms.
    pub fn pin_events(&self) -> &[PinEvent] {
        &self.pins
    }

    /// Whether the model stopped at [`PULSE_BUDGET`].
    pub fn exhausted(&self) -> bool {
        self.exhausted
    }

    // ---- the host's side of the bus (3-1) ----

    pub fn write_command(&mut self, byte: u8) {
        self.write(byte, true);
    }

    pub fn write_data(&mut self, byte: u8) {
        self.write(byte, false);
    }

    fn write(&mut self, byte: u8, command: bool) {
        // 3-1-1 (2): a byte written while IBF = 1 deletes the one waiting.
        // Every byte is taken no sooner than 6 us after its own write
        // (N11).
        let pickup = self.fw(self.cfg.byte_pickup);
        self.take_at = Some((self.now + pickup).max(self.free_at));
        self.inbuf = Some((byte, command, self.now));
        self.run_until(self.now);
    }

    /// Status register (3-1-1): no side effects.
    pub fn read_status(&self) -> u8 {
        let mut s = self.field;
        if self.obf {
            s |= 0x01;
        }
        if self.inbuf.is_some() {
            s |= 0x02;
        }
        if self.busy {
            s |= 0x04;
        }
        s
    }

    /// Data register (3-1-2): the latch, stale when OBF = 0 (notes N34).
    pub fn read_data(&mut self) -> u8 {
        if self.obf {
            self.obf = false;
            if !self.out.is_empty() {
                let at = self.now + self.fw(self.cfg.obf_next);
                self.schedule(at, Event::ObfReady);
            }
        }
        self.latch
    }

    /// Drives an input pin; `asserted` = pulled low.
    pub fn set_input(&mut self, input: Input, asserted: bool) {
        let bit = 1u16 << input.index();
        let was = self.inputs & bit != 0;
        if was == asserted {
            return;
        }
        if asserted {
            self.inputs |= bit;
            self.input_asserted(input);
        } else {
            self.inputs &= !bit;
        }
        self.run_until(self.now);
    }

    fn asserted(&self, input: Input) -> bool {
        self.inputs & (1 << input.index()) != 0
    }

    /// The output pins now.
    pub fn pins(&self) -> Pins {
        let phases = self.phases_now();
        Pins {
            int: self.int,
            hold: self.hold,
            aux: self.aux,
            auxo: self.auxo,
            phases,
            phase_levels: self.levels(phases),
            dir: if self.ccw {
                Direction::Ccw
            } else {
                Direction::Cw
            },
            busy: self.busy,
        }
    }

    /// The energized pattern, stop switching's chopping aside: what the
    /// record's phases show (the chopping is its own pin).
    fn pattern_now(&self) -> u8 {
        self.shown
            .filter(|_| self.energized)
            .map_or(0, |w| w.pattern(self.step))
    }

    fn phases_now(&self) -> u8 {
        let Some(w) = self.shown.filter(|_| self.energized) else {
            return 0;
        };
        let pattern = w.pattern(self.step);
        match self.switching_since {
            Some(since) if (self.now - since) % (self.ton + self.toff) >= self.ton => 0,
            _ => pattern,
        }
    }

    fn levels(&self, phases: u8) -> u8 {
        if self.positive {
            phases
        } else {
            !phases & 0x1F
        }
    }

    /// Lets time pass up to and including `until`.
    pub fn advance_to(&mut self, until: Instant) {
        self.run_until(until.as_nanos());
    }

    // ---- time ----

    fn fw(&self, d: Duration) -> u64 {
        self.straps.firmware_time(d).as_nanos()
    }

    fn schedule(&mut self, at: u64, e: Event) {
        self.seq += 1;
        self.events.push((at, self.seq, e));
    }

    /// Runs every event due up to `until`: at one instant pulses first,
    /// then the other events in the order they were set, then the firmware
    /// taking a byte (notes N40).
    fn run_until(&mut self, until: u64) {
        loop {
            let next_event = self
                .events
                .iter()
                .enumerate()
                .min_by_key(|(_, (at, seq, e))| (*at, !matches!(e, Event::Pulse { .. }), *seq))
                .map(|(i, (at, _, _))| (i, *at));
            let take = self.take_at.filter(|_| !self.starved);
            match (next_event, take) {
                (Some((i, at)), t) if at <= until && t.is_none_or(|t| at <= t) => {
                    let (at, _, e) = self.events.swap_remove(i);
                    self.now = self.now.max(at);
                    self.fire(e);
                }
                (_, Some(t)) if t <= until => {
                    self.now = self.now.max(t);
                    self.take();
                }
                _ => break,
            }
        }
        self.now = self.now.max(until);
    }

    fn set_pin(&mut self, pin: Pin, value: u8) {
        self.pins.push(PinEvent {
            at: Instant::from_nanos(self.now),
            pin,
            value,
        });
    }

    fn set_busy(&mut self, busy: bool) {
        if self.busy != busy {
            self.busy = busy;
            self.set_pin(Pin::Busy, u8::from(busy));
        }
    }

    fn set_int(&mut self, int: bool) {
        if self.int != int {
            self.int = int;
            self.set_pin(Pin::Int, u8::from(int));
        }
    }

    fn set_hold(&mut self, hold: bool) {
        if self.hold != hold {
            self.hold = hold;
            self.set_pin(Pin::Hold, u8::from(hold));
        }
    }

    fn set_switching(&mut self, on: bool) {
        let active = self.switching_since.is_some();
        if active != on {
            self.switching_since = on.then_some(self.now);
            self.set_pin(Pin::Switching, u8::from(on));
        }
    }

    /// Shows the phases set outside stepping where they differ from
    /// `was`, the pattern before: a pin that does not move makes no change
    /// (a re-initialization keeps them, 3-2-1 (3)).
    fn show_phases_from(&mut self, was: u8) {
        let p = self.phases_now();
        if p != was {
            self.set_pin(Pin::Phases, p);
        }
    }

    fn fire(&mut self, e: Event) {
        let live = |s: &Self, id: u64| s.mv.as_ref().is_some_and(|m| m.id == id && !m.over);
        match e {
            Event::Pulse { id } if live(self, id) => self.pulse(),
            Event::BusyRise { id } if live(self, id) => {
                self.set_busy(true);
                self.set_hold(false);
                self.hold_epoch += 1;
                self.set_switching(false);
                // DIR follows the move from BUSY's rise (notes N49).
                let ccw = self.mv.as_ref().is_some_and(|m| m.ccw);
                if self.ccw != ccw {
                    self.ccw = ccw;
                    self.set_pin(Pin::Dir, u8::from(ccw));
                }
            }
            Event::BusyFall { id } if self.mv.as_ref().is_some_and(|m| m.id == id) => {
                self.busy_fall()
            }
            Event::Decelerate { id, limit } if live(self, id) => self.decelerate(limit),
            // A timer: it fires even when the next move is already taken,
            // and BUSY rising turns HOLD off again (N38).
            Event::HoldOn { epoch } if epoch == self.hold_epoch => {
                self.set_hold(true);
                if self.setup.is_some_and(|s| s.switching) && !self.initializing {
                    self.set_switching(true);
                }
            }
            Event::PhasesSet { epoch } if epoch == self.epoch => {
                let was = self.pattern_now();
                self.energized = true;
                self.show_phases_from(was);
            }
            // A completed initialization holds the motor (N38), and starts
            // the stop switching it asks for (N39).
            Event::InitDone { epoch } if epoch == self.epoch && self.mv.is_none() => {
                self.initializing = false;
                self.set_hold(true);
                if self.setup.is_some_and(|s| s.switching) {
                    self.set_switching(true);
                }
            }
            Event::ObfReady => self.load_output(),
            Event::Aux(on) if self.aux != on => {
                self.aux = on;
                self.set_pin(Pin::Aux, u8::from(on));
            }
            Event::Auxo(v) if self.auxo != v => {
                self.auxo = v;
                self.set_pin(Pin::Auxo, v);
            }
            Event::ExcitationOff { epoch } if epoch == self.epoch => {
                let was = self.pattern_now();
                self.energized = false;
                self.shown = None;
                self.step = 0;
                self.set_switching(false);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.show_phases_from(was);
            }
            _ => {}
        }
    }
}

/// `num / den` rounded to the nearest integer, a half rounded up.
fn div_round(num: u128, den: u128) -> u64 {
    u64::try_from((2 * num + den) / (2 * den)).unwrap_or(u64::MAX)
}
