//! `ppmc list`: the scenarios with their section, tags and summary.

use super::args::SelectArgs;
use crate::scenario::Scenario;
use clap::Args;
use std::process::ExitCode;

/// Which scenarios to take.
#[derive(Debug, Args)]
pub struct ListArgs {
    #[command(flatten)]
    select: SelectArgs,
}

pub fn run(args: ListArgs, suite: &[Scenario]) -> ExitCode {
    let scenarios = match args.select.scenarios(suite) {
        Ok(s) => s,
        Err(e) => return super::usage_error(e),
    };
    for s in &scenarios {
        println!(
            "{:<58} {:<7} [{}]  {}",
            s.name,
            s.section,
            s.tags.join(","),
            s.summary
        );
    }
    println!("{} scenarios", scenarios.len());
    ExitCode::SUCCESS
}
