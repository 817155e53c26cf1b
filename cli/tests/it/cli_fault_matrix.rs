//! `ppmc fault-matrix` as a user runs it (the matrix itself is checked in
//! process by the `ppmc` crate's tests/fault_matrix.rs).

use ppmc::faults::CATALOGUE;
use std::path::Path;
use std::process::Command;

/// The command over the pty, as a user runs it, on two faults.
#[test]
fn the_command_runs_over_the_pty() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .current_dir(&root)
        .args([
            "fault-matrix",
            "--fault",
            "dir-inverted",
            "--fault",
            "status-bit3-stuck",
        ])
        .output()
        .expect("ppmc runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("| clean | - | - | - | - | - | no false alarm |"),
        "{text}"
    );
    assert!(text.contains("| dir-inverted |"), "{text}");
    // The capture column: dir-inverted caught (DIR at a pulse, 3-3-1),
    // the scenario too long for a capture named, and why
    // status-bit3-stuck, refused by the health check, is judged all the
    // same.
    let row = |board: &str| {
        text.lines()
            .find(|l| l.starts_with(&format!("| {board} |")))
            .unwrap_or_else(|| panic!("{board}: {text}"))
            .split('|')
            .map(str::trim)
            .collect::<Vec<_>>()
    };
    assert!(row("dir-inverted")[6].ends_with(" ms"), "{text}");
    assert!(row("status-bit3-stuck")[6].ends_with(" ms"), "{text}");
    assert!(
        text.contains("not judged: `s3_3_4_accel_ffffff_is_16777216_steps`"),
        "{text}"
    );
    assert!(text.contains("every fault caught"), "{text}");
    let listed = Command::new(env!("CARGO_BIN_EXE_ppmc"))
        .args(["fault-matrix", "--list"])
        .output()
        .expect("ppmc runs");
    let list = String::from_utf8_lossy(&listed.stdout);
    assert_eq!(
        list.lines().filter(|l| l.starts_with("| `")).count(),
        CATALOGUE.len()
    );
}
