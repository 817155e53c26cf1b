//! Which capture channel carries which of the chip's signals: a
//! [`ChannelMap`], given (`--map CS=0,RD=1,...` or a file of such lines)
//! or found from the capture's own channel names when they are the chip's
//! (`CS*`, `nRD`, `D3`, `POUT`, ...). A signal with no channel narrows
//! what can be judged; [`ChannelMap::missing`] says which, and
//! [`ChannelMap::bus`] whether the bus can be decoded at all.
//!
//! A map names each signal once and each channel once: a signal given
//! twice, or one channel given for two signals, is refused (which one is
//! it?). A channel may be inverted (`POUT=~12`): a board whose output
//! stage inverts a pin, or an analyzer probe on the complement. An
//! analyzer's own channel names (sigrok's `D0`..`D15`, a Saleae's `0`..)
//! are never taken for the chip's data lines: when the capture has a
//! channel named `D8` or above, its `D<n>` names are the analyzer's.

use super::source::{Change, LogicError, LogicInfo, LogicSource};
use ppmc_core::protocol::Input;
use std::fmt;

/// A signal of the chip a capture may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Signal {
    /// CS*, RD*, WR*: the bus strobes, active low (Table 3-1).
    Cs,
    Rd,
    Wr,
    /// A0: high selects the command register (write) or status (read).
    A0,
    /// D0..D7.
    D(u8),
    /// The pulse output.
    Pout,
    /// The direction output.
    Dir,
    /// The interrupt output INT*, active low.
    Int,
    /// BUSY, where the board brings it out.
    Busy,
    /// HOLD, high while on.
    Hold,
    /// AUX*, active low.
    Aux,
    /// AUXO0..AUXO3, active low.
    Auxo(u8),
    /// The excitation outputs S1..S5 (`Phase(1)` is S1), at the levels
    /// the initialization's output logic gives them (Section 3-2-1).
    Phase(u8),
    /// An input the board drives into the chip: the limits L1*..L4*, ALM*,
    /// CNP* and AUXI0..3, all active low (the pin pulled low asserts it).
    /// The judge gives the model what the capture shows on them.
    Input(Input),
}

impl Signal {
    /// Every signal, bus first.
    pub const ALL: [Signal; 37] = [
        Signal::Cs,
        Signal::Rd,
        Signal::Wr,
        Signal::A0,
        Signal::D(0),
        Signal::D(1),
        Signal::D(2),
        Signal::D(3),
        Signal::D(4),
        Signal::D(5),
        Signal::D(6),
        Signal::D(7),
        Signal::Pout,
        Signal::Dir,
        Signal::Int,
        Signal::Busy,
        Signal::Hold,
        Signal::Aux,
        Signal::Auxo(0),
        Signal::Auxo(1),
        Signal::Auxo(2),
        Signal::Auxo(3),
        Signal::Phase(1),
        Signal::Phase(2),
        Signal::Phase(3),
        Signal::Phase(4),
        Signal::Phase(5),
        Signal::Input(Input::L1),
        Signal::Input(Input::L2),
        Signal::Input(Input::L3),
        Signal::Input(Input::L4),
        Signal::Input(Input::Alm),
        Signal::Input(Input::Cnp),
        Signal::Input(Input::Auxi0),
        Signal::Input(Input::Auxi1),
        Signal::Input(Input::Auxi2),
        Signal::Input(Input::Auxi3),
    ];

    /// Its name in a map and in reports: `CS`, `D3`, `POUT`.
    pub fn name(self) -> String {
        match self {
            Signal::Cs => "CS".into(),
            Signal::Rd => "RD".into(),
            Signal::Wr => "WR".into(),
            Signal::A0 => "A0".into(),
            Signal::D(i) => format!("D{i}"),
            Signal::Pout => "POUT".into(),
            Signal::Dir => "DIR".into(),
            Signal::Int => "INT".into(),
            Signal::Busy => "BUSY".into(),
            Signal::Hold => "HOLD".into(),
            Signal::Aux => "AUX".into(),
            Signal::Auxo(i) => format!("AUXO{i}"),
            Signal::Phase(k) => format!("S{k}"),
            Signal::Input(i) => i.name().to_ascii_uppercase(),
        }
    }

    /// The signal a name stands for: ours, with the usual marks of an
    /// active-low pin (`CS*`, `CS#`, `/CS`, `nCS`, `CS_N`, `~CS`) and a data
    /// line as `D3`, `DB3` or `D[3]`, in any case.
    pub fn parse(name: &str) -> Option<Signal> {
        let mut n = name.trim().to_ascii_uppercase();
        for mark in ["*", "#", "_N", "_B"] {
            if let Some(s) = n.strip_suffix(mark) {
                n = s.to_string();
            }
        }
        for mark in ["/", "~", "!"] {
            if let Some(s) = n.strip_prefix(mark) {
                n = s.to_string();
            }
        }
        let low = |s: &str| n == s || n == format!("N{s}");
        if low("CS") {
            return Some(Signal::Cs);
        }
        if low("RD") {
            return Some(Signal::Rd);
        }
        if low("WR") {
            return Some(Signal::Wr);
        }
        if low("INT") {
            return Some(Signal::Int);
        }
        if low("AUX") {
            return Some(Signal::Aux);
        }
        for i in 0..4 {
            if low(&format!("AUXO{i}")) {
                return Some(Signal::Auxo(i));
            }
        }
        if let Some(i) = Input::ALL
            .into_iter()
            .find(|i| low(&i.name().to_ascii_uppercase()))
        {
            return Some(Signal::Input(i));
        }
        match n.as_str() {
            "A0" | "A" => return Some(Signal::A0),
            "POUT" => return Some(Signal::Pout),
            "DIR" => return Some(Signal::Dir),
            "BUSY" => return Some(Signal::Busy),
            "HOLD" => return Some(Signal::Hold),
            "S1" => return Some(Signal::Phase(1)),
            "S2" => return Some(Signal::Phase(2)),
            "S3" => return Some(Signal::Phase(3)),
            "S4" => return Some(Signal::Phase(4)),
            "S5" => return Some(Signal::Phase(5)),
            _ => {}
        }
        let digits = n
            .strip_prefix("DB")
            .or_else(|| n.strip_prefix("D"))?
            .trim_start_matches('[')
            .trim_end_matches(']');
        match digits.parse::<u8>() {
            Ok(i) if i < 8 => Some(Signal::D(i)),
            _ => None,
        }
    }
}

impl fmt::Display for Signal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The channels of the bus, all present.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusChannels {
    pub cs: usize,
    pub rd: usize,
    pub wr: usize,
    pub a0: usize,
    pub d: [usize; 8],
}

/// For each signal, the capture channel that carries it, if any.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChannelMap {
    pairs: Vec<(Signal, usize)>,
    /// Bit `c`: channel `c` is read inverted (`SIGNAL=~CHANNEL`).
    inverted: u64,
}

impl ChannelMap {
    /// The channels read inverted, one bit each (bit `c`: channel `c`).
    pub fn inverted(&self) -> u64 {
        self.inverted
    }

    /// Whether `signal`'s channel is read inverted.
    pub fn is_inverted(&self, signal: Signal) -> bool {
        self.get(signal)
            .is_some_and(|c| c < super::source::MAX_CHANNELS && self.inverted >> c & 1 == 1)
    }

    /// This map with `signal`'s channel read inverted (or no longer), for
    /// a judge that tries the map a capture seems to need.
    pub fn with_inverted(&self, signal: Signal, on: bool) -> ChannelMap {
        let mut m = self.clone();
        if let Some(c) = self
            .get(signal)
            .filter(|&c| c < super::source::MAX_CHANNELS)
        {
            match on {
                true => m.inverted |= 1 << c,
                false => m.inverted &= !(1 << c),
            }
        }
        m
    }

    /// This map with the channels of `a` and `b` exchanged.
    pub fn swapped(&self, a: Signal, b: Signal) -> ChannelMap {
        let mut m = self.clone();
        let (ca, cb) = (self.get(a), self.get(b));
        m.pairs.retain(|(s, _)| *s != a && *s != b);
        if let Some(c) = cb {
            m.pairs.push((a, c));
        }
        if let Some(c) = ca {
            m.pairs.push((b, c));
        }
        m
    }

    /// The map in `--map` form: `CS=cs,RD=rd,...,POUT=~pout`, each
    /// channel by its name in the capture.
    pub fn spelled(&self, info: &LogicInfo) -> String {
        self.spelled_against(&ChannelMap::default(), info)
    }

    /// What `--map` must say for this map over `base` (the map the
    /// channel names give): the pairs that differ from it.
    pub fn spelled_against(&self, base: &ChannelMap, info: &LogicInfo) -> String {
        let mut pairs: Vec<(Signal, usize)> = self
            .pairs
            .iter()
            .copied()
            .filter(|&(s, c)| base.get(s) != Some(c) || base.is_inverted(s) != self.is_inverted(s))
            .collect();
        pairs.sort();
        pairs
            .iter()
            .map(|&(s, c)| {
                let name = info
                    .channels
                    .get(c)
                    .cloned()
                    .unwrap_or_else(|| c.to_string());
                let inv = if self.is_inverted(s) { "~" } else { "" };
                format!("{s}={inv}{name}")
            })
            .collect::<Vec<_>>()
            .join(",")
    }

    /// The channel of `signal`.
    pub fn get(&self, signal: Signal) -> Option<usize> {
        self.pairs
            .iter()
            .find(|(s, _)| *s == signal)
            .map(|(_, c)| *c)
    }

    /// The bus's channels, if every one of them is mapped.
    pub fn bus(&self) -> Option<BusChannels> {
        let mut d = [0; 8];
        for (i, slot) in d.iter_mut().enumerate() {
            *slot = self.get(Signal::D(i as u8))?;
        }
        Some(BusChannels {
            cs: self.get(Signal::Cs)?,
            rd: self.get(Signal::Rd)?,
            wr: self.get(Signal::Wr)?,
            a0: self.get(Signal::A0)?,
            d,
        })
    }

    /// The bus's channels, or why the bus cannot be decoded: the bus
    /// signals no channel carries, named (and, where the capture's
    /// channels carry an analyzer's own names, that they do).
    pub fn require_bus(&self, info: &LogicInfo) -> Result<BusChannels, String> {
        self.bus().ok_or_else(|| {
            let missing: Vec<String> = self
                .missing()
                .into_iter()
                .filter(|s| {
                    matches!(
                        s,
                        Signal::Cs | Signal::Rd | Signal::Wr | Signal::A0 | Signal::D(_)
                    )
                })
                .map(Signal::name)
                .collect();
            let why = format!(
                "the bus cannot be decoded: no channel for {} (give --map SIGNAL=CHANNEL)",
                missing.join(", ")
            );
            match analyzer_names(info) && missing.iter().any(|m| m.starts_with('D')) {
                true => format!(
                    "{why}; the capture's channels are named as the analyzer names them ({}..{}), not as the chip's signals: its `D0`..`D7` are not taken for the data lines without a map (e.g. --map D0-7=D4-D11)",
                    info.channels.first().map_or("", String::as_str),
                    info.channels.last().map_or("", String::as_str)
                ),
                false => why,
            }
        })
    }

    /// The signals no channel carries.
    pub fn missing(&self) -> Vec<Signal> {
        Signal::ALL
            .into_iter()
            .filter(|s| self.get(*s).is_none())
            .collect()
    }

    /// The map the capture's channel names give: every channel whose name
    /// is one of the chip's signals. Two channels naming one signal are an
    /// error (which one is it?). Where the names are an analyzer's own
    /// (a channel named `D8` or above: sigrok's `D0`..`D15`), no `D<n>`
    /// is taken for a data line.
    pub fn from_names(info: &LogicInfo) -> Result<ChannelMap, String> {
        let mut map = ChannelMap::default();
        let analyzer = analyzer_names(info);
        for (c, name) in info.channels.iter().enumerate() {
            if let Some(s) = Signal::parse(name) {
                if analyzer && matches!(s, Signal::D(_)) {
                    continue;
                }
                map.insert(s, c, info)?;
            }
        }
        Ok(map)
    }

    /// Reads `SIGNAL=CHANNEL` pairs, separated by commas or lines (`#`
    /// starts a comment), where CHANNEL is a channel's name in the capture
    /// or its number from 0, over the map the names give. `D0-7=8-15`
    /// maps a range at once.
    pub fn parse(text: &str, info: &LogicInfo) -> Result<ChannelMap, String> {
        let mut map = ChannelMap::from_names(info).unwrap_or_default();
        // What the text itself gave, and where: a signal or a channel given
        // twice there is refused.
        let mut given: Vec<(Signal, usize, String)> = Vec::new();
        let one_line = text.trim_end().lines().count() <= 1;
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or_default();
            for pair in line.split(',').map(str::trim).filter(|p| !p.is_empty()) {
                let at = |what: String| match one_line {
                    true => format!("`{pair}`: {what}"),
                    false => format!("map line {}: `{pair}`: {what}", n + 1),
                };
                let (sig, chan) = pair
                    .split_once('=')
                    .ok_or_else(|| at("write SIGNAL=CHANNEL, e.g. CS=0 or RD=nRD".into()))?;
                let (sig, chan) = (sig.trim(), chan.trim());
                if let (Some(range), Some((c0, c1))) =
                    (sig.strip_prefix("D0-"), chan.split_once('-'))
                {
                    let last: u8 = range
                        .parse()
                        .map_err(|_| at("D0-N with N a digit".into()))?;
                    let (c0, c1) = (
                        channel(c0, info).map_err(&at)?.0,
                        channel(c1, info).map_err(&at)?.0,
                    );
                    if usize::from(last) + c0 != c1 || last > 7 {
                        return Err(at(format!(
                            "D0-{last} needs {} channels, {c0}-{c1} is not that",
                            last + 1
                        )));
                    }
                    for i in 0..=last {
                        let c = c0 + usize::from(i);
                        once(&given, Signal::D(i), c, info).map_err(&at)?;
                        given.push((Signal::D(i), c, pair.to_string()));
                        map.replace(Signal::D(i), c, false);
                    }
                    continue;
                }
                let s = Signal::parse(sig).ok_or_else(|| {
                    at(format!(
                        "no signal `{sig}`: use CS, RD, WR, A0, D0..D7, POUT, DIR, INT, BUSY, HOLD, AUX, AUXO0..AUXO3, L1..L4, ALM, CNP or AUXI0..AUXI3"
                    ))
                })?;
                let (c, inverted) = channel(chan, info).map_err(&at)?;
                once(&given, s, c, info).map_err(&at)?;
                given.push((s, c, pair.to_string()));
                map.replace(s, c, inverted);
            }
        }
        Ok(map)
    }

    fn insert(&mut self, s: Signal, c: usize, info: &LogicInfo) -> Result<(), String> {
        if let Some(other) = self.get(s) {
            return Err(format!(
                "channels `{}` and `{}` both name {s}: say which with --map {s}=CHANNEL",
                info.channels[other], info.channels[c]
            ));
        }
        self.pairs.push((s, c));
        Ok(())
    }

    /// `s` on channel `c`: what the names gave for `s`, or for `c`, gives
    /// way (a map overrides the names).
    fn replace(&mut self, s: Signal, c: usize, inverted: bool) {
        self.pairs.retain(|&(t, d)| t != s && d != c);
        self.pairs.push((s, c));
        if c < super::source::MAX_CHANNELS {
            match inverted {
                true => self.inverted |= 1 << c,
                false => self.inverted &= !(1 << c),
            }
        }
    }
}

/// A capture read through a map's inverted channels
/// ([`ChannelMap::inverted`]): their known levels flipped, so that every
/// reader of the changes sees the chip's levels (with none inverted, the
/// changes as they are).
pub struct Inverted<'a> {
    src: &'a mut dyn LogicSource,
    mask: u64,
}

impl std::fmt::Debug for Inverted<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Inverted")
            .field("info", self.src.info())
            .field("mask", &format_args!("{:#x}", self.mask))
            .finish()
    }
}

impl<'a> Inverted<'a> {
    pub fn new(src: &'a mut dyn LogicSource, map: &ChannelMap) -> Self {
        Inverted {
            src,
            mask: map.inverted(),
        }
    }
}

impl LogicSource for Inverted<'_> {
    fn info(&self) -> &LogicInfo {
        self.src.info()
    }

    fn next_change(&mut self) -> Result<Option<Change>, LogicError> {
        Ok(self.src.next_change()?.map(|c| Change {
            levels: c.levels ^ (self.mask & !c.unknown),
            ..c
        }))
    }

    fn end_ps(&self) -> u64 {
        self.src.end_ps()
    }

    fn cut_short(&self) -> Option<String> {
        self.src.cut_short()
    }
}

/// Whether the capture's channel names are an analyzer's own rather than
/// the chip's: a channel named `D8` or above (sigrok's `D0`..`D15`).
pub fn analyzer_names(info: &LogicInfo) -> bool {
    info.channels.iter().any(|n| {
        n.strip_prefix('D')
            .and_then(|d| d.parse::<u32>().ok())
            .is_some_and(|i| i >= 8)
    })
}

/// Refuses `s` on `c` when the map's text already gave `s` a channel, or
/// `c` a signal.
fn once(
    given: &[(Signal, usize, String)],
    s: Signal,
    c: usize,
    info: &LogicInfo,
) -> Result<(), String> {
    if let Some((_, _, pair)) = given.iter().find(|g| g.0 == s) {
        return Err(format!(
            "{s} is given twice (`{pair}` before): one channel a signal"
        ));
    }
    if let Some((t, _, pair)) = given.iter().find(|g| g.1 == c) {
        let name = info
            .channels
            .get(c)
            .map_or_else(|| c.to_string(), |n| format!("`{n}`"));
        return Err(format!(
            "channel {name} is given for {t} already (`{pair}`): one signal a channel"
        ));
    }
    Ok(())
}

/// A channel given by name or number, `~` before it to read it inverted.
fn channel(text: &str, info: &LogicInfo) -> Result<(usize, bool), String> {
    if let Some(c) = info.channel(text) {
        return Ok((c, false));
    }
    if let Some(rest) = text.strip_prefix('~') {
        return channel(rest.trim(), info).map(|(c, inv)| (c, !inv));
    }
    match text.parse::<usize>() {
        Ok(c) if c < info.channels.len() => Ok((c, false)),
        Ok(c) => Err(format!(
            "channel {c}: the capture has {} (0 to {})",
            info.channels.len(),
            info.channels.len().saturating_sub(1)
        )),
        Err(_) => Err(format!(
            "no channel `{text}` in the capture (it has {})",
            info.channels.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::super::source::testing::ch;
    use super::super::source::Recorded;
    use super::*;

    fn info(names: &[&str]) -> LogicInfo {
        LogicInfo {
            channels: names.iter().map(|n| n.to_string()).collect(),
            resolution_ps: 1000,
            sample_rate_hz: None,
            format: "test".into(),
        }
    }

    #[test]
    fn the_usual_spellings_of_a_pin_name_are_read() {
        for (name, s) in [
            ("CS*", Signal::Cs),
            ("nCS", Signal::Cs),
            ("/rd", Signal::Rd),
            ("WR#", Signal::Wr),
            ("wr_n", Signal::Wr),
            ("A0", Signal::A0),
            ("D[7]", Signal::D(7)),
            ("L3*", Signal::Input(Input::L3)),
            ("AUX*", Signal::Aux),
            ("auxo3_n", Signal::Auxo(3)),
            ("HOLD", Signal::Hold),
            ("nALM", Signal::Input(Input::Alm)),
            ("auxi2", Signal::Input(Input::Auxi2)),
            ("DB3", Signal::D(3)),
            ("pout", Signal::Pout),
            ("INT*", Signal::Int),
            ("s3", Signal::Phase(3)),
        ] {
            assert_eq!(Signal::parse(name), Some(s), "{name}");
        }
        for name in ["D8", "CLK", "", "DX", "S6", "S0"] {
            assert_eq!(Signal::parse(name), None, "{name}");
        }
    }

    #[test]
    fn names_give_the_map_and_a_map_overrides_them() {
        let i = info(&[
            "CS*", "RD*", "WR*", "A0", "D0", "D1", "D2", "D3", "D4", "D5", "D6", "D7", "x",
        ]);
        let m = ChannelMap::from_names(&i).expect("names");
        let bus = m.bus().expect("the whole bus");
        assert_eq!((bus.cs, bus.rd, bus.d[7]), (0, 1, 11));
        assert_eq!(m.missing(), Signal::ALL[12..]);
        let m = ChannelMap::parse("POUT=x, CS=3 # swapped\nA0=0", &i).expect("map");
        assert_eq!(
            (m.get(Signal::Pout), m.get(Signal::Cs), m.get(Signal::A0)),
            (Some(12), Some(3), Some(0))
        );
        let r = ChannelMap::parse("D0-7=4-11", &info(&["a"; 12])).expect("range");
        assert_eq!(r.get(Signal::D(5)), Some(9));
    }

    #[test]
    fn a_bad_map_says_where_and_what() {
        let i = info(&["a", "b"]);
        for (text, says) in [
            ("CS", "`CS`: write SIGNAL=CHANNEL"),
            ("XX=0", "no signal `XX`"),
            ("CS=5", "channel 5: the capture has 2"),
            ("CS=zz", "no channel `zz` in the capture (it has a, b)"),
            ("\nD0-7=0-3", "map line 2"),
        ] {
            let e = ChannelMap::parse(text, &i).expect_err(text);
            assert!(e.contains(says), "{text}: {e}");
        }
        let twice = ChannelMap::from_names(&info(&["CS", "nCS"])).expect_err("two CS");
        assert!(twice.contains("both name CS"), "{twice}");
    }

    #[test]
    fn a_signal_or_a_channel_given_twice_is_refused() {
        let i = info(&["cs", "rd", "wr"]);
        for (text, says) in [
            ("CS=cs,CS=rd", "`CS=rd`: CS is given twice (`CS=cs` before)"),
            (
                "CS=cs,RD=cs",
                "`RD=cs`: channel `cs` is given for CS already (`CS=cs`)",
            ),
            ("D0-7=0-7,D3=8", "is given twice"),
            (
                "CS=0\nWR=~cs",
                "map line 2: `WR=~cs`: channel `cs` is given for CS",
            ),
        ] {
            let text = text.replace("\\n", "\n");
            let i = if text.starts_with("D0") {
                info(&["a"; 9])
            } else {
                i.clone()
            };
            let e = ChannelMap::parse(&text, &i).expect_err(&text);
            assert!(e.contains(says), "{text}: {e}");
        }
        // Exchanging two named channels is a map, not a double.
        let m = ChannelMap::parse("CS=RD,RD=CS", &info(&["CS", "RD"])).expect("swap");
        assert_eq!((m.get(Signal::Cs), m.get(Signal::Rd)), (Some(1), Some(0)));
    }

    #[test]
    fn a_tilde_reads_a_channel_inverted() {
        let i = info(&["pout", "dir", "x"]);
        let m = ChannelMap::parse("POUT=~pout, DIR=~1", &i).expect("map");
        assert_eq!(m.inverted(), 0b11);
        assert!(m.is_inverted(Signal::Pout) && m.is_inverted(Signal::Dir));
        assert_eq!(
            m.spelled_against(&ChannelMap::from_names(&i).expect("names"), &i),
            "POUT=~pout,DIR=~dir"
        );
        let changes = vec![ch(0, 0b101, 0), ch(10, 0b100, 0)];
        let mut src = Recorded::new(i.clone(), changes, 20);
        let mut inv = Inverted::new(&mut src, &m);
        let a = inv.next_change().expect("reads").expect("a change");
        assert_eq!(a.levels, 0b110, "POUT and DIR flipped, x kept");
        assert!(ChannelMap::parse("POUT=~nope", &i).is_err());
    }

    #[test]
    fn an_analyzers_own_names_are_never_the_data_lines() {
        let names: Vec<String> = (0..16).map(|i| format!("D{i}")).collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let i = info(&names);
        let m = ChannelMap::from_names(&i).expect("names");
        assert_eq!(m.get(Signal::D(0)), None);
        let e = m.require_bus(&i).expect_err("no bus");
        assert!(
            e.contains("named as the analyzer names them (D0..D15)"),
            "{e}"
        );
        // With eight data lines named D0..D7, they are the chip's.
        let chip = info(&[
            "cs", "rd", "wr", "a0", "D0", "D1", "D2", "D3", "D4", "D5", "D6", "D7",
        ]);
        assert_eq!(
            ChannelMap::from_names(&chip)
                .expect("names")
                .get(Signal::D(7)),
            Some(11)
        );
        let m = ChannelMap::parse("CS=D0,RD=D1,WR=D2,A0=D3,D0-7=D4-D11", &i).expect("map");
        assert!(m.require_bus(&i).is_ok());
    }
}
