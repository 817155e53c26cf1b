//! `ppmc fuzz triage`: findings bucketed by the invariant each breaks.

use super::inputs::*;
use crate::CliError;
use std::path::PathBuf;

pub fn run(paths: &[PathBuf], model: &ModelArgs) -> Result<(), CliError> {
    let cfg = model.model()?;
    let inputs = load_inputs(paths, model.kind.into(), &cfg)?;
    let (buckets, clean) = ppmc::fuzzing::campaign::triage(&inputs, &cfg);
    outln!("| invariant | inputs | shortest input | its ops | break |\n|---|---:|---|---:|---|");
    for b in &buckets {
        let (name, n, v) = &b.smallest;
        outln!(
            "| {} | {} | {name} | {n} | after op {}: {} |",
            b.invariant,
            b.inputs.len(),
            v.op,
            v.detail
        );
    }
    outln!(
        "\n{} inputs: {} findings in {} buckets, {} break nothing",
        inputs.len(),
        inputs.len() - clean.len(),
        buckets.len(),
        clean.len()
    );
    if buckets.is_empty() {
        Ok(())
    } else {
        Err(CliError::Verdict)
    }
}
