//! The bridge simulator's I/O loop: the bridge engine over the reference
//! model ([`SimEngine`]) on a byte port (the master side of a
//! pseudo-terminal), with optional line faults and pacing to the wall clock.

use super::abort::{AbortLine, AbortWatch};
use super::engine::BridgeEngine;
use super::timed::Timed;
use super::wire::Timer;
use crate::bus::EmuBus;
use crate::time::Duration;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// What `ppmc bridge-sim` runs: the bridge engine over the reference model.
pub type SimEngine = BridgeEngine<SimBus>;

pub use super::sim_bus::{SimBus, SimChip};

/// The simulator's engine in front of the emulated chip `emu` (an
/// [`EmuBus`], or anything that becomes one, such as an `EmuTarget`);
/// `session` should differ between runs. The bridge's timer counts
/// nanoseconds, in step with the chip.
pub fn engine(emu: impl Into<EmuBus>, session: u32, virtual_time: bool) -> SimEngine {
    BridgeEngine::new(
        SimBus::new(SimChip::Exact(emu.into()), !virtual_time),
        session,
        virtual_time,
        format!("ppmc-bridge-sim {}", crate::VERSION),
    )
    .with_abort(AbortLine::new())
}

/// The simulator's engine with a timer of `timer_hz` that is not locked to
/// the chip's clock: every time on the wire is in its ticks, and pulses
/// are captured edge by edge at its resolution.
pub fn timed_engine(
    emu: impl Into<EmuBus>,
    session: u32,
    virtual_time: bool,
    timer_hz: u64,
) -> SimEngine {
    let timer = Timer { hz: timer_hz };
    BridgeEngine::new(
        SimBus::new(SimChip::Timed(Timed::new(emu.into(), timer)), !virtual_time),
        session,
        virtual_time,
        format!("ppmc-bridge-sim {} (timer {timer_hz} Hz)", crate::VERSION),
    )
    .with_timer(timer)
    .with_abort(AbortLine::new())
}

/// How the simulated link or board misbehaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkFaults {
    /// Probability that a byte (either direction) is lost.
    pub drop_rate: f64,
    /// Probability that a byte (either direction) has a bit flipped.
    pub corrupt_rate: f64,
    /// Probability that a byte (either direction) arrives twice.
    pub dup_rate: f64,
    /// Probability that a byte (either direction) swaps places with the
    /// byte after it.
    pub reorder_rate: f64,
    /// After this many frames the bridge stops answering (it keeps reading).
    pub stall_after: Option<u64>,
    /// After this many frames the bridge closes the link and ends.
    pub disconnect_after: Option<u64>,
    /// Seed of the fault draws, so a faulty run can be replayed.
    pub seed: u64,
}

impl Default for LinkFaults {
    fn default() -> Self {
        LinkFaults {
            drop_rate: 0.0,
            corrupt_rate: 0.0,
            dup_rate: 0.0,
            reorder_rate: 0.0,
            stall_after: None,
            disconnect_after: None,
            seed: 1,
        }
    }
}

/// How the simulated bridge itself behaves, as opposed to its link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimOptions {
    /// Hold each reply until the wall clock has caught up with the
    /// emulator's virtual time, and announce real time in HELLO_REPLY.
    pub realtime: bool,
    /// Records (pulse runs, pin changes and move records) the capture
    /// buffer holds (see [`BridgeEngine::with_capture_capacity`]).
    pub capture_capacity: u32,
    /// A bridge timer of this rate, not locked to the chip's clock (see
    /// [`timed_engine`]); `None`: a nanosecond timer in step with the chip.
    pub timer_hz: Option<u64>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            realtime: false,
            capture_capacity: u32::MAX,
            timer_hz: None,
        }
    }
}

/// Why [`serve`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServeEnd {
    /// `stop` was set.
    Stopped,
    /// The disconnect fault fired.
    Disconnected,
}

struct Faulty {
    f: LinkFaults,
    rng: StdRng,
}

impl Faulty {
    /// `bytes` as they come out of the faulty line. Each byte draws its
    /// faults in a fixed order (drop, corrupt, duplicate, reorder), so a
    /// seed replays the same line.
    fn apply(&mut self, bytes: &[u8]) -> Vec<u8> {
        let f = self.f;
        if f.drop_rate == 0.0 && f.corrupt_rate == 0.0 && f.dup_rate == 0.0 && f.reorder_rate == 0.0
        {
            return bytes.to_vec();
        }
        let mut out = Vec::with_capacity(bytes.len() + 8);
        // A byte held back to come after the next one.
        let mut held: Option<u8> = None;
        for &b in bytes {
            if self.rng.random::<f64>() < f.drop_rate {
                continue;
            }
            let b = if self.rng.random::<f64>() < f.corrupt_rate {
                b ^ (1 << self.rng.random_range(0..8))
            } else {
                b
            };
            let twice = self.rng.random::<f64>() < f.dup_rate;
            if held.is_none() && self.rng.random::<f64>() < f.reorder_rate {
                held = Some(b);
                continue;
            }
            out.push(b);
            if twice {
                out.push(b);
            }
            out.extend(held.take());
        }
        out.extend(held);
        out
    }
}

/// Serves the bridge protocol until `stop` is set or the disconnect fault
/// fires: requests read from `reader` (on a thread of its own, so that an
/// ABORT is heard while a request runs), replies written to `writer`.
///
/// With `realtime`, the chip's clock follows the wall clock, as a board's
/// does: the time between requests passes on the chip too (a move goes on
/// while the host is away), and each op returns when the wall clock has
/// caught up with it, so a request takes as long as its ops take on the
/// chip and an ABORT stops it within a few milliseconds. Runs are then no
/// longer repeatable, exactly as on a board.
///
/// The line's faults are drawn per direction, each from its own generator
/// seeded by the fault seed, so a seed replays the same line.
pub fn serve<R: Read + Send + 'static, W: Write>(
    reader: R,
    writer: &mut W,
    server: &mut SimEngine,
    faults: LinkFaults,
    realtime: bool,
    stop: &Arc<AtomicBool>,
) -> io::Result<ServeEnd> {
    let mut outgoing = Faulty {
        f: faults,
        rng: StdRng::seed_from_u64(faults.seed ^ OUTGOING_SEED),
    };
    let (tx, rx) = mpsc::channel();
    // Ends the reader when this returns, however it returns.
    let done = Arc::new(AtomicBool::new(false));
    let _reader = ReaderGuard {
        done: Arc::clone(&done),
        handle: Some(std::thread::spawn({
            let watch = server.abort_line().cloned().map(AbortWatch::new);
            let (stop, done) = (Arc::clone(stop), Arc::clone(&done));
            move || receive(reader, faults, watch, tx, &stop, &done)
        })),
    };
    server.bus_mut().stop_with(Arc::clone(stop));
    // When the chip's clock last caught up with the wall clock.
    let mut synced = WallInstant::now();
    while !stop.load(Ordering::Relaxed) {
        let incoming = match rx.recv_timeout(WallDuration::from_millis(20)) {
            Ok(bytes) => bytes,
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        if realtime {
            let began = WallInstant::now();
            server.pass_time(Duration::from_nanos(
                began.saturating_duration_since(synced).as_nanos() as u64,
            ));
            server.bus_mut().anchor_now();
        }
        let reply = server.on_bytes(&incoming);
        if faults.disconnect_after.is_some_and(|k| server.frames >= k) {
            return Ok(ServeEnd::Disconnected);
        }
        if realtime {
            synced = server.bus().due().unwrap_or_else(WallInstant::now);
        }
        if faults.stall_after.is_some_and(|k| server.frames >= k) {
            continue;
        }
        writer.write_all(&outgoing.apply(&reply))?;
        writer.flush()?;
    }
    Ok(ServeEnd::Stopped)
}

/// [`serve`] on the master side of a pseudo-terminal, read through a
/// second handle of its own.
pub fn serve_tty(
    master: &mut serialport::TTYPort,
    server: &mut SimEngine,
    faults: LinkFaults,
    realtime: bool,
    stop: &Arc<AtomicBool>,
) -> io::Result<ServeEnd> {
    let reader = master.try_clone_native().map_err(io::Error::other)?;
    serve(reader, master, server, faults, realtime, stop)
}

/// Mixed into the outgoing direction's seed, so that the two directions
/// draw different faults from one seed.
const OUTGOING_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

/// Stops the reader thread (at its next read timeout) when dropped.
struct ReaderGuard {
    done: Arc<AtomicBool>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl Drop for ReaderGuard {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// The receive path: reads what arrives, puts the line's faults on it,
/// shows it to the abort watch, and queues it for the engine.
fn receive<R: Read>(
    mut reader: R,
    faults: LinkFaults,
    mut watch: Option<AbortWatch>,
    tx: mpsc::Sender<Vec<u8>>,
    stop: &AtomicBool,
    done: &AtomicBool,
) {
    let mut incoming = Faulty {
        f: faults,
        rng: StdRng::seed_from_u64(faults.seed),
    };
    let mut buf = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) && !done.load(Ordering::Relaxed) {
        let n = match reader.read(&mut buf) {
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            // The other end closed (EIO on a pty master): wait for it to
            // open again.
            Err(_) => {
                std::thread::sleep(WallDuration::from_millis(20));
                0
            }
        };
        if n == 0 {
            continue;
        }
        let bytes = incoming.apply(&buf[..n]);
        if let Some(w) = &mut watch {
            w.on_bytes(&bytes);
        }
        if tx.send(bytes).is_err() {
            return;
        }
    }
}

/// A bridge simulator serving an emulator on its own thread, on a fresh
/// pseudo-terminal: what tests, `ppmc bench` and `ppmc fault-matrix` point
/// a serial target at. Dropping it stops the thread.
///
/// Hosts reach it through a symbolic link of its own in the temporary
/// directory ([`PtyBridge::path`]), removed when the bridge stops serving,
/// as a board is reached through a stable device path: the kernel reuses a
/// pseudo-terminal's number as soon as it is free, so a host reconnecting
/// to a bridge that went away could otherwise open another one.
#[derive(Debug)]
pub struct PtyBridge {
    path: String,
    stop: Arc<AtomicBool>,
    handle: Option<std::thread::JoinHandle<Option<ServeEnd>>>,
}

impl PtyBridge {
    /// Serves `emu` (in virtual time) with `faults` on the link.
    pub fn start(emu: impl Into<EmuBus>, faults: LinkFaults) -> io::Result<PtyBridge> {
        Self::start_with(emu, faults, SimOptions::default())
    }

    /// Serves `emu` as a bridge set up by `bridge`, with `faults` on the
    /// link.
    pub fn start_with(
        emu: impl Into<EmuBus>,
        faults: LinkFaults,
        bridge: SimOptions,
    ) -> io::Result<PtyBridge> {
        use serialport::SerialPort;
        let emu: EmuBus = emu.into();
        let (mut master, slave) = serialport::TTYPort::pair().map_err(io::Error::other)?;
        master
            .set_timeout(WallDuration::from_millis(20))
            .map_err(io::Error::other)?;
        let pty = slave
            .name()
            .ok_or_else(|| io::Error::other("the pseudo-terminal has no path"))?;
        let path = link_to(&pty)?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let link = path.clone();
        let handle = std::thread::spawn(move || {
            let _keep_open = slave;
            let server = match bridge.timer_hz {
                Some(hz) => timed_engine(emu, 0x5EED, !bridge.realtime, hz),
                None => engine(emu, 0x5EED, !bridge.realtime),
            };
            let mut server = server.with_capture_capacity(bridge.capture_capacity);
            let end = match master.try_clone_native() {
                Ok(reader) => serve(
                    reader,
                    &mut master,
                    &mut server,
                    faults,
                    bridge.realtime,
                    &flag,
                )
                .ok(),
                Err(_) => None,
            };
            // Gone before the pty is: a host reconnecting now finds nothing.
            let _ = std::fs::remove_file(&link);
            end
        });
        Ok(PtyBridge {
            path,
            stop,
            handle: Some(handle),
        })
    }

    /// The bridge's path (a link to its pty), for `serial:<path>`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Stops serving; how the serve loop ended (`None` if it failed).
    pub fn stop(mut self) -> Option<ServeEnd> {
        self.halt()
    }

    fn halt(&mut self) -> Option<ServeEnd> {
        self.stop.store(true, Ordering::Relaxed);
        self.handle.take().and_then(|h| h.join().ok().flatten())
    }
}

impl Drop for PtyBridge {
    fn drop(&mut self) {
        self.halt();
        let _ = std::fs::remove_file(&self.path);
    }
}

/// A new symbolic link to `pty` in the temporary directory, under a name
/// no other bridge of this process has used.
fn link_to(pty: &str) -> io::Result<String> {
    use std::sync::atomic::AtomicUsize;
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let link = std::env::temp_dir().join(format!("ppmc-pty-{}-{n}", std::process::id()));
        match std::os::unix::fs::symlink(pty, &link) {
            Ok(()) => {
                return link
                    .into_os_string()
                    .into_string()
                    .map_err(|_| io::Error::other("the temporary directory's path is not UTF-8"))
            }
            // Left by an earlier process with this id: take another name.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Why `--link` could not be placed: a path of someone else's (the user's
/// to change), or the file system's refusal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkRefused {
    /// Something at the path that is not a stale bridge-sim link.
    Taken(String),
    /// The file system refused.
    Io(String),
}

impl std::fmt::Display for LinkRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkRefused::Taken(why) | LinkRefused::Io(why) => f.write_str(why),
        }
    }
}

/// Makes `link` a symbolic link to the pty at `pty`. Something already at
/// `link` is replaced only when it is a stale link of a bridge-sim (a link
/// to a pseudo-terminal that is gone); anything else is refused.
#[cfg(unix)]
pub fn place_link(link: &std::path::Path, pty: &str) -> Result<(), LinkRefused> {
    let io = |e: std::io::Error| LinkRefused::Io(format!("{}: {e}", link.display()));
    match std::fs::symlink_metadata(link) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(io(e)),
        Ok(meta) if meta.file_type().is_symlink() => {
            let to = std::fs::read_link(link).unwrap_or_default();
            let stale_pty = to.starts_with("/dev/pts/") && !to.exists();
            if !stale_pty {
                return Err(LinkRefused::Taken(format!(
                    "--link {}: is a link to {}, not a stale bridge-sim link; \
                     remove it or choose another path",
                    link.display(),
                    to.display()
                )));
            }
            std::fs::remove_file(link).map_err(io)?;
        }
        Ok(_) => {
            return Err(LinkRefused::Taken(format!(
                "--link {}: exists and is not a link; bridge-sim replaces only a \
                 stale link of its own",
                link.display()
            )));
        }
    }
    std::os::unix::fs::symlink(pty, link)
        .map_err(|e| LinkRefused::Io(format!("cannot link {} to {pty}: {e}", link.display())))
}

/// Removes `link` if it is still this bridge's link to `pty`.
pub fn remove_own_link(link: &std::path::Path, pty: &str) {
    if std::fs::read_link(link).is_ok_and(|to| to == std::path::Path::new(pty)) {
        let _ = std::fs::remove_file(link);
    }
}

impl LinkFaults {
    /// Each rate a probability from 0 to 1: the first that is not, named
    /// by its option.
    pub fn check(&self) -> Result<(), String> {
        for (name, rate) in [
            ("--drop-rate", self.drop_rate),
            ("--corrupt-rate", self.corrupt_rate),
            ("--dup-rate", self.dup_rate),
            ("--reorder-rate", self.reorder_rate),
        ] {
            if !(0.0..=1.0).contains(&rate) {
                return Err(format!("{name} {rate}: give a probability from 0 to 1"));
            }
        }
        Ok(())
    }
}
