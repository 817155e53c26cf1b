//! Recovery by power: a board's power switch, and what the runner may
//! spend of it.
//!
//! A board that hangs (its bridge silent past the link's bounds, or its
//! chip still BUSY after a chip reset) is brought back by cycling its
//! power once, then reaching its bridge again ([`Target::power_cycle`]). The
//! switch is, for each board:
//!
//! - `--power-cmd CMD`: the shell runs `CMD cycle`, with `PPMC_BOARD` (the
//!   board's label) and `PPMC_TARGET` (its address) in the environment, so
//!   one script serves every board of a run;
//! - `--power-hub LOCATION:PORT`: a USB hub port, cycled by `uhubctl -l
//!   LOCATION -p PORT -a cycle` (a board powered from its USB port);
//! - otherwise, for a `labgrid:<place>` target, the place's own power:
//!   `labgrid-client -p PLACE power cycle` (its power resource, or the
//!   power driver of the environment `LG_ENV` names).
//!
//! Every command is bounded ([`SWITCH_TIMEOUT`]) and runs in a process
//! group of its own. One that fails or hangs leaves the board as a board
//! without a switch is (a silent bridge lost, a BUSY chip left to the next
//! scenario's reset), and says why. The runner's side (what a hang is,
//! whose verdict it is) is `runner.rs`'s `run_checked`.
//!
//! [`Target::power_cycle`]: super::target::Target::power_cycle

use super::bridged::BridgeError;
use super::link::labgrid::parse_labgrid;
use super::link::lease::client_program;
use super::spec::{SpecError, TargetSpec};
use super::target::{Op, Reply, Target, TargetError, TargetErrorKind};
use crate::stop::StopRequest;
use std::fmt;
use std::process::Command;
use std::time::Duration;

/// The longest a power switch may take to cycle a board.
pub const SWITCH_TIMEOUT: Duration = Duration::from_secs(60);

/// What a run may do with its boards' power: the switch given on the
/// command line, and how many cycles each board may have.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PowerOptions {
    /// `--power-cmd`: a shell command that takes `cycle`.
    pub cmd: Option<String>,
    /// `--power-hub LOCATION:PORT`.
    pub hub: Option<Hub>,
    /// Power cycles each board may have in one run (`--power-cycles`); 0
    /// turns recovery by power off.
    pub cycles: u32,
    /// How long a board may take, once its power is back, for its bridge
    /// to answer again (`--boot-timeout`).
    pub boot: Duration,
}

impl Default for PowerOptions {
    fn default() -> Self {
        PowerOptions {
            cmd: None,
            hub: None,
            cycles: 3,
            boot: Duration::from_secs(30),
        }
    }
}

/// A port of a USB hub that switches its power: `uhubctl`'s location
/// (`1-1.4`) and port number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hub {
    pub location: String,
    pub port: u16,
}

impl Hub {
    /// Reads `LOCATION:PORT` (`1-1.4:2`), as `uhubctl` lists them.
    pub fn parse(s: &str) -> Result<Hub, SpecError> {
        let bad = |why: &str| SpecError(format!("--power-hub `{s}`: {why}"));
        let (location, port) = s
            .rsplit_once(':')
            .ok_or_else(|| bad("write LOCATION:PORT, as `uhubctl` lists them (1-1.4:2)"))?;
        let fine = |c: char| c.is_ascii_digit() || c == '-' || c == '.';
        if location.is_empty() || !location.chars().all(fine) {
            return Err(bad(
                "the hub's location is digits, `-` and `.` (1-1.4), as `uhubctl` lists it",
            ));
        }
        let port = port
            .parse::<u16>()
            .ok()
            .filter(|p| *p >= 1)
            .ok_or_else(|| bad("the port is a number from 1"))?;
        Ok(Hub {
            location: location.to_string(),
            port,
        })
    }
}

/// How one board's power is switched.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PowerSwitch {
    /// A shell command that takes `cycle`.
    Command(String),
    /// A USB hub port, through `uhubctl`.
    Hub(Hub),
    /// A labgrid place's power.
    Labgrid(String),
}

impl PowerSwitch {
    /// The switch of the board `spec` names under `opts`: the command
    /// line's, else a labgrid place's own; `None` without one, or when
    /// recovery by power is off. The emulator has none.
    pub fn of(spec: &TargetSpec, opts: &PowerOptions) -> Option<PowerSwitch> {
        if opts.cycles == 0 || spec.address == "emu" {
            return None;
        }
        if let Some(cmd) = &opts.cmd {
            return Some(PowerSwitch::Command(cmd.clone()));
        }
        if let Some(hub) = &opts.hub {
            return Some(PowerSwitch::Hub(hub.clone()));
        }
        parse_labgrid(&spec.address).map(|p| PowerSwitch::Labgrid(p.name))
    }

    /// The command that cycles the board, as a program and its arguments.
    fn command(&self, spec: &TargetSpec) -> Command {
        match self {
            PowerSwitch::Command(cmd) => {
                let mut c = Command::new("sh");
                c.arg("-c")
                    .arg(format!("{cmd} cycle"))
                    .env("PPMC_BOARD", spec.label())
                    .env("PPMC_TARGET", &spec.address);
                c
            }
            PowerSwitch::Hub(h) => {
                let mut c = Command::new(uhubctl());
                c.args(["-l", &h.location, "-p", &h.port.to_string()])
                    .args(["-a", "cycle"]);
                c
            }
            PowerSwitch::Labgrid(place) => {
                let mut c = Command::new(client_program());
                c.args(["-p", place, "power", "cycle"]);
                c
            }
        }
    }

    /// Cycles the power of the board `spec` names, at most
    /// [`SWITCH_TIMEOUT`]; the error says which command failed, and how.
    pub fn cycle(&self, spec: &TargetSpec) -> std::io::Result<()> {
        let shown = self.to_string();
        super::command::run_within(&mut self.command(spec), &shown, SWITCH_TIMEOUT).map(drop)
    }
}

/// `uhubctl`, or the program `PPMC_UHUBCTL` names.
fn uhubctl() -> String {
    std::env::var("PPMC_UHUBCTL").unwrap_or_else(|_| "uhubctl".into())
}

impl fmt::Display for PowerSwitch {
    /// The command as a person would type it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PowerSwitch::Command(cmd) => write!(f, "{cmd} cycle"),
            PowerSwitch::Hub(h) => {
                write!(f, "{} -l {} -p {} -a cycle", uhubctl(), h.location, h.port)
            }
            PowerSwitch::Labgrid(p) => write!(f, "{} -p {p} power cycle", client_program()),
        }
    }
}

/// Whether `e` says a board's bridge fell silent, the hang a power cycle
/// may cure: a bridge's own error says so
/// ([`BridgeError::is_silence`]); another target's link error is taken
/// so.
pub fn silent(e: &TargetError) -> bool {
    match e.get_ref().downcast_ref::<BridgeError>() {
        Some(b) => b.is_silence(),
        None => e.kind == TargetErrorKind::Link,
    }
}

/// The health check of a board that may have hung: a chip reset, and the
/// status after it. `Some(status)` when the chip is still BUSY (3-1-1: the
/// reset ends any move, so a chip BUSY past it is hung).
pub fn busy_after_reset(target: &mut dyn Target) -> Result<Option<u8>, TargetError> {
    let replies = target.execute(&[Op::Reset, Op::ReadStatus])?;
    Ok(match replies.get(1) {
        Some(Reply::Status { status, .. }) if status.busy() => Some(status.0),
        _ => None,
    })
}

/// Why [`Power::cycle`] did not bring a board back.
#[derive(Debug)]
pub enum CycleError {
    /// No cycle was tried (none left, or a stop was asked for): why. The
    /// board is as it was.
    NotTried(String),
    /// The switch failed: its words, and the target's error.
    Switch { why: String, error: TargetError },
    /// Power-cycled (`cycled` says how), and not reached again.
    NotBack { cycled: String, error: TargetError },
}

/// One board's switch, and the cycles it has left in this run.
#[derive(Debug, Clone)]
pub struct Power {
    pub switch: PowerSwitch,
    pub spec: TargetSpec,
    /// Cycles left.
    pub left: u32,
    /// How many it had.
    pub of: u32,
    pub boot: Duration,
    /// Asked for, no cycle starts (one under way ends: a board left
    /// without power is worse than a wait).
    pub stop: StopRequest,
}

impl Power {
    /// Spends one of the board's cycles on `target`: its switch cycles its
    /// power, and the target is reached again ([`Target::power_cycle`]).
    /// What was done (`power-cycled by `CMD` (1 of 3)`), or why not. The
    /// chip's health is the caller's to check.
    pub fn cycle(&mut self, target: &mut dyn Target) -> Result<String, CycleError> {
        if self.left == 0 {
            return Err(CycleError::NotTried(format!(
                "the board has had the {} power cycles it may have in a run (--power-cycles)",
                self.of
            )));
        }
        if self.stop.requested() {
            return Err(CycleError::NotTried(
                "no power cycle: the run was interrupted".into(),
            ));
        }
        self.left -= 1;
        let cycled = format!(
            "power-cycled by `{}` ({} of {})",
            self.switch,
            self.of - self.left,
            self.of
        );
        let mut switched = Ok(());
        let (switch, spec) = (&self.switch, &self.spec);
        let back = target.power_cycle(
            &mut || {
                switched = switch.cycle(spec).map_err(|e| e.to_string());
                switched.clone()
            },
            self.boot,
        );
        match (back, switched) {
            (Ok(()), _) => Ok(cycled),
            (Err(error), Err(why)) => Err(CycleError::Switch { why, error }),
            (Err(error), Ok(())) => Err(CycleError::NotBack { cycled, error }),
        }
    }

    /// The board `spec` names, with its switch under `opts`; `None` when it
    /// has none.
    pub fn of(spec: &TargetSpec, opts: &PowerOptions, stop: &StopRequest) -> Option<Power> {
        PowerSwitch::of(spec, opts).map(|switch| Power {
            switch,
            spec: spec.clone(),
            left: opts.cycles,
            of: opts.cycles,
            boot: opts.boot,
            stop: stop.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(s: &str) -> TargetSpec {
        TargetSpec::parse(s).expect("works")
    }

    #[test]
    fn each_board_gets_the_command_lines_switch_or_its_places_own() {
        let none = PowerOptions::default();
        assert_eq!(PowerSwitch::of(&spec("emu"), &none), None);
        assert_eq!(PowerSwitch::of(&spec("serial:/dev/ttyACM0"), &none), None);
        assert_eq!(
            PowerSwitch::of(&spec("labgrid:rig1,acquire,rev=B"), &none),
            Some(PowerSwitch::Labgrid("rig1".into()))
        );
        let cmd = PowerOptions {
            cmd: Some("./relay.sh 3".into()),
            ..PowerOptions::default()
        };
        assert_eq!(
            PowerSwitch::of(&spec("labgrid:rig1"), &cmd),
            Some(PowerSwitch::Command("./relay.sh 3".into()))
        );
        let off = PowerOptions { cycles: 0, ..cmd };
        assert_eq!(PowerSwitch::of(&spec("serial:/dev/ttyACM0"), &off), None);
        assert_eq!(PowerSwitch::of(&spec("emu"), &off), None);
    }

    #[test]
    fn a_hub_port_is_location_and_port_as_uhubctl_lists_them() {
        assert_eq!(
            Hub::parse("1-1.4:2").expect("works"),
            Hub {
                location: "1-1.4".into(),
                port: 2
            }
        );
        for bad in ["1-1.4", "1-1.4:0", ":2", "1-1;rm:2", "1-1:x"] {
            let e = Hub::parse(bad).expect_err("fails").0;
            assert!(e.starts_with(&format!("--power-hub `{bad}`: ")), "{e}");
        }
    }

    #[test]
    fn the_command_gets_cycle_and_the_boards_name() {
        let dir = tempfile::tempdir().expect("works");
        let log = dir.path().join("log");
        let switch = PowerSwitch::Command(format!(
            "echo \"$PPMC_BOARD $PPMC_TARGET\" >> '{}'; echo",
            log.display()
        ));
        switch
            .cycle(&spec("serial:/dev/ttyACM0,name=rig-3"))
            .expect("works");
        let said = std::fs::read_to_string(&log).expect("works");
        assert_eq!(said, "rig-3 serial:/dev/ttyACM0\n");
        let failing = PowerSwitch::Command("exit 4; true".into());
        let e = failing
            .cycle(&spec("serial:/dev/x"))
            .expect_err("fails")
            .to_string();
        assert!(e.contains("`exit 4; true cycle` failed"), "{e}");
    }
}
