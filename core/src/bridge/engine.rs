//! The bridge side of the protocol: the request executor a bridge runs,
//! over any [`Bus`]. `ppmc bridge-sim` runs it over the reference model
//! ([`crate::bus::EmuBus`]); a bridge firmware runs the same code over the
//! real chip.
//!
//! [`BridgeEngine::on_bytes`] takes bytes from the link and returns the
//! bytes to send back. It keeps the last request that ran anything and its
//! response, so a request retransmitted with the same sequence number
//! (because its response was lost or corrupted) is answered again without
//! running twice: every retry the host makes is safe. The cache outlives a
//! HELLO from the same host session, so a host that reconnects after a
//! dropped connection and sends its request again is answered from it too
//! (at most once, `docs/bridge-protocol.md` section 3).

use super::abort::AbortLine;
use super::abort_line::takes_over;
use super::frame::{self, FrameDecoder, FrameError};
use super::wire::{
    self, capture_bytes, fragment, kind, BridgeErrorCode, CaptureChunk, Hello, Incoming,
    ReplyWriter, Request, Response, Timer, WireError, WireOp, MAX_BATCH_OPS, MAX_REPLY,
    PROTOCOL_VERSION,
};
use crate::bus::{Bus, Op, Reply};
use crate::protocol::{Command, MoveStart, OpFlags, OutputMark, Status};
use crate::time::{Duration, Instant};
use alloc::boxed::Box;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

/// Records per capture chunk, sized so that a reply fits in 255 fragments.
const CHUNK_RUNS: usize = 300;
const CHUNK_PINS: usize = 300;
const CHUNK_MOVES: usize = 60;

/// A request payload and the frames that answered it.
#[derive(Debug)]
struct Answered {
    payload: Vec<u8>,
    frames: Vec<Vec<u8>>,
}

/// Encodes `frames` onto `out`, which grows once for them.
fn put_frames<F: AsRef<[u8]>>(out: &mut Vec<u8>, frames: &[F]) {
    // COBS adds a byte in 254 and one more; then the check and the
    // delimiter.
    let len = |f: &F| {
        let body = f.as_ref().len() + frame::CHECK_LEN;
        body + body / 254 + 2
    };
    out.reserve(frames.iter().map(len).sum());
    for f in frames {
        out.extend(frame::encode(f.as_ref()));
    }
}

/// A bridge in front of a chip.
#[derive(Debug)]
pub struct BridgeEngine<B> {
    bus: B,
    /// What HELLO_REPLY says the bridge runs.
    firmware: String,
    /// The bridge's serial number, for HELLO_REPLY (empty: none).
    serial: String,
    decoder: FrameDecoder,
    session: u32,
    timer: Timer,
    virtual_time: bool,
    /// Records (pulse runs, pin changes and move records) the capture
    /// buffer holds (as announced in HELLO_REPLY); beyond it the capture
    /// is overrun until the next chip reset.
    capture_capacity: u32,
    /// What the bus let go of its record since the last reset (what the
    /// host had fetched): the host's positions count from the reset, the
    /// bus's record from here.
    forgotten: OutputMark,
    /// The host session of the last HELLO (0: none yet).
    host: u32,
    /// The last request that was not a HELLO, LINK or RESEND, and the
    /// frames sent for it: what a retransmission is answered from.
    last: Option<Answered>,
    /// The last HELLO or LINK, when it came after `last` (they change
    /// nothing on the chip, and leave `last` alone).
    control: Option<Answered>,
    /// Data bytes per reply fragment, as the host last asked (LINK).
    fragment: usize,
    /// Every reply is padded with 0x00 to a multiple of this (LINK; 0:
    /// not padded).
    pad: usize,
    /// Frames handled so far (for fault injection by the caller).
    pub frames: u64,
    /// Raised by the receive path when an ABORT arrives ([`AbortLine`]).
    abort: Option<AbortLine>,
    /// The request an abort stopped last, if the last request was it
    /// (ABORT_REPLY).
    stopped: Option<u8>,
    /// The sequence number of the request running.
    current: u8,
}

impl<B: Bus> BridgeEngine<B> {
    /// `session` should differ between runs of the bridge (a bridge that
    /// restarts must not reuse it); `firmware` names the bridge in
    /// HELLO_REPLY.
    pub fn new(bus: B, session: u32, virtual_time: bool, firmware: impl Into<String>) -> Self {
        BridgeEngine {
            bus,
            firmware: firmware.into(),
            serial: String::new(),
            decoder: FrameDecoder::new(),
            session,
            timer: Timer::NANOS,
            virtual_time,
            capture_capacity: u32::MAX,
            forgotten: OutputMark::default(),
            host: 0,
            last: None,
            control: None,
            fragment: wire::FRAGMENT_DATA,
            pad: 0,
            frames: 0,
            abort: None,
            stopped: None,
            current: 0,
        }
    }

    /// A bridge that stops a request in flight when `line` is raised (by
    /// an [`AbortWatch`](super::abort::AbortWatch) on its receive path):
    /// between ops, and inside a bus's long waits ([`Bus::watch_abort`]).
    /// Without one, an ABORT is read only after the request it meant.
    pub fn with_abort(mut self, line: AbortLine) -> Self {
        self.bus.watch_abort(line.clone());
        self.abort = Some(line);
        self
    }

    /// Gives the bridge a serial number, which HELLO_REPLY carries (an
    /// RP2350's chip ID): at most 255 bytes of it are sent.
    pub fn with_serial(mut self, serial: &str) -> Self {
        let mut end = serial.len().min(255);
        while !serial.is_char_boundary(end) {
            end -= 1;
        }
        self.serial = serial[..end].into();
        self
    }

    /// A bridge whose capture buffer holds `records` records (pulse runs,
    /// pin changes and move records): past that, capture requests answer
    /// CAPTURE_OVERRUN until the next chip reset, as a board with a small
    /// buffer would, and a batch stops before its next op (a chip reset
    /// excepted) with the same answer, so that the capture outgrows its
    /// buffer by at most what one op adds: a bridge sizes its buffer by
    /// its memory (firmware/README.md).
    pub fn with_capture_capacity(mut self, records: u32) -> Self {
        self.capture_capacity = records;
        self
    }

    /// A bridge whose timer runs at `timer.hz`: every time and duration on
    /// the wire is in its ticks, and HELLO_REPLY says so.
    pub fn with_timer(mut self, timer: Timer) -> Self {
        self.timer = timer;
        self
    }

    pub fn bus(&self) -> &B {
        &self.bus
    }

    /// The line an ABORT raises, if the bridge has one
    /// ([`BridgeEngine::with_abort`]): its receive path watches for ABORT
    /// with an [`AbortWatch`](super::abort::AbortWatch) of it.
    pub fn abort_line(&self) -> Option<&AbortLine> {
        self.abort.as_ref()
    }

    /// Handles received bytes; returns the bytes to send back (whole
    /// frames, possibly none).
    pub fn on_bytes(&mut self, bytes: &[u8]) -> Vec<u8> {
        self.decoder.extend(bytes);
        let mut out = Vec::new();
        loop {
            match self.decoder.decode() {
                Ok(Some(payload)) => {
                    self.frames += 1;
                    self.on_payload(&payload, &mut out);
                }
                Ok(None) => break,
                Err(e) => {
                    let code = match e {
                        FrameError::TooLong => BridgeErrorCode::Overflow,
                        _ => BridgeErrorCode::BadFrame,
                    };
                    let resp = Response::Error {
                        code,
                        detail: e.to_string(),
                    };
                    out.extend(frame::encode(&resp.encode(0, self.timer)));
                }
            }
        }
        // Empty frames (back-to-back delimiters) are skipped by every
        // decoder; they only fill a server's buffer so that it sends.
        if self.pad > 0 && out.len() % self.pad != 0 {
            out.resize(out.len().next_multiple_of(self.pad), 0);
        }
        out
    }

    /// The virtual time the emulator has reached (to pace `--realtime`).
    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Lets `d` pass on the chip between requests, as it does on a board
    /// while the host is busy elsewhere (`--realtime`).
    pub fn pass_time(&mut self, d: Duration) {
        self.bus.run(Op::Delay(d));
    }

    /// The frames answering one request payload, encoded onto `out`.
    ///
    /// The at-most-once rule (`docs/bridge-protocol.md` section 3): a
    /// payload byte for byte the same as the last request's, or as the last
    /// HELLO's or LINK's, is answered with the same frames and not run
    /// again. HELLO, LINK and RESEND never replace the cached request, so a
    /// host that reconnects, says HELLO with its own host session again and
    /// resends the request whose reply it lost gets that reply; a HELLO
    /// with another host session (another host) clears the cache.
    fn on_payload(&mut self, payload: &[u8], out: &mut Vec<u8>) {
        // Read in its turn, even when answered from the cache: what it
        // raised on the receive path is done with (the request an ABORT
        // named has ended; a new host's HELLO has stopped what ran).
        if let Some(line) = &self.abort {
            match payload.get(1).copied() {
                Some(kind::ABORT) => payload.get(2).map_or((), |&r| line.read_abort(r)),
                Some(kind::HELLO) => line.read_takeover(),
                _ => {}
            }
        }
        for cached in [&self.control, &self.last].into_iter().flatten() {
            if cached.payload == payload {
                return put_frames(out, &cached.frames);
            }
        }
        let seq = payload.first().copied().unwrap_or(0);
        // A batch's SAMPLE ops stay whole: memory does not grow with them.
        let decoded = Incoming::decode(payload, self.timer);
        if let Ok((s, Incoming::Other(Request::Resend { fragments }))) = &decoded {
            // Only for the request answered last, or the one before a
            // HELLO or LINK.
            let answered = [&self.control, &self.last]
                .into_iter()
                .flatten()
                .find(|a| a.payload.first() == Some(s));
            let frames: Vec<&[u8]> = match answered {
                Some(a) => fragments
                    .iter()
                    .filter_map(|i| a.frames.get(usize::from(*i)).map(Vec::as_slice))
                    .collect(),
                None => {
                    let e = Response::Error {
                        code: BridgeErrorCode::Malformed,
                        detail: format!("no reply to sequence {s} to resend"),
                    };
                    return put_frames(out, &[e.encode(seq, self.timer)]);
                }
            };
            return put_frames(out, &frames);
        }
        let control = matches!(
            decoded,
            Ok((
                _,
                Incoming::Other(
                    Request::Hello { .. } | Request::Link { .. } | Request::Abort { .. }
                )
            ))
        );
        if !control {
            // Replaced by this request's answer: free while it runs.
            self.last = None;
            self.control = None;
            self.stopped = None;
        }
        let mut reply = match decoded {
            Ok((_, req)) => {
                self.current = seq;
                if let Some(line) = &self.abort {
                    let runs_ops = match &req {
                        Incoming::Other(r) => matches!(r, Request::SelfTest(_)),
                        Incoming::Batch(_) | Incoming::BatchCapture { .. } => true,
                    };
                    line.begin(seq, runs_ops);
                }
                let reply = self.respond(seq, req);
                if let Some(line) = &self.abort {
                    line.end();
                }
                reply
            }
            Err(e) => Response::Error {
                code: match e {
                    WireError::UnknownKind(_) | WireError::UnknownCode { .. } => {
                        BridgeErrorCode::UnknownOp
                    }
                    _ => BridgeErrorCode::Malformed,
                },
                detail: e.to_string(),
            }
            .encode(seq, self.timer),
        };
        if reply.len() > MAX_REPLY {
            reply = self.overflow(seq, reply.len());
        }
        let frames = fragment(&reply, self.fragment);
        drop(reply);
        put_frames(out, &frames);
        let answered = Some(Answered {
            payload: payload.to_vec(),
            frames,
        });
        if control {
            self.control = answered;
        } else {
            self.last = answered;
        }
    }

    /// Never a truncated reply: the host asked for too much at once.
    fn overflow(&self, seq: u8, len: usize) -> Vec<u8> {
        Response::Error {
            code: BridgeErrorCode::Overflow,
            detail: format!("the reply takes {len} bytes, more than {MAX_REPLY}; send fewer ops"),
        }
        .encode(seq, self.timer)
    }

    /// The encoded response to `req`.
    fn respond(&mut self, seq: u8, req: Incoming) -> Vec<u8> {
        match req {
            Incoming::Batch(ops) => {
                let mut replies = ReplyWriter::new(seq, false, self.timer, MAX_REPLY);
                match self.run_ops(&ops, &mut replies) {
                    Err(e) => e.encode(seq, self.timer),
                    Ok(()) => replies
                        .finish()
                        .unwrap_or_else(|len| self.overflow(seq, len)),
                }
            }
            Incoming::BatchCapture {
                ops,
                runs,
                pins,
                moves,
                max,
            } => {
                let mut replies = ReplyWriter::new(seq, true, self.timer, MAX_REPLY);
                match self.run_ops(&ops, &mut replies) {
                    Err(e) => e.encode(seq, self.timer),
                    // The ops ran, but what they left is not all there.
                    Ok(()) if let Some(held) = self.overrun() => {
                        self.overrun_error(held).encode(seq, self.timer)
                    }
                    Ok(()) if let Some(gone) = self.let_go(runs, pins, moves) => {
                        gone.encode(seq, self.timer)
                    }
                    Ok(()) => match replies.finish() {
                        Ok(mut bytes) => {
                            let tentative = self.bus.settle_record();
                            // The capture takes what room the replies leave.
                            let mut max = max;
                            loop {
                                let chunk = self.chunk(runs, pins, moves, max, tentative);
                                let capture = capture_bytes(&chunk, self.timer);
                                if max <= 1 || bytes.len() + capture.len() <= MAX_REPLY {
                                    bytes.extend_from_slice(&capture);
                                    break bytes;
                                }
                                max /= 2;
                            }
                        }
                        // Too long with the least capture too.
                        // (Its size with every record counted: nothing is
                        // served, so nothing need be settled.)
                        Err(len) => {
                            let chunk = self.chunk(runs, pins, moves, 1, 0);
                            self.overflow(seq, len + capture_bytes(&chunk, self.timer).len())
                        }
                    },
                }
            }
            Incoming::Other(req) => self.handle(req).encode(seq, self.timer),
        }
    }

    fn handle(&mut self, req: Request) -> Response {
        match req {
            Request::Hello { version, .. } if version != PROTOCOL_VERSION => Response::Error {
                code: BridgeErrorCode::Version,
                detail: format!("bridge speaks protocol {PROTOCOL_VERSION}, host {version}"),
            },
            Request::Hello { host, .. } => Response::Hello(Box::new(Hello {
                resumed: self.greet(host),
                serial: self.serial.clone(),
                version: PROTOCOL_VERSION,
                session: self.session,
                timer_hz: self.timer.hz,
                max_batch_ops: MAX_BATCH_OPS,
                max_payload: frame::MAX_PAYLOAD as u16,
                capture_capacity: self.capture_capacity,
                inputs_wired: 0x3FF,
                virtual_time: self.virtual_time,
                firmware: self.firmware.clone(),
                straps: self.bus.straps(),
                uncertainty: self
                    .bus
                    .uncertainty()
                    .at_least(Duration::from_nanos(self.timer.to_nanos_up(1))),
            })),
            Request::Batch(_) => Response::Error {
                code: BridgeErrorCode::Malformed,
                detail: "batch handled before dispatch".into(),
            },
            Request::Resend { .. } => Response::Error {
                code: BridgeErrorCode::Malformed,
                detail: "resend handled before dispatch".into(),
            },
            Request::Capture {
                runs,
                pins,
                moves,
                max,
            } => match (self.overrun(), self.let_go(runs, pins, moves)) {
                (Some(held), _) => self.overrun_error(held),
                (None, Some(gone)) => gone,
                (None, None) => {
                    let tentative = self.bus.settle_record();
                    Response::Capture(self.chunk(runs, pins, moves, max, tentative))
                }
            },
            Request::BatchCapture { .. } => Response::Error {
                code: BridgeErrorCode::Malformed,
                detail: "batch-capture handled before dispatch".into(),
            },
            Request::SelfTest(plan) => {
                if let Some(what) = self.bus.fault() {
                    return Response::Error {
                        code: BridgeErrorCode::Hardware,
                        detail: what.into(),
                    };
                }
                // The self-test resets the chip, and its capture with it.
                self.forgotten = OutputMark::default();
                match self.bus.self_test(&plan) {
                    Ok(reply) => Response::SelfTest(reply),
                    Err(detail) => Response::Error {
                        code: BridgeErrorCode::UnknownOp,
                        detail,
                    },
                }
            }
            Request::Abort { request } => Response::Abort {
                stopped: self.stopped == Some(request),
            },
            Request::Link { fragment, pad } => {
                self.fragment =
                    usize::from(fragment).clamp(wire::MIN_FRAGMENT_DATA, wire::FRAGMENT_DATA);
                self.pad = usize::from(pad.min(wire::MAX_PAD));
                Response::Link {
                    fragment: self.fragment as u8,
                    pad: self.pad as u16,
                }
            }
        }
    }

    /// Takes a HELLO from host session `host`: whether the bridge kept
    /// that host's cached request (the same host, and no other since). A
    /// new host starts with nothing cached, so that a request of its own
    /// that happens to match the last host's is run, not answered from the
    /// cache. Host session 0 is nobody's: it always starts afresh.
    fn greet(&mut self, host: u32) -> bool {
        let resumed = !takes_over(self.host, host);
        if !resumed {
            self.last = None;
            self.host = host;
        }
        resumed
    }

    /// Runs a batch's ops within the batch limit, their replies into
    /// `replies`; the error response otherwise. A batch stops before an op
    /// (a chip reset excepted, which empties the capture) once the capture
    /// holds more than its buffer: the capture then outgrows its buffer by
    /// at most what one op (or one run of samples, `Bus::sample_run`)
    /// adds, whatever the batch asks for.
    fn run_ops(&mut self, ops: &[WireOp], replies: &mut ReplyWriter) -> Result<(), Response> {
        if ops.len() > usize::from(MAX_BATCH_OPS) {
            return Err(Response::Error {
                code: BridgeErrorCode::Overflow,
                detail: format!("{} ops in one batch, at most {MAX_BATCH_OPS}", ops.len()),
            });
        }
        let mut full = None;
        let mut ran = 0;
        let mut i = 0;
        'ops: while let Some(w) = ops.get(i) {
            if let WireOp::Sample { step, .. } = *w {
                // SAMPLE ops in a row at one step: one run of samples, for
                // a bus that runs them as one (`Bus::sample_run`).
                let run = ops[i..]
                    .iter()
                    .take_while(|n| matches!(n, WireOp::Sample { step: s, .. } if *s == step))
                    .count();
                let pairs = ops[i..i + run].iter().map(|n| n.len() / 2).sum::<usize>();
                if self.abort_pending() {
                    return Err(self.abort_request(ran));
                }
                let held = self.held();
                if held > self.capture_capacity as usize {
                    full = Some(held);
                    break;
                }
                let after = ops.get(i + run).map(|n| n.op(0));
                if self
                    .bus
                    .sample_run(step, pairs, after, &mut |r| replies.push(r))
                {
                    ran += 2 * pairs;
                    i += run;
                    continue;
                }
            }
            // The op after this wire op's last.
            let after = ops.get(i + 1).map(|n| n.op(0));
            for j in 0..w.len() {
                let op = w.op(j);
                if self.abort_pending() {
                    return Err(self.abort_request(ran));
                }
                let held = self.held();
                if op != Op::Reset && held > self.capture_capacity as usize {
                    full = Some(held);
                    break 'ops;
                }
                let next = if j + 1 < w.len() {
                    Some(w.op(j + 1))
                } else {
                    after
                };
                self.bus.next_op(next);
                replies.push(self.bus.run(op));
                if op == Op::Reset {
                    // A new capture, counted from 0.
                    self.forgotten = OutputMark::default();
                }
                ran += 1;
            }
            i += 1;
        }
        // Stopped inside the last op's wait, perhaps.
        if self.abort_pending() {
            return Err(self.abort_request(ran.saturating_sub(1)));
        }
        if full.is_some() {
            self.bus.abandon();
        }
        match (self.bus.fault(), full) {
            (Some(what), _) => Err(Response::Error {
                code: BridgeErrorCode::Hardware,
                detail: what.into(),
            }),
            (None, Some(held)) => Err(self.overrun_error(held)),
            (None, None) => Ok(()),
        }
    }

    fn abort_pending(&self) -> bool {
        self.abort.as_ref().is_some_and(AbortLine::pending)
    }

    /// Stops the request in flight, which had run `ran` ops in full, and
    /// the chip with it: an Immediate Stop where a move runs (datasheet
    /// 3-3-1; not otherwise, where it would be Error #0), so that the chip
    /// is left stopped with the capture so far, for the host to fetch.
    fn abort_request(&mut self, ran: usize) -> Response {
        if let Some(line) = &self.abort {
            line.acknowledge();
        }
        self.stopped = Some(self.current);
        // No op of the batch follows: nothing to aim the stop's at, and
        // nothing read ahead for one (a status read behind a write).
        self.bus.abandon();
        self.bus.next_op(None);
        let busy =
            matches!(self.bus.run(Op::ReadStatus), Reply::Status { status, .. } if status.busy());
        let stop = if busy {
            // The command register frees within microseconds (Table 3-3);
            // a chip that keeps IBF for a millisecond is left as it is.
            let byte = Command::ImmediateStop(OpFlags::PLAIN).encode();
            let written = self.bus.run(Op::WriteCommand {
                byte,
                wait_ibf: Some(Duration::from_millis(1)),
            });
            if !matches!(written, Reply::Written { .. }) {
                "; the chip kept IBF set, so the Immediate Stop could not be written"
            } else {
                // Processed within microseconds (Table 3-3): the reply
                // goes once the chip has stopped.
                match self.bus.run(Op::AwaitStatus {
                    mask: Status::BUSY,
                    value: 0,
                    timeout: Duration::from_millis(10),
                }) {
                    Reply::Awaited { .. } => "; the move was stopped (Immediate Stop)",
                    _ => "; the chip was still BUSY 10 ms after an Immediate Stop",
                }
            }
        } else {
            ""
        };
        Response::Error {
            code: BridgeErrorCode::Aborted,
            detail: format!("stopped by ABORT after {ran} ops{stop}"),
        }
    }

    /// The records captured since the last reset: pulse runs, pin changes
    /// and move records, those let go of after the host fetched them
    /// included (`capture_capacity` counts from the reset, as HELLO_REPLY
    /// announces it).
    fn held(&self) -> usize {
        let rec = self.bus.record();
        let gone = self.forgotten;
        rec.runs.len() + rec.pins.len() + rec.moves.len() + gone.runs + gone.pins + gone.moves
    }

    /// The records captured since the last reset, if more than the
    /// capture buffer holds.
    fn overrun(&self) -> Option<usize> {
        let held = self.held();
        (held > self.capture_capacity as usize || self.bus.capture_lost()).then_some(held)
    }

    fn overrun_error(&self, held: usize) -> Response {
        let detail = if self.bus.capture_lost() {
            "edges came faster than the capture was drained; some were lost".into()
        } else {
            format!(
                "{held} records captured since the last reset; the buffer holds {}",
                self.capture_capacity
            )
        };
        Response::Error {
            code: BridgeErrorCode::CaptureOverrun,
            detail,
        }
    }

    /// The bus, to let it work between requests (a bridge draining its
    /// capture while it waits for the host).
    pub fn bus_mut(&mut self) -> &mut B {
        &mut self.bus
    }

    /// The host asks for the capture from these positions on (counted
    /// from the last reset): what came before, it has. The bus may let
    /// that go ([`Bus::forget_record_before`]). `Some` refusal when the
    /// host asks for records let go already (a host that has not fetched
    /// them: another host's session, with no chip reset since).
    fn let_go(&mut self, runs: u32, pins: u32, moves: u32) -> Option<Response> {
        let want = OutputMark {
            runs: runs as usize,
            pins: pins as usize,
            moves: moves as usize,
        };
        if want.before(self.forgotten) {
            return Some(Response::Error {
                code: BridgeErrorCode::CaptureOverrun,
                detail: format!(
                    "the capture before run {}, pin change {} and move {} was fetched and let go: reset the chip to capture afresh",
                    self.forgotten.runs,
                    self.forgotten.pins,
                    self.forgotten.moves
                ),
            });
        }
        let dropped = self.bus.forget_record_before(want.minus(self.forgotten));
        self.forgotten = self.forgotten.plus(dropped);
        None
    }

    /// Up to `max` capture records of each kind from these positions on
    /// (counted from the last reset; [`Self::let_go`] has run), but for the
    /// last `tentative` move records ([`Bus::settle_record`]).
    fn chunk(&self, runs: u32, pins: u32, moves: u32, max: u16, tentative: usize) -> CaptureChunk {
        let rec = self.bus.record();
        let settled = rec.moves.len().saturating_sub(tentative);
        let gone = self.forgotten;
        let (runs, pins, moves) = (
            runs.saturating_sub(gone.runs as u32),
            pins.saturating_sub(gone.pins as u32),
            moves.saturating_sub(gone.moves as u32),
        );
        let max = usize::from(max.max(1));
        let take = |from: u32, len: usize, max: usize| {
            let from = (from as usize).min(len);
            (from, (from + max).min(len))
        };
        let (r0, r1) = take(runs, rec.runs.len(), CHUNK_RUNS.min(max));
        let (p0, p1) = take(pins, rec.pins.len(), CHUNK_PINS.min(max));
        let (m0, m1) = take(moves, settled, CHUNK_MOVES.min(max));
        CaptureChunk {
            runs: rec.runs[r0..r1].to_vec(),
            pins: rec.pins[p0..p1].to_vec(),
            // Each move's first run, counted from the reset as the host
            // counts.
            moves: rec.moves[m0..m1]
                .iter()
                .map(|m| MoveStart {
                    first_run: m.first_run + gone.runs,
                    ..*m
                })
                .collect(),
            overwritten_bytes: rec.overwritten_bytes,
            more: r1 < rec.runs.len() || p1 < rec.pins.len() || m1 < settled,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::{EmuBus, Reply};
    use crate::emu::ModelConfig;
    use crate::protocol::Straps;
    use alloc::vec;

    fn server() -> BridgeEngine<EmuBus> {
        let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
        BridgeEngine::new(bus, 42, true, "test-bridge")
    }

    /// The response in `out`, reassembled from its fragments.
    fn collect(out: &[u8]) -> (u8, Response) {
        let mut d = FrameDecoder::new();
        d.extend(out);
        let mut payload = Vec::new();
        while let Some(f) = d.decode().expect("valid frame") {
            match crate::bridge::wire::parse_fragment(&f) {
                Some((_, _, _, data)) => payload.extend_from_slice(data),
                None => payload = f,
            }
        }
        Response::decode(&payload, Timer::NANOS).expect("decodes")
    }

    fn ask<B: Bus>(s: &mut BridgeEngine<B>, seq: u8, req: &Request) -> Response {
        let out = s.on_bytes(&frame::encode(&req.encode(seq, Timer::NANOS)));
        let mut d = FrameDecoder::new();
        d.extend(&out);
        let mut payload = Vec::new();
        while let Some(f) = d.decode().expect("valid frame") {
            match crate::bridge::wire::parse_fragment(&f) {
                Some((_, _, _, data)) => payload.extend_from_slice(data),
                None => payload = f,
            }
        }
        let (got_seq, resp) = Response::decode(&payload, Timer::NANOS).expect("decodes");
        assert_eq!(got_seq, seq);
        resp
    }

    #[test]
    fn hello_announces_the_bridge() {
        let mut s = server();
        let Response::Hello(h) = ask(
            &mut s,
            1,
            &Request::Hello {
                version: PROTOCOL_VERSION,
                host: 7,
            },
        ) else {
            panic!("hello reply");
        };
        assert_eq!(
            (h.session, h.timer_hz, h.max_batch_ops),
            (42, 1_000_000_000, MAX_BATCH_OPS)
        );
        assert_eq!(h.straps, Straps::default());
        let r = ask(
            &mut s,
            2,
            &Request::Hello {
                version: 99,
                host: 7,
            },
        );
        assert!(matches!(
            r,
            Response::Error {
                code: BridgeErrorCode::Version,
                ..
            }
        ));
    }

    #[test]
    fn link_pads_every_reply_to_the_asked_multiple_and_the_replies_still_decode() {
        let mut s = server();
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 7,
        };
        let plain = s.on_bytes(&frame::encode(&hello.encode(1, Timer::NANOS)));
        assert_ne!(plain.len() % 64, 0, "unpadded by default");
        let set = ask(
            &mut s,
            2,
            &Request::Link {
                fragment: 48,
                pad: 64,
            },
        );
        assert_eq!(
            set,
            Response::Link {
                fragment: 48,
                pad: 64
            }
        );
        for (seq, req) in [
            (3, hello.clone()),
            (4, Request::Batch(vec![Op::Delay(Duration::from_millis(1))])),
        ] {
            let out = s.on_bytes(&frame::encode(&req.encode(seq, Timer::NANOS)));
            assert_eq!(out.len() % 64, 0, "{req:?}: {} bytes", out.len());
            assert!(out.ends_with(&[0, 0]), "padded with delimiters");
        }
        // The padded reply is the unpadded one plus empty frames.
        let padded = s.on_bytes(&frame::encode(&hello.encode(5, Timer::NANOS)));
        let end = padded.iter().rposition(|b| *b != 0).expect("a frame") + 2;
        assert!(padded[end..].iter().all(|b| *b == 0), "padding is zeros");
        assert!(matches!(collect(&padded[..end]).1, Response::Hello(_)));
        assert!(matches!(collect(&padded).1, Response::Hello(_)));
        // Padding is bounded, and 0 turns it off.
        let capped = ask(
            &mut s,
            6,
            &Request::Link {
                fragment: 48,
                pad: 60_000,
            },
        );
        assert_eq!(
            capped,
            Response::Link {
                fragment: 48,
                pad: wire::MAX_PAD
            }
        );
        ask(
            &mut s,
            7,
            &Request::Link {
                fragment: 48,
                pad: 0,
            },
        );
        let again = s.on_bytes(&frame::encode(&hello.encode(8, Timer::NANOS)));
        assert_eq!(again.len(), plain.len());
    }

    #[test]
    fn a_bridge_without_a_generator_refuses_the_self_test_and_goes_on() {
        use crate::bus::SelfTestPlan;
        let mut s = server();
        let plan = SelfTestPlan {
            count: 10,
            high: Duration::from_micros(5),
            low: Duration::from_micros(5),
            bursts: 1,
            gap: Duration::ZERO,
        };
        match ask(&mut s, 3, &Request::SelfTest(plan)) {
            Response::Error {
                code: BridgeErrorCode::UnknownOp,
                detail,
            } => assert!(detail.contains("no self-test generator"), "{detail}"),
            other => panic!("{other:?}"),
        }
        let after = ask(&mut s, 4, &Request::Batch(vec![Op::ReadStatus]));
        assert!(matches!(after, Response::Batch(r) if r.len() == 1));
    }

    #[test]
    fn a_retransmitted_request_is_answered_without_running_twice() {
        let mut s = server();
        let req = Request::Batch(vec![Op::Delay(Duration::from_millis(5))]);
        let a = ask(&mut s, 7, &req);
        let b = ask(&mut s, 7, &req);
        assert_eq!(a, b);
        assert_eq!(s.now().as_nanos(), 5_000_000, "the delay ran once");
        ask(&mut s, 8, &req);
        assert_eq!(s.now().as_nanos(), 10_000_000);
    }

    fn hello(host: u32) -> Request {
        Request::Hello {
            version: PROTOCOL_VERSION,
            host,
        }
    }

    fn resumed(r: Response) -> bool {
        match r {
            Response::Hello(h) => h.resumed,
            other => panic!("not a hello reply: {other:?}"),
        }
    }

    /// At most once across a reconnect (section 3): the host's connection
    /// drops after the bridge ran a batch; it reconnects, says HELLO with
    /// its own host session again and sends the batch again. The bridge
    /// answers from its cache.
    #[test]
    fn a_batch_sent_again_after_a_hello_of_the_same_host_does_not_run_twice() {
        let mut s = server();
        assert!(!resumed(ask(&mut s, 1, &hello(77))), "a new host");
        let req = Request::Batch(vec![Op::Delay(Duration::from_millis(5))]);
        let a = ask(&mut s, 2, &req);
        assert!(resumed(ask(&mut s, 3, &hello(77))), "the same host again");
        let link = Request::Link {
            fragment: 48,
            pad: 0,
        };
        ask(&mut s, 4, &link);
        let b = ask(&mut s, 2, &req);
        assert_eq!(a, b);
        assert_eq!(s.now().as_nanos(), 5_000_000, "the delay ran once");
        // The fragments of its reply can still be asked for after a HELLO.
        ask(&mut s, 5, &hello(77));
        let again = s.on_bytes(&frame::encode(
            &Request::Resend { fragments: vec![0] }.encode(2, Timer::NANOS),
        ));
        assert_eq!(collect(&again), (2, a));
        // A new request runs.
        ask(&mut s, 6, &req);
        assert_eq!(s.now().as_nanos(), 10_000_000);
    }

    /// Another host's request that happens to be byte for byte the same as
    /// the last host's last one is run: a HELLO from another host session
    /// forgets the cache, and says so.
    #[test]
    fn a_hello_from_another_host_forgets_the_last_hosts_requests() {
        let mut s = server();
        ask(&mut s, 1, &hello(1));
        let req = Request::Batch(vec![Op::Delay(Duration::from_millis(5))]);
        ask(&mut s, 2, &req);
        assert!(!resumed(ask(&mut s, 1, &hello(2))), "another host");
        ask(&mut s, 2, &req);
        assert_eq!(s.now().as_nanos(), 10_000_000, "the second host's ran");
        // The first host, back after the second: its state is gone, and
        // the bridge says so rather than pretend.
        assert!(!resumed(ask(&mut s, 9, &hello(1))));
        // Host session 0 never resumes.
        assert!(!resumed(ask(&mut s, 10, &hello(0))));
        assert!(!resumed(ask(&mut s, 11, &hello(0))));
        let gone = s.on_bytes(&frame::encode(
            &Request::Resend { fragments: vec![0] }.encode(2, Timer::NANOS),
        ));
        assert!(matches!(
            collect(&gone).1,
            Response::Error {
                code: BridgeErrorCode::Malformed,
                ..
            }
        ));
    }

    #[test]
    fn corrupt_and_oversized_requests_get_error_codes() {
        let mut s = server();
        let hello = Request::Hello {
            version: PROTOCOL_VERSION,
            host: 1,
        };
        let mut bad = frame::encode(&hello.encode(1, Timer::NANOS));
        bad[2] ^= 0xFF;
        let code = |r: Response| match r {
            Response::Error { code, .. } => Some(code),
            _ => None,
        };
        assert_eq!(
            code(collect(&s.on_bytes(&bad)).1),
            Some(BridgeErrorCode::BadFrame)
        );
        let unknown = s.on_bytes(&frame::encode(&[4, 0x02, 1, 0, 0x99]));
        assert_eq!(code(collect(&unknown).1), Some(BridgeErrorCode::UnknownOp));
        let truncated = s.on_bytes(&frame::encode(&[5, 0x02, 1, 0, 0x10]));
        assert_eq!(
            code(collect(&truncated).1),
            Some(BridgeErrorCode::Malformed)
        );
        let big = Request::Batch(vec![Op::ReadStatus; usize::from(MAX_BATCH_OPS) + 1]);
        assert_eq!(code(ask(&mut s, 3, &big)), Some(BridgeErrorCode::Overflow));
    }

    /// Initialization (Section 3-2) and time for it to finish.
    fn init_ops() -> Vec<Op> {
        let mut ops = vec![Op::WriteCommand {
            byte: 0x06,
            wait_ibf: None,
        }];
        for b in [100u8, 20, 100, 0] {
            ops.push(Op::WriteData {
                byte: b,
                wait_ibf: Some(Duration::from_secs(1)),
            });
        }
        ops.push(Op::Delay(Duration::from_millis(200)));
        ops
    }

    #[test]
    fn capture_comes_in_chunks() {
        let mut s = server();
        ask(&mut s, 1, &Request::Batch(init_ops()));
        for k in 0..30u8 {
            let step = vec![
                Op::WriteCommand {
                    byte: 0x4A,
                    wait_ibf: Some(Duration::from_secs(1)),
                },
                Op::AwaitStatus {
                    mask: 4,
                    value: 4,
                    timeout: Duration::from_millis(5),
                },
                Op::AwaitStatus {
                    mask: 4,
                    value: 0,
                    timeout: Duration::from_millis(5),
                },
                Op::Delay(Duration::from_micros(200 + u64::from(k))),
            ];
            let Response::Batch(r) = ask(&mut s, 2 + k, &Request::Batch(step)) else {
                panic!("batch reply");
            };
            assert!(matches!(r[1], Reply::Awaited { .. }));
        }
        let (mut runs, mut pins, mut moves) = (0u32, 0u32, 0u32);
        loop {
            let Response::Capture(c) = ask(
                &mut s,
                100,
                &Request::Capture {
                    runs,
                    pins,
                    moves,
                    max: 50,
                },
            ) else {
                panic!("capture reply");
            };
            runs += c.runs.len() as u32;
            pins += c.pins.len() as u32;
            moves += c.moves.len() as u32;
            if !c.more {
                break;
            }
        }
        // Every record came, counted from the reset; what the host had
        // fetched the bridge let go of (the last move and its runs kept).
        let rec = s.bus().record();
        let gone = s.forgotten;
        assert_eq!(
            (runs as usize, pins as usize, moves as usize),
            (
                rec.runs.len() + gone.runs,
                rec.pins.len() + gone.pins,
                rec.moves.len() + gone.moves
            )
        );
        assert_eq!(moves, 30);
        assert!(gone.moves > 0 && rec.moves.len() < 30, "{gone:?}");
        // Asking again for what was let go: refused, saying so.
        let Response::Error { code, detail } = ask(
            &mut s,
            101,
            &Request::Capture {
                runs: 0,
                pins: 0,
                moves: 0,
                max: 50,
            },
        ) else {
            panic!("an error");
        };
        assert_eq!(code, BridgeErrorCode::CaptureOverrun);
        assert!(detail.contains("let go"), "{detail}");
    }

    /// A batch of `ops`, with the capture from the last reset on (up to
    /// 60 records of each kind).
    fn from_the_reset(ops: Vec<Op>) -> Request {
        Request::BatchCapture {
            ops,
            runs: 0,
            pins: 0,
            moves: 0,
            max: 60,
        }
    }

    #[test]
    fn batch_capture_runs_the_ops_then_returns_the_capture_after_them() {
        let mut s = server();
        // Initialization, then a single step (0x4A): one move and one
        // pulse run.
        let mut ops = init_ops();
        ops.extend([
            Op::WriteCommand {
                byte: 0x4A,
                wait_ibf: Some(Duration::from_secs(1)),
            },
            Op::Delay(Duration::from_millis(5)),
        ]);
        let Response::BatchCapture { replies, capture } =
            ask(&mut s, 1, &from_the_reset(ops.clone()))
        else {
            panic!("batch-capture reply");
        };
        assert_eq!(replies.len(), ops.len());
        let rec = s.bus().record();
        assert_eq!(capture.moves.len(), rec.moves.len());
        assert_eq!(capture.runs, rec.runs);
        assert!(!capture.moves.is_empty(), "the step's move is in the chunk");
        let too_many = from_the_reset(vec![Op::ReadStatus; usize::from(MAX_BATCH_OPS) + 1]);
        assert!(matches!(
            ask(&mut s, 2, &too_many),
            Response::Error {
                code: BridgeErrorCode::Overflow,
                ..
            }
        ));
    }

    /// A bridge that keeps its move records from the bus knows a move was
    /// taken only once a status read shows IBF = 0 after its last byte
    /// (Section 3-1-1; the chip takes a byte no sooner than 6 us after its
    /// write, N11): until then the record is not served, so a record
    /// served is never withdrawn; the capture asked later brings it.
    #[test]
    fn a_move_record_is_served_once_a_status_read_shows_the_chip_took_it() {
        use crate::bridge::move_tracker::Tracked;
        let bus = EmuBus::new(Straps::default(), ModelConfig::default()).expect("emu");
        let mut s = BridgeEngine::new(Tracked::new(bus), 42, true, "test-bridge");
        let capture = |s: &mut BridgeEngine<Tracked<EmuBus>>, seq, ops: Vec<Op>| {
            let Response::BatchCapture { capture, .. } = ask(s, seq, &from_the_reset(ops)) else {
                panic!("batch-capture reply");
            };
            capture
        };
        capture(&mut s, 1, init_ops());
        // A single step (0x4A, no parameters): its code is its last byte,
        // and the engine's own status read comes while IBF is still 1.
        let step = Op::WriteCommand {
            byte: 0x4A,
            wait_ibf: Some(Duration::from_secs(1)),
        };
        let first = capture(&mut s, 2, vec![step]);
        assert_eq!(first.moves.len(), 0, "not served while tentative");
        assert!(!first.more);
        assert_eq!(s.bus().record().moves.len(), 1, "held");
        let later = capture(&mut s, 3, vec![Op::Delay(Duration::from_micros(50))]);
        assert_eq!(later.moves.len(), 1, "settled by the bridge's own read");
    }

    /// Initialization, then a constant-speed move (Section 3-3-5) of
    /// `steps` at rate 100, and its pulse period.
    fn moving_ops(steps: u32) -> (Vec<Op>, Duration) {
        use crate::protocol::{ClockSource, Command, Direction, MoveCommand, MoveKind, Straps};
        let mut ops = init_ops();
        let cmd = Command::Move(MoveCommand::new(MoveKind::Constant, Direction::Cw, false));
        let count = (steps - 1).to_le_bytes();
        ops.push(Op::WriteCommand {
            byte: cmd.encode(),
            wait_ibf: Some(Duration::from_secs(1)),
        });
        for b in [100, count[0], count[1], count[2]] {
            ops.push(Op::WriteData {
                byte: b,
                wait_ibf: Some(Duration::from_secs(1)),
            });
        }
        let st = Straps::default();
        let tclock = st.tclock(ClockSource::Internal).expect("internal clock");
        (ops, st.pulse_interval(100, tclock))
    }

    /// The reference model, with an ABORT arriving (through an
    /// [`AbortWatch`](crate::bridge::abort::AbortWatch) on the receive
    /// path) as the `at`th op of a batch ends: as a host's Ctrl-C
    /// lands while a board waits out a move.
    struct AbortingBus {
        emu: EmuBus,
        watch: Option<crate::bridge::abort::AbortWatch>,
        /// The frames the bridge has received by then: the batch, ABORT.
        stream: Vec<u8>,
        ops: usize,
        at: usize,
    }

    impl Bus for AbortingBus {
        fn run(&mut self, op: Op) -> Reply {
            let reply = self.emu.run(op);
            self.ops += 1;
            if self.ops == self.at {
                if let Some(w) = &mut self.watch {
                    w.on_bytes(&self.stream);
                }
            }
            reply
        }
        fn record(&self) -> &crate::protocol::OutputRecord {
            self.emu.record()
        }
        fn straps(&self) -> Straps {
            self.emu.straps()
        }
        fn now(&self) -> crate::time::Instant {
            self.emu.now()
        }
        fn watch_abort(&mut self, line: AbortLine) {
            self.watch = Some(crate::bridge::abort::AbortWatch::new(line));
        }
    }

    /// The ABORT of `docs/bridge-protocol.md` section 5: a move that would
    /// take 16,777,216 pulses (datasheet 3-3-4) is stopped where the
    /// batch had got to, the chip with it (an Immediate Stop, 3-3-1), the
    /// capture so far is kept, and ABORT_REPLY says the request was
    /// stopped.
    #[test]
    fn abort_stops_the_batch_and_the_move_and_keeps_the_capture() {
        let (mut ops, period) = moving_ops(16_777_216);
        let started = ops.len();
        ops.push(Op::Delay(Duration::from_nanos(period.as_nanos() * 50)));
        ops.push(Op::AwaitStatus {
            mask: crate::protocol::Status::BUSY,
            value: 0,
            timeout: Duration::from_secs(7_200),
        });
        let batch = Request::Batch(ops.clone()).encode(1, Timer::NANOS);
        let mut stream = frame::encode(&batch);
        stream.extend(frame::encode(
            &Request::Abort { request: 1 }.encode(2, Timer::NANOS),
        ));
        let bus = AbortingBus {
            emu: EmuBus::new(Straps::default(), ModelConfig::default()).expect("model"),
            watch: None,
            stream: stream.clone(),
            ops: 0,
            // After the move's 50 periods, before the wait for its end.
            at: started + 1,
        };
        let mut s = BridgeEngine::new(bus, 1, true, "test").with_abort(AbortLine::new());
        let out = s.on_bytes(&frame::encode(&batch));
        match collect(&out).1 {
            Response::Error {
                code: BridgeErrorCode::Aborted,
                detail,
            } => assert_eq!(
                detail,
                format!(
                    "stopped by ABORT after {} ops; the move was stopped (Immediate Stop)",
                    started + 1
                )
            ),
            other => panic!("not ABORTED: {other:?}"),
        }
        let emu = &s.bus().emu;
        assert!(!emu.board().read_status().busy(), "the chip is stopped");
        let pulses = emu.record().last_move_pulses().count;
        assert!(
            (50..=52).contains(&pulses),
            "the capture keeps the move's pulses so far: {pulses}"
        );
        // The ABORT itself, read after the batch's reply.
        let abort = Request::Abort { request: 1 };
        let out = s.on_bytes(&frame::encode(&abort.encode(2, Timer::NANOS)));
        assert_eq!(collect(&out).1, Response::Abort { stopped: true });
        // A request after it runs in full; an ABORT then stops nothing.
        let out = s.on_bytes(&frame::encode(
            &Request::Batch(vec![Op::ReadStatus]).encode(3, Timer::NANOS),
        ));
        assert!(matches!(collect(&out).1, Response::Batch(r) if r.len() == 1));
        let abort = Request::Abort { request: 3 };
        let out = s.on_bytes(&frame::encode(&abort.encode(4, Timer::NANOS)));
        assert_eq!(collect(&out).1, Response::Abort { stopped: false });
    }

    /// `pairs` pin samples `step` apart.
    fn samples(pairs: usize, step: Duration) -> Vec<Op> {
        (0..pairs)
            .flat_map(|_| [Op::ReadPins, Op::Delay(step)])
            .collect()
    }

    #[test]
    fn a_reply_too_long_for_255_fragments_is_an_overflow_error_not_cut_short() {
        // Sampled between one and two pulse periods apart, every sample of a
        // phase-stepping move differs from the one before: no run-length
        // saving, so 20 SAMPLE ops of 512 samples need about 60 KB.
        let (init, period) = moving_ops(100_000);
        let ops = samples(20 * wire::MAX_SAMPLES, period.scale(13, 10));
        let mut reference = server();
        init.iter().for_each(|op| {
            reference.bus.run(*op);
        });
        let replies: Vec<Reply> = ops.iter().map(|op| reference.bus.run(*op)).collect();
        let len = Response::Batch(replies).encode(1, Timer::NANOS).len();
        assert!(len > MAX_REPLY, "precondition: the reply is {len} bytes");
        let mut s = server();
        ask(&mut s, 1, &Request::Batch(init));
        let r = ask(&mut s, 2, &Request::Batch(ops));
        // The length said is the whole reply's, though the bridge kept no
        // more of it than fits.
        let says = format!("the reply takes {len} bytes");
        assert!(
            matches!(
                &r,
                Response::Error {
                    code: BridgeErrorCode::Overflow,
                    detail,
                } if detail.contains("send fewer ops") && detail.contains(&says)
            ),
            "{r:?}"
        );
    }

    /// A single step (0x4A), waited out: a move record, a pulse run and
    /// pin changes (BUSY, HOLD).
    fn single_step() -> [Op; 2] {
        [
            Op::WriteCommand {
                byte: 0x4A,
                wait_ibf: Some(Duration::from_secs(1)),
            },
            Op::Delay(Duration::from_millis(5)),
        ]
    }

    #[test]
    fn a_batch_stops_at_a_full_capture_and_a_chip_reset_starts_it_again() {
        let mut s = server().with_capture_capacity(20);
        ask(&mut s, 1, &Request::Batch(init_ops()));
        let held = |s: &BridgeEngine<EmuBus>| {
            let r = s.bus().record();
            (r.runs.len(), r.pins.len(), r.moves.len())
        };
        let (runs, pins, moves) = held(&s);
        assert!(runs + pins + moves < 20, "precondition");
        // Thirty steps in one batch: far more than the buffer holds.
        let steps: Vec<Op> = (0..30).flat_map(|_| single_step()).collect();
        let r = ask(&mut s, 2, &Request::Batch(steps));
        assert!(
            matches!(
                &r,
                Response::Error {
                    code: BridgeErrorCode::CaptureOverrun,
                    detail,
                } if detail.contains("the buffer holds 20")
            ),
            "{r:?}"
        );
        // It stopped at the op after the one that filled it: the capture
        // holds at most one op's records more than the buffer (a step's
        // wait adds its run and pin changes), moves counted.
        let (runs, pins, moves) = held(&s);
        assert!(moves < 30, "the batch stopped: {moves} moves");
        assert!(
            runs + pins + moves > 20 && runs + pins + moves <= 20 + 6,
            "{runs} runs, {pins} pin changes, {moves} moves"
        );
        // A batch without a reset does not run; the capture is overrun.
        let more = ask(&mut s, 3, &Request::Batch(single_step().to_vec()));
        assert!(matches!(
            more,
            Response::Error {
                code: BridgeErrorCode::CaptureOverrun,
                ..
            }
        ));
        assert_eq!(held(&s), (runs, pins, moves), "nothing ran");
        let capture = Request::Capture {
            runs: 0,
            pins: 0,
            moves: 0,
            max: 60,
        };
        assert!(matches!(
            ask(&mut s, 4, &capture),
            Response::Error {
                code: BridgeErrorCode::CaptureOverrun,
                ..
            }
        ));
        // A chip reset runs, and empties the capture.
        let mut ops = vec![Op::Reset];
        ops.extend(init_ops());
        ops.extend(single_step());
        let Response::Batch(replies) = ask(&mut s, 5, &Request::Batch(ops.clone())) else {
            panic!("the batch with a reset runs");
        };
        assert_eq!(replies.len(), ops.len());
        let Response::Capture(c) = ask(&mut s, 6, &capture) else {
            panic!("the capture is whole again");
        };
        assert_eq!(c.moves.len(), 1);
    }

    #[test]
    fn the_capture_chunk_shrinks_to_fit_beside_a_long_batch_reply() {
        let mut s = server();
        ask(&mut s, 1, &Request::Batch(init_ops()));
        // Many moves: a capture far longer than what fits beside the reply.
        for k in 0..200u8 {
            let step = vec![
                Op::WriteCommand {
                    byte: 0x4A,
                    wait_ibf: Some(Duration::from_secs(1)),
                },
                Op::Delay(Duration::from_micros(300)),
            ];
            ask(&mut s, k.wrapping_add(2), &Request::Batch(step));
        }
        let rec = s.bus().record();
        assert!(
            rec.pins.len() >= 300,
            "precondition: {} pin changes",
            rec.pins.len()
        );
        // 128 pulse summaries: the longest reply entries there are.
        let ops = vec![Op::ReadPulses; usize::from(MAX_BATCH_OPS)];
        let req = Request::BatchCapture {
            ops,
            runs: 0,
            pins: 0,
            moves: 0,
            max: 300,
        };
        let out = s.on_bytes(&frame::encode(&req.encode(100, Timer::NANOS)));
        let (seq, r) = collect(&out);
        assert_eq!(seq, 100);
        let Response::BatchCapture { replies, capture } = r else {
            panic!("batch-capture reply");
        };
        assert_eq!(replies.len(), usize::from(MAX_BATCH_OPS));
        assert!(capture.more, "the rest of the capture is left for later");
        assert!(!capture.moves.is_empty(), "as much as fits came along");
        let len = Response::BatchCapture { replies, capture }
            .encode(100, Timer::NANOS)
            .len();
        assert!(len <= MAX_REPLY, "{len} bytes");
    }
}
