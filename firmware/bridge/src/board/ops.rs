//! The engine's ops on the board ([`Bus`] for [`Board`]): each op run
//! with the capture drained around it, delays that end early to aim the
//! next op's moment, pin reads on a delay's grid, waits for pulses, and
//! the chip's reset.

use super::cycles::ANCHOR;
use super::Board;
use crate::bus_cycle::{self, Cycle};
use crate::hal::{Counter, Hal};
use crate::limits;
use crate::pins;
use crate::ring::RING_WORDS;
use alloc::string::String;
use ppmc_core::bridge::abort::AbortLine;
use ppmc_core::bus::{Bus, Op, Reply, SelfTestPlan, SelfTestReply};
use ppmc_core::protocol::{Input as ChipInput, OutputRecord, Status, Straps};
use ppmc_core::time::{Duration, Instant};

/// The longest pass of a spin on the clock ([`Board::spin_until`]): a
/// clock reading, some 6 system clock cycles on the RP2350, rounded up to
/// 4 ticks (8 cycles). A pin read whose spin ended later than that after
/// its aim came late, and is stamped where the clock then said.
pub(super) const SPIN_TICKS: u64 = 4;

/// How far a pin read's levels may lie from its stamp: a spin's pass
/// ([`SPIN_TICKS`]) and the read itself after it (a register access, some
/// 12 cycles: 6 ticks). The `access` uncertainty HELLO_REPLY declares.
pub(super) const ACCESS_TICKS: u64 = SPIN_TICKS + 6;

/// How often a wait for a pulse drains the capture while it waits (the
/// outputs sampled, the rings emptied), between looks for its pulse.
const DRAIN_EVERY_NS: u64 = 50_000;

/// What the code between a delay's end and the next op's moment may take,
/// beyond the op's bus cycles, so that the op can aim its moment at the
/// delay's end ([`Board::lead`]). An op that starts early spins until its
/// moment, so a lead longer than needed costs nothing but the spin; one
/// too short makes the op late. On the image on rp2350-emu the delay's
/// reply, the next op's dispatch and, for a write that waits for IBF = 0,
/// its status read and what it notes, took some 13 us of the RP2350's
/// time: at 8 us a Decelerating Stop aimed 17.4 us before a pulse came
/// 5.3 us late (`s3_6_decel_stop_17us_not_after`); at 2 us (what the
/// twin, which charges the board code's arithmetic nothing, had needed)
/// an input aimed 24.6 us after a pulse came 9 us late. Half as much
/// again as the longest seen.
const CPU_LEAD_US: u64 = 20;

/// The longest run of pin samples [`Board::sample_run`] reads in one loop
/// while a move may run: the capture waits in its rings meanwhile (256
/// words each: 640 us at 400 kpps). The three periods of stop switching
/// Section 3-5-1's scenarios sample take 521 us.
const SAMPLE_RUN_NS: u64 = 600_000;

/// The longest run of pin samples while the chip is not BUSY (its last
/// status read so, and nothing written since: only a write starts a
/// move): no pulse fills a ring,
/// and the run is bounded by the host's ABORT, which it hears only after.
/// Section 3-5-1's look for chopping after a move samples 3 ms.
const IDLE_SAMPLE_RUN_NS: u64 = 4_000_000;

/// Time enough for a look at the capture FIFOs' levels (ticks: 32 cycles).
const LOOK_TICKS: u64 = 16;

/// The kinds of op a delay ends early for ([`Bus::next_op`]), to aim
/// their moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Lag {
    /// A write that waits for IBF = 0 (a status read first).
    WriteAfterIbf,
    Write,
    /// A read that waits for OBF = 1.
    ReadAfterObf,
    Read,
    Input,
    /// A pin sample.
    Pins,
}

impl Lag {
    /// Every kind, in the order of [`Board::leads`].
    pub(super) const ALL: [Lag; 6] = [
        Lag::WriteAfterIbf,
        Lag::Write,
        Lag::ReadAfterObf,
        Lag::Read,
        Lag::Input,
        Lag::Pins,
    ];

    fn of(op: Op) -> Option<Lag> {
        Some(match op {
            Op::WriteCommand { wait_ibf, .. } | Op::WriteData { wait_ibf, .. } => {
                if wait_ibf.is_some() {
                    Lag::WriteAfterIbf
                } else {
                    Lag::Write
                }
            }
            Op::ReadData { wait_obf: Some(_) } => Lag::ReadAfterObf,
            Op::ReadData { wait_obf: None } | Op::ReadStatus => Lag::Read,
            Op::SetInput { .. } => Lag::Input,
            Op::ReadPins => Lag::Pins,
            _ => return None,
        })
    }
}

fn level(asserted: bool) -> bool {
    // The chip's inputs are active low: asserted is low.
    !asserted
}

impl<H: Hal> Board<H> {
    /// How long before its moment an op of kind `k` must start (ticks),
    /// worked out once ([`Board::leads`]): a delay that ends for an aimed
    /// op is often right behind a wait for a pulse, and on the image the
    /// working out took some 500 cycles of the 3,700 between a pulse and a
    /// stop aimed 24.6 us after it (Section 3-6's probes).
    fn lead(&self, k: Lag) -> u64 {
        self.leads[k as usize]
    }

    /// [`Board::lead`] of `k`, worked out: its bus cycles before the
    /// moment (a status read first, for one that waits on a flag), and
    /// [`CPU_LEAD_US`] for the code between.
    pub(super) fn work_out_lead(&self, k: Lag) -> u64 {
        let cycles = |c: Cycle, to_moment: bool| -> u64 {
            let Some(steps) = self.counts.map(|n| n.steps(c)) else {
                return 0;
            };
            let words = steps.words();
            let n = if to_moment {
                c.moment_step()
            } else {
                words.len()
            };
            let sum: u64 = words[..n]
                .iter()
                .map(|w| u64::from(bus_cycle::step_cycles(*w)))
                .sum();
            sum + if to_moment {
                u64::from(bus_cycle::PINS_AT)
            } else {
                0
            }
        };
        let read = Cycle::Read { a0: true };
        let write = Cycle::Write { a0: true, byte: 0 };
        let anchor = u64::from(bus_cycle::step_cycles(ANCHOR));
        let c = match k {
            Lag::WriteAfterIbf => cycles(read, false) + anchor + cycles(write, true),
            Lag::Write => anchor + cycles(write, true),
            Lag::ReadAfterObf => cycles(read, false) + anchor + cycles(read, true),
            Lag::Read => anchor + cycles(read, true),
            Lag::Input | Lag::Pins => 0,
        };
        c / 2 + self.timer.to_ticks(CPU_LEAD_US * 1_000)
    }

    /// `Op::Delay`: until `d` after the last op's moment. When the next op
    /// is one with a moment ([`Bus::next_op`]), the delay ends early by
    /// that op's [`Board::lead`], and the op aims its moment at the delay's
    /// end: a bus cycle through a wait step in the player, to the cycle; an
    /// input or a pin sample by spinning on the clock.
    fn delay(&mut self, d: Duration) -> Reply {
        let target = self.moment + self.timer.to_ticks(d.as_nanos());
        let kind = self.next.and_then(Lag::of);
        let until = target.saturating_sub(kind.map_or(0, |k| self.lead(k)));
        loop {
            let now = self.now_ticks();
            if now >= until || self.aborted() {
                break;
            }
            // No poll that would end past `until`: the capture waits in
            // its FIFOs until the next op's poll.
            if now + self.poll_ticks < until {
                self.refresh();
            }
            self.idle(until);
        }
        let end = self.now_ticks();
        if self.aborted() {
            // Cut short by the host's ABORT: what follows (the engine's
            // stop of the chip) acts now, not at the delay's end.
            self.aim = None;
            self.moment = end;
            return Reply::Delayed { at: self.at(end) };
        }
        // Late (the CPU took longer than `d`): the next op acts now.
        self.aim = kind.map(|_| target.max(end));
        self.moment = target.max(end);
        Reply::Delayed {
            at: self.at(self.moment),
        }
    }

    /// Spins on the clock until tick `t`; the clock's last reading (at or
    /// after `t`: later when the CPU came to it late).
    fn spin_until(&mut self, t: u64) -> u64 {
        loop {
            let now = self.now_ticks();
            if now >= t {
                return now;
            }
        }
    }

    /// The time of pulse `n` (from 1) of the last move, if it came:
    /// looked for from the move's last run back, as a wait for a pulse
    /// asks for the one that just came (a ramp is a run per pulse).
    fn pulse_time(&mut self, n: u64) -> Option<Instant> {
        let first = self.record.moves.last()?.first_run;
        let index = n.checked_sub(1)?;
        // Pulses before each run, counted down from the move's total.
        let mut before = self.move_pulses();
        for r in self.record.runs[first..].iter().rev() {
            before -= u64::from(r.count);
            if index >= before {
                let k = index - before;
                return (k < u64::from(r.count)).then(|| r.at(k as u32));
            }
        }
        None
    }

    pub(super) fn reset_chip(&mut self) -> Reply {
        self.hal.set_reset(false);
        // The inputs start over too (`Op::Reset`): all released.
        for i in 0..pins::INPUTS.len() {
            self.hal.set_input(i, level(false));
        }
        // RESET held low for 100 us, well beyond any chip's minimum.
        let until = self.deadline(Duration::from_micros(100));
        while self.now_ticks() < until {
            self.idle(until);
        }
        self.hal.set_reset(true);
        self.refresh();
        // A fresh timebase for the new record: whatever a stall did to the
        // last one is gone.
        self.started = self.hal.start_counters();
        self.epoch = self.now_ticks();
        self.moment = self.epoch;
        self.record = OutputRecord::default();
        self.counted = Default::default();
        self.pending.clear();
        self.last_pulse = 0;
        self.edges.reset();
        self.tracker.reset();
        self.lost = false;
        self.busy = false;
        self.switching = false;
        self.last_toggle = None;
        self.recorded_s = self.energized(self.last_s);
        Reply::ResetDone {
            at: self.at(self.epoch),
        }
    }
}

impl<H: Hal> Bus for Board<H> {
    fn run(&mut self, op: Op) -> Reply {
        if self.fault.is_some() {
            // The engine answers HARDWARE for the whole batch.
            return Reply::InputSet {
                at: self.at(self.now_ticks()),
            };
        }
        // The core may have slept since the batch before (between
        // requests, in the executor's `wfe`), never within one.
        if self.batch_done {
            self.hal.resync();
            self.batch_done = false;
        }
        // The capture is kept up between ops ([`Board::keep_up`]: a sight
        // of the outputs, a drain when they changed or the last is old),
        // but for those aimed at a moment: an op right after a delay that
        // ended early for it, and a delay that will end early for the next
        // (its loop drains the capture while there is time). A tight run
        // of pin samples so drains nothing; a ring the DMA laps meanwhile
        // is the capture lost (CAPTURE_OVERRUN).
        let aimed = self.aim.is_some();
        let aiming = matches!(op, Op::Delay(_)) && self.next.and_then(Lag::of).is_some();
        // After a wait for a pulse, which ended in a drain, the op that
        // acts on the pulse (a stop, an input) goes at once.
        let drained = core::mem::take(&mut self.drained);
        // Played behind the write before, for this op alone.
        let early = self.early_status.take();
        if matches!(op, Op::ReadPulses) {
            // It answers from the record: every pulse so far drained.
            self.refresh();
        } else if !aimed && !aiming && !drained && early.is_none() {
            self.keep_up();
        }
        let reply = match op {
            Op::WriteCommand { byte, wait_ibf } => self.write(true, byte, wait_ibf),
            Op::WriteData { byte, wait_ibf } => self.write(false, byte, wait_ibf),
            Op::ReadStatus => {
                let (t, status) = match early {
                    Some((t, status)) => {
                        self.note_status(t, status);
                        (t, status)
                    }
                    None => self.read_status(self.aim),
                };
                Reply::Status {
                    at: self.at(t),
                    status,
                }
            }
            Op::ReadData { wait_obf } => {
                let mut waited = Duration::ZERO;
                if let Some(d) = wait_obf {
                    let deadline = self.deadline(d);
                    match self.wait_status(Status::OBF, Status::OBF, deadline) {
                        Ok((_, w, _)) => waited = Duration::from_nanos(self.timer.to_nanos(w)),
                        Err((t, status)) => {
                            return Reply::ReadTimedOut {
                                at: self.at(t),
                                status,
                            }
                        }
                    }
                }
                let aim = self.aim;
                let (t, b) = self.cycle(Cycle::Read { a0: false }, aim);
                Reply::Data {
                    at: self.at(t),
                    byte: b.unwrap_or(0),
                    waited,
                }
            }
            Op::Delay(d) => self.delay(d),
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => {
                let deadline = self.deadline(timeout);
                match self.wait_status(mask, value & mask, deadline) {
                    Ok((end, w, status)) => Reply::Awaited {
                        at: self.at(end),
                        waited: Duration::from_nanos(self.timer.to_nanos(w)),
                        status,
                    },
                    Err((t, status)) => Reply::AwaitTimedOut {
                        at: self.at(t),
                        status,
                    },
                }
            }
            Op::SetInput { input, asserted } => {
                let i = ChipInput::ALL.iter().position(|x| *x == input).unwrap_or(0);
                // At the moment the delay before it aimed at, or now.
                let at = self.aim.map_or(0, |t| {
                    self.approach(t);
                    t * 2
                });
                self.moment = self.hal.set_input_at(i, level(asserted), at) / 2;
                Reply::InputSet {
                    at: self.at(self.moment),
                }
            }
            Op::ReadPins => match self.aim {
                Some(t) => {
                    // Read where the delay before it aimed, the cycles of a
                    // GPIO read after the clock said so: stamped there, so
                    // that regular samples stay on their grid (one SAMPLES
                    // entry on the wire, as on the model). No poll: the
                    // capture waits in its FIFOs (a tight sampling loop).
                    // Every 8th sample, a look at the capture's FIFOs, when
                    // there is time before the sample; every 64th, in any
                    // case. Drained when a quarter full, at the cost of
                    // that sample's place on the grid.
                    self.samples += 1;
                    let look = self.samples.is_multiple_of(8)
                        && (self.now_ticks() + LOOK_TICKS < t || self.samples.is_multiple_of(64));
                    if look && self.hal.capture_level() >= 2 {
                        self.refresh();
                    }
                    // Past the sample's time (a drain, or ops that cost
                    // the CPU more than the step): stamped when read, not
                    // where it was aimed, so that a stamp never lies.
                    // Within a pass of the spin loop it is on time.
                    self.approach(t);
                    let seen = self.spin_until(t);
                    let word = self.hal.read_high_pins();
                    self.moment = if seen > t + SPIN_TICKS { seen } else { t };
                    self.sighted(word & pins::SAMPLED_HIGH, self.moment);
                    Reply::Pins {
                        at: self.at(self.moment),
                        pins: self.pins_from(word),
                    }
                }
                None => {
                    let pins = self.pins();
                    self.moment = self.last_sample;
                    Reply::Pins {
                        at: self.at(self.moment),
                        pins,
                    }
                }
            },
            Op::ReadPulses => Reply::Pulses {
                at: self.at(self.now_ticks()),
                summary: self.record.last_move_pulses(),
            },
            Op::AwaitPulses { count, timeout } => {
                let deadline = self.deadline(timeout);
                let began = self.at(self.now_ticks());
                // Drained at the start, then while the wait goes on every
                // DRAIN_EVERY_NS or when a ring fills a quarter; between,
                // the pulse is looked for among the POUT words not drained
                // yet, so that it is seen within a pass of the idle loop
                // rather than a drain (some 2,000 cycles at 400 kpps).
                let every = self.timer.to_ticks(DRAIN_EVERY_NS);
                let mut drained_at: Option<u64> = None;
                loop {
                    // The look for the pulse first; a drain, when due, only
                    // where it is not there yet, and then a look again.
                    if drained_at.is_none() {
                        self.refresh();
                        drained_at = Some(self.now_ticks());
                    }
                    let n = self.move_pulses();
                    let t = self.now_ticks();
                    // The pulse drained into the record, or its word
                    // waiting in the ring.
                    let pulse = if n >= count {
                        Some(self.pulse_time(count).unwrap_or(self.at(t)))
                    } else {
                        usize::try_from(count - n - 1)
                            .ok()
                            .and_then(|k| self.hal.capture_peek(Counter::Pout, k))
                            .map(|w| self.at(self.edge_ticks(w)))
                    };
                    if let Some(at) = pulse {
                        // The moment is the pulse's own, not when the
                        // capture brought it: a delay counts from it. A
                        // pulse that came before the wait began ends it
                        // as it begins, as on the reference model: a
                        // reply is never stamped before the op ahead.
                        let at = at.max(began);
                        self.moment = self.epoch + self.timer.to_ticks(at.as_nanos());
                        self.drained = true;
                        break Reply::PulsesReached { at };
                    }
                    if t >= deadline || self.aborted() {
                        // Counted with every pulse drained.
                        self.refresh();
                        break Reply::PulsesTimedOut {
                            at: self.at(t),
                            count: self.move_pulses(),
                        };
                    }
                    // No drain when the pulse is the next to come: a drain
                    // takes some 6 us of the RP2350's time (the image on
                    // rp2350-emu), and the pulse, seen only after it, had
                    // made the op that acts on it late
                    // (`s3_6_decel_stop_17us_not_after`, 1 us of 0.4).
                    let next = count - n == 1
                        || usize::try_from(count - n - 2)
                            .ok()
                            .is_some_and(|k| self.hal.capture_peek(Counter::Pout, k).is_some());
                    // But never a millisecond without one: the watchdog is
                    // fed there, and a pulse that does not come (the move
                    // ended short) leaves words in the rings, which end
                    // every idle at once.
                    let overdue = drained_at.is_some_and(|d| t >= d + 20 * every);
                    if (!next || overdue)
                        && (drained_at.is_some_and(|d| t >= d + every)
                            || self.hal.capture_level() >= RING_WORDS / 4)
                    {
                        self.refresh();
                        drained_at = Some(self.now_ticks());
                        continue;
                    }
                    self.idle(deadline);
                }
            }
            Op::Reset => self.reset_chip(),
        };
        if matches!(op, Op::Delay(_)) && self.aim.is_some() {
            return reply;
        }
        // The next op drains the capture before it runs (above): only the
        // batch's last drains it here, so that an op costs one drain.
        let ends_batch = self.next.is_none();
        if ends_batch {
            self.drained = false;
            self.refresh();
        }
        self.batch_done |= ends_batch;
        self.aim = None;
        reply
    }

    fn next_op(&mut self, next: Option<Op>) {
        self.next = next;
    }

    fn abandon(&mut self) {
        self.early_status = None;
    }

    /// A SAMPLE op's `(ReadPins, Delay(step))` pairs on the grid the delay
    /// before aimed the first at: read in one tight loop
    /// ([`Hal::read_pins_grid`]), then noted and answered as the ops one
    /// by one would have been, the last delay as `Board::delay` runs it.
    /// Op by op, the engine and the board code cost the image on
    /// rp2350-emu some 10 us a pair, and the stop-switching scenarios'
    /// samples 250 ns apart each came off their grid: a reply of 34 KB for
    /// a buffer of 12 (OVERFLOW). Not for a run longer than `SAMPLE_RUN_NS` while the chip may
    /// pulse (`IDLE_SAMPLE_RUN_NS` while it does not): the capture waits
    /// in its rings meanwhile.
    fn sample_run(
        &mut self,
        step: Duration,
        pairs: usize,
        after: Option<Op>,
        emit: &mut dyn FnMut(Reply),
    ) -> bool {
        let n = pairs;
        let st = self.timer.to_ticks(step.as_nanos());
        if self.fault.is_some()
            || n == 0
            || n > limits::GRID_SAMPLES
            || st.saturating_mul(n as u64)
                > self.timer.to_ticks(if self.busy || self.wrote {
                    SAMPLE_RUN_NS
                } else {
                    IDLE_SAMPLE_RUN_NS
                })
        {
            return false;
        }
        if core::mem::take(&mut self.batch_done) {
            self.hal.resync();
        }
        self.early_status = None;
        self.drained = false;
        // Where the delay before aimed the first read; else now (the
        // capture is drained after the reads, below: a drain first had put
        // the run's first reads 1 to 2 us off the grid of the run before,
        // a request before, on the twin).
        let t0 = match self.aim {
            Some(t) => {
                self.approach(t);
                t
            }
            None => self.now_ticks(),
        };
        self.hal.read_pins_grid(t0 * 2, st * 2, SPIN_TICKS * 2, n);
        // The reads as sights of the outputs, then the capture drained
        // (it waited in its rings through the run), then the answers.
        for k in 0..n {
            let (c, word) = self.hal.grid_read(k);
            self.sighted(word & pins::SAMPLED_HIGH, c / 2);
        }
        self.refresh();
        for k in 0..n {
            let (c, word) = self.hal.grid_read(k);
            let m = c / 2;
            self.moment = m;
            emit(Reply::Pins {
                at: self.at(m),
                pins: self.pins_from(word),
            });
            if k + 1 < n {
                // Each delay between ends where the next read was.
                let (next, _) = self.hal.grid_read(k + 1);
                emit(Reply::Delayed {
                    at: self.at(next / 2),
                });
            } else {
                self.next = after;
                self.aim = None;
                emit(self.run(Op::Delay(step)));
            }
        }
        true
    }

    fn record(&self) -> &OutputRecord {
        &self.record
    }

    /// A move whose last byte no status read has seen the chip take (IBF
    /// = 0) is settled by a status read of the board's own: the chip takes
    /// a byte within microseconds (Section 3-1-1), and a status read
    /// changes nothing in it.
    fn settle_record(&mut self) -> usize {
        if self.tracker.unsettled() > 0 && self.fault.is_none() {
            if core::mem::take(&mut self.batch_done) {
                self.hal.resync();
            }
            self.early_status = None;
            // A read of the board's own: the next request's ops are timed
            // from the op before it, and a write's pulses still guarded.
            let (moment, wrote) = (self.moment, self.wrote);
            self.read_status(None);
            (self.moment, self.wrote) = (moment, wrote);
            self.batch_done = true;
        }
        self.tracker.unsettled()
    }

    fn uncertainty(&self) -> ppmc_core::bus::Uncertainty {
        Board::uncertainty(self)
    }

    fn straps(&self) -> Straps {
        self.straps
    }

    fn now(&self) -> Instant {
        self.at(self.now_ticks())
    }

    fn capture_lost(&self) -> bool {
        self.lost
    }

    fn fault(&self) -> Option<&str> {
        self.fault.as_deref()
    }

    fn self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestReply, String> {
        self.run_self_test(plan)
    }

    fn watch_abort(&mut self, line: AbortLine) {
        self.abort = Some(line);
    }
}
