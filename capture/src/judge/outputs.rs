//! The chip's outputs besides POUT and DIR, compared change by change:
//! INT*, BUSY, HOLD, AUX* and AUXO0..AUXO3 as the capture shows them,
//! against the model's record of its pins, each change within the
//! capture's resolution and the latency tolerance of the time since what
//! caused it (the last register access or the last pulse before it:
//! Table 3-3 times INT*, BUSY and HOLD from them). S1..S5 have their
//! own rules ([`super::phases`]).

use super::frame::Frame;
use super::phases::{self, PhaseLevels, PhaseWatch, Rules};
use super::{Divergence, Marginal};
use ppmc::emu::Board;
use ppmc::protocol::Pin;
use ppmc::time::{Duration, Instant};
use ppmc_logic::map::{ChannelMap, Signal};
use ppmc_logic::source::Change;
use std::collections::VecDeque;

/// The outputs compared, as a judge holds them.
#[derive(Clone)]
pub(super) struct Outputs {
    watches: Vec<Watch>,
    /// Recent register accesses, in capture time (the newest last).
    accesses: VecDeque<u64>,
    compared: u64,
    /// The changes matched within the capture's uncertainty of their limit.
    marginal: Marginal,
    /// S1..S5, where the capture has channels for them, and their levels
    /// as the model drove them.
    phases: Vec<PhaseWatch>,
    levels: Option<PhaseLevels>,
}

/// One output pin and its two sides.
#[derive(Clone)]
struct Watch {
    signal: Signal,
    channel: usize,
    pin: Pin,
    /// Low while asserted (INT*, AUX*, AUXO).
    active_low: bool,
    /// Which bit of the model's value (AUXO's four pins share one event).
    bit: u8,
    /// The board's changes not compared yet: capture time, asserted.
    board: VecDeque<(u64, bool)>,
    /// The board's level as last seen (asserted), once seen.
    seen: Option<bool>,
    /// The model's level as far as compared, and where its record of pin
    /// changes has been read to.
    model: bool,
    next_event: usize,
}

impl Watch {
    fn model_level(&self, value: u8) -> bool {
        value >> self.bit & 1 == 1
    }

    fn word(&self, asserted: bool) -> &'static str {
        match (self.active_low, asserted) {
            (true, true) => "asserted (low)",
            (true, false) => "released (high)",
            (false, true) => "high",
            (false, false) => "low",
        }
    }
}

impl Outputs {
    /// The outputs `map` has channels for, their model side as `board`
    /// stands now (the capture's start).
    pub(super) fn new(map: &ChannelMap, board: &Board) -> Outputs {
        let pins = board.pins();
        let mut watches = Vec::new();
        let mut watch = |signal: Signal, pin: Pin, active_low: bool, bit: u8, now: bool| {
            if let Some(channel) = map.get(signal) {
                watches.push(Watch {
                    signal,
                    channel,
                    pin,
                    active_low,
                    bit,
                    board: VecDeque::new(),
                    seen: None,
                    model: now,
                    next_event: board.record().pins.len(),
                });
            }
        };
        watch(Signal::Int, Pin::Int, true, 0, pins.int);
        watch(Signal::Busy, Pin::Busy, false, 0, pins.busy);
        watch(Signal::Hold, Pin::Hold, false, 0, pins.hold);
        watch(Signal::Aux, Pin::Aux, true, 0, pins.aux);
        for k in 0..4 {
            let now = pins.auxo >> k & 1 == 1;
            watch(Signal::Auxo(k), Pin::Auxo, true, k, now);
        }
        let phases: Vec<PhaseWatch> = (1..=5)
            .filter_map(|k| {
                map.get(Signal::Phase(k))
                    .map(|c| PhaseWatch::new(k, c, board))
            })
            .collect();
        let levels = (!phases.is_empty()).then(|| PhaseLevels::new(board));
        Outputs {
            watches,
            accesses: VecDeque::new(),
            compared: 0,
            marginal: Marginal::default(),
            phases,
            levels,
        }
    }

    /// The signals compared.
    pub(super) fn signals(&self) -> impl Iterator<Item = Signal> + '_ {
        let phases = self.phases.iter().map(PhaseWatch::signal);
        self.watches.iter().map(|w| w.signal).chain(phases)
    }

    /// Changes compared so far.
    pub(super) fn compared(&self) -> u64 {
        self.compared
    }

    /// The changes matched within the capture's uncertainty of their limit.
    pub(super) fn marginal(&self) -> Marginal {
        self.marginal.clone()
    }

    /// A register access ended at `ps`: what the changes after it are
    /// timed from.
    pub(super) fn access(&mut self, ps: u64) {
        if self.accesses.len() == 64 {
            self.accesses.pop_front();
        }
        self.accesses.push_back(ps);
    }

    /// The capture's change `c`: the board's side of every output. Its
    /// first level counts as a change when the model's differs.
    pub(super) fn observe(&mut self, c: &Change) {
        for w in &mut self.watches {
            let asserted = c.high(w.channel) != w.active_low;
            match w.seen {
                Some(level) if level == asserted => {}
                None if asserted == w.model => {}
                _ => w.board.push_back((c.time_ps, asserted)),
            }
            w.seen = Some(asserted);
        }
        for w in &mut self.phases {
            w.observe(c);
        }
    }

    /// Compares the changes, the board's and the model's, that lie before
    /// `horizon_ps` by more than their tolerance (the model has run up to
    /// `horizon_ps`). `zero_ps` is the capture's time of the model's zero;
    /// `slack_ps` how far the board's last pulse was from the model's (an
    /// output timed from it may be as far off).
    pub(super) fn compare(
        &mut self,
        f: &Frame<'_>,
        horizon_ps: u64,
        after: Option<String>,
    ) -> Result<(), Divergence> {
        let record = f.board.record();
        let resolution_ps = f.resolution_ps;
        for w in &mut self.watches {
            loop {
                // The model's next change of this pin.
                let mut model = None;
                while let Some(e) = record.pins.get(w.next_event) {
                    if e.pin == w.pin && w.model_level(e.value) != w.model {
                        model = Some((e.at, w.model_level(e.value)));
                        break;
                    }
                    w.next_event += 1;
                }
                // How far the change may be from the model's: the floor,
                // two samples, and the latency tolerance of the time since
                // its cause.
                let allowed =
                    |m_ps: u64, accesses: &VecDeque<u64>| f.allowed(m_ps, accesses, false);
                let diverge =
                    |w: &Watch, at_ps: u64, board: String, model: String, level: bool| Divergence {
                        at_ps,
                        what: format!("{} {}", w.signal.name(), w.word(level)),
                        board,
                        model,
                        after: after.clone(),
                    };
                let at = |ps: u64| Instant::from_nanos(ps / 1000);
                match (w.board.front().copied(), model) {
                    (None, None) => break,
                    (Some((b, level)), None) => {
                        let allowed = allowed(b, &self.accesses);
                        if b.saturating_add(allowed) >= horizon_ps {
                            break;
                        }
                        return Err(diverge(
                            w,
                            b,
                            format!("at {}", at(b)),
                            format!("no change within {}", Duration::from_nanos(allowed / 1000)),
                            level,
                        ));
                    }
                    (b, Some((m, level))) => {
                        let m_ps = f.capture_ps(m);
                        let allowed = allowed(m_ps, &self.accesses);
                        match b {
                            Some((b, bl)) if bl == level && b.abs_diff(m_ps) <= allowed => {
                                self.marginal.note(
                                    b.abs_diff(m_ps),
                                    allowed,
                                    2 * resolution_ps,
                                    || {
                                        format!(
                                            "{} {} at {}: {} from the model's, allowed {} (two samples of it the capture's uncertainty)",
                                            w.signal.name(),
                                            w.word(level),
                                            at(b),
                                            Duration::from_nanos(b.abs_diff(m_ps) / 1000),
                                            Duration::from_nanos(allowed / 1000)
                                        )
                                    },
                                );
                                w.board.pop_front();
                                w.model = level;
                                w.next_event += 1;
                                self.compared += 1;
                            }
                            Some((b, bl)) if b.min(m_ps).saturating_add(allowed) < horizon_ps => {
                                let (at_ps, shown) = if b < m_ps { (b, bl) } else { (m_ps, level) };
                                return Err(diverge(
                                    w,
                                    at_ps,
                                    format!("{} at {}", w.word(bl), at(b)),
                                    format!(
                                        "{} at {m} (allowed {})",
                                        w.word(level),
                                        Duration::from_nanos(allowed / 1000)
                                    ),
                                    shown,
                                ));
                            }
                            None if m_ps.saturating_add(allowed) < horizon_ps => {
                                return Err(diverge(
                                    w,
                                    m_ps,
                                    "no change".into(),
                                    format!("at {m}"),
                                    level,
                                ));
                            }
                            _ => break,
                        }
                    }
                }
            }
        }
        self.compare_phases(f, horizon_ps, after)
    }

    /// [`Outputs::compare`] for S1..S5.
    fn compare_phases(
        &mut self,
        f: &Frame<'_>,
        horizon_ps: u64,
        after: Option<String>,
    ) -> Result<(), Divergence> {
        let Some(levels) = &mut self.levels else {
            return Ok(());
        };
        levels.draw(f.board);
        let rules = Rules {
            frame: f,
            accesses: &self.accesses,
            horizon_ps,
            after,
        };
        for w in &mut self.phases {
            w.compare(levels, &rules, &mut self.marginal, &mut self.compared)?;
        }
        phases::taken(levels, &self.phases);
        Ok(())
    }
}
