//! One request and its reply over the link: sequence numbers,
//! retransmission with backoff, reply fragments and RESEND, noise counted,
//! and the bounded reconnect that resends the request in flight under the
//! at-most-once rule.

use super::error::*;
use super::options::*;
use super::target::*;
use crate::backend::link::Link;
use crate::stop::StopRequest;
use ppmc_core::bridge::frame::{self, FrameDecoder};
use ppmc_core::bridge::wire::{
    parse_fragment, BridgeErrorCode, Request, Response, FRAGMENT_DATA, MIN_FRAGMENT_DATA,
};
use std::io;
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// The slowest bridge a host waits for by its WORKING messages: 1/200 of
/// real time over a request (the board twin on a busy machine runs at
/// about 1/50). A bridge whose clock creeps slower, or one that says it is
/// working while its clock hardly moves, is given up all the same.
const SLOWEST_BRIDGE: u32 = 200;

/// The shortest wait for a reply from a bridge that has said WORKING: its
/// first WORKING about a request comes within 10 ms, the next 50 ms later.
const WORKING_WAIT: WallDuration = WallDuration::from_millis(100);

/// `t + d`, or the far future where that does not fit (absurd options).
fn later(t: WallInstant, d: WallDuration) -> WallInstant {
    t.checked_add(d)
        .unwrap_or_else(|| t + WallDuration::from_secs(100 * 365 * 24 * 3600))
}

/// What the bridge says of a request that kept arriving garbled.
#[derive(Debug)]
pub(super) enum Ran {
    /// It never ran it: safe to send its ops again, split.
    No,
    /// It ran it; here is the whole reply.
    Yes(Response),
    /// It ran it; some fragments of the reply have arrived.
    Partly,
    /// No clear answer: keep asking for the reply.
    Unknown,
}

/// The fragments of a long reply received so far.
#[derive(Debug, Default)]
pub(super) struct Fragments {
    parts: Vec<Option<Vec<u8>>>,
}

impl Fragments {
    /// Stores fragment `i` of `n`; true when all have arrived.
    pub(super) fn put(&mut self, i: u8, n: u8, data: &[u8]) -> bool {
        if self.parts.len() != usize::from(n) {
            self.parts = vec![None; usize::from(n)];
        }
        self.parts[usize::from(i)] = Some(data.to_vec());
        self.parts.iter().all(Option::is_some)
    }

    pub(super) fn received(&self) -> usize {
        self.parts.iter().filter(|p| p.is_some()).count()
    }

    /// Indices still missing, if any fragment at all has arrived.
    pub(super) fn missing(&self) -> Option<Vec<u8>> {
        (self.received() > 0).then(|| {
            self.parts
                .iter()
                .enumerate()
                .filter(|(_, p)| p.is_none())
                .map(|(i, _)| i as u8)
                // A short RESEND survives a noisy line; the rest are asked
                // for next time.
                .take(MAX_RESEND)
                .collect()
        })
    }

    pub(super) fn take(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.parts)
            .into_iter()
            .flatten()
            .flatten()
            .collect()
    }
}

/// Silent tries of a HELLO while reconnecting, before that attempt of the
/// reconnect loop is counted as failed.
pub(super) const RECOVERY_RETRIES: u32 = 3;

/// What a link brought during one request other than its reply.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Noise {
    bytes: u64,
    corrupt: u64,
    stale: u64,
    bad_frames: u64,
}

/// Whether `bytes` hold a telnet negotiation (IAC then WILL, WONT, DO or
/// DONT): the server speaks telnet, as an RFC 2217 port does (ser2net
/// opens with `IAC WILL SUPPRESS-GO-AHEAD`).
pub(super) fn telnet_negotiation(bytes: &[u8]) -> bool {
    bytes
        .windows(2)
        .any(|w| w[0] == 0xFF && (0xFB..=0xFE).contains(&w[1]))
}

/// What a "no answer" adds when the link spoke telnet.
const TELNET_HINT: &str = "; among them a telnet negotiation: the server speaks telnet, as an RFC 2217 port does (try rfc2217:// in place of tcp://)";

impl std::fmt::Display for Noise {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.bytes == 0 {
            return f.write_str("nothing came back");
        }
        write!(
            f,
            "{} bytes came back: {} corrupt frames, {} replies to other requests, {} bad-frame errors",
            self.bytes, self.corrupt, self.stale, self.bad_frames
        )
    }
}

impl<L: Link> BridgeTarget<L> {
    /// Sends a request and waits for its reply, asking again for what was
    /// lost or corrupted (the whole reply, or the missing fragments of a
    /// long one) and reopening a vanished link. Gives up after `retries`
    /// attempts in a row that brought nothing new.
    pub(super) fn request(
        &mut self,
        req: &Request,
        what: &str,
        extra: WallDuration,
    ) -> Result<Response, BridgeError> {
        if self.want_fragment != self.fragment && self.link_ok && !self.recovering {
            self.set_fragment(self.want_fragment)?;
        }
        let garbled = self.garbled;
        let r = self.exchange(req, what, extra).map_err(|e| {
            let seq = self.in_flight.unwrap_or(self.seq);
            self.abort_after(req, seq, e)
        });
        if !matches!(req, Request::Link { .. }) {
            // Only a garbled frame says the line is noisy: a lost reply, a
            // stall or a dropped connection does not ask for smaller ones.
            if self.garbled > garbled {
                self.clean = 0;
                self.want_fragment = (self.fragment / 2).max(MIN_FRAGMENT_DATA as u8);
            } else {
                self.clean += 1;
                if self.clean >= CLEAN_TO_GROW {
                    self.clean = 0;
                    self.want_fragment = self.fragment.saturating_mul(2).min(FRAGMENT_DATA as u8);
                }
            }
        }
        r
    }

    /// Asks the bridge for reply fragments of `size` data bytes. A bridge
    /// that does not know LINK (UNKNOWN_OP) keeps its own, and is not
    /// asked again.
    pub(super) fn set_fragment(&mut self, size: u8) -> Result<(), BridgeError> {
        self.set_link(size, self.pad)
    }

    /// Sets the reply fragment size and padding (LINK).
    pub(super) fn set_link(&mut self, fragment: u8, pad: u16) -> Result<(), BridgeError> {
        match self.exchange(&Request::Link { fragment, pad }, "link", WallDuration::ZERO)? {
            Response::Link { fragment, pad } => {
                self.fragment = fragment;
                self.want_fragment = fragment;
                self.pad = pad;
            }
            Response::Error {
                code: BridgeErrorCode::UnknownOp,
                ..
            } => self.link_ok = false,
            other => return Err(self.unexpected("link", &other)),
        }
        Ok(())
    }

    /// One request and its reply, asked again as the line needs, within
    /// the limits of [`BridgeOptions`] (fewer while reconnecting). `span`
    /// is the bridge time the request's own waits may take: wall time on a
    /// real-time bridge; on a bridge in virtual time, its clock, which its
    /// WORKING messages report while it runs the request.
    pub(super) fn exchange(
        &mut self,
        req: &Request,
        what: &str,
        span: WallDuration,
    ) -> Result<Response, BridgeError> {
        let extra = match self.hello.virtual_time {
            true => WallDuration::ZERO,
            false => span,
        };
        // The most bridge time the request may take, progress or not.
        let bridge_bound = span + self.opts.request_limit();
        let mut bridge_elapsed = WallDuration::ZERO;
        let seq = self.next_seq();
        if !self.recovering {
            self.in_flight = Some(seq);
            self.sent = false;
        }
        let payload = req.encode(seq, self.timer);
        let splittable = payload.len() > MIN_REQUEST;
        let full = frame::encode(&payload);
        let mut frags = Fragments::default();
        let mut next = full.clone();
        // While reconnecting, a hello that hears nothing after a few tries
        // fails this attempt of the reconnect loop, which has its own limit.
        let retries = match self.recovering {
            true => self.opts.retries.min(RECOVERY_RETRIES),
            false => self.opts.retries,
        };
        let start = WallInstant::now();
        let stall_limit = extra + self.opts.reply_timeout * (retries + 1);
        let base = later(start, extra + self.opts.request_limit());
        // A bridge's WORKING messages stretch that by its progress alone:
        // its clock's run, taken at 1/SLOWEST_BRIDGE of real time. A clock
        // that creeps gains nothing; one that runs is waited for.
        let mut give_up_at = base;
        let mut progress_at = start;
        // What the link brought instead of the reply, for the error.
        let mut noise = Noise::default();
        // Silent attempts reconnect once before the request is given up: a
        // network connection can die without a word (a half-open TCP
        // connection, a server that stalls).
        let mut reconnected = self.recovering;
        // Reconnects since the last progress: a server that takes every
        // connection and drops it again ends the request, not a loop.
        let mut reconnects = 0;
        // A probe of `ran` went unanswered: its "no reply" may still come,
        // after the request was sent again, and would then be stale.
        let mut probe_lost = false;
        // Attempts in a row that brought nothing new: `silent` ones heard
        // nothing at all (a dead link: `retries` of them end the request),
        // `fruitless` ones at most heard garbage (a live, noisy line: it
        // gets ten times as many).
        let mut fruitless = 0;
        let mut silent = 0;
        let mut garbled = 0;
        let mut attempts = 0u32;
        let mut wait = self.rtt.timeout(&self.opts);
        // A bridge that says WORKING says it 10 ms into a request at the
        // latest (and every 50 ms): not asked again before it could have.
        if self.stats.working > 0 {
            wait = wait.max(WORKING_WAIT);
        }
        let mut pause = WallDuration::ZERO;
        loop {
            if self.opts.stop.requested() {
                return Err(self.interrupted());
            }
            if self.past_deadline() {
                return Err(BridgeError::PastDeadline {
                    link: self.link.name(),
                    what: what.to_string(),
                    abort: AbortOutcome::NotSent,
                });
            }
            let now = WallInstant::now();
            let stalled = now >= progress_at + stall_limit || now >= give_up_at;
            let out_of_tries = silent > retries || fruitless > retries * NOISY_RETRIES;
            // The last attempts heard nothing at all, whatever came before.
            let gone_quiet = silent > retries || (stalled && silent > 0);
            if gone_quiet && !reconnected {
                // Nothing comes back any more: reconnect, then try again.
                reconnected = true;
                let silence =
                    io::Error::new(io::ErrorKind::TimedOut, format!("no answer to {what}"));
                match self.recover(silence) {
                    Ok(()) => {}
                    // Say what went unanswered, and that reconnecting did
                    // not help.
                    Err(BridgeError::LinkLost {
                        attempts: reconnects,
                        last,
                        ..
                    }) => {
                        return Err(self.no_answer(
                            what,
                            attempts,
                            start,
                            format!(
                                "nothing came back, and {reconnects} attempts to reconnect failed: {last}"
                            ),
                        ))
                    }
                    Err(e) => return Err(e),
                }
                next = self.after_reconnect(req, seq, &mut frags, &full);
                (silent, fruitless, progress_at) = (0, 0, WallInstant::now());
                continue;
            }
            if stalled || out_of_tries {
                break;
            }
            if attempts > 0 {
                self.stats.retransmissions += 1;
                if self.opts.stop.sleep(pause) {
                    return Err(self.interrupted());
                }
            }
            attempts += 1;
            if let Err(e) = self.link.send(&next) {
                reconnects += 1;
                if reconnects > self.opts.reopen_attempts && !self.recovering {
                    return Err(self.dropped_again(what, attempts, start, e));
                }
                self.link_failed(e)?;
                next = self.after_reconnect(req, seq, &mut frags, &full);
                fruitless += 1;
                silent += 1;
                continue;
            }
            let sent = WallInstant::now();
            if !self.recovering {
                self.sent = true;
            }
            self.stats.round_trips += 1;
            let had = frags.received();
            let mut budget = (wait + extra).min(give_up_at.saturating_duration_since(sent));
            let reply = loop {
                match self.await_reply(seq, budget, give_up_at, &mut frags, &mut noise) {
                    // The bridge has the request and is running it, slower
                    // than real time: wait by its clock, as long as it
                    // advances and stays within the request's bound.
                    Ok(Some(Response::Working { elapsed })) => {
                        let elapsed = WallDuration::from_nanos(elapsed.as_nanos());
                        if elapsed > bridge_bound {
                            return Err(self.no_answer(
                                what,
                                attempts,
                                start,
                                format!(
                                    "the bridge says it is still working on it after {:.3} s of its own clock, past the {:.3} s the request may take",
                                    elapsed.as_secs_f64(),
                                    bridge_bound.as_secs_f64()
                                ),
                            ));
                        }
                        self.stats.working += 1;
                        let now = WallInstant::now();
                        if elapsed > bridge_elapsed {
                            bridge_elapsed = elapsed;
                            (silent, fruitless) = (0, 0);
                            progress_at = now;
                            let earned = bridge_elapsed.saturating_mul(SLOWEST_BRIDGE);
                            give_up_at = give_up_at.max(later(base, earned));
                        } else if now >= progress_at + stall_limit {
                            // WORKING whose clock stands still: no progress.
                            break Ok(None);
                        }
                        budget = self
                            .opts
                            .reply_timeout
                            .min(give_up_at.saturating_duration_since(now));
                    }
                    other => break other,
                }
            };
            match reply {
                Ok(Some(Response::Error {
                    code: BridgeErrorCode::BadFrame,
                    ..
                })) => {
                    noise.bad_frames += 1;
                    self.garbled += 1;
                    garbled += 1;
                    // Our RESEND or request was garbled on the way: ask
                    // again as before, never mixing fragments of two runs.
                    next = match frags.missing() {
                        Some(m) => {
                            frame::encode(&Request::Resend { fragments: m }.encode(seq, self.timer))
                        }
                        None => full.clone(),
                    };
                    if garbled >= 2 && frags.received() == 0 && splittable {
                        // Too long for this line? Only if the bridge never
                        // ran it: a bad-frame error does not say which frame
                        // was bad, so ask before splitting.
                        match self.ran(seq, give_up_at, &mut frags, &mut noise, &mut probe_lost)? {
                            Ran::No if probe_lost => {}
                            Ran::No => {
                                return Err(BridgeError::Garbled {
                                    link: self.link.name(),
                                    len: payload.len(),
                                })
                            }
                            Ran::Yes(r) => return Ok(r),
                            Ran::Partly | Ran::Unknown => {
                                if let Some(m) = frags.missing() {
                                    next = frame::encode(
                                        &Request::Resend { fragments: m }.encode(seq, self.timer),
                                    );
                                }
                            }
                        }
                    }
                }
                // A late answer to a probe that went unanswered: stale, not
                // this request's reply (a request is never answered so).
                Ok(Some(Response::Error {
                    code: BridgeErrorCode::Malformed,
                    detail,
                })) if probe_lost && detail.contains("no reply to sequence") => {
                    noise.stale += 1;
                    next = full.clone();
                }
                Ok(Some(r)) => {
                    // Karn's rule: only an exchange that was not repeated
                    // times the link, and only one with no waits of its own.
                    if attempts == 1 && extra.is_zero() && bridge_elapsed.is_zero() {
                        self.rtt.sample(sent.elapsed());
                    }
                    return Ok(r);
                }
                Ok(None) => {
                    next = match frags.missing() {
                        Some(m) => {
                            frame::encode(&Request::Resend { fragments: m }.encode(seq, self.timer))
                        }
                        None => full.clone(),
                    }
                }
                Err(e) => {
                    reconnects += 1;
                    if reconnects > self.opts.reopen_attempts && !self.recovering {
                        return Err(self.dropped_again(what, attempts, start, e));
                    }
                    self.link_failed(e)?;
                    next = self.after_reconnect(req, seq, &mut frags, &full);
                }
            }
            if frags.received() > had {
                reconnects = 0;
                fruitless = 0;
                silent = 0;
                pause = WallDuration::ZERO;
                progress_at = WallInstant::now();
            } else {
                fruitless += 1;
                // Back off: after silence, wait longer for the reply (a
                // slow or busy bridge; a garbled reply was heard, so its
                // wait was long enough); and pause longer before asking
                // again (a burst of noise).
                if self.heard {
                    silent = 0;
                } else {
                    silent += 1;
                    wait = (wait * 2).min(self.opts.reply_timeout);
                }
                pause = if pause.is_zero() {
                    FIRST_RETRY_PAUSE
                } else {
                    (pause * 2).min(MAX_RETRY_PAUSE)
                };
            }
        }
        Err(self.no_answer(what, attempts, start, noise.to_string()))
    }

    /// The error of a request given up after `tries` since `start`, and
    /// what the link brought instead.
    pub(super) fn no_answer(
        &self,
        what: &str,
        tries: u32,
        start: WallInstant,
        heard: String,
    ) -> BridgeError {
        BridgeError::NoAnswer {
            link: self.link.name(),
            what: what.into(),
            tries,
            secs: start.elapsed().as_secs_f64(),
            heard: match self.telnet && self.link.name().starts_with("tcp://") {
                true => heard + TELNET_HINT,
                false => heard,
            },
        }
    }

    /// The next sequence number: never 0 (the bridge's own errors carry
    /// 0), and, while reconnecting, never the request in flight's, so that
    /// a RESEND for its reply can only find its reply.
    pub(super) fn next_seq(&mut self) -> u8 {
        loop {
            self.seq = self.seq.wrapping_add(1);
            if self.seq != 0 && !(self.recovering && self.in_flight == Some(self.seq)) {
                return self.seq;
            }
        }
    }

    /// What to send after a reconnect: the fragments of the reply still
    /// missing (the bridge answers a RESEND from the reply it cached, which
    /// it kept for this host across the reconnect), or the whole request
    /// again when none has arrived, which the bridge answers from its cache
    /// if it ran it (section 3: at most once).
    ///
    /// A HELLO or LINK is sent whole again, its fragments so far dropped:
    /// it changes nothing on the chip, the bridge keeps the reply of only
    /// the newest one (the reconnect's own HELLO), and its new reply may
    /// differ from the first (a HELLO's `resumed`).
    pub(super) fn after_reconnect(
        &self,
        req: &Request,
        seq: u8,
        frags: &mut Fragments,
        full: &[u8],
    ) -> Vec<u8> {
        match frags.missing() {
            Some(m) if !matches!(req, Request::Hello { .. } | Request::Link { .. }) => {
                frame::encode(&Request::Resend { fragments: m }.encode(seq, self.timer))
            }
            _ => {
                *frags = Fragments::default();
                full.to_vec()
            }
        }
    }

    /// A request whose connection kept dropping with no progress between.
    pub(super) fn dropped_again(
        &self,
        what: &str,
        tries: u32,
        start: WallInstant,
        e: io::Error,
    ) -> BridgeError {
        let heard = format!(
            "the connection dropped {} times with nothing gained between (the last: {e})",
            self.opts.reopen_attempts + 1
        );
        self.no_answer(what, tries, start, heard)
    }

    /// Counts a frame that arrived corrupt.
    pub(super) fn corrupt(&mut self, noise: &mut Noise) {
        self.stats.corrupt_frames += 1;
        self.garbled += 1;
        noise.corrupt += 1;
    }

    /// Whether a scenario's `--timeout` has passed
    /// ([`Target::set_deadline`](crate::backend::Target::set_deadline)).
    pub(super) fn past_deadline(&self) -> bool {
        self.deadline.is_some_and(|d| WallInstant::now() >= d)
    }

    /// The error for a stop request.
    pub(super) fn interrupted(&self) -> BridgeError {
        BridgeError::Interrupted {
            link: self.link.name(),
            abort: AbortOutcome::NotSent,
        }
    }

    /// After the link failed mid-exchange: reconnects (the exchange then
    /// sends its request again), or, while already reconnecting, fails
    /// this attempt of the reconnect loop.
    pub(super) fn link_failed(&mut self, e: io::Error) -> Result<(), BridgeError> {
        if self.opts.stop.requested() {
            return Err(self.interrupted());
        }
        if self.recovering {
            return Err(BridgeError::Io {
                path: self.link.name(),
                source: e,
            });
        }
        self.recover(e)
    }

    /// Asks the bridge whether it ran request `seq` (a RESEND of its first
    /// reply fragment): it answers with the cached reply if it did, and with
    /// an error naming the sequence if it did not.
    ///
    /// A "no reply" is believed only while no probe of this request has
    /// gone unanswered (`probe_lost`): a late answer to a lost probe may
    /// come after the request was sent again and ran.
    pub(super) fn ran(
        &mut self,
        seq: u8,
        hard_end: WallInstant,
        frags: &mut Fragments,
        noise: &mut Noise,
        probe_lost: &mut bool,
    ) -> Result<Ran, BridgeError> {
        let probe = frame::encode(&Request::Resend { fragments: vec![0] }.encode(seq, self.timer));
        for _ in 0..=self.opts.retries {
            self.stats.retransmissions += 1;
            if let Err(e) = self.link.send(&probe) {
                self.link_failed(e)?;
                return Ok(Ran::Unknown);
            }
            self.stats.round_trips += 1;
            let before = frags.received();
            if WallInstant::now() >= hard_end {
                return Ok(Ran::Unknown);
            }
            match self.await_reply(seq, self.rtt.timeout(&self.opts), hard_end, frags, noise) {
                Ok(Some(Response::Error {
                    code: BridgeErrorCode::Malformed,
                    detail,
                })) if detail.contains("no reply to sequence") => return Ok(Ran::No),
                Ok(Some(Response::Error {
                    code: BridgeErrorCode::BadFrame,
                    ..
                })) => {
                    noise.bad_frames += 1;
                    self.garbled += 1;
                }
                // Still running it: it has the request, not yet a reply.
                Ok(Some(Response::Working { .. })) => return Ok(Ran::Unknown),
                Ok(Some(r)) => return Ok(Ran::Yes(r)),
                Ok(None) if frags.received() > before => return Ok(Ran::Partly),
                Ok(None) if self.opts.stop.requested() => return Err(self.interrupted()),
                Ok(None) => *probe_lost = true,
                Err(e) => {
                    self.link_failed(e)?;
                    return Ok(Ran::Unknown);
                }
            }
        }
        Ok(Ran::Unknown)
    }

    /// Reads until the reply to `seq` is complete (`Some`), or the link
    /// goes quiet, the timeout passes without it or a stop is asked for
    /// (`None`: ask again, or stop).
    /// It never waits past `hard_end`, the request's own deadline.
    pub(super) fn await_reply(
        &mut self,
        seq: u8,
        timeout: WallDuration,
        hard_end: WallInstant,
        frags: &mut Fragments,
        noise: &mut Noise,
    ) -> io::Result<Option<Response>> {
        let start = WallInstant::now();
        let mut deadline = (start + timeout).min(hard_end);
        // A reply still arriving is waited for, as long as bytes keep
        // coming (a slow line, a long reply), but not for ever.
        let latest = (start + timeout.max(self.opts.reply_timeout) * 4).min(hard_end);
        // The round trip does not change while waiting: the gap allowed
        // between bytes of a reply still arriving, and the quiet after a
        // corrupted frame, are fixed for this wait.
        let gap = self.rtt.timeout(&self.opts);
        let quiet = self.opts.quiet.min(gap);
        self.heard = false;
        // After a corrupted frame, stop waiting once the line is quiet.
        let mut quiet_by: Option<WallInstant> = None;
        let mut buf = [0u8; 4096];
        loop {
            loop {
                match self.decoder.decode() {
                    Ok(Some(payload)) => {
                        if let Some((s, i, n, data)) = parse_fragment(&payload) {
                            if s != seq {
                                noise.stale += 1;
                            } else if frags.put(i, n, data) {
                                match Response::decode(&frags.take(), self.timer) {
                                    Ok((_, r)) => return Ok(Some(r)),
                                    Err(_) => self.corrupt(noise),
                                }
                            }
                            continue;
                        }
                        match Response::decode(&payload, self.timer) {
                            // A bad-frame error carries seq 0: our request was
                            // garbled on the way.
                            Ok((
                                _,
                                r @ Response::Error {
                                    code: BridgeErrorCode::BadFrame,
                                    ..
                                },
                            )) => {
                                return Ok(Some(r));
                            }
                            Ok((s, r)) if s == seq => return Ok(Some(r)),
                            // A stale reply to an earlier try, or a reply
                            // to nothing this host asked.
                            Ok(_) => noise.stale += 1,
                            Err(_) => self.corrupt(noise),
                        }
                    }
                    Ok(None) => break,
                    Err(_) => {
                        self.corrupt(noise);
                        quiet_by = Some(WallInstant::now() + quiet);
                    }
                }
            }
            let now = WallInstant::now();
            let until = quiet_by.map_or(deadline, |q| q.min(deadline));
            if now >= until || self.opts.stop.requested() || self.past_deadline() {
                return Ok(None);
            }
            let n = self
                .link
                .recv(&mut buf, (until - now).min(StopRequest::SLICE))?;
            if n > 0 {
                self.heard = true;
                noise.bytes += n as u64;
                // Only a raw link can bring telnet: an RFC 2217 link reads
                // it away itself.
                self.telnet |= telnet_negotiation(&buf[..n]);
                deadline = deadline.max((WallInstant::now() + gap).min(latest));
            }
            if n > 0 && quiet_by.is_some() {
                quiet_by = Some(WallInstant::now() + quiet);
            }
            self.decoder.extend(&buf[..n]);
        }
    }

    /// Reopens a failed link and says HELLO again: a loop of at most
    /// `reopen_attempts`, with doubling backoff, where a connection that
    /// opens but fails before the bridge has answered HELLO counts as a
    /// failed attempt. The bridge must still be the same session holding
    /// this host's requests, or the run cannot trust the chip's state.
    pub(super) fn recover(&mut self, e: io::Error) -> Result<(), BridgeError> {
        let mut last = e.to_string();
        // The first attempt at once (a dropped network connection is
        // usually back at once), then with doubling backoff.
        let mut wait = WallDuration::ZERO;
        self.recovering = true;
        let r = (|| {
            for _ in 0..self.opts.reopen_attempts {
                if self.opts.stop.urgent() || self.opts.stop.sleep(wait) {
                    return Err(self.interrupted());
                }
                wait = (wait * 2).max(self.opts.backoff);
                if let Err(e) = self.link.reopen() {
                    last = e.to_string();
                    continue;
                }
                self.stats.reopens += 1;
                self.decoder = FrameDecoder::new();
                // A delimiter first: whatever part of a frame the bridge
                // kept from before the drop ends there, not in our HELLO.
                if let Err(e) = self.link.send(&[0]) {
                    last = e.to_string();
                    continue;
                }
                match self.say_hello() {
                    Ok(_) => return Ok(()),
                    // The link failed again, or the bridge said nothing:
                    // another attempt.
                    Err(e @ (BridgeError::Io { .. } | BridgeError::NoAnswer { .. })) => {
                        last = e.to_string()
                    }
                    Err(e) => return Err(e),
                }
            }
            Err(BridgeError::LinkLost {
                link: self.link.name(),
                attempts: self.opts.reopen_attempts,
                last: last.clone(),
            })
        })();
        self.recovering = false;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::telnet_negotiation;

    /// Issue 42: `tcp://` aimed at an RFC 2217 port said only "204 corrupt
    /// frames"; a telnet negotiation among the bytes is noticed (and the
    /// "no answer" then says what to try: cli_network.rs).
    #[test]
    fn a_telnet_negotiation_is_told_from_frame_bytes() {
        assert!(!telnet_negotiation(&[0x00, 0x12, 0xFF, 0x34]));
        // As ser2net opens: IAC WILL SUPPRESS-GO-AHEAD, IAC DO ...
        assert!(telnet_negotiation(&[0xFF, 0xFB, 0x03, 0xFF, 0xFD, 0x03]));
    }
}
