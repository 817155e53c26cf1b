//! `ppmc export`: a trace as a VCD waveform, or a scenario run on the
//! emulator (clean or with a board fault) as a logic analyzer would record
//! it.

use crate::{usage, CliError};
use clap::Args;
use ppmc::scenario::Scenario;
use ppmc::trace::Trace;
use ppmc_core::bus::HostTiming;
use ppmc_files as files;
use std::path::PathBuf;

/// What to export, and where.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A trace or golden file.
    #[arg(required_unless_present = "scenario", conflicts_with = "scenario")]
    trace: Option<PathBuf>,
    /// Instead of a trace: run this scenario on the emulator, every
    /// register access taking a bus cycle as on a real bus (the golden
    /// traces' accesses take no time), and export what a logic analyzer on
    /// the board would record (with --bus, the bus too).
    #[arg(long, value_name = "NAME")]
    scenario: Option<String>,
    /// With --scenario: run the chip with this fault of the catalogue
    /// (`ppmc fault-matrix --list`), swap-error-A-B or status-stuck-0xNN;
    /// repeat to combine.
    #[arg(long = "chip-fault", value_name = "FAULT", requires = "scenario")]
    chip_faults: Vec<String>,
    /// The VCD file to write (default: `out/<name>.vcd` in the current
    /// folder, the trace's or the scenario's name; never beside the input,
    /// which may be a tracked golden file); `-` for standard output.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Draw the host's bus too: CS*, RD*, WR*, A0 and D0-D7, one cycle per
    /// register access of the trace (its timing is in the file's header
    /// and docs/capture.md), as a logic analyzer on the chip's bus would
    /// record it; and every pin at its level: S1..S5 under the output
    /// logic the initialization chose, chopped while stop switching is on.
    #[arg(long)]
    bus: bool,
    /// With --scenario: how the host times an access it waits for.
    /// `polling` (default): it polls the status and accesses a bus cycle
    /// after the poll that saw the chip ready. `exact`: it waits Table
    /// 3-3's times instead, and each access ends the instant the chip is
    /// ready (IBF falls, OBF rises), the edge case for a logic analyzer's
    /// sampling (docs/capture.md).
    #[arg(long, value_name = "HOW", default_value = "polling", value_parser = parse_host, requires = "scenario")]
    host: HostTiming,
}

/// `--host`: `polling` or `exact`.
fn parse_host(text: &str) -> Result<HostTiming, String> {
    match text {
        "polling" => Ok(HostTiming::Polling),
        "exact" => Ok(HostTiming::Exact),
        _ => Err(format!("`{text}`: say `polling` or `exact`")),
    }
}

/// The trace of `name` run on the emulator with `faults`, every register
/// access taking a bus cycle, as a logic analyzer records it (every
/// access the chip served, though the scenario fail).
fn scenario_trace(
    name: &str,
    faults: &[String],
    host: HostTiming,
    suite: &[Scenario],
) -> Result<Trace, CliError> {
    let Some(s) = suite.iter().find(|s| s.name == name) else {
        return Err(usage(format!("no scenario `{name}` (see `ppmc list`)")));
    };
    let mut model = ppmc::emu::ModelConfig::default();
    ppmc::faults::apply_all(faults, &mut model).map_err(|e| usage(format!("--chip-fault: {e}")))?;
    ppmc_capture::fault_matrix::capture::analyzer_trace_with(&model, s, host)
        .map(|(trace, _)| trace)
        .map_err(|e| CliError::Failed(format!("{name}: {e}")))
}

pub fn run(args: ExportArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let (trace, input) = match (&args.trace, &args.scenario) {
        (_, Some(name)) => (
            scenario_trace(name, &args.chip_faults, args.host, suite)?,
            None,
        ),
        (Some(path), None) => {
            let text = files::read_text(path, files::MAX_TRACE_BYTES)?;
            match Trace::parse(&text) {
                Ok(t) => (t, Some(path.clone())),
                Err(e) => {
                    return Err(usage(format!(
                        "{}:{}: {}",
                        path.display(),
                        e.line,
                        e.message
                    )))
                }
            }
        }
        (None, None) => return Err(usage("give a trace file or --scenario NAME")),
    };
    let out = match &args.output {
        Some(o) => o.clone(),
        None => {
            let dir = PathBuf::from("out"); // of the current folder
            files::prepare_folder(&dir)?;
            // The name a file gave, only as a plain file name.
            let stem = input
                .as_ref()
                .and_then(|i| i.file_stem())
                .map(|s| s.to_string_lossy().into_owned());
            let name = [Some(trace.scenario.clone()), stem]
                .into_iter()
                .flatten()
                .find(|n| files::plain_file_name(n))
                .unwrap_or_else(|| "export".into());
            dir.join(format!("{name}.vcd"))
        }
    };
    let what = ppmc::vcd_export::Export {
        window: None,
        bus: args.bus,
    };
    // Streamed: a 16-million-pulse trace costs time, not memory.
    if out.as_os_str() == "-" {
        let stdout = std::io::stdout().lock();
        return match ppmc::vcd_export::export_with(&trace, what, stdout) {
            // A reader that stops early (`| head`) is not an error.
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(CliError::Failed(format!("standard output: {e}")))
            }
            _ => Ok(()),
        };
    }
    if input.as_ref().is_some_and(|i| files::same_file(&out, i)) {
        let how = match args.output {
            Some(_) => "-o names the input trace",
            None => "the default output is the input trace itself",
        };
        return Err(usage(format!(
            "{}: {how}; ppmc does not write over its input (give another -o, or - for standard output)",
            out.display()
        )));
    }
    files::check_writable(&out)?;
    files::write_with(&out, |w| ppmc::vcd_export::export_with(&trace, what, w))?;
    outln!("wrote {}", out.display());
    Ok(())
}
