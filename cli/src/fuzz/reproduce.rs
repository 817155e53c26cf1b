//! `ppmc fuzz reproduce`: a fuzz input as a console script, with the invariant it breaks.

use super::inputs::*;
use crate::CliError;
use ppmc::fuzzing::finding::{self};

pub fn run(input: &InputArgs) -> Result<(), CliError> {
    let (cfg, ops) = input.load()?;
    let data = finding::to_bytes(&ops);
    let source = input.file.display().to_string();
    let (script, found) = finding::reproducer_with(&data, &source, cfg);
    outln!("{}", script.trim_end_matches('\n'));
    if found.is_some() {
        Err(CliError::Verdict)
    } else {
        Ok(())
    }
}
