//! A campaign's files: the seeds it starts from, and the inputs it keeps
//! (its corpus, its findings), each written once.

use super::inputs::read_folder;
use crate::{usage, CliError};
use std::path::{Path, PathBuf};

/// Writes `bytes` as `dir/name` unless a file of that name is there (the
/// same input, by its hash).
pub fn keep(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), CliError> {
    let path = dir.join(name);
    match path.exists() {
        true => Ok(()),
        false => Ok(ppmc_files::create_new(&path, bytes)?),
    }
}

/// A campaign's seeds: the inputs under `dirs` (else the conformance
/// suite's bus traffic), then the corpus it resumes; a usage error when
/// none is an input that is not empty.
pub fn seeds(
    dirs: &[PathBuf],
    corpus: Option<&Path>,
    suite: &[ppmc::scenario::Scenario],
) -> Result<Vec<Vec<u8>>, CliError> {
    let mut seeds = match dirs.is_empty() {
        true => ppmc::fuzzing::seeds::suite_traffic(suite).map_err(CliError::Failed)?,
        false => Vec::new(),
    };
    for dir in dirs.iter().map(PathBuf::as_path).chain(corpus) {
        seeds.extend(read_folder(dir)?);
    }
    match seeds.iter().all(|x| x.is_empty()) {
        true => Err(usage(
            "no seed input to start from: --seeds and --corpus hold no file that is not empty",
        )),
        false => Ok(seeds),
    }
}
