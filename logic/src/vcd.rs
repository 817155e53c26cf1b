//! Value change dumps (IEEE 1364 VCD) from any producer: sigrok-cli and
//! PulseView, Saleae Logic 2's VCD export, GTKWave's tools, simulators, and
//! ppmc's own `ppmc export`, read as one stream of level changes
//! ([`Change`]) in bounded memory, whatever the file's length.
//!
//! What is read: 1-bit signals and vectors (`D [7:0]` is the channels
//! `D[0]`..`D[7]`, bit 0 the value's last digit; a value shorter than its
//! vector is extended on the left with `0`, or with `x` or `z` when it
//! starts with one); any `$timescale` from 1 s down to 1 fs, times in
//! picoseconds, exact when the timescale is a whole number of picoseconds,
//! rounded to the nearest below that (two times that round to one are one
//! change); `$dumpvars`, `$dumpall`, `$dumpon` and `$dumpoff` (which makes
//! every channel unknown); `x`, `z` (and VHDL's `u`, `w`, `-`) as unknown,
//! VHDL's `l` and `h` as 0 and 1; scopes (a channel is named by its
//! reference alone, or `scope.name` when two share a name, or by its whole
//! path when even that is shared); identifier codes of any length; one
//! code declared by several variables (each is a channel of its own);
//! references of several words (`Channel 0`). Real and string variables
//! (`real`, `realtime`, `string`) and events are declared and ignored, and
//! so are their values; `$comment`s are skipped anywhere, and so are the
//! header commands ppmc has no use for (`$date`, GTKWave's `$attrbegin`).
//! A variable never given a value is unknown; values before the first
//! timestamp are at time 0; the first change is the levels at the first
//! timestamp; a timestamp at which nothing changes gives nothing; the
//! capture ends at the last timestamp. A file without `$timescale` is in
//! nanoseconds, as GTKWave takes it. A first line `META samplerate: N`,
//! which sigrok-cli 0.7.2 puts before the header when it converts a VCD to
//! a VCD, is skipped. At most [`MAX_CHANNELS`](super::source::MAX_CHANNELS) 1-bit
//! channels: more is an error that says how many.
//!
//! Why not the `vcd` crate (which `vcd_export.rs` writes with): its parser
//! streams, but it refuses what real producers write (variable types such
//! as SystemVerilog's `logic`, VHDL scope types, GTKWave's `$attrbegin`,
//! references of several words), builds a `Vec` for every vector value and
//! a `String` of any length for every comment, and reads a byte at a time.
//! The tokenizer here is small: whitespace-separated tokens straight from
//! the `BufRead`'s buffer, none kept longer than [`MAX_TOKEN`] bytes, and
//! identifier codes looked up in a table, not hashed. On a 105 MB VCD
//! (sixteen signals and a bus, in release, on a shared 2-core machine)
//! this reader gives every change at 116 MB/s; the crate's parser alone,
//! keeping no state, parses it at 61 MB/s (the ignored `throughput` test
//! of `capture/tests/it/logic_readers.rs`).
//!
//! Every error names the file and the line (`line 12: ...`); nothing
//! panics.

use super::source::{Change, LogicError, LogicInfo, LogicSource};
use super::vcd_header::{ones, read_header, shown, Layout, Tokens};
use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

pub use super::vcd_header::{MAX_IGNORED, MAX_SCOPE_DEPTH, MAX_TOKEN};

/// A streaming VCD reader.
pub struct VcdReader<R> {
    info: LogicInfo,
    tokens: Tokens<R>,
    /// The value token of a vector, real or string change.
    value: Vec<u8>,
    /// Codes to bits, timescale.
    map: Layout,
    levels: u64,
    unknown: u64,
    last: Option<(u64, u64)>,
    /// The current time, once a timestamp or a value has set it.
    now: Option<u64>,
    /// The current timestamp, in the file's ticks.
    ticks: u64,
    /// The open `$dumpvars`/`$dumpall`/`$dumpon`/`$dumpoff`, if any.
    section: Option<&'static str>,
    done: bool,
}

impl<R> fmt::Debug for VcdReader<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("VcdReader")
            .field("file", &self.tokens.file)
            .field("info", &self.info)
            .field("line", &self.tokens.line)
            .finish_non_exhaustive()
    }
}

impl VcdReader<BufReader<File>> {
    /// Opens a VCD file (a regular file: never blocks on a FIFO) and reads
    /// its header.
    pub fn open(path: &Path) -> Result<Self, LogicError> {
        let file = ppmc_files::open_stream(path).map_err(|e| LogicError::opening(path, e))?;
        VcdReader::new(BufReader::with_capacity(1 << 16, file), path)
    }
}

impl<R: BufRead> VcdReader<R> {
    /// Reads the header of the VCD `r`; `file` names it in errors.
    pub fn new(r: R, file: &Path) -> Result<Self, LogicError> {
        let mut tokens = Tokens {
            r,
            file: file.to_path_buf(),
            line: 1,
            tok: Vec::new(),
            tok_line: 1,
            long: false,
            skipped: 0,
            cut: false,
        };
        let map = read_header(&mut tokens)?;
        Ok(VcdReader {
            info: LogicInfo {
                channels: map.channels.clone(),
                resolution_ps: map.resolution_ps,
                sample_rate_hz: None,
                format: map.format.clone(),
            },
            tokens,
            value: Vec::new(),
            levels: 0,
            unknown: map.all,
            map,
            last: None,
            now: None,
            ticks: 0,
            section: None,
            done: false,
        })
    }

    fn err(&self, line: u64, what: impl Into<String>) -> LogicError {
        self.tokens.err(line, what)
    }

    fn undeclared(&self, id: &[u8], line: u64) -> LogicError {
        let id = shown(id);
        self.err(line, format!("a value for `{id}`, a code no $var declares"))
    }

    /// Sets the bits of the variables of code `id` from `digits` (most
    /// significant first).
    fn set(&mut self, id: &[u8], digits: &[u8], line: u64) -> Result<(), LogicError> {
        let Some(slot) = self.map.ids.get(id) else {
            return Err(self.undeclared(id, line));
        };
        let (start, n) = self.map.slots[slot as usize];
        for k in start..start + n {
            let t = self.map.targets[k as usize];
            let (bits, unk) = value(digits, t.width).ok_or_else(|| {
                self.err(
                    line,
                    format!("bad value `{}` for `{}`", shown(digits), shown(id)),
                )
            })?;
            let m = t.mask();
            self.levels = self.levels & !m | bits << t.shift;
            self.unknown = self.unknown & !m | unk << t.shift;
        }
        Ok(())
    }

    /// The levels at the current time, if they differ from the last given.
    fn flush(&mut self) -> Option<Change> {
        let now = self.now?;
        let state = (self.levels, self.unknown);
        if self.last == Some(state) {
            return None;
        }
        self.last = Some(state);
        Some(Change {
            time_ps: now,
            levels: self.levels,
            unknown: self.unknown,
        })
    }

    /// A `#ticks` timestamp: the change at the time before it, if any.
    fn timestamp(&mut self, line: u64) -> Result<Option<Change>, LogicError> {
        let digits = &self.tokens.tok[1..];
        let ticks = std::str::from_utf8(digits)
            .ok()
            .filter(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| {
                self.err(line, format!("bad timestamp `{}`", shown(&self.tokens.tok)))
            })?;
        if self.now.is_some() && ticks < self.ticks {
            return Err(self.err(
                line,
                format!("time goes backwards: #{ticks} after #{}", self.ticks),
            ));
        }
        let ps = u128::from(ticks) * u128::from(self.map.mul) + u128::from(self.map.div / 2);
        let ps = u64::try_from(ps / u128::from(self.map.div)).map_err(|_| {
            self.err(
                line,
                format!("#{ticks} is past 2^64 picoseconds (213 days)"),
            )
        })?;
        self.ticks = ticks;
        match self.now {
            Some(now) if now == ps => Ok(None),
            Some(_) => {
                let out = self.flush();
                self.now = Some(ps);
                Ok(out)
            }
            None => {
                self.now = Some(ps);
                Ok(None)
            }
        }
    }

    /// Reads on to the next change.
    fn advance(&mut self) -> Result<Option<Change>, LogicError> {
        loop {
            match self.tokens.next() {
                Ok(true) => {}
                Ok(false) => {
                    self.done = true;
                    if let Some(s) = self.section {
                        return Err(self.err(self.tokens.line, format!("the file ends inside {s}")));
                    }
                    return Ok(self.flush());
                }
                Err(e) => return Err(self.err(self.tokens.line, format!("cannot read: {e}"))),
            }
            let line = self.tokens.tok_line;
            if self.tokens.long {
                return Err(self.err(line, format!("a token longer than {MAX_TOKEN} bytes")));
            }
            let Some(&head) = self.tokens.tok.first() else {
                continue;
            };
            match head {
                b'#' => {
                    if let Some(c) = self.timestamp(line)? {
                        return Ok(Some(c));
                    }
                }
                b'0' | b'1' | b'x' | b'X' | b'z' | b'Z' | b'u' | b'U' | b'w' | b'W' | b'l'
                | b'L' | b'h' | b'H' | b'-' => {
                    self.now.get_or_insert(0);
                    let tok = std::mem::take(&mut self.tokens.tok);
                    let r = self.set(&tok[1..], &tok[..1], line);
                    self.tokens.tok = tok;
                    r?;
                }
                b'b' | b'B' | b'r' | b'R' | b's' | b'S' => {
                    self.now.get_or_insert(0);
                    // Two buffers, swapped, so that no value allocates.
                    std::mem::swap(&mut self.value, &mut self.tokens.tok);
                    match self.tokens.next() {
                        Ok(true) if !self.tokens.long => {}
                        Ok(_) => {
                            let v = shown(&self.value);
                            return Err(self.err(line, format!("a value `{v}` without a code")));
                        }
                        Err(e) => {
                            return Err(self.err(self.tokens.line, format!("cannot read: {e}")))
                        }
                    }
                    let (id, val) = (
                        std::mem::take(&mut self.tokens.tok),
                        std::mem::take(&mut self.value),
                    );
                    let r = match head {
                        b'b' | b'B' => self.set(&id, &val[1..], line),
                        _ if self.map.ids.get(&id).is_none() => Err(self.undeclared(&id, line)),
                        _ => Ok(()),
                    };
                    (self.tokens.tok, self.value) = (id, val);
                    r?;
                }
                b'$' => self.command(line)?,
                _ => {
                    return Err(self.err(line, format!("unexpected `{}`", shown(&self.tokens.tok))));
                }
            }
        }
    }

    /// A command in the value changes.
    fn command(&mut self, line: u64) -> Result<(), LogicError> {
        let section = match self.tokens.tok.as_slice() {
            b"$comment" => {
                self.tokens.body("$comment", 0)?;
                return Ok(());
            }
            b"$end" => {
                return match self.section.take() {
                    Some(_) => Ok(()),
                    None => Err(self.err(line, "`$end` with no section open")),
                };
            }
            b"$dumpvars" => "$dumpvars",
            b"$dumpall" => "$dumpall",
            b"$dumpon" => "$dumpon",
            b"$dumpoff" => "$dumpoff",
            t => {
                return Err(self.err(
                    line,
                    format!("unexpected command `{}` after $enddefinitions", shown(t)),
                ))
            }
        };
        if let Some(open) = self.section {
            return Err(self.err(line, format!("{section} inside {open}")));
        }
        self.section = Some(section);
        if section == "$dumpoff" {
            self.now.get_or_insert(0);
            self.levels = 0;
            self.unknown = self.map.all;
        }
        Ok(())
    }
}

impl<R: BufRead> LogicSource for VcdReader<R> {
    fn info(&self) -> &LogicInfo {
        &self.info
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        if self.done {
            return Ok(None);
        }
        match self.advance() {
            // The last token of a file that ends in the middle of a line
            // may be a part of one (`1` cut from `1!`, a code cut short,
            // `#2` cut from `#2151`): a value without its code, or for a
            // code not declared, or a time before the last, there is where
            // the recording ends, as `cut_short` says.
            Err(e)
                if self.tokens.cut
                    && (e.what.starts_with("a value")
                        || e.what.starts_with("time goes backwards")) =>
            {
                self.done = true;
                Ok(self.flush())
            }
            r => r,
        }
    }

    fn end_ps(&self) -> u64 {
        self.now.unwrap_or(0)
    }

    fn cut_short(&self) -> Option<String> {
        (self.done && self.tokens.cut).then(|| {
            format!(
                "the file ends in the middle of line {}, with no end of line: the recording was cut short",
                self.tokens.line
            )
        })
    }
}

/// A value's bits and unknown bits over `width` bits, left-extended as
/// VCD extends it: `x` and `z` with themselves, `0` and `1` with `0`.
fn value(digits: &[u8], width: u32) -> Option<(u64, u64)> {
    let first = *digits.first()?;
    let w = width as usize;
    let cut = &digits[digits.len().saturating_sub(w)..];
    let (mut bits, mut unk) = (0u64, 0u64);
    for &c in cut {
        bits <<= 1;
        unk <<= 1;
        match c {
            b'1' | b'h' | b'H' => bits |= 1,
            b'0' | b'l' | b'L' => {}
            b'x' | b'X' | b'z' | b'Z' | b'u' | b'U' | b'w' | b'W' | b'-' => unk |= 1,
            _ => return None,
        }
    }
    if cut.len() < w
        && matches!(
            first,
            b'x' | b'X' | b'z' | b'Z' | b'u' | b'U' | b'w' | b'W' | b'-'
        )
    {
        unk |= ones(width) & !ones(cut.len() as u32);
    }
    Some((bits, unk))
}

#[cfg(test)]
mod tests {
    use super::super::source::testing::{ch, drain, Read};
    use super::*;
    use proptest::prelude::*;

    fn read_with(text: &[u8], capacity: usize) -> Result<Read, LogicError> {
        let r = BufReader::with_capacity(capacity, text);
        drain(&mut VcdReader::new(r, Path::new("t.vcd"))?)
    }

    fn read(text: &str) -> Read {
        let got = read_with(text.as_bytes(), 1 << 16).expect("a good VCD");
        // Every token split across buffer fills: the same result.
        let small = read_with(text.as_bytes(), 3).expect("a good VCD, read 3 bytes at a time");
        assert_eq!(small, got, "a small buffer reads the same");
        got
    }

    fn fails(text: &str) -> String {
        match read_with(text.as_bytes(), 1 << 16) {
            Ok(r) => panic!("read: {r:?}"),
            Err(e) => e.to_string(),
        }
    }

    const HEAD: &str = "$timescale 1 ns $end $scope module top $end\n\
        $var wire 1 ! a $end\n$var wire 1 \" b $end\n$upscope $end\n$enddefinitions $end\n";

    #[test]
    fn changes_are_merged_per_timestamp_and_empty_ones_give_nothing() {
        let (info, changes, end) =
            read(&format!("{HEAD}#0\n$dumpvars 0! 1\" $end\n#10 1!\n#20\n#30 0\" 0\"\n#40 0! 1!\n#50 1\" 0!\n#60\n"));
        assert_eq!(info.channels, ["a", "b"]);
        assert_eq!(info.resolution_ps, 1000);
        assert_eq!(info.sample_rate_hz, None);
        assert_eq!(
            changes,
            [
                ch(0, 0b10, 0),
                ch(10_000, 0b11, 0),
                ch(30_000, 0b01, 0),
                ch(50_000, 0b10, 0)
            ]
        );
        assert_eq!(end, 60_000);
    }

    #[test]
    fn a_signal_never_given_a_value_is_unknown_and_values_before_a_timestamp_are_at_zero() {
        let (_, changes, end) = read(&format!("{HEAD}1!\n#5 1\"\n"));
        assert_eq!(changes, [ch(0, 0b01, 0b10), ch(5_000, 0b11, 0)]);
        assert_eq!(end, 5_000);
        // The first change is at the first timestamp, whatever it is.
        let (_, changes, _) = read(&format!("{HEAD}#7\n#9 0! 0\"\n"));
        assert_eq!(changes, [ch(7_000, 0, 0b11), ch(9_000, 0, 0)]);
    }

    #[test]
    // The bits grouped by variable: bit[7], plain, bus, up, D.
    #[allow(clippy::unusual_byte_groupings)]
    fn vectors_become_one_channel_per_bit_and_short_values_extend() {
        let text = "$timescale 1ps $end\n$var wire 4 # D [3:0] $end\n$var reg 3 $ up [0:2] $end\n\
            $var wire 2 % bus[5:4] $end\n$var wire 3 & plain $end\n$var wire 1 ' bit [7] $end\n\
            $enddefinitions $end\n#0 b1010 # b1 $ b0 % bx & 1'\n#1 b1 # bz1 $ bX0 % b110 &\n#2 b11111 #\n";
        let (info, changes, _) = read(text);
        assert_eq!(
            info.channels,
            [
                "D[0]", "D[1]", "D[2]", "D[3]", "up[2]", "up[1]", "up[0]", "bus[4]", "bus[5]",
                "plain[0]", "plain[1]", "plain[2]", "bit[7]"
            ]
        );
        assert_eq!(info.resolution_ps, 1);
        assert_eq!(changes[0], ch(0, 0b1_000_00_001_1010, 0b0_111_00_000_0000));
        // z extends as z, x as x (the 1 of `bz1` stays at bit 0).
        assert_eq!(changes[1], ch(1, 0b1_110_00_001_0001, 0b0_000_10_110_0000));
        // A value longer than its vector keeps its last digits.
        assert_eq!(changes[2], ch(2, 0b1_110_00_001_1111, 0b0_000_10_110_0000));
    }

    #[test]
    fn x_and_z_are_unknown_in_any_case() {
        let (_, changes, _) = read(&format!(
            "{HEAD}#0 x! Z\"\n#1 1! z\"\n#2 X! 0\"\n#3 u! h\"\n"
        ));
        assert_eq!(
            changes,
            [
                ch(0, 0, 0b11),
                ch(1, 0b01, 0b10),
                ch(2, 0, 0b01),
                ch(3, 0b10, 0b01)
            ]
            .map(|c| Change {
                time_ps: c.time_ps * 1000,
                ..c
            })
        );
    }

    #[test]
    fn names_drop_the_scope_unless_two_share_one() {
        let text = "$scope module top $end $scope module a $end $var wire 1 ! clk $end $var wire 1 # d $end \
            $upscope $end $scope module b $end $var wire 1 \" clk $end $scope task t $end \
            $var wire 1 $ clk $end $upscope $end $upscope $end $scope module c $end $scope module a $end \
            $var wire 1 % clk $end $upscope $end $upscope $end $upscope $end $enddefinitions $end #0";
        let (info, _, _) = read(text);
        assert_eq!(
            info.channels,
            ["top.a.clk", "d", "b.clk", "t.clk", "top.c.a.clk"]
        );
    }

    #[test]
    fn an_alias_is_a_channel_of_its_own_and_long_codes_work() {
        let text = "$scope module top $end $var wire 1 !! clk $end $scope module cpu $end \
            $var wire 1 !! clk $end $var wire 1 abcdefgh data $end $var wire 1 {} Channel 0 $end \
            $upscope $end $upscope $end $enddefinitions $end #0 0!! 1abcdefgh 0{} #3 1!! #4 1{}";
        let (info, changes, _) = read(text);
        assert_eq!(info.channels, ["top.clk", "cpu.clk", "data", "Channel 0"]);
        assert_eq!(
            changes,
            [ch(0, 0b0100, 0), ch(3_000, 0b0111, 0), ch(4_000, 0b1111, 0)]
        );
    }

    #[test]
    fn any_timescale_gives_picoseconds() {
        for (scale, tick_ps, res) in [
            ("1 s", 1e12, 1_000_000_000_000),
            ("100ms", 1e11, 100_000_000_000),
            ("10 us", 1e7, 10_000_000),
            ("1ns", 1e3, 1_000),
            ("100 ps", 1e2, 100),
            ("1 ps", 1.0, 1),
        ] {
            let (info, changes, end) = read(&format!(
                "$timescale {scale} $end $var wire 1 ! a $end $enddefinitions $end #0 0! #3 1! #4"
            ));
            assert_eq!(info.resolution_ps, res, "{scale}");
            assert_eq!(changes[1].time_ps, (3.0 * tick_ps) as u64, "{scale}");
            assert_eq!(end, (4.0 * tick_ps) as u64, "{scale}");
        }
        // Femtoseconds round to the picosecond; two times that round to one
        // are one change.
        let (info, changes, end) = read(
            "$timescale 100 fs $end $var wire 1 ! a $end $var wire 1 \" b $end $enddefinitions $end \
             #0 0! 0\" #14 1! #16 1\" #20 0! #21 1! #10000000 0!",
        );
        assert_eq!(info.resolution_ps, 1);
        assert_eq!(
            changes,
            [
                ch(0, 0, 0),
                ch(1, 1, 0),
                ch(2, 0b11, 0),
                ch(1_000_000, 0b10, 0)
            ]
        );
        assert_eq!(end, 1_000_000);
        // Without a timescale: nanoseconds.
        let (info, _, end) = read("$var wire 1 ! a $end $enddefinitions $end #0 1! #2");
        assert_eq!((info.resolution_ps, end), (1000, 2000));
    }

    #[test]
    fn dumpoff_makes_everything_unknown_until_dumpon() {
        let (_, changes, _) = read(&format!(
            "{HEAD}#0 $dumpvars 1! 0\" $end\n#10 $dumpoff x! x\" $end\n#20 $dumpon 1! 1\" $end\n\
             #30 $dumpall 1! 1\" $end\n#40 $dumpoff $end\n#50 $dumpon 1! 0\" $end\n"
        ));
        assert_eq!(
            changes,
            [
                ch(0, 1, 0),
                ch(10_000, 0, 0b11),
                ch(20_000, 0b11, 0),
                ch(40_000, 0, 0b11),
                ch(50_000, 1, 0)
            ]
        );
    }

    #[test]
    fn comments_reals_strings_and_other_header_commands_are_skipped() {
        let text = "\u{feff}$date today $end $version Icarus Verilog $end $comment a $var in a comment $end\n\
            $timescale 1ns $end $attrbegin misc 07 top.a 1 $end $scope vhdl_architecture top $end\n\
            $var logic 1 ! a $end $var real 64 \" r $end $var string 1 # s $end $var event 1 $ e $end\n\
            $comment\n   more\n$end\n$upscope $end $enddefinitions $end\n\
            #0 1! r1.5 \" sHello # $comment 0! is not a change here $end\n#1 r2 \" 1$ $comment x $end\n#2 0!";
        let (info, changes, end) = read(text);
        assert_eq!(info.channels, ["a"]);
        assert_eq!(info.format, "VCD (Icarus Verilog)");
        assert_eq!(changes, [ch(0, 1, 0), ch(2_000, 0, 0)]);
        assert_eq!(end, 2_000);
    }

    #[test]
    fn the_meta_line_sigrok_cli_puts_first_is_skipped_there_only() {
        let (info, changes, _) = read(&format!("META samplerate: 1000000000\n{HEAD}#0 1! 0\"\n"));
        assert_eq!(info.channels, ["a", "b"]);
        assert_eq!(changes, [ch(0, 1, 0)]);
        let e = fails(&format!("\nMETA samplerate: 1000000000\n{HEAD}"));
        assert!(e.contains("line 2: not a VCD: `META`"), "{e}");
    }

    #[test]
    fn more_than_64_channels_is_an_error_that_says_how_many() {
        let mut text = String::from("$var wire 60 ! d $end\n");
        for i in 0..6 {
            text.push_str(&format!("$var wire 1 {} w{i} $end\n", (b'#' + i) as char));
        }
        text.push_str("$var wire 64 z big $end\n$enddefinitions $end\n#0\n");
        let e = fails(&text);
        assert!(
            e.contains("130 one-bit channels") && e.contains("at most 64"),
            "{e}"
        );
        assert!(e.starts_with("t.vcd: line 9:"), "{e}");
        // 64 exactly is fine.
        let (info, _, _) = read("$var wire 64 ! d $end $enddefinitions $end #0 b1 !");
        assert_eq!(info.channels.len(), 64);
    }

    #[test]
    fn a_file_cut_in_the_middle_of_a_line_says_so() {
        // Whole: ends with its line.
        let text = format!("{HEAD}#0 0! 0\"\n#10 1!\n#20 1\"\n");
        let mut r = VcdReader::new(text.as_bytes(), Path::new("t.vcd")).expect("header");
        drain(&mut r).expect("reads");
        assert_eq!(r.cut_short(), None);
        // Cut inside the last value: `1` of `1"`, which cannot be read.
        let cut = &text[..text.len() - 2];
        let mut r = VcdReader::new(cut.as_bytes(), Path::new("t.vcd")).expect("header");
        let (_, changes, end) = drain(&mut r).expect("reads what is whole");
        assert_eq!(changes, [ch(0, 0, 0), ch(10_000, 0b01, 0)]);
        assert_eq!(end, 20_000);
        let why = r.cut_short().expect("cut short");
        assert!(why.contains("ends in the middle of line 8"), "{why}");
        // Cut inside a timestamp: read, and still said to be cut.
        let cut = format!("{HEAD}#0 0! 0\"\n#10 1!\n#2");
        let mut r = VcdReader::new(cut.as_bytes(), Path::new("t.vcd")).expect("header");
        drain(&mut r).expect("reads");
        assert!(r.cut_short().is_some());
    }

    #[test]
    fn scopes_nested_past_the_limit_are_refused_in_bounded_memory() {
        let deep = "$scope module m $end\n".repeat(MAX_SCOPE_DEPTH + 1);
        let text = format!("$timescale 1 ns $end\n{deep}$var wire 1 ! a $end\n");
        let e = VcdReader::new(text.as_bytes(), Path::new("t.vcd")).expect_err("too deep");
        assert!(
            e.to_string().contains(&format!(
                "line {}: $scope nested deeper than {MAX_SCOPE_DEPTH}",
                MAX_SCOPE_DEPTH + 2
            )),
            "{e}"
        );
        let ok = "$scope module m $end\n".repeat(MAX_SCOPE_DEPTH);
        let text = format!(
            "$timescale 1 ns $end\n{ok}$var wire 1 ! a $end\n$enddefinitions $end\n#0 1!\n"
        );
        assert!(VcdReader::new(text.as_bytes(), Path::new("t.vcd")).is_ok());
        let reals = "$var real 64 r x $end\n".repeat(MAX_IGNORED + 1);
        let text = format!("$var wire 1 ! a $end\n{reals}");
        let e = VcdReader::new(text.as_bytes(), Path::new("t.vcd")).expect_err("too many");
        assert!(
            e.to_string().contains("real, string or event variables"),
            "{e}"
        );
    }

    #[test]
    fn bad_files_are_errors_naming_the_line() {
        let cases: [(&str, &str); 16] = [
            ("", "t.vcd: empty file"),
            ("\n\n", "t.vcd: empty file"),
            ("hello world", "line 1: not a VCD"),
            ("#0 1!", "line 1: `#0` before $enddefinitions"),
            (
                "$timescale 1 ns $end\n$var wire 1 ! a",
                "line 2: the file ends inside $var (opened on line 2)",
            ),
            (
                "$var wire 1 ! a $end\n$comment never closed",
                "the file ends inside $comment",
            ),
            (
                "$var wire 1 ! a $end",
                "line 1: the file ends before $enddefinitions",
            ),
            (
                "$timescale 3 hours $end",
                "line 1: bad $timescale `3 hours`",
            ),
            ("$var wire wide ! a $end", "line 1: $var size `wide`"),
            ("$var wire 1 ! $end", "line 1: a $var needs"),
            (
                "$var real 64 ! r $end $enddefinitions $end",
                "declares no logic signal",
            ),
            (
                &format!("{HEAD}#10 1!\n#5 0!\n"),
                "line 7: time goes backwards: #5 after #10",
            ),
            (&format!("{HEAD}#0 1?\n"), "line 6: a value for `?`"),
            (
                &format!("{HEAD}#0 b102 !"),
                "line 6: bad value `102` for `!`",
            ),
            (
                &format!("{HEAD}#0\n\n1! $end"),
                "line 8: `$end` with no section open",
            ),
            (
                &format!("{HEAD}#0 $dumpvars 1!"),
                "the file ends inside $dumpvars",
            ),
        ];
        for (text, want) in cases {
            let e = fails(text);
            assert!(e.contains(want), "{text:?}: {e}");
        }
        for (text, want) in [
            (
                format!("{HEAD}#0 b1\n"),
                "line 6: a value `b1` without a code",
            ),
            (format!("{HEAD}#0 garbage"), "line 6: unexpected `garbage`"),
            (format!("{HEAD}#1.5"), "line 6: bad timestamp `#1.5`"),
            (format!("{HEAD}#-1"), "line 6: bad timestamp"),
            (
                format!("{HEAD}#99999999999999999999"),
                "line 6: bad timestamp",
            ),
            (format!("{HEAD}#18446744073709552"), "past 2^64 picoseconds"),
            (
                format!("{HEAD}$dumpvars $dumpall"),
                "$dumpall inside $dumpvars",
            ),
            (
                format!("{HEAD}$scope module x $end"),
                "unexpected command `$scope`",
            ),
            (
                format!("{HEAD}#0 1{}", "!".repeat(MAX_TOKEN + 1)),
                "longer than 4096 bytes",
            ),
        ] {
            let e = fails(&text);
            assert!(e.contains(want), "{text:.80}: {e}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Random bytes: a result or an error, never a panic.
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = read_with(&bytes, 7);
        }

        /// A good file with bytes changed: a result or an error, and the
        /// changes a result gives are in time order and change something.
        #[test]
        fn damaged_files_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6)) {
            let mut bytes = format!("{HEAD}#0 $dumpvars 1! 0\" $end #10 b1 \" #20 x! #30 0! 1\" #40").into_bytes();
            for (at, b) in edits {
                let n = bytes.len();
                bytes[at % n] = b" !\"#$01xzb\n"[usize::from(b) % 11];
            }
            if let Ok((_, changes, end)) = read_with(&bytes, 5) {
                for w in changes.windows(2) {
                    prop_assert!(w[0].time_ps < w[1].time_ps);
                    prop_assert!((w[0].levels, w[0].unknown) != (w[1].levels, w[1].unknown));
                }
                if let Some(last) = changes.last() {
                    prop_assert!(last.time_ps <= end);
                }
            }
        }
    }
}
