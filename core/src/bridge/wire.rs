//! Bridge messages: typed requests and responses, and their bytes.
//!
//! A frame payload is `seq:u8, kind:u8, body`. All integers are little
//! endian. Times and durations on the wire are ticks of the bridge's timer,
//! whose rate the bridge announces in its hello reply; the host converts.
//! [`Request::decode`] and [`Response::decode`] check every length and
//! value and never panic; `docs/bridge-protocol.md` is the specification.

use crate::bus::{Op, Reply};
use crate::protocol::capture::MoveStart;
use crate::protocol::{
    Direction, Input, MoveKind, Pin, PinEvent, Pins, PulseRun, PulseSummary, Status, Straps,
    Winding,
};
use crate::time::{Duration, Instant};
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

/// The protocol version this build speaks.
pub const PROTOCOL_VERSION: u16 = 3;

/// Message kinds (the second payload byte).
pub mod kind {
    pub const HELLO: u8 = 0x01;
    pub const BATCH: u8 = 0x02;
    pub const CAPTURE: u8 = 0x03;
    pub const RESEND: u8 = 0x04;
    pub const BATCH_CAPTURE: u8 = 0x05;
    pub const HELLO_REPLY: u8 = 0x81;
    pub const BATCH_REPLY: u8 = 0x82;
    pub const CAPTURE_REPLY: u8 = 0x83;
    pub const FRAGMENT: u8 = 0x84;
    pub const BATCH_CAPTURE_REPLY: u8 = 0x85;
    pub const ERROR: u8 = 0xFF;
}

/// Error codes a bridge reports in an [`Response::Error`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BridgeErrorCode {
    /// 1: a frame arrived with a bad CRC or COBS (its seq is unknown: 0).
    BadFrame,
    /// 2: unknown message kind or op code.
    UnknownOp,
    /// 3: a request longer than the bridge can hold, or too many ops.
    Overflow,
    /// 4: the capture buffer filled; pulses or pin changes were lost.
    CaptureOverrun,
    /// 5: a message whose fields do not fit its kind.
    Malformed,
    /// 6: the host speaks another protocol version.
    Version,
    /// Any other code, kept as received.
    Unknown(u8),
}

impl BridgeErrorCode {
    pub fn code(self) -> u8 {
        match self {
            BridgeErrorCode::BadFrame => 1,
            BridgeErrorCode::UnknownOp => 2,
            BridgeErrorCode::Overflow => 3,
            BridgeErrorCode::CaptureOverrun => 4,
            BridgeErrorCode::Malformed => 5,
            BridgeErrorCode::Version => 6,
            BridgeErrorCode::Unknown(c) => c,
        }
    }

    pub fn from_code(c: u8) -> Self {
        match c {
            1 => BridgeErrorCode::BadFrame,
            2 => BridgeErrorCode::UnknownOp,
            3 => BridgeErrorCode::Overflow,
            4 => BridgeErrorCode::CaptureOverrun,
            5 => BridgeErrorCode::Malformed,
            6 => BridgeErrorCode::Version,
            other => BridgeErrorCode::Unknown(other),
        }
    }
}

/// What the bridge says about itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hello {
    pub version: u16,
    /// Changes every time the bridge starts: a different session after a
    /// reconnect means the bridge (and the chip's state) were reset.
    pub session: u32,
    /// Rate of the bridge's timer; every time on the wire is in its ticks.
    pub timer_hz: u64,
    /// Most ops one batch may hold.
    pub max_batch_ops: u16,
    /// Largest frame payload the bridge accepts.
    pub max_payload: u16,
    /// Pulse runs and pin changes the capture buffer holds.
    pub capture_capacity: u32,
    /// One bit per [`Input`] (bit = `Input::index`) that is wired.
    pub inputs_wired: u16,
    /// The bridge runs in virtual time (a simulator answering at once),
    /// so the host must not expect replies to take as long as their waits.
    pub virtual_time: bool,
    /// Firmware name and version.
    pub firmware: String,
    /// How the chip is strapped on its board.
    pub straps: Straps,
}

/// A host request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    Hello {
        version: u16,
    },
    /// Ops run back to back on the bridge; durations in ticks.
    Batch(Vec<Op>),
    /// Capture records from these positions on, at most `max` of each kind.
    Capture {
        runs: u32,
        pins: u32,
        moves: u32,
        max: u16,
    },
    /// Send these fragments of the reply to this same sequence number again.
    Resend {
        fragments: Vec<u8>,
    },
    /// A batch, then the capture from these positions on: one round trip
    /// where a host needs both.
    BatchCapture {
        ops: Vec<Op>,
        runs: u32,
        pins: u32,
        moves: u32,
        max: u16,
    },
}

/// Largest response payload sent as one frame; longer ones go as
/// fragments of this many bytes, so that a noisy link loses little.
pub const FRAGMENT_DATA: usize = 48;

/// The longest response payload: 255 fragments.
pub const MAX_REPLY: usize = 255 * FRAGMENT_DATA;

/// Splits a response payload into frame payloads: itself if short, else
/// `seq, FRAGMENT, index, count, data`. A payload over [`MAX_REPLY`] loses
/// its tail; the bridge never sends one (it answers OVERFLOW instead).
pub fn fragment(payload: &[u8]) -> Vec<Vec<u8>> {
    if payload.len() <= FRAGMENT_DATA {
        return vec![payload.to_vec()];
    }
    let seq = payload.first().copied().unwrap_or(0);
    let chunks: Vec<&[u8]> = payload.chunks(FRAGMENT_DATA).collect();
    let count = chunks.len().min(255) as u8;
    chunks
        .iter()
        .take(255)
        .enumerate()
        .map(|(i, c)| {
            let mut f = vec![seq, kind::FRAGMENT, i as u8, count];
            f.extend_from_slice(c);
            f
        })
        .collect()
}

/// A fragment frame: `(seq, index, count, data)`, or `None` if the payload
/// is not one.
pub fn parse_fragment(payload: &[u8]) -> Option<(u8, u8, u8, &[u8])> {
    match payload {
        [seq, k, i, n, data @ ..] if *k == kind::FRAGMENT && *n > 0 && i < n => {
            Some((*seq, *i, *n, data))
        }
        _ => None,
    }
}

/// A chunk of the capture.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CaptureChunk {
    pub runs: Vec<PulseRun>,
    pub pins: Vec<PinEvent>,
    pub moves: Vec<MoveStart>,
    pub overwritten_bytes: u64,
    /// More records follow (ask again from the new positions).
    pub more: bool,
}

/// A bridge response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Response {
    Hello(Hello),
    Batch(Vec<Reply>),
    Capture(CaptureChunk),
    /// The replies to a BATCH_CAPTURE's ops, then the capture chunk.
    BatchCapture {
        replies: Vec<Reply>,
        capture: CaptureChunk,
    },
    Error {
        code: BridgeErrorCode,
        detail: String,
    },
}

/// Why a message does not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    #[error("message ends early (wanted {wanted} more bytes at offset {at})")]
    Truncated { at: usize, wanted: usize },
    #[error("unknown message kind 0x{0:02X}")]
    UnknownKind(u8),
    #[error("unknown op or reply code 0x{code:02X} at offset {at}")]
    UnknownCode { at: usize, code: u8 },
    #[error("bad value {value} for {field} at offset {at}")]
    BadValue {
        at: usize,
        field: &'static str,
        value: u64,
    },
    #[error("{0} bytes left over at the end of the message")]
    Trailing(usize),
}

// ----- little-endian writer and checked reader -----------------------------

/// Converts between nanoseconds and ticks of a timer running at `hz`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timer {
    pub hz: u64,
}

impl Timer {
    /// The simulator's timer: one tick per nanosecond.
    pub const NANOS: Timer = Timer { hz: 1_000_000_000 };

    /// Nanoseconds to ticks, to the nearest tick: so that ticks turned into
    /// nanoseconds ([`Timer::to_nanos`], which truncates) and back are the
    /// same ticks for any timer up to 500 MHz.
    pub fn to_ticks(self, ns: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ns;
        }
        let t = (u128::from(ns) * u128::from(self.hz) + 500_000_000) / 1_000_000_000;
        u64::try_from(t).unwrap_or(u64::MAX)
    }

    pub fn to_nanos(self, ticks: u64) -> u64 {
        if self.hz == Self::NANOS.hz {
            return ticks;
        }
        if self.hz == 0 {
            return u64::MAX;
        }
        let n = u128::from(ticks) * 1_000_000_000 / u128::from(self.hz);
        u64::try_from(n).unwrap_or(u64::MAX)
    }
}

#[derive(Debug)]
struct W(Vec<u8>, Timer);

impl W {
    fn dur(&mut self, d: Duration) {
        let t = self.1.to_ticks(d.as_nanos());
        self.u64(t);
    }
    fn time(&mut self, i: Instant) {
        let t = self.1.to_ticks(i.as_nanos());
        self.u64(t);
    }
    fn opt_dur(&mut self, d: Option<Duration>) {
        let v = d.map(|d| self.1.to_ticks(d.as_nanos()));
        self.opt(v);
    }
    fn opt_time(&mut self, i: Option<Instant>) {
        let v = i.map(|i| self.1.to_ticks(i.as_nanos()));
        self.opt(v);
    }
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u16(&mut self, v: u16) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn opt(&mut self, v: Option<u64>) {
        match v {
            Some(x) => {
                self.u8(1);
                self.u64(x);
            }
            None => self.u8(0),
        }
    }
    fn str(&mut self, s: &str) {
        let b = s.as_bytes();
        let n = b.len().min(255);
        self.u8(n as u8);
        self.0.extend_from_slice(&b[..n]);
    }
}

struct R<'a> {
    b: &'a [u8],
    at: usize,
    timer: Timer,
}

impl<'a> R<'a> {
    fn new(b: &'a [u8], timer: Timer) -> Self {
        R { b, at: 0, timer }
    }
    fn dur(&mut self) -> Result<Duration, WireError> {
        let t = self.u64()?;
        Ok(Duration::from_nanos(self.timer.to_nanos(t)))
    }
    fn time(&mut self) -> Result<Instant, WireError> {
        let t = self.u64()?;
        Ok(Instant::from_nanos(self.timer.to_nanos(t)))
    }
    fn opt_dur(&mut self) -> Result<Option<Duration>, WireError> {
        let t = self.timer;
        Ok(self.opt()?.map(|v| Duration::from_nanos(t.to_nanos(v))))
    }
    fn opt_time(&mut self) -> Result<Option<Instant>, WireError> {
        let t = self.timer;
        Ok(self.opt()?.map(|v| Instant::from_nanos(t.to_nanos(v))))
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        if self.b.len() - self.at < n {
            return Err(WireError::Truncated {
                at: self.at,
                wanted: n - (self.b.len() - self.at),
            });
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, WireError> {
        Ok(self.take(1)?[0])
    }
    fn u16(&mut self) -> Result<u16, WireError> {
        let s = self.take(2)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self) -> Result<u32, WireError> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn u64(&mut self) -> Result<u64, WireError> {
        let s = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(u64::from_le_bytes(a))
    }
    fn bool(&mut self, field: &'static str) -> Result<bool, WireError> {
        let at = self.at;
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(WireError::BadValue {
                at,
                field,
                value: u64::from(v),
            }),
        }
    }
    fn opt(&mut self) -> Result<Option<u64>, WireError> {
        Ok(if self.bool("option flag")? {
            Some(self.u64()?)
        } else {
            None
        })
    }
    fn str(&mut self) -> Result<String, WireError> {
        let n = usize::from(self.u8()?);
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    fn peek(&self) -> Option<u8> {
        self.b.get(self.at).copied()
    }
    /// A sample count: 2..=MAX_SAMPLES.
    fn samples(&mut self) -> Result<usize, WireError> {
        let at = self.at;
        let n = usize::from(self.u16()?);
        if !(2..=MAX_SAMPLES).contains(&n) {
            return Err(WireError::BadValue {
                at,
                field: "sample count",
                value: n as u64,
            });
        }
        Ok(n)
    }
    fn count(&mut self, max_item: usize) -> Result<usize, WireError> {
        let at = self.at;
        let n = usize::from(self.u16()?);
        // A count cannot promise more items than bytes left.
        if n.saturating_mul(max_item.max(1)) > (self.b.len() - self.at).saturating_mul(64) {
            return Err(WireError::BadValue {
                at,
                field: "count",
                value: n as u64,
            });
        }
        Ok(n)
    }
    fn end(&self) -> Result<(), WireError> {
        match self.b.len() - self.at {
            0 => Ok(()),
            n => Err(WireError::Trailing(n)),
        }
    }
    fn dir(&mut self) -> Result<Direction, WireError> {
        Ok(Direction::from_bit(self.bool("direction")?))
    }
    fn input(&mut self) -> Result<Input, WireError> {
        let at = self.at;
        let i = self.u8()?;
        Input::ALL
            .get(usize::from(i))
            .copied()
            .ok_or(WireError::BadValue {
                at,
                field: "input",
                value: u64::from(i),
            })
    }
}

/// Strap flags in HELLO_REPLY.
mod strap_flag {
    pub const CSEL_HIGH: u8 = 0x01;
    pub const VSEL_HIGH: u8 = 0x02;
    pub const EXT_CLOCK: u8 = 0x04;
}

fn put_straps(w: &mut W, s: &Straps) {
    w.u32(s.sysclk_hz);
    let mut flags = 0;
    if s.csel_high {
        flags |= strap_flag::CSEL_HIGH;
    }
    if s.vsel_high {
        flags |= strap_flag::VSEL_HIGH;
    }
    if s.ext_clock_hz.is_some() {
        flags |= strap_flag::EXT_CLOCK;
    }
    w.u8(flags);
    w.u32(s.ext_clock_hz.unwrap_or(0));
}

fn get_straps(r: &mut R) -> Result<Straps, WireError> {
    let sysclk_hz = r.u32()?;
    let at = r.at;
    let flags = r.u8()?;
    let all = strap_flag::CSEL_HIGH | strap_flag::VSEL_HIGH | strap_flag::EXT_CLOCK;
    if flags & !all != 0 {
        return Err(WireError::BadValue {
            at,
            field: "strap flags",
            value: u64::from(flags),
        });
    }
    let at = r.at;
    let ext = r.u32()?;
    let fitted = flags & strap_flag::EXT_CLOCK != 0;
    if fitted != (ext != 0) {
        return Err(WireError::BadValue {
            at,
            field: "external clock (0 exactly when not fitted)",
            value: u64::from(ext),
        });
    }
    Ok(Straps {
        sysclk_hz,
        csel_high: flags & strap_flag::CSEL_HIGH != 0,
        vsel_high: flags & strap_flag::VSEL_HIGH != 0,
        ext_clock_hz: fitted.then_some(ext),
    })
}

fn pin_code(p: Pin) -> u8 {
    Pin::ALL.iter().position(|x| *x == p).unwrap_or(0) as u8
}

fn winding_code(w: Option<Winding>) -> u8 {
    w.and_then(|w| Winding::ALL.iter().position(|x| *x == w))
        .map_or(0, |i| i as u8 + 1)
}

fn winding_from(c: u8) -> Option<Winding> {
    Winding::ALL.get(usize::from(c).checked_sub(1)?).copied()
}

/// Op codes inside a batch.
mod op {
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
mod rep {
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

/// Most pin samples one SAMPLE op (or one SAMPLES reply entry) stands for.
pub const MAX_SAMPLES: usize = 512;

/// The largest reply entry of a plain op on the wire (PULSES).
pub const MAX_REPLY_ENTRY: usize = 69;

/// Most ops one batch may carry: the largest reply (128 x
/// [`MAX_REPLY_ENTRY`] bytes) then stays within 255 fragments. A bridge
/// may announce fewer in HELLO_REPLY, never more.
pub const MAX_BATCH_OPS: u16 = 128;

/// A SAMPLES entry without its runs: code, time, step, samples, runs.
const SAMPLES_HEAD: usize = 1 + 8 + 8 + 2 + 2;

/// One SAMPLES run: count, then the pins.
const SAMPLES_RUN: usize = 2 + 4;

/// The number of `(ReadPins, Delay(step))` pairs, all with the same step,
/// that `ops` starts with, at most [`MAX_SAMPLES`].
fn sample_pairs(ops: &[Op]) -> usize {
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
fn worst_reply_entry(o: &Op) -> usize {
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

fn put_wire_op(w: &mut W, group: &[Op]) {
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
fn put_ops(w: &mut W, ops: &[Op]) {
    let groups = wire_ops(ops);
    w.u16(groups.len() as u16);
    let mut rest = ops;
    for n in groups {
        let (group, tail) = rest.split_at(n);
        put_wire_op(w, group);
        rest = tail;
    }
}

fn get_ops(r: &mut R) -> Result<Vec<Op>, WireError> {
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
fn sample_replies(replies: &[Reply], timer: Timer) -> Option<(usize, u64, u64)> {
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
fn put_replies(w: &mut W, replies: &[Reply]) {
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
fn put_samples(w: &mut W, pairs: &[Reply], t0: u64, step: u64) {
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

fn get_replies(r: &mut R) -> Result<Vec<Reply>, WireError> {
    let n = r.count(9)?;
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

fn get_samples(r: &mut R, out: &mut Vec<Reply>) -> Result<(), WireError> {
    r.u8()?;
    let (t0, step) = (r.u64()?, r.u64()?);
    let at = r.at;
    let samples = r.samples()?;
    let runs = r.count(SAMPLES_RUN)?;
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
        let n = r.u16()?;
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

fn put_pins(w: &mut W, pins: &Pins) {
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

fn get_pins(r: &mut R) -> Result<Pins, WireError> {
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

/// Where a capture fetch starts, and its chunk size (CAPTURE,
/// BATCH_CAPTURE).
fn put_capture_from(w: &mut W, runs: u32, pins: u32, moves: u32, max: u16) {
    w.u32(runs);
    w.u32(pins);
    w.u32(moves);
    w.u16(max);
}

fn put_op(w: &mut W, o: &Op) {
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

fn get_op(r: &mut R) -> Result<Op, WireError> {
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

fn put_reply(w: &mut W, rp: &Reply) {
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

fn get_reply(r: &mut R) -> Result<Reply, WireError> {
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

fn move_kind_code(k: MoveKind) -> u8 {
    k.code()
}

fn move_kind_from(at: usize, c: u8) -> Result<MoveKind, WireError> {
    MoveKind::ALL
        .into_iter()
        .find(|k| k.code() == c)
        .ok_or(WireError::BadValue {
            at,
            field: "move kind",
            value: u64::from(c),
        })
}

fn put_capture(w: &mut W, c: &CaptureChunk) {
    w.u16(c.runs.len() as u16);
    for run in &c.runs {
        w.u64(run.start.as_nanos());
        w.dur(run.interval);
        w.u32(run.count);
        w.u8(u8::from(run.dir.bit()));
    }
    w.u16(c.pins.len() as u16);
    for p in &c.pins {
        w.time(p.at);
        w.u8(pin_code(p.pin));
        w.u8(p.value);
    }
    w.u16(c.moves.len() as u16);
    for m in &c.moves {
        w.time(m.at);
        w.u8(move_kind_code(m.kind));
        w.u8(u8::from(m.dir.bit()));
        w.u8(u8::from(m.pout));
        w.u32(m.steps);
        w.u8(winding_code(m.winding));
        w.u32(m.phase_index);
        w.u32(m.first_run as u32);
    }
    w.u64(c.overwritten_bytes);
    w.u8(u8::from(c.more));
}

fn get_capture(r: &mut R) -> Result<CaptureChunk, WireError> {
    let mut c = CaptureChunk::default();
    let n = r.count(21)?;
    for _ in 0..n {
        let start = r.time()?;
        let interval = r.dur()?;
        let count = r.u32()?;
        let dir = r.dir()?;
        c.runs.push(PulseRun {
            start,
            interval,
            count,
            dir,
        });
    }
    let n = r.count(10)?;
    for _ in 0..n {
        let at = r.time()?;
        let pat = r.at;
        let code = r.u8()?;
        let pin = *Pin::ALL.get(usize::from(code)).ok_or(WireError::BadValue {
            at: pat,
            field: "pin",
            value: u64::from(code),
        })?;
        c.pins.push(PinEvent {
            at,
            pin,
            value: r.u8()?,
        });
    }
    let n = r.count(24)?;
    for _ in 0..n {
        let at = r.time()?;
        let kat = r.at;
        let kind = move_kind_from(kat, r.u8()?)?;
        let dir = r.dir()?;
        let pout = r.bool("pout")?;
        let steps = r.u32()?;
        let wat = r.at;
        let wc = r.u8()?;
        let winding = winding_from(wc);
        if wc != 0 && winding.is_none() {
            return Err(WireError::BadValue {
                at: wat,
                field: "winding",
                value: u64::from(wc),
            });
        }
        let phase_index = r.u32()?;
        let first_run = r.u32()? as usize;
        c.moves.push(MoveStart {
            at,
            kind,
            dir,
            pout,
            steps,
            first_run,
            phase_index,
            winding,
        });
    }
    c.overwritten_bytes = r.u64()?;
    c.more = r.bool("more")?;
    Ok(c)
}

impl Request {
    /// The frame payload for this request with sequence number `seq`,
    /// times in ticks of `timer`.
    pub fn encode(&self, seq: u8, timer: Timer) -> Vec<u8> {
        let mut w = W(Vec::new(), timer);
        w.u8(seq);
        match self {
            Request::Hello { version } => {
                w.u8(kind::HELLO);
                w.u16(*version);
            }
            Request::Batch(ops) => {
                w.u8(kind::BATCH);
                put_ops(&mut w, ops);
            }
            Request::Capture {
                runs,
                pins,
                moves,
                max,
            } => {
                w.u8(kind::CAPTURE);
                put_capture_from(&mut w, *runs, *pins, *moves, *max);
            }
            Request::BatchCapture {
                ops,
                runs,
                pins,
                moves,
                max,
            } => {
                w.u8(kind::BATCH_CAPTURE);
                put_ops(&mut w, ops);
                put_capture_from(&mut w, *runs, *pins, *moves, *max);
            }
            Request::Resend { fragments } => {
                w.u8(kind::RESEND);
                w.u8(fragments.len().min(255) as u8);
                for f in fragments.iter().take(255) {
                    w.u8(*f);
                }
            }
        }
        w.0
    }

    /// `(seq, request)` from a frame payload, times in ticks of `timer`.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Request), WireError> {
        let mut r = R::new(payload, timer);
        let seq = r.u8()?;
        let req = match r.u8()? {
            kind::HELLO => Request::Hello { version: r.u16()? },
            kind::BATCH => Request::Batch(get_ops(&mut r)?),
            kind::CAPTURE => Request::Capture {
                runs: r.u32()?,
                pins: r.u32()?,
                moves: r.u32()?,
                max: r.u16()?,
            },
            kind::BATCH_CAPTURE => {
                let ops = get_ops(&mut r)?;
                Request::BatchCapture {
                    ops,
                    runs: r.u32()?,
                    pins: r.u32()?,
                    moves: r.u32()?,
                    max: r.u16()?,
                }
            }
            kind::RESEND => {
                let n = usize::from(r.u8()?);
                Request::Resend {
                    fragments: r.take(n)?.to_vec(),
                }
            }
            k => return Err(WireError::UnknownKind(k)),
        };
        r.end()?;
        Ok((seq, req))
    }
}

impl Response {
    /// The frame payload for this response to request `seq`, times in
    /// ticks of `timer`.
    pub fn encode(&self, seq: u8, timer: Timer) -> Vec<u8> {
        let mut w = W(Vec::new(), timer);
        w.u8(seq);
        match self {
            Response::Hello(h) => {
                w.u8(kind::HELLO_REPLY);
                w.u16(h.version);
                w.u32(h.session);
                w.u64(h.timer_hz);
                w.u16(h.max_batch_ops);
                w.u16(h.max_payload);
                w.u32(h.capture_capacity);
                w.u16(h.inputs_wired);
                w.u8(u8::from(h.virtual_time));
                w.str(&h.firmware);
                put_straps(&mut w, &h.straps);
            }
            Response::Batch(replies) => {
                w.u8(kind::BATCH_REPLY);
                put_replies(&mut w, replies);
            }
            Response::Capture(c) => {
                w.u8(kind::CAPTURE_REPLY);
                put_capture(&mut w, c);
            }
            Response::BatchCapture { replies, capture } => {
                w.u8(kind::BATCH_CAPTURE_REPLY);
                put_replies(&mut w, replies);
                put_capture(&mut w, capture);
            }
            Response::Error { code, detail } => {
                w.u8(kind::ERROR);
                w.u8(code.code());
                w.str(detail);
            }
        }
        w.0
    }

    /// `(seq, response)` from a frame payload, times in ticks of `timer`.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Response), WireError> {
        let mut r = R::new(payload, timer);
        let seq = r.u8()?;
        let resp = match r.u8()? {
            kind::HELLO_REPLY => Response::Hello(Hello {
                version: r.u16()?,
                session: r.u32()?,
                timer_hz: r.u64()?,
                max_batch_ops: r.u16()?,
                max_payload: r.u16()?,
                capture_capacity: r.u32()?,
                inputs_wired: r.u16()?,
                virtual_time: r.bool("virtual time flag")?,
                firmware: r.str()?,
                straps: get_straps(&mut r)?,
            }),
            kind::BATCH_REPLY => Response::Batch(get_replies(&mut r)?),
            kind::CAPTURE_REPLY => Response::Capture(get_capture(&mut r)?),
            kind::BATCH_CAPTURE_REPLY => {
                let replies = get_replies(&mut r)?;
                Response::BatchCapture {
                    replies,
                    capture: get_capture(&mut r)?,
                }
            }
            kind::ERROR => Response::Error {
                code: BridgeErrorCode::from_code(r.u8()?),
                detail: r.str()?,
            },
            k => return Err(WireError::UnknownKind(k)),
        };
        r.end()?;
        Ok((seq, resp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const T: Timer = Timer::NANOS;

    #[test]
    fn ticks_survive_the_trip_through_nanoseconds() {
        for hz in [
            1_000_000,
            16_000_000,
            48_000_000,
            72_000_000,
            84_000_000,
            168_000_000,
            480_000_000,
        ] {
            let t = Timer { hz };
            for k in (0..2_000).chain([u64::from(u32::MAX), 1 << 40]) {
                assert_eq!(t.to_ticks(t.to_nanos(k)), k, "{hz} Hz, {k} ticks");
            }
        }
    }

    #[test]
    fn a_16mhz_timer_converts_both_ways() {
        let t = Timer { hz: 16_000_000 };
        let ops = Request::Batch(vec![Op::Delay(Duration::from_micros(250))]);
        let bytes = ops.encode(1, t);
        // 250 us = 4,000 ticks of 62.5 ns.
        assert_eq!(&bytes[5..13], &4_000u64.to_le_bytes());
        assert_eq!(Request::decode(&bytes, t), Ok((1, ops)));
    }

    fn sample_ops() -> Vec<Op> {
        vec![
            Op::WriteCommand {
                byte: 0x43,
                wait_ibf: Some(Duration::from_secs(1)),
            },
            Op::WriteData {
                byte: 0xE7,
                wait_ibf: None,
            },
            Op::ReadStatus,
            Op::ReadData {
                wait_obf: Some(Duration::from_millis(100)),
            },
            Op::Delay(Duration::from_micros(250)),
            Op::AwaitStatus {
                mask: 4,
                value: 0,
                timeout: Duration::from_secs(2),
            },
            Op::SetInput {
                input: Input::Auxi3,
                asserted: true,
            },
            Op::ReadPins,
            Op::ReadPulses,
            Op::AwaitPulses {
                count: 500,
                timeout: Duration::from_secs(60),
            },
            Op::Reset,
        ]
    }

    #[test]
    fn every_op_round_trips() {
        let req = Request::Batch(sample_ops());
        assert_eq!(Request::decode(&req.encode(7, T), T), Ok((7, req)));
        let h = Request::Hello {
            version: PROTOCOL_VERSION,
        };
        assert_eq!(Request::decode(&h.encode(0, T), T), Ok((0, h)));
    }

    #[test]
    fn every_reply_round_trips() {
        let at = Instant::from_nanos(123_456);
        let pins = Pins {
            int: true,
            hold: false,
            aux: true,
            auxo: 0b1010,
            phases: 0b11000,
            phase_levels: 0b00111,
            dir: Direction::Ccw,
            busy: true,
        };
        let replies = vec![
            Reply::Written {
                at,
                waited: Duration::from_micros(6),
            },
            Reply::WriteTimedOut {
                at,
                status: Status(0x06),
            },
            Reply::Status {
                at,
                status: Status(0x84),
            },
            Reply::Data {
                at,
                byte: 0x83,
                waited: Duration::from_micros(20),
            },
            Reply::ReadTimedOut {
                at,
                status: Status(0),
            },
            Reply::Delayed { at },
            Reply::Awaited {
                at,
                waited: Duration::from_micros(60),
                status: Status(4),
            },
            Reply::AwaitTimedOut {
                at,
                status: Status(4),
            },
            Reply::InputSet { at },
            Reply::Pins { at, pins },
            Reply::Pulses {
                at,
                summary: PulseSummary {
                    count: 10,
                    cw: 10,
                    ccw: 0,
                    first: Some(at),
                    last: None,
                    min_interval: Some(Duration::from_micros(42)),
                    max_interval: None,
                },
            },
            Reply::PulsesReached { at },
            Reply::PulsesTimedOut { at, count: 3 },
            Reply::ResetDone { at },
        ];
        // Each reply fits the worst case of the op it answers.
        let ops = sample_ops();
        let answers = |r: &Reply| -> Vec<&Op> {
            ops.iter()
                .filter(|o| {
                    matches!(
                        (o, r),
                        (
                            Op::WriteCommand { .. } | Op::WriteData { .. },
                            Reply::Written { .. } | Reply::WriteTimedOut { .. }
                        ) | (Op::ReadStatus, Reply::Status { .. })
                            | (
                                Op::ReadData { .. },
                                Reply::Data { .. } | Reply::ReadTimedOut { .. }
                            )
                            | (Op::Delay(_), Reply::Delayed { .. })
                            | (
                                Op::AwaitStatus { .. },
                                Reply::Awaited { .. } | Reply::AwaitTimedOut { .. }
                            )
                            | (Op::SetInput { .. }, Reply::InputSet { .. })
                            | (Op::ReadPins, Reply::Pins { .. })
                            | (Op::ReadPulses, Reply::Pulses { .. })
                            | (
                                Op::AwaitPulses { .. },
                                Reply::PulsesReached { .. } | Reply::PulsesTimedOut { .. }
                            )
                            | (Op::Reset, Reply::ResetDone { .. })
                    )
                })
                .collect()
        };
        for r in &replies {
            let mut w = W(Vec::new(), T);
            put_reply(&mut w, r);
            let ops = answers(r);
            assert!(!ops.is_empty(), "{r:?}");
            for o in ops {
                assert!(
                    w.0.len() <= worst_reply_len(core::slice::from_ref(o)),
                    "{r:?}"
                );
            }
        }
        let resp = Response::Batch(replies);
        assert_eq!(Response::decode(&resp.encode(9, T), T), Ok((9, resp)));
    }

    #[test]
    fn hello_capture_and_error_round_trip() {
        let hello = Response::Hello(Hello {
            version: 1,
            session: 0xDEAD_BEEF,
            timer_hz: 1_000_000_000,
            max_batch_ops: 256,
            max_payload: 4096,
            capture_capacity: 65_536,
            inputs_wired: 0x3FF,
            virtual_time: true,
            firmware: "ppmc-bridge-sim 0.1.0".into(),
            straps: Straps {
                sysclk_hz: 12_288_000,
                csel_high: false,
                vsel_high: true,
                ext_clock_hz: Some(500_000),
            },
        });
        assert_eq!(Response::decode(&hello.encode(1, T), T), Ok((1, hello)));
        let cap = Response::Capture(CaptureChunk {
            runs: vec![PulseRun {
                start: Instant::from_nanos(5),
                interval: Duration::from_nanos(42_000),
                count: 1_000,
                dir: Direction::Cw,
            }],
            pins: vec![PinEvent {
                at: Instant::from_nanos(9),
                pin: Pin::Switching,
                value: 1,
            }],
            moves: vec![MoveStart {
                at: Instant::from_nanos(1),
                kind: MoveKind::OriginSearch,
                dir: Direction::Ccw,
                pout: false,
                steps: 1 << 24,
                first_run: 3,
                phase_index: 7,
                winding: Winding::from_name("5ph-23"),
            }],
            overwritten_bytes: 2,
            more: true,
        });
        assert_eq!(Response::decode(&cap.encode(2, T), T), Ok((2, cap)));
        let err = Response::Error {
            code: BridgeErrorCode::CaptureOverrun,
            detail: "full".into(),
        };
        assert_eq!(Response::decode(&err.encode(3, T), T), Ok((3, err)));
    }

    #[test]
    fn long_replies_fragment_and_reassemble() {
        let payload: Vec<u8> = (0..130u16).map(|i| i as u8).collect();
        let frags = fragment(&payload);
        assert_eq!(frags.len(), 3);
        let mut whole = Vec::new();
        for (i, f) in frags.iter().enumerate() {
            let (seq, idx, n, data) = parse_fragment(f).expect("a fragment");
            assert_eq!((seq, usize::from(idx), n), (0, i, 3));
            whole.extend_from_slice(data);
        }
        assert_eq!(whole, payload);
        assert_eq!(fragment(&[5, 1, 2]), vec![vec![5, 1, 2]]);
        let r = Request::Resend {
            fragments: vec![0, 2],
        };
        assert_eq!(Request::decode(&r.encode(4, T), T), Ok((4, r)));
        let c = Request::Capture {
            runs: 1,
            pins: 2,
            moves: 3,
            max: 40,
        };
        assert_eq!(Request::decode(&c.encode(5, T), T), Ok((5, c)));
        let bc = Request::BatchCapture {
            ops: sample_ops(),
            runs: 4,
            pins: 5,
            moves: 6,
            max: 60,
        };
        assert_eq!(Request::decode(&bc.encode(6, T), T), Ok((6, bc)));
        let reply = Response::BatchCapture {
            replies: vec![Reply::Delayed {
                at: Instant::from_nanos(77),
            }],
            capture: CaptureChunk {
                runs: vec![],
                pins: vec![PinEvent {
                    at: Instant::from_nanos(9),
                    pin: Pin::Busy,
                    value: 1,
                }],
                moves: vec![],
                overwritten_bytes: 0,
                more: false,
            },
        };
        assert_eq!(Response::decode(&reply.encode(6, T), T), Ok((6, reply)));
    }

    #[test]
    fn bad_messages_say_where() {
        assert_eq!(
            Request::decode(&[1], T),
            Err(WireError::Truncated { at: 1, wanted: 1 })
        );
        assert_eq!(
            Request::decode(&[1, 0x77], T),
            Err(WireError::UnknownKind(0x77))
        );
        assert_eq!(
            Request::decode(&[1, kind::BATCH, 1, 0, 0x99], T),
            Err(WireError::UnknownCode { at: 4, code: 0x99 })
        );
        let mut ok = Request::Hello { version: 1 }.encode(1, T);
        ok.push(0);
        assert_eq!(Request::decode(&ok, T), Err(WireError::Trailing(1)));
        // A count that promises more than the bytes could hold.
        assert!(matches!(
            Response::decode(&[1, kind::BATCH_REPLY, 0xFF, 0xFF], T),
            Err(WireError::BadValue { field: "count", .. })
        ));
    }

    fn pins(phases: u8) -> Pins {
        Pins {
            int: false,
            hold: true,
            aux: false,
            auxo: 0,
            phases,
            phase_levels: !phases & 0x1F,
            dir: Direction::Cw,
            busy: true,
        }
    }

    #[test]
    fn pin_samples_go_as_sample_ops_and_samples_entries() {
        let step = Duration::from_nanos(250);
        let mut ops = vec![Op::Reset];
        for _ in 0..1500 {
            ops.extend([Op::ReadPins, Op::Delay(step)]);
        }
        ops.push(Op::ReadPins);
        // 1,500 samples: two SAMPLEs of the most, one of the rest; the lone
        // read at the end stays a PINS op.
        assert_eq!(
            wire_ops(&ops),
            vec![1, 2 * MAX_SAMPLES, 2 * MAX_SAMPLES, 2 * 476, 1]
        );
        let req = Request::Batch(ops);
        let bytes = req.encode(3, T);
        assert!(bytes.len() < 40, "{} bytes", bytes.len());
        assert_eq!(Request::decode(&bytes, T), Ok((3, req)));

        // Replies on one grid: the phases change every 7 samples.
        let mut replies = vec![Reply::ResetDone {
            at: Instant::from_nanos(10),
        }];
        for i in 0..1500u64 {
            let at = Instant::from_nanos(10 + 250 * i);
            let p = pins(1 << ((i / 7) % 4));
            replies.extend([
                Reply::Pins { at, pins: p },
                Reply::Delayed {
                    at: Instant::from_nanos(10 + 250 * (i + 1)),
                },
            ]);
        }
        let resp = Response::Batch(replies.clone());
        let bytes = resp.encode(3, T);
        // 215 runs of 6 bytes, not 3,000 entries of 9 to 13.
        assert!(bytes.len() < 1_400, "{} bytes", bytes.len());
        assert_eq!(Response::decode(&bytes, T), Ok((3, resp)));

        // Off the grid (a read late by 1 ns), the run stops there and the
        // rest still comes back exact.
        if let Some(Reply::Pins { at, .. }) = replies.get_mut(2 * 700 + 1) {
            *at = Instant::from_nanos(at.as_nanos() + 1);
        }
        let resp = Response::Batch(replies);
        assert_eq!(Response::decode(&resp.encode(4, T), T), Ok((4, resp)));
    }

    #[test]
    fn a_sample_count_out_of_range_is_refused() {
        for n in [0u16, 1, MAX_SAMPLES as u16 + 1] {
            let mut b = vec![1, kind::BATCH, 1, 0, op::SAMPLE];
            b.extend(n.to_le_bytes());
            b.extend(250u64.to_le_bytes());
            assert!(matches!(
                Request::decode(&b, T),
                Err(WireError::BadValue {
                    field: "sample count",
                    ..
                })
            ));
        }
    }

    fn arb_op() -> impl Strategy<Value = Op> {
        prop_oneof![
            Just(Op::ReadPins),
            Just(Op::ReadStatus),
            (0u64..3).prop_map(|d| Op::Delay(Duration::from_nanos(250 * d))),
        ]
    }

    fn arb_reply() -> impl Strategy<Value = Reply> {
        prop_oneof![
            (0u64..4, 0u8..3).prop_map(|(t, p)| Reply::Pins {
                at: Instant::from_nanos(100 * t),
                pins: pins(p),
            }),
            (0u64..4).prop_map(|t| Reply::Delayed {
                at: Instant::from_nanos(100 * t)
            }),
            (0u64..4).prop_map(|t| Reply::Status {
                at: Instant::from_nanos(100 * t),
                status: Status(0),
            }),
        ]
    }

    proptest! {
        #[test]
        fn any_batch_round_trips(ops in prop::collection::vec(arb_op(), 0..400)) {
            let req = Request::Batch(ops);
            prop_assert_eq!(Request::decode(&req.encode(1, T), T), Ok((1, req)));
        }

        #[test]
        fn any_reply_list_round_trips(
            mut replies in prop::collection::vec(arb_reply(), 0..400),
            grid in 0usize..200,
        ) {
            // Lay a stretch on a grid, so that SAMPLES entries occur.
            for (j, r) in replies.iter_mut().skip(grid).take(150).enumerate() {
                let k = (j / 2) as u64;
                *r = if j % 2 == 0 {
                    Reply::Pins {
                        at: Instant::from_nanos(1_000 + 100 * k),
                        pins: pins((j / 10) as u8 % 3),
                    }
                } else {
                    Reply::Delayed { at: Instant::from_nanos(1_000 + 100 * (k + 1)) }
                };
            }
            let resp = Response::Batch(replies);
            prop_assert_eq!(Response::decode(&resp.encode(1, T), T), Ok((1, resp)));
        }
    }

    proptest! {
        #[test]
        fn arbitrary_payloads_never_panic(b in prop::collection::vec(any::<u8>(), 0..300)) {
            let _ = Request::decode(&b, T);
            let _ = Response::decode(&b, T);
        }
    }
}
