//! `ppmc fuzz coverage`: the domain coverage of a corpus.

use super::*;

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
