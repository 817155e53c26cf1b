//! The capture a command reads (`ppmc decode`, `ppmc judge`): the file,
//! its channel map, its glitch filter.

use crate::args::parse_duration;
use crate::{usage, CliError};
use clap::Args;
use ppmc::time::Duration;
use ppmc_logic::map::ChannelMap;
use ppmc_logic::source::{LogicInfo, LogicSource};
use std::path::PathBuf;

/// The capture and how to read it.
#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// The capture: a sigrok session (.sr, from sigrok-cli or PulseView), a
    /// VCD, or a Saleae Logic 2 export (its CSV, or its binary export's
    /// digital_N.bin files or their folder).
    pub(crate) capture: PathBuf,
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
    pub(crate) glitch: Duration,
}

impl CaptureArgs {
    /// The capture opened, and its channel map.
    pub(crate) fn open(&self) -> Result<(Box<dyn LogicSource>, ChannelMap), CliError> {
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

pub(crate) fn describe(info: &LogicInfo, path: &std::path::Path) {
    outln!(
        "capture: {} ({}, {} channels, {} a sample)",
        path.display(),
        info.format,
        info.channels.len(),
        Duration::from_nanos(info.resolution_ps / 1000)
    );
}
