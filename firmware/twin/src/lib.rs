//! Serving a simulated bridge on a pseudo-terminal, as `ppmc-twin` and
//! `ppmc-emu` (the image on rp2350-emu) both do: the options both take
//! (the chip's straps and faults, a link to the pty), a stop on SIGINT or
//! SIGTERM, the pty and its reader, and the WORKING messages of a bridge
//! that runs slower than real time (`docs/bridge-protocol.md` section 5),
//! sent by the host side of the simulation with the simulated clock's
//! progress.

use ppmc_core::bridge::frame;
use ppmc_core::bridge::wire::{Response, Timer};
use ppmc_core::emu::{faults, ModelConfig};
use ppmc_core::protocol::Straps;
use ppmc_core::time::Duration;
use std::ffi::CStr;
use std::io::{self, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

/// The `--help` lines of [`BoardOptions`].
pub const BOARD_OPTIONS_HELP: &str =
    "  --clock-mhz MHZ      the chip's SysClk strap, 1 to 40 (fractions allowed); default 16
  --csel high|low      default high
  --vsel high|low      default high
  --chip-fault NAME    a fault of the catalogue (ppmc fault-matrix --list),
                       swap-error-A-B or status-stuck-0xNN; repeat to combine
  --link PATH          also make PATH a symbolic link to the pty (removed on exit)";

/// The options of the board a simulated bridge serves: the chip's straps
/// and faults, and where to link its pty.
#[derive(Debug, Default)]
pub struct BoardOptions {
    pub straps: Straps,
    pub model: ModelConfig,
    pub link: Option<PathBuf>,
}

impl BoardOptions {
    /// Takes `flag`, and its value from `value`, when it is one of
    /// [`BOARD_OPTIONS_HELP`]'s: `Ok(false)` when it is not.
    pub fn take(
        &mut self,
        flag: &str,
        value: &mut dyn FnMut() -> Result<String, String>,
    ) -> Result<bool, String> {
        match flag {
            "--clock-mhz" => {
                let v = value()?;
                let mhz: f64 = v
                    .parse()
                    .map_err(|_| format!("--clock-mhz `{v}` is not a number"))?;
                let hz = (mhz * 1e6).round();
                if !(1e6..=40e6).contains(&hz) {
                    return Err(format!("--clock-mhz `{v}`: 1 to 40"));
                }
                self.straps.sysclk_hz = hz as u32;
            }
            "--csel" | "--vsel" => {
                let v = value()?;
                let high = match v.as_str() {
                    "high" => true,
                    "low" => false,
                    _ => return Err(format!("{flag} `{v}`: high or low")),
                };
                if flag == "--csel" {
                    self.straps.csel_high = high;
                } else {
                    self.straps.vsel_high = high;
                }
            }
            "--chip-fault" => {
                let v = value()?;
                faults::apply_named(&v, &mut self.model)
                    .map_err(|e| format!("--chip-fault: {e}"))?;
            }
            "--link" => self.link = Some(PathBuf::from(value()?)),
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// Makes `--link` a symbolic link to the pty at `path`, if given.
    pub fn make_link(&self, path: &str) -> Result<(), String> {
        if let Some(link) = &self.link {
            let _ = std::fs::remove_file(link);
            std::os::unix::fs::symlink(path, link)
                .map_err(|e| format!("--link {}: {e}", link.display()))?;
        }
        Ok(())
    }

    /// Removes the `--link`, if given.
    pub fn remove_link(&self) {
        remove_link(self.link.as_deref());
    }
}

/// Removes `link`, if any.
pub fn remove_link(link: Option<&Path>) {
    if let Some(link) = link {
        let _ = std::fs::remove_file(link);
    }
}

/// Raised by SIGINT or SIGTERM once [`stop_on_signals`] has run.
pub static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::Relaxed);
}

/// Whether a signal asked the simulation to stop.
pub fn stopping() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// SIGINT and SIGTERM raise [`STOP`] from here on.
pub fn stop_on_signals() {
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
}

/// A simulated bridge's `main`: its arguments parsed (`None` asks for
/// the help: `help[0]`, the board options' lines, `help[1]`), the stop on
/// signals, then `serve`. Exit status 0 when it served and stopped, 1
/// when it could not serve, 2 on bad usage; each error on stderr after
/// `name`.
pub fn run_main<O>(
    name: &str,
    help: [&str; 2],
    parse: impl FnOnce(&[String]) -> Result<Option<O>, String>,
    serve: impl FnOnce(O) -> Result<(), String>,
) -> std::process::ExitCode {
    use std::process::ExitCode;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let o = match parse(&args) {
        Ok(Some(o)) => o,
        Ok(None) => {
            println!("{}{BOARD_OPTIONS_HELP}\n{}", help[0], help[1]);
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("{name}: {e}");
            return ExitCode::from(2);
        }
    };
    stop_on_signals();
    match serve(o) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{name}: {e}");
            ExitCode::from(1)
        }
    }
}

/// The pty's reader, on a thread of its own until [`STOP`]: each read is
/// shown to `look` as it arrives, then queued.
pub fn read_pty(
    mut pty: std::fs::File,
    mut look: impl FnMut(&[u8]) + Send + 'static,
) -> mpsc::Receiver<Vec<u8>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while !stopping() {
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
            look(&buf[..n]);
            if tx.send(buf[..n].to_vec()).is_err() {
                return;
            }
        }
    });
    rx
}

/// A pseudo-terminal in raw mode: the master, and the slave's path.
pub fn open_pty() -> io::Result<(OwnedFd, String)> {
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
pub fn readable(fd: std::os::fd::RawFd) -> bool {
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
#[derive(Debug)]
pub struct Running {
    pub seq: u8,
    pub cycle: u64,
    pub since: std::time::Instant,
    /// When the last WORKING about it went out.
    pub said: Option<std::time::Instant>,
}

impl Running {
    /// A WORKING is due: none yet, or the last 50 ms ago.
    fn due(&self) -> bool {
        self.said
            .is_none_or(|t| t.elapsed() >= std::time::Duration::from_millis(50))
    }
}

/// A lock that a panicked holder does not poison for the rest.
pub fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// While the engine runs one request, a WORKING message
/// (`docs/bridge-protocol.md` section 5) 10 ms after it began and every
/// 50 ms after that, with how far the simulated clock has run since it
/// began: `progress` counts its cycles, at `cycle_hz`. A simulation runs
/// slower than real time, more so on a busy machine, and the host waits
/// by its clock instead of its own.
pub fn working(
    out: Arc<Mutex<std::fs::File>>,
    running: Arc<Mutex<Option<Running>>>,
    progress: Arc<AtomicU64>,
    cycle_hz: u32,
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
                let ns = u128::from(cycles) * 1_000_000_000 / u128::from(cycle_hz);
                let elapsed = Duration::from_nanos(ns as u64);
                frame::encode(&Response::Working { elapsed }.encode(r.seq, timer))
            }
            _ => continue,
        };
        let _ = out.write_all(&frame).and_then(|_| out.flush());
    });
}
