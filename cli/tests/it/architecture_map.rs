//! ARCHITECTURE.md cannot point at what is gone: every path it names in
//! backticks exists. A path from the repository's root (`core/...`,
//! `harness/...`, `docs/...`) must be there as written (`*` matches any
//! name); one relative to a crate (`cli/args.rs`, `twin/`) must end some
//! path of the repository; a bare file name (`ring.rs`) must be some
//! file's name.

use std::path::{Path, PathBuf};

/// The repository's top-level folders a rooted path starts with.
const ROOTS: [&str; 18] = [
    "contrib/",
    "core/",
    "files/",
    "record/",
    "report/",
    "logic/",
    "harness/",
    "capture/",
    "cli/",
    "test-support/",
    "scenarios/",
    "firmware/",
    "docs/",
    "examples/",
    "fuzz/",
    "golden/",
    "hardware/",
    "scripts/",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every file and folder of the repository, relative, `/`-separated;
/// folders end in `/`. Build output and version control left out.
fn tree(dir: &Path, rel: &str, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if matches!(name.as_str(), "target" | ".git" | "node_modules") {
            continue;
        }
        let path = format!("{rel}{name}");
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            out.push(format!("{path}/"));
            tree(&e.path(), &format!("{path}/"), out);
        } else {
            out.push(path);
        }
    }
}

/// `pattern` with `*` matching any run of characters but `/`.
fn matches(pattern: &str, path: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == path,
        Some((head, tail)) => {
            let Some(rest) = path.strip_prefix(head) else {
                return false;
            };
            (0..=rest.len()).any(|i| {
                rest.is_char_boundary(i) && !rest[..i].contains('/') && matches(tail, &rest[i..])
            })
        }
    }
}

/// The backticked words of `text` that look like paths.
fn named_paths(text: &str) -> Vec<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter(|w| {
            !w.contains(' ') && !w.contains("::") && !w.contains("://") && !w.starts_with('-')
        })
        .filter(|w| {
            w.contains('/')
                || [".rs", ".md", ".toml", ".json", ".sh", ".py"]
                    .iter()
                    .any(|x| w.ends_with(x))
        })
        .map(str::to_string)
        .collect()
}

#[test]
fn every_path_architecture_md_names_exists() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let mut all = Vec::new();
    tree(&root(), "", &mut all);
    let named = named_paths(&text);
    assert!(
        named.len() > 40,
        "{} paths found: the parser broke",
        named.len()
    );
    let missing: Vec<&String> = named
        .iter()
        .filter(|p| {
            let p = p.as_str();
            if ROOTS.iter().any(|r| p.starts_with(r)) {
                // A folder may be named with or without its `/`.
                !all.iter()
                    .any(|a| matches(p, a) || a.strip_suffix('/') == Some(p))
            } else if p.contains('/') {
                !all.iter()
                    .any(|a| a.ends_with(p) && a[..a.len() - p.len()].ends_with('/'))
            } else {
                !all.iter().any(|a| a == p || a.ends_with(&format!("/{p}")))
            }
        })
        .collect();
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names paths that do not exist: {missing:?}"
    );
}

#[test]
fn the_path_check_can_fail() {
    assert!(matches(
        "harness/tests/s3_*.rs",
        "harness/tests/s3_1_host_interface.rs"
    ));
    assert!(!matches(
        "harness/tests/s3_*.rs",
        "harness/tests/other/s3_1.rs"
    ));
    assert!(!matches("core/src/bridge/wire.rs", "core/src/bridge/wire/"));
    assert_eq!(
        named_paths("see `core/src/x.rs` and `Op::Reset`, `a b.rs`, `--target`, `ring.rs`"),
        ["core/src/x.rs", "ring.rs"]
    );
}
