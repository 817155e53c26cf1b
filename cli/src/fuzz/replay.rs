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
    /// Shrink it while it finds the same (the same invariant broken, the
    /// same kind of departure from the model): on the emulator where it
    /// finds it there too (fast, and checked on the target after), else
    /// on the target, each try an execution from a chip reset. Written to
    /// -o (default FILE.min).
    #[arg(long)]
    shrink: bool,
    /// Where --shrink writes the shrunk input.
    #[arg(short, long, requires = "shrink")]
    output: Option<PathBuf>,
    /// Judge by the invariants alone, not also against the reference
    /// model on the target's timeline (as `fuzz campaign --no-model`).
    #[arg(long)]
    no_model: bool,
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
    let model = (!args.no_model).then(|| args.target.model());
    let model = model.as_ref();
    let (found, took) = guided::execute(target.as_mut(), &ops, model)
        .map_err(|e| CliError::Failed(format!("infrastructure error: {name}: {e}")))?;
    let head = format!(
        "{}: {} ops on {name}, {:.6} s of board time",
        args.file.display(),
        ops.len(),
        took.as_secs_f64()
    );
    let Some(found) = found else {
        outln!(
            "{head}: breaks no invariant{}",
            match model {
                Some(_) => " and does not depart from the model",
                None => "",
            }
        );
        return Ok(());
    };
    match &found {
        guided::What::Break(_) => outln!("{head}: breaks {found}"),
        _ => outln!("{head}: {found}"),
    }
    if !args.shrink {
        return Err(CliError::Verdict);
    }
    let what = found.name();
    let failed = |e| CliError::Failed(format!("infrastructure error while shrinking: {e}"));
    // On the emulator when it finds the same there too and the small one
    // still does on the target; else on the target itself. (A departure
    // from the model is the board's alone: it shrinks on the board.)
    let mut emu = EmuTarget::new(target.straps(), args.target.model()).map_err(usage)?;
    let on_emu = guided::shrink_on(&mut emu, &ops, model, &what).map_err(failed)?;
    let checked = match on_emu {
        Some(m) => finds(target.as_mut(), &m.ops, model, &what)?.then_some(("the emulator", m)),
        None => None,
    };
    let (where_, small) = match checked {
        Some(x) => x,
        None => match guided::shrink_on(target.as_mut(), &ops, model, &what).map_err(failed)? {
            Some(m) => (name.as_str(), m),
            None => {
                errln!("ppmc fuzz replay: {what} did not repeat on {name}");
                return Err(CliError::Verdict);
            }
        },
    };
    ppmc_files::write(&out, &ppmc::fuzzing::finding::to_bytes(&small.ops))?;
    outln!(
        "shrunk on {where_}: {} ops -> {} ops ({} tries), {}; wrote {}",
        ops.len(),
        small.ops.len(),
        small.tries,
        match &small.what {
            guided::What::Break(f) => format!("{} still breaks", f.violation.invariant),
            other => format!("still {other}"),
        },
        out.display()
    );
    for op in &small.ops {
        outln!("{op}");
    }
    Err(CliError::Verdict)
}

/// Whether `ops` find what is named `what` on `target`.
fn finds(
    target: &mut dyn Target,
    ops: &[BusOp],
    model: Option<&ppmc::emu::ModelConfig>,
    what: &str,
) -> Result<bool, CliError> {
    let (found, _) = guided::execute(target, ops, model)
        .map_err(|e| CliError::Failed(format!("infrastructure error: {e}")))?;
    Ok(found.is_some_and(|f| f.name() == what))
}
