//! The header of a VCD, for [`super::vcd`]: the tokenizer (whitespace-
//! separated tokens straight from a `BufRead`'s buffer, none kept longer
//! than [`MAX_TOKEN`] bytes, each with its line), the declarations read up
//! to `$enddefinitions`, and what the reader needs of them: the channels
//! and their names, the timescale, and a table from identifier codes to
//! the bits of their variables. Errors name the file and the line.

use super::source::{LogicError, MAX_CHANNELS};
use std::collections::HashMap;
use std::io::{self, BufRead};
use std::path::PathBuf;

/// The most bytes of a token read past [`MAX_TOKEN`] before the file is
/// refused.
const MAX_SKIPPED: u64 = 1 << 20;

/// The longest token kept: a longer one is cut there (and refused where it
/// matters: a name, a value, a time).
pub const MAX_TOKEN: usize = 4096;

/// The deepest nesting of `$scope`s read: deeper is refused, so that the
/// scopes kept stay bounded whatever the file (a million nested scopes is
/// no capture).
pub const MAX_SCOPE_DEPTH: usize = 256;

/// A scope's name is kept to this many bytes (it names channels only).
const MAX_SCOPE_NAME: usize = 256;

/// The most variables whose values are ignored (real, string, event): more
/// is refused, so that their codes kept stay bounded.
pub const MAX_IGNORED: usize = 16_384;

/// Identifier codes of up to this many characters are looked up in a
/// table; longer ones in a hash map.
const DENSE_ID_CHARS: usize = 2;

/// Whitespace-separated tokens of a `BufRead`, with the line each starts on.
pub(super) struct Tokens<R> {
    pub(super) r: R,
    /// The file, for errors.
    pub(super) file: PathBuf,
    /// The line of the next byte.
    pub(super) line: u64,
    pub(super) tok: Vec<u8>,
    /// The line `tok` starts on.
    pub(super) tok_line: u64,
    /// `tok` was cut at [`MAX_TOKEN`] bytes.
    pub(super) long: bool,
    /// The bytes of `tok` read past [`MAX_TOKEN`] and dropped.
    pub(super) skipped: u64,
    /// The input ended inside a token, with no whitespace after it: a
    /// file cut short in the middle of a line (every writer ends its last
    /// line).
    pub(super) cut: bool,
}

impl<R: BufRead> Tokens<R> {
    /// Reads the next token into `tok`; `false` at the end of the input.
    pub(super) fn next(&mut self) -> io::Result<bool> {
        self.tok.clear();
        self.long = false;
        self.skipped = 0;
        loop {
            let buf = match self.r.fill_buf() {
                Ok(b) => b,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            if buf.is_empty() {
                self.cut |= !self.tok.is_empty();
                return Ok(!self.tok.is_empty());
            }
            let mut i = 0;
            if self.tok.is_empty() {
                while i < buf.len() && buf[i].is_ascii_whitespace() {
                    self.line += u64::from(buf[i] == b'\n');
                    i += 1;
                }
                if i == buf.len() {
                    self.r.consume(i);
                    continue;
                }
                self.tok_line = self.line;
            }
            let start = i;
            while i < buf.len() && !buf[i].is_ascii_whitespace() {
                i += 1;
            }
            let take = (i - start).min(MAX_TOKEN.saturating_sub(self.tok.len()));
            self.tok.extend_from_slice(&buf[start..start + take]);
            self.long |= take < i - start;
            self.skipped += (i - start - take) as u64;
            let ended = i < buf.len();
            self.r.consume(i);
            if ended {
                return Ok(true);
            }
            // A token past its limit is read on, not kept, but never for
            // long: a file of one 10 GB token is no VCD.
            if self.skipped > MAX_SKIPPED {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("a token longer than {MAX_SKIPPED} bytes: not a VCD"),
                ));
            }
        }
    }
}

/// A token for a message: at most 40 characters, lossy.
pub(super) fn shown(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(40)]).into_owned();
    match tok.len() > 40 {
        true => format!("{s}..."),
        false => s,
    }
}

/// Where a variable's bits go: `width` channels from bit `shift` of the
/// levels.
#[derive(Debug, Clone, Copy)]
pub(super) struct Target {
    pub(super) shift: u32,
    pub(super) width: u32,
}

impl Target {
    pub(super) fn mask(self) -> u64 {
        ones(self.width) << self.shift
    }
}

/// The low `n` bits set (`n` up to 64).
pub(super) fn ones(n: u32) -> u64 {
    match n {
        0 => 0,
        n if n >= 64 => u64::MAX,
        n => (1u64 << n) - 1,
    }
}

/// A logic variable as the header declares it.
#[derive(Debug)]
struct Decl {
    id: Vec<u8>,
    /// Its scopes, outermost first.
    scopes: Vec<String>,
    /// Its reference, with a bit-select (`D[3]`) but no range.
    name: String,
    /// The range of a vector: (msb, lsb).
    range: Option<(i64, i64)>,
    width: u32,
}

impl Decl {
    /// The channel names of its bits, bit 0 (the value's last digit) first.
    fn channel_names(&self, base: &str) -> Vec<String> {
        if self.width == 1 && self.range.is_none() {
            return vec![base.to_string()];
        }
        let (msb, lsb) = self.range.unwrap_or((i64::from(self.width) - 1, 0));
        let step = if msb >= lsb { 1 } else { -1 };
        (0..i64::from(self.width))
            .map(|p| format!("{base}[{}]", lsb.saturating_add(step * p)))
            .collect()
    }
}

/// Identifier codes to the slots of their variables' targets.
#[derive(Debug, Default)]
pub(super) struct Ids {
    /// By the code's number, for short codes: slot + 1, 0 for none.
    dense: Vec<u32>,
    sparse: HashMap<Vec<u8>, u32>,
}

impl Ids {
    /// The number of a short code of printable characters.
    fn number(code: &[u8]) -> Option<usize> {
        if code.is_empty() || code.len() > DENSE_ID_CHARS {
            return None;
        }
        let mut n = 0usize;
        for &c in code {
            if !(b'!'..=b'~').contains(&c) {
                return None;
            }
            n = n * 94 + usize::from(c - b'!') + 1;
        }
        Some(n)
    }

    pub(super) fn get(&self, code: &[u8]) -> Option<u32> {
        let slot = match Self::number(code) {
            Some(n) => self.dense.get(n).copied().unwrap_or(0),
            None => self.sparse.get(code).copied().unwrap_or(0),
        };
        slot.checked_sub(1)
    }

    fn insert(&mut self, code: &[u8], slot: u32) {
        match Self::number(code) {
            Some(n) => {
                if self.dense.len() <= n {
                    self.dense.resize(n + 1, 0);
                }
                self.dense[n] = slot + 1;
            }
            None => {
                self.sparse.insert(code.to_vec(), slot + 1);
            }
        }
    }
}

/// What the header says.
#[derive(Debug, Default)]
struct Header {
    decls: Vec<Decl>,
    /// Every 1-bit channel declared, those past [`MAX_CHANNELS`] too.
    bits: u64,
    /// Codes of variables whose values are ignored (real, string, event).
    ignored: Vec<Vec<u8>>,
    /// Picoseconds per tick: `mul / div`.
    mul: u64,
    div: u64,
    version: Option<String>,
    ppmc: bool,
}

/// What the reader needs of a header.
#[derive(Debug)]
pub(super) struct Layout {
    pub(super) channels: Vec<String>,
    pub(super) resolution_ps: u64,
    pub(super) format: String,
    pub(super) ids: Ids,
    /// The targets of each slot: `slots[s]` is a range of `targets`.
    pub(super) slots: Vec<(u32, u32)>,
    pub(super) targets: Vec<Target>,
    /// Every channel's bit.
    pub(super) all: u64,
    /// Picoseconds per tick: `mul / div`.
    pub(super) mul: u64,
    pub(super) div: u64,
}

/// Reads a header up to `$enddefinitions`.
pub(super) fn read_header<R: BufRead>(t: &mut Tokens<R>) -> Result<Layout, LogicError> {
    let h = t.header()?;
    lay_out(h, t)
}

impl<R> Tokens<R> {
    pub(super) fn err(&self, line: u64, what: impl Into<String>) -> LogicError {
        LogicError::new(&self.file, format!("line {line}"), what)
    }
}

impl<R: BufRead> Tokens<R> {
    /// The next token, or an error naming what the file ended in.
    pub(super) fn next_in(&mut self, inside: &str, opened: u64) -> Result<(), LogicError> {
        match self.next() {
            Ok(true) => Ok(()),
            Ok(false) => Err(self.err(
                self.line,
                format!("the file ends inside {inside} (opened on line {opened})"),
            )),
            Err(e) => Err(self.err(self.line, format!("cannot read: {e}"))),
        }
    }

    /// The tokens of a command's body up to its `$end` (the first `keep`
    /// of them kept, the rest read and dropped).
    pub(super) fn body(&mut self, cmd: &str, keep: usize) -> Result<Vec<Vec<u8>>, LogicError> {
        let opened = self.tok_line;
        let mut out = Vec::new();
        loop {
            self.next_in(cmd, opened)?;
            if self.tok == b"$end" {
                return Ok(out);
            }
            if out.len() < keep {
                out.push(self.tok.clone());
            }
        }
    }

    fn header(&mut self) -> Result<Header, LogicError> {
        let mut h = Header {
            mul: 1000,
            div: 1,
            ..Header::default()
        };
        let mut scopes: Vec<String> = Vec::new();
        let (mut first, mut meta) = (true, false);
        loop {
            match self.next() {
                Ok(true) => {}
                Ok(false) if first => {
                    return Err(LogicError::new(&self.file, "", "empty file: not a VCD"))
                }
                Ok(false) => {
                    return Err(self.err(self.line, "the file ends before $enddefinitions"))
                }
                Err(e) => return Err(self.err(self.line, format!("cannot read: {e}"))),
            }
            if first {
                first = false;
                if let Some(rest) = self.tok.strip_prefix("\u{feff}".as_bytes()) {
                    self.tok = rest.to_vec();
                }
                // sigrok-cli 0.7.2 (libsigrok 0.5.2) converting a VCD to a
                // VCD starts the file with `META samplerate: N`: skipped.
                meta = self.tok == b"META";
            }
            if meta && self.tok_line == 1 {
                continue;
            }
            let line = self.tok_line;
            let tok = std::mem::take(&mut self.tok);
            match tok.as_slice() {
                b"$enddefinitions" => {
                    self.body("$enddefinitions", 0)?;
                    return Ok(h);
                }
                b"$timescale" => {
                    let words = self.body("$timescale", 4)?;
                    (h.mul, h.div) = timescale(&words.concat()).ok_or_else(|| {
                        self.err(
                            line,
                            format!("bad $timescale `{}`", shown(&words.join(&b' '))),
                        )
                    })?;
                }
                b"$scope" => {
                    let words = self.body("$scope", 3)?;
                    if scopes.len() == MAX_SCOPE_DEPTH {
                        return Err(self.err(
                            line,
                            format!("$scope nested deeper than {MAX_SCOPE_DEPTH} levels: not a capture this reader takes"),
                        ));
                    }
                    let name = words.get(1).or(words.first()).map(|w| {
                        String::from_utf8_lossy(&w[..w.len().min(MAX_SCOPE_NAME)]).into_owned()
                    });
                    scopes.push(name.unwrap_or_default());
                }
                b"$upscope" => {
                    self.body("$upscope", 0)?;
                    scopes.pop();
                }
                b"$var" => self.var(&mut h, &scopes, line)?,
                b"$version" => {
                    let words = self.body("$version", 8)?;
                    let text = String::from_utf8_lossy(&words.join(&b' ')).into_owned();
                    h.version = Some(text.chars().take(60).collect());
                }
                b"$comment" => {
                    let words = self.body("$comment", 1)?;
                    h.ppmc |= words.first().is_some_and(|w| w == b"ppmc");
                }
                t if t.starts_with(b"$") && t != b"$end" => {
                    let cmd = format!("`{}`", shown(t));
                    self.body(&cmd, 0)?;
                }
                t if first_data(t) => {
                    return Err(self.err(line, format!("`{}` before $enddefinitions", shown(t))))
                }
                t => {
                    return Err(self.err(
                        line,
                        format!("not a VCD: `{}` where a command ($...) should be", shown(t)),
                    ))
                }
            }
        }
    }

    /// A `$var type size code reference [range] $end`.
    fn var(&mut self, h: &mut Header, scopes: &[String], line: u64) -> Result<(), LogicError> {
        let words = self.body("$var", 16)?;
        if words.len() < 4 {
            return Err(self.err(line, "a $var needs a type, a size, a code and a reference"));
        }
        let kind = words[0].to_ascii_lowercase();
        let width: u64 = std::str::from_utf8(&words[1])
            .ok()
            .and_then(|s| s.parse().ok())
            .filter(|&w| w > 0)
            .ok_or_else(|| {
                self.err(
                    line,
                    format!("$var size `{}` is not a number of bits", shown(&words[1])),
                )
            })?;
        let id = words[2].clone();
        if matches!(
            kind.as_slice(),
            b"real" | b"realtime" | b"string" | b"event" | b"shortreal"
        ) {
            if h.ignored.len() == MAX_IGNORED {
                return Err(self.err(
                    line,
                    format!("more than {MAX_IGNORED} real, string or event variables: not a capture this reader takes"),
                ));
            }
            h.ignored.push(id);
            return Ok(());
        }
        let mut refs: Vec<&[u8]> = words[3..].iter().map(Vec::as_slice).collect();
        let mut range = None;
        if refs.len() > 1 {
            if let Some(r) = refs.last().and_then(|t| index(t)) {
                range = Some(r);
                refs.pop();
            }
        }
        let mut name = String::from_utf8_lossy(&refs.join(&b' ')).into_owned();
        if range.is_none() && width > 1 {
            if let Some(at) = name.rfind('[') {
                if let Some(r) = index(&name.as_bytes()[at..]) {
                    range = Some(r);
                    name.truncate(at);
                }
            }
        }
        let range = match range {
            Some((m, l)) if width == 1 => {
                if m == l {
                    name.push_str(&format!("[{m}]"));
                } else {
                    name.push_str(&format!("[{m}:{l}]"));
                }
                None
            }
            r => r,
        };
        h.bits = h.bits.saturating_add(width);
        if h.bits <= MAX_CHANNELS as u64 {
            h.decls.push(Decl {
                id,
                scopes: scopes.to_vec(),
                name,
                range,
                width: width as u32,
            });
        }
        Ok(())
    }
}

/// Channels named, codes mapped to their bits.
fn lay_out<R>(h: Header, t: &Tokens<R>) -> Result<Layout, LogicError> {
    let line = t.tok_line;
    if h.bits > MAX_CHANNELS as u64 {
        return Err(t.err(
            line,
            format!(
                "the file declares {} one-bit channels (vectors counted bit by bit); \
                 at most {MAX_CHANNELS} can be read",
                h.bits
            ),
        ));
    }
    if h.decls.is_empty() {
        return Err(t.err(
            line,
            "the file declares no logic signal (only reals, strings or events, or none)",
        ));
    }
    let mut out = Layout {
        channels: Vec::new(),
        resolution_ps: ((h.mul + h.div / 2) / h.div).max(1),
        format: match (h.version, h.ppmc) {
            (Some(v), _) if !v.is_empty() => format!("VCD ({v})"),
            (_, true) => "VCD (ppmc)".into(),
            _ => "VCD".into(),
        },
        ids: Ids::default(),
        slots: Vec::new(),
        targets: Vec::new(),
        all: 0,
        mul: h.mul,
        div: h.div,
    };
    let names = unique_names(&h.decls);
    let mut shift = 0u32;
    let mut by_id: Vec<(&[u8], Target)> = Vec::new();
    for (d, base) in h.decls.iter().zip(names) {
        out.channels.extend(d.channel_names(&base));
        let width = d.width;
        by_id.push((&d.id, Target { shift, width }));
        shift += d.width;
    }
    out.all = ones(shift);
    by_id.sort_by(|a, b| a.0.cmp(b.0));
    for (i, (id, t)) in by_id.iter().enumerate() {
        if i == 0 || by_id[i - 1].0 != *id {
            out.ids.insert(id, out.slots.len() as u32);
            out.slots.push((out.targets.len() as u32, 0));
        }
        out.targets.push(*t);
        if let Some(s) = out.slots.last_mut() {
            s.1 += 1;
        }
    }
    for id in &h.ignored {
        if out.ids.get(id).is_none() {
            out.ids.insert(id, out.slots.len() as u32);
            out.slots.push((0, 0));
        }
    }
    Ok(out)
}

/// Whether a token is a value change or a timestamp (not a command).
fn first_data(t: &[u8]) -> bool {
    matches!(
        t.first(),
        Some(b'#' | b'0' | b'1' | b'x' | b'X' | b'z' | b'Z' | b'b' | b'B' | b'r' | b'R')
    )
}

/// A timescale's picoseconds per tick, `(mul, div)`: `1ns`, `10 us`, `100fs`.
fn timescale(text: &[u8]) -> Option<(u64, u64)> {
    let text = std::str::from_utf8(text).ok()?;
    let at = text.find(|c: char| !c.is_ascii_digit())?;
    let n: u64 = text[..at]
        .parse()
        .ok()
        .filter(|&n| n > 0 && n <= 1_000_000)?;
    let (mul, div) = match &text[at..] {
        "s" => (1_000_000_000_000, 1),
        "ms" => (1_000_000_000, 1),
        "us" => (1_000_000, 1),
        "ns" => (1_000, 1),
        "ps" => (1, 1),
        "fs" => (1, 1000),
        _ => return None,
    };
    let mul = n.checked_mul(mul)?;
    let g = gcd(mul, div);
    Some((mul / g, div / g))
}

fn gcd(a: u64, b: u64) -> u64 {
    match b {
        0 => a,
        b => gcd(b, a % b),
    }
}

/// A range or bit-select `[7:0]`, `[3]`: (msb, lsb).
fn index(t: &[u8]) -> Option<(i64, i64)> {
    let inner = std::str::from_utf8(t.strip_prefix(b"[")?.strip_suffix(b"]")?).ok()?;
    let (m, l) = inner.split_once(':').unwrap_or((inner, inner));
    Some((m.trim().parse().ok()?, l.trim().parse().ok()?))
}

/// Each variable's base name: its reference, or `scope.reference` when two
/// share it, or its whole path when those are shared too.
fn unique_names(decls: &[Decl]) -> Vec<String> {
    let count = |names: &[String], n: &str| names.iter().filter(|m| *m == n).count();
    let plain: Vec<String> = decls.iter().map(|d| d.name.clone()).collect();
    let scoped: Vec<String> = decls
        .iter()
        .map(|d| match d.scopes.last() {
            Some(s) => format!("{s}.{}", d.name),
            None => d.name.clone(),
        })
        .collect();
    decls
        .iter()
        .enumerate()
        .map(|(i, d)| {
            if count(&plain, &plain[i]) == 1 {
                plain[i].clone()
            } else if count(&scoped, &scoped[i]) == 1 {
                scoped[i].clone()
            } else {
                let mut path = d.scopes.join(".");
                if !path.is_empty() {
                    path.push('.');
                }
                path + &d.name
            }
        })
        .collect()
}
