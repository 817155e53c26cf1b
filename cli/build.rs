//! Which of the outside tools the integration tests use are installed, as
//! `cfg`s the tests read: a test whose tool is missing is compiled
//! `#[ignore]`d with the reason, so that `cargo test` counts it among the
//! ignored ("ignored, ser2net is not installed ...") rather than as
//! passed. In CI (`CI` set) every test is compiled to run: `.ci/run`
//! installs the tools, and a test that finds one missing fails.

use std::env;
use std::path::Path;

/// The tools probed, each with the `cfg` set when it is missing.
const TOOLS: [(&str, &str); 3] = [
    ("ser2net", "ppmc_missing_ser2net"),
    ("sigrok-cli", "ppmc_missing_sigrok_cli"),
    ("labgrid-client", "ppmc_missing_labgrid"),
];

fn main() {
    println!("cargo:rerun-if-env-changed=PATH");
    println!("cargo:rerun-if-env-changed=CI");
    println!("cargo:rerun-if-env-changed=PPMC_LABGRID_BIN");
    let path = env::var_os("PATH").unwrap_or_default();
    let dirs: Vec<_> = env::split_paths(&path).filter(|d| d.is_dir()).collect();
    // An install into a folder of PATH changes it, and so probes again.
    for d in &dirs {
        println!("cargo:rerun-if-changed={}", d.display());
    }
    let labgrid = env::var_os("PPMC_LABGRID_BIN");
    let ci = env::var_os("CI").is_some();
    for (tool, cfg) in TOOLS {
        println!("cargo::rustc-check-cfg=cfg({cfg})");
        let found = dirs.iter().any(|d| d.join(tool).is_file())
            || (tool == "labgrid-client"
                && labgrid
                    .as_ref()
                    .is_some_and(|b| Path::new(b).join(tool).is_file()));
        if !found && !ci {
            println!("cargo:rustc-cfg={cfg}");
        }
    }
}
