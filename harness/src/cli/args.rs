//! The argument groups several commands share: the target and its straps,
//! the scenario selection, the comparison tolerances.

use super::CliError;
use crate::backend::{
    EmuTarget, LabgridLink, Link, Rfc2217Link, SerialLink, SerialOptions, SerialTarget, Target,
    TcpLink,
};
use crate::compare::Tolerances;
use crate::emu::{AccelCurve, ModelConfig};
use crate::protocol::Straps;
use crate::runner::{parse_shard, validate_suite, Selection};
use crate::scenario::Scenario;
use crate::stop::Stop;
use crate::time::Duration;
use clap::{Args, ValueEnum};

/// Which chip to drive, and how its board is strapped.
#[derive(Debug, Args)]
pub struct TargetArgs {
    /// `emu` (the reference emulator), `serial:<path>[,baud=N]` (a board,
    /// or `ppmc bridge-sim`, behind the serial bus bridge),
    /// `tcp://<host>:<port>` (a bridge's serial port served on the network
    /// in raw mode, as ser2net or socat serve it),
    /// `rfc2217://<host>:<port>[,baud=N]` (served over telnet with RFC 2217,
    /// as ser2net's telnet(rfc2217) mode and labgrid's exporter serve it) or
    /// `labgrid:<place>` (the serial port of a labgrid place you have
    /// acquired). Any of them may end in options of that board alone:
    /// `,name=LABEL`, `,rev=LABEL`, `,pad=BYTES` (reply padding, default 64
    /// on a network target, 0 on a serial port) and the straps `,clock-mhz=`, `,csel=`,
    /// `,vsel=`, `,ext-clock-khz=` (they override the flags below).
    /// `ppmc run` takes several, one per board, and spreads the suite over
    /// them.
    #[arg(long = "target", value_name = "TARGET", default_value = "emu")]
    targets: Vec<String>,
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
    /// Shape of the acceleration ramp (the datasheet's chapter 1 is not available).
    #[arg(long, value_enum, default_value_t = Curve::LinearSpeed)]
    accel_curve: Curve,
    /// Asked for (a signal), opening a target and every wait on its link
    /// end early.
    #[arg(skip)]
    pub(super) stop: Stop,
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

/// `value` Hz (the flag's `shown` value) as a whole number of hertz.
fn hz(value: f64, flag: &str, shown: f64) -> Result<u32, String> {
    let v = value.round();
    if v.is_finite() && v >= 1.0 && v <= f64::from(u32::MAX) {
        Ok(v as u32)
    } else {
        Err(format!("{flag} {shown} is not a usable frequency"))
    }
}

pub fn parse_duration(s: &str) -> Result<Duration, String> {
    s.parse::<Duration>().map_err(|e| e.to_string())
}

/// The strap options given, on the command line or in a target's spec.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct StrapFlags {
    clock_mhz: Option<f64>,
    csel: Option<Level>,
    vsel: Option<Level>,
    ext_clock_khz: Option<f64>,
}

impl StrapFlags {
    /// These flags, with `under`'s where these give none.
    fn over(self, under: StrapFlags) -> StrapFlags {
        StrapFlags {
            clock_mhz: self.clock_mhz.or(under.clock_mhz),
            csel: self.csel.or(under.csel),
            vsel: self.vsel.or(under.vsel),
            ext_clock_khz: self.ext_clock_khz.or(under.ext_clock_khz),
        }
    }

    /// The straps: those given, the emulator's defaults for the rest.
    fn straps(&self) -> Result<Straps, String> {
        let d = Straps::default();
        let straps = Straps {
            sysclk_hz: match self.clock_mhz {
                Some(mhz) => hz(mhz * 1e6, "--clock-mhz", mhz)?,
                None => d.sysclk_hz,
            },
            csel_high: self.csel.map_or(d.csel_high, |l| l == Level::High),
            vsel_high: self.vsel.map_or(d.vsel_high, |l| l == Level::High),
            ext_clock_hz: self
                .ext_clock_khz
                .map(|k| hz(k * 1e3, "--ext-clock-khz", k))
                .transpose()?,
        };
        straps.validate().map_err(|e| match e {
            crate::protocol::StrapsError::SysClk(_) => format!(
                "--clock-mhz {}: the system clock must be 1 to 40 MHz",
                self.clock_mhz.unwrap_or(16.0)
            ),
            crate::protocol::StrapsError::ExtClock { max, .. } => format!(
                "--ext-clock-khz {}: the external clock must be 1 kHz to SysClk/16 ({} kHz here)",
                self.ext_clock_khz.unwrap_or(0.0),
                f64::from(max) / 1e3
            ),
        })?;
        Ok(straps)
    }

    /// The straps given that disagree with `reported` (what a bridge says
    /// its chip is strapped to), each as `--flag: bridge X, given Y`.
    fn disagreements(&self, reported: &Straps) -> Result<Vec<String>, String> {
        let given = self.straps()?;
        let mhz = |hz: u32| (f64::from(hz) / 1e6).to_string();
        let level = |high| if high { "high" } else { "low" }.to_string();
        let khz =
            |h: Option<u32>| h.map_or("none".to_string(), |h| (f64::from(h) / 1e3).to_string());
        // Each strap given: its flag, the bridge's value and the given
        // one, as the user writes them.
        let straps = [
            (
                self.clock_mhz.is_some(),
                "--clock-mhz",
                mhz(reported.sysclk_hz),
                mhz(given.sysclk_hz),
            ),
            (
                self.csel.is_some(),
                "--csel",
                level(reported.csel_high),
                level(given.csel_high),
            ),
            (
                self.vsel.is_some(),
                "--vsel",
                level(reported.vsel_high),
                level(given.vsel_high),
            ),
            (
                self.ext_clock_khz.is_some(),
                "--ext-clock-khz",
                khz(reported.ext_clock_hz),
                khz(given.ext_clock_hz),
            ),
        ];
        Ok(straps
            .into_iter()
            .filter(|(set, _, bridge, cli)| *set && bridge != cli)
            .map(|(_, flag, bridge, cli)| {
                format!("{flag}: the bridge reports {bridge}, given {cli}")
            })
            .collect())
    }
}

/// One `--target`: where its chip is, and the options of that board alone.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetSpec {
    /// The target as its backend takes it, board options removed:
    /// `serial:/dev/ttyACM0,baud=115200`.
    pub address: String,
    /// What the reports call the board (`name=`); default: the address.
    pub name: Option<String>,
    /// The board revision label (`rev=`); default: `--board-rev`.
    pub rev: Option<String>,
    /// Reply padding to ask the bridge for (`pad=`); default: 64 on a
    /// network target, none on a serial port.
    pub pad: Option<u16>,
    straps: StrapFlags,
}

impl TargetSpec {
    /// Splits `spec` into its address and the board's own options
    /// (`name=`, `rev=`, `pad=`, `clock-mhz=`, `csel=`, `vsel=`,
    /// `ext-clock-khz=`);
    /// other `key=value` parts (`baud=`) stay with the address.
    pub fn parse(spec: &str) -> Result<TargetSpec, String> {
        let mut parts = spec.split(',');
        let mut address = parts.next().unwrap_or_default().to_string();
        let mut t = TargetSpec {
            address: String::new(),
            name: None,
            rev: None,
            pad: None,
            straps: StrapFlags::default(),
        };
        let bad = |what: &str| format!("--target `{spec}`: {what}");
        let number = |k: &str, v: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(&format!("{k}={v} is not a number")))
        };
        let level = |k: &str, v: &str| match v {
            "high" => Ok(Level::High),
            "low" => Ok(Level::Low),
            _ => Err(bad(&format!("{k}={v}: write high or low"))),
        };
        let text = |k: &str, v: &str| {
            if v.is_empty() {
                Err(bad(&format!("{k}= needs a value")))
            } else {
                Ok(v.to_string())
            }
        };
        for part in parts {
            let (k, v) = part.split_once('=').unwrap_or((part, ""));
            match k {
                "name" => t.name = Some(text(k, v)?),
                "rev" => t.rev = Some(text(k, v)?),
                "pad" => {
                    t.pad = Some(
                        v.parse::<u16>()
                            .ok()
                            .filter(|p| *p <= ppmc_core::bridge::wire::MAX_PAD)
                            .ok_or_else(|| bad(&format!("pad={v}: give 0 to 512 bytes")))?,
                    )
                }
                "clock-mhz" => t.straps.clock_mhz = Some(number(k, v)?),
                "ext-clock-khz" => t.straps.ext_clock_khz = Some(number(k, v)?),
                "csel" => t.straps.csel = Some(level(k, v)?),
                "vsel" => t.straps.vsel = Some(level(k, v)?),
                _ => {
                    address.push(',');
                    address.push_str(part);
                }
            }
        }
        t.address = address;
        Ok(t)
    }

    /// What the reports call this board.
    pub fn label(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.address)
    }

    /// The address read as its backend takes it; a usage message naming
    /// the form to write when it does not read.
    fn parsed(&self) -> Result<Address, String> {
        let a = self.address.as_str();
        let bad = |form: &str| format!("bad target `{a}`: write {form}");
        if a == "emu" {
            Ok(Address::Emu)
        } else if a.starts_with("serial:") {
            let (path, baud) =
                crate::backend::parse_spec(a).ok_or_else(|| bad("serial:<path>[,baud=N]"))?;
            Ok(Address::Serial { path, baud })
        } else if a.starts_with("tcp://") {
            crate::backend::parse_tcp(a)
                .filter(|addr| host_and_port(addr))
                .map(Address::Tcp)
                .ok_or_else(|| bad("tcp://<host>:<port> (an IPv6 address in brackets: [::1])"))
        } else if a.starts_with("rfc2217://") {
            let (addr, baud) = crate::backend::parse_rfc2217(a)
                .filter(|(addr, _)| host_and_port(addr))
                .ok_or_else(|| {
                    bad("rfc2217://<host>:<port>[,baud=N] (an IPv6 address in brackets: [::1])")
                })?;
            Ok(Address::Rfc2217 { addr, baud })
        } else if a.starts_with("labgrid:") {
            crate::backend::parse_labgrid(a)
                .map(Address::Labgrid)
                .ok_or_else(|| bad("labgrid:<place>"))
        } else {
            Err(format!(
                "unknown target `{a}`: use `emu`, `serial:<path>[,baud=N]`, `tcp://<host>:<port>`, `rfc2217://<host>:<port>[,baud=N]` or `labgrid:<place>`"
            ))
        }
    }
}

/// Whether `addr` reads as `host:port` that a connection can be tried to:
/// a port from 1 to 65535 after a host name, an IPv4 address or an IPv6
/// address in brackets (`[::1]:4321`). Anything else (`[::1`, `::1:4321`,
/// a space in the name) is the user's typing, refused before any
/// connection, never a network failure.
fn host_and_port(addr: &str) -> bool {
    let Some((host, port)) = addr.rsplit_once(':') else {
        return false;
    };
    let port_ok = port.parse::<u16>().is_ok_and(|p| p != 0);
    let host_ok = match host.strip_prefix('[') {
        Some(v6) => v6
            .strip_suffix(']')
            .is_some_and(|v6| v6.parse::<std::net::Ipv6Addr>().is_ok()),
        None => {
            !host.is_empty()
                && host
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_'))
        }
    };
    port_ok && host_ok
}

/// Where a target's chip is, as its backend takes it.
enum Address {
    Emu,
    Serial { path: String, baud: u32 },
    Tcp(String),
    Rfc2217 { addr: String, baud: u32 },
    Labgrid(crate::backend::Place),
}

impl TargetArgs {
    /// Every `--target`, parsed, with unique labels (a second `emu`
    /// becomes `emu#2`).
    pub fn specs(&self) -> Result<Vec<TargetSpec>, String> {
        let mut specs = Vec::with_capacity(self.targets.len());
        // Where a bridge is, whatever the options after it.
        let place = |s: &TargetSpec| s.address.split(',').next().unwrap_or_default().to_string();
        for t in &self.targets {
            let mut spec = TargetSpec::parse(t)?;
            if spec.address != "emu" && specs.iter().any(|s| place(s) == place(&spec)) {
                return Err(format!(
                    "--target {} given twice: a bridge serves one host at a time, and two would drive one chip at once",
                    place(&spec)
                ));
            }
            let mut n = 1;
            let base = spec.label().to_string();
            while specs.iter().any(|s: &TargetSpec| s.label() == spec.label()) {
                n += 1;
                spec.name = Some(format!("{base}#{n}"));
            }
            specs.push(spec);
        }
        Ok(specs)
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

    fn flags(&self) -> StrapFlags {
        StrapFlags {
            clock_mhz: self.clock_mhz,
            csel: self.csel,
            vsel: self.vsel,
            ext_clock_khz: self.ext_clock_khz,
        }
    }

    /// The straps of the single target: those given (on the command line
    /// or in its spec), the emulator's defaults for the rest.
    pub fn straps(&self) -> Result<Straps, String> {
        self.straps_of(&self.single()?)
    }

    /// The straps given for `spec` (its own, then the flags'), the
    /// emulator's defaults for the rest.
    pub fn straps_of(&self, spec: &TargetSpec) -> Result<Straps, String> {
        spec.straps.over(self.flags()).straps()
    }

    /// The single target's address (`emu`, `serial:...`); the first one's
    /// when several were given.
    pub fn name(&self) -> String {
        self.specs()
            .ok()
            .and_then(|s| s.into_iter().next())
            .map_or_else(|| self.targets.join(" "), |s| s.address)
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

    /// Opens the single target. A board target is health checked on the
    /// way (hello, chip reset, status 0x00).
    pub fn open(&self) -> Result<Box<dyn Target>, OpenError> {
        let spec = self.single().map_err(OpenError::Usage)?;
        self.check(&spec)?;
        self.open_spec(&spec)
    }

    /// The options of `spec` that can be checked without touching a port:
    /// a bad one is the user's, before any board is opened.
    pub fn check(&self, spec: &TargetSpec) -> Result<(), OpenError> {
        self.straps_of(spec).map_err(OpenError::Usage)?;
        if let Address::Emu = spec.parsed().map_err(OpenError::Usage)? {
            return Ok(());
        }
        if self.link_timeout.as_nanos() < 1_000_000 {
            return Err(OpenError::Usage(format!(
                "--link-timeout {}: give at least 1ms",
                self.link_timeout
            )));
        }
        Ok(())
    }

    /// Opens `spec`, already [`checked`](Self::check).
    pub fn open_spec(&self, spec: &TargetSpec) -> Result<Box<dyn Target>, OpenError> {
        // A serial server on the way (ser2net, labgrid's exporter) holds a
        // partly filled 64-byte buffer for a millisecond or more; a reply
        // padded to fill it goes at once (docs/bridge-protocol.md, LINK).
        // On a serial port the padding would only cost time.
        const NETWORK_PAD: u16 = 64;
        match spec.parsed().map_err(OpenError::Usage)? {
            Address::Emu => {
                let straps = self.straps_of(spec).map_err(OpenError::Usage)?;
                let t = EmuTarget::new(straps, self.model())
                    .map_err(|e| OpenError::Usage(e.to_string()))?;
                Ok(Box::new(t))
            }
            Address::Serial { path, baud } => {
                let link = SerialLink::open(&path, baud).map_err(infra)?;
                self.open_bridge(link, spec, 0)
            }
            Address::Tcp(addr) => {
                let link = TcpLink::open_until(&addr, self.stop.clone()).map_err(infra)?;
                self.open_bridge(link, spec, NETWORK_PAD)
            }
            Address::Rfc2217 { addr, baud } => {
                let link =
                    Rfc2217Link::open_until(&addr, baud, self.stop.clone()).map_err(infra)?;
                self.open_bridge(link, spec, NETWORK_PAD)
            }
            Address::Labgrid(place) => {
                let link = LabgridLink::open_until(place, self.stop.clone())
                    .map_err(OpenError::Infrastructure)?;
                self.open_bridge(link, spec, NETWORK_PAD)
            }
        }
    }

    /// A bridge behind `link`: opened, health checked, and its straps
    /// reconciled with those given; `pad` is the reply padding unless the
    /// spec gives its own.
    fn open_bridge<L: Link + 'static>(
        &self,
        link: L,
        spec: &TargetSpec,
        pad: u16,
    ) -> Result<Box<dyn Target>, OpenError> {
        let opts = SerialOptions {
            reply_timeout: std::time::Duration::from_nanos(self.link_timeout.as_nanos()),
            retries: self.link_retries,
            pad: spec.pad.unwrap_or(pad),
            stop: self.stop.clone(),
            ..SerialOptions::default()
        };
        let t = SerialTarget::open(link, opts).map_err(infra)?;
        // The bridge knows how its chip is strapped; the command line may
        // only confirm it. A board at 12 MHz judged as one at 16 would fail
        // for the wrong reason.
        let reported = t.straps();
        let differ = spec
            .straps
            .over(self.flags())
            .disagreements(&reported)
            .map_err(OpenError::Usage)?;
        if !differ.is_empty() {
            return Err(OpenError::Infrastructure(format!(
                "{}: the bridge reports its chip strapped {reported}, which the command line contradicts ({}); fix the options or the board, or leave the strap options out to use the bridge's",
                spec.address,
                differ.join("; ")
            )));
        }
        Ok(Box::new(t))
    }
}

/// A link that fails is the infrastructure's, never the board's.
fn infra(e: crate::backend::SerialError) -> OpenError {
    OpenError::Infrastructure(e.to_string())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_addresses_are_host_and_port_or_the_users_mistake() {
        for good in [
            "bench1.lab:4321",
            "127.0.0.1:2001",
            "[::1]:4321",
            "[fe80::1]:1",
            "rig_1:65535",
        ] {
            assert!(host_and_port(good), "{good}");
        }
        for bad in [
            "[::1",
            "[::1]",
            "[::1:4321",
            "::1:4321",
            "[nothost]:4321",
            "host:0",
            "host:65536",
            ":4321",
            "host name:4321",
            "host",
        ] {
            assert!(!host_and_port(bad), "{bad}");
        }
        let spec = |t: &str| TargetSpec::parse(t).expect("splits");
        for t in ["tcp://[::1", "tcp://[::1:4321", "rfc2217://[::1,baud=9600"] {
            let e = spec(t).parsed().err().expect("refused");
            assert!(e.contains("an IPv6 address in brackets"), "{t}: {e}");
        }
        assert!(matches!(
            spec("tcp://[::1]:4321").parsed(),
            Ok(Address::Tcp(a)) if a == "[::1]:4321"
        ));
        assert!(matches!(
            spec("rfc2217://[::1]:4321,baud=9600").parsed(),
            Ok(Address::Rfc2217 { baud: 9600, .. })
        ));
    }
}
