//! Saleae Logic 2's binary export of digital channels, read as one stream
//! of level changes ([`Change`]) in bounded memory.
//!
//! [`SaleaeBinary`]: the binary export, one file per channel
//! (`digital_0.bin`, `digital_1.bin`, ...), as Saleae documents it: a
//! header (`<SALEAE>`, a version, type 0 for digital, all little-endian),
//! then in version 0 the initial state, the begin and end times (f64
//! seconds) and the transition times (f64 seconds, each toggling the
//! level); in version 1 a count of chunks, each with its initial state,
//! sample rate, begin and end times and transitions, a gap between two
//! chunks being no data (the channel is unknown there). The reader takes a
//! folder or a list of files and merges the channels: each file is read
//! as it goes (one buffer each), the earliest next transition taken from
//! them in turn. Times count from the capture's start, the earliest begin
//! time of any channel; a channel is unknown before its own begin. Version
//! 1 gives the sample rate (`sample_rate_hz`, when the channels agree on a
//! whole number of hertz); version 0 gives none, and its resolution is then
//! 1 ps. Errors name the channel's file and the byte offset.
//!
//! The CSV export is read by `saleae_csv.rs`.

use super::source::{Change, LogicError, LogicInfo, LogicSource, MAX_CHANNELS};
use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// What a binary file begins with.
const MAGIC: &[u8; 8] = b"<SALEAE>";

/// The level a channel takes at a time: `None` for no data.
type Event = (f64, Option<bool>);

/// One channel's file, read as it goes.
struct Channel {
    file: PathBuf,
    r: BufReader<File>,
    /// Bytes read so far.
    at: u64,
    /// Chunks after the current one.
    chunks_left: u64,
    /// Transitions left in the current chunk.
    left: u64,
    state: bool,
    begin: f64,
    end: f64,
    last: f64,
    /// Events read but not yet given: a chunk's start, a gap.
    queued: Vec<Event>,
    /// The next event, in picoseconds from the capture's start.
    head: Option<(u64, Option<bool>)>,
}

/// A chunk's header: initial state, sample rate, begin, end, transitions.
struct Chunk {
    state: bool,
    rate: Option<f64>,
    begin: f64,
    end: f64,
    n: u64,
}

impl Channel {
    fn err(&self, what: impl Into<String>) -> LogicError {
        LogicError::new(&self.file, format!("byte {}", self.at), what)
    }

    fn bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N], LogicError> {
        let mut b = [0u8; N];
        match self.r.read_exact(&mut b) {
            Ok(()) => {
                self.at += N as u64;
                Ok(b)
            }
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => {
                Err(self.err(format!("the file ends inside {what} (truncated)")))
            }
            Err(e) => Err(self.err(format!("cannot read: {e}"))),
        }
    }

    fn u32(&mut self, what: &str) -> Result<u32, LogicError> {
        self.bytes::<4>(what).map(u32::from_le_bytes)
    }

    fn u64(&mut self, what: &str) -> Result<u64, LogicError> {
        self.bytes::<8>(what).map(u64::from_le_bytes)
    }

    fn f64(&mut self, what: &str) -> Result<f64, LogicError> {
        let at = self.at;
        let v = self.bytes::<8>(what).map(f64::from_le_bytes)?;
        match v.is_finite() {
            true => Ok(v),
            false => Err(LogicError::new(
                &self.file,
                format!("byte {at}"),
                format!("{what} is {v}, not a time"),
            )),
        }
    }

    /// A chunk's header (version 0 has one, without a sample rate).
    fn chunk(&mut self, version: u32) -> Result<Chunk, LogicError> {
        let state = match self.u32("the initial state")? {
            0 => false,
            1 => true,
            s => return Err(self.err(format!("initial state {s}, not 0 or 1"))),
        };
        let rate = match version {
            0 => None,
            _ => Some(self.f64("the sample rate")?),
        };
        let (begin, end) = (self.f64("the begin time")?, self.f64("the end time")?);
        if end < begin {
            return Err(self.err(format!(
                "the end time {end} s is before the begin time {begin} s"
            )));
        }
        let n = self.u64("the transition count")?;
        Ok(Chunk {
            state,
            rate,
            begin,
            end,
            n,
        })
    }

    /// Opens a channel's file and reads its header and first chunk's.
    fn open(file: &Path) -> Result<(Channel, u32, Option<Chunk>), LogicError> {
        let f = ppmc_files::open_stream(file).map_err(|e| LogicError::opening(file, e))?;
        let len = f.metadata().map(|m| m.len()).unwrap_or(u64::MAX);
        let mut c = Channel {
            file: file.to_path_buf(),
            r: BufReader::new(f),
            at: 0,
            chunks_left: 0,
            left: 0,
            state: false,
            begin: f64::INFINITY,
            end: f64::NEG_INFINITY,
            last: f64::NEG_INFINITY,
            queued: Vec::new(),
            head: None,
        };
        if &c.bytes::<8>("the header")? != MAGIC {
            return Err(LogicError::new(
                file,
                "byte 0",
                "not a Saleae binary export (no <SALEAE>)",
            ));
        }
        let version = c.u32("the header")?;
        if version > 1 {
            return Err(LogicError::new(
                file,
                "byte 8",
                format!("version {version}: versions 0 and 1 are read"),
            ));
        }
        match c.u32("the header")? {
            0 => {}
            1 => {
                return Err(LogicError::new(
                    file,
                    "byte 12",
                    "an analog export: only digital ones are read",
                ))
            }
            t => {
                return Err(LogicError::new(
                    file,
                    "byte 12",
                    format!("data type {t}, not 0 (digital)"),
                ))
            }
        }
        let first = match version {
            0 => {
                let ch = c.chunk(0)?;
                // Version 0 is a header and the transitions: its length is known.
                let want = ch.n.checked_mul(8).and_then(|b| b.checked_add(c.at));
                if want != Some(len) {
                    let holds = len.saturating_sub(c.at) / 8;
                    return Err(LogicError::new(
                        file,
                        "byte 36",
                        format!(
                            "the header says {} transitions, the file's {len} bytes hold {holds}",
                            ch.n
                        ),
                    ));
                }
                Some(ch)
            }
            _ => match c.u64("the chunk count")? {
                0 => None,
                n => {
                    c.chunks_left = n - 1;
                    Some(c.chunk(1)?)
                }
            },
        };
        if let Some(ch) = &first {
            c.enter(ch);
        }
        Ok((c, version, first))
    }

    /// Starts a chunk: its initial state at its begin time.
    fn enter(&mut self, ch: &Chunk) {
        self.state = ch.state;
        self.left = ch.n;
        self.begin = self.begin.min(ch.begin);
        self.end = self.end.max(ch.end);
        self.last = ch.begin;
        self.queued.push((ch.begin, Some(ch.state)));
    }

    /// The channel's next event, in file order.
    fn next_event(&mut self) -> Result<Option<Event>, LogicError> {
        loop {
            if !self.queued.is_empty() {
                return Ok(Some(self.queued.remove(0)));
            }
            if self.left > 0 {
                let t = self.f64("a transition time")?;
                if t < self.last {
                    return Err(self.err(format!(
                        "a transition at {t} s, before the one before it ({} s)",
                        self.last
                    )));
                }
                if t > self.end {
                    return Err(self.err(format!(
                        "a transition at {t} s, after the chunk's end ({} s)",
                        self.end
                    )));
                }
                self.left -= 1;
                self.last = t;
                self.state = !self.state;
                return Ok(Some((t, Some(self.state))));
            }
            if self.chunks_left == 0 {
                return match self.r.fill_buf() {
                    Ok([]) => Ok(None),
                    Ok(_) => Err(self.err("bytes after the last transition")),
                    Err(e) => Err(self.err(format!("cannot read: {e}"))),
                };
            }
            self.chunks_left -= 1;
            let ch = self.chunk(1)?;
            if ch.begin < self.end {
                return Err(self.err(format!(
                    "a chunk begins at {} s, before the last one's end ({} s)",
                    ch.begin, self.end
                )));
            }
            if ch.begin > self.end {
                self.queued.push((self.end, None));
            }
            self.enter(&ch);
        }
    }

    /// Reads the next event into `head`.
    fn advance(&mut self, start: f64) -> Result<(), LogicError> {
        self.head = match self.next_event()? {
            None => None,
            Some((t, level)) => Some((
                to_ps(t, start).ok_or_else(|| self.err(format!("time {t} s is out of range")))?,
                level,
            )),
        };
        Ok(())
    }
}

/// Seconds from `start` to picoseconds, rounded.
fn to_ps(t: f64, start: f64) -> Option<u64> {
    let ps = ((t - start) * 1e12).round();
    (0.0..1.8e19).contains(&ps).then_some(ps as u64)
}

/// Saleae Logic 2's binary export of digital channels.
pub struct SaleaeBinary {
    info: LogicInfo,
    channels: Vec<Channel>,
    start: f64,
    levels: u64,
    unknown: u64,
    last: Option<(u64, u64)>,
    end_ps: u64,
}

impl fmt::Debug for SaleaeBinary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let files: Vec<&PathBuf> = self.channels.iter().map(|c| &c.file).collect();
        f.debug_struct("SaleaeBinary")
            .field("info", &self.info)
            .field("files", &files)
            .finish_non_exhaustive()
    }
}

impl SaleaeBinary {
    /// Opens an export: a folder (its `digital_N.bin` files, by channel
    /// number) or one file.
    pub fn open(path: &Path) -> Result<SaleaeBinary, LogicError> {
        if !path.is_dir() {
            return SaleaeBinary::open_files(&[path.to_path_buf()]);
        }
        let entries = std::fs::read_dir(path)
            .map_err(|e| LogicError::new(path, "", format!("cannot list the folder: {e}")))?;
        let mut found: Vec<(u64, PathBuf)> = entries
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                let n = name
                    .strip_prefix("digital_")?
                    .strip_suffix(".bin")?
                    .parse()
                    .ok()?;
                Some((n, e.path()))
            })
            .collect();
        if found.is_empty() {
            return Err(LogicError::new(
                path,
                "",
                "no digital_N.bin file in the folder: not a Saleae binary export",
            ));
        }
        found.sort();
        let files: Vec<PathBuf> = found.into_iter().map(|(_, p)| p).collect();
        SaleaeBinary::open_files(&files)
    }

    /// Opens the files of an export, one channel each, in this order.
    pub fn open_files(files: &[PathBuf]) -> Result<SaleaeBinary, LogicError> {
        let Some(first) = files.first() else {
            return Err(LogicError::new(Path::new("."), "", "no file to read"));
        };
        if files.len() > MAX_CHANNELS {
            return Err(LogicError::new(
                first,
                "",
                format!(
                    "{} channel files; at most {MAX_CHANNELS} can be read",
                    files.len()
                ),
            ));
        }
        let mut channels = Vec::new();
        let mut names = Vec::new();
        let mut versions = Vec::new();
        let mut rates = Vec::new();
        for f in files {
            let (c, version, chunk) = Channel::open(f)?;
            let stem = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            names.push(match stem.strip_prefix("digital_") {
                Some(n) if n.parse::<u64>().is_ok() => format!("Channel {n}"),
                _ => stem,
            });
            if !versions.contains(&version) {
                versions.push(version);
            }
            rates.extend(chunk.and_then(|ch| ch.rate));
            channels.push(c);
        }
        let start = channels
            .iter()
            .map(|c| c.begin)
            .fold(f64::INFINITY, f64::min);
        if !start.is_finite() {
            return Err(LogicError::new(
                first,
                "",
                "no channel holds any data (no chunks)",
            ));
        }
        for c in &mut channels {
            c.advance(start)?;
        }
        let fastest = rates.iter().copied().fold(0.0, f64::max);
        let whole = |r: f64| r >= 1.0 && r.fract() == 0.0 && r < 1e15;
        let sample_rate_hz = match rates.first() {
            Some(&r) if whole(r) && rates.iter().all(|&o| o == r) => Some(r as u64),
            _ => None,
        };
        let resolution_ps = match fastest > 0.0 {
            true => ((1e12 / fastest).round() as u64).max(1),
            false => 1,
        };
        versions.sort();
        let v: Vec<String> = versions.iter().map(u32::to_string).collect();
        let format = match v.len() {
            1 => format!("Saleae Logic 2 binary (version {})", v[0]),
            _ => format!("Saleae Logic 2 binary (versions {})", v.join(" and ")),
        };
        Ok(SaleaeBinary {
            info: LogicInfo {
                channels: names,
                resolution_ps,
                sample_rate_hz,
                format,
            },
            unknown: ones(channels.len()),
            channels,
            start,
            levels: 0,
            last: None,
            end_ps: 0,
        })
    }
}

/// The low `n` bits set.
fn ones(n: usize) -> u64 {
    match n {
        n if n >= 64 => u64::MAX,
        n => (1u64 << n) - 1,
    }
}

impl LogicSource for SaleaeBinary {
    fn info(&self) -> &LogicInfo {
        &self.info
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        loop {
            let Some(t) = self
                .channels
                .iter()
                .filter_map(|c| c.head.map(|h| h.0))
                .min()
            else {
                let end = self
                    .channels
                    .iter()
                    .map(|c| c.end)
                    .fold(self.start, f64::max);
                self.end_ps = to_ps(end, self.start).unwrap_or(u64::MAX);
                return Ok(None);
            };
            for i in 0..self.channels.len() {
                while let Some((_, level)) = self.channels[i].head.filter(|h| h.0 == t) {
                    let bit = 1u64 << i;
                    match level {
                        Some(high) => {
                            self.unknown &= !bit;
                            self.levels = if high {
                                self.levels | bit
                            } else {
                                self.levels & !bit
                            };
                        }
                        None => {
                            self.unknown |= bit;
                            self.levels &= !bit;
                        }
                    }
                    self.channels[i].advance(self.start)?;
                }
            }
            let state = (self.levels, self.unknown);
            if self.last != Some(state) {
                self.last = Some(state);
                return Ok(Some(Change {
                    time_ps: t,
                    levels: self.levels,
                    unknown: self.unknown,
                }));
            }
        }
    }

    fn end_ps(&self) -> u64 {
        self.end_ps
    }
}

#[cfg(test)]
mod tests {
    use super::super::source::testing::{ch, drain, Read};
    use super::*;
    use proptest::prelude::*;

    fn header(version: i32) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend(version.to_le_bytes());
        b.extend(0i32.to_le_bytes());
        b
    }

    fn v0(initial: u32, begin: f64, end: f64, times: &[f64]) -> Vec<u8> {
        let mut b = header(0);
        b.extend(initial.to_le_bytes());
        b.extend(begin.to_le_bytes());
        b.extend(end.to_le_bytes());
        b.extend((times.len() as u64).to_le_bytes());
        times.iter().for_each(|t| b.extend(t.to_le_bytes()));
        b
    }

    /// Chunks of (initial state, sample rate, begin, end, transitions).
    fn v1(chunks: &[(u32, f64, f64, f64, &[f64])]) -> Vec<u8> {
        let mut b = header(1);
        b.extend((chunks.len() as u64).to_le_bytes());
        for &(initial, rate, begin, end, times) in chunks {
            b.extend(initial.to_le_bytes());
            b.extend(rate.to_le_bytes());
            b.extend(begin.to_le_bytes());
            b.extend(end.to_le_bytes());
            b.extend((times.len() as u64).to_le_bytes());
            times.iter().for_each(|t| b.extend(t.to_le_bytes()));
        }
        b
    }

    fn write(files: &[Vec<u8>]) -> (tempfile::TempDir, Vec<PathBuf>) {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let paths = files
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let p = dir.path().join(format!("digital_{i}.bin"));
                std::fs::write(&p, b).expect("written");
                p
            })
            .collect();
        (dir, paths)
    }

    fn read(files: &[Vec<u8>]) -> Result<Read, LogicError> {
        let (_dir, paths) = write(files);
        drain(&mut SaleaeBinary::open_files(&paths)?)
    }

    #[test]
    fn version_0_channels_merge_into_one_stream() {
        let (info, changes, end) = read(&[
            v0(0, -1e-6, 1e-3, &[0.0, 1e-6]),
            v0(1, -1e-6, 1e-3, &[0.5e-6, 1e-6]),
        ])
        .expect("reads");
        assert_eq!(info.channels, ["Channel 0", "Channel 1"]);
        assert_eq!(info.format, "Saleae Logic 2 binary (version 0)");
        assert_eq!((info.resolution_ps, info.sample_rate_hz), (1, None));
        assert_eq!(
            changes,
            [
                ch(0, 0b10, 0),
                ch(1_000_000, 0b11, 0),
                ch(1_500_000, 0b01, 0),
                ch(2_000_000, 0b10, 0)
            ]
        );
        assert_eq!(end, 1_001_000_000);
    }

    #[test]
    fn version_1_gaps_are_unknown_and_a_late_channel_is_unknown_until_it_begins() {
        let (info, changes, end) = read(&[
            v1(&[
                (1, 1e6, 0.0, 10e-6, &[5e-6]),
                (1, 1e6, 20e-6, 30e-6, &[25e-6]),
            ]),
            v1(&[(0, 1e6, 3e-6, 30e-6, &[])]),
        ])
        .expect("reads");
        assert_eq!(info.format, "Saleae Logic 2 binary (version 1)");
        assert_eq!(
            (info.resolution_ps, info.sample_rate_hz),
            (1_000_000, Some(1_000_000))
        );
        let us = 1_000_000;
        assert_eq!(
            changes,
            [
                ch(0, 0b01, 0b10),
                ch(3 * us, 0b01, 0),
                ch(5 * us, 0, 0),
                ch(10 * us, 0, 0b01),
                ch(20 * us, 0b01, 0),
                ch(25 * us, 0, 0)
            ]
        );
        assert_eq!(end, 30 * us);
        // Channels of both versions, rates that are no whole number.
        let (info, _, _) =
            read(&[v0(0, 0.0, 1.0, &[]), v1(&[(0, 2.5e6 / 3.0, 0.0, 1.0, &[])])]).expect("reads");
        assert_eq!(info.format, "Saleae Logic 2 binary (versions 0 and 1)");
        assert_eq!((info.resolution_ps, info.sample_rate_hz), (1_200_000, None));
    }

    #[test]
    fn a_folder_is_read_by_channel_number() {
        let dir = tempfile::tempdir().expect("a temporary folder");
        for (name, initial) in [("digital_10.bin", 1), ("digital_2.bin", 0)] {
            std::fs::write(dir.path().join(name), v0(initial, 0.0, 1.0, &[])).expect("written");
        }
        std::fs::write(dir.path().join("analog_0.bin"), b"not read").expect("written");
        let mut r = SaleaeBinary::open(dir.path()).expect("opens");
        assert_eq!(r.info().channels, ["Channel 2", "Channel 10"]);
        assert_eq!(r.next_change(), Ok(Some(ch(0, 0b10, 0))));
        let empty = tempfile::tempdir().expect("a temporary folder");
        let e = SaleaeBinary::open(empty.path()).expect_err("no files");
        assert!(e.to_string().contains("no digital_N.bin file"), "{e}");
    }

    #[test]
    fn bad_files_are_errors_naming_the_byte() {
        let mut analog = header(0);
        analog[12] = 1;
        let mut nan = v0(0, 0.0, 1.0, &[0.5]);
        let n = nan.len();
        nan[n - 8..].copy_from_slice(&f64::NAN.to_le_bytes());
        let mut short = v0(0, 0.0, 1.0, &[0.1, 0.2, 0.3]);
        short.truncate(short.len() - 8);
        let mut trailing = v1(&[(0, 1e6, 0.0, 1.0, &[0.5])]);
        trailing.push(0);
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (Vec::new(), "byte 0: the file ends inside the header"),
            (
                b"<SALEAE".to_vec(),
                "byte 0: the file ends inside the header",
            ),
            (
                b"GARBAGE!xxxxxxxxxxxxxxxx".to_vec(),
                "byte 0: not a Saleae binary export",
            ),
            (header(2), "byte 8: version 2"),
            (analog, "byte 12: an analog export"),
            (
                short,
                "byte 36: the header says 3 transitions, the file's 60 bytes hold 2",
            ),
            (v0(2, 0.0, 1.0, &[]), "byte 20: initial state 2"),
            (v0(0, 1.0, 0.0, &[]), "is before the begin time"),
            (nan, "byte 44: a transition time is NaN, not a time"),
            (
                v0(0, 0.0, 1.0, &[0.5, 0.25]),
                "byte 60: a transition at 0.25 s, before the one before it (0.5 s)",
            ),
            (
                v0(0, 0.0, 1.0, &[2.0]),
                "byte 52: a transition at 2 s, after the chunk's end (1 s)",
            ),
            (
                v1(&[(0, 1e6, 0.0, 1.0, &[0.5])])[..60].to_vec(),
                "byte 60: the file ends inside a transition time (truncated)",
            ),
            (trailing, "byte 68: bytes after the last transition"),
            (
                v1(&[(0, 1e6, 0.0, 1.0, &[]), (0, 1e6, 0.5, 2.0, &[])]),
                "a chunk begins at 0.5 s, before the last one's end (1 s)",
            ),
            (v1(&[]), "no channel holds any data"),
        ];
        for (bytes, want) in cases {
            let e = read(&[bytes]).expect_err(want).to_string();
            assert!(
                e.contains("digital_0.bin") && e.contains(want),
                "{want}: {e}"
            );
        }
        let many: Vec<PathBuf> = (0..65)
            .map(|i| PathBuf::from(format!("digital_{i}.bin")))
            .collect();
        let e = SaleaeBinary::open_files(&many)
            .expect_err("too many")
            .to_string();
        assert!(e.contains("65 channel files; at most 64"), "{e}");
        let e = SaleaeBinary::open(Path::new("/nonexistent/digital_0.bin")).expect_err("missing");
        assert!(
            e.to_string().starts_with("/nonexistent/digital_0.bin: "),
            "{e}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// A good file with bytes changed or cut: changes or an error,
        /// never a panic.
        #[test]
        fn damaged_files_never_panic(
            edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..4),
            cut in any::<usize>(),
            version in 0..2u8,
        ) {
            let mut b = match version {
                0 => v0(1, 0.0, 1e-3, &[1e-4, 2e-4, 3e-4]),
                _ => v1(&[(1, 1e6, 0.0, 1e-4, &[5e-5]), (0, 1e6, 2e-4, 1e-3, &[3e-4, 4e-4])]),
            };
            for (at, v) in edits {
                let n = b.len();
                b[at % n] = v;
            }
            let n = b.len();
            b.truncate(n - cut % 9);
            let _ = read(&[b]);
        }
    }
}
