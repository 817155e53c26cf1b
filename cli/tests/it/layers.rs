//! The crates keep the layers ARCHITECTURE.md lists (issue 41): its table
//! names every workspace crate, with exactly the workspace crates each
//! depends on (normal dependencies, as `cargo metadata` reads the
//! manifests), each of a lower layer; and what a crate compiles (`cargo
//! tree`) holds no more than its place allows: the scenario language
//! (`library-user`, on `ppmc` alone) and the fuzz crate no SQLite, zip or
//! clap.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `cargo metadata` of `manifest`, as JSON: its packages as their
/// manifests declare them.
fn metadata(manifest: &Path) -> serde_json::Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.args([
        "metadata",
        "--format-version",
        "1",
        "--offline",
        "--no-deps",
    ])
    .arg("--manifest-path")
    .arg(manifest);
    let out = cmd.output().expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata's JSON")
}

/// ARCHITECTURE.md's crate table: each crate's layer and the workspace
/// crates it says it depends on.
fn table() -> BTreeMap<String, (u32, BTreeSet<String>)> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let mut rows = BTreeMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // `| layer | crate | folder | what | depends on |`
        let (Some(layer), Some(name), Some(deps)) = (cells.get(1), cells.get(2), cells.get(5))
        else {
            continue;
        };
        let Ok(layer) = layer.parse::<u32>() else {
            continue;
        };
        let deps = deps
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty())
            .map(str::to_string)
            .collect();
        rows.insert(name.trim_matches('`').to_string(), (layer, deps));
    }
    rows
}

#[test]
fn the_crates_keep_the_layers_architecture_md_lists() {
    let rows = table();
    let meta = metadata(&root().join("Cargo.toml"));
    let packages = meta["packages"].as_array().expect("packages");
    let members: BTreeSet<String> = packages
        .iter()
        .map(|p| p["name"].as_str().expect("a name").to_string())
        .collect();
    let listed: BTreeSet<String> = rows.keys().cloned().collect();
    assert_eq!(
        listed, members,
        "ARCHITECTURE.md's crate table lists every workspace crate"
    );
    for p in packages {
        let name = p["name"].as_str().expect("a name");
        let deps: BTreeSet<String> = p["dependencies"]
            .as_array()
            .expect("dependencies")
            .iter()
            .filter(|d| d["kind"].is_null())
            .map(|d| d["name"].as_str().expect("a name").to_string())
            .filter(|d| members.contains(d))
            .collect();
        let (layer, said) = &rows[name];
        assert_eq!(
            &deps, said,
            "{name}: its workspace dependencies, as the table says them"
        );
        for d in &deps {
            assert!(
                rows[d].0 < *layer,
                "{name} (layer {layer}) depends on {d} (layer {}): a crate imports only lower layers",
                rows[d].0
            );
        }
    }
}

/// Every package `from` compiles for this machine (normal and build
/// dependencies), as `cargo tree` resolves them from the lock file,
/// offline: the tests never fetch.
fn compiled(from: &str) -> BTreeSet<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "--locked",
            "-e",
            "normal,build",
            "--prefix",
            "none",
            "-p",
            from,
        ])
        .arg("--manifest-path")
        .arg(root().join("Cargo.toml"))
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

const HEAVY: [&str; 5] = ["rusqlite", "libsqlite3-sys", "zip", "clap", "indicatif"];

#[test]
fn the_scenario_language_compiles_no_sqlite_zip_or_clap() {
    let user = compiled("library-user");
    assert!(
        user.contains("ppmc"),
        "library-user depends on ppmc: {user:?}"
    );
    for heavy in HEAVY {
        assert!(
            !user.contains(heavy),
            "library-user compiles {heavy}: {user:?}"
        );
    }
    // The command line does compile them: the check can fail.
    let cli = compiled("ppmc-cli");
    assert!(cli.contains("rusqlite") && cli.contains("clap"), "{cli:?}");
}

/// The fuzz crate (outside the workspace: it needs nightly) declares only
/// `ppmc` of ppmc's crates, and `ppmc` compiles no SQLite: the fuzz
/// targets build without it.
#[test]
fn the_fuzz_crate_builds_on_the_harness_alone() {
    let fuzz = metadata(&root().join("fuzz/Cargo.toml"));
    let deps: BTreeSet<String> = fuzz["packages"][0]["dependencies"]
        .as_array()
        .expect("dependencies")
        .iter()
        .map(|d| d["name"].as_str().expect("a name").to_string())
        .filter(|d| d.starts_with("ppmc"))
        .collect();
    assert_eq!(deps, BTreeSet::from(["ppmc".to_string()]));
    let harness = compiled("ppmc");
    for heavy in HEAVY {
        assert!(!harness.contains(heavy), "ppmc compiles {heavy}");
    }
    // And its own lock file, which `cargo fuzz` builds from, holds none.
    let lock = std::fs::read_to_string(root().join("fuzz/Cargo.lock")).expect("fuzz/Cargo.lock");
    for heavy in HEAVY {
        assert!(
            !lock.contains(&format!("name = \"{heavy}\"")),
            "fuzz/Cargo.lock locks {heavy}"
        );
    }
}

/// CI fuzzes without AddressSanitizer (`.ci/run`, fuzz/README.md): the
/// sanitizer checks unsafe code, and the workspace crates the fuzz
/// targets reach (the harness and every workspace crate below it) forbid
/// it. Each must inherit the workspace's lints, and those must forbid
/// `unsafe_code`.
#[test]
fn the_crates_the_fuzz_targets_reach_forbid_unsafe_code() {
    let manifest =
        std::fs::read_to_string(root().join("Cargo.toml")).expect("the workspace's Cargo.toml");
    let rust_lints = manifest
        .split("[workspace.lints.rust]")
        .nth(1)
        .expect("a [workspace.lints.rust] table");
    let rust_lints = rust_lints.split("\n[").next().unwrap_or_default();
    assert!(
        rust_lints
            .lines()
            .any(|l| l.replace(' ', "") == "unsafe_code=\"forbid\""),
        "[workspace.lints.rust] does not forbid unsafe_code:{rust_lints}"
    );
    let layers = table();
    let mut reached = BTreeSet::from(["ppmc".to_string()]);
    let mut todo = vec!["ppmc".to_string()];
    while let Some(name) = todo.pop() {
        let (_, deps) = layers
            .get(&name)
            .unwrap_or_else(|| panic!("{name} is not in ARCHITECTURE.md's table"));
        for dep in deps {
            if reached.insert(dep.clone()) {
                todo.push(dep.clone());
            }
        }
    }
    let workspace = metadata(&root().join("Cargo.toml"));
    for package in workspace["packages"].as_array().expect("packages") {
        let name = package["name"].as_str().expect("a name");
        if !reached.contains(name) {
            continue;
        }
        let path = package["manifest_path"].as_str().expect("a manifest path");
        let text = std::fs::read_to_string(path).expect("the crate's Cargo.toml");
        assert!(
            text.replace(' ', "").contains("[lints]\nworkspace=true"),
            "{path}: the fuzz targets reach {name}, which does not inherit the workspace's lints (`[lints] workspace = true`)"
        );
        reached.remove(name);
    }
    assert!(reached.is_empty(), "not workspace members: {reached:?}");
}
