//! Which capture channel carries which of the chip's signals: a
//! [`ChannelMap`], given (`--map CS=0,RD=1,...` or a file of such lines)
//! or found from the capture's own channel names when they are the chip's
//! (`CS*`, `nRD`, `D3`, `POUT`, ...). A signal with no channel narrows
//! what can be judged; [`ChannelMap::missing`] says which, and
//! [`ChannelMap::bus`] whether the bus can be decoded at all.

use super::source::LogicInfo;
use crate::protocol::Input;
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
    /// An input the board drives into the chip: the limits L1*..L4*, ALM*,
    /// CNP* and AUXI0..3, all active low (the pin pulled low asserts it).
    /// The judge gives the model what the capture shows on them.
    Input(Input),
}

impl Signal {
    /// Every signal, bus first.
    pub const ALL: [Signal; 32] = [
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
}

impl ChannelMap {
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
    /// signals no channel carries, named.
    pub fn require_bus(&self) -> Result<BusChannels, String> {
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
            format!(
                "the bus cannot be decoded: no channel for {} (give --map SIGNAL=CHANNEL)",
                missing.join(", ")
            )
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
    /// error (which one is it?).
    pub fn from_names(info: &LogicInfo) -> Result<ChannelMap, String> {
        let mut map = ChannelMap::default();
        for (c, name) in info.channels.iter().enumerate() {
            if let Some(s) = Signal::parse(name) {
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
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or_default();
            for pair in line.split(',').map(str::trim).filter(|p| !p.is_empty()) {
                let at = |what: String| format!("map line {}: `{pair}`: {what}", n + 1);
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
                        channel(c0, info).map_err(&at)?,
                        channel(c1, info).map_err(&at)?,
                    );
                    if usize::from(last) + c0 != c1 || last > 7 {
                        return Err(at(format!(
                            "D0-{last} needs {} channels, {c0}-{c1} is not that",
                            last + 1
                        )));
                    }
                    for i in 0..=last {
                        map.replace(Signal::D(i), c0 + usize::from(i));
                    }
                    continue;
                }
                let s = Signal::parse(sig).ok_or_else(|| {
                    at(format!(
                        "no signal `{sig}`: use CS, RD, WR, A0, D0..D7, POUT, DIR, INT, BUSY, HOLD, AUX, AUXO0..AUXO3, L1..L4, ALM, CNP or AUXI0..AUXI3"
                    ))
                })?;
                map.replace(s, channel(chan, info).map_err(&at)?);
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

    fn replace(&mut self, s: Signal, c: usize) {
        self.pairs.retain(|(t, _)| *t != s);
        self.pairs.push((s, c));
    }
}

/// A channel given by name or number.
fn channel(text: &str, info: &LogicInfo) -> Result<usize, String> {
    if let Some(c) = info.channel(text) {
        return Ok(c);
    }
    match text.parse::<usize>() {
        Ok(c) if c < info.channels.len() => Ok(c),
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
        ] {
            assert_eq!(Signal::parse(name), Some(s), "{name}");
        }
        for name in ["D8", "CLK", "", "DX"] {
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
            ("CS", "map line 1: `CS`: write SIGNAL=CHANNEL"),
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
}
