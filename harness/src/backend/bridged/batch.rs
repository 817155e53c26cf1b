//! A batch of ops as requests: sized to the line, the bridge clock
//! followed, the capture downloaded in chunks, and the self-test.

use super::error::*;
use super::options::*;
use super::target::*;
use crate::backend::link::Link;
use crate::backend::target::{Op, Reply, SelfTestPlan, SelfTestRun};
use crate::protocol::{MoveStart, OutputMark, OutputRecord};
use crate::time::Instant;
use ppmc_core::bridge::wire::MAX_BATCH_OPS;
use ppmc_core::bridge::wire::{self, CaptureChunk, Request, Response};
use std::time::Duration as WallDuration;

impl<L: Link> BridgeTarget<L> {
    /// The bridge time a batch's own waits may take: wall time on a
    /// real-time bridge, the bridge's clock on one in virtual time (which
    /// says how far it got with WORKING).
    pub(super) fn batch_time(&self, ops: &[Op]) -> WallDuration {
        let total: u64 = ops
            .iter()
            .map(|o| match *o {
                Op::Delay(d) => d.as_nanos(),
                Op::AwaitStatus { timeout, .. } | Op::AwaitPulses { timeout, .. } => {
                    timeout.as_nanos()
                }
                Op::WriteCommand {
                    wait_ibf: Some(t), ..
                }
                | Op::WriteData {
                    wait_ibf: Some(t), ..
                }
                | Op::ReadData { wait_obf: Some(t) } => t.as_nanos(),
                _ => 0,
            })
            .fold(0u64, u64::saturating_add);
        WallDuration::from_nanos(total)
    }

    /// Where the next capture fetch starts: the last pulse run known (it
    /// may have grown), and the pin changes and moves after those known.
    pub(super) fn capture_from(&self) -> (u32, u32, u32) {
        // Counted from the chip's reset, across what was let go.
        let at = self.let_go.plus(self.captured.mark());
        (
            at.runs.saturating_sub(1) as u32,
            at.pins as u32,
            at.moves as u32,
        )
    }

    /// Adds a capture chunk fetched from [`Self::capture_from`]; returns
    /// whether more records remain.
    pub(super) fn absorb(&mut self, c: CaptureChunk) -> bool {
        let from_run = self.captured.runs.len().saturating_sub(1);
        if !c.runs.is_empty() {
            self.captured.runs.truncate(from_run);
        }
        self.captured.runs.extend(c.runs);
        self.captured.pins.extend(c.pins);
        // A move's first run, counted from the reset on the wire, from
        // what is held here.
        let gone = self.let_go.runs;
        self.captured
            .moves
            .extend(c.moves.into_iter().map(|m| MoveStart {
                first_run: m.first_run.saturating_sub(gone),
                ..m
            }));
        self.captured.overwritten_bytes = c.overwritten_bytes;
        c.more
    }

    /// How many of `ops` go in the next request (at least one): as many
    /// wire ops as fit the request size in force and the bridge's batch
    /// limit, whose replies cannot outgrow [`REPLY_ENTRIES_BUDGET`].
    pub(super) fn next_request_len(&self, ops: &[Op], max_ops: usize) -> usize {
        // seq, kind, count; BATCH_CAPTURE adds where the capture starts.
        let mut bytes = 4 + 14;
        let mut reply = 0;
        let mut n = 0;
        for (i, group) in wire::wire_ops(ops).into_iter().enumerate() {
            let g = &ops[n..n + group];
            bytes += wire::wire_op_len(g, self.timer);
            reply += wire::worst_reply_len(g);
            if i > 0 && (i >= max_ops || bytes > self.request_size || reply > REPLY_ENTRIES_BUDGET)
            {
                break;
            }
            n += group;
        }
        n
    }

    /// Follows the bridge's clock through the replies to `ops`: it restarts
    /// at a chip reset and otherwise never goes back further than the
    /// bridge's declared uncertainty of an access and a poll. Within that,
    /// a reply a little before the one ahead of it is an op that came a
    /// little early (on the board twin, an op aimed at a short delay's end
    /// comes up to 0.3 us before it: `firmware/README.md`), not a bridge
    /// that restarted, whose clock starts again from nothing.
    pub(super) fn check_clock(&mut self, ops: &[Op], replies: &[Reply]) -> Result<(), BridgeError> {
        let u = self.hello.uncertainty;
        let slack = u.access + u.polled;
        for (op, r) in ops.iter().zip(replies) {
            let at = r.at();
            if *op == Op::Reset {
                self.clock = at;
                continue;
            }
            if at + slack < self.clock {
                return Err(BridgeError::ClockWentBack {
                    link: self.link.name(),
                    was: self.clock,
                    now: at,
                    op: op.to_string(),
                });
            }
            self.clock = self.clock.max(at);
        }
        Ok(())
    }

    /// Runs `ops` in requests of the size in force. On a clean link the last
    /// request also brings back the capture since the last fetch (what the
    /// bridge has not sent yet, up to one chunk), so that reading the
    /// capture after a batch, which every scenario does, costs no round
    /// trip of its own.
    pub(super) fn run_batch(&mut self, ops: &[Op]) -> Result<Vec<Reply>, BridgeError> {
        self.captured_current = false;
        if ops.contains(&Op::Reset) {
            // A chip reset clears the bridge's capture.
            self.captured = OutputRecord::default();
            self.let_go = OutputMark::default();
        }
        let mut out = Vec::with_capacity(ops.len());
        let max_ops = usize::from(self.hello.max_batch_ops.clamp(1, MAX_BATCH_OPS.max(1)));
        let mut rest = ops;
        let mut garbled_rounds = 0;
        while !rest.is_empty() {
            let n = self.next_request_len(rest, max_ops);
            let (chunk, tail) = rest.split_at(n);
            rest = tail;
            let what = format!(
                "a batch of {} ops starting with `{}`",
                chunk.len(),
                chunk[0]
            );
            let extra = self.batch_time(chunk);
            let garbled_before = self.garbled;
            // The capture rides along only on a clean link: on a noisy one
            // (requests shrunk) a longer reply is likelier to need resending.
            let req = if rest.is_empty() && self.request_size >= MAX_REQUEST {
                let (runs, pins, moves) = self.capture_from();
                Request::BatchCapture {
                    ops: chunk.to_vec(),
                    runs,
                    pins,
                    moves,
                    max: CAPTURE_CHUNK,
                }
            } else {
                Request::Batch(chunk.to_vec())
            };
            let reply = match self.request(&req, &what, extra) {
                Err(e @ BridgeError::Garbled { .. }) => {
                    // Not run: send the same ops again, in smaller requests
                    // while they can shrink; a line that garbles even the
                    // smallest this often is given up.
                    garbled_rounds += 1;
                    if self.request_size <= MIN_REQUEST && garbled_rounds > self.opts.retries {
                        return Err(e);
                    }
                    self.request_size = (self.request_size / 2).max(MIN_REQUEST);
                    rest = ops_from(ops, out.len());
                    continue;
                }
                other => {
                    garbled_rounds = 0;
                    other?
                }
            };
            // Noisy line: smaller requests (and so smaller replies); clean:
            // back up towards the largest.
            self.request_size = if self.garbled > garbled_before {
                (self.request_size / 2).max(MIN_REQUEST)
            } else {
                (self.request_size * 2).min(MAX_REQUEST)
            };
            match reply {
                Response::Batch(r) if r.len() == chunk.len() => {
                    self.check_clock(chunk, &r)?;
                    out.extend(r);
                }
                Response::BatchCapture { replies, capture } if replies.len() == chunk.len() => {
                    self.check_clock(chunk, &replies)?;
                    out.extend(replies);
                    let more = self.absorb(capture);
                    self.captured_current = !more && self.hello.virtual_time;
                }
                other => return Err(self.unexpected(&what, &other)),
            }
        }
        Ok(out)
    }
}

impl<L: Link> BridgeTarget<L> {
    /// SELF_TEST, then the capture it made: the bridge resets its chip
    /// first, so the capture and the bridge's clock start afresh.
    pub(super) fn run_self_test(
        &mut self,
        plan: &SelfTestPlan,
    ) -> Result<SelfTestRun, BridgeError> {
        self.captured = OutputRecord::default();
        self.let_go = OutputMark::default();
        self.captured_current = false;
        self.clock = Instant::ZERO;
        // The chip reset (100 us) and the bursts, each with its gap.
        let extra = WallDuration::from_nanos(plan.length().as_nanos().saturating_add(1_000_000));
        let reply = match self.request(&Request::SelfTest(*plan), "self-test", extra)? {
            Response::SelfTest(r) => r,
            other => return Err(self.unexpected("self-test", &other)),
        };
        let capture = match self.fetch_capture() {
            Ok(()) => Ok(self.captured.clone()),
            Err(BridgeError::CaptureOverrun { detail, .. }) => Err(detail),
            Err(e) => return Err(e),
        };
        Ok(SelfTestRun { reply, capture })
    }

    /// Brings `captured` up to date with the bridge's capture.
    pub(super) fn fetch_capture(&mut self) -> Result<(), BridgeError> {
        while !self.captured_current {
            let (runs, pins, moves) = self.capture_from();
            let req = Request::Capture {
                runs,
                pins,
                moves,
                max: CAPTURE_CHUNK,
            };
            match self.request(&req, "capture", WallDuration::ZERO)? {
                Response::Capture(c) => {
                    // Every chunk that says there is more must bring some,
                    // and the capture can hold no more than the bridge said
                    // its buffer does: a bridge that says `more` for ever
                    // ends the download.
                    let brought = c.runs.len() + c.pins.len() + c.moves.len();
                    let more = self.absorb(c);
                    let held = self.captured.runs.len() + self.captured.pins.len();
                    let room = (self.hello.capture_capacity as usize).min(MAX_CAPTURE_RECORDS);
                    if more && (brought == 0 || held > room) {
                        return Err(BridgeError::Protocol {
                            link: self.link.name(),
                            what: "capture".into(),
                            detail: match brought {
                                0 => "a chunk that says more records follow brought none".into(),
                                _ => format!(
                                    "{held} records and still more, past the {room} its buffer holds"
                                ),
                            },
                        });
                    }
                    if !more {
                        break;
                    }
                }
                other => return Err(self.unexpected("capture", &other)),
            }
        }
        self.captured_current = self.hello.virtual_time;
        Ok(())
    }
}

/// The ops of `ops` from index `from` on.
pub(super) fn ops_from(ops: &[Op], from: usize) -> &[Op] {
    &ops[from.min(ops.len())..]
}
