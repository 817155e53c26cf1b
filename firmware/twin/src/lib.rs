//! Serving a simulated bridge on a pseudo-terminal, as `ppmc-twin` and
//! `ppmc-emu` (the image on rp2350-emu) both do: the pty itself, and the
//! WORKING messages of a bridge that runs slower than real time
//! (`docs/bridge-protocol.md` section 5), sent by the host side of the
//! simulation with the simulated clock's progress.

use ppmc_core::bridge::frame;
use ppmc_core::bridge::wire::{Response, Timer};
use ppmc_core::time::Duration;
use std::ffi::CStr;
use std::io::{self, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

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
