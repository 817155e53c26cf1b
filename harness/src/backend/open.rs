//! Opening a [`TargetSpec`]: the emulator with the straps given, or a
//! bridge over the link its address names, health checked (HELLO, a chip
//! reset, status 0x00) and its reported straps reconciled with those
//! given. Why it failed says whose it is: the user's options
//! ([`OpenError::Invalid`]) or the board, bridge or link
//! ([`OpenError::Infrastructure`]), never the device's verdict.

use super::bridged::{BridgeError, BridgeOptions, BridgeTarget};
use super::emu::EmuTarget;
use super::link::{Link, LinkDriver};
use super::spec::{Address, SpecError, StrapOptions, TargetSpec};
use super::target::Target;
use crate::emu::ModelConfig;
use crate::protocol::Straps;
use crate::stop::StopRequest;
use std::fmt;
use std::time::Duration as WallDuration;

/// How to open a target: what holds for every board of a run.
#[derive(Debug, Clone)]
pub struct OpenOptions {
    /// Strap options for every board, under each spec's own.
    pub straps: StrapOptions,
    /// The emulator's model (its acceleration curve).
    pub model: ModelConfig,
    /// On a board: the longest wait for a reply beyond the batch's own
    /// waits (the host waits less on a link it has measured to be fast);
    /// at least 1 ms.
    pub link_timeout: WallDuration,
    /// On a board: silent attempts in a row before a request is given up
    /// as a link error.
    pub link_retries: u32,
    /// Asked for, opening and every wait on the link end early.
    pub stop: StopRequest,
    /// A place ppmc acquires may be taken from a dead ppmc's lock
    /// (`--steal-stale`, `backend::link::lease`).
    pub steal_stale: bool,
    /// How a board that hangs is brought back: its power switch, and the
    /// cycles it may have ([`super::power`]).
    pub power: super::power::PowerOptions,
}

impl Default for OpenOptions {
    fn default() -> Self {
        let serial = BridgeOptions::default();
        OpenOptions {
            straps: StrapOptions::default(),
            model: ModelConfig::default(),
            link_timeout: serial.reply_timeout,
            link_retries: serial.retries,
            stop: StopRequest::default(),
            steal_stale: false,
            power: super::power::PowerOptions::default(),
        }
    }
}

impl OpenOptions {
    /// The straps given for `spec` (its own, then these options'), the
    /// emulator's defaults for the rest.
    pub fn straps_of(&self, spec: &TargetSpec) -> Result<Straps, SpecError> {
        spec.straps.over(self.straps).straps()
    }
}

/// Why a target could not be opened.
#[derive(Debug)]
pub enum OpenError {
    /// The spec or the options are wrong: the user's to fix.
    Invalid(String),
    /// The board, bridge or link is not there or not healthy: not the
    /// device's fault, and not the user's typing either.
    Infrastructure(String),
}

impl fmt::Display for OpenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OpenError::Invalid(m) => f.write_str(m),
            OpenError::Infrastructure(m) => write!(f, "infrastructure error: {m}"),
        }
    }
}

impl std::error::Error for OpenError {}

impl From<SpecError> for OpenError {
    fn from(e: SpecError) -> OpenError {
        OpenError::Invalid(e.0)
    }
}

/// A link that fails is the infrastructure's, never the board's.
fn infra(e: BridgeError) -> OpenError {
    OpenError::Infrastructure(e.to_string())
}

/// What of `spec` and `opts` can be checked without touching a port: a
/// bad option is the user's, found before any board is opened.
pub fn check(spec: &TargetSpec, opts: &OpenOptions) -> Result<Address, OpenError> {
    opts.straps_of(spec)?;
    let address = spec.resolve()?;
    if address != Address::Emu && opts.link_timeout < WallDuration::from_millis(1) {
        return Err(OpenError::Invalid(format!(
            "--link-timeout {}: give at least 1ms",
            crate::time::Duration::from_nanos(opts.link_timeout.as_nanos() as u64)
        )));
    }
    Ok(address)
}

/// Opens `spec`: the emulator, or a board behind its bridge, health
/// checked and its straps reconciled with those given.
pub fn open(spec: &TargetSpec, opts: &OpenOptions) -> Result<Box<dyn Target>, OpenError> {
    let address = check(spec, opts)?;
    match address {
        Address::Emu => {
            let straps = opts.straps_of(spec)?;
            let mut model = opts.model.clone();
            crate::faults::apply_all(&spec.chip_faults, &mut model)
                .map_err(|e| OpenError::Invalid(e.to_string()))?;
            let t = EmuTarget::new(straps, model)
                .map_err(|e| OpenError::Invalid(e.to_string()))?
                .with_chip_faults(&spec.chip_faults)
                .with_dropped_batch(spec.drop_batch);
            Ok(Box::new(t))
        }
        Address::Bridge { driver, address } => {
            let how = crate::backend::link::LinkOpen {
                stop: opts.stop.clone(),
                steal_stale: opts.steal_stale,
            };
            let link = driver
                .open(&address, &how)
                .map_err(|e| OpenError::Infrastructure(e.to_string()))?;
            open_bridge(link, driver, spec, opts)
        }
    }
}

/// A bridge behind `link`: opened, health checked, and its straps
/// reconciled with those given.
fn open_bridge(
    link: Box<dyn Link>,
    driver: &dyn LinkDriver,
    spec: &TargetSpec,
    opts: &OpenOptions,
) -> Result<Box<dyn Target>, OpenError> {
    let serial = BridgeOptions {
        reply_timeout: opts.link_timeout,
        retries: opts.link_retries,
        pad: spec.pad.unwrap_or(driver.default_pad()),
        stop: opts.stop.clone(),
        ..BridgeOptions::default()
    };
    let t = BridgeTarget::open(link, serial).map_err(infra)?;
    // The bridge knows how its chip is strapped; the options may only
    // confirm it. A board at 12 MHz judged as one at 16 would fail for the
    // wrong reason.
    let reported = t.straps();
    let differ = spec.straps.over(opts.straps).disagreements(&reported)?;
    if !differ.is_empty() {
        return Err(OpenError::Infrastructure(format!(
            "{}: the bridge reports its chip strapped {reported}, which the command line contradicts ({}); fix the options or the board, or leave the strap options out to use the bridge's",
            spec.address,
            differ.join("; ")
        )));
    }
    Ok(Box::new(t))
}
