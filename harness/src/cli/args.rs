//! The argument groups several commands share: the target and its straps,
//! the scenario selection, the comparison tolerances.

use super::CliError;
use crate::backend::{EmuTarget, SerialLink, SerialOptions, SerialTarget, Target};
use crate::compare::Tolerances;
use crate::emu::{AccelCurve, ModelConfig};
use crate::protocol::Straps;
use crate::runner::{parse_shard, validate_suite, Selection};
use crate::scenario::Scenario;
use crate::time::Duration;
use clap::{Args, ValueEnum};

/// Which chip to drive, and how its board is strapped.
#[derive(Debug, Args)]
pub struct TargetArgs {
    /// `emu` (the reference emulator) or `serial:<path>[,baud=N]` (a board,
    /// or `ppmc bridge-sim`, behind the serial bus bridge).
    #[arg(long, default_value = "emu")]
    target: String,
    /// System clock in MHz (fractions allowed, e.g. 12.288).
    #[arg(long, default_value_t = 16.0)]
    clock_mhz: f64,
    /// CSEL strap: high = internal clock SysClk/32 (500 kHz at 16 MHz), low = SysClk/128.
    #[arg(long, value_enum, default_value_t = Level::High)]
    csel: Level,
    /// VSEL strap: high = Equations 3-1/3-2, low = 3-3/3-4 (+7.5 us per pulse).
    #[arg(long, value_enum, default_value_t = Level::High)]
    vsel: Level,
    /// Frequency on the CLOCK pin in kHz, if the board has one (used when the
    /// initialization selects the external clock).
    #[arg(long)]
    ext_clock_khz: Option<f64>,
    /// Shape of the acceleration ramp (the datasheet's chapter 1 is not available).
    #[arg(long, value_enum, default_value_t = Curve::LinearSpeed)]
    accel_curve: Curve,
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

impl TargetArgs {
    pub fn straps(&self) -> Result<Straps, String> {
        let hz = |mhz: f64, what: &str| -> Result<u32, String> {
            let v = (mhz * 1e6).round();
            if v.is_finite() && v >= 1.0 && v <= f64::from(u32::MAX) {
                Ok(v as u32)
            } else {
                Err(format!("{what} {mhz} is not a usable frequency"))
            }
        };
        let straps = Straps {
            sysclk_hz: hz(self.clock_mhz, "--clock-mhz")?,
            csel_high: self.csel == Level::High,
            vsel_high: self.vsel == Level::High,
            ext_clock_hz: self
                .ext_clock_khz
                .map(|k| hz(k / 1e3, "--ext-clock-khz"))
                .transpose()?,
        };
        straps.validate().map_err(|e| e.to_string())?;
        Ok(straps)
    }

    /// The `--target` text.
    pub fn name(&self) -> &str {
        &self.target
    }

    pub fn model(&self) -> ModelConfig {
        ModelConfig {
            accel_curve: match self.accel_curve {
                Curve::LinearSpeed => AccelCurve::LinearSpeed,
                Curve::LinearRate => AccelCurve::LinearRate,
            },
            ..ModelConfig::default()
        }
    }

    /// Opens the target named by `--target`. A board target is health
    /// checked on the way (hello, chip reset, status 0x00).
    pub fn open(&self) -> Result<Box<dyn Target>, OpenError> {
        if self.target == "emu" {
            let t = EmuTarget::new(self.straps().map_err(OpenError::Usage)?, self.model())
                .map_err(|e| OpenError::Usage(e.to_string()))?;
            return Ok(Box::new(t));
        }
        if self.target.starts_with("serial:") {
            let (path, baud) = crate::backend::parse_spec(&self.target).ok_or_else(|| {
                OpenError::Usage(format!(
                    "bad target `{}`: write serial:<path>[,baud=N]",
                    self.target
                ))
            })?;
            let infra = |e: crate::backend::SerialError| OpenError::Infrastructure(e.to_string());
            let link = SerialLink::open(&path, baud).map_err(infra)?;
            let t = SerialTarget::open(link, SerialOptions::default()).map_err(infra)?;
            return Ok(Box::new(t));
        }
        Err(OpenError::Usage(format!(
            "unknown target `{}`: use `emu` or `serial:<path>[,baud=N]`",
            self.target
        )))
    }
}

/// Why a target could not be opened.
#[derive(Debug)]
pub enum OpenError {
    /// The options are wrong (exit status 2).
    Usage(String),
    /// The board, bridge or link is not there or not healthy: not the
    /// device's fault, and not the user's typing either (exit status 1).
    Infrastructure(String),
}

impl std::fmt::Display for OpenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OpenError::Usage(m) => f.write_str(m),
            OpenError::Infrastructure(m) => write!(f, "infrastructure error: {m}"),
        }
    }
}

impl From<OpenError> for CliError {
    fn from(e: OpenError) -> CliError {
        match e {
            OpenError::Usage(m) => CliError::Usage(m),
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
            shard: self.shard,
        }
    }

    /// The selection, for the run record.
    pub fn describe(&self, opts: &mut crate::report::RunOptions) {
        opts.filter = self.filter.clone();
        opts.tags = self.tags.clone();
        opts.skip_tags = self.skip_tags.clone();
        opts.shard = self.shard.map(|(i, n)| format!("{i}/{n}"));
    }

    /// The suite, validated, narrowed to the selection. A filter or tags
    /// that match nothing are an error (a typo); a shard past the end of a
    /// small selection is simply empty (N CI jobs over fewer scenarios).
    pub fn scenarios(&self, suite: &[Scenario]) -> Result<Vec<Scenario>, String> {
        validate_suite(suite).map_err(|e| e.to_string())?;
        let selection = self.selection();
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
