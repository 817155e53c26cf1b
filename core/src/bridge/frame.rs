//! Framing of the bus bridge link: COBS frames with a CRC, split on 0x00.
//!
//! A frame on the wire is `COBS(payload ++ crc32c_le(payload)) ++ 0x00`,
//! CRC-32C (Castagnoli). Thirty-two bits, because on a line that garbles
//! one frame in two, a 16-bit check lets about one garbled frame in 65,536
//! through as valid: a few a day on a noisy cable, each a wrong byte the
//! host would believe. COBS leaves no 0x00 inside a frame, so after line
//! noise the decoder resynchronises at the next delimiter: one corrupted
//! frame never reframes the ones after it.
//!
//! [`FrameDecoder`] works like tokio-util's `Decoder`: feed it bytes with
//! [`FrameDecoder::extend`], then call [`FrameDecoder::decode`] until it
//! returns `Ok(None)` (need more bytes). An error reports one bad frame; the
//! decoder has already dropped it and goes on with the next. Both the host
//! driver and the bridge simulator use this one implementation.

use alloc::vec::Vec;
use crc::{Crc, Table, CRC_32_ISCSI};

/// CRC-32C (Castagnoli: poly 0x1EDC6F41 reflected, init and final XOR
/// 0xFFFFFFFF), called ISCSI in the CRC catalogue. Slice-by-16 tables (16
/// KiB of constants) keep it fast on both ends of a busy link.
const CRC32C: Crc<u32, Table<16>> = Crc::<u32, Table<16>>::new(&CRC_32_ISCSI);

/// Bytes of the check appended to every payload.
pub(crate) const CHECK_LEN: usize = 4;

/// Largest payload a frame may carry (before CRC and COBS).
pub const MAX_PAYLOAD: usize = 4096;

/// Largest encoded frame: payload, CRC, COBS overhead (one byte in 254).
pub const MAX_ENCODED: usize = MAX_PAYLOAD + CHECK_LEN + (MAX_PAYLOAD + CHECK_LEN) / 254 + 1;

/// One frame that could not be decoded. The decoder has skipped it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// More bytes than [`MAX_ENCODED`] without a delimiter: the rest of
    /// this frame is dropped up to the next 0x00.
    #[error("frame longer than {MAX_ENCODED} bytes (buffer overflow); dropped")]
    TooLong,
    /// The bytes between two delimiters are not valid COBS.
    #[error("corrupt frame ({len} bytes): not valid COBS")]
    Cobs { len: usize },
    /// Too short to hold a CRC.
    #[error("corrupt frame: {len} bytes is too short")]
    TooShort { len: usize },
    /// The CRC does not match the payload.
    #[error("corrupt frame: CRC 0x{got:08X}, expected 0x{expected:08X}")]
    Crc { expected: u32, got: u32 },
}

/// Encodes `payload` as one frame, delimiter included.
///
/// # Panics
/// Never for payloads up to [`MAX_PAYLOAD`]; callers check the length.
pub fn encode(payload: &[u8]) -> Vec<u8> {
    let mut body = Vec::with_capacity(payload.len() + CHECK_LEN);
    body.extend_from_slice(payload);
    body.extend_from_slice(&CRC32C.checksum(payload).to_le_bytes());
    let mut out = cobs::encode_vec(&body);
    out.push(0);
    out
}

/// Splits a byte stream into checked frame payloads.
#[derive(Debug, Default)]
pub struct FrameDecoder {
    buf: Vec<u8>,
    /// Dropping an over-long frame until the next delimiter.
    skipping: bool,
}

impl FrameDecoder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds received bytes. Memory stays bounded: an over-long frame is
    /// cut off and reported by [`Self::decode`].
    pub fn extend(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next frame: `Ok(Some(payload))`, `Ok(None)` when more bytes are
    /// needed, or `Err` for one bad frame (already skipped; call again).
    pub fn decode(&mut self) -> Result<Option<Vec<u8>>, FrameError> {
        loop {
            let Some(end) = self.buf.iter().position(|b| *b == 0) else {
                if self.buf.len() > MAX_ENCODED {
                    self.buf.clear();
                    if !self.skipping {
                        self.skipping = true;
                        return Err(FrameError::TooLong);
                    }
                }
                return Ok(None);
            };
            let frame: Vec<u8> = self.buf.drain(..=end).take(end).collect();
            if core::mem::take(&mut self.skipping) {
                // The tail of an over-long frame, already reported.
                continue;
            }
            if frame.is_empty() {
                // Back-to-back delimiters (a sender may flush with 0x00).
                continue;
            }
            if frame.len() > MAX_ENCODED {
                return Err(FrameError::TooLong);
            }
            let body =
                cobs::decode_vec(&frame).map_err(|_| FrameError::Cobs { len: frame.len() })?;
            if body.len() < CHECK_LEN {
                return Err(FrameError::TooShort { len: body.len() });
            }
            let (payload, crc) = body.split_at(body.len() - CHECK_LEN);
            let got = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
            let expected = CRC32C.checksum(payload);
            if got != expected {
                return Err(FrameError::Crc { expected, got });
            }
            return Ok(Some(payload.to_vec()));
        }
    }

    /// Bytes held that do not yet form a frame.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn crc_is_crc32c() {
        // The catalogue check value for "123456789".
        assert_eq!(CRC32C.checksum(b"123456789"), 0xE306_9283);
    }

    #[test]
    fn frames_split_on_zero_and_survive_garbage() {
        let mut d = FrameDecoder::new();
        let mut stream = encode(b"one");
        stream.extend_from_slice(&[0x55, 0x13, 0x00]); // noise, then a delimiter
        stream.extend(encode(&[0, 0, 0]));
        d.extend(&stream);
        assert_eq!(d.decode(), Ok(Some(b"one".to_vec())));
        assert!(d.decode().is_err(), "the noise is one bad frame");
        assert_eq!(d.decode(), Ok(Some(vec![0, 0, 0])));
        assert_eq!(d.decode(), Ok(None));
        assert_eq!(d.pending(), 0);
    }

    #[test]
    fn a_flipped_bit_is_a_crc_error_and_the_next_frame_still_decodes() {
        let mut bad = encode(b"hello world");
        bad[3] ^= 0x04;
        let mut d = FrameDecoder::new();
        d.extend(&bad);
        d.extend(&encode(b"next"));
        assert!(matches!(
            d.decode(),
            Err(FrameError::Crc { .. } | FrameError::Cobs { .. })
        ));
        assert_eq!(d.decode(), Ok(Some(b"next".to_vec())));
    }

    #[test]
    fn partial_frames_wait_for_more() {
        let f = encode(b"split me");
        let mut d = FrameDecoder::new();
        d.extend(&f[..4]);
        assert_eq!(d.decode(), Ok(None));
        d.extend(&f[4..]);
        assert_eq!(d.decode(), Ok(Some(b"split me".to_vec())));
    }

    #[test]
    fn endless_garbage_is_bounded_and_reported_once() {
        let mut d = FrameDecoder::new();
        for _ in 0..10 {
            d.extend(&[0x11; 1000]);
            let _ = d.decode();
            assert!(d.pending() <= MAX_ENCODED + 1000);
        }
        d.extend(&[0]);
        d.extend(&encode(b"after"));
        assert_eq!(d.decode(), Ok(Some(b"after".to_vec())));
    }

    proptest! {
        #[test]
        fn any_payload_round_trips(payload in prop::collection::vec(any::<u8>(), 0..600)) {
            let mut d = FrameDecoder::new();
            d.extend(&encode(&payload));
            prop_assert_eq!(d.decode(), Ok(Some(payload)));
        }

        /// Any bytes at all: errors or frames, never a panic, and a valid
        /// frame sent afterwards (after a delimiter) always comes through.
        #[test]
        fn arbitrary_bytes_never_panic_and_resync(noise in prop::collection::vec(any::<u8>(), 0..2000)) {
            let mut d = FrameDecoder::new();
            d.extend(&noise);
            d.extend(&[0]);
            d.extend(&encode(b"sync"));
            let mut last = None;
            for _ in 0..4000 {
                match d.decode() {
                    Ok(Some(p)) => last = Some(p),
                    Ok(None) => break,
                    Err(_) => {}
                }
            }
            prop_assert_eq!(last, Some(b"sync".to_vec()));
        }
    }
}

#[cfg(test)]
mod cross_check {
    /// Frames computed by an independent implementation (Python, from the
    /// CRC catalogue and the COBS paper) for `docs/bridge-protocol.md`.
    use crate::bridge::wire::{Request, Timer, PROTOCOL_VERSION};
    use crate::bus::Op;
    use crate::time::Duration;

    #[test]
    fn matches_the_examples_in_the_protocol_document() {
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 0x1234_5678,
        }
        .encode(1, Timer::NANOS);
        assert_eq!(hello, [0x01, 0x01, 0x09, 0x00, 0x78, 0x56, 0x34, 0x12]);
        assert_eq!(super::encode(&hello), HELLO);
        let rs = Request::Batch(vec![Op::ReadStatus]).encode(2, Timer::NANOS);
        assert_eq!(super::encode(&rs), BATCH_RS);
        let samples = Request::Batch(
            (0..3)
                .flat_map(|_| [Op::ReadPins, Op::Delay(Duration::from_nanos(250))])
                .collect(),
        )
        .encode(3, Timer::NANOS);
        assert_eq!(super::encode(&samples), BATCH_SAMPLE);
    }

    const HELLO: &[u8] = &[
        0x04, 0x01, 0x01, 0x09, 0x09, 0x78, 0x56, 0x34, 0x12, 0x57, 0xC6, 0x55, 0xD8, 0x00,
    ];
    const BATCH_RS: &[u8] = &[
        0x04, 0x02, 0x02, 0x01, 0x06, 0x12, 0x0A, 0xAF, 0x13, 0xDE, 0x00,
    ];
    const BATCH_SAMPLE: &[u8] = &[
        0x04, 0x03, 0x02, 0x01, 0x03, 0x1B, 0x03, 0x02, 0xFA, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01,
        0x05, 0x1C, 0xC2, 0xB3, 0x01, 0x00,
    ];
}
