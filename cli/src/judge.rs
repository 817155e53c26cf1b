//! `ppmc decode` and `ppmc judge`: a logic-analyzer capture of the chip's
//! bus and pins, decoded into register accesses, or judged against the
//! reference model (`docs/capture.md`).

use super::args::{parse_duration, ChipArgs, ToleranceArgs};
use crate::{usage, CliError};
use clap::Args;
use ppmc::time::{Duration, Instant};
use ppmc_capture::judge::{judge_reopening, JudgeOptions, Judgement, Verdict};
use ppmc_logic::decode::BusDecoder;
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::{LogicInfo, LogicSource};
use std::path::PathBuf;

/// The capture and how to read it.
#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// The capture: a sigrok session (.sr, from sigrok-cli or PulseView), a
    /// VCD, or a Saleae Logic 2 export (its CSV, or its binary export's
    /// digital_N.bin files or their folder).
    capture: PathBuf,
    /// Which channel carries which signal: SIGNAL=CHANNEL pairs, the
    /// channel by its name in the capture or its number from 0, e.g.
    /// `CS=0,RD=1,WR=2,A0=3,D0-7=4-11,POUT=12`; `@FILE` reads them from a
    /// file, one or more a line, `#` for comments. Signals: CS, RD, WR,
    /// A0, D0..D7, POUT, DIR, INT, BUSY, HOLD, AUX, AUXO0..AUXO3, and the
    /// inputs the board drives (L1..L4, ALM, CNP, AUXI0..AUXI3), which
    /// the model is given; a channel named `reset` starts the model where
    /// it falls. `~` before a channel reads it inverted (`POUT=~12`,
    /// `DIR=~dir`: an output stage that inverts). Each signal once, each
    /// channel once. Default: the capture's channel names, where they are
    /// the chip's (`CS*`, `nRD`, `D3`, `POUT`); an analyzer's own names
    /// (sigrok's `D0`..`D15`) are never taken for the data lines.
    #[arg(long, value_name = "PAIRS|@FILE")]
    map: Option<String>,
    /// Bus strobes shorter than this are glitches, dropped.
    #[arg(long, value_name = "DURATION", default_value = "20ns", value_parser = parse_duration)]
    glitch: Duration,
}

impl CaptureArgs {
    /// The capture opened, and its channel map.
    fn open(&self) -> Result<(Box<dyn LogicSource>, ChannelMap), CliError> {
        let source = ppmc_logic::open::open(&self.capture)
            .map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?;
        let map = match &self.map {
            None => ChannelMap::from_names(source.info()),
            Some(text) => {
                let text = match text.strip_prefix('@') {
                    Some(file) => ppmc_files::read_text(std::path::Path::new(file), 1 << 20)?,
                    None => text.clone(),
                };
                ChannelMap::parse(&text, source.info())
            }
        }
        .map_err(|e| usage(format!("--map: {e}")))?;
        Ok((source, map))
    }
}

fn describe(info: &LogicInfo, path: &std::path::Path) {
    outln!(
        "capture: {} ({}, {} channels, {} a sample)",
        path.display(),
        info.format,
        info.channels.len(),
        Duration::from_nanos(info.resolution_ps / 1000)
    );
}

/// Print the register accesses of a capture in the bus console's language.
#[derive(Debug, Args)]
pub struct DecodeArgs {
    #[command(flatten)]
    capture: CaptureArgs,
}

pub fn decode(args: DecodeArgs) -> Result<(), CliError> {
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

/// Judge a board from a capture of its bus and pins: the captured writes
/// replayed into the reference model, the chip's answers, pulses and
/// outputs compared (docs/capture.md). Exit status: 0 passed; 1 the board
/// diverged; 3 the board passed but the host firmware broke a rule of
/// chapter 3; 4 the capture cannot be judged (a channel missing, a sample
/// rate too low for the bus, nothing on the bus); 2 a file that does not
/// read, or bad usage.
#[derive(Debug, Args)]
pub struct JudgeArgs {
    #[command(flatten)]
    capture: CaptureArgs,
    #[command(flatten)]
    chip: ChipArgs,
    #[command(flatten)]
    tolerance: ToleranceArgs,
    /// Write a JUnit XML report (a test case for the board, a divergence a
    /// failure of type device; one for the host firmware, its findings a
    /// failure of type host; a capture that cannot be judged an error of
    /// type capture); `-` for standard output (the verdict lines then go
    /// to standard error).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Write a JSON run record (docs/run-record.schema.json, as `ppmc run`
    /// writes it; the capture stands as the board, `run.source` says what
    /// it is, each result names whom it blames); `-` for standard output.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Keep the run record in a results store (SQLite; made when not
    /// there), beside the runs of boards behind a bridge
    /// (docs/results-store.md).
    #[arg(long, value_name = "FILE")]
    store: Option<PathBuf>,
    /// The board's serial number, for the reports and the store.
    #[arg(long, value_name = "SERIAL")]
    board_serial: Option<String>,
    /// The board's revision label, for the reports and the store.
    #[arg(long, value_name = "REV")]
    board_rev: Option<String>,
    /// Also write the capture as a trace in our format, `DIR/<scenario>.snap`
    /// (never replacing a file there), for `ppmc compare GOLDEN --traces
    /// DIR`: the writes and data reads, the moves they started, the pulses
    /// and the outputs the capture has (docs/capture.md).
    #[arg(long, value_name = "DIR")]
    trace: Option<PathBuf>,
    /// The scenario the capture records: the trace's name (default: the
    /// capture file's name without its extension).
    #[arg(long, value_name = "NAME", requires = "trace")]
    scenario: Option<String>,
    /// Judge what the capture holds though it is not whole: it ends
    /// mid-line, during a register access or while the board is still
    /// moving, or it has no channel for POUT while the chip pulses. The
    /// verdict then says what was not judged. Without it such a capture
    /// is the capture's problem (exit 4), never a pass.
    #[arg(long)]
    partial: bool,
}

pub fn run(args: JudgeArgs) -> Result<(), CliError> {
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
    super::reports::prepare_reports(
        args.junit.as_deref(),
        args.json.as_deref(),
        None,
        args.store.as_deref(),
    )?;
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
    let mut store = super::reports::open_store(args.store.as_deref())?;
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
    if args.junit.is_some() || args.json.is_some() || store.is_some() {
        let mut record = j.record(&args.capture.capture, &info, &opts, started.elapsed());
        record.run.boards[0].board_rev = args.board_rev.clone();
        record.run.boards[0].board_serial = args.board_serial.clone();
        let outputs = super::reports::Outputs::of(&args.junit, &args.json, &None);
        problems.extend(super::reports::write(&record, outputs, store.as_mut()));
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
        Some(m) if matches!(j.verdict, Verdict::Passed) => {
            outln!("{m}");
            "MARGINAL"
        }
        _ => "PASS",
    };
    let word = |w: &str| super::out::verdict_word(w, 0);
    match &j.verdict {
        Verdict::Failed(d) => {
            outln!("{} the board: {d}", word("FAIL"));
            Err(CliError::Verdict)
        }
        Verdict::Capture(why) => {
            outln!("{} the capture: {why}", word("ERROR"));
            Err(CliError::Code(4))
        }
        Verdict::Passed if !j.host.is_empty() => {
            outln!(
                "{} the board; the host firmware broke chapter 3's rules {} times",
                word(passed),
                j.host.len()
            );
            Err(CliError::Code(3))
        }
        Verdict::Passed => {
            outln!("{} the board", word(passed));
            Ok(())
        }
    }
}
