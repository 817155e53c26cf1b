//! `ppmc-twin`, run by `firmware/run-twin`: the RP2350 bridge's board code
//! (`ppmc_bridge_fw::board`) on the board twin (a model of the RP2350's PIO
//! blocks and GPIOs wired pin by pin to the reference chip model), behind
//! the same `BridgeEngine` the image runs, serving the bridge protocol on a
//! pseudo-terminal as `ppmc bridge-sim` and `firmware/run-qemu` do.
//!
//! Time is virtual: it passes as the twin simulates, cycle by cycle where
//! anything happens, so runs are repeatable.

use ppmc_bridge_fw::twin;
use ppmc_core::bridge::abort::{AbortLine, AbortWatch};
use ppmc_core::bridge::engine::BridgeEngine;
use ppmc_core::bridge::frame::{self, FrameDecoder};
use ppmc_core::bridge::wire::{Response, Timer};
use ppmc_core::emu::{faults, ModelConfig};
use ppmc_core::protocol::Straps;
use ppmc_core::time::Duration;
use std::ffi::CStr;
use std::io::{self, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

const HELP: &str = "\
ppmc-twin: the RP2350 bridge's board code on a twin of the RP2350, served on a pseudo-terminal

usage: firmware/run-twin [options]

  --clock-mhz MHZ      the chip's SysClk strap, 1 to 40 (fractions allowed); default 16
  --csel high|low      default high
  --vsel high|low      default high
  --chip-fault NAME    a fault of the catalogue (ppmc fault-matrix --list),
                       swap-error-A-B or status-stuck-0xNN; repeat to combine
  --link PATH          also make PATH a symbolic link to the pty (removed on exit)
  -h, --help           this text

It prints `run-twin: serving on /dev/pts/N` once it serves, and stops on
SIGINT or SIGTERM.";

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::Relaxed);
}

struct Options {
    straps: Straps,
    model: ModelConfig,
    link: Option<PathBuf>,
}

fn parse(args: &[String]) -> Result<Option<Options>, String> {
    let mut straps = Straps::default();
    let mut model = ModelConfig::default();
    let mut link = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{a} needs a value"))
        };
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--clock-mhz" => {
                let v = value()?;
                let mhz: f64 = v
                    .parse()
                    .map_err(|_| format!("--clock-mhz `{v}` is not a number"))?;
                let hz = (mhz * 1e6).round();
                if !(1e6..=40e6).contains(&hz) {
                    return Err(format!("--clock-mhz `{v}`: 1 to 40"));
                }
                straps.sysclk_hz = hz as u32;
            }
            "--csel" | "--vsel" => {
                let v = value()?;
                let high = match v.as_str() {
                    "high" => true,
                    "low" => false,
                    _ => return Err(format!("{a} `{v}`: high or low")),
                };
                if a == "--csel" {
                    straps.csel_high = high;
                } else {
                    straps.vsel_high = high;
                }
            }
            "--chip-fault" => {
                let v = value()?;
                faults::apply_named(&v, &mut model).map_err(|e| format!("--chip-fault: {e}"))?;
            }
            "--link" => link = Some(PathBuf::from(value()?)),
            other => return Err(format!("unknown option `{other}` (--help lists them)")),
        }
    }
    Ok(Some(Options {
        straps,
        model,
        link,
    }))
}

/// A pseudo-terminal in raw mode: the master, and the slave's path.
fn open_pty() -> io::Result<(OwnedFd, String)> {
    let mut master: libc::c_int = -1;
    let mut slave: libc::c_int = -1;
    // SAFETY: openpty writes two descriptors; the name, termios and
    // window size are optional and null here.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if rc != 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: both are open descriptors openpty just gave us.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    // SAFETY: a zeroed termios is filled by tcgetattr before use.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: valid descriptor and pointer.
    unsafe {
        if libc::tcgetattr(slave.as_raw_fd(), &mut t) == 0 {
            libc::cfmakeraw(&mut t);
            libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t);
        }
    }
    // SAFETY: ptsname_r writes a NUL-terminated name into the buffer.
    let mut name = [0 as libc::c_char; 128];
    let rc = unsafe { libc::ptsname_r(master.as_raw_fd(), name.as_mut_ptr(), name.len()) };
    if rc != 0 {
        return Err(io::Error::from_raw_os_error(rc));
    }
    // SAFETY: NUL-terminated by ptsname_r.
    let path = unsafe { CStr::from_ptr(name.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    // The slave stays open here too, so that a host closing it does not
    // leave the master reading EIO; dropping it would.
    std::mem::forget(slave);
    Ok((master, path))
}

/// Waits up to 50 ms for the master to be readable.
fn readable(fd: std::os::fd::RawFd) -> bool {
    let mut p = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: one valid pollfd.
    let n = unsafe { libc::poll(&mut p, 1, 50) };
    n > 0 && p.revents & libc::POLLIN != 0
}

/// The request the engine is running: its sequence number, the twin's
/// cycle and the wall time when it began.
struct Running {
    seq: u8,
    cycle: u64,
    since: std::time::Instant,
    /// When the last WORKING about it went out.
    said: Option<std::time::Instant>,
}

impl Running {
    /// A WORKING is due: none yet, or the last 50 ms ago.
    fn due(&self) -> bool {
        self.said
            .is_none_or(|t| t.elapsed() >= std::time::Duration::from_millis(50))
    }
}

/// A lock that a panicked holder does not poison for the rest.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// While the engine runs one request, a WORKING message
/// (`docs/bridge-protocol.md` section 5) 10 ms after it began and every
/// 50 ms after that, with how far the twin's clock has run since it
/// began: the twin runs slower than real time, more so on a busy machine,
/// and the host waits by its clock instead of its own.
fn working(
    out: Arc<Mutex<std::fs::File>>,
    running: Arc<Mutex<Option<Running>>>,
    progress: Arc<AtomicU64>,
    timer: Timer,
) {
    use std::time::Duration as Wall;
    std::thread::spawn(move || loop {
        std::thread::sleep(Wall::from_millis(10));
        // The reply's writer holds `out` while it clears `running`: no
        // WORKING follows the reply it is about.
        let mut out = lock(&out);
        let frame = match &mut *lock(&running) {
            Some(r) if r.since.elapsed() >= Wall::from_millis(10) && r.due() => {
                r.said = Some(std::time::Instant::now());
                let cycles = progress.load(Ordering::Relaxed).saturating_sub(r.cycle);
                let elapsed = Duration::from_nanos(timer.to_nanos(cycles / 2));
                frame::encode(&Response::Working { elapsed }.encode(r.seq, timer))
            }
            _ => continue,
        };
        let _ = out.write_all(&frame).and_then(|_| out.flush());
    });
}

/// The receive path, on a thread of its own as a board's USB is on its
/// own core: what arrives is shown to the abort watch at once (an ABORT
/// stops the request the engine runs, `docs/bridge-protocol.md`
/// section 5), then queued for the engine.
fn receive(mut pty: std::fs::File, mut watch: AbortWatch) -> mpsc::Receiver<Vec<u8>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while !STOP.load(Ordering::Relaxed) {
            if !readable(pty.as_raw_fd()) {
                continue;
            }
            let n = match io::Read::read(&mut pty, &mut buf) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                // No host on the other end: wait for one.
                Err(_) => {
                    std::thread::sleep(std::time::Duration::from_millis(20));
                    continue;
                }
            };
            watch.on_bytes(&buf[..n]);
            if tx.send(buf[..n].to_vec()).is_err() {
                return;
            }
        }
    });
    rx
}

fn serve(o: Options) -> Result<(), String> {
    let board = twin::board(o.straps, o.model).map_err(|e| format!("the twin cannot boot: {e}"))?;
    let timer = board.timer();
    let progress = board.hal().progress.clone();
    let session = std::process::id() ^ 0x7717_0000;
    let firmware = concat!(
        "ppmc-bridge-twin ",
        env!("CARGO_PKG_VERSION"),
        " (the RP2350 board code on a twin of the RP2350)"
    );
    let abort = AbortLine::new();
    let mut engine = BridgeEngine::new(board, session, true, firmware)
        .with_timer(timer)
        .with_capture_capacity(ppmc_bridge_fw::limits::CAPTURE_RECORDS)
        .with_abort(abort.clone());
    let (master, path) = open_pty().map_err(|e| format!("no pseudo-terminal: {e}"))?;
    if let Some(link) = &o.link {
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&path, link)
            .map_err(|e| format!("--link {}: {e}", link.display()))?;
    }
    // A signal during a long op (the twin runs every cycle of it) must not
    // wait for the op to end: a second later, this thread stops the twin.
    let link = o.link.clone();
    std::thread::spawn(move || loop {
        std::thread::sleep(std::time::Duration::from_millis(50));
        if STOP.load(Ordering::Relaxed) {
            std::thread::sleep(std::time::Duration::from_secs(1));
            if let Some(link) = &link {
                let _ = std::fs::remove_file(link);
            }
            eprintln!("run-twin: stopped in the middle of an op");
            std::process::exit(0);
        }
    });
    println!("run-twin: serving on {path}");
    let _ = io::stdout().flush();
    let file = std::fs::File::from(master);
    let out = Arc::new(Mutex::new(
        file.try_clone()
            .map_err(|e| format!("no second handle on {path}: {e}"))?,
    ));
    let running: Arc<Mutex<Option<Running>>> = Arc::default();
    working(out.clone(), running.clone(), progress.clone(), timer);
    let reader = file
        .try_clone()
        .map_err(|e| format!("no third handle on {path}: {e}"))?;
    let arrived = receive(reader, AbortWatch::new(abort.clone()));
    let mut requests = FrameDecoder::new();
    let result = loop {
        if STOP.load(Ordering::Relaxed) {
            break Ok(());
        }
        let bytes = match arrived.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok(bytes) => bytes,
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => break Ok(()),
        };
        // Frame by frame, so that a long request is known by its sequence
        // number while it runs (WORKING).
        let mut failed = None;
        for chunk in bytes.split_inclusive(|b| *b == 0) {
            requests.extend(chunk);
            if let Ok(Some(p)) = requests.decode() {
                if let Some(&seq) = p.first() {
                    *lock(&running) = Some(Running {
                        seq,
                        cycle: progress.load(Ordering::Relaxed),
                        since: std::time::Instant::now(),
                        said: None,
                    });
                }
            }
            let reply = engine.on_bytes(chunk);
            let mut out = lock(&out);
            *lock(&running) = None;
            if let Err(e) = out.write_all(&reply).and_then(|_| out.flush()) {
                failed = Some(format!("writing to {path}: {e}"));
                break;
            }
        }
        if let Some(e) = failed {
            break Err(e);
        }
    };
    if let Some(link) = &o.link {
        let _ = std::fs::remove_file(link);
    }
    result
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let o = match parse(&args) {
        Ok(Some(o)) => o,
        Ok(None) => {
            println!("{HELP}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("run-twin: {e}");
            return ExitCode::from(2);
        }
    };
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
        libc::signal(
            libc::SIGTERM,
            on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
    match serve(o) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("run-twin: {e}");
            ExitCode::from(1)
        }
    }
}
