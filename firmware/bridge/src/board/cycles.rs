//! Bus cycles through the PIO step player (PIO0 SM0): each step written
//! when the player's FIFO has room, the cycle's moment predicted from the
//! steps' lengths or aimed at a tick, every wait with a deadline; status
//! and data reads, writes, and waits on a status flag.

use super::Board;
use crate::bus_cycle::{self, Cycle};
use crate::hal::Hal;
use alloc::format;
use alloc::string::String;
use ppmc_core::bus::Reply;
use ppmc_core::protocol::{Pin, Status};
use ppmc_core::time::Duration;

/// Two status reads at most this far apart (ns) are a wait's loop: a flag
/// that changed between them is stamped halfway, within half of it (the
/// `polled` uncertainty HELLO_REPLY declares, [`Board::uncertainty`]).
pub(super) const CLOSE_NS: u64 = 2_000;

/// The longest a bus cycle may take before the bridge calls its player
/// stuck: 1 ms (a cycle of the longest steps takes 35 us at 150 MHz).
const CYCLE_DEADLINE_US: u64 = 1_000;

/// The step an aimed cycle starts with: the bus left idle for 47 cycles,
/// time enough for the CPU to write the wait step after it.
pub(super) const ANCHOR: u32 = bus_cycle::step(0xFF, bus_cycle::IDLE, false, 40);

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
        let deadline =
            self.hal.cycles() + CYCLE_DEADLINE_US * u64::from(self.sysclk_hz / 1_000_000);
        let mut moment = self.hal.cycles();
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
            while self.hal.cycles() + fits < goal {}
            let Some(pull) = self.push_step(ANCHOR, deadline, c) else {
                return (self.now_ticks(), None);
            };
            let waited = pull + anchor + u64::from(bus_cycle::STEP_CYCLES) + before;
            if goal >= waited {
                let count = (goal - waited).min(u64::from(bus_cycle::MAX_COUNT)) as u32;
                if self
                    .push_step(
                        bus_cycle::step(0xFF, bus_cycle::IDLE, false, count),
                        deadline,
                        c,
                    )
                    .is_none()
                {
                    return (self.now_ticks(), None);
                }
            }
        }
        for (i, w) in steps.words().iter().enumerate() {
            let Some(pull) = self.push_step(*w, deadline, c) else {
                return (self.now_ticks(), None);
            };
            if i == c.moment_step() {
                moment = pull + u64::from(bus_cycle::PINS_AT);
            }
        }
        self.moment = moment / 2;
        let byte = match c {
            Cycle::Read { .. } => loop {
                if let Some(w) = self.hal.bus_pull() {
                    break Some(w as u8);
                }
                if self.hal.cycles() > deadline {
                    self.fail(format!(
                        "the bus player (PIO0 SM0) returned no byte for 1 ms after a {c:?}"
                    ));
                    return (self.now_ticks(), None);
                }
            },
            Cycle::Write { .. } => {
                while !self.hal.bus_tx_empty() {
                    if self.hal.cycles() > deadline {
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

    /// Writes step `w` when the player's TX FIFO has room; the cycle the
    /// player will take it on (its `pull`), predicted. `None` when the
    /// player took no step for the cycle's deadline: a hardware fault.
    fn push_step(&mut self, w: u32, deadline: u64, c: Cycle) -> Option<u64> {
        while self.hal.bus_tx_full() {
            if self.hal.cycles() > deadline {
                self.fail(format!(
                    "the bus player (PIO0 SM0) took no step for 1 ms: a step of a {c:?} not written"
                ));
                return None;
            }
        }
        let pushed = self.hal.bus_push(w);
        let pull = self.player_free.max(pushed + 1);
        self.player_free = pull + u64::from(bus_cycle::step_cycles(w));
        Some(pull)
    }

    pub(super) fn read_status(&mut self, aim: Option<u64>) -> (u64, Status) {
        let (t, b) = self.cycle(Cycle::Read { a0: true }, aim);
        let status = Status(b.unwrap_or(0));
        self.tracker.on_status(&mut self.record, status);
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
        (t, status)
    }

    /// Polls the status register until `status & mask == value`, at most
    /// until `deadline`; the ticks waited, or the last status. The flag
    /// changed between the last two reads: when they are close (the loop's
    /// pass), the wait is taken to end halfway, the best estimate of the
    /// chip's own moment.
    pub(super) fn wait_status(
        &mut self,
        mask: u8,
        value: u8,
        deadline: u64,
    ) -> Result<(u64, Status), (u64, Status)> {
        let start = self.now_ticks();
        let mut prev = None;
        loop {
            let (t, s) = self.read_status(None);
            if s.0 & mask == value {
                let end = match prev {
                    Some(p) if t - p <= self.timer.to_ticks(CLOSE_NS) => p + (t - p) / 2,
                    _ => t,
                };
                if let Some(p) = prev {
                    self.longest_pass = self.longest_pass.max(t - p);
                }
                return Ok((end.saturating_sub(start), s));
            }
            prev = Some(t);
            if t >= deadline || self.aborted() {
                return Err((t, s));
            }
            self.refresh();
        }
    }

    pub(super) fn write(&mut self, command: bool, byte: u8, wait: Option<Duration>) -> Reply {
        let mut waited = Duration::ZERO;
        if let Some(d) = wait {
            let deadline = self.deadline(d);
            match self.wait_status(Status::IBF, 0, deadline) {
                Ok((w, _)) => waited = Duration::from_nanos(self.timer.to_nanos(w)),
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
        let at = self.at(t);
        self.refresh();
        self.tracker
            .on_write(&mut self.record, command, byte, at, phases);
        Reply::Written { at, waited }
    }
}
