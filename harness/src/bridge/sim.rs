//! The bridge simulator's I/O loop: a [`BridgeServer`] on a byte port (the
//! master side of a pseudo-terminal), with optional line faults and pacing
//! to the wall clock.

use super::server::BridgeServer;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration as WallDuration, Instant as WallInstant};

/// How the simulated link or board misbehaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkFaults {
    /// Probability that a byte (either direction) is lost.
    pub drop_rate: f64,
    /// Probability that a byte (either direction) has a bit flipped.
    pub corrupt_rate: f64,
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
            stall_after: None,
            disconnect_after: None,
            seed: 1,
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
    fn apply(&mut self, bytes: &[u8]) -> Vec<u8> {
        if self.f.drop_rate == 0.0 && self.f.corrupt_rate == 0.0 {
            return bytes.to_vec();
        }
        let mut out = Vec::with_capacity(bytes.len());
        for &b in bytes {
            if self.rng.random::<f64>() < self.f.drop_rate {
                continue;
            }
            if self.rng.random::<f64>() < self.f.corrupt_rate {
                out.push(b ^ (1 << self.rng.random_range(0..8)));
            } else {
                out.push(b);
            }
        }
        out
    }
}

/// Serves the bridge protocol on `port` until `stop` is set or the
/// disconnect fault fires. With `realtime`, replies are held back until the
/// wall clock has caught up with the emulator's virtual time.
pub fn serve<P: Read + Write>(
    port: &mut P,
    server: &mut BridgeServer,
    faults: LinkFaults,
    realtime: bool,
    stop: &Arc<AtomicBool>,
) -> io::Result<ServeEnd> {
    let mut faulty = Faulty {
        f: faults,
        rng: StdRng::seed_from_u64(faults.seed),
    };
    let started = WallInstant::now();
    let virtual_start = server.now();
    let mut buf = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) {
        let n = match port.read(&mut buf) {
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
        let incoming = faulty.apply(&buf[..n]);
        let reply = server.on_bytes(&incoming);
        if faults.disconnect_after.is_some_and(|k| server.frames >= k) {
            return Ok(ServeEnd::Disconnected);
        }
        if faults.stall_after.is_some_and(|k| server.frames >= k) {
            continue;
        }
        if realtime {
            let ahead = server.now().saturating_since(virtual_start);
            let wall = WallDuration::from_nanos(ahead.as_nanos());
            let elapsed = started.elapsed();
            if wall > elapsed {
                std::thread::sleep(wall - elapsed);
            }
        }
        let outgoing = faulty.apply(&reply);
        port.write_all(&outgoing)?;
        port.flush()?;
    }
    Ok(ServeEnd::Stopped)
}

/// A bridge simulator serving an emulator on its own thread, on a fresh
/// pseudo-terminal: what tests, `ppmc bench` and `ppmc fault-matrix` point
/// a serial target at. Dropping it stops the thread.
#[derive(Debug)]
pub struct PtyBridge {
    path: String,
    stop: Arc<AtomicBool>,
    handle: Option<std::thread::JoinHandle<Option<ServeEnd>>>,
}

impl PtyBridge {
    /// Serves `emu` (in virtual time) with `faults` on the link.
    pub fn start(emu: crate::target::EmuTarget, faults: LinkFaults) -> io::Result<PtyBridge> {
        use serialport::SerialPort;
        let (mut master, slave) = serialport::TTYPort::pair().map_err(io::Error::other)?;
        master
            .set_timeout(WallDuration::from_millis(20))
            .map_err(io::Error::other)?;
        let path = slave
            .name()
            .ok_or_else(|| io::Error::other("the pseudo-terminal has no path"))?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let handle = std::thread::spawn(move || {
            let _keep_open = slave;
            let mut server = BridgeServer::new(emu, 0x5EED, true);
            serve(&mut master, &mut server, faults, false, &flag).ok()
        });
        Ok(PtyBridge {
            path,
            stop,
            handle: Some(handle),
        })
    }

    /// The pty's path, for `serial:<path>`.
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
    }
}
