//! The crates keep the layers ARCHITECTURE.md lists (issue 41): its table
//! names every workspace crate, with exactly the workspace crates each
//! depends on (normal dependencies, as `cargo metadata` reads the
//! manifests), each of a lower layer; and what a crate compiles holds no
//! more than its place allows: the scenario language (`library-user`, on
//! `ppmc` alone) and the fuzz crate no SQLite, zip or clap.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `cargo metadata` of `manifest`, as JSON; `deps`: with the resolved
/// graph (from the lock file, offline: the tests never fetch).
fn metadata(manifest: &Path, deps: bool) -> serde_json::Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.args([
        "metadata",
        "--format-version",
        "1",
        "--offline",
        "--manifest-path",
    ])
    .arg(manifest);
    if !deps {
        cmd.arg("--no-deps");
    } else {
        cmd.arg("--locked");
    }
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
    let meta = metadata(&root().join("Cargo.toml"), false);
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

/// Every package `from` compiles (normal and build dependencies, on any
/// target), by the resolved graph of `meta`.
fn compiled(meta: &serde_json::Value, from: &str) -> BTreeSet<String> {
    let names: BTreeMap<&str, &str> = meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| {
            (
                p["id"].as_str().expect("id"),
                p["name"].as_str().expect("name"),
            )
        })
        .collect();
    let nodes: BTreeMap<&str, Vec<&str>> = meta["resolve"]["nodes"]
        .as_array()
        .expect("resolve")
        .iter()
        .map(|n| {
            let deps = n["deps"]
                .as_array()
                .expect("deps")
                .iter()
                .filter(|d| {
                    d["dep_kinds"]
                        .as_array()
                        .expect("dep_kinds")
                        .iter()
                        .any(|k| k["kind"].as_str() != Some("dev"))
                })
                .map(|d| d["pkg"].as_str().expect("pkg"))
                .collect();
            (n["id"].as_str().expect("id"), deps)
        })
        .collect();
    let start = names
        .iter()
        .find(|(_, n)| **n == from)
        .map(|(id, _)| *id)
        .expect("the package");
    let mut seen = BTreeSet::new();
    let mut todo = vec![start];
    while let Some(id) = todo.pop() {
        if seen.insert(id) {
            todo.extend(nodes.get(id).into_iter().flatten());
        }
    }
    seen.into_iter().map(|id| names[id].to_string()).collect()
}

const HEAVY: [&str; 5] = ["rusqlite", "libsqlite3-sys", "zip", "clap", "indicatif"];

#[test]
fn the_scenario_language_compiles_no_sqlite_zip_or_clap() {
    let meta = metadata(&root().join("Cargo.toml"), true);
    let user = compiled(&meta, "library-user");
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
    let cli = compiled(&meta, "ppmc-cli");
    assert!(cli.contains("rusqlite") && cli.contains("clap"), "{cli:?}");
}

/// The fuzz crate (outside the workspace: it needs nightly) declares only
/// `ppmc` of ppmc's crates, and `ppmc` compiles no SQLite: the fuzz
/// targets build without it.
#[test]
fn the_fuzz_crate_builds_on_the_harness_alone() {
    let fuzz = metadata(&root().join("fuzz/Cargo.toml"), false);
    let deps: BTreeSet<String> = fuzz["packages"][0]["dependencies"]
        .as_array()
        .expect("dependencies")
        .iter()
        .map(|d| d["name"].as_str().expect("a name").to_string())
        .filter(|d| d.starts_with("ppmc"))
        .collect();
    assert_eq!(deps, BTreeSet::from(["ppmc".to_string()]));
    let meta = metadata(&root().join("Cargo.toml"), true);
    let harness = compiled(&meta, "ppmc");
    for heavy in HEAVY {
        assert!(!harness.contains(heavy), "ppmc compiles {heavy}");
    }
}
