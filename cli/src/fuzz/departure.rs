//! What `ppmc fuzz [run]` does around its loop: opens its target, and
//! keeps a departure (replays its seed up to it, minimizes it on the
//! target, and writes the reproducer).

use crate::args::TargetArgs;
use crate::{usage, CliError};
use ppmc::backend::{EmuTarget, Target};
use ppmc::fuzzing::differential::{self, Departure, DiffSettings};
use ppmc::protocol::Straps;
use std::path::Path;

/// The run's target: with `--target emu`, the emulator on `straps` with
/// `faults` (a board with them, against the clean reference); else the
/// board, which takes no fault.
pub fn open(
    target: &TargetArgs,
    straps: Straps,
    faults: &[String],
) -> Result<Box<dyn Target>, CliError> {
    if target.name() == "emu" {
        let mut model = target.model();
        ppmc::faults::apply_all(faults, &mut model)
            .map_err(|e| usage(format!("--chip-fault: {e}")))?;
        return Ok(Box::new(EmuTarget::new(straps, model).map_err(usage)?));
    }
    if !faults.is_empty() {
        return Err(usage(
            "--chip-fault applies to --target emu; a bridge simulator takes it as `ppmc bridge-sim --chip-fault`",
        ));
    }
    target.open()
}

/// Minimizes departure `d` of run `seed` on `target` (at most `budget`
/// replays) and writes its reproducer to `out`; a departure is the
/// board's verdict, so this ends in [`CliError::Verdict`] unless writing
/// fails.
pub fn keep(
    target: &mut dyn Target,
    settings: &DiffSettings,
    seed: u64,
    name: &str,
    d: &Departure,
    budget: usize,
    out: &Path,
) -> Result<(), CliError> {
    // The seed replays the run up to the departure.
    let acts: Vec<_> = differential::program(seed).take(d.action + 1).collect();
    let (small, small_d) = match differential::minimize(target, &acts, settings, budget) {
        Ok(x) => x,
        Err(e) => {
            errln!("ppmc fuzz: infrastructure error while minimizing: {e}");
            return Err(CliError::Verdict);
        }
    };
    let (acts_out, d_out) = match small_d {
        Some(sd) => (small, sd),
        // Not reproducible from a reset (a flaky board): keep the whole run.
        None => {
            errln!("ppmc fuzz: the departure did not repeat from a reset; keeping the whole run");
            (acts, d.clone())
        }
    };
    let text = differential::script(&acts_out, &d_out, seed, name);
    ppmc_files::write(out, text.as_bytes())?;
    outln!(
        "minimized to {} actions; reproducer written to {}",
        acts_out.len(),
        out.display()
    );
    Err(CliError::Verdict)
}
