//! `ppmc-emu`, run by `firmware/run-emu`: the RP2350 bridge's image, the
//! very ELF `firmware/build` turns into the UF2 a lab flashes, on
//! rp2350-emu (an emulator of the RP2350 that this project did not
//! write, vendored with the changes `firmware/vendor/rp2350-emu/
//! PPMC-CHANGES.md` lists), its GPIOs wired to the reference chip model
//! and its USB device, enumerated by a host of ours, served on a
//! pseudo-terminal as `ppmc bridge-sim`, `firmware/run-qemu` and
//! `firmware/run-twin` serve theirs.
//!
//! Time is the emulator's: it passes as the image runs, far slower than
//! real time, so the host side says WORKING for the image while a
//! request runs (`docs/bridge-protocol.md` section 5), as the twin does.

mod cdc;
mod machine;
mod usb;

use cdc::Transactions;
use machine::{Machine, SYS_CLK_HZ};
use ppmc_bridge_fw::twin::chip::ChipSide;
use ppmc_core::bridge::frame::FrameDecoder;
use ppmc_core::bridge::wire::Timer;
use ppmc_core::emu::Board as Model;
use ppmc_twin::{lock, open_pty, read_pty, stopping, working, BoardOptions, Running};
use std::collections::VecDeque;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

/// `--help`, around [`ppmc_twin::BOARD_OPTIONS_HELP`].
const HELP: [&str; 2] = [
    "\
ppmc-emu: the RP2350 bridge image, unmodified, on rp2350-emu, served on a pseudo-terminal

usage: firmware/run-emu [options]          (builds the image first)
       ppmc-emu --image ELF [options]

  --image ELF          the board's ELF, as firmware/build prints it
",
    "  -h, --help           this text

The chip's SysClk strap must be the one the image was built with
(PPMC_SYSCLK_HZ, 16 MHz by default). It boots the image, enumerates its
USB device, prints `run-emu: serving on /dev/pts/N`, and stops on SIGINT
or SIGTERM.",
];

struct Options {
    image: PathBuf,
    board: BoardOptions,
}

/// The options; `None` for `--help`.
fn parse(args: &[String]) -> Result<Option<Options>, String> {
    let mut image = None;
    let mut board = BoardOptions::default();
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
        if a == "--image" {
            image = Some(PathBuf::from(value()?));
        } else if !board.take(a, &mut value)? {
            return Err(format!("unknown option `{a}` (--help lists them)"));
        }
    }
    let image = image.ok_or("--image ELF is needed (firmware/run-emu builds and gives it)")?;
    Ok(Some(Options { image, board }))
}

/// The requests the image has yet to answer, by sequence number and the
/// cycle each arrived at: the oldest is the one WORKING speaks of.
#[derive(Default)]
struct Outstanding {
    requests: FrameDecoder,
    replies: FrameDecoder,
    waiting: VecDeque<(u8, u64)>,
}

impl Outstanding {
    fn sent(&mut self, bytes: &[u8], cycle: u64) {
        for chunk in bytes.split_inclusive(|b| *b == 0) {
            self.requests.extend(chunk);
            if let Ok(Some(p)) = self.requests.decode() {
                if let Some(&seq) = p.first() {
                    self.waiting.push_back((seq, cycle));
                }
            }
        }
    }

    /// Takes the bytes the image sent; true when an answer came.
    fn answered(&mut self, bytes: &[u8]) -> bool {
        let mut any = false;
        for chunk in bytes.split_inclusive(|b| *b == 0) {
            self.replies.extend(chunk);
            if let Ok(Some(p)) = self.replies.decode() {
                if let Some(&seq) = p.first() {
                    let before = self.waiting.len();
                    self.waiting.retain(|(s, _)| *s != seq);
                    any |= self.waiting.len() != before;
                }
            }
        }
        any
    }
}

/// Cycles the image runs between two looks at the USB: 100 us.
const SLICE: u64 = 15_000;
/// With nothing to send and nothing outstanding, the image runs this long
/// after the last byte, then waits for the host with its clock stopped.
const IDLE_AFTER: u64 = 7_500_000;

fn serve(o: Options) -> Result<(), String> {
    let elf = std::fs::read(&o.image).map_err(|e| format!("{}: {e}", o.image.display()))?;
    let flash = machine::flash_image(&elf).map_err(|e| format!("{}: {e}", o.image.display()))?;
    let model = Model::new(o.board.straps, o.board.model.clone())
        .map_err(|e| format!("the chip model: {e}"))?;
    let mut m = Machine::boot(&flash, ChipSide::new(model, SYS_CLK_HZ))?;
    let mut host = usb::Host::new(&mut m);
    let enumerated = cdc::enumerate(&mut host);
    let mut port = enumerated.map_err(|e| format!("USB enumeration: {e}; {}", m.where_it_is()))?;
    eprintln!(
        "run-emu: the image enumerated as \"{}\" (serial {}) after {} ms of its time",
        port.product,
        port.serial,
        m.cycles() / u64::from(SYS_CLK_HZ / 1000)
    );
    let (master, path) = open_pty().map_err(|e| format!("no pseudo-terminal: {e}"))?;
    o.board.make_link(&path)?;
    println!("run-emu: serving on {path}");
    let _ = io::stdout().flush();
    let file = std::fs::File::from(master);
    let out = Arc::new(Mutex::new(
        file.try_clone()
            .map_err(|e| format!("no second handle on {path}: {e}"))?,
    ));
    let running: Arc<Mutex<Option<Running>>> = Arc::default();
    let progress = Arc::new(AtomicU64::new(m.cycles()));
    let timer = Timer {
        hz: ppmc_bridge_fw::timebase::timer_hz(SYS_CLK_HZ),
    };
    working(
        out.clone(),
        running.clone(),
        progress.clone(),
        SYS_CLK_HZ,
        timer,
    );
    let reader = file
        .try_clone()
        .map_err(|e| format!("no third handle on {path}: {e}"))?;
    // What the host writes, queued for the USB host to send.
    let arrived = read_pty(reader, |_| {});
    let mut pending: VecDeque<u8> = VecDeque::new();
    let mut outstanding = Outstanding::default();
    let mut last_traffic = m.cycles();
    let result = loop {
        if stopping() {
            break Ok(());
        }
        let idle = pending.is_empty()
            && outstanding.waiting.is_empty()
            && m.cycles() - last_traffic > IDLE_AFTER;
        let wait = if idle { 50 } else { 0 };
        match arrived.recv_timeout(std::time::Duration::from_millis(wait)) {
            Ok(bytes) => {
                outstanding.sent(&bytes, m.cycles());
                pending.extend(bytes);
                last_traffic = m.cycles();
            }
            Err(mpsc::RecvTimeoutError::Timeout) if idle => continue,
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break Ok(()),
        }
        let mut host = usb::Host::new(&mut m);
        if let Err(e) = host.run(SLICE) {
            break Err(e);
        }
        if !pending.is_empty() {
            let n = pending.len().min(port.packet);
            let chunk: Vec<u8> = pending.iter().take(n).copied().collect();
            match port.send(&mut host, &chunk) {
                Ok(true) => {
                    pending.drain(..n);
                }
                Ok(false) => {}
                Err(e) => break Err(e),
            }
        }
        let mut failed = None;
        loop {
            let data = match port.receive(&mut host) {
                Ok(d) => d,
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            };
            if data.is_empty() {
                break;
            }
            last_traffic = host.cycles();
            let mut out = lock(&out);
            if outstanding.answered(&data) {
                *lock(&running) = None;
            }
            if let Err(e) = out.write_all(&data).and_then(|_| out.flush()) {
                failed = Some(format!("writing to {path}: {e}"));
                break;
            }
        }
        if let Some(e) = failed {
            break Err(e);
        }
        let now = m.cycles();
        progress.store(now, Ordering::Relaxed);
        let mut r = lock(&running);
        if r.is_none() {
            if let Some(&(seq, cycle)) = outstanding.waiting.front() {
                *r = Some(Running {
                    seq,
                    cycle,
                    since: std::time::Instant::now(),
                    said: None,
                });
            }
        }
    };
    o.board.remove_link();
    result
}

fn main() -> ExitCode {
    ppmc_twin::run_main("run-emu", HELP, parse, serve)
}
