//! `ppmc fuzz seeds`: the fuzz targets' seed corpora written from the
//! bridge protocol and the suite (`ppmc::fuzzing::seeds`), after a
//! protocol or scenario change.

use crate::CliError;
use ppmc::runner::run_suite;
use ppmc::scenario::{DriverOptions, Scenario};
use std::path::Path;

pub fn run(out: &Path, suite: &[Scenario]) -> Result<(), CliError> {
    let mut emu = ppmc::backend::EmuTarget::new(Default::default(), Default::default())
        .map_err(|e| CliError::Failed(e.to_string()))?;
    let traces: Vec<_> = run_suite(&mut emu, suite, 1, DriverOptions::default(), |_| {})
        .into_iter()
        .filter_map(|r| Some((r.name, r.trace?)))
        .collect();
    let seeds = ppmc::fuzzing::seeds::all(&traces).map_err(CliError::Failed)?;
    let (mut written, mut same) = (0, 0);
    for (target, name, bytes) in &seeds {
        let dir = out.join(target);
        ppmc_files::prepare_folder(&dir)?;
        let path = dir.join(name);
        if std::fs::read(&path).ok().as_deref() == Some(&bytes[..]) {
            same += 1;
            continue;
        }
        ppmc_files::write(&path, bytes)?;
        outln!("wrote {}", path.display());
        written += 1;
    }
    outln!("{} seeds: {written} written, {same} unchanged", seeds.len());
    Ok(())
}
