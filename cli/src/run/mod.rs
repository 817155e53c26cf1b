//! `ppmc run`: the conformance suite on a target, graded, with reports.
//! The run itself is the library's (`ppmc::session`); this file checks the
//! arguments, opens the boards, prints and picks the exit status.

mod args;

pub use args::RunArgs;

use crate::lines::{board_lines, not_passed_lines, summary_lines, verdict_line};
use crate::{usage, CliError};
use ppmc::compare::Tolerances;
use ppmc::runner::{Farm, Spread};
use ppmc::scenario::{DriverOptions, Grading, NotRun, Retry, Scenario, Verdict};
use ppmc::session::{self, Plan, RunVerdict};
use ppmc_record::RunOptions;

pub fn run(mut args: RunArgs, suite: &[Scenario]) -> Result<(), CliError> {
    // Before anything is opened: a signal during the open still leaves
    // reports, and ends every wait on a link within a second.
    let stop = crate::signals::install();
    args.target.stop = stop.clone();
    let scenarios = args.select.scenarios(suite).map_err(usage)?;
    let tol = args.tolerance.tolerances().map_err(usage)?;
    args.check()?;
    let mut store = args.reports.open_store()?;
    let outputs = args.reports.outputs();
    let specs = args.target.specs().map_err(usage)?;
    let several_specs = specs.len();
    args.power.check(several_specs).map_err(usage)?;
    let spread = match args.each && several_specs > 1 {
        true => Spread::Each,
        false => Spread::Share,
    };
    let open = ppmc::backend::OpenOptions {
        power: args.power.options(),
        ..args.target.open_options()
    };
    let mut farm = Farm::open(specs, &open)?;
    let (rev, serial) = (&args.target.board_rev, &args.target.board_serial);
    let boards = session::boards(&farm, rev.as_deref(), serial.as_deref());
    let mut info = ppmc::runner::run_info(boards, spread.name(several_specs));
    info.options = args.options(&tol);
    let plan = Plan {
        scenarios: &scenarios,
        repeat: args.repeat as usize,
        options: DriverOptions {
            grading: Grading::percent(args.marginal),
            retry: Retry {
                times: args.retries,
                failures: args.retry_failures,
            },
            timeout: (args.timeout).map(|d| std::time::Duration::from_nanos(d.as_nanos())),
            ..DriverOptions::default()
        },
        spread,
        golden: args.golden.as_deref().map(|dir| (dir, tol)),
        artifacts: args
            .artifacts
            .as_deref()
            .map(|d| (d, args.artifacts_window)),
        draw: args.reports.json.is_some() || args.reports.html.is_some(),
    };
    if farm.reached_none() {
        // Nothing ran: say so in the reports too, so CI shows an
        // infrastructure problem rather than a bad board.
        let why = farm.unreached_reason();
        let record = session::unreached(&mut farm, &plan, info);
        for e in crate::reports::write(&record, outputs, store.as_mut()) {
            errln!("ppmc: {e}");
        }
        summary_lines(&record.summary, record.scenarios.len());
        if stop.requested() {
            return Err(CliError::Interrupted);
        }
        let why = why.strip_prefix("infrastructure error: ").unwrap_or(&why);
        return Err(CliError::Infrastructure(why.to_string()));
    }
    for (b, e) in farm.unreached() {
        errln!(
            "ppmc: board {} takes no part in the run: {e}",
            info.boards[*b].name
        );
    }
    let runs = match spread {
        Spread::Each => several_specs - farm.unreached().len(),
        Spread::Share => 1,
    };
    let progress = crate::progress::Progress::new(scenarios.len() * plan.repeat * runs);
    let several = info.boards.len() > 1;
    let stopped = || stop.requested() || crate::out::stdout_closed();
    let mut ended = session::run(&mut farm, &plan, info, stopped, |r, board| {
        progress.step(r.name);
        if !matches!(r.verdict, Verdict::NotRun(NotRun::Interrupted)) {
            progress.line(&verdict_line(r, several.then_some(board)));
        }
    });
    progress.finish();
    let record = &ended.record;
    ended
        .problems
        .extend(crate::reports::write(record, outputs, store.as_mut()));
    if ended.unlisted > 0 {
        outln!(
            "{} runs that did not pass are counted, not listed: the reports list the first {} after the first pass",
            ended.unlisted,
            ppmc::sink::MAX_LISTED
        );
    }
    not_passed_lines(record);
    summary_lines(&record.summary, record.summary.runs());
    if several {
        board_lines(&record.run, &ended.board_tallies);
    }
    for p in &ended.problems {
        errln!("ppmc: {p}");
    }
    match ended.verdict(&farm, args.flaky_is_failure) {
        RunVerdict::Passed => Ok(()),
        RunVerdict::Interrupted => Err(CliError::Interrupted),
        RunVerdict::Infrastructure(why) => Err(CliError::Infrastructure(why)),
        RunVerdict::Failed => {
            let flaky = ended.record.summary.flaky;
            if args.flaky_is_failure && flaky > 0 {
                errln!("ppmc: {flaky} scenarios passed only on a retry, and --flaky-is-failure is given");
            }
            Err(CliError::Verdict)
        }
    }
}

impl RunArgs {
    /// The options in force, for the run record.
    fn options(&self, tol: &Tolerances) -> RunOptions {
        let mut o = RunOptions {
            repeat: self.repeat,
            golden: self.golden.as_ref().map(|g| g.display().to_string()),
            marginal_pct: self.marginal,
            latency_tol_pct: tol.latency_bp as f64 / 100.0,
            interval_tol_pct: tol.interval_bp as f64 / 100.0,
            time_floor_ns: tol.floor.as_nanos(),
            retries: self.retries,
            retry_failures: self.retry_failures,
            flaky_is_failure: self.flaky_is_failure,
            ..RunOptions::default()
        };
        self.select.describe(&mut o);
        o
    }
}
