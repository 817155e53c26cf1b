//! `ppmc export`: a trace as a VCD waveform.

use crate::cli::{usage, CliError};
use crate::files;
use crate::trace::Trace;
use clap::Args;
use std::path::PathBuf;

/// What to export, and where.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A trace or golden file.
    trace: PathBuf,
    /// The VCD file to write (default: the trace's name with .vcd; `-` for
    /// standard output).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Draw the host's bus too: CS*, RD*, WR*, A0 and D0-D7, one cycle per
    /// register access of the trace (its timing is in the file's header
    /// and docs/captures.md), as a logic analyzer on the chip's bus would
    /// record it.
    #[arg(long)]
    bus: bool,
}

pub fn run(args: ExportArgs) -> Result<(), CliError> {
    let text = files::read_text(&args.trace, files::MAX_TRACE_BYTES)?;
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
    let out = match &args.output {
        Some(o) => o.clone(),
        None => args.trace.with_extension("vcd"),
    };
    let what = crate::vcd_export::Export {
        window: None,
        bus: args.bus,
    };
    // Streamed: a 16-million-pulse trace costs time, not memory.
    if out.as_os_str() == "-" {
        let stdout = std::io::stdout().lock();
        return match crate::vcd_export::export_with(&trace, what, stdout) {
            // A reader that stops early (`| head`) is not an error.
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(CliError::Failed(format!("standard output: {e}")))
            }
            _ => Ok(()),
        };
    }
    if files::same_file(&out, &args.trace) {
        let how = match args.output {
            Some(_) => "-o names the input trace",
            None => "the default output (the trace's name with .vcd) is the input trace itself",
        };
        return Err(usage(format!(
            "{}: {how}; ppmc does not write over its input (give another -o, or - for standard output)",
            out.display()
        )));
    }
    files::check_writable(&out)?;
    files::write_with(&out, |w| crate::vcd_export::export_with(&trace, what, w))?;
    outln!("wrote {}", out.display());
    Ok(())
}
