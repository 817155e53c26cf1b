//! `ppmc decode`: a logic-analyzer capture of the chip's bus decoded into
//! register accesses, printed in the bus console's language.

use crate::capture_args::CaptureArgs;
use crate::{usage, CliError};
use clap::Args;
use ppmc::time::{Duration, Instant};
use ppmc_logic::decode::BusDecoder;
use ppmc_logic::source::LogicSource;

/// Print the register accesses of a capture in the bus console's language.
#[derive(Debug, Args)]
pub struct DecodeArgs {
    #[command(flatten)]
    capture: CaptureArgs,
}

pub fn run(args: DecodeArgs) -> Result<(), CliError> {
    let (mut source, map) = args.capture.open()?;
    let info = source.info().clone();
    let bus = map
        .require_bus(&info)
        .map_err(|why| usage(format!("{}: {why}", args.capture.capture.display())))?;
    let mut source = ppmc_logic::map::Inverted::new(source.as_mut(), &map);
    let mut d = BusDecoder::new(bus, &info, args.capture.glitch.as_nanos() * 1000);
    outln!(
        "# {} ({}), decoded by ppmc: replay with `ppmc console`",
        args.capture.capture.display(),
        info.format
    );
    let mut last_end: Option<u64> = None;
    while let Some(c) = source
        .next_change()
        .map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?
    {
        if let Some(t) = d.push(c) {
            if let Some(prev) = last_end {
                let gap = Duration::from_nanos(t.end_ps.saturating_sub(prev) / 1000);
                if gap > Duration::ZERO {
                    outln!("wait {gap}");
                }
            }
            let at = Instant::from_nanos(t.end_ps / 1000);
            match t.to_string() {
                read if read.contains('#') => outln!("{read} at {at}"),
                write => outln!("{write}  # at {at}"),
            }
            last_end = Some(t.end_ps);
        }
    }
    let s = d.summary();
    outln!(
        "# {} accesses, {} glitches dropped, {} bus fights",
        s.transactions,
        s.glitches,
        s.conflicts
    );
    if let Some(why) = s.rate_problem(&info) {
        errln!("ppmc: {why}");
        return Err(CliError::Code(4));
    }
    Ok(())
}
