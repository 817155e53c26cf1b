//! The argument groups several commands share: the target and its straps,
//! the scenario selection, the comparison tolerances.

use super::CliError;
use clap::{Args, ValueEnum};
use ppmc::backend::{self, OpenError, OpenOptions, StrapOptions, Target, TargetSpec};
use ppmc::compare::Tolerances;
use ppmc::emu::{AccelCurve, ModelConfig};
use ppmc::protocol::Straps;
use ppmc::runner::{parse_shard, validate_suite, Selection};
use ppmc::scenario::Scenario;
use ppmc::stop::StopRequest;
use ppmc::time::Duration;
use std::path::PathBuf;

/// Which chip to drive, and how its board is strapped.
#[derive(Debug, Args)]
pub struct TargetArgs {
    /// Which chip: `emu` or a bridge's address, each with options of that
    /// board alone (the full list: --help).
    #[arg(
        long = "target",
        value_name = "TARGET",
        default_value = "emu",
        long_help = target_help()
    )]
    targets: Vec<String>,
    #[command(flatten)]
    chip: ChipArgs,
    /// On a board: how long to wait at most for a reply (beyond the time
    /// the batch's own waits take), e.g. 1s, 250ms. The host waits less on
    /// a link it has measured to be fast, and backs off up to this.
    #[arg(long, value_name = "DURATION", default_value = "1s", value_parser = parse_duration)]
    link_timeout: Duration,
    /// On a board: attempts in a row that hear nothing before a request is
    /// given up as a link error (ten times as many that hear only garbage:
    /// a noisy line is alive).
    #[arg(long, value_name = "N", default_value_t = 10)]
    link_retries: u32,
    /// A place this run acquires (`labgrid:<place>,acquire`) that a dead
    /// ppmc of this machine left locked (killed outright, so it could not
    /// let go) is taken, where it would be refused with its owner and age.
    /// A lock of a live run, of another machine or of a person is never
    /// taken (docs/board-farm.md).
    #[arg(long)]
    steal_stale: bool,
    /// The board's serial number, for the reports and the results store
    /// (a target's own `,board-serial=` overrides it).
    #[arg(long, value_name = "SERIAL", value_parser = label)]
    pub(super) board_serial: Option<String>,
    /// The board's revision label, for the reports and the results store
    /// (a target's own `,rev=` overrides it).
    #[arg(long, value_name = "REV", value_parser = label)]
    pub(super) board_rev: Option<String>,
    /// Asked for (a signal), opening a target and every wait on its link
    /// end early.
    #[arg(skip)]
    pub(super) stop: StopRequest,
}

/// The chip itself: how its board is strapped, and the emulator's ramp.
/// On a board, the bridge reports the straps and those given must agree.
#[derive(Debug, Args)]
pub struct ChipArgs {
    /// System clock in MHz, 1 to 40 (fractions allowed, e.g. 12.288).
    /// Default: 16 on the emulator; on a board, what its bridge reports
    /// (given, it must agree).
    #[arg(long, value_name = "MHZ")]
    clock_mhz: Option<f64>,
    /// CSEL strap: high = internal clock SysClk/32 (500 kHz at 16 MHz), low =
    /// SysClk/128. Default: high on the emulator; on a board, the bridge's.
    #[arg(long, value_enum)]
    csel: Option<Level>,
    /// VSEL strap: high = Equations 3-1/3-2, low = 3-3/3-4 (+7.5 us per
    /// pulse). Default: high on the emulator; on a board, the bridge's.
    #[arg(long, value_enum)]
    vsel: Option<Level>,
    /// Frequency on the CLOCK pin in kHz, if the board has one (used when the
    /// initialization selects the external clock). Default: none on the
    /// emulator; on a board, the bridge's.
    #[arg(long, value_name = "KHZ")]
    ext_clock_khz: Option<f64>,
    /// Shape of the acceleration ramp (the datasheet's chapter 1 is not available).
    #[arg(long, value_enum, default_value_t = Curve::LinearSpeed)]
    accel_curve: Curve,
}

impl ChipArgs {
    /// The strap options given.
    fn strap_options(&self) -> StrapOptions {
        let level = |l: Option<Level>| l.map(|l| l == Level::High);
        StrapOptions {
            clock_mhz: self.clock_mhz,
            csel_high: level(self.csel),
            vsel_high: level(self.vsel),
            ext_clock_khz: self.ext_clock_khz,
        }
    }

    /// The straps given, the emulator's defaults for the rest.
    pub fn straps(&self) -> Result<Straps, String> {
        self.strap_options().straps().map_err(String::from)
    }

    /// The emulator's model: the default, with the ramp chosen.
    pub fn model(&self) -> ModelConfig {
        ModelConfig {
            accel_curve: match self.accel_curve {
                Curve::LinearSpeed => AccelCurve::LinearSpeed,
                Curve::LinearRate => AccelCurve::LinearRate,
            },
            ..ModelConfig::default()
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Level {
    High,
    Low,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Curve {
    LinearSpeed,
    LinearRate,
}

pub fn parse_duration(s: &str) -> Result<Duration, String> {
    s.parse::<Duration>().map_err(|e| e.to_string())
}

/// A wall-clock length, as [`parse_duration`] reads it or in minutes or
/// hours too (`5m`, `1.5h`): how long a fuzz run or a soak lasts.
pub fn parse_wall_duration(s: &str) -> Result<Duration, String> {
    let t = s.trim();
    let scaled = [("h", 3_600u64), ("m", 60)]
        .into_iter()
        .find_map(|(unit, secs)| Some((t.strip_suffix(unit)?, secs)))
        .filter(|(n, _)| !n.is_empty() && !n.ends_with(['m', 'u', 'n', 'µ']));
    let Some((n, secs)) = scaled else {
        return parse_duration(s)
            .map_err(|e| e.replace("ns, us, ms or s", "ns, us, ms, s, m or h"));
    };
    let x: f64 = n
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite() && *x >= 0.0)
        .ok_or_else(|| format!("duration `{s}`: `{n}` is not a number"))?;
    let ns = x * secs as f64 * 1e9;
    if ns >= u64::MAX as f64 {
        return Err(format!("duration `{s}` is too long"));
    }
    Ok(Duration::from_nanos(ns.round() as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 42: `fuzz --duration 3m` was refused while its help said `5m`.
    #[test]
    fn a_wall_duration_reads_minutes_and_hours() {
        let secs = |s: &str| parse_wall_duration(s).map(|d| d.as_nanos() / 1_000_000_000);
        assert_eq!(secs("3m"), Ok(180));
        assert_eq!(secs("1.5h"), Ok(5_400));
        assert_eq!(secs("90s"), Ok(90));
        assert_eq!(secs("250ms").map(|_| ()), Ok(()));
        let e = parse_wall_duration("3x").expect_err("refused");
        assert!(e.contains("ns, us, ms, s, m or h"), "{e}");
        assert!(parse_wall_duration("m").is_err());
        assert!(parse_wall_duration("-1m").is_err());
    }
}

/// The `--target` help: `emu`, then every link kind of
/// [`backend::DRIVERS`] with its form and what it reaches, then the
/// options of one board.
fn target_help() -> String {
    let mut help = String::from(
        "Which chip to drive: `emu` (the reference emulator), or a board's bus bridge at an address of one of these forms:\n",
    );
    for d in backend::DRIVERS {
        help.push_str(&format!("\n  {}\n      {}", d.form(), d.about()));
        help.push_str(&format!(
            "; reply padding {} bytes unless `,pad=` says",
            d.default_pad()
        ));
        help.push('\n');
    }
    help.push_str(
        "\nAny of them may end in options of that board alone: `,name=LABEL`, `,rev=LABEL`, `,board-serial=SERIAL`, `,pad=BYTES` (reply padding) and the straps `,clock-mhz=`, `,csel=`, `,vsel=`, `,ext-clock-khz=` (they override the flags below). \
`emu,chip-fault=NAME` (once per fault) makes the emulator a board with that fault of the catalogue (`ppmc fault-matrix --list`), and `emu,drop-batch=N` fails its Nth batch once, as a lost link would (to try `--retries`). \
`ppmc run` takes several, one per board, and spreads the suite over them.",
    );
    help
}

impl TargetArgs {
    /// Every `--target`, parsed ([`TargetSpec::parse_all`]).
    pub fn specs(&self) -> Result<Vec<TargetSpec>, String> {
        TargetSpec::parse_all(&self.targets).map_err(String::from)
    }

    /// The one target of a command that drives one board.
    pub fn single(&self) -> Result<TargetSpec, String> {
        let mut specs = self.specs()?;
        if specs.len() != 1 {
            return Err(format!(
                "--target given {} times: only `ppmc run` drives several boards",
                specs.len()
            ));
        }
        Ok(specs.remove(0))
    }

    /// What the flags say for every target.
    pub fn open_options(&self) -> OpenOptions {
        OpenOptions {
            straps: self.chip.strap_options(),
            model: self.model(),
            link_timeout: std::time::Duration::from_nanos(self.link_timeout.as_nanos()),
            link_retries: self.link_retries,
            stop: self.stop.clone(),
            steal_stale: self.steal_stale,
            power: Default::default(),
        }
    }

    /// The straps of the single target: those given (on the command line
    /// or in its spec), the emulator's defaults for the rest.
    pub fn straps(&self) -> Result<Straps, String> {
        let spec = self.single()?;
        self.open_options().straps_of(&spec).map_err(String::from)
    }

    /// The single target's address (`emu`, `serial:...`); the first one's
    /// when several were given.
    pub fn name(&self) -> String {
        self.specs()
            .ok()
            .and_then(|s| s.into_iter().next())
            .map_or_else(|| self.targets.join(" "), |s| s.address)
    }

    /// The emulator's model ([`ChipArgs::model`]).
    pub fn model(&self) -> ModelConfig {
        self.chip.model()
    }

    /// Opens the single target ([`backend::open`]).
    pub fn open(&self) -> Result<Box<dyn Target>, CliError> {
        let spec = self.single().map_err(CliError::Usage)?;
        Ok(backend::open(&spec, &self.open_options())?)
    }
}

impl From<OpenError> for CliError {
    fn from(e: OpenError) -> CliError {
        match e {
            OpenError::Invalid(m) => CliError::Usage(m),
            OpenError::Infrastructure(m) => CliError::Infrastructure(m),
        }
    }
}

#[derive(Debug, Args)]
pub struct SelectArgs {
    /// Only scenarios whose name contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// Only scenarios with this tag (repeat for several; all must match).
    #[arg(long = "tag")]
    tags: Vec<String>,
    /// Leave out scenarios with this tag (repeat for several), e.g.
    /// `--skip-tag long` on a board.
    #[arg(long = "skip-tag", value_name = "TAG")]
    skip_tags: Vec<String>,
    /// Leave out the scenario of this name, the whole name as `ppmc list`
    /// gives it (repeat for several).
    #[arg(long = "skip", value_name = "NAME")]
    skip: Vec<String>,
    /// Run the I-th of N interleaved parts of the suite, e.g. 2/4, to split
    /// it across CI jobs or boards.
    #[arg(long, value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
}

impl SelectArgs {
    pub fn selection(&self) -> Selection {
        Selection {
            filter: self.filter.clone(),
            tags: self.tags.clone(),
            skip_tags: self.skip_tags.clone(),
            skip: self.skip.clone(),
            shard: self.shard,
        }
    }

    /// The selection, for the run record.
    pub fn describe(&self, opts: &mut ppmc_record::RunOptions) {
        opts.filter = self.filter.clone();
        opts.tags = self.tags.clone();
        opts.skip_tags = self.skip_tags.clone();
        opts.skip = self.skip.clone();
        opts.shard = self.shard.map(|(i, n)| format!("{i}/{n}"));
    }

    /// The suite, validated, narrowed to the selection. A filter or tags
    /// that match nothing are an error (a typo); a shard past the end of a
    /// small selection is simply empty (N CI jobs over fewer scenarios).
    pub fn scenarios(&self, suite: &[Scenario]) -> Result<Vec<Scenario>, String> {
        validate_suite(suite).map_err(|e| e.to_string())?;
        let selection = self.selection();
        if let Some(name) = self
            .skip
            .iter()
            .find(|n| !suite.iter().any(|s| s.name == *n))
        {
            return Err(format!(
                "--skip {name}: no scenario of that name (give the whole name, as `ppmc list` shows it)"
            ));
        }
        if selection.matching(suite).is_empty() {
            return Err("no scenario matches the selection (see `ppmc list`)".into());
        }
        Ok(selection.select(suite))
    }
}

/// Comparison tolerances, defaulting to the datasheet's 1 %.
#[derive(Debug, Args)]
pub struct ToleranceArgs {
    /// Relative tolerance on latencies, in percent of the golden value.
    #[arg(long, default_value_t = 1.0)]
    latency_tol: f64,
    /// Relative tolerance on each pulse interval, in percent.
    #[arg(long, default_value_t = 1.0)]
    interval_tol: f64,
    /// Absolute slack on every timing (timer resolution).
    #[arg(long, default_value = "100ns", value_parser = parse_duration)]
    time_floor: Duration,
}

impl ToleranceArgs {
    pub fn tolerances(&self) -> Result<Tolerances, String> {
        let bp = |pct: f64, name: &str| {
            if pct.is_finite() && (0.0..=100.0).contains(&pct) {
                Ok((pct * 100.0).round() as u64)
            } else {
                Err(format!("--{name} {pct}: give a percentage from 0 to 100"))
            }
        };
        Ok(Tolerances {
            latency_bp: bp(self.latency_tol, "latency-tol")?,
            interval_bp: bp(self.interval_tol, "interval-tol")?,
            floor: self.time_floor,
        })
    }
}

/// The reports a command writes of its run record (`ppmc run`, `ppmc
/// compare`, `ppmc judge`): one group, so each flag means one thing.
/// A board's label, as the reports and the store keep it
/// ([`ppmc_record::check_label`]).
pub(crate) fn label(s: &str) -> Result<String, String> {
    ppmc_record::check_label(s).map(|()| s.to_string())
}

#[derive(Debug, Default, Clone, Args)]
pub struct ReportArgs {
    /// Write a JUnit XML report (docs/reports.md: a test case per scenario,
    /// or for a capture one for the board and one for the host firmware;
    /// a device failure a failure, anything else an error of its own
    /// type); `-` for standard output (the verdict lines then go to
    /// standard error).
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Write a JSON run record (docs/run-record.schema.json: the target or
    /// capture, the board, the options, every verdict and measurement with
    /// its limits and uncertainty, whom each result blames); `-` for
    /// standard output.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write the HTML report: one file, offline (docs/reports.md): every
    /// verdict, each measurement against its Table 3-3 band, each move's
    /// speed profile (over the golden one where there is one) with the
    /// first divergence marked, the pins around each failure.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
    /// Keep the run record in a results store, for `ppmc history` and
    /// `ppmc report --store` (docs/results-store.md): an SQLite file (made
    /// when not there), or a lab's PostgreSQL database
    /// (`postgres://user@host/db`; TLS as `sslmode=` asks, the password
    /// from the URL or PGPASSWORD). A run the store does not take is kept
    /// on disk for `ppmc store push`.
    #[arg(
        long,
        value_name = "FILE|URL",
        env = "PPMC_STORE",
        hide_env_values = true
    )]
    pub store: Option<PathBuf>,
}

impl ReportArgs {
    /// Whether any report is asked for.
    pub fn any(&self) -> bool {
        self.junit.is_some() || self.json.is_some() || self.html.is_some() || self.store.is_some()
    }

    /// Tries every output before the work ([`crate::reports::prepare_reports`]).
    pub fn prepare(&self) -> Result<(), CliError> {
        crate::reports::prepare_reports(
            self.junit.as_deref(),
            self.json.as_deref(),
            self.html.as_deref(),
            self.store.as_deref(),
        )
    }

    /// Where the record goes, the store aside.
    pub fn outputs(&self) -> crate::reports::Outputs<'_> {
        crate::reports::Outputs {
            junit: self.junit.as_deref(),
            json: self.json.as_deref(),
            html: self.html.as_deref(),
        }
    }

    /// Opens the store, if asked for ([`crate::store::open_store`]).
    pub fn open_store(&self) -> Result<Option<ppmc_report::store::Store>, CliError> {
        crate::store::open_store(self.store.as_deref())
    }
}
