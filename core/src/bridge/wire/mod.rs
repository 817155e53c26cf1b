//! Bridge messages: typed requests and responses, and their bytes.
//!
//! A frame payload is `seq:u8, kind:u8, body`. All integers are little
//! endian. Times and durations on the wire are ticks of the bridge's timer,
//! whose rate the bridge announces in its hello reply; the host converts.
//! [`Request::decode`] and [`Response::decode`] check every length and
//! value and never panic; `docs/bridge-protocol.md` is the specification.

mod bridge_side;
mod bytes;
mod capture;
mod codec;
mod message;
mod ops;
#[cfg(test)]
mod tests;

pub use self::bridge_side::{capture_bytes, Incoming, ReplyWriter, WireOp};
pub use self::bytes::{FastTimer, Timer};
pub use self::message::{
    fragment, kind, parse_fragment, BridgeErrorCode, CaptureChunk, Hello, Request, Response,
    WireError, FRAGMENT_DATA, MAX_PAD, MAX_REPLY, MAX_SAMPLES, MIN_FRAGMENT_DATA, PROTOCOL_VERSION,
};
pub use self::ops::{wire_op_len, wire_ops, worst_reply_len, MAX_BATCH_OPS, MAX_REPLY_ENTRY};
