//! The chip behind `ppmc bridge-sim`: the reference model, answering in
//! virtual time or paced to the wall clock (`--realtime`), as a board's
//! waits take their time, and so can be cut short by an ABORT
//! (`docs/bridge-protocol.md` section 5).

use super::timed::Timed;
use crate::bus::{Bus, EmuBus, Op, Reply};
use crate::protocol::{OutputMark, OutputRecord, Straps};
use crate::time::{Duration, Instant};
use ppmc_core::bridge::abort::AbortLine;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// The longest stretch of a paced wait between two looks at the wall
/// clock and the abort line: an ABORT stops a wait within about this.
const SLICE: Duration = Duration::from_millis(10);

/// The reference model as the simulated bridge sees it: exactly, to the
/// nanosecond, or through a timer of its own ([`Timed`]), as a bridge
/// whose timer is not locked to the chip sees a board.
#[derive(Debug, Clone)]
pub enum SimChip {
    Exact(EmuBus),
    Timed(Timed<EmuBus>),
}

impl SimChip {
    fn bus(&self) -> &dyn Bus {
        match self {
            SimChip::Exact(b) => b,
            SimChip::Timed(b) => b,
        }
    }

    fn bus_mut(&mut self) -> &mut dyn Bus {
        match self {
            SimChip::Exact(b) => b,
            SimChip::Timed(b) => b,
        }
    }
}

/// [`SimChip`], in virtual time (every op done at once) or paced: each op
/// returns when the wall clock has caught up with the chip's, and a wait
/// runs in slices of 10 ms, each checked against the abort line.
#[derive(Debug, Clone)]
pub struct SimBus {
    chip: SimChip,
    /// Paced: where the wall clock and the chip's clock were last lined
    /// up (`None` in virtual time).
    anchor: Option<(WallInstant, Instant)>,
    abort: Option<AbortLine>,
    /// The simulator is asked to stop (SIGINT): paced waits end at once.
    stop: Option<Arc<AtomicBool>>,
}

impl SimBus {
    pub fn new(chip: SimChip, realtime: bool) -> SimBus {
        SimBus {
            anchor: realtime.then(|| (WallInstant::now(), chip.bus().now())),
            chip,
            abort: None,
            stop: None,
        }
    }

    /// Paced waits end at once when `stop` is set (the simulator is
    /// shutting down): a ten-minute move must not hold up its exit.
    pub fn stop_with(&mut self, stop: Arc<AtomicBool>) {
        self.stop = Some(stop);
    }

    /// Paced: lines the chip's clock up with the wall clock now (a request
    /// begins; the time before it was passed on the chip by the caller).
    pub fn anchor_now(&mut self) {
        if self.anchor.is_some() {
            self.anchor = Some((WallInstant::now(), self.chip.bus().now()));
        }
    }

    /// Paced: the wall-clock moment that matches the chip's clock now.
    pub fn due(&self) -> Option<WallInstant> {
        let (wall, virt) = self.anchor?;
        Some(
            wall + WallDuration::from_nanos(
                self.chip.bus().now().saturating_since(virt).as_nanos(),
            ),
        )
    }

    fn aborted(&self) -> bool {
        self.abort.as_ref().is_some_and(AbortLine::pending)
            || self
                .stop
                .as_ref()
                .is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// Waits until the wall clock has caught up with the chip, or an
    /// abort is pending; whether it was not aborted.
    fn keep_pace(&mut self) -> bool {
        let Some(due) = self.due() else { return true };
        loop {
            if self.aborted() {
                return false;
            }
            match due.checked_duration_since(WallInstant::now()) {
                Some(left) if !left.is_zero() => {
                    std::thread::sleep(left.min(WallDuration::from_millis(20)));
                }
                _ => return true,
            }
        }
    }

    /// `op` (a wait of `total`) run as slices of at most [`SLICE`], each
    /// made with `slice(limit)` and kept in pace; `done` says whether a
    /// slice's reply ends the wait, `merge` folds the waits before it in.
    fn sliced(
        &mut self,
        total: Duration,
        slice: impl Fn(Duration) -> Op,
        done: impl Fn(&Reply) -> bool,
        merge: impl Fn(Reply, Duration) -> Reply,
    ) -> Reply {
        let mut waited = Duration::ZERO;
        loop {
            let part = total.saturating_sub(waited).min(SLICE);
            let before = self.chip.bus().now();
            let reply = self.chip.bus_mut().run(slice(part));
            let paced = self.keep_pace();
            if done(&reply) || waited + part >= total || !paced {
                return merge(reply, waited);
            }
            waited += self.chip.bus().now().saturating_since(before).max(part);
        }
    }
}

impl Bus for SimBus {
    fn run(&mut self, op: Op) -> Reply {
        if self.anchor.is_none() {
            return self.chip.bus_mut().run(op);
        }
        match op {
            Op::Delay(d) => self.sliced(d, Op::Delay, |_| false, |r, _| r),
            Op::AwaitStatus {
                mask,
                value,
                timeout,
            } => self.sliced(
                timeout,
                |t| Op::AwaitStatus {
                    mask,
                    value,
                    timeout: t,
                },
                |r| matches!(r, Reply::Awaited { .. }),
                |r, before| match r {
                    Reply::Awaited { at, waited, status } => Reply::Awaited {
                        at,
                        waited: waited + before,
                        status,
                    },
                    other => other,
                },
            ),
            Op::AwaitPulses { count, timeout } => self.sliced(
                timeout,
                |t| Op::AwaitPulses { count, timeout: t },
                |r| matches!(r, Reply::PulsesReached { .. }),
                |r, _| r,
            ),
            Op::Reset => {
                let reply = self.chip.bus_mut().run(op);
                // The chip's clock starts again at zero.
                self.anchor = Some((WallInstant::now(), self.chip.bus().now()));
                reply
            }
            op => {
                let reply = self.chip.bus_mut().run(op);
                self.keep_pace();
                reply
            }
        }
    }

    fn next_op(&mut self, next: Option<Op>) {
        self.chip.bus_mut().next_op(next);
    }

    fn record(&self) -> &OutputRecord {
        self.chip.bus().record()
    }

    /// The exact chip lets the fetched capture go; the timed one keeps its
    /// (its edges are resampled from the chip's, position by position).
    fn forget_record_before(&mut self, mark: OutputMark) -> OutputMark {
        self.chip.bus_mut().forget_record_before(mark)
    }

    fn straps(&self) -> Straps {
        self.chip.bus().straps()
    }

    fn now(&self) -> Instant {
        self.chip.bus().now()
    }

    fn capture_lost(&self) -> bool {
        self.chip.bus().capture_lost()
    }

    fn watch_abort(&mut self, line: AbortLine) {
        self.abort = Some(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::ModelConfig;

    fn paced() -> SimBus {
        let emu = EmuBus::new(Straps::default(), ModelConfig::default()).expect("model");
        SimBus::new(SimChip::Exact(emu), true)
    }

    /// A paced wait made of slices ends where one wait would: the same
    /// virtual time, the same reply.
    #[test]
    fn a_sliced_wait_is_one_wait() {
        let mut bus = paced();
        let reply = bus.run(Op::AwaitStatus {
            mask: 0x04,
            value: 0x04,
            timeout: Duration::from_millis(35),
        });
        assert!(matches!(reply, Reply::AwaitTimedOut { .. }), "{reply:?}");
        assert_eq!(bus.now(), Instant::ZERO + Duration::from_millis(35));
        let reply = bus.run(Op::Delay(Duration::from_millis(25)));
        assert_eq!(
            reply,
            Reply::Delayed {
                at: Instant::ZERO + Duration::from_millis(60)
            }
        );
    }

    /// A pending abort ends a paced wait at its next slice: the chip's
    /// clock stops within [`SLICE`] of where the wait began, not at its
    /// end (virtual time; no wall-clock bound is asserted).
    #[test]
    fn an_abort_ends_a_paced_wait_within_a_slice() {
        let mut bus = paced();
        let line = AbortLine::new();
        bus.watch_abort(line.clone());
        line.begin(1, true);
        line.raise(1);
        bus.run(Op::Delay(Duration::from_secs(5)));
        assert!(bus.now() <= Instant::ZERO + SLICE, "{:?}", bus.now());
    }
}
