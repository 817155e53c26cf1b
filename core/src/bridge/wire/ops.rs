//! Bus ops and their replies on the wire: the BATCH and BATCH_REPLY
//! entries, SAMPLE ops and their run-length SAMPLES replies, and the
//! worst-case sizes a host packs requests by.

use super::bytes::{Timer, R, W};
use super::message::*;
use crate::bus::{Op, Reply};
use crate::protocol::{Direction, Pins, PulseSummary, Status};
use crate::time::Instant;
use alloc::vec::Vec;

/// Op codes inside a batch.
pub(super) mod op {
    pub const WC: u8 = 0x10;
    pub const WD: u8 = 0x11;
    pub const RS: u8 = 0x12;
    pub const RD: u8 = 0x13;
    pub const DELAY: u8 = 0x14;
    pub const AWAIT: u8 = 0x15;
    pub const SET: u8 = 0x16;
    pub const PINS: u8 = 0x17;
    pub const PULSES: u8 = 0x18;
    pub const AWAIT_PULSES: u8 = 0x19;
    pub const RESET: u8 = 0x1A;
    pub const SAMPLE: u8 = 0x1B;
}

/// Reply codes inside a batch reply.
pub(super) mod rep {
    pub const WRITTEN: u8 = 0x01;
    pub const WRITE_TIMEOUT: u8 = 0x02;
    pub const STATUS: u8 = 0x03;
    pub const DATA: u8 = 0x04;
    pub const READ_TIMEOUT: u8 = 0x05;
    pub const DELAYED: u8 = 0x06;
    pub const AWAITED: u8 = 0x07;
    pub const AWAIT_TIMEOUT: u8 = 0x08;
    pub const INPUT_SET: u8 = 0x09;
    pub const PINS: u8 = 0x0A;
    pub const PULSES: u8 = 0x0B;
    pub const PULSES_REACHED: u8 = 0x0C;
    pub const PULSES_TIMEOUT: u8 = 0x0D;
    pub const RESET_DONE: u8 = 0x0E;
    pub const SAMPLES: u8 = 0x0F;
}

/// The largest reply entry of a plain op on the wire (PULSES).
pub const MAX_REPLY_ENTRY: usize = 73;

/// Most ops one batch may carry: the largest reply (128 x
/// [`MAX_REPLY_ENTRY`] bytes) then stays within 255 fragments. A bridge
/// may announce fewer in HELLO_REPLY, never more.
pub const MAX_BATCH_OPS: u16 = 128;

/// A SAMPLES entry without its runs: code, time, step, samples, runs.
pub(super) const SAMPLES_HEAD: usize = 1 + 8 + 8 + 2 + 2;

/// One SAMPLES run: count, then the pins.
pub(super) const SAMPLES_RUN: usize = 2 + 4;

/// The number of `(ReadPins, Delay(step))` pairs, all with the same step,
/// that `ops` starts with, at most [`MAX_SAMPLES`].
pub(super) fn sample_pairs(ops: &[Op]) -> usize {
    let Some(Op::Delay(step)) = ops.get(1) else {
        return 0;
    };
    ops.chunks_exact(2)
        .take(MAX_SAMPLES)
        .take_while(|p| matches!(p, [Op::ReadPins, Op::Delay(s)] if s == step))
        .count()
}

/// How a batch goes on the wire: for each wire op in order, how many ops
/// of `ops` it stands for. Two or more `(ReadPins, Delay(step))` pairs in a
/// row with the same step are one SAMPLE op (twice the sample count); any
/// other op is itself (1).
pub fn wire_ops(ops: &[Op]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < ops.len() {
        let n = match sample_pairs(&ops[i..]) {
            pairs @ 2.. => 2 * pairs,
            _ => 1,
        };
        out.push(n);
        i += n;
    }
    out
}

/// The bytes one wire op (a group from [`wire_ops`]) takes in a request.
pub fn wire_op_len(group: &[Op], timer: Timer) -> usize {
    let mut w = W(Vec::with_capacity(16), timer);
    put_wire_op(&mut w, group);
    w.0.len()
}

/// The most bytes the reply entry to one wire op can take.
pub fn worst_reply_len(group: &[Op]) -> usize {
    match group {
        [] => 0,
        [o] => worst_reply_entry(o),
        _ => SAMPLES_HEAD + SAMPLES_RUN * (group.len() / 2),
    }
}

/// The most bytes the reply entry to a plain op can take: code, time, and
/// the longest of the replies it may get.
pub(super) fn worst_reply_entry(o: &Op) -> usize {
    1 + 8
        + match o {
            Op::WriteCommand { .. } | Op::WriteData { .. } => 8,
            Op::ReadStatus => 1,
            Op::ReadData { .. } | Op::AwaitStatus { .. } => 1 + 8,
            Op::Delay(_) | Op::SetInput { .. } | Op::Reset => 0,
            Op::ReadPins => 4,
            Op::ReadPulses => MAX_REPLY_ENTRY - 9,
            Op::AwaitPulses { .. } => 8,
        }
}

pub(super) fn put_wire_op(w: &mut W, group: &[Op]) {
    match (group, group.len() / 2) {
        ([Op::ReadPins, Op::Delay(step), ..], pairs) if pairs >= 2 => {
            w.u8(op::SAMPLE);
            w.u16(pairs as u16);
            w.dur(*step);
        }
        _ => {
            if let Some(o) = group.first() {
                put_op(w, o);
            }
        }
    }
}

/// A `count` u16 of wire ops, then the wire ops (BATCH, BATCH_CAPTURE).
pub(super) fn put_ops(w: &mut W, ops: &[Op]) {
    let groups = wire_ops(ops);
    w.u16(groups.len() as u16);
    let mut rest = ops;
    for n in groups {
        let (group, tail) = rest.split_at(n);
        put_wire_op(w, group);
        rest = tail;
    }
}

pub(super) fn get_ops(r: &mut R) -> Result<Vec<Op>, WireError> {
    let n = r.count(1)?;
    let mut ops = Vec::with_capacity(n);
    for _ in 0..n {
        if r.peek() == Some(op::SAMPLE) {
            r.u8()?;
            let pairs = r.samples()?;
            let step = r.dur()?;
            for _ in 0..pairs {
                ops.push(Op::ReadPins);
                ops.push(Op::Delay(step));
            }
        } else {
            ops.push(get_op(r)?);
        }
    }
    Ok(ops)
}

/// The run of regular pin samples that `replies` starts with, in ticks of
/// `timer`: `(pairs, first time, step)` when at least two
/// `(Pins, Delayed)` pairs follow each other on one grid (each pins read at
/// the end of the delay before it, each delay `step` long), at most
/// [`MAX_SAMPLES`].
pub(super) fn sample_replies(replies: &[Reply], timer: Timer) -> Option<(usize, u64, u64)> {
    let tick = |i: Instant| timer.to_ticks(i.as_nanos());
    let (t0, step) = match replies {
        [Reply::Pins { at, .. }, Reply::Delayed { at: end }, ..] => {
            (tick(*at), tick(*end).checked_sub(tick(*at))?)
        }
        _ => return None,
    };
    let pairs = replies
        .chunks_exact(2)
        .take(MAX_SAMPLES)
        .enumerate()
        .take_while(|(i, p)| {
            let at = step.checked_mul(*i as u64).and_then(|d| t0.checked_add(d));
            let end = at.and_then(|a| a.checked_add(step));
            matches!(p, [Reply::Pins { at: a, .. }, Reply::Delayed { at: e }]
                if Some(tick(*a)) == at && Some(tick(*e)) == end)
        })
        .count();
    (pairs >= 2).then_some((pairs, t0, step))
}

/// A `count` u16 of reply entries, then the entries (BATCH_REPLY,
/// BATCH_CAPTURE_REPLY). A run of regular pin samples is one SAMPLES entry.
pub(super) fn put_replies(w: &mut W, replies: &[Reply]) {
    let count_at = w.0.len();
    w.u16(0);
    let mut entries: u16 = 0;
    let mut rest = replies;
    while !rest.is_empty() {
        let n = match sample_replies(rest, w.1) {
            Some((pairs, t0, step)) => {
                put_samples(w, &rest[..2 * pairs], t0, step);
                2 * pairs
            }
            None => {
                put_reply(w, &rest[0]);
                1
            }
        };
        rest = &rest[n..];
        entries = entries.saturating_add(1);
    }
    w.0[count_at..count_at + 2].copy_from_slice(&entries.to_le_bytes());
}

/// A SAMPLES entry: first time and step (ticks), the sample count, then
/// the pins as runs of equal samples.
pub(super) fn put_samples(w: &mut W, pairs: &[Reply], t0: u64, step: u64) {
    let pins: Vec<Pins> = pairs
        .iter()
        .filter_map(|r| match r {
            Reply::Pins { pins, .. } => Some(*pins),
            _ => None,
        })
        .collect();
    let mut runs: Vec<(u16, Pins)> = Vec::new();
    for p in pins.iter().copied() {
        match runs.last_mut() {
            Some((n, q)) if *q == p => *n += 1,
            _ => runs.push((1, p)),
        }
    }
    w.u8(rep::SAMPLES);
    w.u64(t0);
    w.u64(step);
    w.u16(pins.len() as u16);
    w.u16(runs.len() as u16);
    for (n, p) in runs {
        w.u16(n);
        put_pins(w, &p);
    }
}

/// The fewest bytes a reply entry takes: a code and a time (DELAYED,
/// INPUT_SET, PULSES_REACHED, RESET_DONE).
pub(super) const MIN_REPLY_ENTRY: usize = 1 + 8;

/// The most replies one response can stand for: a reply per op of a
/// batch of [`MAX_BATCH_OPS`] wire ops, each at most a SAMPLE op of
/// [`MAX_SAMPLES`] pairs. A reply that expands to more is refused, so a
/// lying bridge cannot make the host allocate more than that.
pub(super) const MAX_REPLIES: usize = 2 * MAX_SAMPLES * MAX_BATCH_OPS as usize;

pub(super) fn get_replies(r: &mut R) -> Result<Vec<Reply>, WireError> {
    let n = r.count(MIN_REPLY_ENTRY)?;
    let mut v = Vec::with_capacity(n);
    for _ in 0..n {
        if r.peek() == Some(rep::SAMPLES) {
            get_samples(r, &mut v)?;
        } else {
            v.push(get_reply(r)?);
        }
    }
    Ok(v)
}

pub(super) fn get_samples(r: &mut R, out: &mut Vec<Reply>) -> Result<(), WireError> {
    r.u8()?;
    let (t0, step) = (r.u64()?, r.u64()?);
    let at = r.at;
    let samples = r.samples()?;
    let runs_at = r.at;
    let runs = r.count(SAMPLES_RUN)?;
    // Each run holds at least one sample; and the replies of a whole
    // response stay within what a batch can ask for.
    if runs > samples {
        return Err(WireError::BadValue {
            at: runs_at,
            field: "sample runs (more than samples)",
            value: runs as u64,
        });
    }
    if out.len() + 2 * samples > MAX_REPLIES {
        return Err(WireError::BadValue {
            at,
            field: "samples (more replies than a batch can ask for)",
            value: samples as u64,
        });
    }
    let timer = r.timer;
    let time = |ticks: Option<u64>| {
        ticks
            .map(|t| Instant::from_nanos(timer.to_nanos(t)))
            .ok_or(WireError::BadValue {
                at,
                field: "sample time",
                value: t0,
            })
    };
    let mut i: u64 = 0;
    for _ in 0..runs {
        let nat = r.at;
        let n = r.u16()?;
        // Checked before expanding: a run past the sample count would
        // otherwise push up to 131,070 replies of a lie.
        if n == 0 || i + u64::from(n) > samples as u64 {
            return Err(WireError::BadValue {
                at: nat,
                field: "sample run length",
                value: u64::from(n),
            });
        }
        let pins = get_pins(r)?;
        for _ in 0..n {
            let start = step.checked_mul(i).and_then(|d| t0.checked_add(d));
            out.push(Reply::Pins {
                at: time(start)?,
                pins,
            });
            out.push(Reply::Delayed {
                at: time(start.and_then(|s| s.checked_add(step)))?,
            });
            i += 1;
        }
    }
    if i != samples as u64 {
        return Err(WireError::BadValue {
            at,
            field: "sample count (runs add up to another)",
            value: i,
        });
    }
    Ok(())
}

pub(super) fn put_pins(w: &mut W, pins: &Pins) {
    let flags = u8::from(pins.int)
        | u8::from(pins.hold) << 1
        | u8::from(pins.aux) << 2
        | u8::from(pins.dir.bit()) << 3
        | u8::from(pins.busy) << 4;
    w.u8(flags);
    w.u8(pins.auxo);
    w.u8(pins.phases);
    w.u8(pins.phase_levels);
}

pub(super) fn get_pins(r: &mut R) -> Result<Pins, WireError> {
    let flags = r.u8()?;
    Ok(Pins {
        int: flags & 1 != 0,
        hold: flags & 2 != 0,
        aux: flags & 4 != 0,
        dir: Direction::from_bit(flags & 8 != 0),
        busy: flags & 16 != 0,
        auxo: r.u8()?,
        phases: r.u8()?,
        phase_levels: r.u8()?,
    })
}

pub(super) fn put_op(w: &mut W, o: &Op) {
    match *o {
        Op::WriteCommand { byte, wait_ibf } | Op::WriteData { byte, wait_ibf } => {
            w.u8(if matches!(o, Op::WriteCommand { .. }) {
                op::WC
            } else {
                op::WD
            });
            w.u8(byte);
            w.opt_dur(wait_ibf);
        }
        Op::ReadStatus => w.u8(op::RS),
        Op::ReadData { wait_obf } => {
            w.u8(op::RD);
            w.opt_dur(wait_obf);
        }
        Op::Delay(d) => {
            w.u8(op::DELAY);
            w.dur(d);
        }
        Op::AwaitStatus {
            mask,
            value,
            timeout,
        } => {
            w.u8(op::AWAIT);
            w.u8(mask);
            w.u8(value);
            w.dur(timeout);
        }
        Op::SetInput { input, asserted } => {
            w.u8(op::SET);
            w.u8(input.index());
            w.u8(u8::from(asserted));
        }
        Op::ReadPins => w.u8(op::PINS),
        Op::ReadPulses => w.u8(op::PULSES),
        Op::AwaitPulses { count, timeout } => {
            w.u8(op::AWAIT_PULSES);
            w.u64(count);
            w.dur(timeout);
        }
        Op::Reset => w.u8(op::RESET),
    }
}

pub(super) fn get_op(r: &mut R) -> Result<Op, WireError> {
    let at = r.at;
    Ok(match r.u8()? {
        c @ (op::WC | op::WD) => {
            let byte = r.u8()?;
            let wait_ibf = r.opt_dur()?;
            if c == op::WC {
                Op::WriteCommand { byte, wait_ibf }
            } else {
                Op::WriteData { byte, wait_ibf }
            }
        }
        op::RS => Op::ReadStatus,
        op::RD => Op::ReadData {
            wait_obf: r.opt_dur()?,
        },
        op::DELAY => Op::Delay(r.dur()?),
        op::AWAIT => Op::AwaitStatus {
            mask: r.u8()?,
            value: r.u8()?,
            timeout: r.dur()?,
        },
        op::SET => Op::SetInput {
            input: r.input()?,
            asserted: r.bool("asserted")?,
        },
        op::PINS => Op::ReadPins,
        op::PULSES => Op::ReadPulses,
        op::AWAIT_PULSES => Op::AwaitPulses {
            count: r.u64()?,
            timeout: r.dur()?,
        },
        op::RESET => Op::Reset,
        code => return Err(WireError::UnknownCode { at, code }),
    })
}

pub(super) fn put_reply(w: &mut W, rp: &Reply) {
    match *rp {
        Reply::Written { at, waited } => {
            w.u8(rep::WRITTEN);
            w.time(at);
            w.dur(waited);
        }
        Reply::WriteTimedOut { at, status } => {
            w.u8(rep::WRITE_TIMEOUT);
            w.time(at);
            w.u8(status.0);
        }
        Reply::Status { at, status } => {
            w.u8(rep::STATUS);
            w.time(at);
            w.u8(status.0);
        }
        Reply::Data { at, byte, waited } => {
            w.u8(rep::DATA);
            w.time(at);
            w.u8(byte);
            w.dur(waited);
        }
        Reply::ReadTimedOut { at, status } => {
            w.u8(rep::READ_TIMEOUT);
            w.time(at);
            w.u8(status.0);
        }
        Reply::Delayed { at } => {
            w.u8(rep::DELAYED);
            w.time(at);
        }
        Reply::Awaited { at, waited, status } => {
            w.u8(rep::AWAITED);
            w.time(at);
            w.dur(waited);
            w.u8(status.0);
        }
        Reply::AwaitTimedOut { at, status } => {
            w.u8(rep::AWAIT_TIMEOUT);
            w.time(at);
            w.u8(status.0);
        }
        Reply::InputSet { at } => {
            w.u8(rep::INPUT_SET);
            w.time(at);
        }
        Reply::Pins { at, pins } => {
            w.u8(rep::PINS);
            w.time(at);
            put_pins(w, &pins);
        }
        Reply::Pulses { at, summary } => {
            w.u8(rep::PULSES);
            w.time(at);
            w.u64(summary.count);
            w.u64(summary.cw);
            w.u64(summary.ccw);
            w.opt_time(summary.first);
            w.opt_time(summary.last);
            w.opt_dur(summary.min_interval);
            w.opt_dur(summary.max_interval);
            w.bound(summary.interval_bound);
        }
        Reply::PulsesReached { at } => {
            w.u8(rep::PULSES_REACHED);
            w.time(at);
        }
        Reply::PulsesTimedOut { at, count } => {
            w.u8(rep::PULSES_TIMEOUT);
            w.time(at);
            w.u64(count);
        }
        Reply::ResetDone { at } => {
            w.u8(rep::RESET_DONE);
            w.time(at);
        }
    }
}

pub(super) fn get_reply(r: &mut R) -> Result<Reply, WireError> {
    let at_code = r.at;
    let code = r.u8()?;
    let at = r.time()?;
    Ok(match code {
        rep::WRITTEN => Reply::Written {
            at,
            waited: r.dur()?,
        },
        rep::WRITE_TIMEOUT => Reply::WriteTimedOut {
            at,
            status: Status(r.u8()?),
        },
        rep::STATUS => Reply::Status {
            at,
            status: Status(r.u8()?),
        },
        rep::DATA => Reply::Data {
            at,
            byte: r.u8()?,
            waited: r.dur()?,
        },
        rep::READ_TIMEOUT => Reply::ReadTimedOut {
            at,
            status: Status(r.u8()?),
        },
        rep::DELAYED => Reply::Delayed { at },
        rep::AWAITED => Reply::Awaited {
            at,
            waited: r.dur()?,
            status: Status(r.u8()?),
        },
        rep::AWAIT_TIMEOUT => Reply::AwaitTimedOut {
            at,
            status: Status(r.u8()?),
        },
        rep::INPUT_SET => Reply::InputSet { at },
        rep::PINS => Reply::Pins {
            at,
            pins: get_pins(r)?,
        },
        rep::PULSES => Reply::Pulses {
            at,
            summary: PulseSummary {
                count: r.u64()?,
                cw: r.u64()?,
                ccw: r.u64()?,
                first: r.opt_time()?,
                last: r.opt_time()?,
                min_interval: r.opt_dur()?,
                max_interval: r.opt_dur()?,
                interval_bound: r.bound()?,
            },
        },
        rep::PULSES_REACHED => Reply::PulsesReached { at },
        rep::PULSES_TIMEOUT => Reply::PulsesTimedOut {
            at,
            count: r.u64()?,
        },
        rep::RESET_DONE => Reply::ResetDone { at },
        code => return Err(WireError::UnknownCode { at: at_code, code }),
    })
}
