//! `ppmc fuzz to-scenario`: a fuzz input as a regression scenario.

use super::inputs::*;
use crate::{usage, CliError};
use ppmc::fuzzing::finding::{self};
use ppmc_files as files;
use std::path::Path;

pub fn run(input: &InputArgs, dir: &Path) -> Result<(), CliError> {
    let (cfg, ops) = input.load()?;
    let Some(v) = finding::first_break(&ops, &cfg) else {
        errln!(
            "ppmc fuzz to-scenario: {} breaks no invariant on this model; \
                 a regression scenario would pass already",
            input.file.display()
        );
        return Err(CliError::Verdict);
    };
    if !dir.is_dir() {
        return Err(usage(format!(
            "{} is not a directory: run from the repository root or give --dir",
            dir.display()
        )));
    }
    let ops = &ops[..=v.op.min(ops.len().saturating_sub(1))];
    let source = input.file.display().to_string();
    // The first free name; another process taking it first moves us on.
    let mut n = 1;
    let (stem, path) = loop {
        let stem = finding::scenario_stem(v.invariant, n);
        let path = dir.join(format!("{stem}.rs"));
        let text = finding::scenario_file(&stem, ops, &v, &source);
        match files::create_new(&path, text.as_bytes()) {
            Ok(()) => break (stem, path),
            Err(files::FileError::Exists { .. }) if n < 10_000 => n += 1,
            Err(e) => return Err(e.into()),
        }
    };
    outln!(
        "wrote {} (scenario {stem}, invariant {}, {} ops); add `{stem}` to the \
             suite! list in scenarios/src/lib.rs, and `cargo test` runs it",
        path.display(),
        v.invariant,
        v.op + 1
    );
    Ok(())
}
