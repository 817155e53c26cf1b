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
//! Which request an abort stops is named, not timed: ABORT carries the
//! sequence number of the request it means, so it stops that request
//! whether the engine is already running it or has yet to begin it, and
//! never another. A HELLO from another host session stops whatever runs.
//! Bytes a bridge drops (a connection that ends mid-frame) cannot make the
//! watch and the engine disagree: nothing is counted.

use super::abort_line::takes_over;
pub use super::abort_line::AbortLine;
use super::frame::FrameDecoder;
use super::wire::{kind, Request, Timer, PROTOCOL_VERSION};

/// Looks at the bytes a bridge receives, as they arrive, for frames that
/// stop the request in flight: ABORT, and a HELLO from another host
/// session than the last (a new host has taken the bridge over, and the
/// old host's request is nobody's). A HELLO of the same host session is a
/// reconnect (section 3): the request runs on and its reply waits in the
/// cache.
#[derive(Debug)]
pub struct AbortWatch {
    line: AbortLine,
    decoder: FrameDecoder,
    host: u32,
}

impl AbortWatch {
    /// A watch on the receive path that raises `line`.
    pub fn new(line: AbortLine) -> AbortWatch {
        AbortWatch {
            line,
            decoder: FrameDecoder::new(),
            host: 0,
        }
    }

    /// Forgets a frame cut short (the connection it came on ended).
    pub fn forget(&mut self) {
        self.decoder = FrameDecoder::new();
    }

    /// Takes bytes as they arrive (before they are queued for the
    /// engine); whether they held an aborting frame.
    pub fn on_bytes(&mut self, bytes: &[u8]) -> bool {
        self.decoder.extend(bytes);
        let mut raised = false;
        loop {
            match self.decoder.decode() {
                Ok(Some(payload)) => raised |= self.look(&payload),
                Ok(None) => return raised,
                // The engine answers it.
                Err(_) => {}
            }
        }
    }

    fn look(&mut self, payload: &[u8]) -> bool {
        if !matches!(payload.get(1).copied(), Some(kind::ABORT | kind::HELLO)) {
            return false;
        }
        match Request::decode(payload, Timer::NANOS) {
            Ok((_, Request::Abort { request })) => {
                self.line.raise(request);
                true
            }
            Ok((_, Request::Hello { version, host })) if version == PROTOCOL_VERSION => {
                let new = takes_over(self.host, host);
                self.host = host;
                if new {
                    self.line.raise_any();
                }
                new
            }
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
    fn an_abort_stops_the_request_it_names_and_no_other() {
        let line = AbortLine::new();
        let mut watch = AbortWatch::new(line.clone());
        line.begin(2, true);
        assert!(!line.pending());
        assert!(watch.on_bytes(&framed(&Request::Abort { request: 2 }, 3)));
        assert!(line.pending(), "request 2 runs and is named");
        line.acknowledge();
        assert!(!line.pending(), "acknowledged: the chip's stop runs");
        line.end();
        // An ABORT for a request that has ended stops no later one.
        assert!(watch.on_bytes(&framed(&Request::Abort { request: 4 }, 5)));
        line.begin(6, true);
        assert!(!line.pending());
        line.end();
        // Request 6 began after it: the ABORT for 4 is stale and gone,
        // and a later request that reuses the number runs.
        line.begin(4, true);
        assert!(!line.pending());
        // Read by the engine in its turn, it is gone too.
        assert!(watch.on_bytes(&framed(&Request::Abort { request: 8 }, 9)));
        line.read_abort(8);
        line.begin(8, true);
        assert!(!line.pending());
    }

    #[test]
    fn an_abort_read_before_the_engine_begins_the_request_still_stops_it() {
        let line = AbortLine::new();
        let mut watch = AbortWatch::new(line.clone());
        let mut bytes = framed(&Request::Batch(alloc::vec![]), 1);
        bytes.extend(framed(&Request::Abort { request: 1 }, 2));
        assert!(watch.on_bytes(&bytes));
        // A LINK read before it leaves the ABORT in place.
        line.begin(7, false);
        line.begin(1, true);
        assert!(line.pending());
    }

    #[test]
    fn only_a_hello_of_another_host_stops_what_runs() {
        let line = AbortLine::new();
        let mut watch = AbortWatch::new(line.clone());
        assert!(watch.on_bytes(&framed(&hello(7), 1)));
        line.read_takeover();
        line.begin(2, true);
        assert!(!watch.on_bytes(&framed(&hello(7), 3)), "a reconnect");
        assert!(!line.pending());
        // Garbage and bad frames are the engine's to answer.
        assert!(!watch.on_bytes(&[0x55, 0x13, 0x00]));
        assert!(watch.on_bytes(&framed(&hello(9), 4)), "another host");
        assert!(line.pending());
        line.acknowledge();
        assert!(!line.pending());
        assert!(watch.on_bytes(&framed(&hello(0), 5)), "nobody's session");
        assert!(line.pending());
    }
}
