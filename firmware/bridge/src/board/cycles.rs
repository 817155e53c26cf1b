//! Bus cycles through the PIO step player (PIO0 SM0): each step written
//! when the player's FIFO has room, the cycle's moment predicted from the
//! steps' lengths or aimed at a tick, every wait with a deadline; status
//! and data reads, writes, and waits on a status flag.

use super::Board;
use crate::bus_cycle::{self, Cycle, Steps};
use crate::hal::Hal;
use alloc::format;
use alloc::string::String;
use ppmc_core::bus::{Op, Reply};
use ppmc_core::protocol::{Pin, Status};
use ppmc_core::time::{Duration, Instant};

/// Two status reads at most this far apart (ns) are a wait's loop: a flag
/// that changed between them is stamped halfway, within half of it (the
/// `polled` uncertainty HELLO_REPLY declares, [`Board::uncertainty`]).
/// A pass of the loop takes the image on rp2350-emu 2.5 us of the
/// RP2350's time (the twin, which charges the board code's arithmetic
/// nothing, 1): at 2 us, its BUSY stamps were the later read's, as much
/// as a pass late, where HELLO said 1 us (`s3_3_3_single_step_cw_then_ccw`
/// failed by 0.4 us beyond it).
pub(super) const CLOSE_NS: u64 = 3_000;

/// The longest a bus cycle may take before the bridge calls its player
/// stuck: 1 ms (a cycle of the longest steps takes 35 us at 150 MHz).
const CYCLE_DEADLINE_US: u64 = 1_000;

/// The step an aimed cycle starts with: the bus left idle for 407 cycles,
/// time enough for the CPU to write the wait step after it, which it
/// works out from when the player took this one. At 47 cycles, on the
/// image on rp2350-emu, the player had finished it before the wait step
/// came, and an aimed write landed up to 1.1 us late (a latency probe
/// of Table 3-3, whose window is 0.4 us); on the twin, late from 40
/// cycles a hardware access on.
pub(super) const ANCHOR: u32 = bus_cycle::step(0xFF, bus_cycle::IDLE, false, 400);

/// The cycles from a read of the clock to the player's taking of a step
/// pushed right after it: the step worked out, a look at the FIFO's level
/// and the push. On the image on rp2350-emu, 20 left an aimed write 0.36
/// us (54 cycles) late.
const PUSH_CYCLES: u64 = 70;

impl<H: Hal> Board<H> {
    /// The bridge's own hardware failed: later ops do nothing, and the
    /// engine answers `HARDWARE` with `what`.
    fn fail(&mut self, what: String) {
        if self.fault.is_none() {
            self.fault = Some(what);
        }
    }

    /// One bus cycle: its moment (ticks: WR*'s rise, RD*'s fall), and the
    /// byte read, if a read. Each step is written only when the player's TX
    /// FIFO has room (4 steps deep; a write to a full FIFO is lost), and
    /// every wait has a deadline.
    ///
    /// The moment is predicted, not observed: the player takes a step at
    /// its `pull` when both the step is in the FIFO and the step before has
    /// played, and every step lasts what its word says, so the cycle each
    /// step starts on follows from the cycle each word went in. (Watching
    /// the FIFO empty would be late by the hold step and the CPU's loop:
    /// more than Table 3-3's tolerances allow.)
    pub(super) fn cycle(&mut self, c: Cycle, aim: Option<u64>) -> (u64, Option<u8>) {
        if self.fault.is_some() {
            return (self.now_ticks(), None);
        }
        let steps = match self.counts {
            Some(counts) => counts.steps(c),
            // The default timing fits; a board's own is checked at start.
            None => return (self.now_ticks(), None),
        };
        self.play(c, &steps, aim)
    }

    /// [`Board::cycle`] of `steps`, cycle `c`'s, worked out already.
    #[inline(always)]
    fn play(&mut self, c: Cycle, steps: &Steps, aim: Option<u64>) -> (u64, Option<u8>) {
        // Cycles from here on are counted on the cheap 32-bit clock, from
        // `base` (a bus cycle takes microseconds; its deadline is 1 ms).
        let (base, f0) = self.hal.clock_pair();
        let mut p = Player {
            f0,
            limit: CYCLE_DEADLINE_US as u32 * (self.sysclk_hz / 1_000_000),
            free: self.player_free.saturating_sub(base).min(1 << 30) as u32,
        };
        if let Some(t) = aim {
            // The cycle's moment at tick `t`: an anchor step, whose start
            // its push tells, then a wait step timed from it.
            let goal = t * 2;
            let before: u64 = steps.words()[..c.moment_step()]
                .iter()
                .map(|w| u64::from(bus_cycle::step_cycles(*w)))
                .sum::<u64>()
                + u64::from(bus_cycle::PINS_AT);
            let anchor = u64::from(bus_cycle::step_cycles(ANCHOR));
            let fits = anchor + u64::from(bus_cycle::MAX_COUNT + bus_cycle::STEP_CYCLES) + before;
            self.approach(goal.saturating_sub(fits) / 2);
            while self.hal.cycles() + fits < goal {}
            let step = u64::from(bus_cycle::STEP_CYCLES);
            // When the player takes what is pushed now: after the steps
            // it still has (a status read's recovery), at the earliest.
            let start = (self.hal.cycles() + PUSH_CYCLES).max(base + u64::from(p.free));
            // The wait step's count, from when the player takes it.
            let count = if start + anchor + step + before > goal {
                // Behind (the CPU came to the cycle with less than the
                // anchor's time to spare, after ops that cost it more
                // than their lead): no anchor, whose idle would make it
                // late, but a wait step timed from the clock, right to
                // within the few cycles a push takes.
                goal.checked_sub(start + step + before)
            } else {
                let Some(pull) = p.push(&mut self.hal, ANCHOR) else {
                    return self.player_stuck(c);
                };
                goal.checked_sub(base + u64::from(pull) + anchor + step + before)
            };
            if let Some(count) = count {
                let count = count.min(u64::from(bus_cycle::MAX_COUNT)) as u32;
                let wait = bus_cycle::step(0xFF, bus_cycle::IDLE, false, count);
                if p.push(&mut self.hal, wait).is_none() {
                    return self.player_stuck(c);
                }
            }
        }
        let mut moment = 0;
        for (i, w) in steps.words().iter().enumerate() {
            let Some(pull) = p.push(&mut self.hal, *w) else {
                return self.player_stuck(c);
            };
            if i == c.moment_step() {
                moment = pull + bus_cycle::PINS_AT;
            }
        }
        self.player_free = base + u64::from(p.free);
        let moment = base + u64::from(moment);
        self.moment = moment / 2;
        let byte = match c {
            Cycle::Read { .. } => loop {
                if let Some(w) = self.hal.bus_pull() {
                    break Some(w as u8);
                }
                if p.late(&self.hal) {
                    self.fail(format!(
                        "the bus player (PIO0 SM0) returned no byte for 1 ms after a {c:?}"
                    ));
                    return (self.now_ticks(), None);
                }
            },
            Cycle::Write { .. } => {
                while !self.hal.bus_tx_empty() {
                    if p.late(&self.hal) {
                        self.fail(format!(
                            "the bus player (PIO0 SM0) did not finish a {c:?} in 1 ms"
                        ));
                        return (self.now_ticks(), None);
                    }
                }
                None
            }
        };
        (moment / 2, byte)
    }

    /// The player took no step for a cycle's deadline: a hardware fault.
    /// Out of line, off the bus cycle's path.
    #[cold]
    #[inline(never)]
    fn player_stuck(&mut self, c: Cycle) -> (u64, Option<u8>) {
        self.fail(format!(
            "the bus player (PIO0 SM0) took no step for 1 ms: a step of a {c:?} not written"
        ));
        (self.now_ticks(), None)
    }

    pub(super) fn read_status(&mut self, aim: Option<u64>) -> (u64, Status) {
        let (t, b) = self.cycle(Cycle::Read { a0: true }, aim);
        let status = Status(b.unwrap_or(0));
        self.note_status(t, status);
        (t, status)
    }

    /// What a status read at tick `t` tells: the move tracker's settling,
    /// and a change of BUSY.
    pub(super) fn note_status(&mut self, t: u64, status: Status) {
        self.wrote = false;
        // The read's time only where the tracker keeps it (a byte seen
        // waiting): a status wait's every pass costs the image's CPU.
        let at = if status.ibf() {
            self.at(t)
        } else {
            Instant::ZERO
        };
        self.tracker.on_status(&mut self.record, status, at);
        let prev = core::mem::replace(&mut self.last_status, t);
        if status.busy() != self.busy {
            self.busy = status.busy();
            // BUSY changed between the last read and this one: halfway,
            // when the reads are close (a wait's loop); else at this one.
            let gap = t.saturating_sub(prev);
            let close = gap <= self.timer.to_ticks(CLOSE_NS);
            let at = self.at(if close { prev + gap / 2 } else { t });
            self.pin(at, Pin::Busy, u8::from(self.busy));
        }
    }

    /// Polls the status register until `status & mask == value`, at most
    /// until `deadline`: the tick the wait ended and the ticks it waited,
    /// or the last read's tick and status. The flag changed between the
    /// last two reads: when they are close (the loop's pass), the wait is
    /// taken to end halfway, the best estimate of the chip's own moment,
    /// the moment the capture gives the change of BUSY too. (A caller
    /// that added the ticks waited to a clock read of its own stamped the
    /// end early by the code between the two reads: 1.3 us on the image.)
    pub(super) fn wait_status(
        &mut self,
        mask: u8,
        value: u8,
        deadline: u64,
    ) -> Result<(u64, u64, Status), (u64, Status)> {
        let start = self.now_ticks();
        let close = self.timer.to_ticks(CLOSE_NS);
        let read = Cycle::Read { a0: true };
        let drain = self.timer.to_ticks(super::capture::WAIT_DRAIN_NS);
        // Worked out once for the whole wait.
        let steps = self.counts.map(|n| n.steps(read));
        let mut prev: Option<(u64, Status)> = None;
        loop {
            let (t, b) = match &steps {
                Some(steps) if self.fault.is_none() => self.play(read, steps, None),
                // As [`Board::cycle`] answers.
                _ => (self.now_ticks(), None),
            };
            let s = Status(b.unwrap_or(0));
            // A read like the one before tells nothing new but its time.
            match prev {
                Some((_, p)) if p == s => self.last_status = t,
                _ => self.note_status(t, s),
            }
            if s.0 & mask == value {
                let end = match prev {
                    Some((p, _)) if t - p <= close => p + (t - p) / 2,
                    _ => t,
                };
                if let Some((p, _)) = prev {
                    self.longest_pass = self.longest_pass.max(t - p);
                }
                return Ok((end, end.saturating_sub(start), s));
            }
            prev = Some((t, s));
            if t >= deadline || self.aborted() {
                return Err((t, s));
            }
            // The outputs sighted at every pass, so that every pass is as
            // long (a pass that did more was longer than CLOSE_NS on the
            // image, and the flag it saw change was stamped at its end);
            // the capture drained only when it must: a drain is a pass of
            // some 6 us on the RP2350, and a flag that changes meanwhile
            // is stamped no closer than that.
            self.sight_in_wait(drain);
        }
    }

    pub(super) fn write(&mut self, command: bool, byte: u8, wait: Option<Duration>) -> Reply {
        let mut waited = Duration::ZERO;
        if let Some(d) = wait {
            let deadline = self.deadline(d);
            match self.wait_status(Status::IBF, 0, deadline) {
                Ok((_, w, _)) => waited = Duration::from_nanos(self.timer.to_nanos(w)),
                Err((t, status)) => {
                    return Reply::WriteTimedOut {
                        at: self.at(t),
                        status,
                    }
                }
            }
        }
        let phases = self.energized(self.last_s);
        let aim = self.aim;
        let (t, _) = self.cycle(Cycle::Write { a0: command, byte }, aim);
        self.wrote = true;
        let at = self.at(t);
        // A status read next in the batch is played right behind the
        // write, the bus's recovery after it, as a host's `out` and `in`
        // follow each other: the ops between would put some 10 us of the
        // RP2350's time between them, and the chip takes a byte within
        // microseconds (Section 3-1-1: IBF is 1 only until then).
        if self.next == Some(Op::ReadStatus) && self.fault.is_none() {
            let (t, b) = self.cycle(Cycle::Read { a0: true }, None);
            self.early_status = Some((t, Status(b.unwrap_or(0))));
        }
        self.refresh();
        self.tracker
            .on_write(&mut self.record, command, byte, at, phases);
        Reply::Written { at, waited }
    }
}

/// The bus player's steps as one cycle pushes them, timed on the cheap
/// 32-bit clock ([`Hal::clock_pair`]) from the cycle's start. Five steps
/// make a status read; on the image on rp2350-emu the 64-bit clock and its
/// arithmetic had cost some 100 cycles of the RP2350 a step, and a status
/// wait's pass 13 us.
struct Player {
    /// The clock's reading at the cycle's start.
    f0: u32,
    /// The cycle's deadline, in cycles from its start.
    limit: u32,
    /// When the player is free for the next step, from the start.
    free: u32,
}

impl Player {
    /// Writes step `w` when the player's TX FIFO has room (a write to a
    /// full FIFO is lost); the cycle the player takes it on (its `pull`),
    /// predicted: the player takes a step when both the step is in the
    /// FIFO and the step before has played ([`Board::cycle`]). `None`
    /// past the deadline.
    #[inline(always)]
    fn push(&mut self, hal: &mut impl Hal, w: u32) -> Option<u32> {
        while hal.bus_tx_full() {
            if self.late(hal) {
                return None;
            }
        }
        let pushed = hal.bus_push_fine(w).wrapping_sub(self.f0);
        let pull = self.free.max(pushed + 1);
        self.free = pull + bus_cycle::step_cycles(w);
        Some(pull)
    }

    #[inline(always)]
    fn late(&self, hal: &impl Hal) -> bool {
        hal.fine().wrapping_sub(self.f0) > self.limit
    }
}
