//! `ppmc list`: the scenarios with their section, tags and summary.

use super::args::SelectArgs;
use crate::{usage, CliError};
use clap::Args;
use ppmc::scenario::Scenario;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct ListArgs {
    #[command(flatten)]
    select: SelectArgs,
}

pub fn run(args: ListArgs, suite: &[Scenario]) -> Result<(), CliError> {
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return Err(usage(e)),
    };
    for s in &scenarios {
        outln!(
            "{:<58} {:<7} [{}]  {}",
            s.name,
            s.section,
            s.tags.join(","),
            s.summary
        );
    }
    outln!("{} scenarios", scenarios.len());
    Ok(())
}
