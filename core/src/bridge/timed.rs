//! A bridge's own view of a chip's outputs: every output edge stamped by
//! the bridge's timer, which is not locked to the chip's clock.
//!
//! [`Timed`] wraps any [`Bus`] and captures its pulses again, one edge at a
//! time, at the resolution of a timer of a given rate, merging them with
//! [`EdgeRuns`] as a bridge firmware does. `ppmc bridge-sim --timer-hz`
//! serves the reference model this way, so the host's handling of a real
//! bridge's capture (intervals that wobble by a tick, runs with a jitter
//! bound) is tested without a board.

use super::wire::Timer;
use crate::bus::{Bus, Op, Reply};
use crate::protocol::{EdgeRuns, MoveStart, OutputRecord, PinEvent, Straps};
use crate::time::Instant;

/// A [`Bus`] whose capture is taken edge by edge with a timer of
/// `timer.hz`: pulse and pin times fall on the timer's ticks, and pulse
/// runs carry the jitter bound that a tick of wobble needs.
#[derive(Debug, Clone)]
pub struct Timed<B> {
    inner: B,
    timer: Timer,
    edges: EdgeRuns,
    record: OutputRecord,
    /// The inner record's runs taken so far: whole runs, then pulses of the
    /// next.
    runs_taken: (usize, u32),
    pins_taken: usize,
    moves_taken: usize,
    /// A move started whose first pulse is not taken yet.
    move_pending: bool,
}

impl<B: Bus> Timed<B> {
    /// `inner` seen through a timer of `timer.hz`, merging pulses into runs
    /// within [`Timer::edge_tolerance`].
    pub fn new(inner: B, timer: Timer) -> Timed<B> {
        let mut t = Timed {
            inner,
            timer,
            edges: EdgeRuns::new(timer.edge_tolerance()),
            record: OutputRecord::default(),
            runs_taken: (0, 0),
            pins_taken: 0,
            moves_taken: 0,
            move_pending: false,
        };
        t.sync();
        t
    }

    /// The timer the capture is taken with.
    pub fn timer(&self) -> Timer {
        self.timer
    }

    pub fn inner(&self) -> &B {
        &self.inner
    }

    pub fn inner_mut(&mut self) -> &mut B {
        &mut self.inner
    }

    /// Takes what the inner capture gained since the last look.
    fn sync(&mut self) {
        let timer = self.timer;
        // A time as the timer stamps it: the nearest tick, in nanoseconds.
        let stamp = |t: Instant| Instant::from_nanos(timer.to_nanos(timer.to_ticks(t.as_nanos())));
        let inner = self.inner.record();
        let (mut run, mut pos) = self.runs_taken;
        while let Some(r) = inner.runs.get(run) {
            if pos == 0 {
                // The moves whose pulses start with this run.
                while let Some(m) = inner.moves.get(self.moves_taken) {
                    if m.first_run > run {
                        break;
                    }
                    self.record.moves.push(MoveStart {
                        at: stamp(m.at),
                        first_run: self.record.runs.len(),
                        ..*m
                    });
                    self.moves_taken += 1;
                    self.move_pending = true;
                }
            }
            for k in pos..r.count {
                self.edges
                    .push(&mut self.record, stamp(r.at(k)), r.dir, self.move_pending);
                self.move_pending = false;
            }
            pos = r.count;
            if run + 1 == inner.runs.len() {
                break;
            }
            (run, pos) = (run + 1, 0);
        }
        self.runs_taken = (run, pos);
        // Moves whose pulses have not begun.
        for m in &inner.moves[self.moves_taken..] {
            self.record.moves.push(MoveStart {
                at: stamp(m.at),
                first_run: self.record.runs.len(),
                ..*m
            });
            self.move_pending = true;
        }
        self.moves_taken = inner.moves.len();
        for p in &inner.pins[self.pins_taken..] {
            self.record.pins.push(PinEvent {
                at: stamp(p.at),
                ..*p
            });
        }
        self.pins_taken = inner.pins.len();
        self.record.overwritten_bytes = inner.overwritten_bytes;
    }
}

impl<B: Bus> Bus for Timed<B> {
    fn next_op(&mut self, next: Option<Op>) {
        self.inner.next_op(next);
    }

    fn run(&mut self, op: Op) -> Reply {
        let reply = self.inner.run(op);
        if op == Op::Reset {
            self.record = OutputRecord::default();
            self.edges.reset();
            self.runs_taken = (0, 0);
            self.pins_taken = 0;
            self.moves_taken = 0;
            self.move_pending = false;
        }
        self.sync();
        reply
    }

    fn record(&self) -> &OutputRecord {
        &self.record
    }

    fn settle_record(&mut self) -> usize {
        let tentative = self.inner.settle_record();
        self.sync();
        tentative
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
