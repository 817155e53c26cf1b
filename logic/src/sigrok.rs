//! sigrok session files (`.sr`, version 2), as sigrok-cli and PulseView
//! save them (libsigrok's `srzip` output), read as one stream of level
//! changes: [`SigrokReader`], a [`LogicSource`].
//!
//! The file is a ZIP archive of `version` (the text `2`; version 1, from
//! libsigrok before 0.3, is refused by name), `metadata` and the samples.
//! `metadata` is a GLib key file whose `[device 1]` gives `capturefile`
//! (the samples' base name, `logic-1`; an analog-only capture has none),
//! `total probes` (logic channels, enabled or not), `samplerate` (`24 MHz`,
//! `1.5 kHz`, `200Hz`: [`parse_rate`]), `unitsize` (bytes per sample) and
//! `probeK=NAME` for each enabled channel K (1-based; a channel without
//! its line was disabled); analog channels (`analogK`, `analog-1-K-M`)
//! are ignored. The samples are `logic-1-1`, `logic-1-2`, ... (or one
//! `logic-1`) end to end, `unitsize` bytes each, little endian, bit K-1
//! for probe K; the chunks must run from 1 with no gap, each of whole
//! samples (libsigrok only warns). [`LogicInfo::channels`] are the enabled
//! channels in probe order; the bits of disabled ones are ignored.
//!
//! Memory stays bounded whatever the capture's length: the chunks are
//! decompressed in turn, in blocks of [`BLOCK_BYTES`], and only the
//! previous sample is kept. The scan compares 8 bytes at a time with the
//! previous sample repeated (unit sizes 1, 2, 4, 8); others go sample by
//! sample.
//!
//! The ZIP crate is `zip` (zip-rs/zip2), the maintained pure-Rust one,
//! with its deflate codec only (zlib-rs; libzip writes deflated or stored
//! entries): it checks each entry's CRC-32 and lends an entry as a `Read`
//! that decompresses as it is read. The entries are read from their local
//! headers in the file's order (`read_zipfile_from_stream`), once to find
//! them (the samples skipped, not decompressed) and once for the samples,
//! never through `ZipArchive`, which holds the whole central directory,
//! some 0.5 KB an entry: that would grow with the capture. libsigrok
//! writes the chunks in order, with their sizes in their local headers;
//! a file whose chunks are out of order, or which leaves the sizes to
//! data descriptors, is refused by name. An entry borrows the reader, so
//! no one value can keep both between two calls of
//! [`LogicSource::next_change`]: a thread owns the file and hands blocks
//! over a channel of [`BLOCKS_IN_FLIGHT`] (inflating on one core while
//! the scan runs on another) until the reader is dropped.
//!
//! Errors name the file and where (`line 5 of metadata`, `byte 4096 of
//! logic-1-3`); nothing panics.

use super::source::{Change, LogicError, LogicInfo, LogicSource, MAX_CHANNELS};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{ErrorKind, Read};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use zip::result::ZipError;

/// The bytes of one decompressed block (cut to whole samples).
pub const BLOCK_BYTES: usize = 256 << 10;

/// Blocks waiting in the channel at most: with the one being filled and
/// the one being scanned, memory is `(BLOCKS_IN_FLIGHT + 2) * BLOCK_BYTES`.
pub const BLOCKS_IN_FLIGHT: usize = 2;

/// The largest `metadata` entry read (sigrok's are a few hundred bytes).
const MAX_METADATA_BYTES: u64 = 1 << 20;

/// The `[device 1]` settings the reader uses.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Metadata {
    capturefile: String,
    rate: u64,
    unitsize: usize,
    /// Bit (probe number - 1) and name of each enabled channel, in order.
    probes: Vec<(u32, String)>,
}

/// A decompressed block: `len` bytes of chunk `chunk` from its byte
/// `offset` on, in `buf`. A chunk's last block is shorter than the
/// others (maybe empty); the others hold whole samples.
#[derive(Debug, Default)]
struct Block {
    chunk: usize,
    offset: u64,
    buf: Vec<u8>,
    len: usize,
}

/// One message of the decompressing thread.
#[derive(Debug)]
enum Piece {
    Data(Block),
    Failed(LogicError),
    Finished,
}

/// Where the scan is: `block.buf[pos..block.len]` is still to scan.
#[derive(Debug, Default)]
struct Scan {
    block: Block,
    pos: usize,
    /// The sample number of the block's first; the samples taken so far.
    first_sample: u64,
    samples: u64,
    /// The previous sample's enabled bits, once there is one.
    prev: Option<u64>,
    /// Every chunk was read; or an error, which every later call repeats.
    finished: bool,
    failed: Option<LogicError>,
}

/// A sigrok session file read as it goes. See the module documentation.
#[derive(Debug)]
pub struct SigrokReader {
    path: PathBuf,
    info: LogicInfo,
    chunks: Vec<String>,
    unit: Unit,
    rx: Receiver<Piece>,
    recycle: Sender<Vec<u8>>,
    scan: Scan,
}

/// Picoseconds in a second.
const PS_PER_S: u64 = 1_000_000_000_000;

/// Eight bytes, little endian (0 if `bytes` is not eight long).
fn le64(bytes: &[u8]) -> u64 {
    <[u8; 8]>::try_from(bytes).map_or(0, u64::from_le_bytes)
}

/// An error of `path` at `at`.
fn fail<T>(path: &Path, at: impl Into<String>, what: impl Into<String>) -> Result<T, LogicError> {
    Err(LogicError::new(path, at, what))
}

impl SigrokReader {
    /// Opens a session file: its version, metadata and chunk list are read
    /// now (their errors returned now), the samples as
    /// [`LogicSource::next_change`] asks.
    pub fn open(path: &Path) -> Result<SigrokReader, LogicError> {
        let mut file = open_regular(path)?;
        check_zip_ends(path, &mut file)?;
        let entries = Entries::read(path, &mut file)?;
        let version = entries
            .version
            .ok_or_else(|| LogicError::new(path, "", "no `version`: not a sigrok session file"))?;
        check_version(path, &version)?;
        let text = entries
            .metadata
            .ok_or_else(|| LogicError::new(path, "", "no `metadata`: not a sigrok session file"))?;
        let meta = parse_metadata(path, &text)?;
        let chunks = chunk_names(
            path,
            entries.names.iter().map(String::as_str),
            &meta.capturefile,
        )?;
        let (tx, rx) = mpsc::sync_channel(BLOCKS_IN_FLIGHT);
        let (recycle, recycled) = mpsc::channel();
        let (names, who, unit) = (chunks.clone(), path.to_path_buf(), meta.unitsize);
        std::thread::Builder::new()
            .name("sigrok-inflate".into())
            .spawn(move || inflate(file, &who, &names, unit, &tx, &recycled))
            .map_err(|e| LogicError::new(path, "", format!("cannot start a thread: {e}")))?;
        let mask = meta.probes.iter().fold(0u64, |m, (bit, _)| m | 1u64 << bit);
        let info = LogicInfo {
            channels: meta.probes.into_iter().map(|(_, name)| name).collect(),
            resolution_ps: LogicInfo::sample_time_ps(1, meta.rate).max(1),
            sample_rate_hz: Some(meta.rate),
            format: "sigrok session (.sr, version 2)".into(),
        };
        let unit = Unit::new(meta.unitsize, mask, meta.rate);
        let path = path.to_path_buf();
        let scan = Scan::default();
        Ok(SigrokReader {
            path,
            info,
            chunks,
            unit,
            rx,
            recycle,
            scan,
        })
    }

    /// The samples read so far (all of them once the stream has ended).
    pub fn samples(&self) -> u64 {
        self.scan.samples
    }

    /// The bytes of one sample in the file (`unitsize`).
    pub fn unitsize(&self) -> usize {
        self.unit.bytes
    }

    /// The next change in the block being scanned, if any.
    fn change_in_block(&mut self) -> Option<Change> {
        let (unit, s) = (&self.unit, &mut self.scan);
        let block = &s.block.buf[..s.block.len];
        let at = match s.prev {
            None if s.pos + unit.bytes <= block.len() => s.pos,
            None => return None,
            Some(prev) => unit.find_change(block, s.pos, prev)?,
        };
        let raw = unit.sample_at(block, at);
        (s.prev, s.pos) = (Some(raw), at + unit.bytes);
        let time_ps = unit.time_ps(s.first_sample + unit.sample_number(at));
        let levels = unit.levels(raw);
        Some(Change {
            time_ps,
            levels,
            unknown: 0,
        })
    }

    /// Takes the thread's next block, or its end.
    fn next_block(&mut self) -> Result<(), LogicError> {
        let block = match self.rx.recv() {
            Ok(Piece::Data(block)) => block,
            Ok(Piece::Failed(e)) => return Err(e),
            Ok(Piece::Finished) if self.scan.samples == 0 => {
                return fail(&self.path, "", "no samples: every chunk is empty")
            }
            Ok(Piece::Finished) => {
                self.scan.finished = true;
                return Ok(());
            }
            Err(_) => return fail(&self.path, "", "the decompressing thread stopped early"),
        };
        let (u, s) = (self.unit.bytes, &mut self.scan);
        let old = std::mem::replace(&mut s.block, block);
        // Back to the thread for the next block; if it has gone, dropped.
        let _ = self.recycle.send(old.buf);
        let (chunk, offset, len) = (s.block.chunk, s.block.offset, s.block.len);
        if len % u != 0 {
            let name = self.chunks.get(chunk).map_or("?", String::as_str);
            let at = format!("byte {} of {name}", offset + (len - len % u) as u64);
            let what = format!(
                "the chunk ends {} byte(s) into a sample of {u} bytes (unitsize {u}): \
                 a chunk holds whole samples",
                len % u
            );
            return fail(&self.path, at, what);
        }
        (s.first_sample, s.pos) = (s.samples, 0);
        s.samples += (len / u) as u64;
        Ok(())
    }
}

impl LogicSource for SigrokReader {
    fn info(&self) -> &LogicInfo {
        &self.info
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        while self.scan.failed.is_none() {
            if let Some(change) = self.change_in_block() {
                return Ok(Some(change));
            }
            if self.scan.finished {
                return Ok(None);
            }
            if let Err(e) = self.next_block() {
                self.scan.failed = Some(e);
            }
        }
        self.scan.failed.clone().map_or(Ok(None), Err)
    }

    fn end_ps(&self) -> u64 {
        match self.scan.samples {
            0 => 0,
            n => self.unit.time_ps(n - 1),
        }
    }
}

/// A sample's layout and time: its bytes, the enabled channels' bits,
/// the sample rate, and what makes the scan fast.
#[derive(Debug, Clone, Copy)]
struct Unit {
    bytes: usize,
    mask: u64,
    rate: u64,
    /// The sample period if it is a whole number of picoseconds (a time is
    /// then one multiplication).
    period_ps: Option<u64>,
    /// `bytes` is `2^shift * (bytes >> shift)`: a byte offset becomes a
    /// sample number without a division for the usual 1, 2, 4 and 8.
    shift: u32,
    /// When `bytes` divides 8, a word of 1 in each sample's place:
    /// 0x0101..01 for 1 byte, 0x0001..0001 for 2, ...
    ones: Option<u64>,
}

impl Unit {
    fn new(bytes: usize, mask: u64, rate: u64) -> Unit {
        let (shift, low) = (bytes.trailing_zeros(), u64::MAX >> (64 - 8 * bytes));
        let ones = (8 % bytes == 0).then_some(u64::MAX / low);
        let period_ps = (PS_PER_S % rate == 0).then_some(PS_PER_S / rate);
        Unit {
            rate,
            period_ps,
            bytes,
            mask,
            shift,
            ones,
        }
    }

    /// The enabled bits of the sample at byte `at` of `block`.
    fn sample_at(&self, block: &[u8], at: usize) -> u64 {
        if let Some(eight) = block.get(at..at + 8) {
            return le64(eight) & self.mask;
        }
        let bytes = block.get(at..at + self.bytes).unwrap_or_default();
        bytes.iter().rev().fold(0, |v, &b| v << 8 | u64::from(b)) & self.mask
    }

    /// The time of sample `n`: [`LogicInfo::sample_time_ps`], faster.
    fn time_ps(&self, n: u64) -> u64 {
        match self.period_ps.and_then(|p| n.checked_mul(p)) {
            Some(t) => t,
            _ => LogicInfo::sample_time_ps(n, self.rate),
        }
    }

    /// The number of the sample at byte `at` of a block (`at` being a
    /// sample boundary).
    fn sample_number(&self, at: usize) -> u64 {
        let (k, odd) = (at >> self.shift, self.bytes >> self.shift);
        (if odd == 1 { k } else { k / odd }) as u64
    }

    /// The channels' levels of enabled bits, bit `i` for
    /// [`LogicInfo::channels`]`[i]`.
    fn levels(&self, raw: u64) -> u64 {
        if self.mask & self.mask.wrapping_add(1) == 0 {
            return raw; // the enabled bits are the low ones
        }
        let (mut out, mut rest, mut i) = (0u64, self.mask, 0);
        while rest != 0 {
            out |= (raw >> rest.trailing_zeros() & 1) << i;
            rest &= rest - 1;
            i += 1;
        }
        out
    }

    /// The byte offset of the first sample at or after `pos` (a sample
    /// boundary) whose enabled bits differ from `prev`.
    fn find_change(&self, block: &[u8], pos: usize, prev: u64) -> Option<usize> {
        let (u, mut i) = (self.bytes, pos);
        if let Some(ones) = self.ones {
            // Whole words of samples against `prev` repeated: four at a
            // time while the block lasts, then one.
            let (rep, mask) = (prev.wrapping_mul(ones), self.mask.wrapping_mul(ones));
            let word = |at: usize| (le64(&block[at..at + 8]) ^ rep) & mask;
            while i + 32 <= block.len() && word(i) | word(i + 8) | word(i + 16) | word(i + 24) == 0
            {
                i += 32;
            }
            while i + 8 <= block.len() {
                let diff = word(i);
                if diff != 0 {
                    // The sample of the first byte that differs (`u` is a
                    // power of two here).
                    let byte = (diff.trailing_zeros() / 8) as usize;
                    return Some(i + (byte & !(u - 1)));
                }
                i += 8;
            }
        }
        while i + u <= block.len() {
            if self.sample_at(block, i) != prev {
                return Some(i);
            }
            i += u;
        }
        None
    }
}

/// What the ZIP's entries are, read from their local headers in turn
/// (`zip::read::read_zipfile_from_stream`), not from the archive's central
/// directory: `ZipArchive` holds that whole, some 0.5 KB an entry, which
/// would grow with the capture. The samples are skipped here, not
/// decompressed.
#[derive(Debug, Default)]
struct Entries {
    version: Option<Vec<u8>>,
    metadata: Option<Vec<u8>>,
    /// The other entries' names, in the file's order.
    names: Vec<String>,
}

impl Entries {
    fn read(path: &Path, file: &mut File) -> Result<Entries, LogicError> {
        use std::io::{BufReader, Seek, SeekFrom};
        let not_zip = |e: ZipError| {
            let what = format!("not a ZIP archive as libsigrok writes a session: {e}");
            LogicError::new(path, "", what)
        };
        let mut entries = Entries::default();
        let mut r = BufReader::with_capacity(1 << 16, &mut *file);
        while let Some(entry) = zip::read::read_zipfile_from_stream(&mut r).map_err(not_zip)? {
            let name = entry.name().to_string();
            match name.as_str() {
                "version" | "metadata" => {
                    let bytes = read_small(entry, path, &name)?;
                    match name.as_str() {
                        "version" => entries.version = Some(bytes),
                        _ => entries.metadata = Some(bytes),
                    }
                }
                _ => entries.names.push(name),
            }
        }
        drop(r);
        file.seek(SeekFrom::Start(0))
            .map_err(|e| LogicError::new(path, "", format!("cannot read: {e}")))?;
        Ok(entries)
    }
}

/// The thread's body: each chunk in turn, decompressed into blocks of
/// whole samples (but a chunk's last), sent to the scan until it is gone.
/// The entries are read in the file's order, as libsigrok writes them: a
/// chunk met before the one due is an error (`chunks` are in order).
fn inflate(
    file: File,
    path: &Path,
    chunks: &[String],
    unitsize: usize,
    tx: &SyncSender<Piece>,
    recycled: &Receiver<Vec<u8>>,
) {
    let fill = BLOCK_BYTES - BLOCK_BYTES % unitsize.max(1);
    let failed = |at: String, what: String| {
        let _ = tx.send(Piece::Failed(LogicError::new(path, at, what)));
    };
    let mut r = std::io::BufReader::with_capacity(1 << 16, file);
    for (chunk, name) in chunks.iter().enumerate() {
        let mut entry = loop {
            match zip::read::read_zipfile_from_stream(&mut r) {
                Ok(Some(e)) if e.name() == name => break e,
                Ok(Some(e)) if chunks.iter().any(|c| c == e.name()) => {
                    return failed(
                        e.name().to_string(),
                        format!("comes before `{name}` in the file: the chunks are not in order"),
                    )
                }
                Ok(Some(_)) => {} // version, metadata, analog: skipped
                Ok(None) => return failed(name.clone(), "not found in the file".into()),
                Err(e) => return failed(name.clone(), format!("cannot open this chunk: {e}")),
            }
        };
        let mut offset = 0u64;
        loop {
            let mut buf = recycled.try_recv().unwrap_or_default();
            buf.resize(fill, 0);
            let mut len = 0;
            while len < fill {
                match entry.read(&mut buf[len..fill]) {
                    Ok(0) => break,
                    Ok(k) => len += k,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) => {
                        let at = format!("byte {} of {name}", offset + len as u64);
                        return failed(at, format!("cannot decompress: {e}"));
                    }
                }
            }
            let piece = Piece::Data(Block {
                chunk,
                offset,
                buf,
                len,
            });
            offset += len as u64;
            if tx.send(piece).is_err() {
                return; // the reader was dropped
            }
            if len < fill {
                break;
            }
        }
    }
    let _ = tx.send(Piece::Finished);
}

/// Whether `file` starts as a ZIP archive does and has the end of its
/// central directory where one must be, within the last 64 KiB (a
/// comment's length) of its end: checked before the `zip` crate, which
/// searches a file with none, 10 GB of zeros say, to its start.
fn check_zip_ends(path: &Path, file: &mut File) -> Result<(), LogicError> {
    use std::io::{Read, Seek, SeekFrom};
    const EOCD: &[u8] = b"PK\x05\x06";
    let not_zip = |why: &str| {
        fail::<()>(
            path,
            "",
            format!("not a ZIP archive, which a sigrok session file is: {why}"),
        )
    };
    let cannot = |e: std::io::Error| LogicError::new(path, "", format!("cannot read: {e}"));
    let len = file.metadata().map_err(cannot)?.len();
    let mut head = [0u8; 4];
    if len < 22 || file.read_exact(&mut head).is_err() {
        return not_zip("too short");
    }
    if &head != b"PK\x03\x04" && head != EOCD {
        return not_zip("it does not start with a ZIP entry");
    }
    let tail_len = len.min(22 + 0xFFFF);
    file.seek(SeekFrom::Start(len - tail_len)).map_err(cannot)?;
    let mut tail = vec![0u8; tail_len as usize];
    file.read_exact(&mut tail).map_err(cannot)?;
    file.seek(SeekFrom::Start(0)).map_err(cannot)?;
    if !tail.windows(4).any(|w| w == EOCD) {
        return not_zip("no end of central directory (a truncated file?)");
    }
    Ok(())
}

/// Opens a regular file for reading, never blocking on a FIFO.
fn open_regular(path: &Path) -> Result<File, LogicError> {
    let mut opts = OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut opts, libc::O_NONBLOCK);
    let cannot = |e: std::io::Error| LogicError::new(path, "", format!("cannot read: {e}"));
    let file = opts.open(path).map_err(cannot)?;
    match file.metadata().map_err(cannot)?.is_file() {
        true => Ok(file),
        false => fail(path, "", "not a regular file"),
    }
}

/// The whole of a small entry, at most [`MAX_METADATA_BYTES`].
fn read_small(entry: impl Read, path: &Path, name: &str) -> Result<Vec<u8>, LogicError> {
    let mut bytes = Vec::new();
    if let Err(e) = entry.take(MAX_METADATA_BYTES + 1).read_to_end(&mut bytes) {
        return fail(path, name, format!("cannot decompress: {e}"));
    }
    match bytes.len() as u64 > MAX_METADATA_BYTES {
        true => fail(
            path,
            name,
            format!("larger than {MAX_METADATA_BYTES} bytes"),
        ),
        false => Ok(bytes),
    }
}

/// Accepts version 2 only.
fn check_version(path: &Path, bytes: &[u8]) -> Result<(), LogicError> {
    let what = match String::from_utf8_lossy(bytes).trim() {
        "2" => return Ok(()),
        "1" => "a version 1 session file (libsigrok before 0.3), which ppmc does not read: \
                open it in PulseView, or `sigrok-cli -i OLD.sr -o NEW.sr`, to save it as version 2"
            .to_string(),
        v => format!("version `{}`: ppmc reads version 2", v.escape_default()),
    };
    fail(path, "version", what)
}

/// The data entries of `capturefile` (`cf`), in order: `logic-1` alone,
/// or `logic-1-1` to `logic-1-N` with none missing.
fn chunk_names<'a>(
    path: &Path,
    names: impl Iterator<Item = &'a str>,
    cf: &str,
) -> Result<Vec<String>, LogicError> {
    let number = |rest: &str| match rest.strip_prefix('-') {
        Some(r) if r.starts_with('0') || !r.bytes().all(|b| b.is_ascii_digit()) => None,
        Some(r) => r.parse::<u64>().ok(),
        None => None,
    };
    let (mut whole, mut numbers) = (false, Vec::new());
    for name in names {
        whole |= name == cf;
        numbers.extend(name.strip_prefix(cf).and_then(number));
    }
    numbers.sort_unstable();
    let last = numbers.last().copied().unwrap_or(0);
    let missing = (1..=last).zip(&numbers).find(|&(want, &n)| n != want);
    let what = match (whole, last, missing) {
        (true, 0, _) => return Ok(vec![cf.to_string()]),
        (true, ..) => format!("both `{cf}` and `{cf}-N` entries: which are the samples?"),
        (false, 0, _) => format!("no sample data: no `{cf}` nor `{cf}-1`"),
        (_, _, Some((want, _))) => {
            format!("`{cf}-{want}` is missing (the chunks run to `{cf}-{last}`)")
        }
        (_, _, None) => return Ok(numbers.iter().map(|n| format!("{cf}-{n}")).collect()),
    };
    fail(path, "", what)
}

/// A GLib key file value's escapes (`\s`, `\n`, `\t`, `\r`, `\\`) undone.
fn unescape(value: &str) -> String {
    let mut chars = value.chars();
    let mut out = String::with_capacity(value.len());
    while let Some(c) = chars.next() {
        out.push(match (c, if c == '\\' { chars.next() } else { None }) {
            (_, Some('s')) => ' ',
            (_, Some('n')) => '\n',
            (_, Some('t')) => '\t',
            (_, Some('r')) => '\r',
            (_, Some(escaped)) => escaped,
            (c, None) => c,
        });
    }
    out
}

/// A line of `metadata` and what is wrong there.
type LineError = (usize, String);

/// Reads `metadata`: its `[device 1]` section.
fn parse_metadata(path: &Path, bytes: &[u8]) -> Result<Metadata, LogicError> {
    let parsed = match std::str::from_utf8(bytes) {
        Ok(text) => device_section(text).and_then(|(keys, line)| device_metadata(&keys, line)),
        Err(e) => {
            let line = bytes[..e.valid_up_to()].split(|&b| b == b'\n').count();
            Err((line, "not UTF-8 text".into()))
        }
    };
    parsed.map_err(|(line, what)| match line {
        0 => LogicError::new(path, "metadata", what),
        n => LogicError::new(path, format!("line {n} of metadata"), what),
    })
}

/// The keys of `[device 1]`, each with its line's number, and the
/// section's line, from a GLib key file; errors at line 0 are the file's.
type Keys = BTreeMap<String, (usize, String)>;

fn device_section(text: &str) -> Result<(Keys, usize), LineError> {
    let (mut section, mut keys, mut device_line) = (None::<&str>, Keys::new(), 0);
    for (i, raw) in text.split('\n').enumerate() {
        let (n, line) = (i + 1, raw.trim_end_matches('\r').trim_start());
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[') {
            let Some(name) = name.trim_end().strip_suffix(']') else {
                return Err((n, "a `[section` without its `]`".into()));
            };
            if name.starts_with("device ") {
                if device_line != 0 {
                    let what = format!("a second device ([{name}]): ppmc reads one device a file");
                    return Err((n, what));
                }
                if name != "device 1" {
                    return Err((n, format!("[{name}] where [device 1] was expected")));
                }
                device_line = n;
            }
            section = Some(name);
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err((n, "neither `key=value` nor a `[section]`".into()));
        };
        match section {
            None => return Err((n, "a key before any `[section]`".into())),
            Some("device 1") => {}
            Some(_) => continue,
        }
        let key = key.trim_end().to_string();
        if let Some((first, _)) = keys.get(&key) {
            return Err((n, format!("`{key}` given twice (first on line {first})")));
        }
        keys.insert(key, (n, unescape(value.trim_start())));
    }
    match device_line {
        0 => Err((0, "no [device 1] section".into())),
        line => Ok((keys, line)),
    }
}

/// The reader's settings from the `[device 1]` keys.
fn device_metadata(keys: &Keys, section: usize) -> Result<Metadata, LineError> {
    let get = |key: &str, why: &str| match keys.get(key) {
        Some((line, v)) => Ok((*line, v.as_str())),
        None => Err((section, format!("[device 1] has no `{key}`{why}"))),
    };
    let (_, capturefile) = get("capturefile", ": no logic data (an analog-only capture?)")?;
    let (line, rate) = get("samplerate", "")?;
    let Some(rate) = parse_rate(rate) else {
        let what = format!("samplerate `{rate}` is not a rate above 0 Hz (such as `24 MHz`)");
        return Err((line, what));
    };
    let (total_line, total) = get("total probes", "")?;
    let total = match total.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_CHANNELS).contains(&n) => n,
        _ => {
            let what =
                format!("total probes `{total}`: 1 to {MAX_CHANNELS} logic channels are read");
            return Err((total_line, what));
        }
    };
    let (line, unit) = get("unitsize", ": no sample data was saved")?;
    let unitsize = match unit.trim().parse::<usize>() {
        Ok(u) if (1..=8).contains(&u) && u * 8 >= total => u,
        _ => {
            let what = format!(
                "unitsize `{unit}` does not match total probes={total} (line {total_line}): \
                 a sample of {total} channels takes {} to 8 bytes",
                total.div_ceil(8)
            );
            return Err((line, what));
        }
    };
    let mut probes = Vec::new();
    for (key, (line, name)) in keys {
        let Some(number) = key.strip_prefix("probe") else {
            continue;
        };
        match number
            .parse::<u32>()
            .ok()
            .filter(|k| (1..=total as u32).contains(k))
        {
            Some(_) if name.is_empty() => return Err((*line, format!("`{key}` has no name"))),
            Some(k) => probes.push((k - 1, name.clone())),
            None => return Err((*line, format!("`{key}` is no probe of 1 to {total}"))),
        }
    }
    if probes.is_empty() {
        let what = "no `probeN` line: every logic channel was disabled";
        return Err((section, what.into()));
    }
    probes.sort_unstable();
    let capturefile = capturefile.to_string();
    Ok(Metadata {
        capturefile,
        rate,
        unitsize,
        probes,
    })
}

/// A sample rate as libsigrok writes and reads it (`sr_parse_sizestring`):
/// `24 MHz`, `24MHz`, `1.5 kHz`, `200 Hz`, `24M`; a `k`, `m`/`M` (mega,
/// as in libsigrok), `g`/`G`, `t`/`T`, `p`/`P` or `e`/`E` prefix. `None`
/// for anything else, for 0 and for a rate that is no whole number of Hz.
pub fn parse_rate(text: &str) -> Option<u64> {
    let digits = |s: &str| s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    let s = text.trim();
    let (int, mut rest) = s.split_at(digits(s));
    let mut frac = "";
    if let Some(r) = rest.strip_prefix('.') {
        (frac, rest) = r.split_at(digits(r));
        if frac.is_empty() {
            return None;
        }
    }
    if int.is_empty() || int.len() + frac.len() > 30 {
        return None;
    }
    let rest = rest.trim_start();
    let prefix = rest.chars().next().map(|c| c.to_ascii_lowercase());
    let (mult, unit) = match "kmgtpe".find(|p| Some(p) == prefix) {
        Some(i) => (1000u128.pow(i as u32 + 1), &rest[1..]),
        None => (1, rest),
    };
    if !(unit.is_empty() || unit.eq_ignore_ascii_case("hz")) {
        return None;
    }
    let scale = 10u128.pow(frac.len() as u32);
    let frac_hz = match frac {
        "" => 0,
        f => f.parse::<u128>().ok()?.checked_mul(mult)?,
    };
    if frac_hz % scale != 0 {
        return None;
    }
    let int = int.parse::<u128>().ok()?;
    let hz = int.checked_mul(mult)?.checked_add(frac_hz / scale)?;
    u64::try_from(hz).ok().filter(|&r| r > 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::io::{Cursor, Write};
    use zip::write::SimpleFileOptions;
    use zip::{CompressionMethod, ZipWriter};

    /// A session file's bytes from its entries, written with the zip
    /// crate's writer as libzip lays one out (deflate, or stored).
    fn zip_bytes(entries: &[(&str, &[u8])], method: CompressionMethod) -> Vec<u8> {
        let mut w = ZipWriter::new(Cursor::new(Vec::new()));
        let opts = SimpleFileOptions::default().compression_method(method);
        for (name, bytes) in entries {
            w.start_file(*name, opts).expect("start entry");
            w.write_all(bytes).expect("write entry");
        }
        w.finish().expect("finish zip").into_inner()
    }

    /// `[device 1]` metadata as sigrok-cli 0.5 writes it, with `probes`
    /// (1-based number, name) enabled.
    fn metadata(total: usize, rate: &str, unitsize: usize, probes: &[(usize, &str)]) -> String {
        let mut m = format!(
            "[global]\nsigrok version=0.5.2\n\n[device 1]\ncapturefile=logic-1\n\
             total probes={total}\nsamplerate={rate}\ntotal analog=0\n"
        );
        for (k, name) in probes {
            m += &format!("probe{k}={name}\n");
        }
        m + &format!("unitsize={unitsize}\n")
    }

    struct Scratch {
        dir: tempfile::TempDir,
    }

    impl Scratch {
        fn new() -> Scratch {
            Scratch {
                dir: tempfile::tempdir().expect("temp dir"),
            }
        }

        fn file(&self, name: &str, bytes: &[u8]) -> PathBuf {
            let p = self.dir.path().join(name);
            std::fs::write(&p, bytes).expect("write file");
            p
        }

        /// A session file of `meta` and the sample `chunks` (`logic-1-1`...).
        fn session(&self, name: &str, meta: &str, chunks: &[Vec<u8>]) -> PathBuf {
            let names: Vec<String> = (1..=chunks.len()).map(|i| format!("logic-1-{i}")).collect();
            let mut entries: Vec<(&str, &[u8])> =
                vec![("version", b"2"), ("metadata", meta.as_bytes())];
            for (n, c) in names.iter().zip(chunks) {
                entries.push((n, c));
            }
            self.file(name, &zip_bytes(&entries, CompressionMethod::Deflated))
        }
    }

    /// What a file reads as: its info, its changes (time, levels), its end.
    type Reading = (LogicInfo, Vec<(u64, u64)>, u64);

    /// Every change of a source, or its first error.
    fn changes(path: &Path) -> Result<Reading, LogicError> {
        let mut r = SigrokReader::open(path)?;
        let mut out = Vec::new();
        while let Some(c) = r.next_change()? {
            assert_eq!(c.unknown, 0);
            out.push((c.time_ps, c.levels));
        }
        Ok((r.info().clone(), out, r.end_ps()))
    }

    fn error(path: &Path) -> LogicError {
        match changes(path) {
            Err(e) => e,
            Ok((_, c, _)) => panic!(
                "{}: read {} changes, expected an error",
                path.display(),
                c.len()
            ),
        }
    }

    #[test]
    fn sample_rates_read_as_libsigrok_writes_them() {
        for (text, hz) in [
            ("24 MHz", 24_000_000),
            ("24MHz", 24_000_000),
            ("200 Hz", 200),
            ("200", 200),
            ("1.5 kHz", 1_500),
            ("41.666666 MHz", 41_666_666),
            ("1 GHz", 1_000_000_000),
            ("24m", 24_000_000),
            ("24 khz", 24_000),
            (" 8 MHz ", 8_000_000),
            ("2 THz", 2_000_000_000_000),
        ] {
            assert_eq!(parse_rate(text), Some(hz), "{text}");
        }
        for bad in [
            "",
            "0 Hz",
            "1.5 Hz",
            "MHz",
            "24 MHz!",
            "24 M Hz",
            "1.",
            ".5 MHz",
            "-1 Hz",
            "1e3",
            "99999999999999999999 GHz",
        ] {
            assert_eq!(parse_rate(bad), None, "{bad}");
        }
    }

    #[test]
    fn unitsize_1_in_several_chunks_gives_each_change_once() {
        let s = Scratch::new();
        // 8 probes at 24 MHz; the chunks split runs of equal samples.
        let meta = metadata(
            8,
            "24 MHz",
            1,
            &[(1, "CS"), (2, "RD"), (3, "WR"), (8, "D7")],
        );
        let chunks = vec![
            vec![0x01, 0x01, 0x01],
            vec![0x01, 0x03],
            vec![],
            vec![0x03, 0x83, 0x80],
        ];
        let p = s.session("u1.sr", &meta, &chunks);
        let (info, got, end) = changes(&p).expect("reads");
        assert_eq!(info.channels, ["CS", "RD", "WR", "D7"]);
        assert_eq!(info.sample_rate_hz, Some(24_000_000));
        assert_eq!(info.resolution_ps, 41_667);
        assert_eq!(info.format, "sigrok session (.sr, version 2)");
        // Sample 0: CS; 4: +RD; 6: +D7 (bit 7 is the 4th channel); 7: only D7.
        let t = |n| LogicInfo::sample_time_ps(n, 24_000_000);
        assert_eq!(
            got,
            [(0, 0b0001), (t(4), 0b0011), (t(6), 0b1011), (t(7), 0b1000)]
        );
        assert_eq!(end, t(7), "the time of the 8th and last sample");
    }

    #[test]
    fn unitsize_2_with_disabled_probes_ignores_their_bits() {
        let s = Scratch::new();
        // 12 probes in 2 bytes; probe 2 and 4..8 disabled (no probeK line),
        // probe 9 (bit 8) and 12 (bit 11) enabled.
        let meta = metadata(
            12,
            "1 MHz",
            2,
            &[(12, "LAST"), (1, "A"), (9, "B"), (3, "C")],
        );
        let samples: [u16; 7] = [
            0x0001, // A
            0x0003, // + probe 2 (disabled): no change
            0x00f3, // + disabled 5..8: no change
            0x0101, // + B
            0x0905, // + C, + LAST
            0x0904, // - A
            0x0904,
        ];
        let bytes: Vec<u8> = samples.iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = s.session("u2.sr", &meta, &[bytes[..6].to_vec(), bytes[6..].to_vec()]);
        let (info, got, end) = changes(&p).expect("reads");
        assert_eq!(
            info.channels,
            ["A", "C", "B", "LAST"],
            "probe order, enabled only"
        );
        let us = 1_000_000;
        assert_eq!(
            got,
            [
                (0, 0b0001),
                (3 * us, 0b0101),
                (4 * us, 0b1111),
                (5 * us, 0b1110)
            ]
        );
        assert_eq!(end, 6 * us);
    }

    #[test]
    fn one_unchunked_capture_file_and_odd_unitsizes_across_blocks() {
        let s = Scratch::new();
        // 20 probes in 3 bytes (libsigrok 0.6 writes ceil(probes / 8)), a
        // chunk of several blocks with changes on their boundaries.
        let meta = metadata(20, "100 kHz", 3, &[(1, "A"), (20, "Z")]);
        let n = 2 * BLOCK_BYTES / 3 + 5;
        let per_block = (BLOCK_BYTES / 3) as u64;
        let mut data = Vec::with_capacity(3 * n);
        let mut want = Vec::new();
        let mut level = 0u64;
        for i in 0..n as u64 {
            if i == 0 || i == per_block || i == per_block - 1 || i == 2 * per_block || i == 77 {
                level ^= 0b11;
                want.push((LogicInfo::sample_time_ps(i, 100_000), level));
            }
            // Noise on disabled probes 2..19.
            let raw = (level & 1) | (level >> 1) << 19 | (0x07_fffe * (i & 1));
            data.extend_from_slice(&raw.to_le_bytes()[..3]);
        }
        let zip = zip_bytes(
            &[
                ("version", b"2\n"),
                ("metadata", meta.as_bytes()),
                ("logic-1", &data),
            ],
            CompressionMethod::Stored,
        );
        let (_, got, end) = changes(&s.file("u3.sr", &zip)).expect("reads");
        let first = got.iter().zip(&want).position(|(a, b)| a != b);
        assert!(
            got == want,
            "{} changes, {} wanted, first apart: {first:?}",
            got.len(),
            want.len()
        );
        assert_eq!(end, LogicInfo::sample_time_ps(n as u64 - 1, 100_000));
    }

    #[test]
    fn analog_entries_and_other_sections_are_ignored() {
        let s = Scratch::new();
        let meta = "[global]\nsigrok version=0.5.2\n\n[device 1]\ncapturefile=logic-1\n\
                    total probes=2\nsamplerate=200 kHz\ntotal analog=1\nprobe1=D0\nprobe2=D1\n\
                    analog3=A0\nunitsize=1\n";
        let zip = zip_bytes(
            &[
                ("version", b"2"),
                ("metadata", meta.as_bytes()),
                ("logic-1-1", &[0, 1, 1, 2]),
                ("analog-1-3-1", &[0x42; 16]),
                ("analog-1-3-2", &[0x43; 16]),
            ],
            CompressionMethod::Deflated,
        );
        let (info, got, _) = changes(&s.file("a.sr", &zip)).expect("reads");
        assert_eq!(info.channels, ["D0", "D1"]);
        assert_eq!(got, [(0, 0), (5_000_000, 1), (15_000_000, 2)]);
    }

    /// Asserts `e` names `at` and says something containing `what`.
    fn says(e: &LogicError, at: &str, what: &str) {
        assert_eq!(e.at, at, "{e}");
        assert!(e.what.contains(what), "{e}");
        assert!(e.to_string().contains(&e.file.display().to_string()), "{e}");
    }

    #[test]
    fn each_bad_file_is_an_error_naming_where() {
        let s = Scratch::new();
        let good = metadata(8, "24 MHz", 1, &[(1, "CS")]);
        let z = |name: &str, entries: &[(&str, &[u8])]| {
            s.file(name, &zip_bytes(entries, CompressionMethod::Deflated))
        };
        let m = good.as_bytes();
        let e = error(&z("nometa.sr", &[("version", b"2"), ("logic-1-1", &[0])]));
        says(&e, "", "no `metadata`: not a sigrok session file");
        let e = error(&z("nover.sr", &[("metadata", m), ("logic-1-1", &[0])]));
        says(&e, "", "no `version`");
        let e = error(&z(
            "v1.sr",
            &[("version", b"1"), ("metadata", m), ("logic-1", &[0])],
        ));
        says(&e, "version", "version 1 session file");
        let e = error(&z("v3.sr", &[("version", b"3"), ("metadata", m)]));
        says(&e, "version", "version `3`");
        let bad_rate = good.replace("24 MHz", "fast");
        let e = error(&s.session("rate.sr", &bad_rate, &[vec![0]]));
        says(&e, "line 7 of metadata", "samplerate `fast`");
        let e = error(&s.session("rate0.sr", &good.replace("24 MHz", "0 Hz"), &[vec![0]]));
        says(&e, "line 7 of metadata", "samplerate `0 Hz`");
        let e = error(&s.session("unit.sr", &metadata(9, "1 MHz", 1, &[(9, "X")]), &[vec![0]]));
        says(
            &e,
            "line 10 of metadata",
            "unitsize `1` does not match total probes=9",
        );
        let e = error(&s.session("unit9.sr", &good.replace("unitsize=1", "unitsize=9"), &[]));
        says(&e, "line 10 of metadata", "unitsize `9`");
        let e = error(&s.session("many.sr", &metadata(65, "1 MHz", 8, &[(1, "X")]), &[]));
        says(&e, "line 6 of metadata", "total probes `65`");
        // A 2-byte sample cut after its first byte, in the second chunk.
        let two = metadata(16, "1 MHz", 2, &[(1, "X")]);
        let e = error(&s.session("cut.sr", &two, &[vec![0; 4], vec![1, 0, 2, 0, 3]]));
        says(
            &e,
            "byte 4 of logic-1-2",
            "ends 1 byte(s) into a sample of 2 bytes",
        );
        let gap = z(
            "gap.sr",
            &[
                ("version", b"2"),
                ("metadata", m),
                ("logic-1-1", &[0]),
                ("logic-1-3", &[1]),
            ],
        );
        says(
            &error(&gap),
            "",
            "`logic-1-2` is missing (the chunks run to `logic-1-3`)",
        );
        let both = z(
            "both.sr",
            &[
                ("version", b"2"),
                ("metadata", m),
                ("logic-1", &[0]),
                ("logic-1-1", &[1]),
            ],
        );
        says(&error(&both), "", "both `logic-1` and `logic-1-N` entries");
        let none = z("none.sr", &[("version", b"2"), ("metadata", m)]);
        says(&error(&none), "", "no sample data");
        let empty = s.session("empty.sr", &good, &[vec![], vec![]]);
        says(&error(&empty), "", "no samples");
        says(
            &error(&s.file("junk.sr", b"PK\x03\x04 not really")),
            "",
            "not a ZIP archive",
        );
        says(&error(&s.dir.path().join("absent.sr")), "", "cannot read");
        says(&error(s.dir.path()), "", "not a regular file");
    }

    #[test]
    fn bad_metadata_is_an_error_naming_its_line() {
        let s = Scratch::new();
        let good = metadata(8, "24 MHz", 1, &[(1, "CS")]);
        for (meta, at, what) in [
            (
                good.replace("[device 1]", "[device 1"),
                "line 4 of metadata",
                "without its `]`",
            ),
            (
                good.replace("capturefile=logic-1\n", ""),
                "line 4 of metadata",
                "no `capturefile`",
            ),
            (
                good.replace("unitsize=1\n", ""),
                "line 4 of metadata",
                "no `unitsize`",
            ),
            (
                good.replace("probe1=CS\n", ""),
                "line 4 of metadata",
                "every logic channel was disabled",
            ),
            (
                good.replace("probe1=CS", "probe9=CS"),
                "line 9 of metadata",
                "`probe9` is no probe of 1 to 8",
            ),
            (
                good.replace("probe1=CS", "probe1="),
                "line 9 of metadata",
                "`probe1` has no name",
            ),
            (
                good.replace("probe1=CS", "probe1 CS"),
                "line 9 of metadata",
                "neither `key=value`",
            ),
            (
                good.replace("unitsize=1", "probe1=RD"),
                "line 10 of metadata",
                "`probe1` given twice (first on line 9)",
            ),
            (
                good.replace("[device 1]", "[device 2]"),
                "line 4 of metadata",
                "[device 2] where [device 1]",
            ),
            (
                good.clone() + "[device 2]\n",
                "line 11 of metadata",
                "a second device",
            ),
            (
                good.replace("[global]\n", ""),
                "line 1 of metadata",
                "a key before any",
            ),
            (
                good.replace("[device 1]", "[other]"),
                "metadata",
                "no [device 1]",
            ),
        ] {
            let e = error(&s.session("m.sr", &meta, &[vec![0]]));
            says(&e, at, what);
        }
        let mut raw = good.into_bytes();
        raw.extend_from_slice(b"probe2=\xff\n");
        let zip = zip_bytes(
            &[("version", b"2"), ("metadata", &raw)],
            CompressionMethod::Stored,
        );
        says(
            &error(&s.file("utf8.sr", &zip)),
            "line 11 of metadata",
            "not UTF-8",
        );
    }

    #[test]
    fn chunks_out_of_order_in_the_file_are_refused_by_name() {
        let s = Scratch::new();
        let meta = metadata(8, "1 MHz", 1, &[(1, "A")]);
        let zip = zip_bytes(
            &[
                ("version", b"2"),
                ("metadata", meta.as_bytes()),
                ("logic-1-2", &[1, 1]),
                ("logic-1-1", &[0, 0]),
            ],
            CompressionMethod::Deflated,
        );
        let e = error(&s.file("order.sr", &zip));
        says(
            &e,
            "logic-1-2",
            "comes before `logic-1-1` in the file: the chunks are not in order",
        );
    }

    #[test]
    fn a_corrupt_chunk_fails_its_crc_with_the_chunk_named() {
        let s = Scratch::new();
        let meta = metadata(8, "1 MHz", 1, &[(1, "A")]);
        let data: Vec<u8> = (0..4096u32).map(|i| (i / 7 % 2) as u8).collect();
        let mut zip = zip_bytes(
            &[
                ("version", b"2"),
                ("metadata", meta.as_bytes()),
                ("logic-1-1", &data),
            ],
            CompressionMethod::Stored,
        );
        let at = zip
            .windows(data.len())
            .position(|w| w == data.as_slice())
            .expect("stored data");
        zip[at + 1000] ^= 0x40;
        let e = error(&s.file("crc.sr", &zip));
        assert!(e.at.ends_with("of logic-1-1"), "{e}");
        assert!(e.what.contains("cannot decompress"), "{e}");
        // The file cut short: the archive's directory is gone.
        says(
            &error(&s.file("short.sr", &zip[..zip.len() / 2])),
            "",
            "not a ZIP archive",
        );
    }

    #[test]
    fn an_error_repeats_and_a_dropped_reader_stops_its_thread() {
        let s = Scratch::new();
        let two = metadata(16, "1 MHz", 2, &[(1, "X")]);
        let p = s.session("cut.sr", &two, &[vec![1, 0, 2]]);
        let mut r = SigrokReader::open(&p).expect("opens");
        let first = r.next_change().expect_err("cut");
        assert_eq!(r.next_change().expect_err("again"), first);
        // A long capture, dropped after its first change: no hang.
        let meta = metadata(8, "1 MHz", 1, &[(1, "X")]);
        let big = vec![vec![0u8; 8 * BLOCK_BYTES]];
        let mut r = SigrokReader::open(&s.session("big.sr", &meta, &big)).expect("opens");
        assert_eq!(r.next_change().expect("reads").map(|c| c.time_ps), Some(0));
        drop(r);
    }

    /// The changes of raw samples, by the definition: sample 0, then every
    /// sample whose enabled bits differ from the one before, the enabled
    /// bits gathered in bit order.
    fn naive(samples: &[u64], enabled: &[u32], rate: u64) -> Vec<(u64, u64)> {
        let gather = |s: u64| {
            enabled
                .iter()
                .enumerate()
                .fold(0, |acc, (i, &bit)| acc | (s >> bit & 1) << i)
        };
        let mut out: Vec<(u64, u64)> = Vec::new();
        for (n, &s) in samples.iter().enumerate() {
            let l = gather(s);
            if out.last().is_none_or(|&(_, prev)| prev != l) {
                out.push((LogicInfo::sample_time_ps(n as u64, rate), l));
            }
        }
        out
    }

    fn capture() -> impl Strategy<Value = (usize, Vec<u32>, Vec<u64>, Vec<usize>)> {
        (1usize..=8)
            .prop_flat_map(|u| {
                let bits = (8 * u) as u32;
                (
                    Just(u),
                    proptest::collection::btree_set(0..bits, 1..=(bits as usize).min(6)),
                    // Samples from a few values, in runs, so most repeat.
                    proptest::collection::vec((any::<u64>(), 1usize..40), 1..60),
                    proptest::collection::vec(0usize..200, 0..4),
                )
            })
            .prop_map(|(u, bits, runs, cuts)| {
                let keep = if u == 8 {
                    u64::MAX
                } else {
                    (1u64 << (8 * u)) - 1
                };
                let samples = runs
                    .iter()
                    .flat_map(|&(v, n)| {
                        std::iter::repeat_n(
                            v & keep & 0x8000_0000_0000_0f35_u64.rotate_left(v as u32 % 64),
                            n,
                        )
                    })
                    .collect();
                (u, bits.into_iter().collect(), samples, cuts)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        #[test]
        fn any_capture_reads_as_its_changes((u, enabled, samples, cuts) in capture()) {
            let s = Scratch::new();
            let probes: Vec<(usize, String)> =
                enabled.iter().map(|&b| (b as usize + 1, format!("P{b}"))).collect();
            let names: Vec<(usize, &str)> = probes.iter().map(|(k, n)| (*k, n.as_str())).collect();
            let meta = metadata(8 * u, "3 MHz", u, &names);
            let bytes: Vec<u8> = samples.iter().flat_map(|v| v.to_le_bytes()[..u].to_vec()).collect();
            // Chunks cut at sample boundaries.
            let mut at: Vec<usize> = cuts.iter().map(|c| c % (samples.len() + 1) * u).collect();
            at.push(0);
            at.push(bytes.len());
            at.sort_unstable();
            let chunks: Vec<Vec<u8>> = at.windows(2).map(|w| bytes[w[0]..w[1]].to_vec()).collect();
            let (info, got, end) = changes(&s.session("p.sr", &meta, &chunks)).expect("reads");
            prop_assert_eq!(info.channels.len(), enabled.len());
            prop_assert_eq!(got, naive(&samples, &enabled, 3_000_000));
            prop_assert_eq!(end, LogicInfo::sample_time_ps(samples.len() as u64 - 1, 3_000_000));
        }

        #[test]
        fn the_word_scan_finds_what_a_sample_scan_finds(
            u in 1usize..=8,
            block in proptest::collection::vec(prop_oneof![Just(0u8), Just(0xffu8), any::<u8>()], 0..200),
            mask in any::<u64>(),
            prev in any::<u64>(),
        ) {
            let len = block.len() / u * u;
            let block = &block[..len];
            let mask = if u == 8 { mask } else { mask & ((1u64 << (8 * u)) - 1) };
            let prev = prev & mask;
            let sample = |i: usize| block[i..i + u].iter().rev().fold(0u64, |a, &b| a << 8 | u64::from(b));
            let slow = (0..len / u).map(|i| i * u).find(|&i| sample(i) & mask != prev);
            let unit = Unit::new(u, mask, 1);
            prop_assert_eq!(unit.find_change(block, 0, prev), slow);
            for i in (0..len).step_by(u) {
                prop_assert_eq!(unit.sample_at(block, i), sample(i) & mask);
                prop_assert_eq!(unit.sample_number(i), (i / u) as u64);
            }
        }

        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let s = Scratch::new();
            let _ = changes(&s.file("r.sr", &bytes));
        }

        #[test]
        fn a_valid_file_with_bytes_flipped_never_panics(
            flips in proptest::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..6),
        ) {
            let s = Scratch::new();
            let meta = metadata(16, "24 MHz", 2, &[(1, "CS"), (3, "WR"), (16, "D7")]);
            let data: Vec<u8> = (0..600u32).map(|i| (i / 5 * 37 % 251) as u8).collect();
            let mut zip = zip_bytes(
                &[
                    ("version", b"2"),
                    ("metadata", meta.as_bytes()),
                    ("logic-1-1", &data[..300]),
                    ("logic-1-2", &data[300..]),
                ],
                if flips.len() % 2 == 0 { CompressionMethod::Stored } else { CompressionMethod::Deflated },
            );
            for (i, x) in &flips {
                let at = i.index(zip.len());
                zip[at] ^= x;
            }
            let _ = changes(&s.file("f.sr", &zip));
        }
    }
}
