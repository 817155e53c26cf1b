//! The bridge's side of a batch, in memory that does not grow with the
//! samples a batch asks for.
//!
//! A SAMPLE op stands for up to [`MAX_SAMPLES`] `(ReadPins, Delay)` pairs,
//! so a batch of [`MAX_BATCH_OPS`] wire ops stands for up to 131,072 ops.
//! Decoded into a `Vec<Op>` (24 bytes an op on a Cortex-M) with a
//! `Vec<Reply>` (104 bytes) for its replies, one batch the host sends to
//! measure stop switching (three SAMPLE ops of 512 pairs) took 400 KB: more
//! than a bridge's heap (firmware/README.md). A bridge reads a batch as
//! [`WireOp`]s instead, one per wire op, and writes the replies as they
//! come with a [`ReplyWriter`], which turns each run of regular samples
//! into its SAMPLES entry on the fly: the same bytes as
//! [`Response::encode`], in memory bounded by [`MAX_REPLY`].

use super::bytes::{Timer, R, W};
use super::capture::{put_capture, RUN_BYTES};
use super::message::*;
use super::ops::{get_op, op, put_pins, put_reply, rep, SAMPLES_HEAD, SAMPLES_RUN};
use crate::bus::{Op, Reply};
use crate::protocol::Pins;
use crate::time::{Duration, Instant};
use alloc::vec;
use alloc::vec::Vec;

/// One op of a batch as it travels: a plain op, or a SAMPLE op that stands
/// for `pairs` `(ReadPins, Delay(step))` pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireOp {
    Op(Op),
    Sample { pairs: u16, step: Duration },
}

impl WireOp {
    /// How many ops it stands for.
    pub fn len(&self) -> usize {
        match self {
            WireOp::Op(_) => 1,
            WireOp::Sample { pairs, .. } => 2 * usize::from(*pairs),
        }
    }

    /// Never: a wire op stands for at least one op.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The `i`th op it stands for (`i < len`).
    pub fn op(&self, i: usize) -> Op {
        match *self {
            WireOp::Op(o) => o,
            WireOp::Sample { step, .. } if i % 2 == 1 => Op::Delay(step),
            WireOp::Sample { .. } => Op::ReadPins,
        }
    }

    /// The ops of `ops`, in order, without expanding them into a vector.
    pub fn ops(ops: &[WireOp]) -> impl Iterator<Item = Op> + '_ {
        ops.iter().flat_map(|w| (0..w.len()).map(move |i| w.op(i)))
    }
}

/// A request as a bridge reads it: the ops of a BATCH or BATCH_CAPTURE as
/// [`WireOp`]s; any other request as [`Request::decode`] gives it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Incoming {
    Batch(Vec<WireOp>),
    BatchCapture {
        ops: Vec<WireOp>,
        runs: u32,
        pins: u32,
        moves: u32,
        max: u16,
    },
    Other(Request),
}

impl Incoming {
    /// `(seq, request)` from a frame payload, times in ticks of `timer`:
    /// the same checks as [`Request::decode`], and the same request.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Incoming), WireError> {
        let k = payload.get(1).copied();
        if k != Some(kind::BATCH) && k != Some(kind::BATCH_CAPTURE) {
            return Request::decode(payload, timer).map(|(seq, req)| (seq, Incoming::Other(req)));
        }
        let mut r = R::new(payload, timer);
        let seq = r.u8()?;
        r.u8()?;
        let ops = get_wire_ops(&mut r)?;
        let req = if k == Some(kind::BATCH) {
            Incoming::Batch(ops)
        } else {
            Incoming::BatchCapture {
                ops,
                runs: r.u32()?,
                pins: r.u32()?,
                moves: r.u32()?,
                max: r.u16()?,
            }
        };
        r.end()?;
        Ok((seq, req))
    }
}

/// The wire ops of a batch, each SAMPLE op whole.
fn get_wire_ops(r: &mut R) -> Result<Vec<WireOp>, WireError> {
    let n = r.count(1)?;
    let mut ops = Vec::with_capacity(n);
    for _ in 0..n {
        if r.peek() == Some(op::SAMPLE) {
            r.u8()?;
            let pairs = r.samples()? as u16;
            let step = r.dur()?;
            ops.push(WireOp::Sample { pairs, step });
        } else {
            ops.push(WireOp::Op(get_op(r)?));
        }
    }
    Ok(ops)
}

/// A run of regular pin samples being gathered: `pairs` `(Pins, Delayed)`
/// pairs so far, the `k`th pins read at `t0 + k * step` ticks.
#[derive(Debug)]
struct SampleRun {
    t0: u64,
    step: u64,
    pairs: usize,
    /// The samples as runs of equal pins.
    runs: Vec<(u16, Pins)>,
    /// The first pair, written as two plain entries if no second follows.
    first: [Reply; 2],
    /// The pins read of the next pair, on the grid, waiting for its delay.
    open: Option<Reply>,
}

/// The reply to a batch, written one op's reply at a time: the same bytes
/// [`Response::encode`] gives a `Response::Batch` (or the replies part of
/// a `Response::BatchCapture`) of the same replies. A run of regular pin
/// samples is held as runs of equal pins until it ends; nothing else is
/// held. Past `limit` bytes it keeps counting but no longer keeps them: a
/// reply that long is not sent (the bridge answers OVERFLOW, saying how
/// long it would have been).
#[derive(Debug)]
pub struct ReplyWriter {
    w: W,
    count_at: usize,
    entries: u16,
    limit: usize,
    /// Bytes written past `limit` and not kept.
    dropped: usize,
    /// A pins read that may start a run of samples.
    lone: Option<Reply>,
    run: Option<SampleRun>,
}

impl ReplyWriter {
    /// The reply to batch `seq` (a BATCH_CAPTURE's, when `with_capture`),
    /// times in ticks of `timer`, kept up to `limit` bytes.
    pub fn new(seq: u8, with_capture: bool, timer: Timer, limit: usize) -> ReplyWriter {
        // Room for the longest reply kept and the entry that crosses it.
        let mut w = W(
            Vec::with_capacity(limit.min(MAX_REPLY) + SAMPLES_HEAD + SAMPLES_RUN * MAX_SAMPLES),
            timer,
        );
        w.u8(seq);
        w.u8(if with_capture {
            kind::BATCH_CAPTURE_REPLY
        } else {
            kind::BATCH_REPLY
        });
        let count_at = w.0.len();
        w.u16(0);
        ReplyWriter {
            w,
            count_at,
            entries: 0,
            limit,
            dropped: 0,
            lone: None,
            run: None,
        }
    }

    fn tick(&self, at: Instant) -> u64 {
        self.w.1.to_ticks(at.as_nanos())
    }

    /// Adds the reply to the next op.
    pub fn push(&mut self, r: Reply) {
        if let Some(run) = &mut self.run {
            let k = run.pairs as u64;
            let grid = run.step.checked_mul(k).and_then(|d| run.t0.checked_add(d));
            match run.open {
                None => {
                    if let Reply::Pins { at, .. } = r {
                        if run.pairs < MAX_SAMPLES && Some(self.w.1.to_ticks(at.as_nanos())) == grid
                        {
                            run.open = Some(r);
                            return;
                        }
                    }
                    self.close_run();
                }
                Some(p) => {
                    let end = grid.and_then(|g| g.checked_add(run.step));
                    if let (Reply::Pins { pins, .. }, Reply::Delayed { at }) = (p, r) {
                        if Some(self.w.1.to_ticks(at.as_nanos())) == end {
                            run.pairs += 1;
                            run.open = None;
                            match run.runs.last_mut() {
                                Some((n, q)) if *q == pins => *n += 1,
                                _ => run.runs.push((1, pins)),
                            }
                            return;
                        }
                    }
                    // The pair breaks the run: the run ends before it,
                    // and the pair starts afresh.
                    self.close_run();
                    self.push(p);
                    self.push(r);
                    return;
                }
            }
        }
        if let Some(p) = self.lone.take() {
            if let (Reply::Pins { at, pins }, Reply::Delayed { at: end }) = (p, r) {
                let t0 = self.tick(at);
                if let Some(step) = self.tick(end).checked_sub(t0) {
                    self.run = Some(SampleRun {
                        t0,
                        step,
                        pairs: 1,
                        runs: vec![(1, pins)],
                        first: [p, r],
                        open: None,
                    });
                    return;
                }
            }
            self.plain(&p);
        }
        match r {
            Reply::Pins { .. } => self.lone = Some(r),
            _ => self.plain(&r),
        }
    }

    /// Ends the run of samples being gathered: one SAMPLES entry for two
    /// pairs or more, plain entries for one; a pins read left open is not
    /// part of it (the caller gives it again).
    fn close_run(&mut self) {
        let Some(run) = self.run.take() else { return };
        if run.pairs < 2 {
            self.plain(&run.first[0]);
            self.plain(&run.first[1]);
            return;
        }
        self.entry(|w| {
            w.u8(rep::SAMPLES);
            w.u64(run.t0);
            w.u64(run.step);
            w.u16(run.pairs as u16);
            w.u16(run.runs.len() as u16);
            for (n, p) in &run.runs {
                w.u16(*n);
                put_pins(w, p);
            }
        });
    }

    fn plain(&mut self, r: &Reply) {
        self.entry(|w| put_reply(w, r));
    }

    fn entry(&mut self, put: impl FnOnce(&mut W)) {
        let start = self.w.0.len();
        put(&mut self.w);
        self.entries = self.entries.saturating_add(1);
        if self.dropped > 0 || self.w.0.len() > self.limit {
            self.dropped += self.w.0.len() - start;
            self.w.0.truncate(start);
        }
    }

    /// The reply so far, the runs of samples still open included: its
    /// length in bytes.
    pub fn len(&self) -> usize {
        self.w.0.len() + self.dropped
    }

    /// Whether no reply has been added.
    pub fn is_empty(&self) -> bool {
        self.entries == 0 && self.lone.is_none() && self.run.is_none()
    }

    /// The reply's bytes (a BATCH_CAPTURE's without its capture, which
    /// the caller appends: [`capture_bytes`]), or its length if that is
    /// more than `limit`.
    pub fn finish(mut self) -> Result<Vec<u8>, usize> {
        if let Some(p) = self.run.as_mut().and_then(|run| run.open.take()) {
            self.close_run();
            self.push(p);
        }
        self.close_run();
        if let Some(p) = self.lone.take() {
            self.plain(&p);
        }
        if self.dropped > 0 {
            return Err(self.len());
        }
        let at = self.count_at;
        self.w.0[at..at + 2].copy_from_slice(&self.entries.to_le_bytes());
        Ok(self.w.0)
    }
}

/// A capture chunk's bytes, as a BATCH_CAPTURE's reply ends with them.
pub fn capture_bytes(c: &CaptureChunk, timer: Timer) -> Vec<u8> {
    // Allocated once: counts, runs, pin changes (time, pin, value), moves
    // (time, kind, dir, pout, steps, winding, phase, first run), the
    // overwritten count and `more`.
    let len = 3 * 2
        + RUN_BYTES * c.runs.len()
        + (8 + 2) * c.pins.len()
        + (8 + 3 + 4 + 1 + 4 + 4) * c.moves.len()
        + 8
        + 1;
    let mut w = W(Vec::with_capacity(len), timer);
    put_capture(&mut w, c);
    debug_assert_eq!(w.0.len(), len);
    w.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{Direction, Status};
    use proptest::prelude::*;

    fn pins(b: u8) -> Pins {
        Pins {
            int: b & 1 != 0,
            hold: b & 2 != 0,
            aux: false,
            auxo: 0,
            phases: b >> 2,
            phase_levels: b >> 2,
            dir: Direction::Cw,
            busy: false,
        }
    }

    fn t(ns: u64) -> Instant {
        Instant::from_nanos(ns)
    }

    /// Replies like a batch's: samples on a grid (with now and then a
    /// sample off it, a pins read without its delay, or another reply in
    /// between), in stretches of up to 1,200 pairs.
    fn replies() -> impl Strategy<Value = Vec<Reply>> {
        let piece = (0u8..8, 1usize..1_200, 1u64..500, 0u8..4, 0u64..3);
        proptest::collection::vec(piece, 0..6).prop_map(|pieces| {
            let mut out = Vec::new();
            let mut now = 1_000u64;
            for (kind, n, step, levels, jitter) in pieces {
                match kind {
                    0 => out.push(Reply::Status {
                        at: t(now),
                        status: Status(0x81),
                    }),
                    1 => out.push(Reply::Pins {
                        at: t(now),
                        pins: pins(levels),
                    }),
                    2 => {
                        out.push(Reply::Delayed { at: t(now) });
                    }
                    _ => {
                        for k in 0..n {
                            // Now and then a read off the grid.
                            let off = if k % 97 == 13 { jitter } else { 0 };
                            out.push(Reply::Pins {
                                at: t(now + off),
                                pins: pins(levels.wrapping_add((k / 7) as u8) & 7),
                            });
                            now += step;
                            out.push(Reply::Delayed { at: t(now) });
                        }
                    }
                }
                now += 10;
            }
            out
        })
    }

    fn written(
        replies: &[Reply],
        timer: Timer,
        with_capture: bool,
        limit: usize,
    ) -> Result<Vec<u8>, usize> {
        let mut w = ReplyWriter::new(9, with_capture, timer, limit);
        for r in replies {
            w.push(*r);
        }
        w.finish()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn the_writer_gives_the_bytes_of_the_whole_response(
            replies in replies(),
            hz in prop::sample::select(vec![1_000_000_000u64, 75_000_000, 16_000_000]),
            limit in prop::sample::select(vec![MAX_REPLY, 2_000, 300]),
        ) {
            let timer = Timer { hz };
            let whole = Response::Batch(replies.clone()).encode(9, timer);
            match written(&replies, timer, false, limit) {
                Ok(bytes) => prop_assert_eq!(bytes, whole),
                Err(len) => {
                    prop_assert!(whole.len() > limit);
                    prop_assert_eq!(len, whole.len());
                }
            }
        }
    }

    #[test]
    fn a_batch_capture_reply_is_the_replies_then_the_capture() {
        let replies: Vec<Reply> = (0..40)
            .flat_map(|k| {
                [
                    Reply::Pins {
                        at: t(k * 100),
                        pins: pins((k / 9) as u8),
                    },
                    Reply::Delayed {
                        at: t(k * 100 + 100),
                    },
                ]
            })
            .collect();
        let capture = CaptureChunk {
            more: true,
            ..CaptureChunk::default()
        };
        let whole = Response::BatchCapture {
            replies: replies.clone(),
            capture: capture.clone(),
        }
        .encode(9, Timer::NANOS);
        let mut bytes = written(&replies, Timer::NANOS, true, MAX_REPLY).expect("short");
        bytes.extend(capture_bytes(&capture, Timer::NANOS));
        assert_eq!(bytes, whole);
    }

    #[test]
    fn a_batch_decodes_to_the_same_ops_with_its_samples_whole() {
        let mut ops = vec![Op::ReadStatus];
        for _ in 0..600 {
            ops.extend([Op::ReadPins, Op::Delay(Duration::from_micros(5))]);
        }
        ops.push(Op::Reset);
        for req in [
            Request::Batch(ops.clone()),
            Request::BatchCapture {
                ops: ops.clone(),
                runs: 1,
                pins: 2,
                moves: 3,
                max: 60,
            },
        ] {
            let bytes = req.encode(4, Timer::NANOS);
            let (seq, lean) = Incoming::decode(&bytes, Timer::NANOS).expect("decodes");
            assert_eq!(seq, 4);
            let wire = match &lean {
                Incoming::Batch(w) => w,
                Incoming::BatchCapture {
                    ops,
                    runs: 1,
                    pins: 2,
                    moves: 3,
                    max: 60,
                } => ops,
                other => panic!("{other:?}"),
            };
            // 600 pairs: a SAMPLE of 512 and one of 88.
            assert_eq!(wire.len(), 4);
            assert_eq!(WireOp::ops(wire).collect::<Vec<_>>(), ops);
            // A message Request::decode refuses, this refuses too.
            let mut cut = bytes.clone();
            cut.pop();
            assert!(Request::decode(&cut, Timer::NANOS).is_err());
            assert!(Incoming::decode(&cut, Timer::NANOS).is_err());
        }
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 7,
        };
        assert_eq!(
            Incoming::decode(&hello.encode(1, Timer::NANOS), Timer::NANOS),
            Ok((1, Incoming::Other(hello)))
        );
    }

    #[test]
    fn past_the_limit_the_writer_counts_and_keeps_nothing_more() {
        let mut w = ReplyWriter::new(1, false, Timer::NANOS, 100);
        for k in 0..50 {
            w.push(Reply::Status {
                at: t(k),
                status: Status(0),
            });
        }
        // Header 4 bytes, 50 entries of 10.
        assert_eq!(w.len(), 504);
        assert!(w.w.0.len() <= 100);
        assert_eq!(w.finish(), Err(504));
    }
}
