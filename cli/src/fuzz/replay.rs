//! `ppmc fuzz replay FILE --target T [--shrink]`: a finding of a campaign
//! (a `bus_bytes` input) replayed on any target, bit for bit as the
//! campaign ran it, and shrunk where it breaks.

use crate::args::TargetArgs;
use crate::{usage, CliError};
use clap::Args;
use ppmc::backend::{EmuTarget, Target};
use ppmc::bus_program::{self, BusOp};
use ppmc::fuzzing::guided;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The input (a finding of `ppmc fuzz campaign`, any `bus_bytes`
    /// input).
    file: PathBuf,
    #[command(flatten)]
    target: TargetArgs,
    /// Shrink it while the same invariant breaks: on the emulator where it
    /// breaks there too (fast, and checked on the target after), else on
    /// the target, each try an execution from a chip reset. Written to
    /// -o (default FILE.min).
    #[arg(long)]
    shrink: bool,
    /// Where --shrink writes the shrunk input.
    #[arg(short, long, requires = "shrink")]
    output: Option<PathBuf>,
}

pub fn run(args: ReplayArgs) -> Result<(), CliError> {
    let bytes = ppmc_files::read(&args.file, 1 << 20)?;
    let ops = bus_program::decode(&bytes);
    let out = args.output.clone().unwrap_or_else(|| {
        let mut name = args.file.clone().into_os_string();
        name.push(".min");
        PathBuf::from(name)
    });
    if args.shrink {
        ppmc_files::check_writable(&out)?;
    }
    let mut target = args.target.open()?;
    let name = args.target.name();
    let (found, took) = guided::execute(target.as_mut(), &ops)
        .map_err(|e| CliError::Failed(format!("infrastructure error: {name}: {e}")))?;
    let head = format!(
        "{}: {} ops on {name}, {:.6} s of board time",
        args.file.display(),
        ops.len(),
        took.as_secs_f64()
    );
    let Some(found) = found else {
        outln!("{head}: breaks no invariant");
        return Ok(());
    };
    outln!("{head}: breaks {} (at {})", found.violation, found.at);
    if !args.shrink {
        return Err(CliError::Verdict);
    }
    let invariant = found.violation.invariant;
    let failed = |e| CliError::Failed(format!("infrastructure error while shrinking: {e}"));
    // On the emulator when it breaks there too and the small one still
    // breaks on the target; else on the target itself.
    let mut emu = EmuTarget::new(target.straps(), Default::default()).map_err(usage)?;
    let on_emu = guided::shrink_on(&mut emu, &ops, invariant).map_err(failed)?;
    let checked = match on_emu {
        Some(m) => breaks(target.as_mut(), &m.ops, invariant)?.then_some(("the emulator", m)),
        None => None,
    };
    let (where_, small) = match checked {
        Some(x) => x,
        None => match guided::shrink_on(target.as_mut(), &ops, invariant).map_err(failed)? {
            Some(m) => (name.as_str(), m),
            None => {
                errln!("ppmc fuzz replay: the break of {invariant} did not repeat on {name}");
                return Err(CliError::Verdict);
            }
        },
    };
    ppmc_files::write(&out, &ppmc::fuzzing::finding::to_bytes(&small.ops))?;
    outln!(
        "shrunk on {where_}: {} ops -> {} ops ({} tries), {} still breaks; wrote {}",
        ops.len(),
        small.ops.len(),
        small.tries,
        small.violation.invariant,
        out.display()
    );
    for op in &small.ops {
        outln!("{op}");
    }
    Err(CliError::Verdict)
}

/// Whether `ops` break `invariant` on `target`.
fn breaks(
    target: &mut dyn Target,
    ops: &[BusOp],
    invariant: ppmc::invariants::ids::Invariant,
) -> Result<bool, CliError> {
    let (found, _) = guided::execute(target, ops)
        .map_err(|e| CliError::Failed(format!("infrastructure error: {e}")))?;
    Ok(found.is_some_and(|f| f.violation.invariant == invariant))
}
