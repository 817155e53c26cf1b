//! `ppmc`: the command-line front end.

mod bench;
mod cmd;
mod diff_cmd;
mod fuzz_cmd;
mod matrix_cmd;

use clap::{Args, Parser, Subcommand, ValueEnum};
use ppmc::console::{self, ConsoleOptions, Line, ScriptError};
use ppmc::emu::{AccelCurve, ModelConfig};
use ppmc::protocol::Straps;
use ppmc::target::{EmuTarget, SerialLink, SerialOptions, SerialTarget, Target};
use ppmc::time::Duration;
use std::io::{self, BufRead, IsTerminal, Read, Write};
use std::path::PathBuf;
use std::process::ExitCode;

/// Hardware-in-the-loop harness, reference emulator and protocol fuzzer for
/// the PPMC-104BFP stepper-motor pulse controller.
#[derive(Debug, Parser)]
#[command(name = "ppmc", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the conformance suite on a target (the emulator by default) and
    /// grade it: passed, marginal, failed (the device), error (the harness or
    /// link). Exit status 0 when all pass, 1 when any does not, 2 on bad usage.
    Run(cmd::RunArgs),
    /// List the scenarios with their section, tags and summary.
    List(cmd::ListArgs),
    /// Run scenarios and write their traces as golden files. Never overwrites
    /// an existing golden file unless --bless is given; writes atomically.
    Record(cmd::RecordArgs),
    /// Compare a golden trace set with a second trace set (--traces) or with a
    /// fresh run on a target, with tolerances; prints each scenario's verdict
    /// and its first divergence.
    Compare(cmd::CompareArgs),
    /// Write a trace as a VCD waveform (POUT, DIR, S1..S5, INT, HOLD, AUX,
    /// BUSY) for GTKWave or PulseView.
    Export(cmd::ExportArgs),
    /// Run a bus script against a target and print one line per result.
    ///
    /// Reads the script from FILE, from -e, or from standard input. On a
    /// terminal each line runs as you type it; otherwise the whole script is
    /// checked first and nothing runs if a line is wrong. See docs/console.md.
    Console(ConsoleArgs),
    /// Serve the bus bridge protocol on a pseudo-terminal with the emulator
    /// behind it, exactly as a board's bridge serves it over USB serial.
    /// Prints the pty path; point `--target serial:<path>` at it.
    BridgeSim(BridgeSimArgs),
    /// Measure the emulator's speed (maximum-length move, constant-rate
    /// stretches, per-pulse expansion) and print the figures.
    Bench(bench::BenchArgs),
    /// Fuzzing: a differential run against a target (`ppmc fuzz --target
    /// serial:<pty> --seed N`), and findings made into regression tests
    /// (`reproduce`, `minimize`, `to-scenario`).
    Fuzz(fuzz_cmd::FuzzArgs),
    /// Run every catalogued board fault (and the clean board) behind
    /// `bridge-sim` on a pty against the conformance suite, the golden
    /// traces and a bounded differential fuzz; print which caught each and
    /// how fast. Exit status 0 when every fault is caught and the clean
    /// board by nothing, 1 otherwise.
    FaultMatrix(matrix_cmd::MatrixArgs),
}

#[derive(Debug, Args)]
struct BridgeSimArgs {
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

#[derive(Debug, Args)]
struct ConsoleArgs {
    /// Script file; `-` or nothing reads standard input.
    file: Option<PathBuf>,
    /// Script text given on the command line (`;` separates operations).
    #[arg(short = 'e', long = "exec", conflicts_with = "file")]
    exec: Option<String>,
    #[command(flatten)]
    target: TargetArgs,
    /// How long `wc` / `wd` wait for IBF = 0 before reporting a timeout.
    #[arg(long, default_value = "1s", value_parser = parse_duration)]
    ibf_timeout: Duration,
    /// How long `rd` waits for OBF = 1 before reporting a timeout.
    #[arg(long, default_value = "1s", value_parser = parse_duration)]
    obf_timeout: Duration,
    /// How long `await` waits when the script gives no timeout.
    #[arg(long, default_value = "1s", value_parser = parse_duration)]
    await_timeout: Duration,
}

/// Which chip to drive, and how its board is strapped.
#[derive(Debug, Args)]
pub struct TargetArgs {
    /// `emu` (the reference emulator) or `serial:<path>[,baud=N]` (a board,
    /// or `ppmc bridge-sim`, behind the serial bus bridge).
    #[arg(long, default_value = "emu")]
    target: String,
    /// System clock in MHz (fractions allowed, e.g. 12.288).
    #[arg(long, default_value_t = 16.0)]
    clock_mhz: f64,
    /// CSEL strap: high = internal clock SysClk/32 (500 kHz at 16 MHz), low = SysClk/128.
    #[arg(long, value_enum, default_value_t = Level::High)]
    csel: Level,
    /// VSEL strap: high = Equations 3-1/3-2, low = 3-3/3-4 (+7.5 us per pulse).
    #[arg(long, value_enum, default_value_t = Level::High)]
    vsel: Level,
    /// Frequency on the CLOCK pin in kHz, if the board has one (used when the
    /// initialization selects the external clock).
    #[arg(long)]
    ext_clock_khz: Option<f64>,
    /// Shape of the acceleration ramp (the datasheet's chapter 1 is not available).
    #[arg(long, value_enum, default_value_t = Curve::LinearSpeed)]
    accel_curve: Curve,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Level {
    High,
    Low,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Curve {
    LinearSpeed,
    LinearRate,
}

pub(crate) fn parse_duration(s: &str) -> Result<Duration, String> {
    s.parse::<Duration>().map_err(|e| e.to_string())
}

impl TargetArgs {
    pub fn straps(&self) -> Result<Straps, String> {
        let hz = |mhz: f64, what: &str| -> Result<u32, String> {
            let v = (mhz * 1e6).round();
            if v.is_finite() && v >= 1.0 && v <= f64::from(u32::MAX) {
                Ok(v as u32)
            } else {
                Err(format!("{what} {mhz} is not a usable frequency"))
            }
        };
        let straps = Straps {
            sysclk_hz: hz(self.clock_mhz, "--clock-mhz")?,
            csel_high: self.csel == Level::High,
            vsel_high: self.vsel == Level::High,
            ext_clock_hz: self
                .ext_clock_khz
                .map(|k| hz(k / 1e3, "--ext-clock-khz"))
                .transpose()?,
        };
        straps.validate().map_err(|e| e.to_string())?;
        Ok(straps)
    }

    /// The `--target` text.
    pub fn name(&self) -> &str {
        &self.target
    }

    pub fn model(&self) -> ModelConfig {
        ModelConfig {
            accel_curve: match self.accel_curve {
                Curve::LinearSpeed => AccelCurve::LinearSpeed,
                Curve::LinearRate => AccelCurve::LinearRate,
            },
            ..ModelConfig::default()
        }
    }

    /// Opens the target named by `--target`. A board target is health
    /// checked on the way (hello, chip reset, status 0x00).
    pub fn open(&self) -> Result<Box<dyn Target>, OpenError> {
        if self.target == "emu" {
            let t = EmuTarget::new(self.straps().map_err(OpenError::Usage)?, self.model())
                .map_err(|e| OpenError::Usage(e.to_string()))?;
            return Ok(Box::new(t));
        }
        if self.target.starts_with("serial:") {
            let (path, baud) = ppmc::target::parse_spec(&self.target).ok_or_else(|| {
                OpenError::Usage(format!(
                    "bad target `{}`: write serial:<path>[,baud=N]",
                    self.target
                ))
            })?;
            let infra = |e: ppmc::target::SerialError| OpenError::Infrastructure(e.to_string());
            let link = SerialLink::open(&path, baud).map_err(infra)?;
            let t = SerialTarget::open(link, SerialOptions::default()).map_err(infra)?;
            return Ok(Box::new(t));
        }
        Err(OpenError::Usage(format!(
            "unknown target `{}`: use `emu` or `serial:<path>[,baud=N]`",
            self.target
        )))
    }
}

/// Why a target could not be opened.
#[derive(Debug)]
pub enum OpenError {
    /// The options are wrong (exit status 2).
    Usage(String),
    /// The board, bridge or link is not there or not healthy: not the
    /// device's fault, and not the user's typing either (exit status 1).
    Infrastructure(String),
}

impl std::fmt::Display for OpenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OpenError::Usage(m) => f.write_str(m),
            OpenError::Infrastructure(m) => write!(f, "infrastructure error: {m}"),
        }
    }
}

impl OpenError {
    /// Reports the error and gives the exit status.
    pub fn exit(&self) -> ExitCode {
        eprintln!("ppmc: {self}");
        match self {
            OpenError::Usage(_) => ExitCode::from(2),
            OpenError::Infrastructure(_) => ExitCode::from(1),
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => cmd::run(args),
        Command::List(args) => cmd::list(args),
        Command::Record(args) => cmd::record(args),
        Command::Compare(args) => cmd::compare_cmd(args),
        Command::Export(args) => cmd::export(args),
        Command::Console(args) => run_console(args),
        Command::Bench(args) => bench::run(args),
        Command::BridgeSim(args) => bridge_sim(args),
        Command::Fuzz(args) => fuzz_cmd::run(args),
        Command::FaultMatrix(args) => matrix_cmd::run(args),
    }
}

/// Exit status 2: bad usage or bad input (the script, an option).
pub(crate) fn usage_error(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ppmc: {msg}");
    ExitCode::from(2)
}

fn run_console(args: ConsoleArgs) -> ExitCode {
    let opts = ConsoleOptions {
        ibf_timeout: args.ibf_timeout,
        obf_timeout: args.obf_timeout,
        await_timeout: args.await_timeout,
    };
    let mut target = match args.target.open() {
        Ok(t) => t,
        Err(e) => return e.exit(),
    };
    let from_stdin = args.exec.is_none() && args.file.as_ref().is_none_or(|f| f.as_os_str() == "-");
    if from_stdin && io::stdin().is_terminal() {
        return interactive(target.as_mut(), &opts);
    }
    let text = match (&args.exec, &args.file) {
        (Some(e), _) => e.clone(),
        (None, Some(f)) if f.as_os_str() != "-" => match std::fs::read_to_string(f) {
            Ok(t) => t,
            Err(e) => return usage_error(format!("cannot read {}: {e}", f.display())),
        },
        _ => {
            let mut t = String::new();
            if let Err(e) = io::stdin().read_to_string(&mut t) {
                return usage_error(format!("cannot read standard input: {e}"));
            }
            t
        }
    };
    let lines = match console::parse_script(&text) {
        Ok(l) => l,
        Err(e) => return script_error(&args.file, &e),
    };
    let stdout = io::stdout();
    let mut out = stdout.lock();
    match console::run(target.as_mut(), &lines, &opts, &mut out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = out.flush();
            eprintln!("ppmc: {e}");
            ExitCode::from(1)
        }
    }
}

fn script_error(file: &Option<PathBuf>, e: &ScriptError) -> ExitCode {
    match file {
        Some(f) if f.as_os_str() != "-" => eprintln!("{}: {e}", f.display()),
        _ => eprintln!("{e}"),
    }
    ExitCode::from(2)
}

/// Line by line at a terminal: a bad line is reported and skipped, so a
/// typo at the bench does not end the session.
fn interactive(target: &mut dyn Target, opts: &ConsoleOptions) -> ExitCode {
    let stdin = io::stdin();
    let stdout = io::stdout();
    for (i, line) in stdin.lock().lines().enumerate() {
        let line = match line {
            Ok(l) => l,
            Err(e) => return usage_error(format!("cannot read standard input: {e}")),
        };
        let parsed: Vec<Line> = match console::parse_line(&line, i + 1) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let mut out = stdout.lock();
        if let Err(e) = console::run(target, &parsed, opts, &mut out) {
            eprintln!("ppmc: {e}");
            return ExitCode::from(1);
        }
    }
    ExitCode::SUCCESS
}

fn bridge_sim(args: BridgeSimArgs) -> ExitCode {
    use ppmc::bridge::sim::engine;
    use ppmc::bridge::sim::{serve, LinkFaults, ServeEnd};
    use serialport::SerialPort;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    for (name, rate) in [
        ("--drop-rate", args.drop_rate),
        ("--corrupt-rate", args.corrupt_rate),
    ] {
        if !(0.0..=1.0).contains(&rate) {
            return usage_error(format!("{name} {rate}: give a probability from 0 to 1"));
        }
    }
    if args.target.target != "emu" {
        return usage_error("bridge-sim serves the emulator; --target must be emu");
    }
    let straps = match args.target.straps() {
        Ok(s) => s,
        Err(e) => return usage_error(e),
    };
    let mut model = args.target.model();
    if let Err(e) = ppmc::faults::apply_all(&args.chip_faults, &mut model) {
        return usage_error(format!("--chip-fault: {e}"));
    }
    let emu = match EmuTarget::new(straps, model) {
        Ok(t) => t,
        Err(e) => return usage_error(e),
    };
    let (mut master, slave) = match serialport::TTYPort::pair() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("ppmc: cannot open a pseudo-terminal: {e}");
            return ExitCode::from(1);
        }
    };
    let _ = master.set_timeout(std::time::Duration::from_millis(50));
    let Some(path) = slave.name() else {
        eprintln!("ppmc: the pseudo-terminal has no path");
        return ExitCode::from(1);
    };
    if let Some(link) = &args.link {
        let _ = std::fs::remove_file(link);
        if let Err(e) = std::os::unix::fs::symlink(&path, link) {
            eprintln!("ppmc: cannot link {} to {path}: {e}", link.display());
            return ExitCode::from(1);
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
            ExitCode::SUCCESS
        }
        Ok(ServeEnd::Stopped) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ppmc: bridge-sim: {e}");
            ExitCode::from(1)
        }
    }
}
