//! `ppmc bridge-sim`: the bridge protocol on a pseudo-terminal, with the
//! emulator behind it.

use super::args::ChipArgs;
use crate::{usage, CliError};
use clap::Args;
use ppmc::backend::EmuTarget;
use std::io::{self, Write};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BridgeSimArgs {
    /// The emulated chip behind the bridge: its straps (which HELLO
    /// reports to the host) and its ramp.
    #[command(flatten)]
    chip: ChipArgs,
    /// Also make PATH a symbolic link to the pty, removed on exit, SIGINT
    /// and SIGTERM. An existing PATH is replaced only when it is a stale
    /// link of an earlier bridge-sim (to a pseudo-terminal that is gone).
    #[arg(long, value_name = "PATH")]
    link: Option<PathBuf>,
    /// Pace replies to the wall clock instead of answering at once in
    /// virtual time (to behave like a real board's timing).
    #[arg(long)]
    realtime: bool,
    /// Records (pulse runs, pin changes and move records) the bridge's
    /// capture buffer holds; past that, capture requests and batches answer
    /// CAPTURE_OVERRUN until the next chip reset (to try a host against a
    /// board with a small buffer). Default: unlimited.
    #[arg(long, value_name = "N", default_value_t = u32::MAX, hide_default_value = true)]
    capture_capacity: u32,
    /// Give the bridge a timer of HZ that is not locked to the chip's clock,
    /// as a real bridge's is: every time on the wire is in its ticks, each
    /// output edge is stamped at the nearest tick, and pulse runs carry the
    /// jitter bound a tick of wobble needs (docs/bridge-protocol.md
    /// section 7), e.g. 150000000 for an RP2350 at 150 MHz. From 1000 to
    /// 500000000. Default: a nanosecond timer in step with the chip.
    #[arg(long, value_name = "HZ")]
    timer_hz: Option<u64>,
    /// The serial number the bridge gives in its HELLO, as an RP2350
    /// bridge gives its chip ID (the reports name the bridge by it).
    /// Default: none.
    #[arg(long, value_name = "TEXT")]
    serial: Option<String>,
    /// Probability of losing each byte on the link, e.g. 0.01.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Probability of flipping a bit in each byte on the link.
    #[arg(long, default_value_t = 0.0)]
    corrupt_rate: f64,
    /// Probability of each byte on the link arriving twice.
    #[arg(long, default_value_t = 0.0)]
    dup_rate: f64,
    /// Probability of each byte on the link swapping places with the next.
    #[arg(long, default_value_t = 0.0)]
    reorder_rate: f64,
    /// Stop answering after N frames (a hung bridge).
    #[arg(long, value_name = "N")]
    stall_after: Option<u64>,
    /// Close the link after N frames (a cable pulled).
    #[arg(long, value_name = "N")]
    disconnect_after: Option<u64>,
    /// Seed for the fault draws.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run a deliberately faulty chip: a name from the board-fault catalogue
    /// (`ppmc fault-matrix --list`), swap-error-A-B (e.g. swap-error-3-4) or
    /// status-stuck-0xNN. Repeat to combine.
    #[arg(long = "chip-fault", value_name = "FAULT")]
    chip_faults: Vec<String>,
}

pub fn run(args: BridgeSimArgs) -> Result<(), CliError> {
    use ppmc::bridge::sim::{engine, place_link, remove_own_link, timed_engine};
    use ppmc::bridge::sim::{serve_tty, LinkFaults, LinkRefused, ServeEnd};
    use serialport::SerialPort;

    let faults = LinkFaults {
        drop_rate: args.drop_rate,
        corrupt_rate: args.corrupt_rate,
        dup_rate: args.dup_rate,
        reorder_rate: args.reorder_rate,
        stall_after: args.stall_after,
        disconnect_after: args.disconnect_after,
        seed: args.seed,
    };
    faults.check().map_err(usage)?;
    let hz_ok = |hz: &u64| (1_000..=500_000_000).contains(hz);
    if let Some(hz) = args.timer_hz.filter(|hz| !hz_ok(hz)) {
        return Err(usage(format!("--timer-hz {hz}: give 1000 to 500000000 Hz")));
    }
    let straps = args.chip.straps().map_err(usage)?;
    let mut model = args.chip.model();
    ppmc::faults::apply_all(&args.chip_faults, &mut model)
        .map_err(|e| usage(format!("--chip-fault: {e}")))?;
    let emu = EmuTarget::new(straps, model).map_err(usage)?;
    let (mut master, slave) = serialport::TTYPort::pair()
        .map_err(|e| CliError::Failed(format!("cannot open a pseudo-terminal: {e}")))?;
    let _ = master.set_timeout(std::time::Duration::from_millis(50));
    let Some(path) = slave.name() else {
        return Err(CliError::Failed(
            "the pseudo-terminal has no path".to_string(),
        ));
    };
    // SIGINT and SIGTERM end the serve loop, so the link is removed: the
    // handlers are in place before the link is, and before anyone learns
    // where the bridge serves.
    let stop = super::signals::stop_requested();
    if let Some(link) = &args.link {
        place_link(link, &path).map_err(|e| match e {
            LinkRefused::Taken(why) => usage(why),
            LinkRefused::Io(why) => CliError::Failed(why),
        })?;
    }
    let session = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |d| d.subsec_nanos() ^ (d.as_secs() as u32));
    let server = match args.timer_hz {
        Some(hz) => timed_engine(emu, session, !args.realtime, hz),
        None => engine(emu, session, !args.realtime),
    };
    let mut server = server
        .with_capture_capacity(args.capture_capacity)
        .with_serial(args.serial.as_deref().unwrap_or(""));
    // Nobody may be reading stdout (a closed pipe): never let that stop
    // the bridge.
    let mut out = io::stdout();
    let _ = writeln!(out, "bridge-sim: serving on {path}");
    let _ = writeln!(out, "bridge-sim: run   ppmc run --target serial:{path}");
    let _ = out.flush();
    let end = serve_tty(&mut master, &mut server, faults, args.realtime, &stop);
    if let Some(link) = &args.link {
        remove_own_link(link, &path);
    }
    drop(slave);
    match end {
        Ok(ServeEnd::Disconnected) => {
            let _ = writeln!(
                io::stdout(),
                "bridge-sim: disconnected after {} frames (fault)",
                server.frames
            );
            Ok(())
        }
        Ok(ServeEnd::Stopped) => Ok(()),
        Err(e) => Err(CliError::Failed(format!("bridge-sim: {e}"))),
    }
}
