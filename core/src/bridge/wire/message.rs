//! The messages: typed requests and responses, the bridge's errors and
//! hello, reply fragments, and why bytes do not decode.

use crate::bus::{Op, Reply, SelfTestPlan, SelfTestReply, Uncertainty};
use crate::protocol::capture::MoveStart;
use crate::protocol::{PinEvent, PulseRun, Straps};
use crate::time::Duration;
use alloc::boxed::Box;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

/// The protocol version this build speaks.
pub const PROTOCOL_VERSION: u16 = 9;

/// Message kinds (the second payload byte).
pub mod kind {
    pub const HELLO: u8 = 0x01;
    pub const BATCH: u8 = 0x02;
    pub const CAPTURE: u8 = 0x03;
    pub const RESEND: u8 = 0x04;
    pub const BATCH_CAPTURE: u8 = 0x05;
    pub const LINK: u8 = 0x06;
    pub const SELF_TEST: u8 = 0x07;
    pub const ABORT: u8 = 0x08;
    pub const HELLO_REPLY: u8 = 0x81;
    pub const BATCH_REPLY: u8 = 0x82;
    pub const CAPTURE_REPLY: u8 = 0x83;
    pub const FRAGMENT: u8 = 0x84;
    pub const BATCH_CAPTURE_REPLY: u8 = 0x85;
    pub const LINK_REPLY: u8 = 0x86;
    pub const SELF_TEST_REPLY: u8 = 0x87;
    pub const WORKING: u8 = 0x88;
    pub const ABORT_REPLY: u8 = 0x89;
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
    /// 8: the request was stopped before its end by the host's ABORT, or
    /// by another host's HELLO (`docs/bridge-protocol.md` section 5).
    Aborted,
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
            BridgeErrorCode::Aborted => 8,
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
            8 => BridgeErrorCode::Aborted,
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
            BridgeErrorCode::Aborted => f.write_str("ABORTED"),
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
    /// One bit per [`Input`](crate::protocol::Input) (bit = `Input::index`) that is wired.
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
    /// The bridge's serial number (an RP2350's chip ID, which its USB
    /// descriptor gives too), so that the reports name the bridge across
    /// a network as well; empty when it has none.
    pub serial: String,
    /// How sure the bridge's times are, by the path each was taken on
    /// (never finer than a tick of its timer).
    pub uncertainty: Uncertainty,
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
    /// Stop request `request` (its sequence number) at its next step and
    /// leave the chip stopped (`docs/bridge-protocol.md` section 5,
    /// ABORT). It changes nothing when that request is not running.
    Abort { request: u8 },
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
    /// Boxed: far larger than the other responses.
    Hello(Box<Hello>),
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
    /// Not a reply: the bridge is still running the request with this
    /// sequence number, and its timer has run `elapsed` since it began
    /// it. A bridge that may run slower than real time (a simulator on a
    /// busy machine) sends one 10 ms into a request and every 50 ms after
    /// (its host's time), so that the host waits by the bridge's clock, not
    /// its own (`docs/bridge-protocol.md` section 5).
    Working {
        elapsed: Duration,
    },
    /// The answer to ABORT: whether the request it named was stopped by
    /// it (its own reply is then ERROR `ABORTED`).
    Abort {
        stopped: bool,
    },
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
            Response::Working { .. } => "WORKING",
            Response::Abort { .. } => "ABORT_REPLY",
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

/// Most pin samples one SAMPLE op (or one SAMPLES reply entry) stands for.
pub const MAX_SAMPLES: usize = 512;
