//! Every file ppmc reads or writes goes through here, so that a lab can
//! trust what it finds on disk:
//!
//! - a write goes to a temporary file created exclusively in the
//!   destination's folder (a symlink planted at any name is never followed),
//!   then is renamed into place, so a reader sees the old file or the new
//!   one, never half; on any error the temporary file is removed;
//! - the rename replaces a regular file only: a directory, a symlink, a
//!   FIFO or a device at the destination is refused by name;
//! - [`create_new`] never replaces anything, not even a dangling symlink:
//!   the new file is linked into place only if the name is free, so of two
//!   processes creating one file, one creates it and the other is told;
//! - [`check_writable`] and [`prepare_folder`] try, before a long run, what
//!   the writes at its end will do (a read-only folder, a parent that is a
//!   regular file), so that a run's work is never lost to a bad path;
//!   [`same_file`] tells two spellings of one output apart from two files;
//! - a read takes regular files only (never blocks on a FIFO, never reads
//!   `/dev/zero` until memory runs out) and refuses one beyond a size limit;
//! - every error names the path and what was being done to it.

pub mod kind;

use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// The largest trace or golden file ppmc reads. The suite's longest trace
/// is a few kilobytes: runs of equal pulses are one line.
pub const MAX_TRACE_BYTES: u64 = 64 << 20;

/// The largest fuzz input or console script ppmc reads.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// What ppmc was doing to a file when it failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    Reading,
    CreatingFolder,
    CreatingTemporary,
    Writing,
    Syncing,
    Renaming,
    Creating,
    /// Trying, before a run, whether a file can be created in a folder.
    Probing,
    /// Creating, before a run, a folder that outputs go into.
    PreparingFolder,
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Action::Reading => "cannot read",
            Action::CreatingFolder => "cannot create its folder",
            Action::CreatingTemporary => "cannot create a temporary file beside it",
            Action::Writing => "cannot write",
            Action::Syncing => "cannot flush to disk",
            Action::Renaming => "cannot move the new file into place",
            Action::Creating => "cannot create",
            Action::Probing => "cannot create files in its folder",
            Action::PreparingFolder => "cannot create this folder",
        })
    }
}

/// A file that could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("{}: {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: Action,
        #[source]
        source: io::Error,
    },
    /// The destination exists and is not a regular file.
    #[error(
        "{}: is {kind}; ppmc only replaces regular files (remove it or choose another path)",
        path.display()
    )]
    NotRegularDestination { path: PathBuf, kind: &'static str },
    /// The source is not a regular file.
    #[error("{}: is {kind}, not a regular file", path.display())]
    NotRegularSource { path: PathBuf, kind: &'static str },
    /// The source is larger than ppmc reads.
    #[error("{}: larger than {limit} bytes, the most ppmc reads from one file", path.display())]
    TooLarge { path: PathBuf, limit: u64 },
    /// The source is not UTF-8 text.
    #[error("{}: not UTF-8 text (byte {offset})", path.display())]
    NotText { path: PathBuf, offset: usize },
    /// [`create_new`] found something at the path.
    #[error("{}: exists; ppmc does not replace it", path.display())]
    Exists { path: PathBuf },
    /// A folder on the way to the path is something else (a regular file).
    #[error("{}: {} is {kind}, not a folder", path.display(), folder.display())]
    NotAFolder {
        path: PathBuf,
        folder: PathBuf,
        kind: &'static str,
    },
}

impl FileError {
    fn io(path: &Path, action: Action) -> impl FnOnce(io::Error) -> FileError + '_ {
        move |source| FileError::Io {
            path: path.to_path_buf(),
            action,
            source,
        }
    }

    /// Whether the file was simply not there.
    pub fn is_not_found(&self) -> bool {
        matches!(self, FileError::Io { source, .. } if source.kind() == io::ErrorKind::NotFound)
    }

    /// The path the error is about.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Io { path, .. }
            | FileError::NotRegularDestination { path, .. }
            | FileError::NotRegularSource { path, .. }
            | FileError::TooLarge { path, .. }
            | FileError::NotText { path, .. }
            | FileError::Exists { path }
            | FileError::NotAFolder { path, .. } => path,
        }
    }
}

/// What a file system entry is, in words, when it is not a regular file.
fn kind_of(t: fs::FileType) -> Option<&'static str> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    if t.is_symlink() {
        Some("a symbolic link")
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_file() {
        None
    } else {
        Some("not a regular file")
    }
}

/// Opens `path` for reading without blocking on a FIFO.
fn open_for_reading(path: &Path) -> io::Result<File> {
    let mut opts = fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // O_NONBLOCK: opening a FIFO with no writer returns at once; the
        // file type check below then refuses it. Regular files ignore it.
        opts.custom_flags(libc::O_NONBLOCK);
    }
    opts.open(path)
}

/// Reads a regular file of at most `limit` bytes (symlinks to one are
/// followed).
pub fn read(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let file = open_for_reading(path).map_err(FileError::io(path, Action::Reading))?;
    let meta = file
        .metadata()
        .map_err(FileError::io(path, Action::Reading))?;
    if let Some(kind) = kind_of(meta.file_type()) {
        return Err(FileError::NotRegularSource {
            path: path.to_path_buf(),
            kind,
        });
    }
    if meta.len() > limit {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            limit,
        });
    }
    let mut bytes = Vec::new();
    // The file may grow while we read: take one byte past the limit to see.
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(FileError::io(path, Action::Reading))?;
    if bytes.len() as u64 > limit {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            limit,
        });
    }
    Ok(bytes)
}

/// Reads a regular file of UTF-8 text of at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String, FileError> {
    String::from_utf8(read(path, limit)?).map_err(|e| FileError::NotText {
        path: path.to_path_buf(),
        offset: e.utf8_error().valid_up_to(),
    })
}

/// Opens a regular file for reading as a stream, for a file too large to
/// hold (a logic-analyzer capture): no size limit, but never a FIFO or a
/// device (symlinks to a regular file are followed).
pub fn open_stream(path: &Path) -> Result<File, FileError> {
    let file = open_for_reading(path).map_err(FileError::io(path, Action::Reading))?;
    let meta = file
        .metadata()
        .map_err(FileError::io(path, Action::Reading))?;
    match kind_of(meta.file_type()) {
        Some(kind) => Err(FileError::NotRegularSource {
            path: path.to_path_buf(),
            kind,
        }),
        None => Ok(file),
    }
}

/// Whether a look-up failed because nothing is at the path: not there, or
/// a folder on the way is not a folder (which [`check_writable`] then names).
fn gone(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
    )
}

/// Refuses a destination that exists and is not a regular file; returns
/// the permissions of the regular file it will replace.
fn check_destination(path: &Path) -> Result<Option<fs::Permissions>, FileError> {
    match fs::symlink_metadata(path) {
        Ok(meta) => match kind_of(meta.file_type()) {
            Some(kind) => Err(FileError::NotRegularDestination {
                path: path.to_path_buf(),
                kind,
            }),
            None => Ok(Some(meta.permissions())),
        },
        Err(e) if gone(&e) => Ok(None),
        Err(source) => Err(FileError::Io {
            path: path.to_path_buf(),
            action: Action::Reading,
            source,
        }),
    }
}

/// Checks that `path` holds nothing or a regular file, which a write may
/// replace (a symlink, a FIFO, a device or a directory is refused by name).
pub fn check_replaceable(path: &Path) -> Result<(), FileError> {
    check_destination(path).map(|_| ())
}

/// Checks, before a long run, that a report can later be written at `path`
/// (`-`, standard output, always can): nothing there or a regular file, and
/// a folder in which a file can be created (tried: a temporary file is
/// created there and removed). A folder not there yet is tried in the
/// nearest one that is, which the write will create it in; nothing is
/// created or left behind.
pub fn check_writable(path: &Path) -> Result<(), FileError> {
    if path.as_os_str() == "-" {
        return Ok(());
    }
    check_destination(path)?;
    let folder = nearest_folder(path, parent_of(path))?;
    probe(path, &folder)
}

/// Makes sure `dir` is a folder ppmc can write files into: created if it
/// is not there, then tried with a temporary file (removed at once).
pub fn prepare_folder(dir: &Path) -> Result<(), FileError> {
    nearest_folder(dir, dir)?;
    fs::create_dir_all(dir).map_err(FileError::io(dir, Action::PreparingFolder))?;
    probe(dir, dir)
}

/// The nearest folder that exists from `start` up (`start` itself, or the
/// one a write to `path` would create the rest in); an entry on the way
/// that is not a folder is refused by name.
fn nearest_folder(path: &Path, start: &Path) -> Result<PathBuf, FileError> {
    let mut folder = start.to_path_buf();
    loop {
        match fs::metadata(&folder) {
            Ok(meta) if meta.is_dir() => return Ok(folder),
            Ok(meta) => {
                return Err(FileError::NotAFolder {
                    path: path.to_path_buf(),
                    folder,
                    kind: kind_of(meta.file_type()).unwrap_or("a regular file"),
                })
            }
            Err(e) if gone(&e) => match folder.parent() {
                Some(up) if !up.as_os_str().is_empty() => folder = up.to_path_buf(),
                _ => return Ok(PathBuf::from(".")),
            },
            Err(source) => {
                return Err(FileError::Io {
                    path: path.to_path_buf(),
                    action: Action::Probing,
                    source,
                })
            }
        }
    }
}

/// Creates a temporary file exclusively in `folder` and removes it: the
/// folder takes new files (a read-only one does not, except for root).
fn probe(path: &Path, folder: &Path) -> Result<(), FileError> {
    tempfile::Builder::new()
        .prefix(".ppmc-probe.")
        .suffix(".tmp")
        .tempfile_in(folder)
        .map(drop)
        .map_err(FileError::io(path, Action::Probing))
}

/// The folder `path` is in (`.` for a bare name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// What names a file system entry, however its path is spelled.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    /// An existing entry: its device and inode (a hard link or a symlink
    /// to it is the same file).
    #[cfg(unix)]
    Inode(u64, u64),
    /// A name not there yet: its folder made absolute (symlinks resolved
    /// when the folder exists) and its own name.
    Name(PathBuf),
}

fn identity(path: &Path) -> Option<Identity> {
    #[cfg(unix)]
    if let Ok(meta) = fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        return Some(Identity::Inode(meta.dev(), meta.ino()));
    }
    let folder = parent_of(path);
    let folder = fs::canonicalize(folder)
        .or_else(|_| std::path::absolute(folder))
        .ok()?;
    Some(Identity::Name(folder.join(path.file_name()?)))
}

/// Whether `name`, a name a file or a record gave, is a plain file name
/// to write under: letters, digits, `-`, `_` and `.`, not starting with a
/// dot, at most 200 bytes (no folder, no `..`, nothing hidden).
pub fn plain_file_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 200
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
}

/// Whether `a` and `b` are one file: the same existing file (by device and
/// inode, so `./x`, `x`, a hard link and a symlink all match), or the same
/// name in the same folder when it is not there yet. `-` (standard output)
/// is no file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if a.as_os_str() == "-" || b.as_os_str() == "-" {
        return false;
    }
    match (identity(a), identity(b)) {
        (Some(x), Some(y)) => x == y,
        // A path that cannot even be made absolute: compare as written.
        _ => a == b,
    }
}

/// A temporary file beside `path`, created exclusively (`O_EXCL`, a random
/// name: a planted symlink is never followed) and removed if dropped.
fn temporary_beside(path: &Path) -> Result<tempfile::NamedTempFile, FileError> {
    let dir = parent_of(path);
    fs::create_dir_all(dir).map_err(FileError::io(dir, Action::CreatingFolder))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(FileError::io(path, Action::CreatingTemporary))
}

/// A temporary file beside `path` filled through `fill`, with the
/// permissions the new file will have (`old`'s, or 0644), flushed to disk.
/// Dropped on any error, so nothing is left behind.
fn filled_beside(
    path: &Path,
    old: Option<fs::Permissions>,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<tempfile::NamedTempFile, FileError> {
    let mut out = BufWriter::new(temporary_beside(path)?);
    fill(&mut out).map_err(FileError::io(path, Action::Writing))?;
    let tmp = out
        .into_inner()
        .map_err(|e| FileError::io(path, Action::Writing)(e.into_error()))?;
    set_permissions(&tmp, old)?;
    tmp.as_file()
        .sync_all()
        .map_err(FileError::io(path, Action::Syncing))?;
    Ok(tmp)
}

/// Fills a temporary file beside `path` through `fill`, then moves it into
/// place over nothing or over a regular file. On any error nothing is left
/// behind and the old file, if any, is untouched.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), FileError> {
    let old = check_destination(path)?;
    let tmp = filled_beside(path, old, fill)?;
    // Between the check and the rename, another process could put something
    // else there; the check is for mistakes, not for an attacker with write
    // access to the folder.
    tmp.persist(path)
        .map_err(|e| FileError::io(path, Action::Renaming)(e.error))?;
    Ok(())
}

/// Writes `bytes` to `path` as [`write_with`] does.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes a report to `path`, or to standard output when `path` is `-`.
pub fn write_report(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    if path.as_os_str() == "-" {
        let mut out = io::stdout().lock();
        return out
            .write_all(bytes)
            .and_then(|()| out.flush())
            .map_err(FileError::io(Path::new("<stdout>"), Action::Writing));
    }
    write(path, bytes)
}

/// Creates `path` with `bytes`, never replacing anything that is there (a
/// file, a directory, or a symlink, dangling or not).
pub fn create_new(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    if fs::symlink_metadata(path).is_ok() {
        return Err(FileError::Exists {
            path: path.to_path_buf(),
        });
    }
    let tmp = filled_beside(path, None, |w| w.write_all(bytes))?;
    // A hard link fails if anything, even a dangling symlink, has the name.
    tmp.persist_noclobber(path).map_err(|e| {
        if e.error.kind() == io::ErrorKind::AlreadyExists {
            FileError::Exists {
                path: path.to_path_buf(),
            }
        } else {
            FileError::io(path, Action::Creating)(e.error)
        }
    })?;
    Ok(())
}

/// The new file gets the permissions of the one it replaces, or the usual
/// 0644 (the temporary file is created 0600).
fn set_permissions(
    tmp: &tempfile::NamedTempFile,
    old: Option<fs::Permissions>,
) -> Result<(), FileError> {
    let perms = match old {
        Some(p) => p,
        None => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                fs::Permissions::from_mode(0o644)
            }
            #[cfg(not(unix))]
            return Ok(());
        }
    };
    tmp.as_file()
        .set_permissions(perms)
        .map_err(FileError::io(tmp.path(), Action::Writing))
}

/// A scratch folder for a test, removed when dropped (even by a failing
/// test).
#[doc(hidden)]
pub fn scratch(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("ppmc-{tag}-"))
        .tempdir()
        .expect("scratch dir")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn write_replaces_a_regular_file_and_leaves_nothing_behind() {
        let d = scratch("files");
        let p = d.path().join("a.txt");
        write(&p, b"one").expect("create");
        write(&p, b"two").expect("replace");
        assert_eq!(fs::read(&p).expect("read"), b"two");
        assert!(leftovers(d.path()).is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn write_refuses_a_symlink_fifo_or_directory_at_the_destination() {
        let d = scratch("files");
        let outside = d.path().join("outside.txt");
        fs::write(&outside, b"keep").expect("outside");
        let link = d.path().join("link.txt");
        std::os::unix::fs::symlink(&outside, &link).expect("symlink");
        let e = write(&link, b"x").expect_err("symlink refused");
        assert!(e.to_string().contains("a symbolic link"), "{e}");
        assert_eq!(fs::read(&outside).expect("read"), b"keep");
        let e = write(d.path(), b"x").expect_err("directory refused");
        assert!(e.to_string().contains("a directory"), "{e}");
        let e = write(Path::new("/dev/null"), b"x").expect_err("device refused");
        assert!(e.to_string().contains("a device"), "{e}");
        assert!(leftovers(d.path()).is_empty());
    }

    #[test]
    fn a_failed_fill_leaves_the_old_file_and_no_temporary() {
        let d = scratch("files");
        let p = d.path().join("r.json");
        write(&p, b"old").expect("create");
        let e = write_with(&p, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("disk full"))
        })
        .expect_err("fails");
        assert!(e.to_string().contains("cannot write"), "{e}");
        assert_eq!(fs::read(&p).expect("read"), b"old");
        assert!(leftovers(d.path()).is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn create_new_never_replaces_even_a_dangling_symlink() {
        let d = scratch("files");
        let p = d.path().join("s.rs");
        std::os::unix::fs::symlink(d.path().join("nowhere"), &p).expect("symlink");
        let e = create_new(&p, b"x").expect_err("refused");
        assert!(matches!(e, FileError::Exists { .. }), "{e}");
        assert!(!d.path().join("nowhere").exists());
        let q = d.path().join("t.rs");
        create_new(&q, b"x").expect("created");
        assert!(matches!(
            create_new(&q, b"y"),
            Err(FileError::Exists { .. })
        ));
        assert_eq!(fs::read(&q).expect("read"), b"x");
        assert!(leftovers(d.path()).is_empty());
    }

    #[test]
    fn check_writable_refuses_a_folder_that_is_a_file_or_a_directory_destination() {
        let d = scratch("files");
        let file = d.path().join("plain");
        fs::write(&file, b"x").expect("file");
        let e = check_writable(&file.join("report.xml")).expect_err("parent is a file");
        assert!(matches!(e, FileError::NotAFolder { .. }), "{e}");
        assert!(
            e.to_string()
                .contains("plain is a regular file, not a folder"),
            "{e}"
        );
        // Deeper under the file too, and the same for a folder to prepare.
        let e = check_writable(&file.join("a/b/report.xml")).expect_err("under a file");
        assert!(
            e.to_string()
                .contains("plain is a regular file, not a folder"),
            "{e}"
        );
        let e = prepare_folder(&file.join("arts")).expect_err("artifacts under a file");
        assert!(
            e.to_string()
                .contains("plain is a regular file, not a folder"),
            "{e}"
        );
        let e = prepare_folder(&file).expect_err("artifacts folder is a file");
        assert!(matches!(e, FileError::NotAFolder { .. }), "{e}");
        let e = check_writable(d.path()).expect_err("a directory");
        assert!(e.to_string().contains("a directory"), "{e}");
    }

    #[test]
    fn check_writable_creates_nothing_and_prepare_folder_creates_the_folder() {
        let d = scratch("files");
        check_writable(&d.path().join("new/deeper/r.json")).expect("can be written later");
        check_writable(&d.path().join("r.json")).expect("can be written");
        assert_eq!(
            fs::read_dir(d.path()).expect("dir").count(),
            0,
            "nothing left"
        );
        let arts = d.path().join("arts/board");
        prepare_folder(&arts).expect("created");
        assert!(arts.is_dir());
        assert_eq!(
            fs::read_dir(&arts).expect("dir").count(),
            0,
            "probe removed"
        );
        prepare_folder(&arts).expect("again");
    }

    /// A read-only folder is found before the run. Root writes into it all
    /// the same, so under root the test says so and checks nothing.
    #[cfg(unix)]
    #[test]
    fn check_writable_and_prepare_folder_find_a_read_only_folder() {
        use std::os::unix::fs::PermissionsExt;
        let d = scratch("files");
        let ro = d.path().join("ro");
        fs::create_dir(&ro).expect("dir");
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).expect("chmod");
        let root = fs::write(ro.join("probe"), b"").is_ok();
        if root {
            eprintln!("note: running as root, a read-only folder is writable; not checked");
        } else {
            let e = check_writable(&ro.join("r.xml")).expect_err("read-only");
            assert!(
                matches!(
                    e,
                    FileError::Io {
                        action: Action::Probing,
                        ..
                    }
                ),
                "{e}"
            );
            assert!(
                e.to_string()
                    .contains("r.xml: cannot create files in its folder"),
                "{e}"
            );
            let e = check_writable(&ro.join("sub/r.xml")).expect_err("read-only above");
            assert!(e.to_string().contains("cannot create files"), "{e}");
            assert!(prepare_folder(&ro).is_err());
        }
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).expect("chmod back");
    }

    #[cfg(unix)]
    #[test]
    fn same_file_sees_through_spellings_hard_links_and_symlinks() {
        let d = scratch("files");
        let x = d.path().join("x.json");
        let dotted = d.path().join(".").join("x.json");
        let up = d.path().join("sub").join("..").join("x.json");
        fs::create_dir(d.path().join("sub")).expect("sub");
        // Not there yet: the same name in the same folder.
        assert!(same_file(&x, &dotted));
        assert!(same_file(&x, &up));
        assert!(!same_file(&x, &d.path().join("y.json")));
        fs::write(&x, b"{}").expect("x");
        assert!(same_file(&x, &dotted));
        let hard = d.path().join("hard.json");
        fs::hard_link(&x, &hard).expect("hard link");
        assert!(same_file(&x, &hard));
        let soft = d.path().join("soft.json");
        std::os::unix::fs::symlink(&x, &soft).expect("symlink");
        assert!(same_file(&soft, &x));
        fs::write(d.path().join("y.json"), b"{}").expect("y");
        assert!(!same_file(&x, &d.path().join("y.json")));
        assert!(!same_file(Path::new("-"), Path::new("-")));
    }

    #[cfg(unix)]
    #[test]
    fn read_refuses_devices_and_big_files_and_missing_is_not_found() {
        let e = read(Path::new("/dev/zero"), 1024).expect_err("device");
        assert!(e.to_string().contains("a device"), "{e}");
        let d = scratch("files");
        let p = d.path().join("big");
        fs::write(&p, vec![b'x'; 100]).expect("write");
        assert!(matches!(read(&p, 99), Err(FileError::TooLarge { .. })));
        assert_eq!(read(&p, 100).expect("fits").len(), 100);
        let e = read(&d.path().join("none"), 10).expect_err("missing");
        assert!(e.is_not_found());
        fs::write(&p, [0xFF, 0xFE]).expect("write");
        assert!(matches!(read_text(&p, 10), Err(FileError::NotText { .. })));
    }

    #[cfg(unix)]
    #[test]
    fn read_refuses_a_fifo_without_blocking() {
        let d = scratch("files");
        let p = d.path().join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .expect("mkfifo runs");
        assert!(made.success());
        let e = read(&p, 10).expect_err("fifo");
        assert!(e.to_string().contains("a FIFO"), "{e}");
    }
}
