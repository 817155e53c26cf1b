//! A chaos proxy: a TCP server between ppmc and a bridge that misbehaves
//! the way lab networks and serial servers do, on purpose, so that the
//! link layer can be proven never to turn a broken link into a verdict on
//! the board (`docs/detection.md`, "The link under attack").
//!
//! The proxy listens (on 127.0.0.1 in the tests), forwards to a bridge
//! reached over TCP (`ser2net`) or a serial port (a `ppmc bridge-sim`
//! pseudo-terminal, a board), and applies one [`Behaviour`]. It keeps its
//! own connection to the bridge across the host's connections, as a
//! serial server does, so that cutting the host's connection leaves the
//! bridge's state behind it: exactly the case where a request the bridge
//! ran must not run again when the host reconnects and sends it anew.
//!
//! `ppmc chaos-proxy` serves it from the command line, for a lab to
//! qualify its own network and bridge.

use crate::backend::timed_out;
use ppmc_core::bridge::frame::{self, FrameDecoder};
use ppmc_core::bridge::wire::{BridgeErrorCode, Response, Timer};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::fmt;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What the proxy does to the traffic. Frames are counted on each host
/// connection, both ways.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Behaviour {
    /// Forwards everything: the reference.
    Clean,
    /// Cuts the host's connection after every `n` frames; the bridge's
    /// connection stays up.
    DropEvery(u64),
    /// Cuts the host's connection once, after the `k`-th frame the proxy
    /// passed on in its life (over every connection); the bridge's stays.
    /// Run with every `k` of a clean run in turn, it drops the connection
    /// at every frame boundary.
    DropAt(u64),
    /// Cuts both connections after every `n` frames (what ser2net does when
    /// its client goes: it closes and reopens the port).
    DropBothEvery(u64),
    /// Cuts the host's connection at a random byte, one in `n` on average.
    DropRandomByte(u64),
    /// After every `n` frames nothing moves for [`STALL`]; then the held
    /// bytes go on.
    Stall(u64),
    /// Accepts every connection and closes it at once (ser2net with its
    /// device missing or busy).
    AcceptClose,
    /// Answers with random bytes, without end.
    FloodRandom,
    /// Forwards the first `n` frames of its life, then answers every
    /// connection with random bytes, without end: a link that turns bad in
    /// the middle of a run.
    FloodAfter(u64),
    /// Answers with 0xFF bytes, without end.
    FloodFf,
    /// Answers with one frame that never ends (no delimiter, ever).
    EndlessFrame,
    /// Answers with random bytes at one a second.
    Trickle,
    /// Forwards, but every reply carries another sequence number.
    WrongSeq,
    /// Answers every request with an ERROR frame, and forwards nothing.
    ErrorOnly,
    /// Sends telnet option negotiations without end (against an
    /// `rfc2217://` target).
    OptionStorm,
    /// Forwards, sending every `n`-th frame twice.
    Duplicate(u64),
    /// Forwards, swapping every `n`-th frame with the one after it.
    Reorder(u64),
    /// After every `n` frames the host's connection goes silent both ways
    /// and is never closed (a peer gone without a word); the next
    /// connection works.
    HalfOpen(u64),
}

impl Behaviour {
    /// Every behaviour, with the parameters the CI runs it with, by name.
    pub const ALL: &'static [&'static str] = &[
        "clean",
        "drop-every=40",
        "drop-every=60",
        "drop-every=100",
        "drop-both-every=40",
        "drop-random-byte=3000",
        "stall=400",
        "accept-close",
        "flood-random",
        "flood-after=300",
        "flood-ff",
        "endless-frame",
        "trickle",
        "wrong-seq",
        "error-only",
        "option-storm",
        "duplicate=5",
        "reorder=5",
        "half-open=300",
    ];

    /// Whether it passes the bridge's traffic on at all.
    pub fn forwards(self) -> bool {
        !matches!(
            self,
            Behaviour::AcceptClose
                | Behaviour::FloodRandom
                | Behaviour::FloodFf
                | Behaviour::EndlessFrame
                | Behaviour::Trickle
                | Behaviour::ErrorOnly
                | Behaviour::OptionStorm
        )
    }
}

impl FromStr for Behaviour {
    type Err = String;

    fn from_str(s: &str) -> Result<Behaviour, String> {
        let (name, arg) = match s.split_once('=') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        let n = || -> Result<u64, String> {
            let a = arg.ok_or_else(|| format!("{name}: give a count, e.g. {name}=40"))?;
            a.parse::<u64>()
                .ok()
                .filter(|n| *n > 0)
                .ok_or_else(|| format!("{name}={a}: give a whole number above 0"))
        };
        let plain = |b: Behaviour| match arg {
            None => Ok(b),
            Some(_) => Err(format!("{name} takes no count")),
        };
        match name {
            "clean" => plain(Behaviour::Clean),
            "drop-every" => Ok(Behaviour::DropEvery(n()?)),
            "drop-at" => Ok(Behaviour::DropAt(n()?)),
            "drop-both-every" => Ok(Behaviour::DropBothEvery(n()?)),
            "drop-random-byte" => Ok(Behaviour::DropRandomByte(n()?)),
            "stall" => Ok(Behaviour::Stall(n()?)),
            "accept-close" => plain(Behaviour::AcceptClose),
            "flood-random" => plain(Behaviour::FloodRandom),
            "flood-after" => Ok(Behaviour::FloodAfter(n()?)),
            "flood-ff" => plain(Behaviour::FloodFf),
            "endless-frame" => plain(Behaviour::EndlessFrame),
            "trickle" => plain(Behaviour::Trickle),
            "wrong-seq" => plain(Behaviour::WrongSeq),
            "error-only" => plain(Behaviour::ErrorOnly),
            "option-storm" => plain(Behaviour::OptionStorm),
            "duplicate" => Ok(Behaviour::Duplicate(n()?)),
            "reorder" => Ok(Behaviour::Reorder(n()?)),
            "half-open" => Ok(Behaviour::HalfOpen(n()?)),
            _ => Err(format!(
                "unknown behaviour `{s}`; one of: {}",
                Behaviour::ALL.join(", ")
            )),
        }
    }
}

impl fmt::Display for Behaviour {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Behaviour::Clean => f.write_str("clean"),
            Behaviour::DropEvery(n) => write!(f, "drop-every={n}"),
            Behaviour::DropAt(n) => write!(f, "drop-at={n}"),
            Behaviour::DropBothEvery(n) => write!(f, "drop-both-every={n}"),
            Behaviour::DropRandomByte(n) => write!(f, "drop-random-byte={n}"),
            Behaviour::Stall(n) => write!(f, "stall={n}"),
            Behaviour::AcceptClose => f.write_str("accept-close"),
            Behaviour::FloodRandom => f.write_str("flood-random"),
            Behaviour::FloodAfter(n) => write!(f, "flood-after={n}"),
            Behaviour::FloodFf => f.write_str("flood-ff"),
            Behaviour::EndlessFrame => f.write_str("endless-frame"),
            Behaviour::Trickle => f.write_str("trickle"),
            Behaviour::WrongSeq => f.write_str("wrong-seq"),
            Behaviour::ErrorOnly => f.write_str("error-only"),
            Behaviour::OptionStorm => f.write_str("option-storm"),
            Behaviour::Duplicate(n) => write!(f, "duplicate={n}"),
            Behaviour::Reorder(n) => write!(f, "reorder={n}"),
            Behaviour::HalfOpen(n) => write!(f, "half-open={n}"),
        }
    }
}

/// Where the bridge is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Upstream {
    /// `host:port` of a raw TCP server (ser2net, socat).
    Tcp(String),
    /// A serial port or pseudo-terminal.
    Serial(String),
}

impl FromStr for Upstream {
    type Err = String;

    fn from_str(s: &str) -> Result<Upstream, String> {
        if let Some(addr) = s.strip_prefix("tcp://") {
            return crate::backend::parse_tcp(s)
                .map(|_| Upstream::Tcp(addr.to_string()))
                .ok_or_else(|| format!("{s}: give tcp://<host>:<port>"));
        }
        match s.strip_prefix("serial:") {
            Some(p) if !p.is_empty() => Ok(Upstream::Serial(p.to_string())),
            _ => Err(format!(
                "{s}: give serial:<path> or tcp://<host>:<port> for the bridge"
            )),
        }
    }
}

/// What the proxy did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Host connections accepted.
    pub connections: u64,
    /// Host connections cut, closed at once or left half-open.
    pub cuts: u64,
    /// Whole frames passed on, both ways.
    pub frames: u64,
    /// Times the behaviour acted other than by a cut: stalls begun, frames
    /// sent twice or out of order, floods begun.
    pub acts: u64,
}

/// A running chaos proxy; stopped (and its port closed) when dropped.
#[derive(Debug)]
pub struct ChaosProxy {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Stats>>,
}

impl ChaosProxy {
    /// Listens on `listen` (`127.0.0.1:0` for a free port) and serves
    /// until stopped. The bridge is opened now (for the behaviours that
    /// forward), so that a missing one is an error here.
    pub fn start(
        listen: &str,
        upstream: Upstream,
        behaviour: Behaviour,
        seed: u64,
    ) -> io::Result<ChaosProxy> {
        let listener = TcpListener::bind(listen)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let up = match behaviour.forwards() {
            true => Some(Port::open_patiently(&upstream)?),
            false => None,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let mut proxy = Proxy {
            behaviour,
            upstream,
            up,
            down: None,
            zombies: Vec::new(),
            rng: StdRng::seed_from_u64(seed),
            stats: Stats::default(),
            conn: Conn::default(),
            errors: 0,
        };
        let thread = std::thread::Builder::new()
            .name(format!("chaos {behaviour}"))
            .spawn(move || {
                while !flag.load(Ordering::Relaxed) {
                    proxy.turn(&listener);
                }
                proxy.stats
            })?;
        Ok(ChaosProxy {
            addr,
            stop,
            thread: Some(thread),
        })
    }

    /// Where it listens.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Stops it; what it did.
    pub fn stop(mut self) -> Stats {
        self.halt()
    }

    fn halt(&mut self) -> Stats {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default()
    }
}

impl Drop for ChaosProxy {
    fn drop(&mut self) {
        self.halt();
    }
}

/// The bridge's side: a TCP connection or a serial port.
enum Port {
    Tcp(TcpStream),
    Serial(Box<dyn serialport::SerialPort>),
}

/// How long a stall holds the traffic: longer than a reply is waited for
/// at the first try, so that the host asks again into the stall.
pub const STALL: Duration = Duration::from_millis(1500);

/// How long opening a serial bridge is tried while the port is there.
const SERIAL_OPEN_PATIENCE: Duration = Duration::from_secs(5);

/// How long one look at a side waits for bytes.
const POLL: Duration = Duration::from_millis(1);

impl Port {
    fn open(at: &Upstream) -> io::Result<Port> {
        match at {
            Upstream::Tcp(addr) => {
                let s = TcpStream::connect(addr)?;
                s.set_nodelay(true)?;
                s.set_read_timeout(Some(POLL))?;
                Ok(Port::Tcp(s))
            }
            Upstream::Serial(path) => serialport::new(path, 115_200)
                .timeout(POLL)
                .open()
                .map(Port::Serial)
                .map_err(io::Error::from),
        }
    }

    /// [`Port::open`], when the proxy starts. A serial bridge's
    /// pseudo-terminal just closed by its last opener (the proxy before
    /// this one, on the same bridge) refuses a new opener's claim for a
    /// moment on a busy machine (serialport's "Unable to acquire exclusive
    /// lock"): tried again for up to [`SERIAL_OPEN_PATIENCE`] while the
    /// port is there.
    fn open_patiently(at: &Upstream) -> io::Result<Port> {
        let deadline = std::time::Instant::now() + SERIAL_OPEN_PATIENCE;
        loop {
            match Port::open(at) {
                Err(_)
                    if matches!(at, Upstream::Serial(path) if std::path::Path::new(path).exists())
                        && std::time::Instant::now() < deadline =>
                {
                    std::thread::sleep(Duration::from_millis(20));
                }
                opened => return opened,
            }
        }
    }

    /// Bytes that arrived within [`POLL`]; `Ok(0)` when none did.
    fn read_some(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let r = match self {
            Port::Tcp(s) => match s.read(buf) {
                Ok(0) => Err(io::Error::new(
                    io::ErrorKind::ConnectionAborted,
                    "the bridge's server closed the connection",
                )),
                r => r,
            },
            Port::Serial(p) => p.read(buf),
        };
        match r {
            Err(e) if timed_out(&e) => Ok(0),
            r => r,
        }
    }

    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        match self {
            Port::Tcp(s) => s.write_all(bytes),
            Port::Serial(p) => p.write_all(bytes),
        }
    }
}

/// Frame boundaries in one direction of a byte stream.
#[derive(Debug, Default)]
struct Frames {
    current: Vec<u8>,
}

impl Frames {
    /// Adds `b`; a whole frame (with its delimiter) when `b` ends one. An
    /// empty frame (a lone delimiter) is passed on as it is.
    fn push(&mut self, b: u8) -> Option<Vec<u8>> {
        self.current.push(b);
        (b == 0).then(|| std::mem::take(&mut self.current))
    }
}

/// The state of one host connection.
#[derive(Debug, Default)]
struct Conn {
    /// Whole frames passed on, both ways.
    frames: u64,
    from_host: Frames,
    from_bridge: Frames,
    /// Bytes held while stalled, each way.
    held_up: Vec<u8>,
    held_down: Vec<u8>,
    stalled_until: Option<Instant>,
    /// A frame held back to be sent after the next one (reorder), and
    /// when it must go anyway.
    swapped: Option<(Vec<u8>, Instant)>,
    /// The next trickle byte is due.
    trickle_at: Option<Instant>,
}

struct Proxy {
    behaviour: Behaviour,
    upstream: Upstream,
    up: Option<Port>,
    down: Option<TcpStream>,
    /// Connections left half-open: never read, written or closed.
    zombies: Vec<TcpStream>,
    rng: StdRng,
    stats: Stats,
    conn: Conn,
    /// Error codes answered so far (error-only).
    errors: u64,
}

/// Half-open connections kept at most; the oldest is closed past that, so
/// that a long session does not run out of file descriptors.
const MAX_ZOMBIES: usize = 64;

/// The telnet commands of an option storm: every option offered and asked
/// for, again and again.
fn storm_bytes() -> Vec<u8> {
    (0u8..=255)
        .flat_map(|opt| [255, 251, opt, 255, 253, opt, 255, 250, opt, 1, 255, 240])
        .collect()
}

impl Proxy {
    /// One turn of the loop: accept, pass bytes each way, make noise.
    fn turn(&mut self, listener: &TcpListener) {
        if let Ok((s, _)) = listener.accept() {
            self.accept(s);
        }
        let mut buf = [0u8; 4096];
        if let Some(d) = &mut self.down {
            match d.read(&mut buf) {
                Ok(0) => self.down = None,
                Ok(n) => self.took_from_host(&buf[..n]),
                Err(e) if timed_out(&e) => {}
                Err(_) => self.down = None,
            }
        }
        if let Some(up) = &mut self.up {
            match up.read_some(&mut buf) {
                Ok(n) if n > 0 => self.took_from_bridge(&buf[..n]),
                Ok(_) => {}
                // The bridge's side failed: open it again next time.
                Err(_) => self.up = None,
            }
        } else {
            std::thread::sleep(POLL);
        }
        if self.behaviour.forwards() && self.up.is_none() {
            self.up = Port::open(&self.upstream).ok();
        }
        self.noise();
        self.timers();
    }

    fn accept(&mut self, s: TcpStream) {
        self.stats.connections += 1;
        if self.behaviour == Behaviour::AcceptClose {
            self.stats.cuts += 1;
            return;
        }
        let _ = s.set_nodelay(true);
        let _ = s.set_read_timeout(Some(POLL));
        let _ = s.set_write_timeout(Some(Duration::from_secs(2)));
        // A new host connection replaces the old one, as the host's
        // reconnect means the old one is dead to it.
        self.down = Some(s);
        self.conn = Conn::default();
        if self.behaviour == Behaviour::OptionStorm {
            // Sent at once and then without end (in `noise`).
            self.send_down(&storm_bytes());
        }
    }

    /// Sends to the host; a host that does not take it is cut.
    fn send_down(&mut self, bytes: &[u8]) {
        if let Some(d) = &mut self.down {
            if d.write_all(bytes).is_err() {
                self.down = None;
            }
        }
    }

    fn send_up(&mut self, bytes: &[u8]) {
        if let Some(up) = &mut self.up {
            if up.write_all(bytes).is_err() {
                self.up = None;
            }
        }
    }

    /// Cuts the host's connection (and, for drop-both, the bridge's).
    fn cut(&mut self) {
        self.stats.cuts += 1;
        if let Some(d) = self.down.take() {
            let _ = d.shutdown(std::net::Shutdown::Both);
        }
        if matches!(self.behaviour, Behaviour::DropBothEvery(_)) {
            self.up = None;
        }
    }

    fn took_from_host(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.down.is_none() {
                return;
            }
            if let Behaviour::DropRandomByte(n) = self.behaviour {
                if self.rng.random_range(0..n) == 0 {
                    // Part of a request reaches the bridge, then the cut,
                    // as a serial server forwards what it got.
                    let part = std::mem::take(&mut self.conn.from_host.current);
                    self.send_up(&part);
                    self.cut();
                    return;
                }
            }
            let Some(frame) = self.conn.from_host.push(b) else {
                continue;
            };
            match self.behaviour {
                Behaviour::ErrorOnly => self.answer_error(&frame),
                b if !b.forwards() => {}
                _ => self.pass_up(frame),
            }
        }
    }

    fn took_from_bridge(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let (Behaviour::DropRandomByte(n), Some(_)) = (self.behaviour, &self.down) {
                if self.rng.random_range(0..n) == 0 {
                    // Part of a reply reaches the host, then the cut.
                    let part = std::mem::take(&mut self.conn.from_bridge.current);
                    self.send_down(&part);
                    self.cut();
                }
            }
            let Some(frame) = self.conn.from_bridge.push(b) else {
                continue;
            };
            if self.down.is_none() {
                // Nobody to take it: a reply lost with the connection.
                continue;
            }
            self.pass_down(frame);
        }
    }

    fn pass_up(&mut self, frame: Vec<u8>) {
        if self.flooding() {
            return;
        }
        if frame == [0] {
            self.send_up(&frame);
            return;
        }
        if self.conn.stalled_until.is_some() {
            self.conn.held_up.extend(frame);
            return;
        }
        self.send_up(&frame);
        if let Behaviour::Duplicate(n) = self.behaviour {
            if self.conn.frames % n == n - 1 {
                self.stats.acts += 1;
                self.send_up(&frame);
            }
        }
        self.after_frame();
    }

    /// A flood-after proxy past its frames: nothing is forwarded any more.
    fn flooding(&self) -> bool {
        matches!(self.behaviour, Behaviour::FloodAfter(n) if self.stats.frames >= n)
    }

    fn pass_down(&mut self, frame: Vec<u8>) {
        if self.flooding() {
            return;
        }
        if frame == [0] {
            self.send_down(&frame);
            return;
        }
        if self.conn.stalled_until.is_some() {
            self.conn.held_down.extend(frame);
            return;
        }
        match self.behaviour {
            Behaviour::WrongSeq => {
                let mut d = FrameDecoder::new();
                d.extend(&frame);
                match d.decode() {
                    Ok(Some(mut payload)) if !payload.is_empty() => {
                        payload[0] = payload[0].wrapping_add(97);
                        self.send_down(&frame::encode(&payload));
                    }
                    _ => self.send_down(&frame),
                }
            }
            Behaviour::Duplicate(n) if self.conn.frames % n == n - 1 => {
                self.stats.acts += 1;
                self.send_down(&frame);
                self.send_down(&frame);
            }
            Behaviour::Reorder(n)
                if self.conn.swapped.is_none() && self.conn.frames % n == n - 1 =>
            {
                self.stats.acts += 1;
                self.conn.swapped = Some((frame, Instant::now() + Duration::from_millis(5)));
                self.after_frame();
                return;
            }
            _ => {
                self.send_down(&frame);
                if let Some((held, _)) = self.conn.swapped.take() {
                    self.send_down(&held);
                }
            }
        }
        self.after_frame();
    }

    /// What happens at a frame boundary, once the frame has gone on: it is
    /// counted, and the behaviours that act every so many frames act.
    fn after_frame(&mut self) {
        self.conn.frames += 1;
        self.stats.frames += 1;
        let frames = self.conn.frames;
        match self.behaviour {
            Behaviour::DropEvery(n) | Behaviour::DropBothEvery(n) if frames % n == 0 => self.cut(),
            Behaviour::DropAt(k) if self.stats.frames == k => self.cut(),
            Behaviour::Stall(n) if frames % n == 0 => {
                self.stats.acts += 1;
                self.conn.stalled_until = Some(Instant::now() + STALL);
            }
            Behaviour::HalfOpen(n) if frames % n == 0 => {
                self.stats.cuts += 1;
                if let Some(d) = self.down.take() {
                    if self.zombies.len() >= MAX_ZOMBIES {
                        self.zombies.remove(0);
                    }
                    self.zombies.push(d);
                }
            }
            _ => {}
        }
    }

    /// An ERROR frame for the request in `frame`, with its sequence number
    /// (a bad-frame error carries 0, as the protocol says).
    fn answer_error(&mut self, frame: &[u8]) {
        let mut d = FrameDecoder::new();
        d.extend(frame);
        let seq = match d.decode() {
            Ok(Some(p)) if !p.is_empty() => p[0],
            _ => return,
        };
        // A bad frame first, which a host must take as noise and ask
        // again; then the errors that answer a request.
        let codes = [
            BridgeErrorCode::BadFrame,
            BridgeErrorCode::Malformed,
            BridgeErrorCode::BadFrame,
            BridgeErrorCode::UnknownOp,
            BridgeErrorCode::Overflow,
        ];
        let code = codes[(self.errors % codes.len() as u64) as usize];
        self.errors += 1;
        let seq = if code == BridgeErrorCode::BadFrame {
            0
        } else {
            seq
        };
        let reply = Response::Error {
            code,
            detail: "chaos proxy: error-only".into(),
        };
        self.send_down(&frame::encode(&reply.encode(seq, Timer::NANOS)));
    }

    /// The behaviours that send on their own.
    fn noise(&mut self) {
        if self.down.is_none() {
            return;
        }
        match self.behaviour {
            Behaviour::FloodRandom => {
                let mut b = [0u8; 1024];
                self.rng.fill(&mut b[..]);
                self.send_down(&b);
            }
            Behaviour::FloodAfter(n) if self.stats.frames >= n => {
                self.stats.acts = 1;
                let mut b = [0u8; 1024];
                self.rng.fill(&mut b[..]);
                self.send_down(&b);
            }
            Behaviour::FloodFf => self.send_down(&[0xFF; 1024]),
            Behaviour::EndlessFrame => {
                let mut b = [0u8; 1024];
                self.rng.fill(&mut b[..]);
                for x in &mut b {
                    *x = (*x).max(1);
                }
                self.send_down(&b);
            }
            Behaviour::OptionStorm => self.send_down(&storm_bytes()),
            Behaviour::Trickle => {
                let now = Instant::now();
                let due = *self.conn.trickle_at.get_or_insert(now);
                if now >= due {
                    let b = [self.rng.random::<u8>()];
                    self.send_down(&b);
                    self.conn.trickle_at = Some(due + Duration::from_secs(1));
                }
            }
            _ => {}
        }
    }

    /// Ends a stall, sends a swapped frame that waited long enough.
    fn timers(&mut self) {
        let now = Instant::now();
        if self.conn.stalled_until.is_some_and(|t| now >= t) {
            self.conn.stalled_until = None;
            let up = std::mem::take(&mut self.conn.held_up);
            let down = std::mem::take(&mut self.conn.held_down);
            self.send_up(&up);
            self.send_down(&down);
        }
        if self.conn.swapped.as_ref().is_some_and(|(_, t)| now >= *t) {
            if let Some((held, _)) = self.conn.swapped.take() {
                self.send_down(&held);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_behaviour_parses_and_prints_back() {
        for name in Behaviour::ALL {
            let b: Behaviour = name.parse().expect(name);
            assert_eq!(b.to_string(), *name);
        }
        for bad in ["drop-every", "drop-every=0", "clean=3", "flood", "stall=x"] {
            assert!(bad.parse::<Behaviour>().is_err(), "{bad}");
        }
        assert_eq!(
            "tcp://127.0.0.1:2000".parse(),
            Ok(Upstream::Tcp("127.0.0.1:2000".into()))
        );
        assert!("tcp://nowhere".parse::<Upstream>().is_err());
        assert!("/dev/pts/3".parse::<Upstream>().is_err());
    }

    /// The proxy cuts the host's connection at the frame count it was
    /// given, and keeps the bridge's: what the host sent before the cut
    /// reached the bridge, whole.
    #[test]
    fn drop_every_cuts_the_host_side_after_n_frames_and_keeps_the_bridge_side() {
        let bridge = TcpListener::bind("127.0.0.1:0").expect("listen");
        let up = Upstream::Tcp(bridge.local_addr().expect("addr").to_string());
        let proxy =
            ChaosProxy::start("127.0.0.1:0", up, Behaviour::DropEvery(3), 1).expect("proxy");
        let (mut bridge_side, _) = bridge.accept().expect("the proxy connects");
        bridge_side
            .set_read_timeout(Some(Duration::from_secs(5)))
            .expect("timeout");
        let mut host = TcpStream::connect(proxy.addr()).expect("connect");
        host.set_read_timeout(Some(Duration::from_secs(5)))
            .expect("timeout");
        host.write_all(&[1, 1, 0, 2, 2, 0, 3, 3, 0, 4, 4, 0])
            .expect("send");
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        while got.len() < 9 {
            let n = bridge_side.read(&mut buf).expect("the bridge reads");
            got.extend_from_slice(&buf[..n]);
        }
        assert_eq!(
            got,
            [1, 1, 0, 2, 2, 0, 3, 3, 0],
            "three frames, then the cut"
        );
        // The host's connection is closed.
        let mut end = [0u8; 8];
        assert!(matches!(host.read(&mut end), Ok(0) | Err(_)));
        // A new connection goes through the same bridge connection.
        let mut again = TcpStream::connect(proxy.addr()).expect("reconnect");
        again.write_all(&[5, 5, 0]).expect("send");
        let mut more = [0u8; 3];
        bridge_side.read_exact(&mut more).expect("same bridge side");
        assert_eq!(more, [5, 5, 0]);
        let stats = proxy.stop();
        assert!(stats.connections >= 2 && stats.cuts >= 1, "{stats:?}");
    }
}
