//! `ppmc`: the command-line front end.

mod bench;
mod cmd;

use clap::{Args, Parser, Subcommand, ValueEnum};
use ppmc::console::{self, ConsoleOptions, Line, ScriptError};
use ppmc::emu::{AccelCurve, ModelConfig};
use ppmc::protocol::Straps;
use ppmc::target::{EmuTarget, Target};
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
    /// Measure the emulator's speed (maximum-length move, constant-rate
    /// stretches, per-pulse expansion) and print the figures.
    Bench(bench::BenchArgs),
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
    /// `emu` (the reference emulator).
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
    fn straps(&self) -> Result<Straps, String> {
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

    fn model(&self) -> ModelConfig {
        ModelConfig {
            accel_curve: match self.accel_curve {
                Curve::LinearSpeed => AccelCurve::LinearSpeed,
                Curve::LinearRate => AccelCurve::LinearRate,
            },
            ..ModelConfig::default()
        }
    }

    /// Opens the target named by `--target`.
    pub fn open(&self) -> Result<Box<dyn Target>, String> {
        match self.target.as_str() {
            "emu" => {
                let t = EmuTarget::new(self.straps()?, self.model()).map_err(|e| e.to_string())?;
                Ok(Box::new(t))
            }
            other => Err(format!(
                "unknown target `{other}`: this version supports `emu`"
            )),
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
        Err(e) => return usage_error(e),
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
