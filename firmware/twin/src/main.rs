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
use ppmc_core::bridge::frame::FrameDecoder;
use ppmc_core::emu::{faults, ModelConfig};
use ppmc_core::protocol::Straps;
use ppmc_twin::{lock, open_pty, readable, working, Running};
use std::io::{self, Write};
use std::os::fd::AsRawFd;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
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
    working(
        out.clone(),
        running.clone(),
        progress.clone(),
        twin::SYSCLK_HZ,
        timer,
    );
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
