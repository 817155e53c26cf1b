//! `ppmc console`: a bus script against a target, one line per result.

use super::args::{parse_duration, TargetArgs};
use crate::{usage, CliError};
use clap::Args;
use ppmc::backend::Target;
use ppmc::console::{self, ConsoleError, ConsoleOptions, Line, ScriptError};
use ppmc::time::Duration;
use std::io::{self, BufRead, IsTerminal, Read, Write};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ConsoleArgs {
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

pub fn run(args: ConsoleArgs) -> Result<(), CliError> {
    let opts = ConsoleOptions {
        ibf_timeout: args.ibf_timeout,
        obf_timeout: args.obf_timeout,
        await_timeout: args.await_timeout,
    };
    let mut target = args.target.open()?;
    let from_stdin = args.exec.is_none() && args.file.as_ref().is_none_or(|f| f.as_os_str() == "-");
    if from_stdin && io::stdin().is_terminal() {
        return interactive(target.as_mut(), &opts);
    }
    let text = match (&args.exec, &args.file) {
        (Some(e), _) => e.clone(),
        (None, Some(f)) if f.as_os_str() != "-" => {
            ppmc_files::read_text(f, ppmc_files::MAX_INPUT_BYTES)?
        }
        _ => {
            let mut t = String::new();
            if let Err(e) = io::stdin().read_to_string(&mut t) {
                return Err(usage(format!("cannot read standard input: {e}")));
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
        Ok(()) => Ok(()),
        // Nobody reads the results any more (`ppmc console s.ppmc | head`).
        Err(ConsoleError::Io(e)) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => {
            let _ = out.flush();
            Err(CliError::Failed(e.to_string()))
        }
    }
}

fn script_error(file: &Option<PathBuf>, e: &ScriptError) -> Result<(), CliError> {
    Err(CliError::BadInput(match file {
        Some(f) if f.as_os_str() != "-" => format!("{}: {e}", f.display()),
        _ => e.to_string(),
    }))
}

/// Line by line at a terminal: a bad line is reported and skipped, so a
/// typo at the bench does not end the session.
fn interactive(target: &mut dyn Target, opts: &ConsoleOptions) -> Result<(), CliError> {
    let stdin = io::stdin();
    let stdout = io::stdout();
    // The prompt goes to standard error, so results written to a file
    // stay clean.
    let prompt = || {
        let mut err = io::stderr();
        let _ = write!(err, "ppmc> ").and_then(|()| err.flush());
    };
    prompt();
    for (i, line) in stdin.lock().lines().enumerate() {
        let line = match line {
            Ok(l) => l,
            Err(e) => return Err(usage(format!("cannot read standard input: {e}"))),
        };
        let parsed: Vec<Line> = match console::parse_line(&line, i + 1) {
            Ok(p) => p,
            Err(e) => {
                errln!("{e}");
                prompt();
                continue;
            }
        };
        let mut out = stdout.lock();
        match console::run(target, &parsed, opts, &mut out) {
            Ok(()) => {}
            Err(ConsoleError::Io(e)) if e.kind() == io::ErrorKind::BrokenPipe => return Ok(()),
            Err(e) => return Err(CliError::Failed(e.to_string())),
        }
        prompt();
    }
    Ok(())
}
