//! The PPMC-104BFP model: a discrete-event simulation in virtual time.
//!
//! The host side is four operations at the chip's current time
//! ([`Chip::write_command`], [`Chip::write_data`], [`Chip::read_status`],
//! [`Chip::read_data`]) plus [`Chip::set_input`]; time moves only through
//! [`Chip::advance_to`], and [`Chip::poll_at`] says when the next observable
//! change can happen, in the manner of smoltcp's `poll` / `poll_at`.
//!
//! Inside, the firmware is modelled as a single server that takes one byte
//! at a time from the input buffer ([`ModelConfig::byte_pickup`] after the
//! write, later if it is still busy with earlier work), plus a pulse
//! generator driven by the closed-form plan of [`super::motion`]. Events at
//! the same instant are taken in this order: pulses due at or before that
//! instant, then timers in the order they were set, then the host
//! operation.

use super::config::{ConfigError, ModelConfig};
use super::motion::{accel_table, Motion, Profile};
use crate::protocol::capture::{MoveStart, Pin, Pins, Record};
use crate::protocol::{
    AuxInputStatus, ClockSource, Command, Direction, ErrorCode, FinishStatus, InitCommand,
    InitData, Input, InputSet, InputStatus, MoveCommand, MoveKind, OutputLogic, OutputStatus,
    PulseCount, Register, Status, StatusField, StopCause, Straps, StrapsError, Winding,
};
use crate::time::{Duration, Instant};
use alloc::collections::VecDeque;
use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

/// Highest accepted number of acceleration pulses (Table 3-2 error 4, notes N5).
pub const PA_MAX: u16 = 11_220;
/// Lowest accepted number of acceleration pulses (Table 3-2 error 5, notes N5).
pub const PA_MIN: u16 = 4;

/// Why a chip could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ChipError {
    #[error(transparent)]
    Straps(#[from] StrapsError),
    #[error(transparent)]
    Config(#[from] ConfigError),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ByteKind {
    Command,
    Data,
}

#[derive(Debug, Clone, Copy)]
struct InByte {
    byte: u8,
    kind: ByteKind,
}

/// What the command parser is waiting for.
#[derive(Debug, Clone, Copy)]
enum Expect {
    Command,
    Params {
        cmd: Command,
        buf: [u8; 4],
        got: u8,
        need: u8,
    },
}

/// Initialization data in force (Section 3-2).
#[derive(Debug, Clone)]
struct Setup {
    clock: ClockSource,
    stop_switching: bool,
    data: InitData,
    /// Acceleration table and high-speed period, `None` without a clock.
    ramp: Option<(Arc<[Duration]>, Duration)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Timer {
    /// The firmware takes the byte in the input buffer.
    Pick,
    /// The next byte of a register read reaches the output buffer.
    ObfReady,
    /// Phase outputs set after initialization.
    InitOutputs {
        epoch: u64,
    },
    /// Initialization processing finished.
    InitDone {
        epoch: u64,
    },
    BusyRise {
        id: u64,
    },
    DecelStart {
        id: u64,
        cause: StopCause,
    },
    Terminate {
        id: u64,
    },
    HoldOn {
        epoch: u64,
    },
    Aux(bool),
    Auxo(u8),
    ExcitationOff {
        epoch: u64,
    },
}

/// The emulated chip and its board.
#[derive(Debug, Clone)]
pub struct Chip {
    straps: Straps,
    cfg: ModelConfig,
    now: Instant,
    timers: Vec<(Instant, u64, Timer)>,
    timer_seq: u64,

    // Host interface (Section 3-1).
    inbuf: Option<InByte>,
    pick_timer: Option<u64>,
    pick_starved: bool,
    proc_free_at: Instant,
    field: StatusField,
    expect: Expect,
    out_pending: VecDeque<u8>,
    obf: bool,
    out_latch: u8,

    // Initialization (Section 3-2).
    winding: Option<Winding>,
    logic: OutputLogic,
    setup: Option<Setup>,
    switch_on: Duration,
    switch_off: Duration,
    /// Bumped by software reset and re-initialization, to void stale timers.
    config_epoch: u64,

    // Outputs.
    busy: bool,
    int: bool,
    hold: bool,
    hold_epoch: u64,
    aux: bool,
    auxo: u8,
    dir: Direction,
    phase_index: u32,
    phases_on: bool,
    switching_since: Option<Instant>,

    // Inputs and results.
    inputs: InputSet,
    finish: FinishStatus,
    remaining: u32,
    motion: Option<Motion>,
    motion_seq: u64,

    record: Record,
}

impl Chip {
    /// A chip straight out of power-on reset.
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Chip, ChipError> {
        straps.validate()?;
        cfg.validate()?;
        Ok(Chip {
            switch_on: straps.firmware_time(cfg.switching_on),
            switch_off: straps.firmware_time(cfg.switching_off),
            straps,
            cfg,
            now: Instant::ZERO,
            timers: Vec::new(),
            timer_seq: 0,
            inbuf: None,
            pick_timer: None,
            pick_starved: false,
            proc_free_at: Instant::ZERO,
            field: StatusField::ParamsRemaining(0),
            expect: Expect::Command,
            out_pending: VecDeque::new(),
            obf: false,
            out_latch: 0,
            winding: None,
            logic: OutputLogic::Negative,
            setup: None,
            config_epoch: 0,
            busy: false,
            int: false,
            hold: false,
            hold_epoch: 0,
            aux: false,
            auxo: 0,
            dir: Direction::Cw,
            phase_index: 0,
            phases_on: false,
            switching_since: None,
            inputs: InputSet::default(),
            finish: FinishStatus::default(),
            remaining: 0,
            motion: None,
            motion_seq: 0,
            record: Record::default(),
        })
    }

    pub fn straps(&self) -> &Straps {
        &self.straps
    }

    pub fn config(&self) -> &ModelConfig {
        &self.cfg
    }

    /// The chip's current virtual time.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// The output record since reset.
    pub fn record(&self) -> &Record {
        &self.record
    }

    pub fn inputs(&self) -> InputSet {
        self.inputs
    }

    /// Whether an initialization is in force (Table 3-2 error 2 otherwise).
    pub fn initialized(&self) -> bool {
        self.setup.is_some()
    }

    /// The finish status register as the chip holds it (reading it through
    /// the bus, 0x80, clears the polling flag; this does not).
    pub fn finish_status(&self) -> FinishStatus {
        self.finish
    }

    /// Host write to the command register (A = H, WR low). A byte written
    /// while IBF = 1 replaces the one waiting (Section 3-1-1 (2)).
    pub fn write_command(&mut self, byte: u8) {
        self.host_write(byte, ByteKind::Command);
    }

    /// Host write to the data register (A = L, WR low).
    pub fn write_data(&mut self, byte: u8) {
        self.host_write(byte, ByteKind::Data);
    }

    /// Host read of the status register (A = H, RD low). No side effects.
    pub fn read_status(&self) -> Status {
        let s = Status::new(self.obf, self.inbuf.is_some(), self.busy, self.field);
        Status(s.0 | self.cfg.faults.status_stuck_high)
    }

    /// Host read of the data register (A = L, RD low). Reading with OBF = 0
    /// returns the stale latch (Section 3-1-1 (1): "the data are invalid").
    pub fn read_data(&mut self) -> u8 {
        if self.obf {
            self.obf = self.cfg.faults.obf_sticky;
            if !self.out_pending.is_empty() {
                let at = self.now + self.fw(self.cfg.obf_next);
                self.schedule(at, Timer::ObfReady);
            }
        }
        self.out_latch
    }

    /// Drives an input: `asserted` = the active-low pin pulled low.
    pub fn set_input(&mut self, input: Input, asserted: bool) {
        if self.inputs.contains(input) == asserted {
            return;
        }
        self.inputs.set(input, asserted);
        if asserted {
            self.react_to_input(input);
        }
        self.advance_to(self.now);
    }

    /// The output pins now.
    pub fn pins(&self) -> Pins {
        let phases = self.energized(self.now);
        Pins {
            int: self.int,
            hold: self.hold,
            aux: self.aux,
            auxo: self.auxo,
            phases,
            phase_levels: self.levels(phases),
            dir: self.dir,
            busy: self.busy,
        }
    }

    /// Pulses output so far by the move in progress (or the last move).
    pub fn move_pulses(&self) -> u64 {
        match &self.motion {
            Some(m) => u64::from(m.emitted),
            None => self.record.last_move_pulses().count,
        }
    }

    /// When the `n`-th pulse (1-based) of the move in progress will come if
    /// nothing changes its plan first; a later time in its current stretch
    /// when `n` lies beyond it. `None` when no further pulse is planned.
    pub fn predict_pulse(&self, n: u64) -> Option<Instant> {
        let m = self.motion.as_ref().filter(|m| m.pulses_left())?;
        if m.next_pulse == Instant::NEVER || n <= u64::from(m.emitted) {
            return None;
        }
        let (interval, stretch) = m.constant_stretch();
        let k = (n - u64::from(m.emitted)).min(u64::from(stretch));
        Some(m.next_pulse + interval.saturating_mul(k - 1))
    }

    /// The next instant at which the status register, a pin or the
    /// termination of a move can change; `None` when nothing is pending.
    /// During a constant-rate stretch this is the end of the stretch, not
    /// the next pulse, so waiting costs O(1) per stretch.
    pub fn poll_at(&self) -> Option<Instant> {
        let timer = self.next_timer().map(|(at, _)| at);
        let pulse = self
            .next_stretch()
            .filter(|(first, _, _)| *first != Instant::NEVER)
            .map(|(first, interval, count)| first + interval.saturating_mul(u64::from(count - 1)));
        match (timer, pulse) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Runs the model up to and including `until`. A time earlier than
    /// [`Chip::now`] is ignored: virtual time never goes backward.
    pub fn advance_to(&mut self, until: Instant) {
        if until < self.now {
            return;
        }
        loop {
            let next_timer = self.next_timer();
            let timer_at = next_timer.map_or(Instant::NEVER, |(at, _)| at);
            let horizon = timer_at.min(until);
            let pulse_at = self
                .motion
                .as_ref()
                .filter(|m| m.pulses_left())
                .map_or(Instant::NEVER, |m| m.next_pulse);
            // A move without a base clock has its next pulse at NEVER: it
            // never comes, however far time is advanced.
            if pulse_at <= horizon && pulse_at != Instant::NEVER {
                self.now = self.now.max(pulse_at);
                self.emit_pulses(horizon);
                continue;
            }
            match next_timer {
                Some((at, idx)) if at <= until => {
                    let (_, _, timer) = self.timers.remove(idx);
                    self.now = self.now.max(at);
                    self.fire(timer);
                }
                _ => break,
            }
        }
        self.now = until;
    }

    // ----- host interface ------------------------------------------------

    fn host_write(&mut self, byte: u8, kind: ByteKind) {
        if self.inbuf.is_some() {
            self.record.overwritten_bytes += 1;
        }
        self.inbuf = Some(InByte { byte, kind });
        if !self.pick_starved {
            let at = (self.now + self.fw(self.cfg.byte_pickup)).max(self.proc_free_at);
            self.schedule_pick(at);
        }
    }

    fn schedule_pick(&mut self, at: Instant) {
        if let Some(seq) = self.pick_timer.take() {
            self.timers.retain(|(_, s, _)| *s != seq);
        }
        self.pick_timer = Some(self.schedule(at, Timer::Pick));
    }

    /// The firmware cannot serve the host while pulsing faster than the
    /// speed limit (Section 3-2-2, notes N7).
    fn starved(&self) -> bool {
        self.motion.as_ref().is_some_and(|m| {
            m.current_interval()
                .is_some_and(|i| i < self.straps.min_interval(m.pout))
        })
    }

    fn pick(&mut self) {
        self.pick_timer = None;
        let Some(inb) = self.inbuf else { return };
        if self.now < self.proc_free_at {
            let at = self.proc_free_at;
            self.schedule_pick(at);
            return;
        }
        if self.starved() {
            self.pick_starved = true;
            return;
        }
        self.inbuf = None;
        let base = self.now - self.fw(self.cfg.byte_pickup);
        match inb.kind {
            ByteKind::Command => self.on_command(Command::decode(inb.byte), base),
            ByteKind::Data => self.on_data(inb.byte, base),
        }
    }

    fn set_error(&mut self, e: ErrorCode) {
        let e = match self.cfg.faults.swap_error {
            Some((from, to)) if from == e => to,
            _ => e,
        };
        self.field = StatusField::Error(e);
        self.expect = Expect::Command;
    }

    fn on_command(&mut self, cmd: Command, base: Instant) {
        // A new command abandons an unfinished one and unread output.
        self.expect = Expect::Command;
        self.field = StatusField::ParamsRemaining(0);
        self.out_pending.clear();
        self.obf = false;
        self.timers.retain(|(_, _, t)| *t != Timer::ObfReady);

        let busy = self.busy;
        match cmd {
            Command::Undefined(_) => self.set_error(ErrorCode::UndefinedCommand),
            Command::ImmediateStop(_) | Command::DecelStop(_) if !busy => {
                self.set_error(ErrorCode::UndefinedCommand)
            }
            Command::ImmediateStop(_) => self.stop_command_immediate(base),
            Command::DecelStop(_) => self.stop_command_decel(base),
            Command::SoftwareReset(_) if busy && self.cfg.faults.reset_quirk_missing => {}
            Command::SoftwareReset(_) | Command::AuxOn(_) if busy => {
                self.schedule(base + self.fw(self.cfg.aux_switch), Timer::Aux(true));
            }
            Command::AuxOn(_) => {
                self.schedule(base + self.fw(self.cfg.aux_switch), Timer::Aux(true));
            }
            Command::AuxOff(_) => {
                self.schedule(base + self.fw(self.cfg.aux_switch), Timer::Aux(false));
            }
            Command::SoftwareReset(_) => self.software_reset(base),
            Command::AuxOutput => self.expect_params(cmd),
            _ if busy => self.set_error(ErrorCode::NotAllowedWhileBusy),
            Command::Move(_) if !self.initialized() => self.set_error(ErrorCode::NotInitialized),
            Command::Move(m) if m.kind.param_count() == 0 => self.start_move(m, [0; 4], base),
            Command::Init(_) | Command::Move(_) | Command::SwitchingParams => {
                self.expect_params(cmd)
            }
            Command::Read(r) => self.load_register(r, base),
        }
    }

    fn expect_params(&mut self, cmd: Command) {
        let need = cmd.param_count();
        self.field = StatusField::ParamsRemaining(need);
        self.expect = Expect::Params {
            cmd,
            buf: [0; 4],
            got: 0,
            need,
        };
    }

    fn on_data(&mut self, byte: u8, base: Instant) {
        let Expect::Params {
            cmd,
            mut buf,
            mut got,
            need,
        } = self.expect
        else {
            self.set_error(if self.busy {
                ErrorCode::DataWhileBusy
            } else {
                ErrorCode::TooManyParameters
            });
            return;
        };
        if self.busy && cmd != Command::AuxOutput {
            self.set_error(ErrorCode::DataWhileBusy);
            return;
        }
        buf[usize::from(got)] = byte;
        got += 1;
        let due = if self.cfg.faults.params_not_counted && got < need {
            need
        } else {
            need - got
        };
        self.field = StatusField::ParamsRemaining(due);
        if got < need {
            self.expect = Expect::Params {
                cmd,
                buf,
                got,
                need,
            };
            return;
        }
        self.expect = Expect::Command;
        match cmd {
            Command::Init(c) => self.initialize(c, InitData::from_bytes(buf), base),
            Command::Move(m) => self.start_move(m, buf, base),
            Command::SwitchingParams => {
                self.switch_on = self.straps.switching_on_time(buf[0]);
                self.switch_off = self.straps.switching_off_time(buf[1]);
            }
            Command::AuxOutput => {
                let bits = buf[0] & 0x0F;
                let bits = if self.cfg.faults.auxo_reversed {
                    bits.reverse_bits() >> 4
                } else {
                    bits
                };
                self.schedule(base + self.fw(self.cfg.aux_output), Timer::Auxo(bits));
            }
            _ => {}
        }
    }

    fn load_register(&mut self, reg: Register, base: Instant) {
        let bytes: Vec<u8> = match reg {
            Register::FinishStatus => {
                let value = self.finish.0;
                if !self.cfg.faults.finish_flag_sticky {
                    self.finish = self.finish.without_polling();
                }
                self.set_int(false);
                vec![value]
            }
            Register::InputSignals => vec![InputStatus::from_inputs(self.inputs).0],
            Register::OutputSignals => {
                let levels = self.levels(self.energized(self.now));
                vec![OutputStatus::new(self.dir, self.hold, levels).0]
            }
            Register::RemainingPulses => {
                let value = if self.cfg.faults.remaining_off_by_one {
                    self.remaining
                } else {
                    self.remaining.saturating_sub(1)
                };
                let [lo, mid, hi, _] = value.to_le_bytes();
                vec![lo, mid, hi]
            }
            Register::AuxInputs => vec![AuxInputStatus::from_inputs(self.inputs).0],
        };
        self.out_pending.extend(bytes);
        self.schedule(base + self.fw(self.cfg.obf_ready), Timer::ObfReady);
    }

    // ----- initialization and reset (Sections 3-2, 3-5-4) ----------------

    fn initialize(&mut self, cmd: InitCommand, data: InitData, base: Instant) {
        let rates_ok = 0 < data.rh && data.rh < data.rl && data.rl < 255;
        if !rates_ok || data.pa < PA_MIN {
            self.set_error(ErrorCode::BadRateData);
            return;
        }
        if data.pa > PA_MAX {
            self.set_error(ErrorCode::AccelPulsesTooMany);
            return;
        }
        if self.winding.is_none() {
            // Type, excitation and logic are frozen until software reset.
            self.winding = Some(Winding {
                motor: cmd.motor,
                excitation: cmd.excitation,
            });
            self.logic = cmd.logic;
            self.phase_index = 0;
        }
        let ramp = self.straps.tclock(cmd.clock).map(|tclock| {
            let table = accel_table(
                self.cfg.accel_curve,
                &self.straps,
                tclock,
                data.rl,
                data.rh,
                data.pa,
            );
            (
                Arc::from(table),
                self.straps.pulse_interval(data.rh, tclock),
            )
        });
        self.setup = Some(Setup {
            clock: cmd.clock,
            stop_switching: cmd.stop_switching,
            data,
            ramp,
        });
        self.config_epoch += 1;
        let epoch = self.config_epoch;
        self.set_switching(None);
        let span = self
            .cfg
            .init_time_max
            .saturating_sub(self.cfg.init_time_min);
        let init_time = self.cfg.init_time_min
            + span.scale(u64::from(data.pa - PA_MIN), u64::from(PA_MAX - PA_MIN));
        let done = base + self.fw(init_time);
        self.proc_free_at = self.proc_free_at.max(done);
        self.schedule(
            base + self.fw(self.cfg.init_outputs),
            Timer::InitOutputs { epoch },
        );
        self.schedule(done, Timer::InitDone { epoch });
    }

    fn software_reset(&mut self, base: Instant) {
        self.winding_reset();
        self.config_epoch += 1;
        let epoch = self.config_epoch;
        self.schedule(
            base + self.fw(self.cfg.excitation_off),
            Timer::ExcitationOff { epoch },
        );
    }

    fn winding_reset(&mut self) {
        self.winding = None;
        self.setup = None;
    }

    // ----- moves (Section 3-3) --------------------------------------------

    fn start_move(&mut self, cmd: MoveCommand, params: [u8; 4], base: Instant) {
        let Some(setup) = self.setup.clone() else {
            self.set_error(ErrorCode::NotInitialized);
            return;
        };
        let kind = cmd.kind;
        let total = match kind {
            MoveKind::SingleStep => 1,
            MoveKind::AccelDecel => {
                PulseCount::from_bytes([params[0], params[1], params[2]]).steps()
            }
            MoveKind::Constant => PulseCount::from_bytes([params[1], params[2], params[3]]).steps(),
            _ => PulseCount::MAX.steps(),
        };
        let tclock = self.straps.tclock(setup.clock);
        let (profile, first_pout) = match (kind, &setup.ramp) {
            (MoveKind::AccelDecel | MoveKind::ContinuousHigh, Some((table, cruise))) => {
                let pa = u32::from(setup.data.pa);
                let mut first = self.cfg.accel_first_pout;
                if total < 2 * pa {
                    // Triangular drive: the deceleration point takes longer to
                    // find the more steps there are (Table 3-3, notes N17).
                    let extra = self
                        .cfg
                        .accel_first_pout_triangle_max
                        .saturating_sub(first)
                        .scale(u64::from(total), 2 * u64::from(PA_MAX));
                    first += extra;
                }
                (
                    Profile::Ramped {
                        table: Arc::clone(table),
                        cruise: *cruise,
                    },
                    Some(first),
                )
            }
            (MoveKind::SingleStep, _) => (
                Profile::Constant {
                    interval: Duration::ZERO,
                },
                tclock.map(|_| self.cfg.single_step_pout),
            ),
            (MoveKind::Constant | MoveKind::ContinuousConstant | MoveKind::OriginSearch, _) => {
                let rate = params[0];
                let interval =
                    tclock.map_or(Duration::MAX, |t| self.straps.pulse_interval(rate, t));
                (
                    Profile::Constant { interval },
                    tclock.map(|_| self.cfg.constant_first_pout),
                )
            }
            // A ramped move without a clock never pulses.
            _ => (
                Profile::Constant {
                    interval: Duration::MAX,
                },
                None,
            ),
        };
        let first_pulse = first_pout.map_or(Instant::NEVER, |d| base + self.fw(d));
        self.motion_seq += 1;
        let id = self.motion_seq;
        let motion = Motion::new(
            id,
            kind,
            cmd.flags.direction,
            cmd.pout,
            cmd.flags.interrupt,
            base,
            total,
            first_pulse,
            profile,
        );
        self.record.moves.push(MoveStart {
            at: base,
            kind,
            dir: cmd.flags.direction,
            pout: cmd.pout,
            steps: total,
            first_run: self.record.runs.len(),
            phase_index: self.phase_index,
            winding: if cmd.pout { None } else { self.winding },
        });
        self.motion = Some(motion);
        let rise = base + self.fw(self.cfg.busy_rise);
        self.proc_free_at = self.proc_free_at.max(rise);
        self.schedule(rise, Timer::BusyRise { id });
    }

    fn stop_command_immediate(&mut self, base: Instant) {
        self.halt(StopCause::StopCommand, base);
    }

    fn stop_command_decel(&mut self, base: Instant) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if !m.kind.ramped() || self.cfg.faults.decel_stop_immediate {
            // Constant-speed moves have no deceleration: stop at once (N13).
            self.halt(StopCause::StopCommand, base);
            return;
        }
        if m.decelerating() || m.decel_requested {
            self.set_error(ErrorCode::DecelStopDuringDecel);
            return;
        }
        let id = m.id;
        if let Some(m) = self.motion.as_mut() {
            m.decel_requested = true;
        }
        self.schedule(
            base + self.fw(self.cfg.decel_stop),
            Timer::DecelStart {
                id,
                cause: StopCause::StopCommand,
            },
        );
    }

    /// Reacts to an input that was just asserted while a move is under way.
    /// Before the first pulse, inputs are sampled instead (see
    /// [`Self::check_inputs_before_first_pulse`]).
    fn react_to_input(&mut self, input: Input) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if !m.pulses_left() || m.emitted == 0 {
            return;
        }
        let now = self.now;
        let (dir, kind, pout) = (m.dir, m.kind, m.pout);
        let mut only = InputSet::default();
        only.set(input, true);
        let seen = self.seen_inputs(only, dir);
        if seen.contains(Input::Alm) {
            self.halt(StopCause::Alarm, now);
        } else if seen.contains(Input::limit_for(dir)) {
            self.halt(StopCause::Limit, now);
        } else if seen.contains(Input::Cnp) && kind == MoveKind::OriginSearch {
            self.halt(StopCause::Completed, now);
        } else if input == Input::high_speed_limit_for(dir) && kind.ramped() {
            self.high_speed_limit(pout);
        }
    }

    /// L3/L4 for the direction of a ramped move: decelerate (Sections 3-3-4,
    /// 3-3-7), except during acceleration in POUT mode.
    fn high_speed_limit(&mut self, pout: bool) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if m.decelerating() || m.decel_requested {
            return;
        }
        let at_speed = m.at_high_speed();
        if pout && !at_speed {
            // Checked again on reaching high speed.
            return;
        }
        let latency = if at_speed {
            self.cfg.hs_limit_cruise
        } else {
            self.cfg.hs_limit_accel
        };
        let id = m.id;
        if let Some(m) = self.motion.as_mut() {
            m.decel_requested = true;
        }
        let at = self.now + self.fw(latency);
        self.schedule(
            at,
            Timer::DecelStart {
                id,
                cause: StopCause::HighSpeedLimit,
            },
        );
    }

    /// Cuts pulse output now. `trigger` is when the cause arose (the stop
    /// command write, or the input edge), from which Table 3-3's abnormal
    /// termination time is counted.
    fn halt(&mut self, cause: StopCause, trigger: Instant) {
        let now = self.now;
        let Some(m) = self.motion.as_mut() else {
            return;
        };
        if !m.pulses_left() {
            // Already past its last pulse: the move completes normally.
            return;
        }
        m.halted = true;
        m.cause = cause;
        let id = m.id;
        let end = if m.kind == MoveKind::SingleStep {
            m.base + self.straps.firmware_time(self.cfg.single_step_done)
        } else if m.kind.ramped() && cause != StopCause::Completed {
            trigger + self.straps.firmware_time(self.cfg.remaining_calc)
        } else {
            now + self.straps.firmware_time(self.cfg.interrupt_delay)
        };
        self.schedule(end.max(now), Timer::Terminate { id });
    }

    fn check_inputs_before_first_pulse(&mut self) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        let (dir, kind, pout) = (m.dir, m.kind, m.pout);
        let now = self.now;
        let inputs = self.seen_inputs(self.inputs, dir);
        if inputs.contains(Input::Alm) {
            self.halt(StopCause::Alarm, now);
        } else if inputs.contains(Input::limit_for(dir)) {
            self.halt(StopCause::Limit, now);
        } else if kind == MoveKind::OriginSearch && inputs.contains(Input::Cnp) {
            self.halt(StopCause::Completed, now);
        } else if kind.ramped() && !pout && inputs.contains(Input::high_speed_limit_for(dir)) {
            // Detected before the first pulse: decelerate from standstill,
            // which leaves the one pulse already being timed.
            if let Some(m) = self.motion.as_mut() {
                if m.begin_decel() {
                    m.cause = StopCause::HighSpeedLimit;
                }
            }
        }
    }

    /// The inputs as the firmware sees them during a move in `dir`: all of
    /// them, unless a board fault hides one.
    fn seen_inputs(&self, mut inputs: InputSet, dir: Direction) -> InputSet {
        let f = &self.cfg.faults;
        if f.alarm_ignored {
            inputs.set(Input::Alm, false);
        }
        if f.origin_ignored {
            inputs.set(Input::Cnp, false);
        }
        if f.limit_ignored == Some(dir) {
            inputs.set(Input::limit_for(dir), false);
        }
        inputs
    }

    /// Whether the move is in POUT mode with its high-speed limit asserted
    /// and not yet acted on: it looks at the limit after every pulse until
    /// high speed is reached (Section 3-3-4, notes N26).
    fn pout_hs_check(m: &Motion, inputs: InputSet) -> bool {
        m.pout
            && m.kind.ramped()
            && !m.decel_requested
            && inputs.contains(Input::high_speed_limit_for(m.dir))
    }

    /// The pulses the move will output next without any decision in
    /// between: `(first, interval, count)`. A whole constant-period stretch,
    /// or one pulse where the model must look again after it (a ramp, the
    /// first pulse, a pending POUT high-speed-limit check). Both [`Self::poll_at`] and
    /// [`Self::emit_pulses`] use it, so waiting never skips a decision.
    fn next_stretch(&self) -> Option<(Instant, Duration, u32)> {
        let m = self.motion.as_ref().filter(|m| m.pulses_left())?;
        let (interval, count) = m.constant_stretch();
        // The first pulse samples the inputs (notes N27).
        let count = if m.emitted == 0 || Self::pout_hs_check(m, self.inputs) {
            count.min(1)
        } else {
            count
        };
        Some((m.next_pulse, interval, count))
    }

    /// Emits the next pulses due at or before `horizon`: one ramp pulse, or a
    /// whole constant-period stretch in one step.
    fn emit_pulses(&mut self, horizon: Instant) {
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        if m.emitted == 0 {
            self.check_inputs_before_first_pulse();
        }
        let Some(m) = self.motion.as_ref() else {
            return;
        };
        let pout_hs_check = Self::pout_hs_check(m, self.inputs);
        let Some((first, interval, stretch)) = self.next_stretch() else {
            return;
        };
        let Some(m) = self.motion.as_mut() else {
            return;
        };
        let fit = if stretch <= 1 || interval == Duration::ZERO {
            stretch
        } else {
            let span = horizon.saturating_since(first).as_nanos() / interval.as_nanos();
            u32::try_from(span.saturating_add(1))
                .unwrap_or(u32::MAX)
                .min(stretch)
        };
        let last = first + interval.saturating_mul(u64::from(fit - 1));
        let new_move = m.emitted == 0;
        let dir = m.dir;
        let steps_phases = !m.pout;
        m.emitted += fit;
        m.last_pulse = Some(last);
        if m.emitted < m.end {
            m.next_pulse = last + m.interval_after(m.emitted - 1);
        }
        let done = m.emitted >= m.end;
        let at_speed = m.at_high_speed();
        let (id, kind, base) = (m.id, m.kind, m.base);
        // Fault: the final pulse of the move never reaches the wire.
        let on_wire = if done && self.cfg.faults.drop_last_pulse {
            fit - 1
        } else {
            fit
        };
        self.record
            .push_pulses(first, interval, on_wire, dir, new_move);
        if steps_phases {
            if let Some(w) = self.winding {
                // Fault: the first step of each move never reaches the phases.
                let skipped = u64::from(new_move && self.cfg.faults.phase_step_skipped);
                let steps = u64::from(fit) - skipped;
                self.phase_index = w.advance(self.phase_index, dir, steps);
            }
        }
        self.now = last;
        if pout_hs_check && at_speed && !done {
            self.high_speed_limit(true);
        }
        if done {
            let end = if kind == MoveKind::SingleStep {
                base + self.fw(self.cfg.single_step_done)
            } else {
                last + self.fw(self.cfg.interrupt_delay)
            };
            self.schedule(end, Timer::Terminate { id });
        }
        if self.pick_starved && !self.starved() {
            self.pick_starved = false;
            let at = self.now.max(self.proc_free_at);
            self.schedule_pick(at);
        }
    }

    // ----- timers ---------------------------------------------------------

    fn fw(&self, d: Duration) -> Duration {
        self.straps.firmware_time(d)
    }

    fn schedule(&mut self, at: Instant, timer: Timer) -> u64 {
        self.timer_seq += 1;
        self.timers.push((at.max(self.now), self.timer_seq, timer));
        self.timer_seq
    }

    fn next_timer(&self) -> Option<(Instant, usize)> {
        self.timers
            .iter()
            .enumerate()
            .min_by_key(|(_, (at, seq, _))| (*at, *seq))
            .map(|(i, (at, _, _))| (*at, i))
    }

    fn fire(&mut self, timer: Timer) {
        let now = self.now;
        match timer {
            Timer::Pick => self.pick(),
            Timer::ObfReady => {
                if let Some(b) = self.out_pending.pop_front() {
                    self.out_latch = b;
                    self.obf = true;
                }
            }
            Timer::InitOutputs { epoch } if epoch == self.config_epoch => {
                self.phases_on = true;
                self.record_phases();
            }
            Timer::InitDone { epoch } if epoch == self.config_epoch && self.motion.is_none() => {
                self.set_hold(true);
                self.start_switching_if_enabled();
            }
            Timer::BusyRise { id } if self.motion_id() == Some(id) => {
                self.busy = true;
                self.record.pin(now, Pin::Busy, 1);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.set_switching(None);
                let shown = |d: Direction| match (d, self.cfg.faults.dir_inverted) {
                    (d, false) => d,
                    (Direction::Cw, true) => Direction::Ccw,
                    (Direction::Ccw, true) => Direction::Cw,
                };
                if let Some(dir) = self.motion.as_ref().map(|m| shown(m.dir)) {
                    if dir != self.dir {
                        self.dir = dir;
                        self.record.pin(now, Pin::Dir, u8::from(dir.bit()));
                    }
                }
            }
            Timer::DecelStart { id, cause } if self.motion_id() == Some(id) => {
                if let Some(m) = self.motion.as_mut() {
                    if m.pulses_left() && m.begin_decel() {
                        m.cause = cause;
                    }
                }
            }
            Timer::Terminate { id } if self.motion_id() == Some(id) => self.terminate(),
            Timer::HoldOn { epoch } if epoch == self.hold_epoch => {
                self.set_hold(true);
                self.start_switching_if_enabled();
            }
            Timer::Aux(on) if self.aux != on => {
                self.aux = on;
                self.record.pin(now, Pin::Aux, u8::from(on));
            }
            Timer::Auxo(bits) if self.auxo != bits => {
                self.auxo = bits;
                self.record.pin(now, Pin::Auxo, bits);
            }
            Timer::ExcitationOff { epoch } if epoch == self.config_epoch => {
                self.phases_on = false;
                self.phase_index = 0;
                self.set_switching(None);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.record_phases();
            }
            // A timer whose move or configuration has since been replaced.
            _ => {}
        }
    }

    fn motion_id(&self) -> Option<u64> {
        self.motion.as_ref().map(|m| m.id)
    }

    fn terminate(&mut self) {
        let Some(m) = self.motion.take() else { return };
        let now = self.now;
        self.busy = false;
        self.record.pin(now, Pin::Busy, 0);
        self.finish = FinishStatus::new(m.kind, m.cause, true);
        self.remaining = m.remaining();
        if m.interrupt || self.cfg.faults.int_unmasked {
            self.set_int(true);
        }
        let next = if m.kind == MoveKind::SingleStep {
            now
        } else {
            now + self.fw(self
                .cfg
                .next_command
                .saturating_sub(self.cfg.interrupt_delay))
        };
        self.proc_free_at = self.proc_free_at.max(next);
        let epoch = self.hold_epoch;
        let hold_at = m.last_pulse.unwrap_or(now) + self.fw(self.cfg.hold_on);
        self.schedule(hold_at, Timer::HoldOn { epoch });
        if self.pick_starved {
            self.pick_starved = false;
            let at = self.proc_free_at.max(now);
            self.schedule_pick(at);
        }
    }

    // ----- outputs --------------------------------------------------------

    fn set_int(&mut self, asserted: bool) {
        if self.int != asserted {
            self.int = asserted;
            self.record.pin(self.now, Pin::Int, u8::from(asserted));
        }
    }

    fn set_hold(&mut self, on: bool) {
        if on && self.cfg.faults.hold_stuck_off {
            return;
        }
        if self.hold != on {
            self.hold = on;
            self.record.pin(self.now, Pin::Hold, u8::from(on));
        }
    }

    fn start_switching_if_enabled(&mut self) {
        let enabled = self.setup.as_ref().is_some_and(|s| s.stop_switching);
        if enabled && self.phases_on {
            self.set_switching(Some(self.now));
        }
    }

    fn set_switching(&mut self, since: Option<Instant>) {
        if self.switching_since.is_some() != since.is_some() {
            self.record
                .pin(self.now, Pin::Switching, u8::from(since.is_some()));
        }
        self.switching_since = since;
    }

    fn record_phases(&mut self) {
        let p = self.energized_pattern();
        self.record.pin(self.now, Pin::Phases, p);
    }

    /// Energized phases ignoring stop switching.
    fn energized_pattern(&self) -> u8 {
        match (self.phases_on, self.winding) {
            (true, Some(w)) => w.pattern(self.phase_index),
            _ => 0,
        }
    }

    /// Energized phases at `t`, with stop switching chopping them.
    fn energized(&self, t: Instant) -> u8 {
        let p = self.energized_pattern();
        match self.switching_since {
            Some(since) => {
                let cycle = (self.switch_on + self.switch_off).as_nanos().max(1);
                let phase = t.saturating_since(since).as_nanos() % cycle;
                if phase < self.switch_on.as_nanos() {
                    p
                } else {
                    0
                }
            }
            None => p,
        }
    }

    /// Pin levels of S1..S5 for an energized pattern (Section 3-2-1).
    fn levels(&self, energized: u8) -> u8 {
        match self.logic {
            OutputLogic::Positive => energized,
            OutputLogic::Negative => !energized & 0x1F,
        }
    }
}
