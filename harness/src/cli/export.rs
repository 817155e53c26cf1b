//! `ppmc export`: a trace as a VCD waveform.

use crate::cli::{usage, CliError};
use crate::golden::{self};
use crate::trace::Trace;
use clap::Args;
use std::path::PathBuf;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A trace or golden file.
    trace: PathBuf,
    /// The VCD file to write (default: the trace's name with .vcd).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn run(args: ExportArgs) -> Result<(), CliError> {
    let text = match std::fs::read_to_string(&args.trace) {
        Ok(t) => t,
        Err(e) => return Err(usage(format!("{}: {e}", args.trace.display()))),
    };
    let trace = match Trace::parse(&text) {
        Ok(t) => t,
        Err(e) => {
            return Err(usage(format!(
                "{}:{}: {}",
                args.trace.display(),
                e.line,
                e.message
            )))
        }
    };
    let out = args
        .output
        .unwrap_or_else(|| args.trace.with_extension("vcd"));
    let mut buf = Vec::new();
    if let Err(e) = crate::vcd_export::export(&trace, &mut buf) {
        return Err(CliError::Failed(format!("{}: {e}", out.display())));
    }
    if let Err(e) = golden::write_atomic(&out, &buf) {
        return Err(CliError::Failed(format!("{}: {e}", out.display())));
    }
    println!("wrote {}", out.display());
    Ok(())
}
