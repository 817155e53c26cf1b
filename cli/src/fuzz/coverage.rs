//! `ppmc fuzz coverage`: the domain coverage of a corpus.

use super::inputs::*;
use crate::CliError;
use ppmc::emu::ModelConfig;
use ppmc::fuzzing::finding::InputKind;
use std::path::PathBuf;

pub fn run(paths: &[PathBuf], kind: InputKind) -> Result<(), CliError> {
    let cfg = ModelConfig::default();
    let inputs = load_inputs(paths, kind, &cfg)?;
    let ops: Vec<_> = inputs.into_iter().map(|(_, o)| o).collect();
    outln!(
        "{}",
        ppmc::fuzzing::campaign::Coverage::of(&ops)
            .render()
            .trim_end_matches('\n')
    );
    Ok(())
}
