//! The bus vocabulary every driver of the chip speaks: an [`Op`] is one
//! bus-level operation (a register access, a wait, an input change, a look
//! at the pins or the pulse capture), a [`Reply`] its outcome stamped with
//! the time it ended on the clock of whoever ran it.
//!
//! A batch of ops runs back to back on the chip's side, which is why
//! waiting (for IBF, OBF, BUSY) is an op, never a host-side polling loop:
//! on a board behind the bus bridge a batch costs one round trip.
//!
//! [`Bus`] is what the bridge engine ([`crate::bridge::engine`]) drives: a
//! chip bus plus its pins and a pulse capture. [`EmuBus`] is the reference
//! model behind it; a bridge firmware implements it over the real chip.

use crate::bridge::abort_line::AbortLine;
use crate::emu::{Board, Chip, ChipError, ModelConfig};
use crate::protocol::{
    Flag, Input, OutputMark, OutputRecord, Pin, Pins, PulseSummary, Status, Straps,
};
use crate::time::{Duration, Instant};
use alloc::string::String;

/// One bus-level operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// Write the command register. With `wait_ibf`, first wait up to that
    /// long for IBF = 0 as the datasheet flowcharts do, and skip the write
    /// if IBF stays 1; without, write at once.
    WriteCommand {
        byte: u8,
        wait_ibf: Option<Duration>,
    },
    /// Write the data register; `wait_ibf` as for [`Op::WriteCommand`].
    WriteData {
        byte: u8,
        wait_ibf: Option<Duration>,
    },
    /// Read the status register.
    ReadStatus,
    /// Read the data register. With `wait_obf`, first wait up to that long
    /// for OBF = 1 and skip the read if it stays 0.
    ReadData { wait_obf: Option<Duration> },
    /// Let time pass.
    Delay(Duration),
    /// Wait until `status & mask == value`, at most `timeout`.
    AwaitStatus {
        mask: u8,
        value: u8,
        timeout: Duration,
    },
    /// Drive an input: `asserted` = the active-low pin pulled low.
    SetInput { input: Input, asserted: bool },
    /// Sample the output pins.
    ReadPins,
    /// Summarize the pulses of the most recent move.
    ReadPulses,
    /// Wait until the most recent move has output `count` pulses (at most
    /// `timeout`), so that the next op acts right after that pulse: how a
    /// scenario drives a limit switch "after N pulses" on the target's own
    /// clock.
    AwaitPulses { count: u64, timeout: Duration },
    /// Hardware reset of the chip (the RESET pin): registers, inputs and the
    /// capture start over, and the target's clock restarts at zero.
    Reset,
}

impl Op {
    /// Wait until a status flag has `value`, at most `timeout`.
    pub fn await_flag(flag: Flag, value: bool, timeout: Duration) -> Op {
        Op::AwaitStatus {
            mask: flag.mask(),
            value: if value { flag.mask() } else { 0 },
            timeout,
        }
    }
}

impl core::fmt::Display for Op {
    /// What the op does, in words: `write command 0x02 (waiting up to
    /// 1000000.000us for IBF = 0)`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let wait = |f: &mut core::fmt::Formatter<'_>, w: Option<Duration>, flag: &str| match w {
            Some(t) => write!(f, " (waiting up to {t} for {flag})"),
            None => Ok(()),
        };
        match *self {
            Op::WriteCommand { byte, wait_ibf } => {
                write!(f, "write command 0x{byte:02X}")?;
                wait(f, wait_ibf, "IBF = 0")
            }
            Op::WriteData { byte, wait_ibf } => {
                write!(f, "write data 0x{byte:02X}")?;
                wait(f, wait_ibf, "IBF = 0")
            }
            Op::ReadStatus => f.write_str("read status"),
            Op::ReadData { wait_obf } => {
                f.write_str("read data")?;
                wait(f, wait_obf, "OBF = 1")
            }
            Op::Delay(d) => write!(f, "wait {d}"),
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => write!(
                f,
                "wait up to {timeout} for status & 0x{mask:02X} = 0x{value:02X}"
            ),
            Op::SetInput { input, asserted } => write!(
                f,
                "{} {}",
                if asserted { "assert" } else { "release" },
                input.name()
            ),
            Op::ReadPins => f.write_str("sample the pins"),
            Op::ReadPulses => f.write_str("count the pulses"),
            Op::AwaitPulses { count, timeout } => {
                write!(f, "wait up to {timeout} for pulse {count}")
            }
            Op::Reset => f.write_str("chip reset"),
        }
    }
}

/// The outcome of one [`Op`], stamped with the target's time when it ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    /// A write happened at `at`, after waiting `waited` for IBF = 0 (zero
    /// for a write without a wait).
    Written {
        at: Instant,
        waited: Duration,
    },
    /// IBF stayed 1 for the whole wait; nothing was written.
    WriteTimedOut {
        at: Instant,
        status: Status,
    },
    Status {
        at: Instant,
        status: Status,
    },
    /// A data register read at `at`, after waiting `waited` for OBF = 1.
    Data {
        at: Instant,
        byte: u8,
        waited: Duration,
    },
    /// OBF stayed 0 for the whole wait; nothing was read.
    ReadTimedOut {
        at: Instant,
        status: Status,
    },
    Delayed {
        at: Instant,
    },
    /// The condition held after `waited`.
    Awaited {
        at: Instant,
        waited: Duration,
        status: Status,
    },
    AwaitTimedOut {
        at: Instant,
        status: Status,
    },
    InputSet {
        at: Instant,
    },
    Pins {
        at: Instant,
        pins: Pins,
    },
    Pulses {
        at: Instant,
        summary: PulseSummary,
    },
    /// The pulse count was reached; `at` is the time of that pulse, or
    /// when the wait began if the pulse came before it (the wait then
    /// ends at once: no reply is stamped before the op ahead of it).
    PulsesReached {
        at: Instant,
    },
    /// The move ended or the timeout passed first; `count` pulses were seen.
    PulsesTimedOut {
        at: Instant,
        count: u64,
    },
    ResetDone {
        at: Instant,
    },
}

impl Reply {
    /// The target time at which the op completed.
    pub fn at(&self) -> Instant {
        match *self {
            Reply::Written { at, .. }
            | Reply::WriteTimedOut { at, .. }
            | Reply::Status { at, .. }
            | Reply::Data { at, .. }
            | Reply::ReadTimedOut { at, .. }
            | Reply::Delayed { at }
            | Reply::Awaited { at, .. }
            | Reply::AwaitTimedOut { at, .. }
            | Reply::InputSet { at }
            | Reply::Pins { at, .. }
            | Reply::Pulses { at, .. }
            | Reply::PulsesReached { at }
            | Reply::PulsesTimedOut { at, .. }
            | Reply::ResetDone { at } => at,
        }
    }
}

impl core::fmt::Display for Reply {
    /// What came back, in words: `status 0x8E at 120.000us`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Reply::Written { .. } => f.write_str("written")?,
            Reply::WriteTimedOut { status, .. } => {
                write!(f, "write skipped, IBF stayed 1 (status 0x{:02X})", status.0)?
            }
            Reply::Status { status, .. } => write!(f, "status 0x{:02X}", status.0)?,
            Reply::Data { byte, .. } => write!(f, "data 0x{byte:02X}")?,
            Reply::ReadTimedOut { status, .. } => {
                write!(f, "read skipped, OBF stayed 0 (status 0x{:02X})", status.0)?
            }
            Reply::Delayed { .. } => f.write_str("waited")?,
            Reply::Awaited { status, .. } => {
                write!(f, "condition met (status 0x{:02X})", status.0)?
            }
            Reply::AwaitTimedOut { status, .. } => {
                write!(f, "timed out (status 0x{:02X})", status.0)?
            }
            Reply::InputSet { .. } => f.write_str("input set")?,
            Reply::Pins { .. } => f.write_str("pins")?,
            Reply::Pulses { summary, .. } => write!(f, "{} pulses", summary.count)?,
            Reply::PulsesReached { .. } => f.write_str("pulse count reached")?,
            Reply::PulsesTimedOut { count, .. } => write!(f, "timed out after {count} pulses")?,
            Reply::ResetDone { .. } => f.write_str("reset done")?,
        }
        write!(f, " at {}", self.at())
    }
}

/// How sure the times a bus gives are (plus or minus), by the path each
/// was taken on (`docs/bridge-protocol.md` section 4): a bridge stamps some
/// edges in hardware as they happen, samples other outputs with its CPU,
/// and finds a status flag's change by polling the status register. The
/// reference model's times are exact: all four 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Uncertainty {
    /// An edge the capture stamps as it happens: POUT's pulses, and the
    /// changes of INT*, HOLD and AUX*.
    pub edge: Duration,
    /// An output the bridge samples: the changes of S1..S5 (the phases and
    /// stop switching), AUXO0..3 and DIR in the capture.
    pub sampled: Duration,
    /// A bus access's stamp (the strobe of a write or a read, a pin read)
    /// and an input's change.
    pub access: Duration,
    /// A status flag's change found by polling the status register: BUSY's
    /// changes in the capture, and the end of a wait for IBF, OBF or BUSY.
    pub polled: Duration,
}

impl Uncertainty {
    /// Exact times (the reference model).
    pub const ZERO: Uncertainty = Uncertainty {
        edge: Duration::ZERO,
        sampled: Duration::ZERO,
        access: Duration::ZERO,
        polled: Duration::ZERO,
    };

    /// The uncertainty of a change of `pin` in the capture.
    pub fn of_pin(&self, pin: Pin) -> Duration {
        match pin {
            Pin::Int | Pin::Hold | Pin::Aux => self.edge,
            Pin::Auxo | Pin::Dir | Pin::Phases | Pin::Switching => self.sampled,
            Pin::Busy => self.polled,
        }
    }

    /// Whether BUSY is found by reading the status register, its polled
    /// flags less sure than an access (the RP2350 bridge, its twin): a
    /// BUSY that rises and falls between two reads leaves no change in the
    /// capture. `ppmc bridge-sim` declares them alike, and sees BUSY as
    /// exactly as its own accesses.
    pub fn polls_busy(&self) -> bool {
        self.polled > self.access
    }

    /// A pass of the loop that polls the status register (up to twice
    /// `polled`) and an access after it: how long after the chip changed a
    /// flag a bridge may act on it, or stamp the change, where it reads
    /// the status register steadily. Zero for exact times.
    pub fn poll_pass(&self) -> Duration {
        match self.polled > Duration::ZERO {
            true => self.polled.saturating_mul(2) + self.access,
            false => Duration::ZERO,
        }
    }

    /// Each path at least `floor` (a timer's tick: no time on the wire is
    /// surer than that).
    pub fn at_least(self, floor: Duration) -> Uncertainty {
        Uncertainty {
            edge: self.edge.max(floor),
            sampled: self.sampled.max(floor),
            access: self.access.max(floor),
            polled: self.polled.max(floor),
        }
    }
}

/// A chip bus plus its pins and a pulse capture: what the bridge engine
/// drives. The reference model implements it ([`EmuBus`]); a bridge
/// firmware implements it over the real chip's bus, pins and edge capture.
pub trait Bus {
    /// Runs one op on the bus's own clock and says how it ended.
    fn run(&mut self, op: Op) -> Reply;

    /// The op that follows the one about to run in the same batch, if any.
    /// A [`Op::Delay`] is the time from the moment of the op before it to
    /// the moment of the op after it; on the reference model ops take no
    /// time, but a bridge's bus cycles do (a write's moment is WR*'s rise,
    /// after its setup and strobe), so a bridge ends a delay early by the
    /// time the next op takes to reach its moment.
    fn next_op(&mut self, _next: Option<Op>) {}

    /// The batch in flight ends here, before the op [`Bus::next_op`] last
    /// named (an ABORT, a full capture): nothing prepared for that op may
    /// serve another.
    fn abandon(&mut self) {}

    /// Runs `pairs` `(ReadPins, Delay(step))` pairs as one (the SAMPLE ops
    /// of the bridge protocol in a row), `after` the op that follows them, and hands
    /// each op's reply to `emit` in order, as [`Bus::run`] would have given
    /// them; `false` (the default) when the bus runs such pairs op by op.
    /// A bridge whose CPU spends microseconds on each op keeps a sampling
    /// grid finer than that only so (firmware/README.md).
    fn sample_run(
        &mut self,
        _step: Duration,
        _pairs: usize,
        _after: Option<Op>,
        _emit: &mut dyn FnMut(Reply),
    ) -> bool {
        false
    }

    /// Everything captured on the output side since the last reset (or
    /// since what [`Bus::forget_record_before`] dropped).
    fn record(&self) -> &OutputRecord;

    /// Lets the bus drop its record before `mark` (a mark of
    /// [`Bus::record`]), which the host has fetched: what it dropped. The
    /// bridge engine counts the host's positions across it, so that a
    /// long session (a fuzz run of hours) holds a window of its capture,
    /// not its history. The default keeps everything, as a bridge whose
    /// capture is a ring buffer of its own may.
    fn forget_record_before(&mut self, _mark: OutputMark) -> OutputMark {
        OutputMark::default()
    }

    /// Called before the record is served to a host: settles what it
    /// holds tentatively, reading the chip if need be, and says how many of
    /// its last move records are still tentative, which are not served yet
    /// (a bridge that keeps its move records from the bus, by
    /// `move_tracker`, knows a move was taken only once a status read shows
    /// IBF = 0 after its last byte; a record served is never withdrawn).
    /// The default: nothing is tentative.
    fn settle_record(&mut self) -> usize {
        0
    }

    /// The chip's straps (system clock, CSEL, VSEL, external clock).
    fn straps(&self) -> Straps;

    /// The bus's clock: time since the last reset.
    fn now(&self) -> Instant;

    /// How sure the times this bus gives are, by path (HELLO_REPLY's
    /// `uncertainty`): exact (0) unless it says otherwise. The bridge
    /// engine raises each to at least one tick of its timer.
    fn uncertainty(&self) -> Uncertainty {
        Uncertainty::ZERO
    }

    /// Whether the capture lost anything since the last reset (a buffer
    /// that filled faster than it was drained): the bridge then answers
    /// CAPTURE_OVERRUN, never a capture with a hole in it.
    fn capture_lost(&self) -> bool {
        false
    }

    /// The bridge's own hardware failed (a state machine that never
    /// finished a bus cycle): what, for the host. Every later request is
    /// answered with it (`BridgeErrorCode::Hardware`) until the bridge is
    /// reset; the board is not to blame.
    fn fault(&self) -> Option<&str> {
        None
    }

    /// Runs a bridge's self-test of its capture ([`SelfTestPlan`]): its
    /// own pulse generator drives the capture inputs of POUT and INT* with
    /// the chip's outputs cut off, and the capture records what it saw
    /// from a fresh start (as after [`Op::Reset`], which the chip also
    /// gets). What the generator was asked is in the reply; what it did,
    /// the capture says. A bus with no generator (the reference model)
    /// says why not.
    fn self_test(&mut self, _plan: &SelfTestPlan) -> Result<SelfTestReply, String> {
        Err("this bridge has no self-test generator".into())
    }

    /// The line an ABORT raises ([`AbortLine`]): a bus whose ops can take
    /// long on a wall clock (a board's waits, a simulator paced to real
    /// time) ends a wait early once it is [pending](AbortLine::pending),
    /// with any reply (the request's answer is ERROR `ABORTED`). A bus in
    /// virtual time, done in an instant, need not look.
    fn watch_abort(&mut self, _line: AbortLine) {}
}

/// What a bridge's self-test generates: `bursts` bursts of `count`
/// pulses, each high for `high` then low for `low`, and `gap` of low
/// between one burst's last pulse and the next burst. The bridge rounds
/// each time to its own resolution and says what it used
/// ([`SelfTestReply`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SelfTestPlan {
    pub count: u32,
    pub high: Duration,
    pub low: Duration,
    pub bursts: u16,
    pub gap: Duration,
}

impl SelfTestPlan {
    /// How long the generator runs: every burst, each followed by its gap.
    pub fn length(&self) -> Duration {
        let burst = (self.high + self.low).saturating_mul(u64::from(self.count)) + self.gap;
        burst.saturating_mul(u64::from(self.bursts))
    }
}

/// A self-test's schedule as the bridge ran it: when each burst's first
/// pulse rose on the bridge's clock (the record's time, from the fresh
/// start), and the high and low times it generated, rounded to its
/// resolution.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SelfTestReply {
    pub starts: alloc::vec::Vec<Instant>,
    pub high: Duration,
    pub low: Duration,
}

/// The reference model as a [`Bus`]: ops run in virtual time, and waits
/// are resolved exactly by jumping from one model event to the next.
#[derive(Debug, Clone)]
pub struct EmuBus {
    /// The model behind its board: status reads, here and in every wait,
    /// pass the board's bus faults.
    board: Board,
    cfg: ModelConfig,
    /// How long a register access takes on the bus; zero (the default):
    /// an access takes no time, as the golden traces are recorded.
    bus_cycle: Duration,
    /// How the host times an access it waits for ([`HostTiming`]).
    host: HostTiming,
}

/// How a host on a real bus times an access that waits for the chip (a
/// write for IBF = 0, a read for OBF = 1, a status wait), with
/// [`EmuBus::set_bus_cycle`]'s cycle per access.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum HostTiming {
    /// It polls the status, and its access ends a bus cycle after the
    /// poll that saw the chip ready (the chapter's flowcharts).
    #[default]
    Polling,
    /// It waits Table 3-3's times instead of polling, and its access ends
    /// the instant the chip is ready (or a bus cycle after its last
    /// access, if later): the edge case of a host that writes each byte
    /// exactly when the chip allows it. A logic analyzer's sampling then
    /// cannot say on which side of the flag's change the access fell.
    Exact,
}

impl EmuBus {
    pub fn new(straps: Straps, cfg: ModelConfig) -> Result<Self, ChipError> {
        Ok(EmuBus {
            board: Board::new(straps, cfg.clone())?,
            cfg,
            bus_cycle: Duration::ZERO,
            host: HostTiming::Polling,
        })
    }

    /// Makes every register access take `cycle` of the chip's time, the
    /// access happening at its end (a write latched as WR* rises, a read
    /// sampled as RD* rises), and a status wait end with the poll that saw
    /// it: a host on a real bus, whose accesses never share an instant.
    /// What `ppmc export --scenario` records its captures with.
    pub fn set_bus_cycle(&mut self, cycle: Duration) {
        self.bus_cycle = cycle;
    }

    /// How the host times an access it waits for ([`HostTiming`]).
    pub fn set_host_timing(&mut self, host: HostTiming) {
        self.host = host;
    }

    /// An access that waited since `start` ends now: a bus cycle on
    /// (polling), or now if a cycle since `start` has passed (exact).
    fn cycle_after_wait(&mut self, start: Instant) {
        match self.host {
            HostTiming::Polling => self.cycle(),
            HostTiming::Exact => {
                let to = start + self.bus_cycle;
                if to > self.board.now() {
                    self.board.advance_to(to);
                }
            }
        }
    }

    /// One bus cycle passes.
    fn cycle(&mut self) {
        if self.bus_cycle > Duration::ZERO {
            let to = self.board.now() + self.bus_cycle;
            self.board.advance_to(to);
        }
    }

    /// The model itself (its own status, without the board).
    pub fn chip(&self) -> &Chip {
        self.board.chip()
    }

    pub fn chip_mut(&mut self) -> &mut Chip {
        self.board.chip_mut()
    }

    /// The model on its board, as the bus sees it.
    pub fn board(&self) -> &Board {
        &self.board
    }

    /// Drops the record before `mark` as far as the model allows
    /// ([`Board::forget_record_before`]); what was dropped.
    pub fn forget_record_before(&mut self, mark: OutputMark) -> OutputMark {
        self.board.forget_record_before(mark)
    }

    /// The model configuration the chip was built with (and is rebuilt
    /// with on [`Op::Reset`]).
    pub fn config(&self) -> &ModelConfig {
        &self.cfg
    }

    /// Waits until `status & mask == value` or `timeout` has passed.
    /// `Ok(waited)` or `Err(())` on timeout; the chip's clock stands at the
    /// moment the condition first held, or at the deadline.
    fn wait_for(&mut self, mask: u8, value: u8, timeout: Duration) -> Result<Duration, ()> {
        let start = self.board.now();
        let deadline = start + timeout;
        loop {
            let now = self.board.now();
            if self.board.read_status().0 & mask == value {
                return Ok(now.saturating_since(start));
            }
            match self.board.poll_at() {
                Some(t) if t > now && t <= deadline => self.board.advance_to(t),
                // Due now: advancing to `now` has processed it already, so a
                // second look cannot change anything before the next event.
                Some(t) if t <= now => {
                    self.board.advance_to(now + Duration::from_nanos(1));
                }
                _ => {
                    self.board.advance_to(deadline);
                    let status = self.board.read_status();
                    return if status.0 & mask == value {
                        Ok(timeout)
                    } else {
                        Err(())
                    };
                }
            }
        }
    }

    /// Waits until the move has output `count` pulses. Stops exactly at
    /// that pulse, even inside a constant-rate stretch.
    fn wait_pulses(&mut self, count: u64, timeout: Duration) -> Result<Instant, u64> {
        let deadline = self.board.now() + timeout;
        loop {
            if self.board.move_pulses() >= count {
                return Ok(self.board.now());
            }
            let next = match (self.board.predict_pulse(count), self.board.poll_at()) {
                (Some(a), Some(b)) => a.min(b),
                (a, b) => match a.or(b) {
                    Some(t) => t,
                    None => break,
                },
            };
            if next > deadline {
                break;
            }
            let now = self.board.now();
            self.board
                .advance_to(next.max(now + Duration::from_nanos(1)).min(deadline));
        }
        self.board.advance_to(deadline.max(self.board.now()));
        Err(self.board.move_pulses())
    }

    fn status_at(&self) -> (Instant, Status) {
        (self.board.now(), self.board.read_status())
    }

    fn run_op(&mut self, op: Op) -> Reply {
        match op {
            Op::WriteCommand { byte, wait_ibf } | Op::WriteData { byte, wait_ibf } => {
                let mut waited = Duration::ZERO;
                let start = self.board.now();
                if let Some(timeout) = wait_ibf {
                    match self.wait_for(Status::IBF, 0, timeout) {
                        Ok(w) => waited = w,
                        Err(()) => {
                            let (at, status) = self.status_at();
                            return Reply::WriteTimedOut { at, status };
                        }
                    }
                }
                self.cycle_after_wait(start);
                if matches!(op, Op::WriteCommand { .. }) {
                    self.board.write_command(byte);
                } else {
                    self.board.write_data(byte);
                }
                Reply::Written {
                    at: self.board.now(),
                    waited,
                }
            }
            Op::ReadStatus => {
                self.cycle();
                let (at, status) = self.status_at();
                Reply::Status { at, status }
            }
            Op::ReadData { wait_obf } => {
                let mut waited = Duration::ZERO;
                let start = self.board.now();
                if let Some(timeout) = wait_obf {
                    match self.wait_for(Status::OBF, Status::OBF, timeout) {
                        Ok(w) => waited = w,
                        Err(()) => {
                            let (at, status) = self.status_at();
                            return Reply::ReadTimedOut { at, status };
                        }
                    }
                }
                self.cycle_after_wait(start);
                let byte = self.board.read_data();
                Reply::Data {
                    at: self.board.now(),
                    byte,
                    waited,
                }
            }
            Op::Delay(d) => {
                let to = self.board.now() + d;
                self.board.advance_to(to);
                Reply::Delayed { at: to }
            }
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => {
                let start = self.board.now();
                let result = self.wait_for(mask, value & mask, timeout);
                // The poll that saw it (or the last one) ends a cycle on;
                // an exact host's read ends as the status changes.
                self.cycle_after_wait(start);
                let (at, status) = self.status_at();
                match result {
                    Ok(waited) => Reply::Awaited { at, waited, status },
                    Err(()) => Reply::AwaitTimedOut { at, status },
                }
            }
            Op::SetInput { input, asserted } => {
                self.board.set_input(input, asserted);
                Reply::InputSet {
                    at: self.board.now(),
                }
            }
            Op::ReadPins => Reply::Pins {
                at: self.board.now(),
                pins: self.board.pins(),
            },
            Op::ReadPulses => Reply::Pulses {
                at: self.board.now(),
                summary: self.board.record().last_move_pulses(),
            },
            Op::AwaitPulses { count, timeout } => match self.wait_pulses(count, timeout) {
                Ok(at) => Reply::PulsesReached { at },
                Err(count) => Reply::PulsesTimedOut {
                    at: self.board.now(),
                    count,
                },
            },
            Op::Reset => {
                // Straps and config were validated when the target was built.
                if let Ok(board) = Board::new(*self.board.straps(), self.cfg.clone()) {
                    self.board = board;
                }
                Reply::ResetDone {
                    at: self.board.now(),
                }
            }
        }
    }
}

impl Bus for EmuBus {
    fn forget_record_before(&mut self, mark: OutputMark) -> OutputMark {
        EmuBus::forget_record_before(self, mark)
    }

    fn run(&mut self, op: Op) -> Reply {
        self.run_op(op)
    }

    fn record(&self) -> &OutputRecord {
        self.board.record()
    }

    fn straps(&self) -> Straps {
        *self.board.straps()
    }

    fn now(&self) -> Instant {
        self.board.now()
    }
}
