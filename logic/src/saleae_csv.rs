//! Saleae Logic 2's CSV export of digital channels, read as one stream of
//! level changes ([`Change`]) in bounded memory, a line at a time.
//!
//! [`SaleaeCsv`]: the CSV export, `Time [s],Channel 0,Channel 1,...` then
//! one row per time at which some channel changes, `0`, `1`, or `X` for no
//! data (unknown). Times count from the first row (Saleae writes them from
//! the trigger, so they may be negative), read exactly to the picosecond;
//! the capture ends at the last row; resolution 1 ps. Errors name the line.

use super::source::{Change, LogicError, LogicInfo, LogicSource, MAX_CHANNELS};
use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufReader};
use std::path::{Path, PathBuf};

/// The longest line read: 64 channels of a few characters each fit many
/// times over.
const MAX_LINE: usize = 64 << 10;

/// Saleae Logic 2's CSV export of digital channels.
pub struct SaleaeCsv<R> {
    file: PathBuf,
    info: LogicInfo,
    r: R,
    line: u64,
    buf: Vec<u8>,
    /// The first row's time, in picoseconds (may be negative).
    start: Option<i128>,
    /// The last row's time, from the start.
    now: u64,
    pending: Option<Change>,
    last: Option<(u64, u64)>,
    done: bool,
}

impl<R> fmt::Debug for SaleaeCsv<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SaleaeCsv")
            .field("file", &self.file)
            .field("info", &self.info)
            .field("line", &self.line)
            .finish_non_exhaustive()
    }
}

impl SaleaeCsv<BufReader<File>> {
    /// Opens a CSV export and reads its header.
    pub fn open(path: &Path) -> Result<Self, LogicError> {
        let f = ppmc_files::open_stream(path).map_err(|e| LogicError::opening(path, e))?;
        SaleaeCsv::new(BufReader::with_capacity(1 << 16, f), path)
    }
}

impl<R: BufRead> SaleaeCsv<R> {
    /// Reads the header of the CSV `r`; `file` names it in errors.
    pub fn new(r: R, file: &Path) -> Result<Self, LogicError> {
        let mut c = SaleaeCsv {
            file: file.to_path_buf(),
            info: LogicInfo {
                channels: Vec::new(),
                resolution_ps: 1,
                sample_rate_hz: None,
                format: "Saleae Logic 2 CSV".into(),
            },
            r,
            line: 0,
            buf: Vec::new(),
            start: None,
            now: 0,
            pending: None,
            last: None,
            done: false,
        };
        if !c.read_line()? {
            return Err(LogicError::new(file, "", "empty file: not a Saleae CSV"));
        }
        let text = String::from_utf8_lossy(&c.buf).into_owned();
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let mut fields = text.split(',').map(unquote);
        let time = fields.next().unwrap_or_default();
        if !time.starts_with("Time") {
            let shown: String = time.chars().take(40).collect();
            return Err(c.err(format!(
                "not a Saleae CSV: the first column is `{shown}`, not `Time [s]`"
            )));
        }
        c.info.channels = fields.map(str::to_string).collect();
        match c.info.channels.len() {
            0 => Err(c.err("no channel columns after the time")),
            n if n > MAX_CHANNELS => {
                Err(c.err(format!("{n} channels; at most {MAX_CHANNELS} can be read")))
            }
            _ => Ok(c),
        }
    }

    fn err(&self, what: impl Into<String>) -> LogicError {
        LogicError::new(&self.file, format!("line {}", self.line), what)
    }

    /// Reads the next line, without its end, into `buf`; `false` at the
    /// end of the file.
    fn read_line(&mut self) -> Result<bool, LogicError> {
        self.buf.clear();
        self.line += 1;
        loop {
            let chunk = match self.r.fill_buf() {
                Ok(b) => b,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(self.err(format!("cannot read: {e}"))),
            };
            if chunk.is_empty() {
                return Ok(!self.buf.is_empty());
            }
            let (take, ended) = match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => (i, true),
                None => (chunk.len(), false),
            };
            if self.buf.len() + take > MAX_LINE {
                return Err(self.err(format!("a line longer than {MAX_LINE} bytes")));
            }
            self.buf.extend_from_slice(&chunk[..take]);
            self.r.consume(take + usize::from(ended));
            if ended {
                if self.buf.last() == Some(&b'\r') {
                    self.buf.pop();
                }
                return Ok(true);
            }
        }
    }

    /// A data row: its time from the start and its levels.
    fn row(&mut self) -> Result<Change, LogicError> {
        let text = std::str::from_utf8(&self.buf).map_err(|_| self.err("not text"))?;
        let mut fields = text.split(',');
        let time = fields.next().unwrap_or_default();
        let ps = seconds_to_ps(unquote(time)).ok_or_else(|| {
            self.err(format!(
                "bad time `{}`",
                time.chars().take(40).collect::<String>()
            ))
        })?;
        let (mut levels, mut unknown, mut n) = (0u64, 0u64, 0usize);
        for (i, f) in fields.enumerate() {
            n = i + 1;
            if i >= self.info.channels.len() {
                break;
            }
            match unquote(f) {
                "1" => levels |= 1 << i,
                "0" => {}
                "X" | "x" => unknown |= 1 << i,
                v => {
                    return Err(self.err(format!(
                        "`{}` for {}: not 0, 1 or X",
                        v.chars().take(20).collect::<String>(),
                        self.info.channels[i]
                    )))
                }
            }
        }
        if n != self.info.channels.len() {
            return Err(self.err(format!(
                "{n} values for {} channels",
                self.info.channels.len()
            )));
        }
        let start = *self.start.get_or_insert(ps);
        let from = u64::try_from(ps - start).map_err(|_| {
            self.err(match ps < start {
                true => "a time before the first row's".to_string(),
                false => "a time past 2^64 picoseconds".to_string(),
            })
        })?;
        if from < self.now {
            return Err(self.err(format!(
                "time goes backwards: {} s after a later row",
                unquote(time)
            )));
        }
        self.now = from;
        Ok(Change {
            time_ps: from,
            levels,
            unknown,
        })
    }

    /// The pending change, if it changes something.
    fn give(&mut self, c: Option<Change>) -> Option<Change> {
        let c = c?;
        let state = (c.levels, c.unknown);
        if self.last == Some(state) {
            return None;
        }
        self.last = Some(state);
        Some(c)
    }
}

impl<R: BufRead> LogicSource for SaleaeCsv<R> {
    fn info(&self) -> &LogicInfo {
        &self.info
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        while !self.done {
            if !self.read_line()? {
                self.done = true;
                let p = self.pending.take();
                return Ok(self.give(p));
            }
            if self.buf.iter().all(u8::is_ascii_whitespace) {
                continue;
            }
            let c = self.row()?;
            let out = match self.pending.replace(c) {
                Some(p) if p.time_ps == c.time_ps => None,
                p => self.give(p),
            };
            if out.is_some() {
                return Ok(out);
            }
        }
        Ok(None)
    }

    fn end_ps(&self) -> u64 {
        self.now
    }
}

/// A field without surrounding spaces and quotes.
fn unquote(f: &str) -> &str {
    let f = f.trim();
    f.strip_prefix('"')
        .and_then(|g| g.strip_suffix('"'))
        .unwrap_or(f)
}

/// A decimal number of seconds (`-0.000012`, `1.25E-06`) in picoseconds,
/// exactly, rounded half away from zero below the picosecond.
pub fn seconds_to_ps(s: &str) -> Option<i128> {
    let (neg, s) = match s.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let (mant, exp) = match s.find(['e', 'E']) {
        Some(i) => (
            &s[..i],
            s[i + 1..].parse::<i32>().ok().filter(|e| e.abs() <= 40)?,
        ),
        None => (s, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    if int.is_empty() && frac.is_empty()
        || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let digits: String = format!("{int}{frac}").trim_start_matches('0').to_string();
    let shift = exp + 12 - frac.len() as i32;
    let (keep, next) = match shift {
        s if s >= 0 => (digits.clone() + &"0".repeat(s as usize), None),
        s => {
            let cut = digits.len() as i64 + i64::from(s);
            if cut < 0 {
                (String::new(), None)
            } else {
                let cut = cut as usize;
                (
                    digits[..cut].to_string(),
                    digits.as_bytes().get(cut).copied(),
                )
            }
        }
    };
    if keep.len() > 30 {
        return None;
    }
    let mut v: i128 = if keep.is_empty() {
        0
    } else {
        keep.parse().ok()?
    };
    if next.is_some_and(|d| d >= b'5') {
        v += 1;
    }
    Some(if neg { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::super::source::testing::{ch, drain, Read};
    use super::*;
    use proptest::prelude::*;

    fn read(text: &str) -> Result<Read, LogicError> {
        drain(&mut SaleaeCsv::new(
            BufReader::with_capacity(5, text.as_bytes()),
            Path::new("t.csv"),
        )?)
    }

    #[test]
    fn rows_are_changes_from_the_first_row() {
        let text = "\u{feff}\"Time [s]\",\"CS\",RD ,Channel 2\r\n-0.000001000,0,1,X\r\n\
            0.000000000,1,1,X\r\n0.000000000,1,1,0\r\n\r\n0.000000500,1,1,0\r\n0.000002500,1,X,1\r\n";
        let (info, changes, end) = read(text).expect("reads");
        assert_eq!(info.channels, ["CS", "RD", "Channel 2"]);
        assert_eq!((info.resolution_ps, info.sample_rate_hz), (1, None));
        assert_eq!(info.format, "Saleae Logic 2 CSV");
        assert_eq!(
            changes,
            [
                ch(0, 0b010, 0b100),
                ch(1_000_000, 0b011, 0),
                ch(3_500_000, 0b101, 0b010)
            ]
        );
        assert_eq!(end, 3_500_000);
    }

    #[test]
    fn seconds_are_read_exactly_to_the_picosecond() {
        for (text, ps) in [
            ("1.000000000001", Some(1_000_000_000_001)),
            ("12", Some(12_000_000_000_000)),
            ("0.0000000000005", Some(1)),
            ("0.00000000000049", Some(0)),
            ("-0.0000000000005", Some(-1)),
            ("1e-12", Some(1)),
            ("1.2345678901235E-03", Some(1_234_567_890)),
            ("+.5", Some(500_000_000_000)),
            ("5.", Some(5_000_000_000_000)),
            ("0000000000000000000000000000000000000001e-12", Some(1)),
            ("1e-40", Some(0)),
            ("", None),
            (".", None),
            ("abc", None),
            ("1e999", None),
            ("1,5", None),
            ("99999999999999999999999999999999", None),
        ] {
            assert_eq!(seconds_to_ps(text), ps, "{text}");
        }
    }

    #[test]
    fn bad_files_are_errors_naming_the_line() {
        let head = "Time [s],Channel 0,Channel 1\n";
        let many = format!("Time [s]{}\n", ",c".repeat(65));
        let long = format!("{head}0,{}\n", "1".repeat(MAX_LINE));
        for (text, want) in [
            ("", "t.csv: empty file"),
            (
                "0.0,1,0\n0.1,0,0\n",
                "line 1: not a Saleae CSV: the first column is `0.0`",
            ),
            ("Time [s]\n", "line 1: no channel columns"),
            (many.as_str(), "line 1: 65 channels; at most 64"),
            (&format!("{head}0.0,1\n"), "line 2: 1 values for 2 channels"),
            (
                &format!("{head}0.0,1,0,1\n"),
                "line 2: 3 values for 2 channels",
            ),
            (
                &format!("{head}0.0,1,0\nnow,1,1\n"),
                "line 3: bad time `now`",
            ),
            (
                &format!("{head}0.0,1,2\n"),
                "line 2: `2` for Channel 1: not 0, 1 or X",
            ),
            (
                &format!("{head}0.5,1,0\n0.1,1,1\n"),
                "line 3: a time before the first row's",
            ),
            (
                &format!("{head}0.1,1,0\n0.5,0,0\n0.2,1,1\n"),
                "line 4: time goes backwards: 0.2 s",
            ),
            (&format!("{head}0,1,0\n1e20,1,1\n"), "line 3: bad time"),
            (
                &format!("{head}0,1,0\n2e7,1,1\n"),
                "line 3: a time past 2^64 picoseconds",
            ),
            (long.as_str(), "line 2: a line longer than 65536 bytes"),
            (
                &format!("{head}0,1,\u{ff}\n"),
                "line 2: `\u{ff}` for Channel 1",
            ),
        ] {
            match read(text) {
                Ok(r) => panic!("{want}: read {r:?}"),
                Err(e) => assert!(e.to_string().contains(want), "{want}: {e}"),
            }
        }
    }

    proptest! {
        /// Random bytes after a good header: rows or an error, never a
        /// panic, the changes in time order.
        #[test]
        fn random_rows_never_panic(bytes in proptest::collection::vec(
            prop_oneof![Just(b','), Just(b'\n'), Just(b'0'), Just(b'1'), Just(b'X'), Just(b'.'), Just(b'-'), Just(b'e'), any::<u8>()],
            0..300,
        )) {
            let mut text = b"Time [s],a,b\n".to_vec();
            text.extend(bytes);
            let r = SaleaeCsv::new(&text[..], Path::new("t.csv"));
            let mut r = r.expect("the header is good");
            let mut last = None;
            while let Ok(Some(c)) = r.next_change() {
                prop_assert!(last.is_none_or(|t| t < c.time_ps));
                last = Some(c.time_ps);
            }
        }
    }
}
