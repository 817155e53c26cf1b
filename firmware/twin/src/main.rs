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
use ppmc_twin::{lock, open_pty, read_pty, remove_link, stopping, working, BoardOptions, Running};
use std::io::{self, Write};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::sync::{mpsc, Arc, Mutex};

/// `--help`, around [`ppmc_twin::BOARD_OPTIONS_HELP`].
const HELP: [&str; 2] = [
    "\
ppmc-twin: the RP2350 bridge's board code on a twin of the RP2350, served on a pseudo-terminal

usage: firmware/run-twin [options]

",
    "  -h, --help           this text

It prints `run-twin: serving on /dev/pts/N` once it serves, and stops on
SIGINT or SIGTERM.",
];

/// The options; `None` for `--help`.
fn parse(args: &[String]) -> Result<Option<BoardOptions>, String> {
    let mut o = BoardOptions::default();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "-h" || a == "--help" {
            return Ok(None);
        }
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{a} needs a value"))
        };
        if !o.take(a, &mut value)? {
            return Err(format!("unknown option `{a}` (--help lists them)"));
        }
    }
    Ok(Some(o))
}

fn serve(o: BoardOptions) -> Result<(), String> {
    let board =
        twin::board(o.straps, o.model.clone()).map_err(|e| format!("the twin cannot boot: {e}"))?;
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
    o.make_link(&path)?;
    // A signal during a long op (the twin runs every cycle of it) must not
    // wait for the op to end: a second later, this thread stops the twin.
    let link = o.link.clone();
    std::thread::spawn(move || loop {
        std::thread::sleep(std::time::Duration::from_millis(50));
        if stopping() {
            std::thread::sleep(std::time::Duration::from_secs(1));
            remove_link(link.as_deref());
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
    // The receive path, on a thread of its own as a board's USB is on its
    // own core: what arrives is shown to the abort watch at once (an ABORT
    // stops the request the engine runs, `docs/bridge-protocol.md`
    // section 5), then queued for the engine.
    let mut watch = AbortWatch::new(abort.clone());
    let arrived = read_pty(reader, move |bytes| {
        watch.on_bytes(bytes);
    });
    let mut requests = FrameDecoder::new();
    let result = loop {
        if stopping() {
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
    o.remove_link();
    result
}

fn main() -> ExitCode {
    ppmc_twin::run_main("run-twin", HELP, parse, serve)
}
