//! Bridge messages: typed requests and responses, and their bytes.
//!
//! A frame payload is `seq:u8, kind:u8, body`. All integers are little
//! endian. Times and durations on the wire are ticks of the bridge's timer,
//! whose rate the bridge announces in its hello reply; the host converts.
//! [`Request::decode`] and [`Response::decode`] check every length and
//! value and never panic; `docs/bridge-protocol.md` is the specification.

use crate::bus::{Op, Reply, SelfTestPlan, SelfTestReply};
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
pub const PROTOCOL_VERSION: u16 = 7;

/// Message kinds (the second payload byte).
pub mod kind {
    pub const HELLO: u8 = 0x01;
    pub const BATCH: u8 = 0x02;
    pub const CAPTURE: u8 = 0x03;
    pub const RESEND: u8 = 0x04;
    pub const BATCH_CAPTURE: u8 = 0x05;
    pub const LINK: u8 = 0x06;
    pub const SELF_TEST: u8 = 0x07;
    pub const HELLO_REPLY: u8 = 0x81;
    pub const BATCH_REPLY: u8 = 0x82;
    pub const CAPTURE_REPLY: u8 = 0x83;
    pub const FRAGMENT: u8 = 0x84;
    pub const BATCH_CAPTURE_REPLY: u8 = 0x85;
    pub const LINK_REPLY: u8 = 0x86;
    pub const SELF_TEST_REPLY: u8 = 0x87;
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
    /// 7: the bridge's own hardware failed (a stuck state machine); the
    /// detail says what. The bridge must be reset.
    Hardware,
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
            BridgeErrorCode::Hardware => 7,
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
            7 => BridgeErrorCode::Hardware,
            other => BridgeErrorCode::Unknown(other),
        }
    }
}

impl core::fmt::Display for BridgeErrorCode {
    /// The name the protocol document gives the code: `BAD_FRAME`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BridgeErrorCode::BadFrame => f.write_str("BAD_FRAME"),
            BridgeErrorCode::UnknownOp => f.write_str("UNKNOWN_OP"),
            BridgeErrorCode::Overflow => f.write_str("OVERFLOW"),
            BridgeErrorCode::CaptureOverrun => f.write_str("CAPTURE_OVERRUN"),
            BridgeErrorCode::Malformed => f.write_str("MALFORMED"),
            BridgeErrorCode::Version => f.write_str("VERSION"),
            BridgeErrorCode::Hardware => f.write_str("HARDWARE"),
            BridgeErrorCode::Unknown(c) => write!(f, "error code {c}"),
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
    /// The bridge kept this host's dedupe state across the HELLO: the host
    /// said HELLO with the same host session before, and no other host has
    /// used the bridge since, so a request the host sends again is answered
    /// from the cache, not run twice (`docs/bridge-protocol.md` section 3).
    pub resumed: bool,
}

/// A host request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    Hello {
        version: u16,
        /// The host's session: a number the host picks each time it opens
        /// the link (never 0), kept across its reconnects. A HELLO with
        /// another one makes the bridge forget the last host's requests.
        host: u32,
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
    Resend { fragments: Vec<u8> },
    /// A batch, then the capture from these positions on: one round trip
    /// where a host needs both.
    BatchCapture {
        ops: Vec<Op>,
        runs: u32,
        pins: u32,
        moves: u32,
        max: u16,
    },
    /// From the next response on, send fragments of at most this many
    /// data bytes ([`MIN_FRAGMENT_DATA`]..=[`FRAGMENT_DATA`]): smaller
    /// frames for a noisier line; and end every reply with 0x00 bytes up
    /// to a multiple of `pad` bytes (0: no padding; at most [`MAX_PAD`]),
    /// so that a serial server in between that holds a partial buffer
    /// (ser2net's `chardelay`) sends each reply at once.
    Link { fragment: u8, pad: u16 },
    /// The bridge's self-test of its capture ([`SelfTestPlan`]): a chip
    /// reset, the generator's bursts, and the capture of them from the
    /// reset on, fetched with CAPTURE as usual.
    SelfTest(SelfTestPlan),
}

/// Largest response payload sent as one frame; longer ones go as
/// fragments of this many bytes, so that a noisy link loses little.
pub const FRAGMENT_DATA: usize = 48;

/// The smallest fragment a host may ask for (LINK).
pub const MIN_FRAGMENT_DATA: usize = 8;

/// The largest reply padding a host may ask for (LINK).
pub const MAX_PAD: u16 = 512;

/// The longest response payload: 255 fragments.
pub const MAX_REPLY: usize = 255 * FRAGMENT_DATA;

/// Splits a response payload into frame payloads: itself if it fits one
/// fragment of `size` data bytes, else `seq, FRAGMENT, index, count, data`
/// pieces of `size` bytes (more, if 255 of `size` would not hold it). A
/// payload over [`MAX_REPLY`] loses its tail; the bridge never sends one
/// (it answers OVERFLOW instead).
pub fn fragment(payload: &[u8], size: usize) -> Vec<Vec<u8>> {
    let size = size
        .clamp(MIN_FRAGMENT_DATA, FRAGMENT_DATA)
        .max(payload.len().div_ceil(255));
    if payload.len() <= size {
        return vec![payload.to_vec()];
    }
    let seq = payload.first().copied().unwrap_or(0);
    let chunks: Vec<&[u8]> = payload.chunks(size).collect();
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
        // A fragment carries at most FRAGMENT_DATA bytes (255 of them make
        // the longest response): a longer one is not a fragment, so that a
        // lying bridge cannot make the host hold 255 frames of 4 KiB.
        [seq, k, i, n, data @ ..]
            if *k == kind::FRAGMENT && *n > 0 && i < n && data.len() <= FRAGMENT_DATA =>
        {
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
    /// The fragment size and padding now in force.
    Link {
        fragment: u8,
        pad: u16,
    },
    SelfTest(SelfTestReply),
}

impl Response {
    /// The message's name in the protocol document: `BATCH_REPLY`.
    pub fn name(&self) -> &'static str {
        match self {
            Response::Hello(_) => "HELLO_REPLY",
            Response::Batch(_) => "BATCH_REPLY",
            Response::Capture(_) => "CAPTURE_REPLY",
            Response::BatchCapture { .. } => "BATCH_CAPTURE_REPLY",
            Response::Error { .. } => "ERROR",
            Response::Link { .. } => "LINK_REPLY",
            Response::SelfTest(_) => "SELF_TEST_REPLY",
        }
    }
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

mod bytes;
mod capture;
mod lean;
mod ops;

pub use self::bytes::Timer;
use self::bytes::{R, W};
use self::capture::{get_capture, put_capture};
pub use self::lean::{capture_bytes, Incoming, ReplyWriter, WireOp};
use self::ops::{get_ops, get_replies, put_ops, put_replies};
pub use self::ops::{
    wire_op_len, wire_ops, worst_reply_len, MAX_BATCH_OPS, MAX_REPLY_ENTRY, MAX_SAMPLES,
};

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

/// Where a capture fetch starts, and its chunk size (CAPTURE,
/// BATCH_CAPTURE).
fn put_capture_from(w: &mut W, runs: u32, pins: u32, moves: u32, max: u16) {
    w.u32(runs);
    w.u32(pins);
    w.u32(moves);
    w.u16(max);
}

impl Request {
    /// The frame payload for this request with sequence number `seq`,
    /// times in ticks of `timer`.
    pub fn encode(&self, seq: u8, timer: Timer) -> Vec<u8> {
        let mut w = W(Vec::new(), timer);
        w.u8(seq);
        match self {
            Request::Hello { version, host } => {
                w.u8(kind::HELLO);
                w.u16(*version);
                w.u32(*host);
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
            Request::Link { fragment, pad } => {
                w.u8(kind::LINK);
                w.u8(*fragment);
                w.u16(*pad);
            }
            Request::SelfTest(p) => {
                w.u8(kind::SELF_TEST);
                w.u32(p.count);
                w.dur(p.high);
                w.dur(p.low);
                w.u16(p.bursts);
                w.dur(p.gap);
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
            kind::HELLO => {
                let version = r.u16()?;
                if version != PROTOCOL_VERSION {
                    // Another version's HELLO may carry other fields: the
                    // bridge answers VERSION whatever follows.
                    return Ok((seq, Request::Hello { version, host: 0 }));
                }
                Request::Hello {
                    version,
                    host: r.u32()?,
                }
            }
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
            kind::LINK => Request::Link {
                fragment: r.u8()?,
                pad: r.u16()?,
            },
            kind::RESEND => {
                let n = usize::from(r.u8()?);
                Request::Resend {
                    fragments: r.take(n)?.to_vec(),
                }
            }
            kind::SELF_TEST => {
                let at = r.at;
                let count = r.u32()?;
                if count == 0 {
                    return Err(WireError::BadValue {
                        at,
                        field: "self-test pulse count",
                        value: 0,
                    });
                }
                let (high, low) = (r.dur()?, r.dur()?);
                let at = r.at;
                let bursts = r.u16()?;
                if bursts == 0 {
                    return Err(WireError::BadValue {
                        at,
                        field: "self-test burst count",
                        value: 0,
                    });
                }
                Request::SelfTest(SelfTestPlan {
                    count,
                    high,
                    low,
                    bursts,
                    gap: r.dur()?,
                })
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
                w.u8(u8::from(h.resumed));
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
            Response::Link { fragment, pad } => {
                w.u8(kind::LINK_REPLY);
                w.u8(*fragment);
                w.u16(*pad);
            }
            Response::SelfTest(t) => {
                w.u8(kind::SELF_TEST_REPLY);
                w.dur(t.high);
                w.dur(t.low);
                let n = t.starts.len().min(usize::from(u16::MAX));
                w.u16(n as u16);
                for at in &t.starts[..n] {
                    w.time(*at);
                }
            }
        }
        w.0
    }

    /// `(seq, response)` from a frame payload, times in ticks of `timer`.
    pub fn decode(payload: &[u8], timer: Timer) -> Result<(u8, Response), WireError> {
        // No bridge sends a longer one (it answers OVERFLOW instead).
        if payload.len() > MAX_REPLY {
            return Err(WireError::BadValue {
                at: 0,
                field: "response length",
                value: payload.len() as u64,
            });
        }
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
                resumed: r.bool("resumed flag")?,
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
            kind::LINK_REPLY => Response::Link {
                fragment: r.u8()?,
                pad: r.u16()?,
            },
            kind::SELF_TEST_REPLY => {
                let (high, low) = (r.dur()?, r.dur()?);
                let n = r.count(8)?;
                let mut starts = Vec::with_capacity(n);
                for _ in 0..n {
                    starts.push(r.time()?);
                }
                Response::SelfTest(SelfTestReply { starts, high, low })
            }
            k => return Err(WireError::UnknownKind(k)),
        };
        r.end()?;
        Ok((seq, resp))
    }
}

#[cfg(test)]
mod tests {
    use super::bytes::W;
    use super::ops::{op, put_reply};
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

    /// Section 7: a run's jitter is a bound, so it is rounded up on the
    /// way to ticks and back, and grows by the two nanoseconds that start
    /// and span may each lose when a tick is not a whole number of them;
    /// a run of no pulses, or a single pulse that spans time, is refused.
    #[test]
    fn run_bounds_survive_a_timer_that_is_not_in_nanoseconds() {
        let t = Timer { hz: 133_333_333 }; // 7.5 ns a tick
        let run = PulseRun {
            start: Instant::from_nanos(t.to_nanos(1_000)),
            count: 1_000,
            dir: Direction::Cw,
            span: Duration::from_nanos(t.to_nanos(266_667)),
            jitter: Duration::from_nanos(8),
        };
        let two = PulseRun::exact(
            run.start,
            Duration::from_nanos(t.to_nanos(267)),
            2,
            Direction::Ccw,
        );
        let cap = Response::Capture(CaptureChunk {
            runs: vec![run, two],
            ..CaptureChunk::default()
        });
        let Ok((_, Response::Capture(back))) = Response::decode(&cap.encode(1, t), t) else {
            panic!("decodes");
        };
        assert_eq!(
            (back.runs[0].start, back.runs[0].span),
            (run.start, run.span)
        );
        // 8 ns is 1.07 ticks: 2 ticks up, 15.0000004 ns: 16 ns up, and 2 ns
        // for the conversion.
        assert_eq!(back.runs[0].jitter, Duration::from_nanos(18));
        // Two pulses are both measured: nothing between them to be off.
        assert_eq!(back.runs[1], two);
        for bad in [PulseRun { count: 0, ..two }, PulseRun { count: 1, ..two }] {
            let cap = Response::Capture(CaptureChunk {
                runs: vec![bad],
                ..CaptureChunk::default()
            });
            assert!(
                matches!(
                    Response::decode(&cap.encode(1, t), t),
                    Err(WireError::BadValue { .. })
                ),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn every_op_round_trips() {
        let req = Request::Batch(sample_ops());
        assert_eq!(Request::decode(&req.encode(7, T), T), Ok((7, req)));
        let h = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 0x1234_5678,
        };
        assert_eq!(Request::decode(&h.encode(0, T), T), Ok((0, h)));
    }

    /// Another version's HELLO is read as far as its version, whatever
    /// follows, so that the bridge can answer VERSION (section 3).
    #[test]
    fn a_hello_of_another_version_is_read_for_its_version() {
        // A version 6 host's HELLO: no host session.
        assert_eq!(
            Request::decode(&[3, kind::HELLO, 6, 0], T),
            Ok((
                3,
                Request::Hello {
                    version: 6,
                    host: 0
                }
            ))
        );
        // A later version's, with fields this one does not know.
        assert_eq!(
            Request::decode(&[3, kind::HELLO, 8, 0, 1, 2, 3, 4, 5, 6, 7], T),
            Ok((
                3,
                Request::Hello {
                    version: 8,
                    host: 0
                }
            ))
        );
        // This version's must carry the host session.
        assert!(Request::decode(&[3, kind::HELLO, PROTOCOL_VERSION as u8, 0], T).is_err());
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
                    interval_bound: Duration::from_nanos(37),
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
            resumed: true,
        });
        assert_eq!(Response::decode(&hello.encode(1, T), T), Ok((1, hello)));
        let cap = Response::Capture(CaptureChunk {
            runs: vec![
                PulseRun::exact(
                    Instant::from_nanos(5),
                    Duration::from_nanos(42_000),
                    1_000,
                    Direction::Cw,
                ),
                PulseRun {
                    start: Instant::from_nanos(50_000_000),
                    count: 16_777_216,
                    dir: Direction::Ccw,
                    span: Duration::from_nanos(167_772_151_234),
                    jitter: Duration::from_nanos(13),
                },
            ],
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
        let frags = fragment(&payload, FRAGMENT_DATA);
        assert_eq!(frags.len(), 3);
        let mut whole = Vec::new();
        for (i, f) in frags.iter().enumerate() {
            let (seq, idx, n, data) = parse_fragment(f).expect("a fragment");
            assert_eq!((seq, usize::from(idx), n), (0, i, 3));
            whole.extend_from_slice(data);
        }
        assert_eq!(whole, payload);
        assert_eq!(fragment(&[5, 1, 2], FRAGMENT_DATA), vec![vec![5, 1, 2]]);
        // Smaller fragments for a noisy line; never below the minimum, and
        // never more than 255 of them.
        let small = fragment(&payload, 10);
        assert_eq!(small.len(), 13);
        assert!(small.iter().all(|f| f.len() <= 4 + 10));
        assert_eq!(
            fragment(&payload, 1).len(),
            130_usize.div_ceil(MIN_FRAGMENT_DATA)
        );
        let long = vec![7u8; MAX_REPLY];
        assert_eq!(fragment(&long, MIN_FRAGMENT_DATA).len(), 255);
        let link = Request::Link {
            fragment: 12,
            pad: 64,
        };
        assert_eq!(Request::decode(&link.encode(6, T), T), Ok((6, link)));
        let set = Response::Link {
            fragment: 12,
            pad: 64,
        };
        assert_eq!(Response::decode(&set.encode(6, T), T), Ok((6, set)));
        let r = Request::Resend {
            fragments: vec![0, 2],
        };
        assert_eq!(Request::decode(&r.encode(4, T), T), Ok((4, r)));
        // SELF_TEST, in a bridge's ticks (75 MHz), and its reply.
        let t = Timer { hz: 75_000_000 };
        let plan = SelfTestPlan {
            count: 100,
            high: Duration::from_nanos(5_000),
            low: Duration::from_nanos(5_000),
            bursts: 3,
            gap: Duration::from_micros(200),
        };
        let st = Request::SelfTest(plan);
        assert_eq!(Request::decode(&st.encode(7, t), t), Ok((7, st)));
        let zero = Request::SelfTest(SelfTestPlan { count: 0, ..plan });
        assert!(matches!(
            Request::decode(&zero.encode(7, t), t),
            Err(WireError::BadValue {
                field: "self-test pulse count",
                ..
            })
        ));
        let none = Request::SelfTest(SelfTestPlan { bursts: 0, ..plan });
        assert!(Request::decode(&none.encode(7, t), t).is_err());
        let done = Response::SelfTest(SelfTestReply {
            starts: vec![Instant::from_nanos(120), Instant::from_nanos(1_200_040)],
            high: Duration::from_nanos(5_000),
            low: Duration::from_nanos(5_000),
        });
        assert_eq!(Response::decode(&done.encode(7, t), t), Ok((7, done)));
        // A count of starts the bytes cannot hold is refused, not allocated.
        let mut lying = Response::SelfTest(SelfTestReply {
            starts: vec![],
            high: Duration::ZERO,
            low: Duration::ZERO,
        })
        .encode(7, t);
        let n = lying.len();
        lying[n - 2..].copy_from_slice(&u16::MAX.to_le_bytes());
        assert!(Response::decode(&lying, t).is_err());
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
        let mut ok = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 1,
        }
        .encode(1, T);
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
