//! A board behind the serial bus bridge: the [`Target`] backend that speaks
//! the bridge protocol (`docs/bridge-protocol.md`) over a [`Link`].
//!
//! Every request carries a sequence number and the bridge answers a
//! retransmitted request from its cache without running it again, so a
//! lost or corrupted reply is simply asked for again. A link that vanishes
//! (a USB re-enumeration, a dropped TCP connection) is reopened with
//! backoff a bounded number of times, and the host says HELLO with its own
//! host session again: the bridge keeps its cache across that, so the
//! request in flight, sent again, still runs at most once. If the bridge
//! comes back as a different session (it restarted) or without this host's
//! cache (another host used it), the run cannot go on safely and the error
//! says so.
//!
//! Every wait has an end (`docs/bridge-protocol.md` section 8): a request
//! gives up after `retries` silent attempts, after a stretch without
//! progress however much noise arrives, and at an absolute deadline; a
//! reconnection is a loop of at most `reopen_attempts`; after
//! [`MAX_GIVE_UPS`] requests given up the link is not trusted for the rest
//! of the run. A [`Stop`] request ends any wait within [`Stop::SLICE`].

mod labgrid;
mod link;
mod rfc2217;
mod tcp;

pub use self::labgrid::{parse_labgrid, LabgridLink, Place};
pub(crate) use self::link::timed_out;
pub use self::link::{parse_spec, Link, SerialLink};
pub use self::rfc2217::{parse_rfc2217, Rfc2217Link};
pub use self::tcp::{parse_tcp, TcpLink};

use super::{
    Op, Reply, SelfTestPlan, SelfTestRun, Target, TargetError, TargetErrorKind, TargetInfo,
};
use crate::protocol::Record;
use crate::protocol::Straps;
use crate::stop::Stop;
use crate::time::Instant;
use ppmc_core::bridge::frame::{self, FrameDecoder};
use ppmc_core::bridge::wire::MAX_BATCH_OPS;
use ppmc_core::bridge::wire::{
    self, parse_fragment, BridgeErrorCode, CaptureChunk, Hello, Request, Response, Timer,
    FRAGMENT_DATA, MIN_FRAGMENT_DATA, PROTOCOL_VERSION,
};
use std::io;
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// Why talking to a bridge failed.
#[derive(Debug, thiserror::Error)]
pub enum SerialError {
    #[error("{path}: no such serial port (is the bridge plugged in?)")]
    PortMissing { path: String },
    #[error("{path}: port busy or not accessible ({detail}); is another program using it?")]
    PortBusy { path: String, detail: String },
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: io::Error,
    },
    #[error("{link}: no bridge answering: no valid reply to {what} after {tries} tries in {secs:.1} s ({heard})")]
    NoAnswer {
        link: String,
        what: String,
        tries: u32,
        /// Wall time spent on the request.
        secs: f64,
        /// What the link brought instead: nothing, noise, replies to other
        /// requests, errors.
        heard: String,
    },
    #[error("{link}: bridge speaks protocol version {theirs}, this ppmc speaks {ours}")]
    Version {
        link: String,
        ours: u16,
        theirs: u16,
    },
    #[error("{link}: the bridge answered {code} to {what}: {detail}")]
    Bridge {
        link: String,
        what: String,
        code: BridgeErrorCode,
        detail: String,
    },
    #[error("{link}: the bridge's capture buffer overran; pulses were lost ({detail})")]
    CaptureOverrun { link: String, detail: String },
    #[error("{link}: unexpected reply to {what}: {detail}")]
    Protocol {
        link: String,
        what: String,
        detail: String,
    },
    #[error("{link}: link lost and not back after {attempts} reopen attempts ({last})")]
    LinkLost {
        link: String,
        attempts: u32,
        last: String,
    },
    #[error("{link}: the bridge restarted (session {old:08x} -> {new:08x}){}; the chip's state is unknown", why.as_ref().map(|w| format!(" after {w}")).unwrap_or_default())]
    Restarted {
        link: String,
        old: u32,
        new: u32,
        /// What the bridge says restarted it, from its new HELLO (the RP2350
        /// image's panic record: `a panic at cycles.rs:123`).
        why: Option<String>,
    },
    /// After a reconnect the bridge no longer held this host's cached
    /// request: another host said HELLO to it while the link was down, and
    /// may have used the chip.
    #[error("{link}: after reconnecting, the bridge no longer holds this host's requests (another host used it while the link was down); the chip's state is unknown")]
    Displaced { link: String },
    /// The link gave up on too many requests in this run to be trusted
    /// with another.
    #[error("{link}: the link gave up on {failures} requests in this run, and is not used for more (the last: {last})")]
    Exhausted {
        link: String,
        failures: u32,
        last: String,
    },
    /// A stop was asked for (SIGINT, SIGTERM) while waiting on the link.
    #[error("{link}: interrupted by a stop request")]
    Interrupted { link: String },
    /// A reply came back timed before an earlier one, with no chip reset
    /// in between: the bridge restarted behind the open port (a watchdog,
    /// a brown-out) and the chip's state was lost with it.
    #[error("{link}: the bridge's clock went back from {was} to {now} without a chip reset: the bridge restarted behind the open port and the chip's state is unknown")]
    ClockWentBack {
        link: String,
        was: Instant,
        now: Instant,
    },
    #[error("{link}: health check failed: {detail}")]
    Unhealthy { link: String, detail: String },
    /// A request of `len` bytes kept arriving garbled; the bridge has not
    /// run it. Batches are then sent in smaller requests.
    #[error("{link}: a {len}-byte request keeps arriving garbled")]
    Garbled { link: String, len: usize },
}

impl SerialError {
    pub fn kind(&self) -> TargetErrorKind {
        match self {
            SerialError::Version { .. } => TargetErrorKind::Unsupported,
            SerialError::Interrupted { .. } => TargetErrorKind::Interrupted,
            // An error or a reply of the wrong kind to a well-formed
            // request is the bridge's or the link's doing (a firmware bug,
            // something else answering on the port), never the chip's.
            _ => TargetErrorKind::Link,
        }
    }
}

impl From<SerialError> for TargetError {
    fn from(e: SerialError) -> Self {
        TargetError::new(e.kind(), e)
    }
}

/// Retry and timeout policy.
///
/// The host learns the link's round-trip time from clean exchanges and
/// waits for a reply a few times that (never less than `min_reply_timeout`,
/// never more than `reply_timeout`), plus the time the batch's own waits
/// take on a real-time bridge. Each attempt in a row that brings nothing
/// new doubles the pause before the next try, and one that heard nothing at
/// all also doubles the wait (exponential backoff, as TCP's retransmission
/// timer does). `retries` silent attempts in a row end the request as a
/// link error; a line that answers, however garbled, is alive and gets ten
/// times as many.
#[derive(Debug, Clone)]
pub struct SerialOptions {
    /// The longest wait for a reply beyond the time the batch itself needs
    /// (the first waits, before the round-trip time is known, and the cap
    /// of the backoff).
    pub reply_timeout: WallDuration,
    /// The shortest wait for a reply, however fast the link has been.
    pub min_reply_timeout: WallDuration,
    /// Silent attempts in a row before a request is given up (after the
    /// first try); ten times as many that heard only garbage.
    pub retries: u32,
    /// Reopen attempts after the link vanished, with doubling backoff.
    pub reopen_attempts: u32,
    /// The first reopen backoff.
    pub backoff: WallDuration,
    /// After a corrupted frame, how long the line must stay silent before
    /// the host asks again (rather than waiting out the reply timeout); at
    /// most this, and less on a link that answers faster.
    pub quiet: WallDuration,
    /// Ask the bridge to pad every reply with empty frames to a multiple of
    /// this many bytes (LINK), so that a serial server in between that
    /// holds a partly filled buffer (ser2net's 64 bytes) sends it at once;
    /// 0 for none.
    pub pad: u16,
    /// Asked for, every wait on the link ends within [`Stop::SLICE`] with
    /// [`SerialError::Interrupted`].
    pub stop: Stop,
}

impl SerialOptions {
    /// How long a request may go without progress (no new reply or
    /// fragment), however much noise arrives, before it is given up:
    /// `reply_timeout` for every attempt it may make in silence.
    pub fn stall_limit(&self) -> WallDuration {
        self.reply_timeout * (self.retries + 1)
    }

    /// The longest a request may take beyond its own waits, progress or
    /// not: three stall limits.
    pub fn request_limit(&self) -> WallDuration {
        self.stall_limit() * 3
    }
}

impl Default for SerialOptions {
    fn default() -> Self {
        SerialOptions {
            reply_timeout: WallDuration::from_millis(1000),
            min_reply_timeout: WallDuration::from_millis(20),
            retries: 10,
            reopen_attempts: 6,
            backoff: WallDuration::from_millis(100),
            quiet: WallDuration::from_millis(30),
            pad: 0,
            stop: Stop::default(),
        }
    }
}

/// Requests a link may give up on in one run: past that it is not used
/// for more, so that a link that only works now and then ends a run in
/// bounded time instead of costing every scenario its stall limit.
pub const MAX_GIVE_UPS: u32 = 3;

/// The pause before the first retry after a fruitless attempt; it doubles
/// with each one in a row, up to [`MAX_RETRY_PAUSE`].
const FIRST_RETRY_PAUSE: WallDuration = WallDuration::from_millis(1);
const MAX_RETRY_PAUSE: WallDuration = WallDuration::from_millis(16);

/// The link's round-trip time, smoothed as TCP does (RFC 6298): from
/// exchanges answered at the first try whose batch had no waits of its own.
#[derive(Debug, Clone, Copy, Default)]
struct RoundTrip {
    srtt: Option<WallDuration>,
    rttvar: WallDuration,
}

impl RoundTrip {
    fn sample(&mut self, rtt: WallDuration) {
        match self.srtt {
            None => {
                self.srtt = Some(rtt);
                self.rttvar = rtt / 2;
            }
            Some(s) => {
                let err = s.abs_diff(rtt);
                self.rttvar = (self.rttvar * 3 + err) / 4;
                self.srtt = Some((s * 7 + rtt) / 8);
            }
        }
    }

    /// How long to wait for a reply: `srtt + 4 rttvar`, within the bounds.
    fn timeout(&self, opts: &SerialOptions) -> WallDuration {
        match self.srtt {
            None => opts.reply_timeout,
            Some(s) => (s + self.rttvar * 4)
                .max(opts.min_reply_timeout)
                .min(opts.reply_timeout),
        }
    }
}

/// Request payload sizes the host adapts between: large on a clean line
/// (fewer round trips), small on a noisy one (small frames survive it). A
/// batch split over several requests runs the same.
const MAX_REQUEST: usize = 2048;
const MIN_REQUEST: usize = 16;

/// A line that answers, however garbled, is alive: a request gets this
/// many times `retries` attempts that bring nothing new before it is given
/// up, where a silent one gets `retries`.
const NOISY_RETRIES: u32 = 10;

/// Most fragments one RESEND asks for.
const MAX_RESEND: usize = 8;

/// After this many requests in a row that needed no second try, the host
/// asks for reply fragments twice as large again (up to the largest).
const CLEAN_TO_GROW: u32 = 8;

/// The most bytes the reply entries to one request may take, at worst:
/// with the capture chunk the bridge adds (which it shrinks to fit), a
/// reply stays within [`wire::MAX_REPLY`].
const REPLY_ENTRIES_BUDGET: usize = 10 * 1024;

/// The most capture records (pulse runs and pin changes) the host takes
/// from one bridge between chip resets, whatever its HELLO says: a
/// 16,777,216-step move is a few hundred.
const MAX_CAPTURE_RECORDS: usize = 4_000_000;

/// Records asked for per capture request.
const CAPTURE_CHUNK: u16 = 300;

/// What the bridge says of a request that kept arriving garbled.
#[derive(Debug)]
enum Ran {
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
struct Fragments {
    parts: Vec<Option<Vec<u8>>>,
}

impl Fragments {
    /// Stores fragment `i` of `n`; true when all have arrived.
    fn put(&mut self, i: u8, n: u8, data: &[u8]) -> bool {
        if self.parts.len() != usize::from(n) {
            self.parts = vec![None; usize::from(n)];
        }
        self.parts[usize::from(i)] = Some(data.to_vec());
        self.parts.iter().all(Option::is_some)
    }

    fn received(&self) -> usize {
        self.parts.iter().filter(|p| p.is_some()).count()
    }

    /// Indices still missing, if any fragment at all has arrived.
    fn missing(&self) -> Option<Vec<u8>> {
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

    fn take(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.parts)
            .into_iter()
            .flatten()
            .flatten()
            .collect()
    }
}

/// What the link has cost so far (for reports and `docs/performance.md`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    pub round_trips: u64,
    pub retransmissions: u64,
    pub corrupt_frames: u64,
    pub reopens: u64,
}

/// A chip behind a bus bridge.
#[derive(Debug)]
pub struct SerialTarget<L: Link> {
    link: L,
    decoder: FrameDecoder,
    seq: u8,
    hello: Hello,
    timer: Timer,
    opts: SerialOptions,
    /// The capture fetched so far (since the last chip reset).
    captured: Record,
    /// `captured` is the whole capture as of now: the last request brought
    /// the rest of it back, and the bridge's chip has not moved on since
    /// (it runs in virtual time, so nothing happens between requests).
    captured_current: bool,
    /// The link's measured round-trip time.
    rtt: RoundTrip,
    /// Whether the last [`Self::await_reply`] received any byte at all.
    heard: bool,
    /// Data bytes per reply fragment in force on the bridge (LINK), and
    /// the size wanted: halved after a request whose reply needed asking
    /// again, doubled back after [`CLEAN_TO_GROW`] clean ones.
    fragment: u8,
    want_fragment: u8,
    /// The reply padding in force on the bridge (LINK).
    pad: u16,
    /// Clean requests in a row.
    clean: u32,
    /// The bridge answers LINK (one that refuses it keeps 48-byte
    /// fragments, and is not asked again).
    link_ok: bool,
    /// The latest bridge time seen since the last chip reset: a reply
    /// timed before it means the bridge restarted.
    clock: Instant,
    /// The request size in force: halved when a request needed asking
    /// again, doubled back after clean ones.
    request_size: usize,
    /// This host's session, said in every HELLO (never 0): the bridge
    /// keeps its cached request across a reconnect for it.
    host: u32,
    /// The target is open: the bridge's session is known, and a HELLO
    /// after a reconnect must find it, and this host's requests, again.
    opened: bool,
    /// A reconnect is under way: a link error ends the attempt instead of
    /// starting another reconnect.
    recovering: bool,
    /// The sequence number of the request whose reply is awaited.
    in_flight: Option<u8>,
    /// Frames that arrived garbled, either way (corrupt frames here,
    /// bad-frame errors from the bridge): what makes the host shrink its
    /// requests and the bridge's reply fragments.
    garbled: u64,
    /// Requests given up so far, and the last reason.
    give_ups: u32,
    last_give_up: String,
    pub stats: LinkStats,
}

/// Silent tries of a HELLO while reconnecting, before that attempt of the
/// reconnect loop is counted as failed.
const RECOVERY_RETRIES: u32 = 3;

/// What a link brought during one request other than its reply.
#[derive(Debug, Default, Clone, Copy)]
struct Noise {
    bytes: u64,
    corrupt: u64,
    stale: u64,
    bad_frames: u64,
}

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

/// What a bridge's firmware text says restarted it: the RP2350 image ends
/// it in `; restarted after a panic at FILE:LINE` after a panic or a hard
/// fault (its panic record, kept across the watchdog's reset).
pub fn restart_cause(firmware: &str) -> Option<String> {
    let (_, cause) = firmware.rsplit_once("restarted after ")?;
    Some(cause.trim().to_string())
}

/// A host session: a number no other host is likely to pick, never 0.
fn host_session() -> u32 {
    use std::hash::{BuildHasher, Hash, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    std::process::id().hash(&mut h);
    std::time::SystemTime::now().hash(&mut h);
    WallInstant::now().hash(&mut h);
    let x = h.finish();
    ((x >> 32) as u32 ^ x as u32).max(1)
}

impl<L: Link> SerialTarget<L> {
    /// Says hello, then checks the board's health: a chip reset, and the
    /// status register reading 0x00 after it.
    pub fn open(link: L, opts: SerialOptions) -> Result<Self, SerialError> {
        let mut t = SerialTarget {
            link,
            decoder: FrameDecoder::new(),
            seq: 0,
            hello: Hello {
                version: PROTOCOL_VERSION,
                session: 0,
                timer_hz: Timer::NANOS.hz,
                max_batch_ops: 1,
                max_payload: 64,
                capture_capacity: 0,
                inputs_wired: 0,
                virtual_time: false,
                firmware: String::new(),
                straps: Straps::default(),
                resumed: false,
            },
            timer: Timer::NANOS,
            opts,
            captured: Record::default(),
            captured_current: false,
            clock: Instant::ZERO,
            rtt: RoundTrip::default(),
            heard: false,
            fragment: FRAGMENT_DATA as u8,
            want_fragment: FRAGMENT_DATA as u8,
            pad: 0,
            clean: 0,
            link_ok: true,
            request_size: MAX_REQUEST,
            host: host_session(),
            opened: false,
            recovering: false,
            in_flight: None,
            garbled: 0,
            give_ups: 0,
            last_give_up: String::new(),
            stats: LinkStats::default(),
        };
        t.hello = t.say_hello()?;
        t.timer = Timer {
            hz: t.hello.timer_hz,
        };
        // Always: a bridge keeps its LINK settings across hosts, and the
        // last one may have asked for padding this link does not want.
        if t.link_ok {
            t.set_link(t.fragment, t.opts.pad)?;
        }
        // From here on a reconnect must find this session again.
        t.opened = true;
        let replies = t
            .run_batch(&[Op::Reset, Op::ReadStatus])
            .map_err(|e| match e {
                e @ SerialError::Interrupted { .. } => e,
                e => SerialError::Unhealthy {
                    link: t.link.name(),
                    detail: e.to_string(),
                },
            })?;
        match replies.get(1) {
            Some(Reply::Status { status, .. }) if status.0 == 0 => Ok(t),
            Some(Reply::Status { status, .. }) => Err(SerialError::Unhealthy {
                link: t.link.name(),
                detail: format!(
                    "after a chip reset the status register reads 0x{:02X}, not 0x00",
                    status.0
                ),
            }),
            other => Err(SerialError::Unhealthy {
                link: t.link.name(),
                detail: match other {
                    Some(r) => format!("the status read after a chip reset got `{r}`"),
                    None => "no reply to the status read after a chip reset".into(),
                },
            }),
        }
    }

    pub fn hello(&self) -> &Hello {
        &self.hello
    }

    /// Says HELLO with this host's session and checks the version. Once the
    /// target is open, the bridge must be the same session, and must have
    /// kept this host's cached request (`resumed`): otherwise what the
    /// chip did while the link was down is unknown.
    fn say_hello(&mut self) -> Result<Hello, SerialError> {
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: self.host,
        };
        let reply = match self.request(&hello, "hello", WallDuration::ZERO) {
            // A line too noisy for the hello reply's 48-byte fragments:
            // ask for the smallest and say hello again (not while
            // reconnecting, where a silent bridge is told by the loop).
            Err(SerialError::NoAnswer { .. }) if self.link_ok && !self.recovering => {
                self.want_fragment = MIN_FRAGMENT_DATA as u8;
                self.request(&hello, "hello", WallDuration::ZERO)?
            }
            other => other?,
        };
        let h = match reply {
            Response::Hello(h) if h.version == PROTOCOL_VERSION => h,
            // Another bridge behind the same address (reflashed, swapped):
            // the link's doing, not a choice of the user's.
            Response::Hello(h) if self.opened => {
                return Err(SerialError::Protocol {
                    link: self.link.name(),
                    what: "hello after a reconnect".into(),
                    detail: format!(
                        "the bridge now speaks protocol version {}, not {PROTOCOL_VERSION}: another bridge answers",
                        h.version
                    ),
                })
            }
            Response::Hello(h) => {
                return Err(SerialError::Version {
                    link: self.link.name(),
                    ours: PROTOCOL_VERSION,
                    theirs: h.version,
                })
            }
            other => return Err(self.unexpected("hello", &other)),
        };
        if self.opened {
            if h.session != self.hello.session {
                return Err(SerialError::Restarted {
                    link: self.link.name(),
                    old: self.hello.session,
                    new: h.session,
                    why: restart_cause(&h.firmware),
                });
            }
            if !h.resumed {
                return Err(SerialError::Displaced {
                    link: self.link.name(),
                });
            }
        }
        Ok(h)
    }

    fn unexpected(&self, what: &str, r: &Response) -> SerialError {
        match r {
            Response::Error {
                code: BridgeErrorCode::Version,
                detail,
            } if !self.opened => SerialError::Version {
                link: self.link.name(),
                ours: PROTOCOL_VERSION,
                theirs: detail
                    .split_whitespace()
                    .find_map(|w| w.parse().ok())
                    .unwrap_or(0),
            },
            Response::Error {
                code: BridgeErrorCode::CaptureOverrun,
                detail,
            } => SerialError::CaptureOverrun {
                link: self.link.name(),
                detail: detail.clone(),
            },
            Response::Error { code, detail } => SerialError::Bridge {
                link: self.link.name(),
                what: what.into(),
                code: *code,
                detail: detail.clone(),
            },
            other => SerialError::Protocol {
                link: self.link.name(),
                what: what.into(),
                detail: format!("a {} message", other.name()),
            },
        }
    }

    /// Sends a request and waits for its reply, asking again for what was
    /// lost or corrupted (the whole reply, or the missing fragments of a
    /// long one) and reopening a vanished link. Gives up after `retries`
    /// attempts in a row that brought nothing new.
    fn request(
        &mut self,
        req: &Request,
        what: &str,
        extra: WallDuration,
    ) -> Result<Response, SerialError> {
        if self.want_fragment != self.fragment && self.link_ok && !self.recovering {
            self.set_fragment(self.want_fragment)?;
        }
        let garbled = self.garbled;
        let r = self.exchange(req, what, extra);
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
    fn set_fragment(&mut self, size: u8) -> Result<(), SerialError> {
        self.set_link(size, self.pad)
    }

    /// Sets the reply fragment size and padding (LINK).
    fn set_link(&mut self, fragment: u8, pad: u16) -> Result<(), SerialError> {
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
    /// the limits of [`SerialOptions`] (fewer while reconnecting).
    fn exchange(
        &mut self,
        req: &Request,
        what: &str,
        extra: WallDuration,
    ) -> Result<Response, SerialError> {
        let seq = self.next_seq();
        if !self.recovering {
            self.in_flight = Some(seq);
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
        let give_up_at = start + extra + self.opts.request_limit();
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
        let mut pause = WallDuration::ZERO;
        loop {
            if self.opts.stop.requested() {
                return Err(self.interrupted());
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
                    Err(SerialError::LinkLost {
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
            self.stats.round_trips += 1;
            let had = frags.received();
            let budget = (wait + extra).min(give_up_at.saturating_duration_since(sent));
            match self.await_reply(seq, budget, give_up_at, &mut frags, &mut noise) {
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
                                return Err(SerialError::Garbled {
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
                    if attempts == 1 && extra.is_zero() {
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
    fn no_answer(&self, what: &str, tries: u32, start: WallInstant, heard: String) -> SerialError {
        SerialError::NoAnswer {
            link: self.link.name(),
            what: what.into(),
            tries,
            secs: start.elapsed().as_secs_f64(),
            heard,
        }
    }

    /// The next sequence number: never 0 (the bridge's own errors carry
    /// 0), and, while reconnecting, never the request in flight's, so that
    /// a RESEND for its reply can only find its reply.
    fn next_seq(&mut self) -> u8 {
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
    fn after_reconnect(
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
    fn dropped_again(
        &self,
        what: &str,
        tries: u32,
        start: WallInstant,
        e: io::Error,
    ) -> SerialError {
        let heard = format!(
            "the connection dropped {} times with nothing gained between (the last: {e})",
            self.opts.reopen_attempts + 1
        );
        self.no_answer(what, tries, start, heard)
    }

    /// Counts a frame that arrived corrupt.
    fn corrupt(&mut self, noise: &mut Noise) {
        self.stats.corrupt_frames += 1;
        self.garbled += 1;
        noise.corrupt += 1;
    }

    /// The error for a stop request.
    fn interrupted(&self) -> SerialError {
        SerialError::Interrupted {
            link: self.link.name(),
        }
    }

    /// After the link failed mid-exchange: reconnects (the exchange then
    /// sends its request again), or, while already reconnecting, fails
    /// this attempt of the reconnect loop.
    fn link_failed(&mut self, e: io::Error) -> Result<(), SerialError> {
        if self.opts.stop.requested() {
            return Err(self.interrupted());
        }
        if self.recovering {
            return Err(SerialError::Io {
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
    fn ran(
        &mut self,
        seq: u8,
        hard_end: WallInstant,
        frags: &mut Fragments,
        noise: &mut Noise,
        probe_lost: &mut bool,
    ) -> Result<Ran, SerialError> {
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
    fn await_reply(
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
            if now >= until || self.opts.stop.requested() {
                return Ok(None);
            }
            let n = self.link.recv(&mut buf, (until - now).min(Stop::SLICE))?;
            if n > 0 {
                self.heard = true;
                noise.bytes += n as u64;
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
    fn recover(&mut self, e: io::Error) -> Result<(), SerialError> {
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
                    Err(e @ (SerialError::Io { .. } | SerialError::NoAnswer { .. })) => {
                        last = e.to_string()
                    }
                    Err(e) => return Err(e),
                }
            }
            Err(SerialError::LinkLost {
                link: self.link.name(),
                attempts: self.opts.reopen_attempts,
                last: last.clone(),
            })
        })();
        self.recovering = false;
        r
    }

    /// The wall time a batch may take on a real-time bridge.
    fn batch_time(&self, ops: &[Op]) -> WallDuration {
        if self.hello.virtual_time {
            return WallDuration::ZERO;
        }
        let total: u64 = ops
            .iter()
            .map(|o| match *o {
                Op::Delay(d) => d.as_nanos(),
                Op::AwaitStatus { timeout, .. } | Op::AwaitPulses { timeout, .. } => {
                    timeout.as_nanos()
                }
                Op::WriteCommand {
                    wait_ibf: Some(t), ..
                }
                | Op::WriteData {
                    wait_ibf: Some(t), ..
                }
                | Op::ReadData { wait_obf: Some(t) } => t.as_nanos(),
                _ => 0,
            })
            .fold(0u64, u64::saturating_add);
        WallDuration::from_nanos(total)
    }

    /// Where the next capture fetch starts: the last pulse run known (it
    /// may have grown), and the pin changes and moves after those known.
    fn capture_from(&self) -> (u32, u32, u32) {
        (
            self.captured.runs.len().saturating_sub(1) as u32,
            self.captured.pins.len() as u32,
            self.captured.moves.len() as u32,
        )
    }

    /// Adds a capture chunk fetched from [`Self::capture_from`]; returns
    /// whether more records remain.
    fn absorb(&mut self, c: CaptureChunk) -> bool {
        let from_run = self.captured.runs.len().saturating_sub(1);
        if !c.runs.is_empty() {
            self.captured.runs.truncate(from_run);
        }
        self.captured.runs.extend(c.runs);
        self.captured.pins.extend(c.pins);
        self.captured.moves.extend(c.moves);
        self.captured.overwritten_bytes = c.overwritten_bytes;
        c.more
    }

    /// How many of `ops` go in the next request (at least one): as many
    /// wire ops as fit the request size in force and the bridge's batch
    /// limit, whose replies cannot outgrow [`REPLY_ENTRIES_BUDGET`].
    fn next_request_len(&self, ops: &[Op], max_ops: usize) -> usize {
        // seq, kind, count; BATCH_CAPTURE adds where the capture starts.
        let mut bytes = 4 + 14;
        let mut reply = 0;
        let mut n = 0;
        for (i, group) in wire::wire_ops(ops).into_iter().enumerate() {
            let g = &ops[n..n + group];
            bytes += wire::wire_op_len(g, self.timer);
            reply += wire::worst_reply_len(g);
            if i > 0 && (i >= max_ops || bytes > self.request_size || reply > REPLY_ENTRIES_BUDGET)
            {
                break;
            }
            n += group;
        }
        n
    }

    /// Follows the bridge's clock through the replies to `ops`: it restarts
    /// at a chip reset and otherwise never goes back.
    fn check_clock(&mut self, ops: &[Op], replies: &[Reply]) -> Result<(), SerialError> {
        for (op, r) in ops.iter().zip(replies) {
            let at = r.at();
            if *op != Op::Reset && at < self.clock {
                return Err(SerialError::ClockWentBack {
                    link: self.link.name(),
                    was: self.clock,
                    now: at,
                });
            }
            self.clock = at;
        }
        Ok(())
    }

    /// Runs `ops` in requests of the size in force. On a clean link the last
    /// request also brings back the capture since the last fetch (what the
    /// bridge has not sent yet, up to one chunk), so that reading the
    /// capture after a batch, which every scenario does, costs no round
    /// trip of its own.
    fn run_batch(&mut self, ops: &[Op]) -> Result<Vec<Reply>, SerialError> {
        self.captured_current = false;
        if ops.contains(&Op::Reset) {
            // A chip reset clears the bridge's capture.
            self.captured = Record::default();
        }
        let mut out = Vec::with_capacity(ops.len());
        let max_ops = usize::from(self.hello.max_batch_ops.clamp(1, MAX_BATCH_OPS.max(1)));
        let mut rest = ops;
        let mut garbled_rounds = 0;
        while !rest.is_empty() {
            let n = self.next_request_len(rest, max_ops);
            let (chunk, tail) = rest.split_at(n);
            rest = tail;
            let what = format!(
                "a batch of {} ops starting with `{}`",
                chunk.len(),
                chunk[0]
            );
            let extra = self.batch_time(chunk);
            let garbled_before = self.garbled;
            // The capture rides along only on a clean link: on a noisy one
            // (requests shrunk) a longer reply is likelier to need resending.
            let req = if rest.is_empty() && self.request_size >= MAX_REQUEST {
                let (runs, pins, moves) = self.capture_from();
                Request::BatchCapture {
                    ops: chunk.to_vec(),
                    runs,
                    pins,
                    moves,
                    max: CAPTURE_CHUNK,
                }
            } else {
                Request::Batch(chunk.to_vec())
            };
            let reply = match self.request(&req, &what, extra) {
                Err(e @ SerialError::Garbled { .. }) => {
                    // Not run: send the same ops again, in smaller requests
                    // while they can shrink; a line that garbles even the
                    // smallest this often is given up.
                    garbled_rounds += 1;
                    if self.request_size <= MIN_REQUEST && garbled_rounds > self.opts.retries {
                        return Err(e);
                    }
                    self.request_size = (self.request_size / 2).max(MIN_REQUEST);
                    rest = ops_from(ops, out.len());
                    continue;
                }
                other => {
                    garbled_rounds = 0;
                    other?
                }
            };
            // Noisy line: smaller requests (and so smaller replies); clean:
            // back up towards the largest.
            self.request_size = if self.garbled > garbled_before {
                (self.request_size / 2).max(MIN_REQUEST)
            } else {
                (self.request_size * 2).min(MAX_REQUEST)
            };
            match reply {
                Response::Batch(r) if r.len() == chunk.len() => {
                    self.check_clock(chunk, &r)?;
                    out.extend(r);
                }
                Response::BatchCapture { replies, capture } if replies.len() == chunk.len() => {
                    self.check_clock(chunk, &replies)?;
                    out.extend(replies);
                    let more = self.absorb(capture);
                    self.captured_current = !more && self.hello.virtual_time;
                }
                other => return Err(self.unexpected(&what, &other)),
            }
        }
        Ok(out)
    }
}

impl<L: Link> Target for SerialTarget<L> {
    fn info(&self) -> TargetInfo {
        TargetInfo {
            name: self.link.name(),
            straps: self.hello.straps,
            extra: vec![
                ("bridge_firmware".into(), self.hello.firmware.clone()),
                ("bridge_protocol".into(), self.hello.version.to_string()),
            ],
        }
    }

    fn straps(&self) -> Straps {
        self.hello.straps
    }

    /// Fetches what the bridge captured since the last fetch: new pin
    /// changes and moves, and the pulse runs from the last one known on
    /// (the last run may have grown). Costs nothing when the last batch
    /// brought the rest of the capture back with it.
    fn capture(&mut self) -> Result<Record, TargetError> {
        Ok(self.counted(Self::fetch_capture)?)
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(self.counted(|t| t.run_batch(ops))?)
    }

    fn self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestRun, TargetError> {
        Ok(self.counted(|t| t.run_self_test(plan))?)
    }
}

impl<L: Link> SerialTarget<L> {
    /// Runs `f` unless the link has given up on too many requests already,
    /// and counts it if it gives up too.
    fn counted<T>(
        &mut self,
        f: impl FnOnce(&mut Self) -> Result<T, SerialError>,
    ) -> Result<T, SerialError> {
        if self.opts.stop.requested() {
            return Err(self.interrupted());
        }
        if self.give_ups >= MAX_GIVE_UPS {
            return Err(SerialError::Exhausted {
                link: self.link.name(),
                failures: self.give_ups,
                last: self.last_give_up.clone(),
            });
        }
        let r = f(self);
        if let Err(e) = &r {
            // A capture overrun is an answer, not a request given up: the
            // bridge works, and the chip reset of the next scenario empties
            // its capture.
            if e.kind() == TargetErrorKind::Link && !matches!(e, SerialError::CaptureOverrun { .. })
            {
                self.give_ups += 1;
                self.last_give_up = e.to_string();
            }
        }
        r
    }

    /// SELF_TEST, then the capture it made: the bridge resets its chip
    /// first, so the capture and the bridge's clock start afresh.
    fn run_self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestRun, SerialError> {
        self.captured = Record::default();
        self.captured_current = false;
        self.clock = Instant::ZERO;
        let extra = if self.hello.virtual_time {
            WallDuration::ZERO
        } else {
            // The chip reset (100 us) and the bursts, each with its gap.
            WallDuration::from_nanos(plan.length().as_nanos().saturating_add(1_000_000))
        };
        let reply = match self.request(&Request::SelfTest(*plan), "self-test", extra)? {
            Response::SelfTest(r) => r,
            other => return Err(self.unexpected("self-test", &other)),
        };
        let capture = match self.fetch_capture() {
            Ok(r) => Ok(r),
            Err(SerialError::CaptureOverrun { detail, .. }) => Err(detail),
            Err(e) => return Err(e),
        };
        Ok(SelfTestRun { reply, capture })
    }

    fn fetch_capture(&mut self) -> Result<Record, SerialError> {
        while !self.captured_current {
            let (runs, pins, moves) = self.capture_from();
            let req = Request::Capture {
                runs,
                pins,
                moves,
                max: CAPTURE_CHUNK,
            };
            match self.request(&req, "capture", WallDuration::ZERO)? {
                Response::Capture(c) => {
                    // Every chunk that says there is more must bring some,
                    // and the capture can hold no more than the bridge said
                    // its buffer does: a bridge that says `more` for ever
                    // ends the download.
                    let brought = c.runs.len() + c.pins.len() + c.moves.len();
                    let more = self.absorb(c);
                    let held = self.captured.runs.len() + self.captured.pins.len();
                    let room = (self.hello.capture_capacity as usize).min(MAX_CAPTURE_RECORDS);
                    if more && (brought == 0 || held > room) {
                        return Err(SerialError::Protocol {
                            link: self.link.name(),
                            what: "capture".into(),
                            detail: match brought {
                                0 => "a chunk that says more records follow brought none".into(),
                                _ => format!(
                                    "{held} records and still more, past the {room} its buffer holds"
                                ),
                            },
                        });
                    }
                    if !more {
                        break;
                    }
                }
                other => return Err(self.unexpected("capture", &other)),
            }
        }
        self.captured_current = self.hello.virtual_time;
        Ok(self.captured.clone())
    }
}

/// The ops of `ops` from index `from` on.
fn ops_from(ops: &[Op], from: usize) -> &[Op] {
    &ops[from.min(ops.len())..]
}

#[cfg(test)]
mod tests {
    use super::link::open_error;
    use super::*;
    use crate::emu::ModelConfig;
    use crate::protocol::Straps;
    use crate::time::Duration;
    use ppmc_core::bridge::engine::BridgeEngine;
    use ppmc_core::bus::EmuBus;

    /// A link straight into a bridge server, which fails on demand.
    #[derive(Debug)]
    struct MemLink {
        server: BridgeEngine<EmuBus>,
        pending: Vec<u8>,
        fail_sends: u32,
        fail_reopens: u32,
        restart_on_reopen: bool,
        /// The bridge restarts at the next reopen with this firmware text
        /// (a panic record in it).
        panic_on_reopen: Option<String>,
        /// How many bytes the bridge sent for each request.
        sent: Vec<usize>,
        /// Frames that crossed the link so far, both ways.
        frames: u64,
        /// The connection drops at this frame boundary: before the frame
        /// with this index crosses (a request is lost, or a reply cut
        /// after the frames before it), and the link fails until reopened.
        cut_at: Option<u64>,
        broken: bool,
        /// The bridge hears, but nothing comes back (a stalled server).
        mute: bool,
        /// Requests sent so far, counted from 1 (LINK and HELLO included).
        sends: usize,
        /// These sends arrive garbled (the bridge answers BAD_FRAME).
        garble: Vec<usize>,
        /// The replies to these sends are held back, and arrive just before
        /// the reply to the next send outside them (a slow path).
        hold: Vec<usize>,
        held: Vec<u8>,
    }

    impl MemLink {
        fn new() -> MemLink {
            MemLink {
                server: Self::bridge(1),
                pending: Vec::new(),
                fail_sends: 0,
                fail_reopens: 0,
                restart_on_reopen: false,
                panic_on_reopen: None,
                sent: Vec::new(),
                frames: 0,
                cut_at: None,
                broken: false,
                mute: false,
                sends: 0,
                garble: Vec::new(),
                hold: Vec::new(),
                held: Vec::new(),
            }
        }

        /// Whether the connection drops before the next frame crosses.
        fn cut_now(&mut self) -> bool {
            if self.cut_at == Some(self.frames) {
                self.broken = true;
            }
            self.frames += 1;
            self.broken
        }

        fn bridge(session: u32) -> BridgeEngine<EmuBus> {
            let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
            BridgeEngine::new(bus, session, true, "test-bridge")
        }
    }

    impl Link for MemLink {
        fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
            if self.fail_sends > 0 {
                self.fail_sends -= 1;
                return Err(io::Error::new(io::ErrorKind::BrokenPipe, "unplugged"));
            }
            let pipe = || io::Error::new(io::ErrorKind::BrokenPipe, "connection dropped");
            if self.broken || (bytes != [0] && self.cut_now()) {
                return Err(pipe());
            }
            if self.mute {
                return Ok(());
            }
            if bytes != [0] {
                self.sends += 1;
            }
            let mut bytes = bytes.to_vec();
            if self.garble.contains(&self.sends) && bytes.len() > 3 {
                bytes[2] ^= 0x5A;
            }
            let out = self.server.on_bytes(&bytes);
            if self.hold.contains(&self.sends) {
                self.held.extend(out);
                return Ok(());
            }
            let held = std::mem::take(&mut self.held);
            self.pending.extend(held);
            self.sent.push(out.len());
            // The reply's frames, each a boundary the connection may drop at.
            for f in out.split_inclusive(|b| *b == 0) {
                if f != [0] && self.cut_now() {
                    break;
                }
                self.pending.extend_from_slice(f);
            }
            Ok(())
        }

        fn recv(&mut self, buf: &mut [u8], _timeout: WallDuration) -> io::Result<usize> {
            if self.pending.is_empty() && self.broken {
                return Err(io::Error::new(
                    io::ErrorKind::ConnectionAborted,
                    "connection dropped",
                ));
            }
            let n = self.pending.len().min(buf.len());
            buf[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            Ok(n)
        }

        fn reopen(&mut self) -> io::Result<()> {
            if self.fail_reopens > 0 {
                self.fail_reopens -= 1;
                return Err(io::Error::new(io::ErrorKind::NotFound, "no such port"));
            }
            self.pending.clear();
            self.broken = false;
            if self.restart_on_reopen {
                self.server = Self::bridge(2);
            }
            if let Some(firmware) = self.panic_on_reopen.take() {
                let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
                self.server = BridgeEngine::new(bus, 3, true, firmware);
            }
            Ok(())
        }

        fn name(&self) -> String {
            "mem".into()
        }
    }

    fn quick() -> SerialOptions {
        SerialOptions {
            reply_timeout: WallDuration::from_millis(20),
            min_reply_timeout: WallDuration::from_millis(1),
            retries: 2,
            reopen_attempts: 3,
            backoff: WallDuration::from_millis(1),
            quiet: WallDuration::from_millis(1),
            pad: 0,
            stop: Stop::default(),
        }
    }

    #[test]
    fn asked_to_pad_the_bridge_sends_whole_multiples_of_the_padding() {
        let opts = SerialOptions { pad: 64, ..quick() };
        let mut t = SerialTarget::open(MemLink::new(), opts).expect("opens");
        let replies = t.execute(&[Op::Reset, Op::ReadStatus]).expect("runs");
        assert_eq!(replies.len(), 2);
        let sent = &t.link.sent;
        // The hello reply (before LINK) is not padded; from LINK's own
        // reply on, every reply fills whole 64-byte buffers.
        assert_ne!(sent[0] % 64, 0, "{sent:?}");
        assert!(sent.len() >= 3, "{sent:?}");
        assert!(sent[1..].iter().all(|n| n % 64 == 0), "{sent:?}");
        // Unasked, nothing is padded.
        let mut plain = SerialTarget::open(MemLink::new(), quick()).expect("opens");
        plain.execute(&[Op::ReadStatus]).expect("runs");
        assert!(
            plain.link.sent.iter().all(|n| n % 64 != 0),
            "{:?}",
            plain.link.sent
        );
    }

    /// Pin samples of a phase-stepping move (Section 3-3-5), `n` of them
    /// `step` apart, taken by a scenario driver on `t`.
    fn sample_a_move(
        t: &mut dyn Target,
        step: fn(Duration) -> Duration,
        n: usize,
    ) -> Vec<(crate::time::Instant, crate::protocol::Pins)> {
        use crate::protocol::Direction;
        use crate::scenario::{Driver, DriverOptions, Init, Move};
        let mut d = Driver::new(t, DriverOptions::default());
        d.reset().expect("reset");
        d.init_and_wait(Init::four_phase()).expect("init");
        d.start(Move::constant(Direction::Cw, 100, 50_000))
            .expect("move");
        let period = d.period(100);
        d.sample_pins(step(period), n).expect("samples")
    }

    #[test]
    fn pin_sampling_costs_a_round_trip_per_1500_samples_and_matches_the_emulator() {
        // On the pulse grid, and off it (every sample then differs from the
        // one before: no run-length saving at all).
        let steps: [fn(Duration) -> Duration; 2] = [|p| p, |p| p.scale(13, 10)];
        for step in steps {
            let mut emu = crate::backend::EmuTarget::new(Straps::default(), ModelConfig::default())
                .expect("emu");
            let want = sample_a_move(&mut emu, step, 3_000);
            // Counting round trips: waits long enough that a loaded
            // machine never makes a reply late and asked for again.
            let patient = SerialOptions {
                reply_timeout: WallDuration::from_secs(5),
                min_reply_timeout: WallDuration::from_secs(2),
                ..quick()
            };
            let mut t = SerialTarget::open(MemLink::new(), patient).expect("healthy");
            let before = t.stats.round_trips;
            let got = sample_a_move(&mut t, step, 3_000);
            assert_eq!(got, want);
            // One batch for everything before the samples and the first
            // ~1,500 of them, one for the rest (it was 47 at 128 ops each).
            assert_eq!(t.stats.round_trips - before, 2);
        }
    }

    /// At most once across reconnects (`docs/bridge-protocol.md` section
    /// 3): the connection drops at every frame boundary of a run in turn,
    /// requests lost on the way and replies cut after any of their frames,
    /// and every run sees exactly what a clean run sees. A batch run twice
    /// would move the chip's clock, the pins or the status.
    #[test]
    fn a_connection_dropped_at_any_frame_boundary_changes_no_reply() {
        use crate::protocol::Direction;
        use crate::scenario::{Driver, DriverOptions, Init, Move};
        let run = |link: MemLink| {
            // Waits long enough that a loaded machine never gives up on a
            // reply (the link never loses one unless cut), short enough
            // that asking again for fragments costs little.
            let opts = SerialOptions {
                reply_timeout: WallDuration::from_millis(500),
                min_reply_timeout: WallDuration::from_millis(5),
                retries: 10,
                ..quick()
            };
            let mut t = SerialTarget::open(link, opts).expect("opens");
            let mut d = Driver::new(&mut t, DriverOptions::default());
            d.reset().expect("reset");
            d.init_and_wait(Init::four_phase()).expect("init");
            d.start(Move::constant(Direction::Cw, 100, 50_000))
                .expect("move");
            let period = d.period(100);
            // Round trips after the chip reset: none of them gives the
            // same replies if it runs twice (the chip's clock moves on).
            let samples: Vec<_> = [40, 300, 7]
                .into_iter()
                .map(|n| d.sample_pins(period.scale(13, 10), n).expect("samples"))
                .collect();
            drop(d);
            let pulses = t.execute(&[Op::ReadPulses]).expect("pulses");
            let capture = t.capture().expect("capture");
            (samples, pulses, capture, t.link.frames, t.stats.reopens)
        };
        let (samples, pulses, capture, frames, reopens) = run(MemLink::new());
        assert_eq!(reopens, 0);
        assert!(frames > 20, "precondition: {frames} frames");
        for cut in 0..frames {
            let link = MemLink {
                cut_at: Some(cut),
                ..MemLink::new()
            };
            let (s, p, c, _, reopens) = run(link);
            assert_eq!(reopens, 1, "cut at frame {cut}");
            // (Not assert_eq: the samples would fill the screen.)
            assert!(s == samples, "cut at frame {cut}: the samples differ");
            assert!(p == pulses, "cut at frame {cut}: the pulses differ");
            assert!(c == capture, "cut at frame {cut}: the capture differs");
        }
    }

    /// A "no reply to sequence N" answers a probe of whether the bridge ran
    /// request N. If the probes go unanswered for a while, and N is then
    /// sent again and runs, their late answers must not be believed: the
    /// host would split N and run its ops a second time. Here N arrives
    /// garbled twice, the first probe too, and the probes' answers come
    /// only after N was sent again.
    #[test]
    fn a_late_answer_to_a_lost_probe_never_runs_a_request_twice() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        let ms = |n| Op::Delay(Duration::from_millis(n));
        let ops = [ms(5), ms(5), Op::ReadStatus];
        let before = t.link.server.now();
        let n = t.link.sends;
        // N, N again, the first probe: garbled. The probes' answers held.
        t.link.garble = vec![n + 1, n + 2, n + 3];
        t.link.hold = (n + 3..=n + 3 + quick().retries as usize).collect();
        let r = t.execute(&ops);
        let ran = t.link.server.now().as_nanos() - before.as_nanos();
        assert_eq!(ran, 10_000_000, "the delays ran once: {r:?}");
        let r = r.expect("answered from the bridge's cache");
        assert_eq!(r.len(), 3);
    }

    /// A bridge that another host said HELLO to while the link was down
    /// may have had its chip used: a reconnect that finds it so ends the
    /// run as a link error, rather than resend a request it may run again.
    #[test]
    fn a_reconnect_to_a_bridge_another_host_used_is_not_trusted() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        let other = Request::Hello {
            version: PROTOCOL_VERSION,
            host: t.host.wrapping_add(1).max(1),
        };
        t.link
            .server
            .on_bytes(&frame::encode(&other.encode(1, Timer::NANOS)));
        t.link.fail_sends = 1;
        let e = t.execute(&[Op::ReadStatus]).expect_err("displaced");
        assert_eq!(e.kind, TargetErrorKind::Link);
        assert!(
            matches!(
                e.get_ref().downcast_ref::<SerialError>(),
                Some(SerialError::Displaced { .. })
            ),
            "{e}"
        );
    }

    /// A bridge whose capture overran answers so until a chip reset: each
    /// answer is the scenario's error, not a request given up, however
    /// many scenarios in a row overrun.
    #[test]
    fn capture_overruns_do_not_use_up_the_link() {
        let mut link = MemLink::new();
        link.server = MemLink::bridge(1).with_capture_capacity(3);
        let mut t = SerialTarget::open(link, quick()).expect("healthy");
        // Initialization (RL 100, RH 20, PA 100) and a single step: more
        // than 3 records.
        let wait_ibf = Some(Duration::from_secs(1));
        let mut ops = vec![Op::WriteCommand {
            byte: 0x06,
            wait_ibf: None,
        }];
        ops.extend([100, 20, 100, 0].map(|byte| Op::WriteData { byte, wait_ibf }));
        ops.push(Op::Delay(Duration::from_millis(200)));
        ops.push(Op::WriteCommand {
            byte: 0x4A,
            wait_ibf,
        });
        ops.push(Op::Delay(Duration::from_millis(5)));
        for n in 0..2 * MAX_GIVE_UPS {
            let mut batch = vec![Op::Reset];
            batch.extend(ops.iter().copied());
            let e = t
                .execute(&batch)
                .and_then(|_| t.capture())
                .expect_err("the capture overran");
            assert!(
                matches!(
                    e.get_ref().downcast_ref::<SerialError>(),
                    Some(SerialError::CaptureOverrun { .. })
                ),
                "{n}: {e}"
            );
        }
        assert_eq!(t.give_ups, 0);
        t.execute(&[Op::Reset, Op::ReadStatus])
            .expect("the link is still used");
    }

    /// Every wait has an end: a bridge that goes silent costs each request
    /// its tries and one reconnect, and after three requests given up the
    /// link is not used again, so the rest of a run ends at once.
    #[test]
    fn a_link_that_gave_up_three_times_is_not_used_again() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        t.link.mute = true;
        for n in 1..=MAX_GIVE_UPS {
            let e = t.execute(&[Op::ReadStatus]).expect_err("silence");
            assert_eq!(e.kind, TargetErrorKind::Link);
            let text = e.to_string();
            assert!(text.contains("no bridge answering"), "{n}: {text}");
            assert!(text.contains("nothing came back"), "{n}: {text}");
        }
        let reopens = t.stats.reopens;
        let began = WallInstant::now();
        let e = t.execute(&[Op::ReadStatus]).expect_err("given up");
        assert!(
            e.to_string()
                .contains("the link gave up on 3 requests in this run"),
            "{e}"
        );
        assert_eq!(t.stats.reopens, reopens, "not even a reconnect");
        assert!(t.capture().is_err());
        // (A bound, not a speed: nothing at all was waited for.)
        assert!(began.elapsed() < WallDuration::from_secs(1));
    }

    /// A stop request ends a wait on a silent link at once, as an
    /// interruption, not a link failure.
    #[test]
    fn a_stop_request_ends_a_wait_as_an_interruption() {
        let opts = SerialOptions {
            reply_timeout: WallDuration::from_secs(30),
            min_reply_timeout: WallDuration::from_secs(30),
            ..quick()
        };
        let stop = opts.stop.clone();
        let mut t = SerialTarget::open(MemLink::new(), opts).expect("healthy");
        t.link.mute = true;
        let asker = std::thread::spawn(move || {
            std::thread::sleep(WallDuration::from_millis(200));
            stop.request();
        });
        let e = t.execute(&[Op::ReadStatus]).expect_err("stopped");
        asker.join().expect("asker");
        assert_eq!(e.kind, TargetErrorKind::Interrupted, "{e}");
        assert_eq!(t.give_ups, 0, "an interruption is nobody's failure");
    }

    #[test]
    fn a_busy_or_forbidden_port_says_another_program_may_hold_it() {
        // (A real second open cannot be refused here: CI runs as root, and
        // root passes the exclusive lock serialport takes on the port.)
        for e in [
            io::Error::from_raw_os_error(16), // EBUSY
            io::Error::new(io::ErrorKind::ResourceBusy, "busy"),
            io::Error::new(io::ErrorKind::PermissionDenied, "denied"),
        ] {
            let msg = open_error("/dev/ttyACM0", e).to_string();
            assert!(msg.starts_with("/dev/ttyACM0: port busy"), "{msg}");
            assert!(msg.contains("another program"), "{msg}");
        }
        let missing = open_error("/dev/ttyACM9", io::ErrorKind::NotFound.into());
        assert!(missing.to_string().contains("no such serial port"));
    }

    #[test]
    fn a_vanished_port_is_reopened_and_the_run_goes_on() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        t.link.fail_sends = 1;
        t.link.fail_reopens = 2;
        let r = t.execute(&[Op::ReadStatus]).expect("recovered");
        assert!(matches!(r[0], Reply::Status { .. }));
        assert_eq!(t.stats.reopens, 1);
    }

    #[test]
    fn a_port_that_stays_gone_ends_with_link_lost() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        t.link.fail_sends = 1;
        t.link.fail_reopens = 10;
        let e = t.execute(&[Op::ReadStatus]).expect_err("gone");
        assert_eq!(e.kind, TargetErrorKind::Link);
        assert!(
            e.to_string()
                .contains("link lost and not back after 3 reopen attempts"),
            "{e}"
        );
        // The serial backend's own error is kept, not flattened to text.
        assert!(matches!(
            e.get_ref().downcast_ref::<SerialError>(),
            Some(SerialError::LinkLost { .. })
        ));
    }

    #[test]
    fn a_restarted_bridge_is_not_trusted() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        t.link.fail_sends = 1;
        t.link.restart_on_reopen = true;
        let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
        assert!(
            e.to_string().contains("the bridge restarted"),
            "{}",
            e.to_string()
        );
    }

    /// Issue 28, item 6: the RP2350 image keeps a panic's place across the
    /// watchdog's reset and says it in HELLO; a run that loses its bridge
    /// to a panic ends in an infrastructure error naming it.
    #[test]
    fn a_bridge_that_panicked_is_an_infrastructure_error_naming_the_panic() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        t.link.fail_sends = 1;
        t.link.panic_on_reopen = Some(
            "ppmc-bridge-rp2350 0.1.0; restarted after a panic at bridge/src/board.rs:442".into(),
        );
        let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
        assert_eq!(e.kind, TargetErrorKind::Link, "not the board's failure");
        assert!(
            e.to_string().contains(
                "the bridge restarted (session 00000001 -> 00000003) after a panic at bridge/src/board.rs:442"
            ),
            "{e}"
        );
        assert_eq!(restart_cause("ppmc-bridge-rp2350 0.1.0"), None);
    }

    /// A bridge that reboots while the port stays open (a UART bridge, a
    /// network link) keeps answering, but its clock starts again at 0: the
    /// run ends as a link error, never as a device failure on a reset chip.
    #[test]
    fn a_bridge_that_restarts_behind_an_open_port_is_caught_by_its_clock() {
        let mut t = SerialTarget::open(MemLink::new(), quick()).expect("healthy");
        let ms = |n| Op::Delay(crate::time::Duration::from_millis(n));
        t.execute(&[ms(5), Op::ReadStatus]).expect("runs");
        // A reset of the host's own moves the clock back, rightly.
        t.execute(&[Op::Reset, Op::ReadStatus])
            .expect("a reset is fine");
        t.execute(&[ms(5)]).expect("runs");
        t.link.server = MemLink::bridge(1);
        let e = t.execute(&[Op::ReadStatus]).expect_err("restarted");
        assert_eq!(e.kind, TargetErrorKind::Link);
        assert!(
            e.to_string().contains(
                "the bridge's clock went back from 5000.000us to 0.000us without a chip reset"
            ),
            "{e}"
        );
    }

    #[test]
    fn a_bridge_of_another_protocol_version_is_refused() {
        // A bridge that answers hello with the next protocol version.
        #[derive(Debug)]
        struct V2(Vec<u8>);
        impl Link for V2 {
            fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
                let mut d = FrameDecoder::new();
                d.extend(bytes);
                if let Ok(Some(p)) = d.decode() {
                    let seq = p[0];
                    let hello = Response::Hello(Hello {
                        version: PROTOCOL_VERSION + 1,
                        session: 1,
                        timer_hz: 1_000_000_000,
                        max_batch_ops: 1,
                        max_payload: 64,
                        capture_capacity: 0,
                        inputs_wired: 0,
                        virtual_time: true,
                        firmware: "future".into(),
                        straps: Straps::default(),
                        resumed: false,
                    });
                    self.0
                        .extend(frame::encode(&hello.encode(seq, Timer::NANOS)));
                }
                Ok(())
            }
            fn recv(&mut self, buf: &mut [u8], _: WallDuration) -> io::Result<usize> {
                let n = self.0.len().min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0.drain(..n);
                Ok(n)
            }
            fn reopen(&mut self) -> io::Result<()> {
                Ok(())
            }
            fn name(&self) -> String {
                "v2".into()
            }
        }
        let e = SerialTarget::open(V2(Vec::new()), quick()).expect_err("version");
        assert!(
            matches!(
                e,
                SerialError::Version { theirs, ours, .. }
                    if theirs == PROTOCOL_VERSION + 1 && ours == PROTOCOL_VERSION
            ),
            "{e}"
        );
    }

    #[test]
    fn specs_parse() {
        assert_eq!(
            parse_spec("serial:/dev/ttyACM0"),
            Some(("/dev/ttyACM0".into(), 115_200))
        );
        assert_eq!(
            parse_spec("serial:/dev/pts/3,baud=921600"),
            Some(("/dev/pts/3".into(), 921_600))
        );
        assert_eq!(parse_spec("serial:"), None);
        assert_eq!(parse_spec("serial:/x,speed=1"), None);
        assert_eq!(parse_spec("emu"), None);
    }
}
