//! What names a target: a [`TargetSpec`] (`emu`, or a bridge's address in
//! one of the forms of [`LinkKind`], then options of that board alone),
//! read into an [`Address`], and the strap options ([`StrapOptions`]) a
//! user may give for a board.
//!
//! The grammar, one string per board:
//!
//! ```text
//! emu | serial:<path>[,baud=N] | tcp://<host>:<port>
//!     | rfc2217://<host>:<port>[,baud=N] | labgrid:<place>[,port=NAME][,acquire]
//! then any of: ,name=LABEL ,rev=LABEL ,pad=BYTES
//!              ,clock-mhz=MHZ ,csel=high|low ,vsel=high|low ,ext-clock-khz=KHZ
//! ```

use super::link::{driver_for, LinkDriver, DRIVERS};
use crate::protocol::{Straps, StrapsError};
use std::fmt;
use std::str::FromStr;

/// Where a target's chip is, as its backend takes it.
#[derive(Debug, Clone)]
pub enum Address {
    /// The reference emulator, in process.
    Emu,
    /// A bridge over a link: the driver of its kind (the first of
    /// [`DRIVERS`] whose prefix the address starts with) and the address
    /// as written, which the driver has read.
    Bridge {
        driver: &'static dyn LinkDriver,
        address: String,
    },
}

impl PartialEq for Address {
    fn eq(&self, other: &Address) -> bool {
        match (self, other) {
            (Address::Emu, Address::Emu) => true,
            (
                Address::Bridge { driver, address },
                Address::Bridge {
                    driver: d,
                    address: a,
                },
            ) => driver.prefix() == d.prefix() && address == a,
            _ => false,
        }
    }
}

impl Eq for Address {}

impl Address {
    /// The driver of the link a bridge at this address is reached over;
    /// `None` for the emulator.
    pub fn driver(&self) -> Option<&'static dyn LinkDriver> {
        match self {
            Address::Emu => None,
            Address::Bridge { driver, .. } => Some(*driver),
        }
    }
}

/// Every address form, as the usage messages list them: `` `emu`,
/// `serial:<path>[,baud=N]`, ... or `labgrid:<place>[,port=NAME][,acquire]` ``.
pub fn forms() -> String {
    let mut forms = String::from("`emu`");
    for (i, d) in DRIVERS.iter().enumerate() {
        let last = i + 1 == DRIVERS.len();
        forms.push_str(if last { " or " } else { ", " });
        forms.push_str(&format!("`{}`", d.form()));
    }
    forms
}

/// A target spec or strap option that does not read: the user's typing,
/// said in words that name the form to write.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SpecError(pub String);

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SpecError {}

impl From<SpecError> for String {
    fn from(e: SpecError) -> String {
        e.0
    }
}

/// Strap options given by the user: on the command line (for every
/// board) or in a spec (for that board). On the emulator they are the
/// straps (the defaults filling in); on a board the bridge reports them,
/// and those given must agree.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StrapOptions {
    /// System clock in MHz (`clock-mhz=`, `--clock-mhz`).
    pub clock_mhz: Option<f64>,
    /// CSEL strap high (`csel=high`).
    pub csel_high: Option<bool>,
    /// VSEL strap high (`vsel=high`).
    pub vsel_high: Option<bool>,
    /// Frequency on the CLOCK pin in kHz (`ext-clock-khz=`).
    pub ext_clock_khz: Option<f64>,
}

/// `value` Hz (the flag's `shown` value) as a whole number of hertz.
fn hz(value: f64, flag: &str, shown: f64) -> Result<u32, SpecError> {
    let v = value.round();
    if v.is_finite() && v >= 1.0 && v <= f64::from(u32::MAX) {
        Ok(v as u32)
    } else {
        Err(SpecError(format!(
            "{flag} {shown} is not a usable frequency"
        )))
    }
}

impl StrapOptions {
    /// These options, with `under`'s where these give none.
    pub fn over(self, under: StrapOptions) -> StrapOptions {
        StrapOptions {
            clock_mhz: self.clock_mhz.or(under.clock_mhz),
            csel_high: self.csel_high.or(under.csel_high),
            vsel_high: self.vsel_high.or(under.vsel_high),
            ext_clock_khz: self.ext_clock_khz.or(under.ext_clock_khz),
        }
    }

    /// The straps: those given, the emulator's defaults for the rest.
    pub fn straps(&self) -> Result<Straps, SpecError> {
        let d = Straps::default();
        let straps = Straps {
            sysclk_hz: match self.clock_mhz {
                Some(mhz) => hz(mhz * 1e6, "--clock-mhz", mhz)?,
                None => d.sysclk_hz,
            },
            csel_high: self.csel_high.unwrap_or(d.csel_high),
            vsel_high: self.vsel_high.unwrap_or(d.vsel_high),
            ext_clock_hz: self
                .ext_clock_khz
                .map(|k| hz(k * 1e3, "--ext-clock-khz", k))
                .transpose()?,
        };
        straps.validate().map_err(|e| {
            SpecError(match e {
                StrapsError::SysClk(_) => format!(
                    "--clock-mhz {}: the system clock must be 1 to 40 MHz",
                    self.clock_mhz.unwrap_or(16.0)
                ),
                StrapsError::ExtClock { max, .. } => format!(
                    "--ext-clock-khz {}: the external clock must be 1 kHz to SysClk/16 ({} kHz here)",
                    self.ext_clock_khz.unwrap_or(0.0),
                    f64::from(max) / 1e3
                ),
            })
        })?;
        Ok(straps)
    }

    /// The straps given that disagree with `reported` (what a bridge says
    /// its chip is strapped to), each as `--flag: the bridge reports X,
    /// given Y`.
    pub fn disagreements(&self, reported: &Straps) -> Result<Vec<String>, SpecError> {
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
                self.csel_high.is_some(),
                "--csel",
                level(reported.csel_high),
                level(given.csel_high),
            ),
            (
                self.vsel_high.is_some(),
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
            .filter(|(set, _, bridge, given)| *set && bridge != given)
            .map(|(_, flag, bridge, given)| {
                format!("{flag}: the bridge reports {bridge}, given {given}")
            })
            .collect())
    }
}

/// One target: where its chip is, and the options of that board alone.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetSpec {
    /// The target as its backend takes it, board options removed:
    /// `serial:/dev/ttyACM0,baud=115200`.
    pub address: String,
    /// What the reports call the board (`name=`); default: the address.
    pub name: Option<String>,
    /// The board revision label (`rev=`).
    pub rev: Option<String>,
    /// The board's serial number (`board-serial=`).
    pub serial: Option<String>,
    /// Reply padding to ask the bridge for (`pad=`); default: the link
    /// kind's ([`LinkDriver::default_pad`]).
    pub pad: Option<u16>,
    /// The board's own strap options (`clock-mhz=`, `csel=`, ...), over
    /// those given for every board.
    pub straps: StrapOptions,
    /// Board faults of the catalogue the emulator models (`chip-fault=`,
    /// once per fault; `emu` only): a faulty board without a board.
    pub chip_faults: Vec<String>,
    /// The emulator's batch that fails as a lost link would, once
    /// (`drop-batch=`; `emu` only).
    pub drop_batch: Option<u64>,
}

impl FromStr for TargetSpec {
    type Err = SpecError;

    fn from_str(s: &str) -> Result<TargetSpec, SpecError> {
        TargetSpec::parse(s)
    }
}

impl TargetSpec {
    /// Splits `spec` into its address and the board's own options
    /// (`name=`, `rev=`, `pad=`, `clock-mhz=`, `csel=`, `vsel=`,
    /// `ext-clock-khz=`); other `key=value` parts (`baud=`) stay with the
    /// address. The address itself is read by [`TargetSpec::resolve`].
    pub fn parse(spec: &str) -> Result<TargetSpec, SpecError> {
        let mut parts = spec.split(',');
        let mut address = parts.next().unwrap_or_default().to_string();
        let mut t = TargetSpec {
            address: String::new(),
            name: None,
            rev: None,
            serial: None,
            pad: None,
            straps: StrapOptions::default(),
            chip_faults: Vec::new(),
            drop_batch: None,
        };
        let bad = |what: &str| SpecError(format!("--target `{spec}`: {what}"));
        let number = |k: &str, v: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(&format!("{k}={v} is not a number")))
        };
        let level = |k: &str, v: &str| match v {
            "high" => Ok(true),
            "low" => Ok(false),
            _ => Err(bad(&format!("{k}={v}: write high or low"))),
        };
        let text = |k: &str, v: &str| {
            if v.is_empty() {
                return Err(bad(&format!("{k}= needs a value")));
            }
            ppmc_record::check_label(v)
                .map(|()| v.to_string())
                .map_err(|why| bad(&format!("{k}=: {why}")))
        };
        for part in parts {
            let (k, v) = part.split_once('=').unwrap_or((part, ""));
            match k {
                "name" => t.name = Some(text(k, v)?),
                "rev" => t.rev = Some(text(k, v)?),
                "board-serial" => t.serial = Some(text(k, v)?),
                "pad" => {
                    t.pad = Some(
                        v.parse::<u16>()
                            .ok()
                            .filter(|p| *p <= ppmc_core::bridge::wire::MAX_PAD)
                            .ok_or_else(|| bad(&format!("pad={v}: give 0 to 512 bytes")))?,
                    )
                }
                "chip-fault" => {
                    let name = text(k, v)?;
                    if ppmc_core::emu::faults::find(&name).is_none() {
                        return Err(bad(&format!(
                            "chip-fault={name}: not in the board-fault catalogue (ppmc fault-matrix --list)"
                        )));
                    }
                    t.chip_faults.push(name);
                }
                "drop-batch" => {
                    t.drop_batch =
                        Some(v.parse::<u64>().ok().filter(|n| *n >= 1).ok_or_else(|| {
                            bad(&format!("drop-batch={v}: give the batch's number, from 1"))
                        })?)
                }
                "clock-mhz" => t.straps.clock_mhz = Some(number(k, v)?),
                "ext-clock-khz" => t.straps.ext_clock_khz = Some(number(k, v)?),
                "csel" => t.straps.csel_high = Some(level(k, v)?),
                "vsel" => t.straps.vsel_high = Some(level(k, v)?),
                _ => {
                    address.push(',');
                    address.push_str(part);
                }
            }
        }
        t.address = address;
        Ok(t)
    }

    /// Every spec of a run on several boards, parsed, with unique labels
    /// (a second `emu` becomes `emu#2`). One bridge named twice is refused:
    /// a bridge serves one host at a time, and two would drive one chip.
    pub fn parse_all<S: AsRef<str>>(specs: &[S]) -> Result<Vec<TargetSpec>, SpecError> {
        let mut out: Vec<TargetSpec> = Vec::with_capacity(specs.len());
        // Where a bridge is, whatever the options after it.
        let place = |s: &TargetSpec| s.address.split(',').next().unwrap_or_default().to_string();
        for t in specs {
            let mut spec = TargetSpec::parse(t.as_ref())?;
            if spec.address != "emu" && out.iter().any(|s| place(s) == place(&spec)) {
                return Err(SpecError(format!(
                    "--target {} given twice: a bridge serves one host at a time, and two would drive one chip at once",
                    place(&spec)
                )));
            }
            let mut n = 1;
            let base = spec.label().to_string();
            while out.iter().any(|s| s.label() == spec.label()) {
                n += 1;
                spec.name = Some(format!("{base}#{n}"));
            }
            out.push(spec);
        }
        Ok(out)
    }

    /// What the reports call this board.
    pub fn label(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.address)
    }

    /// The address read as its backend takes it; an error naming the form
    /// to write when it does not read.
    pub fn resolve(&self) -> Result<Address, SpecError> {
        let a = self.address.as_str();
        if a == "emu" {
            return Ok(Address::Emu);
        }
        if self.drop_batch.is_some() {
            return Err(SpecError(format!(
                "--target `{a}`: drop-batch= fails a batch of the emulator; a real link brings its own faults (to make them: ppmc chaos-proxy, ppmc bridge-sim --drop-rate)"
            )));
        }
        if !self.chip_faults.is_empty() {
            return Err(SpecError(format!(
                "--target `{a}`: chip-fault= makes the emulator a faulty board; a real board brings its own faults (for a faulty board behind a bridge: ppmc bridge-sim --chip-fault)"
            )));
        }
        let Some(driver) = driver_for(a) else {
            return Err(SpecError(unknown(a)));
        };
        driver.check(a).map_err(|hint| {
            SpecError(format!("bad target `{a}`: write {}{hint}", driver.form()))
        })?;
        Ok(Address::Bridge {
            driver,
            address: a.to_string(),
        })
    }
}

/// Why `address` (no link kind's) is not a target, and what to write.
fn unknown(address: &str) -> String {
    let (head, rest) = address.split_once(',').unwrap_or((address, ""));
    if head == "emu" {
        // The emulator's options are all the board's or its own: anything
        // left is an option misspelt, not a target.
        let option = rest.split(',').next().unwrap_or_default();
        return format!(
            "--target `{address}`: unknown option `{option}`: the board's options are {BOARD_OPTIONS}; the emulator's own, chip-fault= and drop-batch="
        );
    }
    if head.starts_with('/') || head.to_ascii_uppercase().starts_with("COM") {
        return format!(
            "unknown target `{address}`: a serial port is written `serial:{address}`; the targets are {}",
            forms()
        );
    }
    format!("unknown target `{address}`: use {}", forms())
}

/// The options every target takes, as a usage error lists them.
const BOARD_OPTIONS: &str =
    "name=, rev=, board-serial=, pad=, clock-mhz=, ext-clock-khz=, csel= and vsel=";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_addresses_are_host_and_port_or_the_users_mistake() {
        let spec = |t: &str| TargetSpec::parse(t).expect("splits");
        for t in ["tcp://[::1", "tcp://[::1:4321", "rfc2217://[::1,baud=9600"] {
            let e = spec(t).resolve().expect_err("refused").0;
            assert!(e.contains("an IPv6 address in brackets"), "{t}: {e}");
        }
        for t in ["tcp://[::1]:4321", "rfc2217://[::1]:4321,baud=9600"] {
            let a = spec(t).resolve().expect("reads");
            assert!(
                matches!(&a, Address::Bridge { address, .. } if address == t),
                "{a:?}"
            );
        }
    }

    /// Issue 42: a misspelt option of the emulator is named as an option,
    /// not as an unknown target; a bare device path is shown its form.
    #[test]
    fn a_misspelt_option_and_a_bare_port_say_what_to_write() {
        let refused = |t: &str| {
            TargetSpec::parse(t)
                .expect("splits")
                .resolve()
                .expect_err("refused")
                .0
        };
        let e = refused("emu,foo=bar");
        assert!(
            e.starts_with(
                "--target `emu,foo=bar`: unknown option `foo=bar`: the board's options are name=,"
            ),
            "{e}"
        );
        assert!(e.contains("chip-fault="), "{e}");
        let e = refused("emu,rev=B,colck-mhz=4");
        assert!(e.contains("unknown option `colck-mhz=4`"), "{e}");
        let e = refused("/dev/ttyACM0");
        assert!(
            e.starts_with(
                "unknown target `/dev/ttyACM0`: a serial port is written `serial:/dev/ttyACM0`"
            ),
            "{e}"
        );
        let e = refused("COM3,baud=115200");
        assert!(e.contains("`serial:COM3,baud=115200`"), "{e}");
    }

    #[test]
    fn every_link_kind_is_in_the_usage_message_and_resolves_to_its_driver() {
        let e = TargetSpec::parse("usb:0")
            .expect("reads")
            .resolve()
            .expect_err("refused")
            .0;
        assert_eq!(
            e,
            "unknown target `usb:0`: use `emu`, `serial:<path>[,baud=N]`, `tcp://<host>:<port>`, `rfc2217://<host>:<port>[,baud=N]` or `labgrid:<place>[,port=NAME][,acquire]`"
        );
        for (text, prefix) in [
            ("serial:/dev/ttyACM0", "serial:"),
            ("tcp://bench1:4321", "tcp://"),
            ("rfc2217://bench1:4321", "rfc2217://"),
            ("labgrid:rig-3", "labgrid:"),
        ] {
            let a = TargetSpec::parse(text)
                .expect("reads")
                .resolve()
                .expect("reads");
            assert_eq!(a.driver().map(|d| d.prefix()), Some(prefix), "{text}");
        }
        assert_eq!(
            TargetSpec::parse("emu").expect("reads").resolve(),
            Ok(Address::Emu)
        );
    }

    #[test]
    fn board_options_leave_the_address_and_labels_are_unique() {
        let s: TargetSpec = "serial:/dev/ttyACM0,baud=9600,name=b1,rev=B,pad=32,csel=low"
            .parse()
            .expect("reads");
        assert_eq!(s.address, "serial:/dev/ttyACM0,baud=9600");
        assert_eq!(
            (s.label(), s.rev.as_deref(), s.pad),
            ("b1", Some("B"), Some(32))
        );
        assert_eq!(s.straps.csel_high, Some(false));
        let all = TargetSpec::parse_all(&["emu", "emu", "emu,name=emu#2"]).expect("reads");
        let labels: Vec<&str> = all.iter().map(TargetSpec::label).collect();
        assert_eq!(labels, ["emu", "emu#2", "emu#2#2"]);
        let twice = TargetSpec::parse_all(&["tcp://a:1", "tcp://a:1,name=x"]).expect_err("refused");
        assert!(twice.0.contains("given twice"), "{twice}");
    }
}
