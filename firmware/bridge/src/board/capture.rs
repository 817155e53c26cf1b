//! The capture: the edge counters' words drained from their FIFOs and
//! placed in time, the pin changes of every source kept in time order
//! until no source can precede them, then moved into the record; the
//! record's room, and a stalled counter reported as a lost capture.

use super::{record_time, Board};
use crate::hal::{Counter, Hal};
use crate::{limits, pins, timebase};
use ppmc_core::protocol::{Direction, Pin, PinEvent};
use ppmc_core::time::Instant;

/// An edge counter has pushed its word within this many ticks of the edge
/// (16 system clock cycles: the 2-cycle input synchroniser, a pass of the
/// counter's loop, the push), so a drain that starts after a tick has
/// every edge from before it, less this.
pub(super) const SETTLE_TICKS: u64 = 8;

/// The most records the board code keeps between chip resets: the
/// capture's capacity and what one op may add beyond it
/// ([`limits::OP_RECORDS`]). Past it, edges and pin changes are dropped,
/// and the engine answers CAPTURE_OVERRUN (the record holds more than the
/// capacity): a chip that pulses without end cannot exhaust the heap.
const MOST_RECORDS: usize = limits::CAPTURE_RECORDS as usize + limits::OP_RECORDS;

/// How long [`Board::keep_up`] lets the capture wait in its rings while
/// the outputs do not change.
const KEEP_UP_NS: u64 = 20_000;

/// How close to its moment an aimed op spins rather than idles
/// ([`Board::approach`]): 5 us (375 ticks). An idle returns at once while
/// a move's words wait in the rings (it does not drain them), and each
/// return and sight costs the image on rp2350-emu a microsecond or more:
/// at 2 us, an input aimed 31.7 us after a pulse came 0.34 us late
/// (`s3_6_hs_limit_accel_12us_not_after` allows 0.3).
const APPROACH_TICKS: u64 = 375;

/// How long a status wait lets the capture wait in its rings
/// ([`Board::sight_in_wait`]): a drain is a gap in the wait's polling, and
/// the longer between them, the fewer flags stamped across one.
pub(super) const WAIT_DRAIN_NS: u64 = 200_000;

/// The longest the board code idles between looks at the abort line:
/// an ABORT stops a quiet wait within about this (`docs/bridge-protocol.md`
/// section 5).
const ABORT_LOOK_NS: u64 = 1_000_000;

impl<H: Hal> Board<H> {
    /// Takes what the capture holds: the outputs the CPU samples, then the
    /// edge words from the PIO counters (an edge from before the sample is
    /// in its FIFO by then), and moves into the record the pin changes no
    /// source can precede any more. Called between ops, in every wait, and
    /// while the bridge waits for the host.
    pub fn poll(&mut self) {
        // Called between requests, when the core may have slept; nothing
        // read ahead for a batch's op serves the next batch.
        self.hal.resync();
        self.early_status = None;
        self.refresh();
    }

    /// [`Board::poll`] within an op.
    pub(super) fn refresh(&mut self) {
        self.hal.keepalive();
        let started = self.now_ticks();
        self.poll_inner();
        // The longest drain so far: one drains more words than the last
        // did when the capture waited meanwhile (a wait for a pulse drains
        // only now and then), and a delay must not start one it cannot end.
        self.poll_ticks = self.poll_ticks.max(self.now_ticks() - started);
    }

    /// [`Board::refresh`] where the capture needs it, a sight of the
    /// sampled outputs where it does not: between ops and in a status
    /// wait's loop. A refresh costs the RP2350 some 900 cycles (6 us; on
    /// the image on rp2350-emu, `firmware/README.md`), a sight some 30.
    /// It refreshes when the outputs changed (or a pin read saw them
    /// change), and when the last refresh is [`KEEP_UP_NS`] old: the
    /// counters' words wait in their rings meanwhile, 256 words each.
    pub(super) fn keep_up(&mut self) {
        let word = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let now = self.now_ticks();
        let fresh = now < self.last_sample + self.timer.to_ticks(KEEP_UP_NS);
        if fresh && word == self.last_word && self.changed_by.is_none() {
            self.sighted(word, now);
        } else {
            self.refresh();
        }
    }

    /// In a status wait's loop, at every pass: a sight of the sampled
    /// outputs (a change is first seen here, and stamped by the next drain
    /// within the bracket of the sights), and a drain only when the last
    /// is [`WAIT_DRAIN_NS`] old (`drain` ticks: the capture waits in its
    /// rings meanwhile, 256 words each: at 400 kpps, 640 us).
    #[inline(always)]
    pub(super) fn sight_in_wait(&mut self, drain: u64) {
        let word = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let now = self.now_ticks();
        self.sighted(word, now);
        if now >= self.last_sample + drain {
            self.refresh();
        }
    }

    fn poll_inner(&mut self) {
        let word = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let sampled = self.now_ticks();
        let before = core::mem::replace(&mut self.last_sample, sampled);
        // A change happened after the outputs were last seen unchanged and
        // by now (or by the pin read that saw it first): stamped halfway,
        // within half the bracket ([`Board::longest_bracket`]).
        let since = core::mem::replace(&mut self.unchanged, sampled);
        let seen = self.changed_by.take();
        let end = match seen {
            Some((c, w)) if w == word && word != self.last_word => c.max(since).min(sampled),
            _ => sampled,
        };
        let bracket = end.saturating_sub(since);
        let changed = self.at(since + bracket / 2);
        self.last_word = word;
        self.drain();
        // A change of S1..S5 is a step when a POUT edge came since the
        // last sample (or just before it, its word then still on its way:
        // `sample` looks for one that came since the drain).
        let stepped = self.last_pulse + SETTLE_TICKS >= before;
        let recorded = self.pending.len();
        self.sample(word, changed, sampled, stepped, seen.map(|(_, w)| w));
        // How sure the stamps of the changes recorded are (steps are not).
        if self.pending.len() > recorded {
            self.longest_bracket = self.longest_bracket.max(bracket);
        }
        let horizon = self.at(sampled.saturating_sub(SETTLE_TICKS));
        let n = self.pending.partition_point(|p| p.at <= horizon);
        self.record.pins.extend(self.pending.drain(..n));
    }

    /// Where a counter's word `w`, taken now, puts its edge (ticks).
    pub(super) fn edge_ticks(&self, w: u32) -> u64 {
        let e = timebase::place(w, (self.hal.cycles() - self.started) / 2);
        self.started / 2 + e.at
    }

    /// The edge counters' words, each placed in time by the clock read
    /// after it was taken from its FIFO (so at or after its edge).
    fn drain(&mut self) {
        let (timer, epoch) = (self.timer, self.epoch);
        let ticks = |hal: &H, started: u64, w: u32| {
            let e = timebase::place(w, (hal.cycles() - started) / 2);
            (e.bit, started / 2 + e.at)
        };
        while let Some(w) = self.hal.capture_pull(Counter::Pout) {
            if !self.room() {
                continue;
            }
            let (bit, t) = ticks(&self.hal, self.started, w);
            self.last_pulse = self.last_pulse.max(t);
            let new_move = self
                .record
                .moves
                .last()
                .is_some_and(|m| m.first_run == self.record.runs.len());
            let at = record_time(timer, epoch, t);
            self.edges
                .push(&mut self.record, at, Direction::from_bit(bit), new_move);
        }
        for (c, pin) in [
            (Counter::Int, Pin::Int),
            (Counter::Hold, Pin::Hold),
            (Counter::Aux, Pin::Aux),
        ] {
            while let Some(w) = self.hal.capture_pull(c) {
                let (high, t) = ticks(&self.hal, self.started, w);
                // HOLD's level as it is, INT*'s and AUX*'s (active low)
                // asserted when low.
                let value = match pin {
                    Pin::Hold => high,
                    _ => !high,
                };
                self.pin(record_time(timer, epoch, t), pin, u8::from(value));
            }
        }
        if self.hal.capture_stalled() {
            // A counter stopped counting while its FIFO was full: this
            // capture has a hole, and every later count would be late by
            // the stall. The capture is lost until the next chip reset;
            // the counters start again now, on a fresh timebase.
            self.lost = true;
            self.overruns += 1;
            self.started = self.hal.start_counters();
        }
    }

    /// A pin change, kept in time order until [`Board::poll`] moves it to
    /// the record.
    pub(super) fn pin(&mut self, at: Instant, pin: Pin, value: u8) {
        if !self.room() {
            return;
        }
        let i = self.pending.partition_point(|p| p.at <= at);
        self.pending.insert(i, PinEvent { at, pin, value });
    }

    /// Whether the record (and the changes on their way to it) has room
    /// for another record ([`MOST_RECORDS`]).
    fn room(&self) -> bool {
        let r = &self.record;
        r.runs.len() + r.pins.len() + r.moves.len() + self.pending.len() < MOST_RECORDS
    }

    /// Drains the capture until tick `t`.
    pub(super) fn drain_until(&mut self, t: u64) {
        while self.now_ticks() < t {
            self.refresh();
            self.idle(t);
        }
    }

    /// Waits, idling, until [`APPROACH_TICKS`] before tick `t`, for an op
    /// aimed at `t` that spins the rest of the way: the outputs are sighted
    /// meanwhile, so that a change in the wait is stamped within its
    /// bracket ([`crate::limits::SAMPLE_BRACKET_NS`]). A spin alone, up to
    /// the 20 us an aimed op starts early, had left the outputs unseen: on
    /// the image on rp2350-emu the software reset's excitation off was
    /// stamped 6.9 us from its change, where HELLO says 5.1
    /// (`s3_5_4_software_reset_frees_the_motor`).
    pub(super) fn approach(&mut self, t: u64) {
        let until = t.saturating_sub(APPROACH_TICKS);
        while self.now_ticks() < until {
            self.idle(until);
        }
    }

    /// Lets the hardware idle until tick `until` or a change of the
    /// outputs it watches. It compares them with their levels when it
    /// begins: a look before says whether those are the levels last
    /// polled (then the time it saw no change is a sight of them), and a
    /// look after whether they changed.
    pub(super) fn idle(&mut self, until: u64) {
        // With an abort line, never long without a look at it: the
        // hardware's own idle may last seconds when nothing moves.
        let until = match self.abort {
            Some(_) => until.min(self.now_ticks() + self.timer.to_ticks(ABORT_LOOK_NS)),
            None => until,
        };
        let entry = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let began = self.now_ticks();
        self.sighted(entry, began);
        // A change seen and not yet stamped: no idle, which would sleep
        // until the outputs change again and so lose this change's
        // bracket to the next. The caller's loop stamps it first.
        if self.changed_by.is_some() {
            return;
        }
        let seen = self.hal.idle(until * 2) / 2;
        self.sighted(entry, seen.max(began));
        let word = self.hal.read_high_pins() & pins::SAMPLED_HIGH;
        let now = self.now_ticks();
        self.sighted(word, now);
    }

    /// A sight of the sampled outputs between polls (`word`, masked, at
    /// tick `at`): it narrows the bracket the next poll stamps a change
    /// in. Levels as last polled move the last sight of them; new levels
    /// are first seen here, unless seen already; levels other than those
    /// seen last start again from the sight before.
    pub(super) fn sighted(&mut self, word: u16, at: u64) {
        match self.changed_by {
            None if word == self.last_word => self.unchanged = self.unchanged.max(at),
            Some((_, w)) if w == word => {}
            Some(_) => {
                self.unchanged = self.unchanged.max(self.last_read);
                self.changed_by = Some((at, word));
            }
            None => self.changed_by = Some((at, word)),
        }
        self.last_read = at;
    }
}
