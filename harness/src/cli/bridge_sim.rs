//! `ppmc bridge-sim`: the bridge protocol on a pseudo-terminal, with the
//! emulator behind it.

use super::args::TargetArgs;
use crate::backend::EmuTarget;
use crate::cli::{usage, CliError};
use clap::Args;
use std::io::{self, Write};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BridgeSimArgs {
    #[command(flatten)]
    target: TargetArgs,
    /// Also make PATH a symbolic link to the pty (removed on exit).
    #[arg(long, value_name = "PATH")]
    link: Option<PathBuf>,
    /// Pace replies to the wall clock instead of answering at once in
    /// virtual time (to behave like a real board's timing).
    #[arg(long)]
    realtime: bool,
    /// Pulse runs plus pin changes the bridge's capture buffer holds; past
    /// that, capture requests answer CAPTURE_OVERRUN until the next chip
    /// reset (to try a host against a board with a small buffer). Default:
    /// unlimited.
    #[arg(long, value_name = "N", default_value_t = u32::MAX, hide_default_value = true)]
    capture_capacity: u32,
    /// Probability of losing each byte on the link, e.g. 0.01.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Probability of flipping a bit in each byte on the link.
    #[arg(long, default_value_t = 0.0)]
    corrupt_rate: f64,
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
    use crate::bridge::sim::engine;
    use crate::bridge::sim::{serve, LinkFaults, ServeEnd};
    use serialport::SerialPort;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    for (name, rate) in [
        ("--drop-rate", args.drop_rate),
        ("--corrupt-rate", args.corrupt_rate),
    ] {
        if !(0.0..=1.0).contains(&rate) {
            return Err(usage(format!(
                "{name} {rate}: give a probability from 0 to 1"
            )));
        }
    }
    if args.target.name() != "emu" {
        return Err(usage(
            "bridge-sim serves the emulator; --target must be emu",
        ));
    }
    let straps = match args.target.straps() {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    let mut model = args.target.model();
    if let Err(e) = crate::faults::apply_all(&args.chip_faults, &mut model) {
        return Err(usage(format!("--chip-fault: {e}")));
    }
    let emu = match EmuTarget::new(straps, model) {
        Ok(t) => t,
        Err(e) => return Err(usage(e)),
    };
    let (mut master, slave) = match serialport::TTYPort::pair() {
        Ok(p) => p,
        Err(e) => {
            return Err(CliError::Failed(format!(
                "cannot open a pseudo-terminal: {e}"
            )));
        }
    };
    let _ = master.set_timeout(std::time::Duration::from_millis(50));
    let Some(path) = slave.name() else {
        return Err(CliError::Failed(
            "the pseudo-terminal has no path".to_string(),
        ));
    };
    if let Some(link) = &args.link {
        let _ = std::fs::remove_file(link);
        if let Err(e) = std::os::unix::fs::symlink(&path, link) {
            return Err(CliError::Failed(format!(
                "cannot link {} to {path}: {e}",
                link.display()
            )));
        }
    }
    let session = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |d| d.subsec_nanos() ^ (d.as_secs() as u32));
    let mut server =
        engine(emu, session, !args.realtime).with_capture_capacity(args.capture_capacity);
    // Nobody may be reading stdout (a closed pipe): never let that stop
    // the bridge.
    let mut out = io::stdout();
    let _ = writeln!(out, "bridge-sim: serving on {path}");
    let _ = writeln!(out, "bridge-sim: run   ppmc run --target serial:{path}");
    let _ = out.flush();
    let stop = Arc::new(AtomicBool::new(false));
    let faults = LinkFaults {
        drop_rate: args.drop_rate,
        corrupt_rate: args.corrupt_rate,
        stall_after: args.stall_after,
        disconnect_after: args.disconnect_after,
        seed: args.seed,
    };
    let end = serve(&mut master, &mut server, faults, args.realtime, &stop);
    if let Some(link) = &args.link {
        let _ = std::fs::remove_file(link);
    }
    drop(slave);
    let _ = stop.load(Ordering::Relaxed);
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
