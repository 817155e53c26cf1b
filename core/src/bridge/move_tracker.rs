//! The move records of a bridge's capture (`docs/bridge-protocol.md`
//! section 7), kept by watching the bus: which command bytes the bridge
//! wrote, what the status register said after them, and which phase
//! pattern the chip was showing. This is what a bridge firmware does; the
//! reference model writes its own records from the inside, and
//! [`Tracked`] checks that the two agree, on the whole suite.
//!
//! - A move record is written at the final byte of a move command (its
//!   `at`: that byte's write), with the kind, direction, POUT mode and step
//!   count from the command and its parameters (Sections 3-3-3 to 3-3-8).
//! - The first status read after it that shows IBF = 0 settles it: the
//!   chip has taken the byte then (Section 3-1-1), and the error flag means
//!   it refused the command (Table 3-2: during BUSY, before an
//!   initialization; N6: an error is raised as the byte is taken), so the
//!   record is withdrawn. A read that still shows IBF = 1 shows the state
//!   from before the byte, the error of a command before included, and
//!   settles nothing. Until settled, a record is tentative: the last one,
//!   never served to a host ([`Bus::settle_record`]).
//! - A byte written within 3 us of a status read (since the byte before)
//!   that showed IBF = 1 replaces that byte (3-1-1 (2)): what the byte
//!   before did (a parameter counted, a command begun, a record) is
//!   undone. With no read between, or an older one, the byte before is
//!   taken as taken.
//! - The winding is that of the first initialization since reset whose
//!   data the chip accepts (Section 3-2, Table 3-2 errors 4 and 5), settled
//!   the same way; a software reset that is not the AUX ON quirk
//!   (3-5-4: sent during BUSY) forgets it.
//! - The phase is read, not modelled: the step of the winding's sequence
//!   whose pattern the chip's S1..S5 show at the final byte (0 while the
//!   phases are off).

use crate::bus::{Bus, Op, Reply};
use crate::emu::{PA_MAX, PA_MIN};
use crate::protocol::{
    Command, InitData, MoveCommand, MoveKind, MoveStart, OutputLogic, OutputRecord, PulseCount,
    Status, Straps, Winding,
};
use crate::time::Instant;

/// A write this soon after a status read that showed the byte before
/// still waiting (IBF = 1) replaced it: the chip takes a byte within
/// microseconds once it may (N11: 6 us after its write when idle), so a
/// read older than this says little of the byte at the write, which is
/// then taken as taken. A campaign reads the status right before each op.
const REPLACED_WITHIN: crate::time::Duration = crate::time::Duration::from_micros(3);

/// What a tentative record is: undone, if the chip refuses it, from
/// what the tracker knew before its last byte ([`Before`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tentative {
    /// A move record, the last of the record's moves.
    Move,
    /// An initialization: the winding, logic and stop switching it set.
    Init,
}

/// Keeps a record's move records from the bus traffic a bridge sees.
#[derive(Debug, Clone, Default)]
pub struct MoveTracker {
    /// The command whose parameter bytes are coming, and those so far.
    params: Option<(Command, [u8; 4], u8)>,
    /// The winding and output logic of the first accepted initialization
    /// since reset.
    winding: Option<(Winding, OutputLogic)>,
    /// An initialization the chip accepted since reset or software reset.
    initialized: bool,
    /// Whether the last accepted initialization asked for stop switching.
    switching: bool,
    /// BUSY as the last status read showed it.
    busy: bool,
    tentative: Option<Tentative>,
    /// When the last status read since the last write showed that byte
    /// still in the input buffer (IBF = 1).
    waiting_seen: Option<Instant>,
    /// What the tracker knew before the last write, to undo it if the
    /// next write replaced that byte.
    before_last: Option<Before>,
}

/// The tracker's knowledge before a write, and the record's moves then.
#[derive(Debug, Clone, Copy)]
struct Before {
    params: Option<(Command, [u8; 4], u8)>,
    winding: Option<(Winding, OutputLogic)>,
    initialized: bool,
    switching: bool,
    moves: usize,
}

impl MoveTracker {
    pub fn new() -> MoveTracker {
        MoveTracker::default()
    }

    /// The output logic of the phases (how to read S1..S5's levels as an
    /// energized pattern), once an initialization has set it.
    pub fn logic(&self) -> Option<OutputLogic> {
        self.winding.map(|(_, l)| l)
    }

    /// Whether the last initialization the chip accepted asked it to chop
    /// the excitation outputs while stopped (Section 3-2, bit 5); never
    /// between a reset and the first initialization.
    pub fn stop_switching(&self) -> bool {
        self.initialized && self.switching
    }

    /// A chip reset: nothing is known any more.
    pub fn reset(&mut self) {
        *self = MoveTracker::default();
    }

    /// The bridge wrote `byte` to the command register (`command`) or the
    /// data register at `at`; `phases` is the energized S1..S5 pattern the
    /// chip shows then (S1 in bit 4).
    pub fn on_write(
        &mut self,
        rec: &mut OutputRecord,
        command: bool,
        byte: u8,
        at: Instant,
        phases: u8,
    ) {
        // The byte before this one, if a status read since showed it still
        // in the input buffer (IBF = 1), is replaced by this one and never
        // seen by the chip (3-1-1 (2)): what it did is undone (a parameter
        // counted, a command begun, a record made). Else a record it made
        // stays: settled by a read with IBF = 0 (a bridge that waits for
        // IBF = 0 before each write settles so), or, with no read since,
        // kept, as the chip most often takes a byte before the next. The
        // status reads from here on tell of this byte (N6: an unasked-for
        // data byte raises an error of its own).
        let replaced = self
            .waiting_seen
            .is_some_and(|t| at.saturating_since(t) <= REPLACED_WITHIN);
        if let Some(b) = self.before_last.take().filter(|_| replaced) {
            self.params = b.params;
            self.undo(rec, b);
        }
        self.tentative = None;
        self.waiting_seen = None;
        self.before_last = Some(Before {
            params: self.params,
            winding: self.winding,
            initialized: self.initialized,
            switching: self.switching,
            moves: rec.moves.len(),
        });
        let (cmd, params) = if command {
            let cmd = Command::decode(byte);
            self.params = None;
            match cmd {
                Command::SoftwareReset(_) if !self.busy => {
                    self.winding = None;
                    self.initialized = false;
                    return;
                }
                Command::Init(_)
                | Command::Move(_)
                | Command::SwitchingParams
                | Command::AuxOutput
                    if cmd.param_count() > 0 =>
                {
                    self.params = Some((cmd, [0; 4], 0));
                    return;
                }
                Command::Move(_) => (cmd, [0; 4]),
                _ => return,
            }
        } else {
            let Some((cmd, mut buf, got)) = self.params.take() else {
                return;
            };
            buf[usize::from(got)] = byte;
            if got + 1 < cmd.param_count() {
                self.params = Some((cmd, buf, got + 1));
                return;
            }
            (cmd, buf)
        };
        match cmd {
            Command::Move(m) => self.start(rec, m, params, at, phases),
            Command::Init(c) => {
                let data = InitData::from_bytes(params);
                let ok = 0 < data.rh
                    && data.rh < data.rl
                    && data.rl < 255
                    && (PA_MIN..=PA_MAX).contains(&data.pa);
                if ok && !self.busy {
                    self.tentative = Some(Tentative::Init);
                    self.switching = c.stop_switching;
                    if self.winding.is_none() {
                        let w = Winding {
                            motor: c.motor,
                            excitation: c.excitation,
                        };
                        self.winding = Some((w, c.logic));
                    }
                    self.initialized = true;
                }
            }
            _ => {}
        }
    }

    fn start(
        &mut self,
        rec: &mut OutputRecord,
        m: MoveCommand,
        p: [u8; 4],
        at: Instant,
        phases: u8,
    ) {
        if !self.initialized {
            return; // error 2: the chip starts nothing
        }
        let steps = match m.kind {
            MoveKind::SingleStep => 1,
            MoveKind::AccelDecel => PulseCount::from_bytes([p[0], p[1], p[2]]).steps(),
            MoveKind::Constant => PulseCount::from_bytes([p[1], p[2], p[3]]).steps(),
            _ => PulseCount::MAX.steps(),
        };
        let winding = self.winding.map(|(w, _)| w);
        let phase_index = winding
            .and_then(|w| (0..w.steps_per_cycle()).find(|&i| w.pattern(i) == phases))
            .unwrap_or(0);
        rec.moves.push(MoveStart {
            at,
            kind: m.kind,
            dir: m.flags.direction,
            pout: m.pout,
            steps,
            first_run: rec.runs.len(),
            phase_index,
            winding: if m.pout { None } else { winding },
        });
        self.tentative = Some(Tentative::Move);
    }

    /// How many of the record's last move records are tentative: their
    /// last byte written, but no status read since has shown the chip take
    /// it (0 or 1).
    pub fn unsettled(&self) -> usize {
        usize::from(self.tentative == Some(Tentative::Move))
    }

    /// The bridge read the status register at `at`.
    pub fn on_status(&mut self, rec: &mut OutputRecord, status: Status, at: Instant) {
        self.busy = status.busy();
        self.waiting_seen = status.ibf().then_some(at);
        if status.ibf() {
            return; // the byte not taken yet: nothing to settle by
        }
        if self.tentative.take().is_some() && status.error_flag() {
            // Refused: undone, its bytes taken all the same.
            if let Some(b) = self.before_last {
                self.undo(rec, b);
            }
        }
    }

    /// Back to what the tracker knew before a write (`b`), a record that
    /// write made withdrawn, but for the parameters expected.
    fn undo(&mut self, rec: &mut OutputRecord, b: Before) {
        self.winding = b.winding;
        self.initialized = b.initialized;
        self.switching = b.switching;
        rec.moves.truncate(b.moves);
    }
}

/// A [`Bus`] whose move records are kept by a [`MoveTracker`] from the
/// bus traffic, as a bridge firmware keeps them, instead of by the chip
/// behind it: for the test that the tracker agrees with the reference
/// model on the whole suite.
#[derive(Debug, Clone)]
pub struct Tracked<B> {
    inner: B,
    tracker: MoveTracker,
    record: OutputRecord,
}

impl<B: Bus> Tracked<B> {
    pub fn new(inner: B) -> Tracked<B> {
        let mut record = inner.record().clone();
        record.moves.clear();
        Tracked {
            inner,
            tracker: MoveTracker::new(),
            record,
        }
    }

    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// The energized S1..S5 pattern the chip shows now.
    fn phases(&mut self) -> u8 {
        match self.inner.run(Op::ReadPins) {
            Reply::Pins { pins, .. } => pins.phases,
            _ => 0,
        }
    }
}

impl<B: Bus> Bus for Tracked<B> {
    fn next_op(&mut self, next: Option<Op>) {
        self.inner.next_op(next);
    }

    fn run(&mut self, op: Op) -> Reply {
        // The pattern at the write: sampled just before it, which on the
        // reference model is the same instant.
        let phases = match op {
            Op::WriteCommand { .. } | Op::WriteData { .. } => self.phases(),
            _ => 0,
        };
        let reply = self.inner.run(op);
        if op == Op::Reset {
            self.tracker.reset();
            self.record = OutputRecord::default();
        }
        // Everything but the moves from the chip's own record, before the
        // tracker looks at it: a write that waited for IBF may have let
        // pulses of the move before out. Pin changes are only appended, and
        // only the last pulse run may have grown.
        let inner = self.inner.record();
        let keep = self.record.runs.len().saturating_sub(1);
        self.record.runs.truncate(keep);
        self.record
            .runs
            .extend_from_slice(inner.runs.get(keep..).unwrap_or_default());
        let had = self.record.pins.len();
        self.record
            .pins
            .extend_from_slice(inner.pins.get(had..).unwrap_or_default());
        self.record.overwritten_bytes = inner.overwritten_bytes;
        match (op, reply) {
            (Op::WriteCommand { byte, .. }, Reply::Written { at, .. }) => {
                self.tracker
                    .on_write(&mut self.record, true, byte, at, phases)
            }
            (Op::WriteData { byte, .. }, Reply::Written { at, .. }) => {
                self.tracker
                    .on_write(&mut self.record, false, byte, at, phases)
            }
            (
                _,
                Reply::Status { status, .. }
                | Reply::Awaited { status, .. }
                | Reply::AwaitTimedOut { status, .. }
                | Reply::WriteTimedOut { status, .. }
                | Reply::ReadTimedOut { status, .. },
            ) => self.tracker.on_status(&mut self.record, status, reply.at()),
            _ => {}
        }
        reply
    }

    fn record(&self) -> &OutputRecord {
        &self.record
    }

    /// A tentative move record is settled by a status read of its own, as
    /// the board code does before it serves its capture.
    fn settle_record(&mut self) -> usize {
        if self.tracker.unsettled() > 0 {
            self.run(Op::ReadStatus);
        }
        self.tracker.unsettled()
    }

    fn straps(&self) -> Straps {
        self.inner.straps()
    }

    fn uncertainty(&self) -> crate::bus::Uncertainty {
        self.inner.uncertainty()
    }

    fn now(&self) -> Instant {
        self.inner.now()
    }

    fn capture_lost(&self) -> bool {
        self.inner.capture_lost()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An initialization (4-phase, RL 100, RH 20, PA 100) with code `code`,
    /// then the status the chip answers.
    fn init(t: &mut MoveTracker, rec: &mut OutputRecord, code: u8, status: u8) {
        t.on_write(rec, true, code, Instant::ZERO, 0);
        for b in [0x64, 0x14, 0x64, 0x00] {
            t.on_write(rec, false, b, Instant::ZERO, 0);
        }
        t.on_status(rec, Status(status), Instant::ZERO);
    }

    /// Section 3-2, bit 5 of the initialization code: stop switching as the
    /// last accepted initialization asked, never before the first one.
    #[test]
    fn stop_switching_follows_the_last_accepted_initialization() {
        let (mut t, mut rec) = (MoveTracker::new(), OutputRecord::default());
        assert!(!t.stop_switching(), "none before the first initialization");
        init(&mut t, &mut rec, 0x22, 0);
        assert!(t.stop_switching());
        // Refused (error flag): the one before still holds.
        init(&mut t, &mut rec, 0x02, Status::ERROR);
        assert!(t.stop_switching());
        init(&mut t, &mut rec, 0x02, 0);
        assert!(!t.stop_switching());
        init(&mut t, &mut rec, 0x22, 0);
        t.reset();
        assert!(!t.stop_switching(), "a reset forgets it");
    }

    fn us(n: u64) -> Instant {
        Instant::from_nanos(n * 1_000)
    }

    /// A continuous high-speed move's code (Section 3-3-7): no
    /// parameters, the code is its last byte.
    fn continuous_high() -> u8 {
        let m = MoveCommand::new(
            MoveKind::ContinuousHigh,
            crate::protocol::Direction::Cw,
            false,
        );
        Command::Move(m).encode()
    }

    /// A zero-parameter move (`code`, Section 3-3) written at 10 us.
    fn move_code(t: &mut MoveTracker, rec: &mut OutputRecord, code: u8) {
        t.on_write(rec, true, code, us(10), 0);
    }

    /// Section 3-1-1 and N6: a status read that still shows IBF = 1 shows
    /// the chip before it took the byte, with the error of the command
    /// before; only a read with IBF = 0 says whether the move was refused.
    #[test]
    fn a_move_is_settled_by_the_first_status_read_with_ibf_0() {
        let (mut t, mut rec) = (MoveTracker::new(), OutputRecord::default());
        init(&mut t, &mut rec, 0x02, 0);
        let code = continuous_high();
        // The command before was refused: its error shows until the chip
        // takes this code.
        move_code(&mut t, &mut rec, code);
        t.on_status(&mut rec, Status(Status::ERROR | Status::IBF | 0x10), us(11));
        assert_eq!(rec.moves.len(), 1, "a stale error withdraws nothing");
        assert_eq!(t.unsettled(), 1);
        t.on_status(&mut rec, Status(Status::BUSY), us(11));
        assert_eq!((rec.moves.len(), t.unsettled()), (1, 0), "taken: kept");

        // Refused while BUSY (error 1), seen only once IBF is 0.
        move_code(&mut t, &mut rec, code);
        t.on_status(&mut rec, Status(Status::IBF | Status::BUSY), us(11));
        assert_eq!((rec.moves.len(), t.unsettled()), (2, 1), "not settled yet");
        t.on_status(
            &mut rec,
            Status(Status::ERROR | Status::BUSY | 0x10),
            us(11),
        );
        assert_eq!(
            (rec.moves.len(), t.unsettled()),
            (1, 0),
            "refused: withdrawn"
        );
    }

    /// Section 3-1-1 (2): a byte written while IBF is 1 replaces the one
    /// there, which the chip never sees. A move whose code a read showed
    /// still waiting, then written over, never started; one written over
    /// with no read between is kept (the chip most often takes a byte
    /// before the next).
    #[test]
    fn a_move_written_over_while_it_waited_is_withdrawn() {
        let (mut t, mut rec) = (MoveTracker::new(), OutputRecord::default());
        init(&mut t, &mut rec, 0x02, 0);
        let code = continuous_high();
        move_code(&mut t, &mut rec, code);
        t.on_status(&mut rec, Status(Status::IBF), us(11));
        move_code(&mut t, &mut rec, code);
        assert_eq!(
            rec.moves.len(),
            1,
            "the first replaced, the second tentative"
        );
        move_code(&mut t, &mut rec, code);
        assert_eq!(rec.moves.len(), 2, "no read between: the second kept");
        t.on_status(&mut rec, Status(Status::BUSY), us(11));
        assert_eq!((rec.moves.len(), t.unsettled()), (2, 0));
        // A read that showed the code waiting, long before the next write:
        // the chip has taken it since (N11), and the move stays.
        move_code(&mut t, &mut rec, code);
        t.on_status(&mut rec, Status(Status::IBF | Status::BUSY), us(11));
        t.on_write(&mut rec, true, code, us(1_000), 0);
        assert_eq!(
            rec.moves.len(),
            4,
            "the move before kept, this one tentative"
        );

        // A parameter written over is one parameter: an accel/decel move
        // (three) is made by its fourth data byte here.
        let (mut t, mut rec) = (MoveTracker::new(), OutputRecord::default());
        init(&mut t, &mut rec, 0x02, 0);
        let m = MoveCommand::new(MoveKind::AccelDecel, crate::protocol::Direction::Cw, false);
        t.on_write(&mut rec, true, Command::Move(m).encode(), us(1), 0);
        t.on_write(&mut rec, false, 10, us(10), 0);
        t.on_status(&mut rec, Status(Status::IBF | 0x20), us(11));
        for b in [20, 0] {
            t.on_write(&mut rec, false, b, us(12), 0);
        }
        assert!(rec.moves.is_empty(), "two parameters taken of three");
        t.on_write(&mut rec, false, 0, us(30), 0);
        assert_eq!(rec.moves.len(), 1);
        assert_eq!(
            rec.moves[0].steps,
            PulseCount::from_bytes([20, 0, 0]).steps()
        );
    }
}
