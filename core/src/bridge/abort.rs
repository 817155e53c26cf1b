//! Stopping a request in flight (`docs/bridge-protocol.md` section 5,
//! ABORT): the one message a bridge must hear while it is busy.
//!
//! A bridge runs a request to its end before it reads the next one, so an
//! ABORT queued behind a ten-minute move would be read ten minutes late.
//! The bridge's receive path therefore looks at every frame as it arrives
//! ([`AbortWatch`], on the USB or UART side, or a reader thread), before
//! the frame waits its turn, and raises the [`AbortLine`] that the
//! [`BridgeEngine`](super::engine::BridgeEngine) checks between ops and a
//! bus checks in its long waits.
//!
//! Which request an abort stops is decided by frame order, not by timing:
//! both sides count the frames they decode from the same bytes, the watch
//! notes the index of the ABORT (or of a HELLO that changes the host), the
//! engine the index of the request it runs, and only a request that came
//! before the abort is stopped. An ABORT that overtakes nothing (the
//! request it meant had ended) stops nothing, and one that is read before
//! the engine has even begun the request before it still stops that one.

use super::frame::FrameDecoder;
use super::wire::{kind, Request, Timer, PROTOCOL_VERSION};
use alloc::sync::Arc;
use core::sync::atomic::{AtomicU32, Ordering};

/// What the receive path and the engine share: the index of the newest
/// frame that aborts, and of the request running. Cheap to clone (both
/// ends hold one) and to check (two atomic loads).
#[derive(Debug, Clone, Default)]
pub struct AbortLine(Arc<Indices>);

#[derive(Debug, Default)]
struct Indices {
    /// The index (from 1) of the newest ABORT, or HELLO of another host.
    seen: AtomicU32,
    /// The index of the request the engine runs (0: none yet).
    running: AtomicU32,
}

impl AbortLine {
    pub fn new() -> AbortLine {
        AbortLine::default()
    }

    /// The receive path decoded an aborting frame, the `index`th frame.
    pub fn raise(&self, index: u32) {
        self.0.seen.store(index, Ordering::Release);
    }

    /// The engine begins the request that was frame `index`.
    pub fn begin(&self, index: u32) {
        self.0.running.store(index, Ordering::Release);
    }

    /// Whether an abort came after the request running: stop it at the
    /// next step. Frame indices wrap after 2^32 frames; they are compared
    /// as a window, as TCP compares sequence numbers.
    pub fn pending(&self) -> bool {
        let seen = self.0.seen.load(Ordering::Acquire);
        let running = self.0.running.load(Ordering::Acquire);
        running != 0 && (seen.wrapping_sub(running) as i32) > 0
    }

    /// The engine has stopped the request: what it does now (stopping the
    /// chip) must not be cut short by the same abort.
    pub fn acknowledge(&self) {
        let seen = self.0.seen.load(Ordering::Acquire);
        self.0.running.store(seen, Ordering::Release);
    }

    /// A watch on the receive path that raises this line.
    pub fn watch(&self) -> AbortWatch {
        AbortWatch {
            line: self.clone(),
            decoder: FrameDecoder::new(),
            frames: 0,
            host: 0,
        }
    }
}

/// Looks at the bytes a bridge receives, as they arrive, for frames that
/// stop the request in flight: ABORT, and a HELLO from another host
/// session than the last (a new host has taken the bridge over, and the
/// old host's request is nobody's). A HELLO of the same host session is a
/// reconnect (section 3): the request runs on and its reply waits in the
/// cache.
///
/// It must see exactly the bytes the engine is given, in the same order,
/// so that the two count the same frames.
#[derive(Debug)]
pub struct AbortWatch {
    line: AbortLine,
    decoder: FrameDecoder,
    frames: u32,
    host: u32,
}

impl AbortWatch {
    /// Takes bytes as they arrive (before they are queued for the
    /// engine); whether they held an aborting frame.
    pub fn on_bytes(&mut self, bytes: &[u8]) -> bool {
        self.decoder.extend(bytes);
        let mut raised = false;
        loop {
            match self.decoder.decode() {
                Ok(Some(payload)) => {
                    self.frames = self.frames.wrapping_add(1);
                    if self.aborts(&payload) {
                        self.line.raise(self.frames);
                        raised = true;
                    }
                }
                Ok(None) => return raised,
                // The engine answers it; it counts no frame there either.
                Err(_) => {}
            }
        }
    }

    fn aborts(&mut self, payload: &[u8]) -> bool {
        match payload.get(1).copied() {
            Some(kind::ABORT) => true,
            Some(kind::HELLO) => match Request::decode(payload, Timer::NANOS) {
                Ok((_, Request::Hello { version, host })) if version == PROTOCOL_VERSION => {
                    // As the engine greets (`greet`): 0 is nobody's.
                    let new = host == 0 || host != self.host;
                    self.host = host;
                    new
                }
                _ => false,
            },
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::frame;
    use super::*;

    fn framed(req: &Request, seq: u8) -> alloc::vec::Vec<u8> {
        frame::encode(&req.encode(seq, Timer::NANOS))
    }

    fn hello(host: u32) -> Request {
        Request::Hello {
            version: PROTOCOL_VERSION,
            host,
        }
    }

    #[test]
    fn an_abort_stops_the_request_before_it_and_no_later_one() {
        let line = AbortLine::new();
        let mut watch = line.watch();
        // HELLO (frame 1), a batch (2), then ABORT (3).
        assert!(watch.on_bytes(&framed(&hello(7), 1)));
        assert!(!watch.on_bytes(&framed(&Request::Batch(alloc::vec![]), 2)));
        line.begin(1);
        assert!(!line.pending(), "the HELLO is the request itself");
        line.begin(2);
        assert!(!line.pending());
        assert!(watch.on_bytes(&framed(&Request::Abort, 3)));
        assert!(line.pending(), "the batch, frame 2, came before the abort");
        line.acknowledge();
        assert!(!line.pending(), "acknowledged: the chip's stop runs");
        line.begin(4);
        assert!(!line.pending(), "a request after the abort runs");
    }

    #[test]
    fn an_abort_read_before_the_engine_begins_the_request_still_stops_it() {
        let line = AbortLine::new();
        let mut watch = line.watch();
        let mut bytes = framed(&Request::Batch(alloc::vec![]), 1);
        bytes.extend(framed(&Request::Abort, 2));
        assert!(watch.on_bytes(&bytes));
        line.begin(1);
        assert!(line.pending());
    }

    #[test]
    fn only_a_hello_of_another_host_aborts() {
        let line = AbortLine::new();
        let mut watch = line.watch();
        assert!(watch.on_bytes(&framed(&hello(7), 1)));
        assert!(!watch.on_bytes(&framed(&hello(7), 2)), "a reconnect");
        assert!(watch.on_bytes(&framed(&hello(9), 3)), "another host");
        assert!(watch.on_bytes(&framed(&hello(0), 4)), "nobody's session");
        // Garbage and bad frames count no frame, as in the engine.
        assert!(!watch.on_bytes(&[0x55, 0x13, 0x00]));
        line.begin(5);
        assert!(!line.pending());
        assert!(watch.on_bytes(&framed(&Request::Abort, 5)) && !line.pending());
        assert!(watch.on_bytes(&framed(&Request::Abort, 6)) && line.pending());
    }

    #[test]
    fn frame_indices_compare_across_their_wrap() {
        let line = AbortLine::new();
        line.begin(u32::MAX);
        line.raise(2);
        assert!(line.pending());
        line.begin(3);
        assert!(!line.pending());
    }
}
