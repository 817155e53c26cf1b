//! Recovery by power on the command line: the flags of `ppmc run` and
//! `ppmc fuzz campaign`, and the options they give the boards
//! ([`ppmc::backend::power`]).

use clap::Args;

/// Recovery by power: how a board that hangs is brought back
/// (docs/board-farm.md, "A board that hangs").
#[derive(Debug, Args)]
#[command(next_help_heading = "Recovery by power")]
pub struct PowerArgs {
    /// A board that hangs (its bridge silent past the link's bounds, or
    /// its chip BUSY after a chip reset) has its power cycled by the shell
    /// running `CMD cycle`, with PPMC_BOARD (the board's label) and
    /// PPMC_TARGET (its address) set; then the run goes on from the next
    /// scenario, and the one it hung under is an infrastructure error that
    /// names the hang. Default: a labgrid place's own power (`labgrid-client
    /// -p PLACE power cycle`); other boards have none.
    #[arg(long, value_name = "CMD")]
    power_cmd: Option<String>,
    /// As --power-cmd, by cycling a USB hub port that powers the board:
    /// `uhubctl -l LOCATION -p PORT -a cycle` (LOCATION:PORT as uhubctl
    /// lists them, e.g. 1-1.4:2).
    #[arg(long, value_name = "LOCATION:PORT", conflicts_with = "power_cmd", value_parser = hub)]
    power_hub: Option<ppmc::backend::Hub>,
    /// Power cycles each board may have in one run; 0 turns recovery by
    /// power off. A board that hangs once more is lost, and the scenarios
    /// left to it are not run.
    #[arg(long, value_name = "N", default_value_t = 3)]
    power_cycles: u32,
    /// How long a board may take after its power cycle for its bridge to
    /// answer again, e.g. 30s.
    #[arg(long, value_name = "DURATION", default_value = "30s", value_parser = crate::args::parse_duration)]
    boot_timeout: ppmc::time::Duration,
}

fn hub(s: &str) -> Result<ppmc::backend::Hub, String> {
    ppmc::backend::Hub::parse(s).map_err(String::from)
}

impl PowerArgs {
    /// What cannot hold for `boards` boards: one hub port for several
    /// would cycle every board when one hangs.
    pub(crate) fn check(&self, boards: usize) -> Result<(), String> {
        match &self.power_hub {
            Some(h) if boards > 1 => Err(format!(
                "--power-hub {}:{} with {boards} --target: one port would cycle every board when one hangs; give --power-cmd a script that picks the board's port by PPMC_BOARD",
                h.location, h.port
            )),
            _ => Ok(()),
        }
    }

    /// What the flags say.
    pub(crate) fn options(&self) -> ppmc::backend::PowerOptions {
        ppmc::backend::PowerOptions {
            cmd: self.power_cmd.clone(),
            hub: self.power_hub.clone(),
            cycles: self.power_cycles,
            boot: std::time::Duration::from_nanos(self.boot_timeout.as_nanos()),
        }
    }
}
