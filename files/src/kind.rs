//! What a file holds, told by its first bytes: the kinds of file ppmc
//! writes, so that a report never replaces a file of another kind (a
//! results store, a golden trace, another report, a file of the user's).

use crate::{Action, FileError};
use std::io::Read;
use std::path::Path;

/// A kind of file ppmc writes, or another.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A JUnit report (`--junit`).
    Junit,
    /// A JSON run record (`--json`).
    Json,
    /// An HTML report of ppmc's (`--html`, `ppmc report`).
    Html,
    /// A results store (SQLite, `--store`).
    Store,
    /// A golden trace (`ppmc record`).
    Golden,
    /// None of ppmc's.
    Other,
}

impl Kind {
    /// What it is, for a sentence.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Junit => "a JUnit report",
            Kind::Json => "a JSON run record",
            Kind::Html => "an HTML report of ppmc's",
            Kind::Store => "a results store (SQLite)",
            Kind::Golden => "a golden trace",
            Kind::Other => "not a report of ppmc's",
        }
    }

    /// The kind of a file that begins with `head`.
    pub fn of_head(head: &[u8]) -> Kind {
        let text = String::from_utf8_lossy(head);
        let text = text.trim_start_matches('\u{feff}').trim_start();
        if head.starts_with(b"SQLite format 3\0") {
            Kind::Store
        } else if text.starts_with("ppmc-trace ")
            || (text.starts_with("---") && text.contains("\nppmc-trace "))
        {
            Kind::Golden
        } else if text.starts_with("<?xml") && text.contains("<testsuite") {
            Kind::Junit
        } else if text.starts_with('{') && text.contains("\"ppmc-run-record/") {
            Kind::Json
        } else if text.starts_with("<!DOCTYPE html") && text.contains("<title>ppmc ") {
            Kind::Html
        } else {
            Kind::Other
        }
    }
}

/// The kind of the file at `path`, from its first 4 KiB; `None` when there
/// is no regular file there or it is empty (nothing a write would destroy).
/// A link is not followed.
pub fn of(path: &Path) -> Result<Option<Kind>, FileError> {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(None);
    };
    if !meta.is_file() || meta.len() == 0 {
        return Ok(None);
    }
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map_err(FileError::io(path, Action::Reading))?;
    Ok(Some(Kind::of_head(&head)))
}

/// Whether a report of `kind` may be written over `path`: nothing there,
/// an empty file, or a report of that kind. `Err` names what is there
/// instead (a results store, a golden trace, another kind of report, a
/// file of the user's), or why it could not be read.
pub fn may_replace(path: &Path, kind: Kind) -> Result<(), String> {
    match of(path) {
        Err(e) => Err(e.to_string()),
        Ok(Some(k)) if k != kind => Err(format!(
            "{}: the file is {}, not {}: refusing to replace it (give another path, or remove the file first)",
            path.display(),
            k.name(),
            kind.name()
        )),
        Ok(_) => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_is_told_by_its_first_bytes() {
        let cases: [(&[u8], Kind); 7] = [
            (b"SQLite format 3\0\x10\x00", Kind::Store),
            (b"ppmc-trace 1\nscenario x\n", Kind::Golden),
            (
                b"---\nsource: harness/tests/golden.rs\n---\nppmc-trace 1\n",
                Kind::Golden,
            ),
            (
                b"<?xml version=\"1.0\"?>\n<testsuites name=\"ppmc\">",
                Kind::Junit,
            ),
            (b"{\n  \"format\": \"ppmc-run-record/4\",", Kind::Json),
            (
                b"<!DOCTYPE html>\n<html><head><title>ppmc run report</title>",
                Kind::Html,
            ),
            (b"{\"a\": 1}", Kind::Other),
        ];
        for (head, kind) in cases {
            assert_eq!(
                Kind::of_head(head),
                kind,
                "{}",
                String::from_utf8_lossy(head)
            );
        }
    }
}
