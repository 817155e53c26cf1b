//! Generates the scenario suite from `../scenarios/*.rs` (each file a
//! module with `pub fn scenarios() -> Vec<Scenario>`), so that a new
//! scenario file is picked up without editing a list, and records the git
//! revision for run records.

use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let dir = manifest.join("../scenarios");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut files: Vec<PathBuf> = fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x == "rs"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    let mut out = String::new();
    let mut mods = Vec::new();
    for f in &files {
        println!("cargo:rerun-if-changed={}", f.display());
        let stem = f
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default()
            .to_string();
        let valid = stem
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_lowercase() || c == '_')
            && stem
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        if !valid {
            panic!(
                "scenarios/{}: a scenario file name must be a snake_case Rust identifier",
                f.display()
            );
        }
        let abs = fs::canonicalize(f).unwrap_or_else(|_| f.clone());
        let _ = writeln!(
            out,
            "#[path = {:?}]\npub mod {stem};",
            abs.display().to_string()
        );
        mods.push(stem);
    }
    out.push_str("\n/// Every scenario in `scenarios/`, file by file.\npub fn all() -> Vec<crate::scenario::Scenario> {\n    let mut v = Vec::new();\n");
    for m in &mods {
        let _ = writeln!(out, "    v.extend({m}::scenarios());");
    }
    out.push_str("    v\n}\n");
    let dest = Path::new(&env::var("OUT_DIR").expect("set by cargo")).join("suite.rs");
    fs::write(dest, out).expect("write suite.rs");

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
    // names, and packed refs.
    let git = manifest.join("../.git");
    let head = git.join("HEAD");
    if head.exists() {
        println!("cargo:rerun-if-changed={}", head.display());
        if let Some(r) = fs::read_to_string(&head)
            .ok()
            .and_then(|h| h.strip_prefix("ref: ").map(|r| r.trim().to_string()))
        {
            println!("cargo:rerun-if-changed={}", git.join(r).display());
        }
        println!(
            "cargo:rerun-if-changed={}",
            git.join("packed-refs").display()
        );
    }
}
