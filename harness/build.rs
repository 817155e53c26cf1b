//! Records the git revision for run records.

use std::env;
use std::fs;
use std::path::PathBuf;
use std::process::Command;

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let rev = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .current_dir(&manifest)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=PPMC_GIT_REV={rev}");
    // Rebuild the revision when HEAD moves: HEAD itself, the branch it
    // names, and packed refs. Only files that exist are named: Cargo takes
    // a missing one as changed on every build, which would rebuild this
    // crate and everything above it each time.
    let git = manifest.join("../.git");
    let head = git.join("HEAD");
    let branch = fs::read_to_string(&head)
        .ok()
        .and_then(|h| h.strip_prefix("ref: ").map(|r| git.join(r.trim())));
    for path in [Some(head), branch, Some(git.join("packed-refs"))]
        .into_iter()
        .flatten()
        .filter(|p| p.exists())
    {
        println!("cargo:rerun-if-changed={}", path.display());
    }
}
