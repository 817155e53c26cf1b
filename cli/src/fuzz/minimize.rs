//! `ppmc fuzz minimize`: a fuzz input shrunk while the same invariant breaks.

use super::inputs::*;
use crate::CliError;
use ppmc::fuzzing::finding::{self};
use std::path::PathBuf;

pub fn run(input: &InputArgs, output: Option<PathBuf>) -> Result<(), CliError> {
    let (cfg, ops) = input.load()?;
    let Some(v) = finding::first_break(&ops, &cfg) else {
        errln!(
            "ppmc fuzz minimize: {} breaks no invariant on this model; nothing to minimize",
            input.file.display()
        );
        return Err(CliError::Verdict);
    };
    let Some(m) = finding::minimize(&ops, &cfg, v.invariant) else {
        errln!(
            "ppmc fuzz minimize: the break of {} is not reproducible",
            v.invariant
        );
        return Err(CliError::Verdict);
    };
    let out = output.unwrap_or_else(|| with_suffix(&input.file, "min"));
    let bytes = finding::to_bytes(&m.ops);
    ppmc_files::write(&out, &bytes)?;
    errln!(
            "ppmc fuzz minimize: {} ops -> {} ops ({} oracle runs), invariant {} still breaks; wrote {}",
            ops.len(),
            m.ops.len(),
            m.tries,
            m.violation.invariant,
            out.display()
        );
    let (script, _) = finding::reproducer_with(&bytes, &out.display().to_string(), cfg);
    outln!("{}", script.trim_end_matches('\n'));
    Ok(())
}
