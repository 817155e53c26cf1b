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
use super::motion::{AccelRamp, Motion, Profile, Ramp, Stretch};
use crate::protocol::capture::{MoveStart, OutputMark, OutputRecord, Pin, Pins};
use crate::protocol::{
    AuxInputStatus, Chop, ClockSource, Command, Direction, ErrorCode, FinishStatus, InitCommand,
    InitData, Input, InputSet, InputStatus, MoveCommand, MoveKind, OutputLogic, OutputStatus,
    PhaseOutputs, PulseCount, Register, Status, StatusField, StopCause, Straps, StrapsError,
    Winding,
};
use crate::time::{Duration, Instant};
use alloc::collections::VecDeque;
use alloc::vec::Vec;

mod host;
mod moves;

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
    /// When the host wrote it.
    written: Instant,
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
    /// Acceleration periods and high-speed period, `None` without a clock.
    ramp: Option<(Ramp, Duration)>,
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
    /// `cfg` with its latencies in this board's firmware time
    /// ([`Straps::firmware_time`]), scaled once.
    fw_cfg: ModelConfig,
    now: Instant,
    timers: Vec<(Instant, u64, Timer)>,
    timer_seq: u64,

    // Host interface (Section 3-1).
    inbuf: Option<InByte>,
    pick_timer: Option<u64>,
    pick_starved: bool,
    /// When the host wrote the byte the firmware is working on: a move
    /// record's time (note N47).
    taken_written: Instant,
    proc_free_at: Instant,
    field: StatusField,
    expect: Expect,
    out_pending: VecDeque<u8>,
    obf: bool,
    out_latch: u8,

    // Initialization (Section 3-2).
    winding: Option<Winding>,
    /// The winding the phase outputs follow. It is `winding` except after
    /// a software reset: the reset cancels the initialization when it is
    /// taken, but the phases stay energized until Table 3-3's excitation
    /// OFF time has passed (note N36).
    out_winding: Option<Winding>,
    logic: OutputLogic,
    /// When the output logic was last changed.
    logic_since: Instant,
    setup: Option<Setup>,
    switch_on: Duration,
    switch_off: Duration,
    /// An initialization is being processed: no stop switching until it
    /// completes (3-2-1 (3), notes N39).
    initializing: bool,
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

    record: OutputRecord,
    /// The ramp of the last initialization, kept for the next one with
    /// the same rates, clock and PA, and across [`Chip::reset`]: its steps
    /// are a pure function of those, and fuzz inputs initialize alike.
    ramp_cache: RampCache,
}

/// What [`Chip::reset`] keeps of a chip for the fresh one: the memory of
/// its timers, its record and its output buffer (emptied), and its ramp
/// cache.
#[derive(Default)]
struct Kept {
    timers: Vec<(Instant, u64, Timer)>,
    record: OutputRecord,
    out_pending: VecDeque<u8>,
    ramp_cache: RampCache,
}

/// A cache, not state: shown as its size only, so a reset chip prints as
/// a new one.
#[derive(Clone, Default)]
struct RampCache(Option<Ramp>);

impl core::fmt::Debug for RampCache {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("RampCache")
    }
}

impl Chip {
    /// A chip straight out of power-on reset.
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Chip, ChipError> {
        straps.validate()?;
        cfg.validate()?;
        let fw_cfg = cfg.map_latencies(|d| straps.firmware_time(d));
        Ok(Chip::fresh(straps, cfg, fw_cfg, Kept::default()))
    }

    /// The chip out of power-on reset with straps and a configuration
    /// already validated (and its latencies in firmware time, `fw_cfg`),
    /// taking over the memory of `kept`.
    fn fresh(straps: Straps, cfg: ModelConfig, fw_cfg: ModelConfig, kept: Kept) -> Chip {
        let Kept {
            timers,
            record,
            out_pending,
            ramp_cache,
        } = kept;
        Chip {
            switch_on: fw_cfg.switching_on,
            switch_off: fw_cfg.switching_off,
            initializing: false,
            straps,
            cfg,
            fw_cfg,
            now: Instant::ZERO,
            timers,
            timer_seq: 0,
            inbuf: None,
            pick_timer: None,
            pick_starved: false,
            taken_written: Instant::ZERO,
            proc_free_at: Instant::ZERO,
            field: StatusField::ParamsRemaining(0),
            expect: Expect::Command,
            out_pending,
            obf: false,
            out_latch: 0,
            winding: None,
            out_winding: None,
            logic: OutputLogic::Negative,
            logic_since: Instant::ZERO,
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
            record,
            ramp_cache,
        }
    }

    /// Back to the chip [`Chip::new`] made, with the same straps and
    /// configuration, keeping the memory of its record and its timers: a
    /// fuzz target runs a fresh chip for every input.
    pub fn reset(&mut self) {
        let mut kept = Kept {
            timers: core::mem::take(&mut self.timers),
            record: core::mem::take(&mut self.record),
            out_pending: core::mem::take(&mut self.out_pending),
            ramp_cache: self.keep_ramp(),
        };
        kept.timers.clear();
        kept.record.clear();
        kept.out_pending.clear();
        // `new` validated these straps and this configuration when it made
        // this chip: a fuzz target resets it for every input, and checking
        // them again each time cost it time and coverage counters.
        *self = Chip::fresh(self.straps, self.cfg.clone(), self.fw_cfg.clone(), kept);
    }

    /// The ramp worth keeping: the one in force (it may have computed more
    /// steps since it was cached), else the one cached.
    fn keep_ramp(&mut self) -> RampCache {
        let current = self.setup.as_ref().and_then(|s| s.ramp.as_ref());
        match current {
            Some((ramp, _)) => RampCache(Some(ramp.clone())),
            None => core::mem::take(&mut self.ramp_cache),
        }
    }

    /// The ramp `accel` describes, with the steps already computed when
    /// the last initialization (or the chip before a reset) had it.
    fn ramp_of(&mut self, accel: AccelRamp) -> Ramp {
        let cache = self.keep_ramp();
        let ramp = match cache.0 {
            Some(r) if r.is_of(&accel) => r,
            _ => Ramp::new(accel),
        };
        self.ramp_cache = RampCache(Some(ramp.clone()));
        ramp
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
    pub fn record(&self) -> &OutputRecord {
        &self.record
    }

    /// Drops the record before `mark` as far as the model allows
    /// ([`OutputRecord::forget_before`]: it still reads the last move's pulses);
    /// what was dropped. For a long differential run, which has compared
    /// everything before its last point of rest.
    pub fn forget_record_before(&mut self, mark: OutputMark) -> OutputMark {
        self.record.forget_before(mark)
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
        Status::new(self.obf, self.inbuf.is_some(), self.busy, self.field)
    }

    /// Host read of the data register (A = L, RD low). Reading with OBF = 0
    /// returns the stale latch (Section 3-1-1 (1): "the data are invalid").
    pub fn read_data(&mut self) -> u8 {
        if self.obf {
            self.obf = self.cfg.faults.obf_sticky;
            if !self.out_pending.is_empty() {
                let at = self.now + self.fw_cfg.obf_next;
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

    /// The output logic and stop switching's ON and OFF times in force:
    /// with the record's phase patterns, switching and pulses, what the
    /// levels of S1..S5 were (the capture judge draws them so).
    pub fn phase_outputs(&self) -> PhaseOutputs {
        PhaseOutputs {
            logic: self.logic,
            logic_since: self.logic_since,
            on: self.switch_on,
            off: self.switch_off,
        }
    }

    /// When the output pins next change by themselves with no event of the
    /// model's (stop switching's chopping, Section 3-5-1): the first such
    /// time after now, if any. For a harness that follows the pins in time.
    pub fn next_pin_change(&self) -> Option<Instant> {
        self.next_chop(self.now)
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
        let next = m.next_pulse?;
        if n <= u64::from(m.emitted) {
            return None;
        }
        let s = m.stretch();
        let k = (n - u64::from(m.emitted)).min(u64::from(s.count));
        Some(next + s.interval.saturating_mul(k - 1))
    }

    /// The next instant at which the status register, a pin or the
    /// termination of a move can change; `None` when nothing is pending.
    /// During a constant-rate stretch this is the end of the stretch, not
    /// the next pulse, so waiting costs O(1) per stretch.
    pub fn poll_at(&self) -> Option<Instant> {
        let timer = self.next_timer().map(|(at, _)| at);
        let pulse = self
            .next_stretch()
            .map(|(first, s)| first + s.interval.saturating_mul(u64::from(s.count - 1)));
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
            let horizon = next_timer.map_or(until, |(at, _)| at.min(until));
            if self.pulse_due(horizon).is_some() {
                // The stretches due by the horizon, one after another: it
                // stands until emitting schedules a timer (a decision:
                // the move's end, a deceleration, the host served again).
                let seq = self.timer_seq;
                while let Some(pulse_at) = self.pulse_due(horizon) {
                    self.now = self.now.max(pulse_at);
                    self.emit_pulses(horizon);
                    if self.timer_seq != seq {
                        break;
                    }
                }
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

    /// When the move's next pulse comes, if it comes by `horizon`. A move
    /// without a base clock has no next pulse: it never comes, however far
    /// time is advanced.
    fn pulse_due(&self, horizon: Instant) -> Option<Instant> {
        self.motion
            .as_ref()
            .filter(|m| m.pulses_left())
            .and_then(|m| m.next_pulse)
            .filter(|at| *at <= horizon)
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
                let was = self.energized_pattern();
                self.phases_on = true;
                self.record_phases_from(was);
            }
            Timer::InitDone { epoch } if epoch == self.config_epoch && self.motion.is_none() => {
                self.initializing = false;
                self.set_hold(true);
                self.start_switching_if_enabled();
            }
            Timer::BusyRise { id } if self.motion_id() == Some(id) => {
                self.busy = true;
                self.record.pin(now, Pin::Busy, 1);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.set_switching(None);
                if let Some(dir) = self.motion.as_ref().map(|m| m.dir) {
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
                let was = self.energized_pattern();
                self.phases_on = false;
                self.out_winding = None;
                self.phase_index = 0;
                self.set_switching(None);
                self.hold_epoch += 1;
                self.set_hold(false);
                self.record_phases_from(was);
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
        let hold_at = m.last_pulse.unwrap_or(now) + self.fw_cfg.hold_on;
        self.schedule(hold_at, Timer::HoldOn { epoch });
        self.serve_again();
    }
}
