//! What every capture reader produces: the capture's channels and
//! resolution ([`LogicInfo`]), then its level changes in time order
//! ([`Change`]) from a [`LogicSource`], one at a time, so that memory stays
//! bounded whatever the capture's length. A reader that fails says which
//! file, where in it, and what ([`LogicError`]); it never panics.

use std::fmt;
use std::path::{Path, PathBuf};

/// The most channels one capture may carry: the levels of a change are
/// one bit each in a `u64`.
pub const MAX_CHANNELS: usize = 64;

/// What a capture holds, known before its first change.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogicInfo {
    /// The channels' names as the capture gives them, in the order of the
    /// bits of [`Change::levels`] (bit `i` is `channels[i]`). A VCD vector
    /// `D[7:0]` is eight channels, `D[0]` to `D[7]`.
    pub channels: Vec<String>,
    /// The capture's resolution in picoseconds: the sample period of a
    /// sampled capture (sigrok, Saleae; rounded, at least 1), the
    /// timescale of a VCD. No edge is known closer than this.
    pub resolution_ps: u64,
    /// The sample rate of a sampled capture, exactly as the file gives it
    /// (24 MHz is no whole number of picoseconds); `None` for a VCD. A
    /// change of a sampled capture is at sample `n`, `time_ps` being
    /// `n * 10^12 / rate` rounded to the nearest picosecond.
    pub sample_rate_hz: Option<u64>,
    /// What the file is, in words, for reports: `sigrok session (.sr,
    /// version 2)`, `VCD (sigrok-cli)`, `Saleae Logic 2 binary (version 1)`.
    pub format: String,
}

impl LogicInfo {
    /// The sample rate, in hertz: the file's, or the one the resolution
    /// stands for (rounded).
    pub fn rate_hz(&self) -> u64 {
        match self.sample_rate_hz {
            Some(r) => r,
            None if self.resolution_ps == 0 => 0,
            None => (1_000_000_000_000 + self.resolution_ps / 2) / self.resolution_ps,
        }
    }

    /// The time of sample `n` of a capture at `rate` Hz, in picoseconds,
    /// rounded (saturating).
    pub fn sample_time_ps(n: u64, rate: u64) -> u64 {
        let t =
            (u128::from(n) * 1_000_000_000_000 + u128::from(rate / 2)) / u128::from(rate.max(1));
        u64::try_from(t).unwrap_or(u64::MAX)
    }

    /// The index of the channel named `name`, if the capture has one.
    pub fn channel(&self, name: &str) -> Option<usize> {
        self.channels.iter().position(|c| c == name)
    }
}

/// The levels of every channel from `time_ps` on, until the next change.
/// The first change a source gives is the levels at the capture's start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Change {
    /// Picoseconds from the capture's start.
    pub time_ps: u64,
    /// Bit `i`: channel `i` is high.
    pub levels: u64,
    /// Bit `i`: channel `i` is unknown (a VCD `x` or `z`); its bit in
    /// `levels` is then 0 and means nothing.
    pub unknown: u64,
}

impl Change {
    /// Whether channel `i` is high (and known).
    pub fn high(&self, i: usize) -> bool {
        i < MAX_CHANNELS && self.levels >> i & 1 == 1 && self.unknown >> i & 1 == 0
    }
}

/// A capture read as it goes.
pub trait LogicSource {
    /// Its channels, resolution and format.
    fn info(&self) -> &LogicInfo;

    /// The next change in time order; `Ok(None)` at the end. Two changes
    /// never share a time, and a change always changes a level (or an
    /// unknown bit).
    fn next_change(&mut self) -> Result<Option<Change>, LogicError>;

    /// Where the capture ends, in picoseconds, once `next_change` has
    /// given `None` (a sampled capture's last sample, a VCD's last
    /// timestamp): a level holds until then.
    fn end_ps(&self) -> u64;

    /// Once `next_change` has given `None`: where the file shows that the
    /// recording was cut short (a VCD ending in the middle of a line), in
    /// words; `None` when it ended as its writer ends it.
    fn cut_short(&self) -> Option<String> {
        None
    }
}

/// A capture held in memory, its changes given whole: one a program made
/// (a test's capture with a board's difference put in, a capture
/// resampled as an analyzer would see it), read as any other.
#[derive(Debug, Clone)]
pub struct Recorded {
    info: LogicInfo,
    changes: std::vec::IntoIter<Change>,
    end_ps: u64,
}

impl Recorded {
    /// `changes` in time order (the first the levels at the start), the
    /// capture ending at `end_ps`.
    pub fn new(info: LogicInfo, changes: Vec<Change>, end_ps: u64) -> Self {
        Recorded {
            info,
            changes: changes.into_iter(),
            end_ps,
        }
    }
}

impl LogicSource for Recorded {
    fn info(&self) -> &LogicInfo {
        &self.info
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        Ok(self.changes.next())
    }

    fn end_ps(&self) -> u64 {
        self.end_ps
    }
}

/// A capture that cannot be read: which file, where in it, and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogicError {
    pub file: PathBuf,
    /// Where in the file: `line 12`, `byte 4096 of logic-1-3`, `sample
    /// 1234`; empty when the file as a whole is wrong.
    pub at: String,
    pub what: String,
}

impl LogicError {
    pub fn new(file: &Path, at: impl Into<String>, what: impl Into<String>) -> LogicError {
        LogicError {
            file: file.to_path_buf(),
            at: at.into(),
            what: what.into(),
        }
    }

    /// A file that would not open (`ppmc_files::open_stream`'s error,
    /// which names the file itself: named once).
    pub fn opening(file: &Path, e: impl fmt::Display) -> LogicError {
        let text = e.to_string();
        let prefix = format!("{}: ", file.display());
        let what = text.strip_prefix(&prefix).unwrap_or(&text);
        LogicError::new(file, "", what)
    }
}

impl fmt::Display for LogicError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.at.is_empty() {
            true => write!(f, "{}: {}", self.file.display(), self.what),
            false => write!(f, "{}: {}: {}", self.file.display(), self.at, self.what),
        }
    }
}

impl std::error::Error for LogicError {}

/// What the readers' tests share.
#[cfg(test)]
pub(super) mod testing {
    use super::*;

    /// What a source reads as: its info, every change, its end.
    pub(crate) type Read = (LogicInfo, Vec<Change>, u64);

    /// Every change of `r`, or its first error; once done, it stays done.
    pub(crate) fn drain(r: &mut dyn LogicSource) -> Result<Read, LogicError> {
        let mut out = Vec::new();
        while let Some(c) = r.next_change()? {
            out.push(c);
        }
        assert_eq!(r.next_change(), Ok(None), "the end stays the end");
        Ok((r.info().clone(), out, r.end_ps()))
    }

    pub(crate) fn ch(time_ps: u64, levels: u64, unknown: u64) -> Change {
        Change {
            time_ps,
            levels,
            unknown,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_says_which_channels_are_high_and_known() {
        let c = Change {
            time_ps: 0,
            levels: 0b0101,
            unknown: 0b0100,
        };
        assert!(c.high(0));
        assert!(!c.high(1));
        assert!(!c.high(2), "unknown is not high");
        assert!(!c.high(64));
        let info = LogicInfo {
            channels: vec!["CS".into(), "RD".into()],
            resolution_ps: 41_667,
            sample_rate_hz: Some(24_000_000),
            format: "test".into(),
        };
        assert_eq!(info.rate_hz(), 24_000_000);
        assert_eq!(LogicInfo::sample_time_ps(3, 24_000_000), 125_000);
        let vcd = LogicInfo {
            sample_rate_hz: None,
            resolution_ps: 1_000,
            ..info.clone()
        };
        assert_eq!(vcd.rate_hz(), 1_000_000_000);
        assert_eq!(info.channel("RD"), Some(1));
        let e = LogicError::new(Path::new("a.sr"), "byte 7 of logic-1-1", "truncated");
        assert_eq!(e.to_string(), "a.sr: byte 7 of logic-1-1: truncated");
    }
}
