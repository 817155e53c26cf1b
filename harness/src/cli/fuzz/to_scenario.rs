//! `ppmc fuzz to-scenario`: a fuzz input as a regression scenario.

use super::*;

pub fn run(input: &InputArgs, dir: &Path) -> Result<(), CliError> {
    let (cfg, ops) = input.load()?;
    let Some(v) = finding::first_break(&ops, &cfg) else {
        eprintln!(
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
    let (stem, path) = (1..)
        .map(|n| {
            let stem = finding::scenario_stem(v.invariant, n);
            let path = dir.join(format!("{stem}.rs"));
            (stem, path)
        })
        .find(|(_, p)| !p.exists())
        .unwrap_or_default();
    let text = finding::scenario_file(
        &stem,
        &ops[..=v.op.min(ops.len().saturating_sub(1))],
        &v,
        &input.file.display().to_string(),
    );
    if let Err(e) = crate::golden::write_atomic(&path, text.as_bytes()) {
        return Err(usage(format!("cannot write {}: {e}", path.display())));
    }
    println!(
        "wrote {} (scenario {stem}, invariant {}, {} ops); add `{stem}` to the \
             suite! list in scenarios/src/lib.rs, and `cargo test` runs it",
        path.display(),
        v.invariant,
        v.op + 1
    );
    Ok(())
}
