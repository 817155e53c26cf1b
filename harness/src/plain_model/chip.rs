//! The plain model: a second, deliberately simple model of the chip,
//! written from chapter 3 of the datasheet and `docs/datasheet-notes.md`,
//! not from the emulator's code, to check the emulator against
//! ([`super::twin`]).
//!
//! Where the emulator plans a move in closed form, batches pulses into
//! runs and jumps over stretches of constant rate, this model does one
//! thing at a time: every pulse is an event of its own, the speed after
//! each pulse is found from the one before it (accelerate while there is
//! room to stop, never above RH), and time is whole nanoseconds in plain
//! integers. It keeps no cache and no plan. It is slow on purpose, and
//! meant for short inputs.
//!
//! It shares with the emulator only the vocabulary (the [`Pins`] and
//! [`PinEvent`] it reports, [`Input`], [`Direction`]), the straps'
//! clock periods ([`Straps::tclock`], [`Straps::firmware_time`]: the
//! clock arithmetic of notes N9, N10, N44) and the latencies of
//! [`ModelConfig`], which are parameters, not behaviour. Command decoding,
//! errors, the ramp, the phase sequences, the speed limit, the register
//! contents and every timing rule are its own. Deliberate faults
//! ([`ModelConfig::faults`], [`ModelConfig::board`]) are not modelled: it
//! is always a good chip.

use crate::emu::ModelConfig;
use crate::protocol::{ClockSource, Direction, Input, Pin, PinEvent, Pins, Straps};
use crate::time::{Duration, Instant};
use std::collections::VecDeque;

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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    ImmediateStop,
    DecelStop,
    SingleStep,
    AccelDecel,
    Constant,
    ContinuousConstant,
    ContinuousHigh,
    OriginSearch,
}

impl Op {
    fn code(self) -> u8 {
        match self {
            Op::ImmediateStop => 0,
            Op::DecelStop => 1,
            Op::SingleStep => 2,
            Op::AccelDecel => 3,
            Op::Constant => 4,
            Op::ContinuousConstant => 5,
            Op::ContinuousHigh => 6,
            Op::OriginSearch => 7,
        }
    }

    fn ramped(self) -> bool {
        matches!(self, Op::AccelDecel | Op::ContinuousHigh)
    }
}

/// A command code as Section 3 and notes N2-N4 lay it out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cmd {
    Init(u8),
    Move {
        op: Op,
        ccw: bool,
        masked: bool,
        pout: bool,
    },
    Read(u8),
    Switching,
    AuxOutput,
    SoftReset,
    AuxOn,
    AuxOff,
    Undefined,
}

fn decode(b: u8) -> Cmd {
    if b & 0xC0 == 0 {
        return if b & 0x03 == 0 {
            Cmd::Undefined
        } else {
            Cmd::Init(b)
        };
    }
    if b & 0xC0 == 0x80 {
        return match b {
            0x80..=0x83 | 0x85 => Cmd::Read(b),
            0x84 => Cmd::Switching,
            0x86 => Cmd::AuxOutput,
            _ => Cmd::Undefined,
        };
    }
    let ccw = b & 0x08 != 0;
    let masked = b & 0x10 != 0;
    if b & 0x80 == 0 {
        let op = match b & 0x07 {
            0 => Op::ImmediateStop,
            1 => Op::DecelStop,
            2 => Op::SingleStep,
            3 => Op::AccelDecel,
            4 => Op::Constant,
            5 => Op::ContinuousConstant,
            6 => Op::ContinuousHigh,
            _ => Op::OriginSearch,
        };
        return Cmd::Move {
            op,
            ccw,
            masked,
            pout: false,
        };
    }
    match b & 0x07 {
        0 => Cmd::SoftReset,
        1 => Cmd::AuxOn,
        2 => Cmd::AuxOff,
        3 => Cmd::Move {
            op: Op::AccelDecel,
            ccw,
            masked,
            pout: true,
        },
        6 => Cmd::Move {
            op: Op::ContinuousHigh,
            ccw,
            masked,
            pout: true,
        },
        _ => Cmd::Undefined,
    }
}

fn params(cmd: Cmd) -> u8 {
    match cmd {
        Cmd::Init(_)
        | Cmd::Move {
            op: Op::Constant, ..
        } => 4,
        Cmd::Move {
            op: Op::AccelDecel, ..
        } => 3,
        Cmd::Move {
            op: Op::ContinuousConstant | Op::OriginSearch,
            ..
        } => 1,
        Cmd::Switching => 2,
        Cmd::AuxOutput => 1,
        _ => 0,
    }
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

    fn show_phases(&mut self) {
        let p = self.phases_now();
        self.set_pin(Pin::Phases, p);
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
                self.energized = true;
                self.show_phases();
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
                self.energized = false;
                self.shown = None;
                self.step = 0;
                self.set_switching(false);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.show_phases();
            }
            _ => {}
        }
    }

    // ---- the firmware taking bytes ----

    fn take(&mut self) {
        let Some((byte, command, _)) = self.inbuf.take() else {
            self.take_at = None;
            return;
        };
        self.take_at = None;
        // Firmware times run from when the byte would have been written
        // had the firmware been idle (notes N12).
        let base = self.now - self.fw(self.cfg.byte_pickup);
        if command {
            self.command(byte, base);
        } else {
            self.data(byte, base);
        }
        // A byte written while this one was being worked on waits for the
        // firmware.
        if self.inbuf.is_some() && self.take_at.is_none() {
            let pickup = self.fw(self.cfg.byte_pickup);
            self.take_at = Some((self.now + pickup).max(self.free_at));
        }
    }

    fn error(&mut self, n: u8) {
        self.field = 0x80 | (n << 4);
    }

    fn command(&mut self, byte: u8, base: u64) {
        let cmd = decode(byte);
        // A new command drops an unfinished one (N35) and unread output
        // (N34).
        self.pending = None;
        self.out.clear();
        self.obf = false;
        self.events.retain(|(_, _, e)| *e != Event::ObfReady);
        self.field = 0;
        if self.busy && self.mv.is_some() {
            // Pulsing: only stops and AUX (3-1-1 (3), 3-5-3, 3-5-4).
            match cmd {
                Cmd::Move {
                    op: Op::ImmediateStop,
                    ..
                } => self.immediate_stop(base),
                Cmd::Move {
                    op: Op::DecelStop, ..
                } => self.decel_stop(base),
                Cmd::AuxOn | Cmd::SoftReset => self.aux_switch(true, base),
                Cmd::AuxOff => self.aux_switch(false, base),
                Cmd::AuxOutput => self.expect(cmd),
                Cmd::Undefined => self.error(0),
                _ => self.error(1),
            }
            return;
        }
        match cmd {
            Cmd::Undefined => self.error(0),
            Cmd::Move {
                op: Op::ImmediateStop | Op::DecelStop,
                ..
            } => self.error(0),
            Cmd::Move { .. } if self.setup.is_none() => self.error(2),
            Cmd::Move {
                op: Op::SingleStep | Op::ContinuousHigh,
                ..
            } => self.start(cmd, &[], base),
            Cmd::Read(code) => self.read_register(code, base),
            Cmd::AuxOn => self.aux_switch(true, base),
            Cmd::AuxOff => self.aux_switch(false, base),
            Cmd::SoftReset => self.software_reset(base),
            _ => self.expect(cmd),
        }
    }

    fn expect(&mut self, cmd: Cmd) {
        self.field = params(cmd) << 4;
        self.pending = Some((cmd, Vec::new()));
    }

    fn data(&mut self, byte: u8, base: u64) {
        let Some((cmd, mut bytes)) = self.pending.take() else {
            self.error(if self.busy { 6 } else { 3 });
            return;
        };
        if self.busy && self.mv.is_some() && cmd != Cmd::AuxOutput {
            self.error(6);
            return;
        }
        bytes.push(byte);
        let left = params(cmd) - bytes.len() as u8;
        self.field = left << 4;
        if left > 0 {
            self.pending = Some((cmd, bytes));
            return;
        }
        match cmd {
            Cmd::Init(code) => self.initialize(code, &bytes, base),
            Cmd::Move { .. } => self.start(cmd, &bytes, base),
            Cmd::Switching => {
                let (on, off) = if self.straps.vsel_high {
                    (27_000, 33_000)
                } else {
                    (25_000, 28_750)
                };
                let ton = u64::from(bytes[0]) * 3_000 + on;
                let toff = u64::from(bytes[1]) * 3_000 + off;
                self.ton = self.fw(Duration::from_nanos(ton));
                self.toff = self.fw(Duration::from_nanos(toff));
            }
            Cmd::AuxOutput => {
                // The pins change 14 us later; the firmware is free
                // meanwhile (notes N49).
                let at = base + self.fw(self.cfg.aux_output);
                self.schedule(at, Event::Auxo(bytes[0] & 0x0F));
            }
            _ => {}
        }
    }

    // ---- initialization (3-2) and software reset (3-5-4) ----

    fn initialize(&mut self, code: u8, d: &[u8], base: u64) {
        let (rl, rh) = (d[0], d[1]);
        let pa = u32::from(u16::from_le_bytes([d[2], d[3]]));
        // 255 > RL > RH > 0, then 4 <= PA <= 11,220 (notes N5).
        if !(rh > 0 && rh < rl && rl < 255) {
            self.error(5);
            return;
        }
        if pa < 4 {
            self.error(5);
            return;
        }
        if pa > 11_220 {
            self.error(4);
            return;
        }
        self.setup = Some(Setup {
            rl,
            rh,
            pa,
            external: code & 0x10 != 0,
            switching: code & 0x20 != 0,
        });
        let first = self.winding.is_none();
        if first {
            let w = Winding {
                phases: MOTOR_PHASES[usize::from(code & 0x03)],
                half: code & 0x04 != 0,
                positive: code & 0x08 != 0,
            };
            self.winding = Some(w);
            self.shown = Some(w);
            self.positive = w.positive;
            self.step = 0;
        }
        // Switching stops while the initialization is processed, and
        // starts again when it completes (3-2-1 (3), notes N39).
        self.set_switching(false);
        self.initializing = true;
        self.epoch += 1;
        let epoch = self.epoch;
        self.schedule(
            base + self.fw(self.cfg.init_outputs),
            Event::PhasesSet { epoch },
        );
        // 16.5 ms at PA = 4 to 162.8 ms at PA = 11,220, linear (N21).
        let min = self.cfg.init_time_min.as_nanos();
        let max = self.cfg.init_time_max.as_nanos();
        let t = div_round(u128::from(max - min) * u128::from(pa - 4), 11_220 - 4) + min;
        let done = base + self.fw(Duration::from_nanos(t));
        self.schedule(done, Event::InitDone { epoch });
        self.free_at = self.free_at.max(done);
    }

    fn software_reset(&mut self, base: u64) {
        self.setup = None;
        self.winding = None;
        self.epoch += 1;
        let epoch = self.epoch;
        // The phases go off 18 us later; the firmware is free meanwhile
        // (notes N49).
        let at = base + self.fw(self.cfg.excitation_off);
        self.schedule(at, Event::ExcitationOff { epoch });
    }

    fn aux_switch(&mut self, on: bool, base: u64) {
        let at = base + self.fw(self.cfg.aux_switch);
        self.schedule(at, Event::Aux(on));
    }

    // ---- register reads (3-4) ----

    fn read_register(&mut self, code: u8, base: u64) {
        let bytes: Vec<u8> = match code {
            0x80 => {
                // The read clears the polling flag and releases INT* when
                // the firmware fetches the register (N30).
                let value = self.finish;
                self.finish &= 0x7F;
                self.set_int(false);
                vec![value]
            }
            0x81 => {
                let mut v = 0x3Fu8;
                for (bit, input) in [
                    Input::L4,
                    Input::L3,
                    Input::L2,
                    Input::L1,
                    Input::Alm,
                    Input::Cnp,
                ]
                .into_iter()
                .enumerate()
                {
                    if self.asserted(input) {
                        v &= !(1 << bit);
                    }
                }
                vec![v]
            }
            0x82 => {
                let levels = self.levels(self.phases_now());
                vec![levels << 3 | u8::from(self.hold) << 2 | u8::from(self.ccw) << 1]
            }
            0x83 => {
                let r = self.remaining.saturating_sub(1);
                vec![r as u8, (r >> 8) as u8, (r >> 16) as u8]
            }
            _ => {
                let mut v = 0x0Fu8;
                for (bit, input) in [Input::Auxi0, Input::Auxi1, Input::Auxi2, Input::Auxi3]
                    .into_iter()
                    .enumerate()
                {
                    if self.asserted(input) {
                        v &= !(1 << bit);
                    }
                }
                vec![v]
            }
        };
        self.out = bytes.into();
        let at = base + self.fw(self.cfg.obf_ready);
        self.schedule(at, Event::ObfReady);
    }

    fn load_output(&mut self) {
        let Some(b) = self.out.pop_front() else {
            return;
        };
        self.latch = b;
        self.obf = true;
    }

    // ---- moves (3-3) ----

    fn start(&mut self, cmd: Cmd, d: &[u8], base: u64) {
        let Cmd::Move {
            op,
            ccw,
            masked,
            pout,
        } = cmd
        else {
            return;
        };
        let Some(setup) = self.setup else {
            self.error(2);
            return;
        };
        let count = |b: &[u8]| u32::from(b[0]) | u32::from(b[1]) << 8 | u32::from(b[2]) << 16;
        let full = 1u32 << 24;
        let (steps, rate) = match op {
            Op::SingleStep => (1, None),
            Op::AccelDecel => (count(d) + 1, None),
            Op::Constant => (count(&d[1..]) + 1, Some(d[0])),
            Op::ContinuousConstant | Op::OriginSearch => (full, Some(d[0])),
            _ => (full, None),
        };
        let source = if setup.external {
            ClockSource::External
        } else {
            ClockSource::Internal
        };
        let tclock = self.straps.tclock(source).map(|t| t.as_nanos());
        self.move_seq += 1;
        let id = self.move_seq;
        self.mv = Some(Move {
            id,
            op,
            ccw,
            masked,
            pout,
            steps,
            end: steps,
            emitted: 0,
            index: -1,
            constant: rate.zip(tclock).map(|(r, t)| self.period(r, t)),
            tclock,
            decelerating: false,
            cause: 0,
            base,
            last_pulse: None,
            over: false,
        });
        let rise = base + self.fw(self.cfg.busy_rise);
        self.schedule(rise, Event::BusyRise { id });
        self.free_at = self.free_at.max(rise);
        let first = match op {
            Op::SingleStep => self.cfg.single_step_pout,
            Op::Constant | Op::ContinuousConstant | Op::OriginSearch => {
                self.cfg.constant_first_pout
            }
            Op::AccelDecel if steps < 2 * setup.pa => {
                // Triangle: the more steps, the longer (N17).
                let extra = self.cfg.accel_first_pout_triangle_max.as_nanos()
                    - self.cfg.accel_first_pout.as_nanos();
                self.cfg.accel_first_pout
                    + Duration::from_nanos(div_round(u128::from(extra) * u128::from(steps), 22_440))
            }
            _ => self.cfg.accel_first_pout,
        };
        if tclock.is_some() {
            self.schedule(base + self.fw(first), Event::Pulse { id });
        }
    }

    /// The period of rate value `r` (Equations 3-1 to 3-4, notes N8).
    fn period(&self, r: u8, tclock: u64) -> u64 {
        let vsel = if self.straps.vsel_high {
            0
        } else if tclock <= 8_000 {
            7_500
        } else if tclock >= 9_000 {
            0
        } else {
            7_500 * (9_000 - tclock) / 1_000
        };
        (u64::from(r) + 1) * tclock + vsel
    }

    /// The period of speed index `k` of the ramp from RL (index 0) to RH
    /// (index PA - 1), on the rate grid (notes N16). Exact: with K = PA - 1
    /// and the periods pl, ph of RL and RH, the linear-speed curve's
    /// period is pl ph K / (ph K + (pl - ph) k), and the rate value is the
    /// nearest (R + 1) x Tclock (+ VSEL's term) to it, a tie going to the
    /// slower rate.
    fn ramp_period(&self, k: u32, tclock: u64) -> u64 {
        let s = self.setup.expect("a ramped move needs an initialization");
        let big_k = u128::from(s.pa - 1);
        let k = u128::from(k);
        let rate = match self.cfg.accel_curve {
            crate::emu::AccelCurve::LinearSpeed => {
                let pl = u128::from(self.period(s.rl, tclock));
                let ph = u128::from(self.period(s.rh, tclock));
                let vsel = u128::from(self.period(0, tclock) - tclock);
                let den = ph * big_k + (pl - ph) * k;
                // (R + 1) = (T - vsel) / tclock, T = pl ph K / den.
                let num = pl * ph * big_k - vsel * den;
                div_round(num, den * u128::from(tclock)).saturating_sub(1)
            }
            crate::emu::AccelCurve::LinearRate => {
                let drop = div_round(u128::from(s.rl - s.rh) * k, big_k);
                u64::from(s.rl) - drop
            }
        };
        let r = rate.clamp(u64::from(s.rh), u64::from(s.rl)) as u8;
        self.period(r, tclock)
    }

    /// The speed limit (3-2-2): a period shorter than this starves the
    /// firmware (notes N7). Compared exactly: period x limit < 1 s.
    fn over_limit(&self, period: u64, pout: bool) -> bool {
        let max = if pout { 40_000u128 } else { 27_000 };
        let limit_pps = max * u128::from(self.straps.sysclk_hz) / 16_000_000;
        u128::from(period) * limit_pps < 1_000_000_000
    }

    fn pulse(&mut self) {
        let now = self.now;
        let setup = self.setup;
        let Some(m) = self.mv.as_mut() else { return };
        if m.emitted == 0 {
            // Inputs already asserted are sampled before the first pulse
            // (notes N27).
            let limit = if m.ccw { Input::L2 } else { Input::L1 };
            let alm = self.inputs & (1 << Input::Alm.index()) != 0;
            let lim = self.inputs & (1 << limit.index()) != 0;
            let cnp = self.inputs & (1 << Input::Cnp.index()) != 0;
            if alm || lim || (m.op == Op::OriginSearch && cnp) {
                let cause = if alm {
                    0x20
                } else if lim {
                    0x10
                } else {
                    0
                };
                self.halt(cause, now);
                return;
            }
            // A high-speed limit already asserted in phase mode: the
            // deceleration starts from standstill and leaves this one
            // pulse (N27).
            let hs = if m.ccw { Input::L4 } else { Input::L3 };
            if m.op.ramped() && !m.pout && !m.decelerating && self.asserted(hs) {
                let m = self.mv.as_mut().expect("checked above");
                m.decelerating = true;
                if m.end > 1 {
                    m.cause = 0x08;
                    m.end = 1;
                }
            }
        }
        let m = self.mv.as_mut().expect("checked above");
        let dir = if m.ccw { Direction::Ccw } else { Direction::Cw };
        self.pulses.push((Instant::from_nanos(now), dir));
        m.emitted += 1;
        m.last_pulse = Some(now);
        let (pout, ccw) = (m.pout, m.ccw);
        if !pout {
            if let Some(w) = self.winding {
                let n = w.steps();
                self.step = if ccw {
                    (self.step + n - 1) % n
                } else {
                    (self.step + 1) % n
                };
            }
        }
        if self.pulses.len() as u64 >= PULSE_BUDGET {
            self.exhausted = true;
        }
        let m = self.mv.as_mut().expect("checked above");
        if m.emitted >= m.end || self.exhausted {
            self.finish_move(now);
            return;
        }
        let tclock = m.tclock.expect("a pulse needs a base clock");
        let period = match m.constant {
            Some(p) => p,
            None => {
                let pa = setup.map_or(4, |s| s.pa);
                // Accelerate while there is room to stop, never past RH.
                let room = i64::from(m.end - m.emitted) - 1;
                m.index = (m.index + 1).min(i64::from(pa) - 1).min(room);
                let k = m.index.max(0) as u32;
                // In POUT mode L3/L4 are not checked while accelerating;
                // one still asserted at high speed acts then (N26).
                let hs = if m.ccw { Input::L4 } else { Input::L3 };
                if m.pout
                    && !m.decelerating
                    && i64::from(k) == i64::from(pa) - 1
                    && self.inputs & (1 << hs.index()) != 0
                {
                    m.decelerating = true;
                    let (id, at) = (m.id, now + self.fw(self.cfg.hs_limit_cruise));
                    self.schedule(at, Event::Decelerate { id, limit: true });
                }
                self.ramp_period(k, tclock)
            }
        };
        let m = self.mv.as_ref().expect("checked above");
        let (id, pout) = (m.id, m.pout);
        // Starved while the period being timed is over the speed limit,
        // served again from the first pulse after which it is not (N7).
        self.starved = self.over_limit(period, pout);
        self.schedule(now + period, Event::Pulse { id });
    }

    /// The last pulse is out: a normal end, or the end of a deceleration
    /// (notes N22). A single step ends when its processing does (N18).
    fn finish_move(&mut self, last_pulse: u64) {
        let m = self.mv.as_ref().expect("a move to finish");
        let (fall, free) = if m.op == Op::SingleStep {
            let done = m.base + self.fw(self.cfg.single_step_done);
            (done, done)
        } else {
            (
                last_pulse + self.fw(self.cfg.interrupt_delay),
                last_pulse + self.fw(self.cfg.next_command),
            )
        };
        // From the final POUT the firmware is busy until it accepts the
        // next command (Table 3-3, N12).
        self.free_at = self.free_at.max(free);
        self.stop_pulsing(fall);
    }

    /// Pulses stop now: an Immediate Stop, L1/L2, ALM, CNP, or a
    /// Decelerating Stop on a constant-rate move (notes N13, N22).
    /// `trigger` is when the cause arose, from which the remaining-pulse
    /// calculation of an accel/decel-type move is timed.
    fn halt(&mut self, cause: u8, trigger: u64) {
        let Some(m) = self.mv.as_mut().filter(|m| !m.over) else {
            // Past its last pulse: it completes normally (N28).
            return;
        };
        m.cause = cause;
        let fall = if m.op == Op::SingleStep {
            m.base + self.fw(self.cfg.single_step_done)
        } else if m.op.ramped() {
            trigger + self.fw(self.cfg.remaining_calc)
        } else {
            self.now + self.fw(self.cfg.interrupt_delay)
        };
        self.stop_pulsing(fall.max(self.now));
    }

    fn stop_pulsing(&mut self, fall: u64) {
        let m = self.mv.as_mut().expect("a move to stop");
        m.over = true;
        let id = m.id;
        self.schedule(fall, Event::BusyFall { id });
        // Pulse output is over: the firmware is no longer starved by the
        // speed limit (3-2-1 (1): commands are refused "during pulse
        // output"), and takes a waiting byte when it is free (N7, N49).
        self.starved = false;
        self.retake();
    }

    /// BUSY falls: the finish status, the remaining pulses and INT* are
    /// set, HOLD comes 3.4 ms after the final POUT, and the firmware takes
    /// the next command 156 us after it (Table 3-3; after a stop, the same
    /// 130 us after BUSY falls, notes N49).
    fn busy_fall(&mut self) {
        let m = self.mv.take().expect("a move to end");
        self.set_busy(false);
        self.finish = 0x80 | m.cause | m.op.code();
        self.remaining = m.steps - m.emitted;
        if !m.masked {
            self.set_int(true);
        }
        let free = if m.op == Op::SingleStep {
            self.now
        } else {
            let after = self
                .cfg
                .next_command
                .saturating_sub(self.cfg.interrupt_delay);
            self.now + self.fw(after)
        };
        self.free_at = self.free_at.max(free);
        self.hold_epoch += 1;
        let epoch = self.hold_epoch;
        let hold = m.last_pulse.unwrap_or(self.now) + self.fw(self.cfg.hold_on);
        self.schedule(hold, Event::HoldOn { epoch });
        self.retake();
    }

    /// After a move, a starved byte is taken again.
    fn retake(&mut self) {
        if self.inbuf.is_some() {
            let t = self.take_at.unwrap_or(self.now).max(self.free_at);
            self.take_at = Some(t);
        }
    }

    fn immediate_stop(&mut self, base: u64) {
        self.halt(0x40, base);
    }

    fn decel_stop(&mut self, base: u64) {
        let Some(m) = self.mv.as_ref().filter(|m| !m.over) else {
            return;
        };
        if !m.op.ramped() {
            self.halt(0x40, base);
            return;
        }
        if m.decelerating || self.in_final_deceleration() {
            self.error(7);
            return;
        }
        let id = m.id;
        let m = self.mv.as_mut().expect("checked above");
        m.decelerating = true;
        self.schedule(
            base + self.fw(self.cfg.decel_stop),
            Event::Decelerate { id, limit: false },
        );
    }

    /// Whether the ramp is already running down to the end (3-3-2).
    fn in_final_deceleration(&self) -> bool {
        let Some(m) = self.mv.as_ref() else {
            return false;
        };
        let Some(s) = self.setup else { return false };
        let room = i64::from(m.end - m.emitted) - 1;
        m.emitted > 0 && (m.index + 1).min(i64::from(s.pa) - 1) > room
    }

    fn decelerate(&mut self, limit: bool) {
        let Some(m) = self.mv.as_mut() else { return };
        // The pulse being timed is still output; from there the ramp runs
        // down from the speed reached (notes N24).
        let end = if m.emitted == 0 {
            1
        } else {
            m.emitted + (m.index.max(0) as u32) + 1
        };
        // A deceleration that would end the move where it ends anyway
        // changes nothing: all its pulses are output, a normal end (3-4-1).
        if end < m.end {
            m.end = end;
            m.cause = if limit { 0x08 } else { 0x40 };
        }
    }

    fn input_asserted(&mut self, input: Input) {
        let now = self.now;
        let Some(m) = self.mv.as_ref().filter(|m| !m.over) else {
            return;
        };
        if m.emitted == 0 {
            // Not yet pulsing: the inputs are sampled as levels before the
            // first pulse; an edge that comes and goes before it is not
            // seen (N27).
            return;
        }
        let same_limit = if m.ccw { Input::L2 } else { Input::L1 };
        let same_hs = if m.ccw { Input::L4 } else { Input::L3 };
        if input == Input::Alm {
            self.halt(0x20, now);
        } else if input == same_limit {
            self.halt(0x10, now);
        } else if input == Input::Cnp && m.op == Op::OriginSearch {
            self.halt(0, now);
        } else if input == same_hs && m.op.ramped() && !m.decelerating {
            if self.in_final_deceleration() {
                return;
            }
            let s = self.setup.expect("a ramped move needs an initialization");
            let accelerating = m.index < i64::from(s.pa) - 1;
            if accelerating && m.pout {
                return;
            }
            let delay = if accelerating {
                self.cfg.hs_limit_accel
            } else {
                self.cfg.hs_limit_cruise
            };
            let id = m.id;
            self.mv.as_mut().expect("checked above").decelerating = true;
            let at = now + self.fw(delay);
            self.schedule(at, Event::Decelerate { id, limit: true });
        }
    }
}

/// `num / den` rounded to the nearest integer, a half rounded up.
fn div_round(num: u128, den: u128) -> u64 {
    u64::try_from((2 * num + den) / (2 * den)).unwrap_or(u64::MAX)
}
