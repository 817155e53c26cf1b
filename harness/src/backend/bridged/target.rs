//! [`BridgeTarget`]: the bridge session (HELLO, the health check, the
//! straps its chip reports) and the [`Target`] it is.

use super::error::*;
use super::options::*;
use crate::backend::link::Link;
use crate::backend::target::{
    Op, Reply, SelfTestPlan, SelfTestRun, Target, TargetError, TargetErrorKind, TargetInfo,
    Uncertainty,
};
use crate::protocol::Straps;
use crate::protocol::{OutputMark, OutputRecord};
use crate::time::Instant;
use ppmc_core::bridge::frame::FrameDecoder;
use ppmc_core::bridge::wire::{
    BridgeErrorCode, Hello, Request, Response, Timer, FRAGMENT_DATA, MIN_FRAGMENT_DATA,
    PROTOCOL_VERSION,
};
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// What the link has cost so far (for reports and `docs/performance.md`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    pub round_trips: u64,
    pub retransmissions: u64,
    pub corrupt_frames: u64,
    pub reopens: u64,
    /// WORKING messages heard: a bridge slower than real time said it was
    /// still running a request.
    pub working: u64,
    /// ABORTs sent: requests this host stopped waiting for while the
    /// bridge may still have been running them.
    pub aborts: u64,
}

/// A chip behind a bus bridge.
#[derive(Debug)]
pub struct BridgeTarget<L: Link> {
    pub(super) link: L,
    pub(super) decoder: FrameDecoder,
    pub(super) seq: u8,
    pub(super) hello: Hello,
    pub(super) timer: Timer,
    pub(super) opts: BridgeOptions,
    /// The capture fetched so far (since the last chip reset, less what
    /// the caller let go: [`Target::forget_capture_before`]).
    pub(super) captured: OutputRecord,
    /// What of the capture since the last chip reset `captured` no longer
    /// holds: the bridge's positions count from the reset.
    pub(super) let_go: OutputMark,
    /// `captured` is the whole capture as of now: the last request brought
    /// the rest of it back, and the bridge's chip has not moved on since
    /// (it runs in virtual time, so nothing happens between requests).
    pub(super) captured_current: bool,
    /// The link's measured round-trip time.
    pub(super) rtt: RoundTrip,
    /// Whether the last [`Self::await_reply`] received any byte at all.
    pub(super) heard: bool,
    /// A telnet negotiation came over this link (an RFC 2217 port reached
    /// as raw TCP): said with every "no answer".
    pub(super) telnet: bool,
    /// Data bytes per reply fragment in force on the bridge (LINK), and
    /// the size wanted: halved after a request whose reply needed asking
    /// again, doubled back after [`CLEAN_TO_GROW`] clean ones.
    pub(super) fragment: u8,
    pub(super) want_fragment: u8,
    /// The reply padding in force on the bridge (LINK).
    pub(super) pad: u16,
    /// Clean requests in a row.
    pub(super) clean: u32,
    /// The bridge answers LINK (one that refuses it keeps 48-byte
    /// fragments, and is not asked again).
    pub(super) link_ok: bool,
    /// The latest bridge time seen since the last chip reset: a reply
    /// timed before it means the bridge restarted.
    pub(super) clock: Instant,
    /// The request size in force: halved when a request needed asking
    /// again, doubled back after clean ones.
    pub(super) request_size: usize,
    /// This host's session, said in every HELLO (never 0): the bridge
    /// keeps its cached request across a reconnect for it.
    pub(super) host: u32,
    /// The target is open: the bridge's session is known, and a HELLO
    /// after a reconnect must find it, and this host's requests, again.
    pub(super) opened: bool,
    /// A reconnect is under way: a link error ends the attempt instead of
    /// starting another reconnect.
    pub(super) recovering: bool,
    /// The sequence number of the request whose reply is awaited.
    pub(super) in_flight: Option<u8>,
    /// Past this moment no request is waited for (a scenario's
    /// `--timeout`, [`Target::set_deadline`]).
    pub(super) deadline: Option<WallInstant>,
    /// Whether the request in flight went out at least once (only then
    /// can the bridge be running it, and an ABORT be worth sending).
    pub(super) sent: bool,
    /// Frames that arrived garbled, either way (corrupt frames here,
    /// bad-frame errors from the bridge): what makes the host shrink its
    /// requests and the bridge's reply fragments.
    pub(super) garbled: u64,
    /// Requests given up so far, and the last reason.
    pub(super) give_ups: u32,
    pub(super) last_give_up: String,
    pub stats: LinkStats,
}

/// A host session: a number no other host is likely to pick, never 0.
pub(super) fn host_session() -> u32 {
    use std::hash::{BuildHasher, Hash, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    std::process::id().hash(&mut h);
    std::time::SystemTime::now().hash(&mut h);
    WallInstant::now().hash(&mut h);
    let x = h.finish();
    ((x >> 32) as u32 ^ x as u32).max(1)
}

impl<L: Link> BridgeTarget<L> {
    /// Says hello, then checks the board's health: a chip reset, and the
    /// status register reading 0x00 after it.
    pub fn open(link: L, opts: BridgeOptions) -> Result<Self, BridgeError> {
        let mut t = Self::unopened(link, opts);
        t.handshake()?;
        Ok(t)
    }

    fn unopened(link: L, opts: BridgeOptions) -> Self {
        BridgeTarget {
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
                serial: String::new(),
                uncertainty: Default::default(),
            },
            timer: Timer::NANOS,
            opts,
            captured: OutputRecord::default(),
            let_go: OutputMark::default(),
            captured_current: false,
            clock: Instant::ZERO,
            rtt: RoundTrip::default(),
            heard: false,
            telnet: false,
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
            deadline: None,
            sent: false,
            garbled: 0,
            give_ups: 0,
            last_give_up: String::new(),
            stats: LinkStats::default(),
        }
    }

    /// A session with the bridge, as at open: HELLO, the link's settings,
    /// and the health check.
    fn handshake(&mut self) -> Result<(), BridgeError> {
        self.session()?;
        self.health_check()
    }

    /// HELLO and the link's settings.
    fn session(&mut self) -> Result<(), BridgeError> {
        let t = self;
        t.hello = t.say_hello()?;
        t.timer = Timer {
            hz: t.hello.timer_hz,
        };
        // Always: a bridge keeps its LINK settings across hosts, and the
        // last one may have asked for padding this link does not want.
        if t.link_ok {
            t.set_link(t.fragment, t.opts.pad)?;
        }
        Ok(())
    }

    /// A chip reset, and the status register reading 0x00 after it.
    fn health_check(&mut self) -> Result<(), BridgeError> {
        let t = self;
        // From here on a reconnect must find this session again.
        t.opened = true;
        let replies = t
            .run_batch(&[Op::Reset, Op::ReadStatus])
            .map_err(|e| match e {
                e @ BridgeError::Interrupted { .. } => e,
                e => BridgeError::Unhealthy {
                    link: t.link.name(),
                    detail: e.to_string(),
                },
            })?;
        match replies.get(1) {
            Some(Reply::Status { status, .. }) if status.0 == 0 => Ok(()),
            Some(Reply::Status { status, .. }) => Err(BridgeError::Unhealthy {
                link: t.link.name(),
                detail: format!(
                    "after a chip reset the status register reads 0x{:02X}, not 0x00",
                    status.0
                ),
            }),
            other => Err(BridgeError::Unhealthy {
                link: t.link.name(),
                detail: match other {
                    Some(r) => format!("the status read after a chip reset got `{r}`"),
                    None => "no reply to the status read after a chip reset".into(),
                },
            }),
        }
    }

    /// Brings back a board that hung: the link let go of, its power cycled
    /// by `cycle`, the link opened anew and a new session started (HELLO,
    /// the link's settings), tried until `boot` has passed (a USB port
    /// enumerates again, a bridge boots). The bridge must report the
    /// straps it reported before: another board behind the link would be
    /// judged as this one. The chip's health is the caller's to check.
    pub fn power_cycle(
        &mut self,
        cycle: &mut dyn FnMut() -> Result<(), String>,
        boot: WallDuration,
    ) -> Result<(), BridgeError> {
        let straps = self.hello.straps;
        self.link.close();
        cycle().map_err(|why| BridgeError::Unhealthy {
            link: self.link.name(),
            detail: format!("its power cycle failed: {why}"),
        })?;
        let end = WallInstant::now() + boot;
        let mut wait = self.opts.backoff.max(WallDuration::from_millis(50));
        loop {
            let tried = self
                .link
                .restart()
                .map_err(|e| e.to_string())
                .and_then(|()| {
                    self.stats.reopens += 1;
                    self.new_session().map_err(|e| e.to_string())
                });
            let why = match tried {
                Ok(()) => break,
                Err(why) => why,
            };
            if self.opts.stop.requested() {
                return Err(self.interrupted());
            }
            if WallInstant::now() >= end || self.opts.stop.sleep(wait) {
                return Err(BridgeError::Unhealthy {
                    link: self.link.name(),
                    detail: format!("not back within {:?} of its power cycle ({why})", boot),
                });
            }
            wait = (wait * 2).min(WallDuration::from_secs(2));
        }
        if self.hello.straps != straps {
            return Err(BridgeError::Unhealthy {
                link: self.link.name(),
                detail: format!(
                    "after its power cycle the bridge reports its chip strapped {}, not {straps} as before: another board answers",
                    self.hello.straps
                ),
            });
        }
        Ok(())
    }

    /// Forgets the session of a bridge that lost its power, and starts
    /// another: what the bridge knew of this host (its cached request,
    /// the link's settings, the capture) is gone with it.
    fn new_session(&mut self) -> Result<(), BridgeError> {
        self.decoder = FrameDecoder::new();
        self.opened = false;
        self.recovering = false;
        self.in_flight = None;
        self.sent = false;
        self.deadline = None;
        self.captured = OutputRecord::default();
        self.let_go = OutputMark::default();
        self.captured_current = false;
        self.clock = Instant::ZERO;
        self.garbled = 0;
        self.clean = 0;
        self.give_ups = 0;
        self.last_give_up.clear();
        // A delimiter first: whatever part of a frame the bridge kept ends
        // there, not in our HELLO.
        self.link.send(&[0]).map_err(|e| BridgeError::Io {
            path: self.link.name(),
            source: e,
        })?;
        self.session()?;
        // From here on a reconnect must find this session again.
        self.opened = true;
        Ok(())
    }

    pub fn hello(&self) -> &Hello {
        &self.hello
    }

    /// Says HELLO with this host's session and checks the version. Once the
    /// target is open, the bridge must be the same session, and must have
    /// kept this host's cached request (`resumed`): otherwise what the
    /// chip did while the link was down is unknown.
    pub(super) fn say_hello(&mut self) -> Result<Hello, BridgeError> {
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: self.host,
        };
        let reply = match self.request(&hello, "hello", WallDuration::ZERO) {
            // A line too noisy for the hello reply's 48-byte fragments:
            // ask for the smallest and say hello again (not while
            // reconnecting, where a silent bridge is told by the loop).
            Err(BridgeError::NoAnswer { .. }) if self.link_ok && !self.recovering => {
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
                return Err(BridgeError::Protocol {
                    link: self.link.name(),
                    what: "hello after a reconnect".into(),
                    detail: format!(
                        "the bridge now speaks protocol version {}, not {PROTOCOL_VERSION}: another bridge answers",
                        h.version
                    ),
                })
            }
            Response::Hello(h) => {
                return Err(BridgeError::Version {
                    link: self.link.name(),
                    ours: PROTOCOL_VERSION,
                    theirs: h.version,
                })
            }
            other => return Err(self.unexpected("hello", &other)),
        };
        if self.opened {
            if h.session != self.hello.session {
                return Err(BridgeError::Restarted {
                    link: self.link.name(),
                    old: self.hello.session,
                    new: h.session,
                    why: restart_cause(&h.firmware),
                });
            }
            if !h.resumed {
                return Err(BridgeError::Displaced {
                    link: self.link.name(),
                });
            }
        }
        Ok(*h)
    }

    pub(super) fn unexpected(&self, what: &str, r: &Response) -> BridgeError {
        match r {
            Response::Error {
                code: BridgeErrorCode::Version,
                detail,
            } if !self.opened => BridgeError::Version {
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
            } => BridgeError::CaptureOverrun {
                link: self.link.name(),
                detail: detail.clone(),
            },
            Response::Error { code, detail } => BridgeError::Bridge {
                link: self.link.name(),
                what: what.into(),
                code: *code,
                detail: detail.clone(),
            },
            other => BridgeError::Protocol {
                link: self.link.name(),
                what: what.into(),
                detail: format!("a {} message", other.name()),
            },
        }
    }
}

impl<L: Link> Target for BridgeTarget<L> {
    /// What the bridge declared in its HELLO, never finer than a tick of
    /// its timer (a bridge that says 0 is not exact).
    fn uncertainty(&self) -> Uncertainty {
        let timer = Timer {
            hz: self.hello.timer_hz.max(1),
        };
        let tick = crate::time::Duration::from_nanos(timer.to_nanos_up(1));
        self.hello.uncertainty.at_least(tick)
    }

    /// The serial number the bridge gives in its HELLO, else the USB
    /// serial number the operating system read from the device.
    fn bridge_serial(&self) -> Option<String> {
        Some(self.hello.serial.clone())
            .filter(|s| !s.is_empty())
            .or_else(|| self.link.device_serial())
    }

    fn set_deadline(&mut self, at: Option<std::time::Instant>) {
        self.deadline = at;
    }

    fn link_stats(&self) -> Option<Vec<(&'static str, u64)>> {
        let s = self.stats;
        Some(vec![
            ("round_trips", s.round_trips),
            ("retransmissions", s.retransmissions),
            ("corrupt_frames", s.corrupt_frames),
            ("reopens", s.reopens),
            ("working", s.working),
            ("aborts", s.aborts),
        ])
    }

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
    fn capture(&mut self) -> Result<OutputRecord, TargetError> {
        self.counted(Self::fetch_capture)?;
        Ok(self.captured.clone())
    }

    /// The batch, then the capture from `from` on: the part the caller has
    /// not seen, not a copy of everything.
    fn execute_then_capture_since(
        &mut self,
        ops: &[Op],
        from: OutputMark,
    ) -> Result<(Vec<Reply>, OutputRecord), TargetError> {
        let replies = self.execute(ops)?;
        self.counted(Self::fetch_capture)?;
        Ok((replies, self.captured.since(from)))
    }

    /// Lets go of the capture before `mark`, as the emulator does (the
    /// last move and its runs stay): the bridge is told where the next
    /// fetch starts, and may let go of it too. A long differential run
    /// so holds a window on both sides.
    fn forget_capture_before(&mut self, mark: OutputMark) -> OutputMark {
        let dropped = self.captured.forget_before(mark);
        self.let_go = self.let_go.plus(dropped);
        dropped
    }

    fn execute(&mut self, ops: &[Op]) -> Result<Vec<Reply>, TargetError> {
        Ok(self.counted(|t| t.run_batch(ops))?)
    }

    fn self_test(&mut self, plan: &SelfTestPlan) -> Result<SelfTestRun, TargetError> {
        Ok(self.counted(|t| t.run_self_test(plan))?)
    }

    fn power_cycle(
        &mut self,
        cycle: &mut dyn FnMut() -> Result<(), String>,
        boot: WallDuration,
    ) -> Result<(), TargetError> {
        Ok(BridgeTarget::power_cycle(self, cycle, boot)?)
    }
}

impl<L: Link> BridgeTarget<L> {
    /// Runs `f` unless the link has given up on too many requests already,
    /// and counts it if it gives up too.
    pub(super) fn counted<T>(
        &mut self,
        f: impl FnOnce(&mut Self) -> Result<T, BridgeError>,
    ) -> Result<T, BridgeError> {
        if self.opts.stop.requested() {
            return Err(self.interrupted());
        }
        if self.give_ups >= MAX_GIVE_UPS {
            return Err(BridgeError::Exhausted {
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
            if e.kind() == TargetErrorKind::Link && !matches!(e, BridgeError::CaptureOverrun { .. })
            {
                self.give_ups += 1;
                self.last_give_up = e.to_string();
            }
        }
        r
    }
}
