//! `ppmc judge`: a board judged from a logic-analyzer capture of its bus
//! and pins against the reference model (`docs/capture.md`). The judging
//! and its run record are the library's (`ppmc_capture::judge`); this file
//! opens the capture, prints and picks the exit status.

mod args;

pub use args::JudgeArgs;

use crate::capture_args::describe;
use crate::{usage, CliError};
use ppmc_capture::judge::{judge_reopening, CaptureVerdict, JudgeOptions, Judgement};

pub fn run(args: JudgeArgs) -> Result<(), CliError> {
    if let (None, Some(n)) = (&args.trace, &args.scenario) {
        return Err(usage(format!(
            "--scenario {n} names the trace --trace DIR writes; give --trace DIR too (the judging needs no scenario: it replays the accesses the capture holds)"
        )));
    }
    let started = std::time::Instant::now();
    let (mut source, map) = args.capture.open()?;
    let info = source.info().clone();
    let opts = JudgeOptions {
        straps: args.chip.straps().map_err(usage)?,
        model: args.chip.model(),
        tolerances: args.tolerance.tolerances().map_err(usage)?,
        glitch_ps: args.capture.glitch.as_nanos() * 1000,
        partial: args.partial,
        ..JudgeOptions::default()
    };
    args.reports.prepare()?;
    let name = match (&args.trace, &args.scenario) {
        (None, _) => None,
        (Some(_), Some(n)) => Some(n.clone()),
        (Some(_), None) => Some(
            args.capture
                .capture
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "capture".into()),
        ),
    };
    if let Some(dir) = &args.trace {
        use ppmc_logic::map::Signal;
        if map.get(Signal::Pout).is_none() || map.get(Signal::Dir).is_none() {
            return Err(usage(
                "--trace needs channels for POUT and DIR: a trace without them cannot compare its pulses (give --map POUT=...,DIR=...)",
            ));
        }
        ppmc_files::prepare_folder(dir)?;
    }
    let mut store = args.reports.open_store()?;
    describe(&info, &args.capture.capture);
    // The capture is read again only where the board diverged, to hold
    // the divergence against the map (judge::judge_reopening).
    let path = args.capture.capture.clone();
    let mut reopen = move || ppmc_logic::open::open(&path);
    let (j, trace) = judge_reopening(source.as_mut(), &mut reopen, &map, &opts, name.as_deref())
        .map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?;
    let mut problems = Vec::new();
    if let (Some(dir), Some(t)) = (&args.trace, &trace) {
        match ppmc::golden::write(dir, t, false) {
            Ok(_) => outln!("trace: {}", ppmc::golden::path_for(dir, &t.scenario).display()),
            Err(ppmc::golden::GoldenError::Exists { path }) => problems.push(format!(
                "--trace: {}: exists, with another trace: remove it, or give another folder or --scenario",
                path.display()
            )),
            Err(e) => problems.push(format!("--trace: {e}")),
        }
    }
    if args.reports.any() {
        let mut record = j.record(&args.capture.capture, &info, &opts, started.elapsed());
        record.run.boards[0].board_rev = args.board_rev.clone();
        record.run.boards[0].board_serial = args.board_serial.clone();
        problems.extend(super::reports::write(
            &record,
            args.reports.outputs(),
            store.as_mut(),
        ));
    }
    let verdict = say(&j);
    match problems.into_iter().next() {
        Some(p) => Err(CliError::Failed(p)),
        None => verdict,
    }
}

/// Says the judgement; its kind is the exit status.
fn say(j: &Judgement) -> Result<(), CliError> {
    for n in &j.not_judged {
        outln!("not judged: {n}");
    }
    outln!("{}", j.counts_line());
    for h in &j.host {
        outln!("{}", h.line());
    }
    for h in &j.hints {
        outln!("hint: {h}");
    }
    let passed = match j.marginal_line() {
        Some(m) if matches!(j.verdict, CaptureVerdict::Passed) => {
            outln!("{m}");
            "MARGINAL"
        }
        _ => "PASS",
    };
    let word = |w: &str| super::out::verdict_word(w, 0);
    match &j.verdict {
        CaptureVerdict::Failed(d) => {
            outln!("{} the board: {d}", word("FAIL"));
            Err(CliError::Verdict)
        }
        CaptureVerdict::Capture(why) => {
            outln!("{} the capture: {why}", word("ERROR"));
            Err(CliError::Code(4))
        }
        CaptureVerdict::Passed if !j.host.is_empty() => {
            outln!(
                "{} the board; the host firmware broke chapter 3's rules {} times",
                word(passed),
                j.host.len()
            );
            Err(CliError::Code(3))
        }
        CaptureVerdict::Passed => {
            outln!("{} the board", word(passed));
            Ok(())
        }
    }
}
