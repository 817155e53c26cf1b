//! Issue 30's proof that the judge and the model agree on every scenario
//! of the suite, as a lab would record it: each scenario run on the clean
//! emulator and exported as a full-pin capture (`ppmc export --scenario
//! NAME --bus`: the bus, POUT, DIR, the phases, INT*, BUSY, HOLD, AUX*,
//! AUXO, and the inputs the board drives), converted by sigrok-cli itself
//! into sigrok sessions at 100, 50 and 23.8 MHz (the last not a divisor of
//! the export's microsecond grid, so every edge is seen late by a
//! different part of a sample), and each judged: the board passes. The
//! scenarios that break chapter 3's host rules on purpose (the error
//! scenarios: a command while BUSY, data no command asked for) pass the
//! board with host findings (exit 3).
//!
//! Each scenario is recorded twice (issue 40): with a host that polls the
//! status and accesses a bus cycle after the poll that saw the chip ready,
//! and with a host that accesses the instant the chip is ready (`ppmc
//! export --host exact`: each write's strobe ends as IBF falls). Sampling
//! then moves a write to either side of IBF's fall, and the judge must
//! follow both orders rather than fail the board for the one its model
//! picked. The exact host's board may be MARGINAL (docs/capture.md): a
//! change within the capture's uncertainty of its limit; the polling
//! host's never is.
//!
//! `cargo test` judges a sample of the suite, one scenario of each kind, at
//! every rate. CI sets `PPMC_SUITE_CAPTURES=all` (`.ci/run`): every
//! scenario, the sample at every rate and the rest at 23.8 MHz, the
//! coarsest and the one off the export's grid (each sigrok-cli conversion
//! costs about a quarter of a CPU-second, and CI is bound by CPU).
//! `PPMC_SUITE_CAPTURES=every-rate` judges every scenario at every rate;
//! `PPMC_SUITE_CAPTURES_HOST=polling` (or `exact`) judges one host's only.

use crate::common;
use common::{ppmc, scratch, text};
use std::path::Path;
use std::sync::Mutex;

/// One scenario of each kind: inputs that stop a move, stop switching's
/// chopping ended by a move, a Decelerating Stop written while the pulses
/// run, the error and host-rule scenarios, the auxiliary outputs,
/// register reads, and the speed limit.
const SAMPLE: [&str; 10] = [
    "s3_3_6_continuous_until_l1",
    "s3_5_1_default_switching_chops_the_phases",
    "s3_3_8_origin_search_stops_at_cnp",
    "s3_6_decel_stop_17us_not_before",
    "s3_3_7_high_speed_until_l3",
    "e1_operation_command_while_busy",
    "s3_5_3_aux_output_drives_auxo",
    "s3_4_2_input_status_alm_cnp",
    "s3_2_2_over_speed_locks_out_the_host",
    "s3_5_4_software_reset_while_busy_is_aux_on",
];

/// The scenarios besides the error scenarios (`e0_*` to `e7_*`) that
/// break a host rule of chapter 3 on purpose, to see the chip's answer.
const ON_PURPOSE: [&str; 6] = [
    "s3_1_1_error_flag_stays_until_the_next_command",
    "s3_1_1_write_while_ibf_loses_the_earlier_byte",
    "s3_2_2_pout_mode_allows_40_kpps",
    "s3_5_1_switching_parameters_while_busy",
    "s3_5_4_software_reset_frees_the_motor",
    "s3_5_4_software_reset_while_busy_is_aux_on",
];

/// The VCD's 1 ns timescale divided: 100, 50 and 23.8 MHz.
const DOWNSAMPLE: [u32; 3] = [10, 20, 42];

/// The coarsest of [`DOWNSAMPLE`], 23.8 MHz: the one rate of a scenario
/// outside the sample under `PPMC_SUITE_CAPTURES=all`.
const COARSEST: [u32; 1] = [42];

/// Captures larger than this are judged from the VCD alone: a sigrok
/// session of the 16,777,216-step move (over 600 s of chip time) would
/// hold some 15 G samples at 24 MHz, more than a lab would record.
const SR_LIMIT_BYTES: u64 = 50 << 20;

/// Judges `capture` and says what went wrong, if anything: the board must
/// pass, exit 0, or 3 with host findings.
/// And with `marginal_ok`, `MARGINAL the board` will do too (the exact
/// host's captures: docs/capture.md, "MARGINAL"). Whether the host broke
/// chapter 3's rules, and whether the board was MARGINAL.
fn judge(capture: &Path, partial: bool, marginal_ok: bool) -> Result<(bool, bool), String> {
    let mut args = vec!["judge", capture.to_str().expect("utf-8")];
    if partial {
        args.push("--partial");
    }
    let out = ppmc(&args);
    let said = text(&out.stdout);
    let code = out.status.code();
    let marginal = said.contains("MARGINAL the board");
    let passed = said.contains("PASS the board") || (marginal_ok && marginal);
    if !passed || !matches!(code, Some(0 | 3)) {
        return Err(format!(
            "{}: exit {code:?}\n{said}{}",
            capture.display(),
            text(&out.stderr)
        ));
    }
    Ok((code == Some(3), marginal))
}

/// How the exported host times its waited accesses (`ppmc export --host`).
const HOSTS: [&str; 2] = ["polling", "exact"];

/// Scenarios recorded with the polling host only: their captures are
/// judged from the VCD alone (over [`SR_LIMIT_BYTES`]), where no sampling
/// moves an edge, so the exact host would add nothing but time.
const POLLING_ONLY: [&str; 1] = ["s3_3_4_accel_ffffff_is_16777216_steps"];

/// Scenarios whose capture ends with the chip still BUSY, waiting for
/// what never comes (an external clock no one drives): judged with
/// `--partial`, which says what was not judged.
const PARTIAL: [&str; 1] = ["s3_2_2_external_clock"];

/// Exports (with a host timed as `host` says), converts and judges
/// `name`; whether the host broke chapter 3's rules in it, and in how
/// many of its captures the board was MARGINAL (never with the polling
/// host).
fn check(dir: &Path, name: &str, host: &str, rates: &[u32]) -> Result<(bool, u32), String> {
    let vcd = dir.join(format!("{name}-{host}.vcd"));
    let out = ppmc(&[
        "export",
        "--scenario",
        name,
        "--bus",
        "--host",
        host,
        "-o",
        vcd.to_str().expect("utf-8"),
    ]);
    if !out.status.success() {
        return Err(format!("{name}: export: {}", text(&out.stderr)));
    }
    let partial = PARTIAL.contains(&name);
    let marginal_ok = host == "exact";
    let (found, marginal) = judge(&vcd, partial, marginal_ok)?;
    let mut marginals = u32::from(marginal);
    let size = std::fs::metadata(&vcd).map_err(|e| e.to_string())?.len();
    if size <= SR_LIMIT_BYTES {
        for &ds in rates {
            let sr = dir.join(format!("{name}-{host}-{ds}.sr"));
            let out = std::process::Command::new("sigrok-cli")
                .args(["-I", &format!("vcd:downsample={ds}"), "-i"])
                .arg(&vcd)
                .arg("-o")
                .arg(&sr)
                .output()
                .map_err(|e| format!("sigrok-cli: {e}"))?;
            if !out.status.success() {
                return Err(format!("{name}: sigrok-cli: {}", text(&out.stderr)));
            }
            let (f, marginal) = judge(&sr, partial, marginal_ok)?;
            marginals += u32::from(marginal);
            if f != found {
                return Err(format!(
                    "{name} ({host} host): host findings at 1/{ds} ns and not in the VCD, or the other way"
                ));
            }
            let _ = std::fs::remove_file(&sr);
        }
    }
    let _ = std::fs::remove_file(&vcd);
    Ok((found, marginals))
}

#[cfg_attr(
    ppmc_missing_sigrok_cli,
    ignore = "sigrok-cli is not installed (apt install sigrok-cli)"
)]
#[test]
fn every_scenarios_capture_passes_at_three_sample_rates() {
    if !common::sigrok_cli("converting captures to sigrok sessions") {
        return;
    }
    let mode = std::env::var("PPMC_SUITE_CAPTURES").unwrap_or_default();
    let all = matches!(mode.as_str(), "all" | "every-rate");
    let rates_of = |name: &str| -> &[u32] {
        if mode == "every-rate" || SAMPLE.contains(&name) {
            &DOWNSAMPLE
        } else {
            &COARSEST
        }
    };
    let names: Vec<String> = if all {
        ppmc_scenarios::all()
            .iter()
            .map(|s| s.name.to_string())
            .collect()
    } else {
        SAMPLE.iter().map(|s| s.to_string()).collect()
    };
    let dir = scratch("suite-captures");
    let jobs: Vec<(String, &str)> = names
        .iter()
        .flat_map(|n| HOSTS.map(|h| (n.clone(), h)))
        .filter(|(n, h)| *h == "polling" || !POLLING_ONLY.contains(&n.as_str()))
        .filter(|(_, h)| std::env::var("PPMC_SUITE_CAPTURES_HOST").map_or(true, |only| only == *h))
        .collect();
    let queue = Mutex::new(jobs.clone());
    let results = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some((name, host)) = queue.lock().expect("queue").pop() else {
                    return;
                };
                let r = check(dir.path(), &name, host, rates_of(&name));
                results.lock().expect("results").push((name, r));
            });
        }
    });
    let results = results.into_inner().expect("results");
    assert_eq!(results.len(), jobs.len());
    let failed: Vec<&str> = results
        .iter()
        .filter_map(|(_, r)| r.as_ref().err().map(String::as_str))
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let mut host: Vec<&str> = results
        .iter()
        .filter(|(_, r)| r.as_ref().is_ok_and(|(h, _)| *h))
        .map(|(n, _)| n.as_str())
        .collect();
    host.sort();
    host.dedup();
    // Only scenarios that misuse the chip on purpose give host findings:
    // each provokes the error or the lost byte it checks for.
    let on_purpose = |n: &str| {
        n.starts_with('e') && n.as_bytes().get(1).is_some_and(u8::is_ascii_digit)
            || ON_PURPOSE.contains(&n)
    };
    assert!(host.iter().all(|n| on_purpose(n)), "{host:?}");
    assert!(
        host.contains(&"e1_operation_command_while_busy"),
        "{host:?}"
    );
    let marginal: u32 = results
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok().map(|(_, m)| *m))
        .sum();
    eprintln!(
        "{} scenarios judged with {} hosts, as VCD and at {} of {} sample rates; host findings in {}; the board MARGINAL in {marginal} of the exact host's captures",
        names.len(),
        HOSTS.len(),
        if all && mode != "every-rate" { "1 (the sample at all)" } else { "all" },
        DOWNSAMPLE.len(),
        host.len()
    );
}
