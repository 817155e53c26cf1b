//! Telling a bridge to stop (`docs/bridge-protocol.md` section 5, ABORT):
//! when this host stops waiting for a request that may still be running
//! (a stop request, SIGINT or SIGTERM; a scenario's `--timeout`; a request
//! given up), so that the
//! bridge does not go on with a ten-minute move for nobody, and the next
//! run on it opens at once.

use super::error::{AbortOutcome, BridgeError};
use super::target::BridgeTarget;
use crate::backend::link::Link;
use crate::stop::StopRequest;
use ppmc_core::bridge::frame;
use ppmc_core::bridge::wire::{Request, Response};
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// How long the host waits for ABORT_REPLY: a bridge stops a wait within
/// milliseconds and answers after its Immediate Stop (10 ms at most).
const ABORT_WAIT: WallDuration = WallDuration::from_millis(500);

impl<L: Link> BridgeTarget<L> {
    /// `error` ended `req`, sent as sequence `seq`: if the bridge may
    /// still be running it, tell it to stop, and say in the error what it
    /// answered.
    pub(super) fn abort_after(
        &mut self,
        req: &Request,
        seq: u8,
        error: BridgeError,
    ) -> BridgeError {
        let runs_ops = matches!(
            req,
            Request::Batch(_) | Request::BatchCapture { .. } | Request::SelfTest(_)
        );
        // Only a request that went out can be running.
        let may_run = runs_ops && self.sent && !self.opts.stop.urgent();
        let mut abort = || match may_run {
            false => AbortOutcome::NotSent,
            true => self.send_abort(seq),
        };
        match error {
            BridgeError::PastDeadline { link, what, .. } => BridgeError::PastDeadline {
                link,
                what,
                abort: abort(),
            },
            BridgeError::Interrupted { link, .. } => BridgeError::Interrupted {
                link,
                abort: abort(),
            },
            BridgeError::NoAnswer {
                link,
                what,
                tries,
                secs,
                mut heard,
            } => {
                heard.push_str(abort().note());
                BridgeError::NoAnswer {
                    link,
                    what,
                    tries,
                    secs,
                    heard,
                }
            }
            other => other,
        }
    }

    /// Sends ABORT for request `request` and waits a little for
    /// ABORT_REPLY. Never fails: the host is giving up already.
    fn send_abort(&mut self, request: u8) -> AbortOutcome {
        match self.abort_exchange(request) {
            Some(true) => AbortOutcome::Stopped,
            Some(false) => AbortOutcome::NothingRunning,
            None => AbortOutcome::Unanswered,
        }
    }

    /// Whether the bridge stopped `request` (`None`: no answer).
    fn abort_exchange(&mut self, request: u8) -> Option<bool> {
        let seq = self.next_seq();
        let bytes = frame::encode(&Request::Abort { request }.encode(seq, self.timer));
        self.link.send(&bytes).ok()?;
        self.stats.aborts += 1;
        let end = WallInstant::now() + ABORT_WAIT;
        let mut buf = [0u8; 512];
        loop {
            while let Ok(Some(payload)) = self.decoder.decode() {
                if let Ok((s, Response::Abort { stopped })) = Response::decode(&payload, self.timer)
                {
                    if s == seq {
                        return Some(stopped);
                    }
                }
            }
            let left = end.checked_duration_since(WallInstant::now())?;
            let n = self
                .link
                .recv(&mut buf, left.min(StopRequest::SLICE))
                .ok()?;
            self.decoder.extend(&buf[..n]);
        }
    }
}
