//! `ppmc decode` and `ppmc judge`: a logic-analyzer capture of the chip's
//! bus and pins, decoded into register accesses, or judged against the
//! reference model (`docs/capture.md`).

use super::args::{parse_duration, ChipArgs, ToleranceArgs};
use crate::cli::{usage, CliError};
use crate::judge::{judge, JudgeOptions, Verdict};
use crate::logic::decode::BusDecoder;
use crate::logic::map::ChannelMap;
use crate::logic::source::{LogicInfo, LogicSource};
use crate::time::{Duration, Instant};
use clap::Args;
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
    /// A0, D0..D7, POUT, DIR, INT, BUSY, and the inputs the board drives
    /// (L1..L4, ALM, CNP, AUXI0..AUXI3), which the model is given. Default: the capture's channel
    /// names, where they are the chip's (`CS*`, `nRD`, `D3`, `POUT`).
    #[arg(long, value_name = "PAIRS|@FILE")]
    map: Option<String>,
    /// Bus strobes shorter than this are glitches, dropped.
    #[arg(long, value_name = "DURATION", default_value = "20ns", value_parser = parse_duration)]
    glitch: Duration,
}

impl CaptureArgs {
    /// The capture opened, and its channel map.
    fn open(&self) -> Result<(Box<dyn LogicSource>, ChannelMap), CliError> {
        let source = crate::logic::open::open(&self.capture)
            .map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?;
        let map = match &self.map {
            None => ChannelMap::from_names(source.info()),
            Some(text) => {
                let text = match text.strip_prefix('@') {
                    Some(file) => crate::files::read_text(std::path::Path::new(file), 1 << 20)?,
                    None => text.replace(',', "\n"),
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
        .require_bus()
        .map_err(|why| usage(format!("{}: {why}", args.capture.capture.display())))?;
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
/// replayed into the reference model, the chip's answers and pulses
/// compared (docs/capture.md). Exit status: 0 passed; 1 the board
/// diverged; 3 the board passed but the host firmware broke a rule of
/// chapter 3; 4 the capture cannot be judged (a channel missing, a sample
/// rate too low for the bus).
#[derive(Debug, Args)]
pub struct JudgeArgs {
    #[command(flatten)]
    capture: CaptureArgs,
    #[command(flatten)]
    chip: ChipArgs,
    #[command(flatten)]
    tolerance: ToleranceArgs,
}

pub fn run(args: JudgeArgs) -> Result<(), CliError> {
    let (mut source, map) = args.capture.open()?;
    let info = source.info().clone();
    describe(&info, &args.capture.capture);
    let opts = JudgeOptions {
        straps: args.chip.straps().map_err(usage)?,
        model: args.chip.model(),
        tolerances: args.tolerance.tolerances().map_err(usage)?,
        glitch_ps: args.capture.glitch.as_nanos() * 1000,
    };
    let j = judge(source.as_mut(), &map, &opts)
        .map_err(|e| CliError::BadInput(format!("ppmc: {e}")))?;
    for n in &j.not_judged {
        outln!("not judged: {n}");
    }
    outln!(
        "{} register accesses, {} POUT pulses compared, {} changes of the other outputs compared",
        j.accesses,
        j.pulses,
        j.changes
    );
    for h in &j.host {
        outln!(
            "host firmware (section {}): at {}: {}",
            h.section,
            Instant::from_nanos(h.at_ps / 1000),
            h.what
        );
    }
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
                word("PASS"),
                j.host.len()
            );
            Err(CliError::Code(3))
        }
        Verdict::Passed => {
            outln!("{} the board", word("PASS"));
            Ok(())
        }
    }
}
