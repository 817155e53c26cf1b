//! `ppmc fuzz twin`: a bus-byte input run on the emulator and on the plain
//! model (the second model, written from the datasheet alone), the first
//! difference shown, and the input shrunk to the fewest ops that still
//! show one.

use super::inputs::*;
use crate::CliError;
use ppmc::bus_program;
use ppmc::emu::ModelConfig;
use ppmc::fuzzing::finding::{self};
use ppmc::plain_model::twin;
use ppmc::protocol::Straps;
use std::path::{Path, PathBuf};

pub fn run(file: &Path, output: Option<PathBuf>) -> Result<(), CliError> {
    let data = ppmc_files::read(file, ppmc_files::MAX_INPUT_BYTES)?;
    let ops = bus_program::decode(&data);
    let cfg = ModelConfig::default();
    let straps = Straps::default();
    let d = match twin::check(&ops, straps, &cfg) {
        Ok(a) => {
            outln!(
                "{}: the models agree ({} ops, {} pulses, {} pin changes{})",
                file.display(),
                a.ops,
                a.pulses,
                a.pin_changes,
                if a.cut_short {
                    "; cut short at the plain model's pulse budget"
                } else {
                    ""
                }
            );
            return Ok(());
        }
        Err(d) => d,
    };
    outln!("{}: the models disagree {d}", file.display());
    let Some((small, found)) = finding::minimize_disagreement(&ops, straps, &cfg) else {
        return Err(CliError::Verdict);
    };
    let out = output.unwrap_or_else(|| with_suffix(file, "min"));
    ppmc_files::write(&out, &bus_program::encode(&small))?;
    errln!(
        "ppmc fuzz twin: {} ops -> {} ops; wrote {}",
        ops.len(),
        small.len(),
        out.display()
    );
    outln!("# {}: the models disagree {found}", out.display());
    for op in &small {
        outln!("{op}");
    }
    Err(CliError::Verdict)
}
