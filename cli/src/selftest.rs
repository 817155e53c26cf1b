//! `ppmc selftest`: a bus bridge's test of its own capture
//! ([`ppmc::selftest`]).

use super::args::{parse_duration, TargetArgs};
use crate::{usage, CliError};
use clap::Args;
use ppmc::backend::TargetErrorKind;
use ppmc::selftest::{checks, judge, Limits};
use ppmc::time::Duration;

#[derive(Debug, Args)]
pub struct SelftestArgs {
    #[command(flatten)]
    target: TargetArgs,
    /// Largest offset (either way) of a captured edge from when the
    /// bridge's generator made it, e.g. 100ns.
    #[arg(long, value_name = "DURATION", default_value = "100ns", value_parser = parse_duration)]
    max_offset: Duration,
    /// Largest spread of those offsets: the capture's jitter, e.g. 30ns.
    #[arg(long, value_name = "DURATION", default_value = "30ns", value_parser = parse_duration)]
    max_jitter: Duration,
}

pub fn run(mut args: SelftestArgs) -> Result<(), CliError> {
    args.target.stop = super::signals::install();
    let mut target = args.target.open()?;
    let info = target.info();
    let firmware = info
        .extra
        .iter()
        .find(|(k, _)| k == "bridge_firmware")
        .map_or("", |(_, v)| v.as_str());
    // Said once the first check has run: a target without a self-test
    // (the emulator) gets its error alone, under no heading.
    let mut heading = Some(format!(
        "selftest of {} (bridge firmware \"{firmware}\")",
        info.name
    ));
    let limits = Limits {
        offset: args.max_offset,
        jitter: args.max_jitter,
    };
    let mut failed = 0;
    let all = checks();
    for check in &all {
        let run = match target.self_test(&check.plan) {
            Ok(r) => r,
            Err(e) if e.kind == TargetErrorKind::Interrupted => {
                return Err(CliError::Infrastructure(format!("{}: {e}", info.name)))
            }
            // The emulator: no bridge.
            Err(e) if e.kind == TargetErrorKind::Unsupported => {
                return Err(usage(format!("{}: {e}", info.name)))
            }
            Err(e) => {
                return Err(CliError::Infrastructure(format!(
                    "{}: the self-test \"{}\" did not run: {e}",
                    info.name, check.name
                )))
            }
        };
        if let Some(h) = heading.take() {
            outln!("{h}");
        }
        let o = judge(check, &run, &limits);
        let p = &check.plan;
        let what = format!(
            "{} x {} pulses, {} high, {} low",
            p.bursts, p.count, o.high, o.low
        );
        let seen = match &o.overrun {
            Some(d) => format!("capture overrun reported ({d})"),
            None => o
                .edges
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("; "),
        };
        let verdict = if o.passed() { "ok" } else { "FAILED" };
        outln!("  {:<20} {what}: {seen}: {verdict}", check.name);
        for f in &o.faults {
            outln!("      {f}");
        }
        if !o.passed() {
            failed += 1;
        }
    }
    let limits_said = format!(
        "limits: offset {} ns, jitter {} ns",
        limits.offset.as_nanos(),
        limits.jitter.as_nanos()
    );
    if failed == 0 {
        outln!("selftest: passed: {} checks ({limits_said})", all.len());
        Ok(())
    } else {
        Err(CliError::Failed(format!(
            "selftest: {failed} of {} checks failed ({limits_said}): the bridge's capture is not to be trusted; see docs/bridge-hardware.md, bring-up",
            all.len()
        )))
    }
}
