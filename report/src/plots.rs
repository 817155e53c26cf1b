//! The report's plots, each one SVG: a measurement against its Table 3-3
//! band, a move's speed profile over the golden one, and the pins around
//! a failure.

use ppmc_core::time::Duration;
use ppmc_record::{Measurement, MoveFigure, PinWave, Waveform, MAX_WAVE_PULSES};

/// Pins, and changes of each, a waveform draws at most.
const MAX_WAVE_PINS: usize = 16;
const MAX_WAVE_CHANGES: usize = 2_000;
use super::svg::{esc, reduce, Plot, Segment};
use std::fmt::Write as _;

/// Room a band's limit label takes beside its limit, px.
const LABEL_W: f64 = 80.0;

/// The profiles' pixel size.
const PROFILE: (f64, f64) = (470.0, 210.0);

/// A measurement's band as a strip: red outside the limits, amber in the
/// marginal zones, green between, the value a dark tick, its uncertainty
/// (± U, where not 0) a bar across it; `data-*` give the numbers.
pub fn measurement(m: &Measurement) -> String {
    let finite = |d: Duration| (d != Duration::MAX).then_some(d.as_nanos());
    let (value_ns, u_ns, lo_ns) = (m.value.as_nanos(), m.u.as_nanos(), m.lo.as_nanos());
    let (hi_ns, marginal_lo_ns, marginal_hi_ns) = (
        finite(m.hi),
        m.marginal_lo.as_nanos(),
        finite(m.marginal_hi),
    );
    let (w, h) = (380.0, 34.0);
    let (l, r) = (8.0, 8.0);
    let hi = hi_ns.unwrap_or(u64::MAX);
    let finite_top = hi_ns.unwrap_or(lo_ns.max(marginal_lo_ns));
    // The view: a band with both ends spans the middle half of the strip,
    // whatever its width (a +/-1 % band drawn from 0 would be a sliver
    // with its labels on top of each other), widened to hold the value and
    // its uncertainty; a band with no upper end is drawn from 0.
    let (view_lo, view_hi) = match hi_ns {
        Some(top) => {
            let width = top.saturating_sub(lo_ns).max(1) as f64;
            let a = (lo_ns as f64 - width / 2.0)
                .min(value_ns.saturating_sub(u_ns) as f64 - width / 8.0)
                .max(0.0);
            let b =
                (top as f64 + width / 2.0).max(value_ns.saturating_add(u_ns) as f64 + width / 8.0);
            (a, b)
        }
        None => (0.0, (finite_top.max(value_ns) as f64 * 1.25).max(1.0)),
    };
    let x = |ns: u64| {
        let f = ((ns as f64).clamp(view_lo, view_hi) - view_lo) / (view_hi - view_lo);
        l + f * (w - l - r)
    };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg class="measure" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" data-value-ns="{}" data-u-ns="{}" data-lo-ns="{}" data-hi-ns="{}" data-grade="{}">"#,
        value_ns,
        u_ns,
        lo_ns,
        hi_ns.map_or("inf".to_string(), |v| v.to_string()),
        m.grade.name()
    );
    let mhi = marginal_hi_ns.unwrap_or(u64::MAX);
    let zones = [
        ("out", 0, lo_ns),
        ("marginal", lo_ns, marginal_lo_ns),
        ("in", marginal_lo_ns, mhi),
        ("marginal", mhi, hi),
        ("out", hi, u64::MAX),
    ];
    for (class, a, b) in zones {
        let (xa, xb) = (x(a), x(b));
        if xb > xa {
            let _ = write!(
                s,
                r#"<rect class="zone {class}" x="{xa:.1}" y="6" width="{:.1}" height="12"/>"#,
                xb - xa
            );
        }
    }
    let xv = x(value_ns);
    if u_ns > 0 {
        let (xa, xb) = (
            x(value_ns.saturating_sub(u_ns)),
            x(value_ns.saturating_add(u_ns)),
        );
        let _ = write!(
            s,
            r#"<line class="uncertainty" x1="{xa:.1}" y1="12" x2="{:.1}" y2="12"/>"#,
            xb.max(xa + 1.0)
        );
    }
    // The lower limit's label ends at it, the upper's starts at it: they
    // cannot meet, as the view keeps the band in its middle half.
    let _ = write!(
        s,
        r#"<line class="value" x1="{xv:.1}" y1="2" x2="{xv:.1}" y2="22"/><text class="tick" x="{:.1}" y="31" text-anchor="{}">{}</text><text class="tick" x="{:.1}" y="31" text-anchor="{}">{}</text></svg>"#,
        x(lo_ns),
        if x(lo_ns) > LABEL_W { "end" } else { "start" },
        esc(&us(lo_ns)),
        if hi_ns.is_some() {
            x(finite_top)
        } else {
            w - r
        },
        if hi_ns.is_some() && x(finite_top) < w - LABEL_W {
            "start"
        } else {
            "end"
        },
        esc(&hi_ns.map_or("no upper limit".to_string(), us)),
    );
    s
}

/// Nanoseconds as microseconds, for labels.
pub fn us(ns: u64) -> String {
    format!("{:.3} us", ns as f64 / 1000.0)
}

/// A move's pulse intervals as segments: against the pulse number (the
/// scenario's, from 1: the move's first pulse is `before + 1`, and has no
/// interval) or against the time from the move.
fn segments(
    runs: &[[u64; 3]],
    before: u64,
    by_time: bool,
    band: impl Fn(f64) -> f64,
) -> Vec<Segment> {
    let mut out = Vec::new();
    let mut pulse = before;
    let mut last: Option<u64> = None;
    for &[from, count, span] in runs.iter().filter(|r| r[1] > 0) {
        let x = |p: u64, t: u64| if by_time { t as f64 / 1e6 } else { p as f64 };
        if let Some(prev) = last {
            let gap = from.saturating_sub(prev) as f64 / 1000.0;
            let p = pulse.saturating_add(1);
            out.push(Segment {
                x0: x(p, from),
                x1: x(p, from),
                n: 1,
                y: band(gap),
            });
        }
        if count > 1 {
            let dt = span as f64 / (count - 1) as f64 / 1000.0;
            out.push(Segment {
                x0: x(
                    pulse.saturating_add(2),
                    from.saturating_add(span / (count - 1)),
                ),
                x1: x(pulse.saturating_add(count), from.saturating_add(span)),
                n: count - 1,
                y: band(dt),
            });
        }
        pulse = pulse.saturating_add(count);
        last = Some(from.saturating_add(span));
    }
    out
}

/// Where the scenario failed in this move: the pulse at or after the
/// failure, its number and its time from the move.
pub fn mark_in(m: &MoveFigure, at_ns: u64) -> Option<(u64, u64)> {
    let t = at_ns.checked_sub(m.at_ns)?;
    let mut pulse = 0u64;
    let mut best = None;
    for &[from, count, span] in &m.runs {
        if count == 0 {
            continue;
        }
        if t <= from.saturating_add(span) {
            let k = match count {
                1 => 0,
                _ if t <= from => 0,
                n => ((t - from) as u128 * u128::from(n - 1)).div_ceil(u128::from(span.max(1)))
                    as u64,
            };
            let when = match count {
                1 => from,
                n => from
                    .saturating_add((u128::from(k) * u128::from(span) / u128::from(n - 1)) as u64),
            };
            return Some((pulse.saturating_add(k + 1), when));
        }
        pulse = pulse.saturating_add(count);
        best = Some((pulse, from.saturating_add(span)));
    }
    best
}

/// The two speed profiles of a move (interval against pulse number, and
/// against time), the golden one beneath with its tolerance band, and the
/// failure marked. `tol` is the interval tolerance, percent, and floor, ns;
/// `before`, the scenario's pulses before this move (the pulses are
/// numbered over the scenario, as its failure texts number them).
/// Also whether either was reduced for drawing (the page says so under
/// them: a note inside a plot would cover what it draws).
pub fn profiles(
    m: &MoveFigure,
    before: u64,
    mark: Option<(u64, &str)>,
    tol: (f64, u64),
) -> (String, bool) {
    let mut out = String::new();
    let mut reduced = false;
    for by_time in [false, true] {
        let (svg, r) = profile(m, before, mark, tol, by_time);
        out.push_str(&svg);
        reduced |= r;
    }
    (out, reduced)
}

fn profile(
    m: &MoveFigure,
    before: u64,
    mark: Option<(u64, &str)>,
    tol: (f64, u64),
    by_time: bool,
) -> (String, bool) {
    let (pct, floor) = (tol.0 / 100.0, tol.1 as f64 / 1000.0);
    let board = segments(&m.runs, before, by_time, |y| y);
    let golden = m.golden.as_deref().map(|g| {
        (
            segments(g, before, by_time, |y| y),
            segments(g, before, by_time, |y| (y - y * pct - floor).max(0.0)),
            segments(g, before, by_time, |y| y + y * pct + floor),
        )
    });
    let all = board.iter().chain(golden.iter().flat_map(|g| g.2.iter()));
    let (mut x_lo, mut x_hi, mut y_hi) = (f64::INFINITY, f64::NEG_INFINITY, 0f64);
    for s in all {
        x_lo = x_lo.min(s.x0);
        x_hi = x_hi.max(s.x1);
        y_hi = y_hi.max(s.y);
    }
    if x_lo > x_hi {
        (x_lo, x_hi) = (0.0, 1.0);
    }
    let class = if by_time {
        "profile by-time"
    } else {
        "profile by-pulse"
    };
    let mut p = Plot::new(PROFILE.0, PROFILE.1, (x_lo, x_hi), (0.0, y_hi * 1.1), class);
    p.axes(
        if by_time {
            "time from the move (ms)"
        } else {
            "pulse number (of the scenario)"
        },
        "interval (us)",
    );
    let cols = p.columns();
    let mut decimated = false;
    // The band beneath, the board's line over it, and the golden line,
    // dashed, on top: where the two agree both still show.
    if let Some((_, lo, hi)) = &golden {
        let (lo, hi) = (reduce(lo, x_lo, x_hi, cols), reduce(hi, x_lo, x_hi, cols));
        p.band("band", &lo.points, &hi.points);
    }
    let b = reduce(&board, x_lo, x_hi, cols);
    decimated |= b.decimated;
    p.line("board", &b.points);
    if let Some((line, _, _)) = &golden {
        let g = reduce(line, x_lo, x_hi, cols);
        decimated |= g.decimated;
        p.line("golden", &g.points);
    }
    if let Some((at, label)) = mark {
        if let Some((pulse, t)) = mark_in(m, at) {
            let pulse = before + pulse;
            let x = if by_time {
                t as f64 / 1e6
            } else {
                pulse as f64
            };
            p.mark("divergence", x, &format!("{label}: pulse {pulse}"));
        }
    }
    (p.finish(), decimated)
}

/// The pins around a failure: POUT's pulses (and the golden's), each pin,
/// the bus accesses, the failure marked.
pub fn waveform(w: &Waveform) -> String {
    // A record is read from a file: what it holds is drawn within bounds,
    // however much of it there is.
    if w.to_ns <= w.from_ns {
        return r#"<p class="detail">(the record's waveform has an empty window: not drawn)</p>"#
            .into();
    }
    let cap = |v: &[u64]| v[..v.len().min(MAX_WAVE_PULSES)].to_vec();
    let pins = &w.pins[..w.pins.len().min(MAX_WAVE_PINS)];
    let w = Waveform {
        pout: cap(&w.pout),
        golden_pout: w.golden_pout.as_deref().map(cap),
        bus: w.bus[..w.bus.len().min(MAX_WAVE_PULSES)].to_vec(),
        pins: pins
            .iter()
            .map(|p| PinWave {
                bits: p.bits.clamp(1, 8),
                changes: p.changes[..p.changes.len().min(MAX_WAVE_CHANGES)].to_vec(),
                ..p.clone()
            })
            .collect(),
        ..w.clone()
    };
    let w = &w;
    let row = 24.0;
    let rows = 1 + usize::from(w.golden_pout.is_some()) + w.pins.len() + 1;
    let (width, label_w) = (940.0, 90.0);
    let height = rows as f64 * row + 44.0;
    let span = (w.to_ns - w.from_ns) as f64;
    let x = |t: u64| {
        let at = label_w + t.saturating_sub(w.from_ns) as f64 / span * (width - label_w - 10.0);
        at.min(width - 10.0)
    };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg class="waveform" width="{width}" height="{height}" viewBox="0 0 {width} {height}" role="img" data-pulses="{}">"#,
        w.pout.len()
    );
    let mut y = 4.0;
    let name = |s: &mut String, y: f64, label: &str| {
        let _ = write!(
            s,
            r#"<text class="pin" x="4" y="{:.1}">{}</text>"#,
            y + 14.0,
            esc(label)
        );
    };
    let ticks = |s: &mut String, y: f64, pulses: &[u64], class: &str| {
        let _ = write!(s, r#"<path class="{class}" d=""#);
        for &t in pulses {
            let _ = write!(s, "M{:.1} {:.1}V{:.1}", x(t), y + 18.0, y + 3.0);
        }
        s.push_str(r#""/>"#);
    };
    name(&mut s, y, "POUT");
    ticks(&mut s, y, &w.pout, "pout");
    y += row;
    if let Some(g) = &w.golden_pout {
        name(&mut s, y, "POUT golden");
        ticks(&mut s, y, g, "pout golden");
        y += row;
    }
    for pin in &w.pins {
        name(&mut s, y, &pin.name);
        let (lo, hi) = (y + 18.0, y + 4.0);
        let mut v = u64::from(pin.initial);
        let mut t0 = w.from_ns;
        let mut pieces = Vec::new();
        for &[t, nv] in pin
            .changes
            .iter()
            .chain(std::iter::once(&[w.to_ns, u64::MAX]))
        {
            pieces.push((t0, t.max(t0), v));
            (t0, v) = (t, nv);
        }
        for (a, b, v) in pieces {
            if pin.bits == 1 {
                let yy = if v != 0 { hi } else { lo };
                // High is shaded down to low, so a level reads at a glance.
                if v != 0 {
                    let _ = write!(
                        s,
                        r#"<rect class="high" x="{:.1}" y="{hi:.1}" width="{:.1}" height="{:.1}"/>"#,
                        x(a),
                        (x(b) - x(a)).max(0.5),
                        lo - hi
                    );
                }
                let _ = write!(
                    s,
                    r#"<line class="level" x1="{:.1}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" data-level="{}"/>"#,
                    x(a),
                    x(b),
                    u8::from(v != 0)
                );
                // An edge where the level changed, not at the window's edge.
                if a > w.from_ns {
                    let _ = write!(
                        s,
                        r#"<line class="level" x1="{0:.1}" y1="{lo:.1}" x2="{0:.1}" y2="{hi:.1}"/>"#,
                        x(a)
                    );
                }
            } else {
                let _ = write!(
                    s,
                    r#"<rect class="bus" x="{:.1}" y="{hi:.1}" width="{:.1}" height="14"/><text class="val" x="{:.1}" y="{:.1}">{v:0width$b}</text>"#,
                    x(a),
                    (x(b) - x(a)).max(0.5),
                    x(a) + 2.0,
                    hi + 11.0,
                    width = usize::from(pin.bits)
                );
            }
        }
        y += row;
    }
    name(&mut s, y, "bus");
    // Each access a tick; its name where there is room before the next
    // name (a label is about 6 px a letter), else in its tooltip alone.
    let mut free_from = 0.0;
    for (t, what) in &w.bus {
        let xt = x(*t);
        let room = xt + 2.0 >= free_from && xt + 2.0 + what.len() as f64 * 6.0 <= width;
        let _ = write!(
            s,
            r#"<g class="access"><title>{3}</title><line x1="{0:.1}" y1="{1:.1}" x2="{0:.1}" y2="{2:.1}"/>"#,
            xt,
            y + 3.0,
            y + 18.0,
            esc(what)
        );
        if room {
            let _ = write!(
                s,
                r#"<text x="{:.1}" y="{:.1}">{}</text>"#,
                xt + 2.0,
                y + 18.0,
                esc(what)
            );
            free_from = xt + 2.0 + what.len() as f64 * 6.0 + 4.0;
        }
        s.push_str("</g>");
    }
    y += row;
    // The time axis, from the failure: ticks at round steps either side.
    let xm = x(w.mark_ns);
    let _ = write!(
        s,
        r#"<line class="mark" x1="{xm:.1}" y1="0" x2="{xm:.1}" y2="{y:.1}"/>"#
    );
    let rel = |t: u64| (t as f64 - w.mark_ns as f64) / 1e3;
    let mut last_end = label_w - 4.0;
    for tick in super::svg::ticks(rel(w.from_ns), rel(w.to_ns), 8) {
        let t = (w.mark_ns as f64 + tick * 1e3).max(0.0) as u64;
        let xt = x(t);
        let label = match tick {
            v if v > 0.0 => format!("+{} us", super::svg::tick_label(v)),
            v => format!("{} us", super::svg::tick_label(v)),
        };
        let half = label.len() as f64 * 3.0;
        if xt - half < last_end || xt + half > width {
            continue;
        }
        last_end = xt + half + 6.0;
        let _ = write!(
            s,
            r#"<line class="grid" x1="{xt:.1}" y1="{:.1}" x2="{xt:.1}" y2="{:.1}"/><text class="tick" x="{xt:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            y,
            y + 4.0,
            y + 14.0,
            esc(&label)
        );
    }
    let _ = write!(
        s,
        r#"<text class="tick" x="4" y="{:.1}">from the failure, at {}</text></svg>"#,
        y + 28.0,
        esc(&us(w.mark_ns)),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mv(runs: Vec<[u64; 3]>) -> MoveFigure {
        MoveFigure {
            at_ns: 1_000,
            runs,
            ..MoveFigure::default()
        }
    }

    #[test]
    fn intervals_come_from_the_runs_and_the_gaps_between() {
        // Pulses at 100, 300, 500 (run 1), then 650, 750 (run 2).
        let s = segments(&[[100, 3, 400], [650, 2, 100]], 0, false, |y| y);
        let points: Vec<_> = s.iter().map(|s| (s.x0, s.x1, s.n, s.y)).collect();
        assert_eq!(
            points,
            vec![(2.0, 3.0, 2, 0.2), (4.0, 4.0, 1, 0.15), (5.0, 5.0, 1, 0.1)]
        );
    }

    #[test]
    fn a_failure_marks_the_pulse_at_or_after_it() {
        let m = mv(vec![[100, 3, 400], [650, 2, 100]]);
        assert_eq!(mark_in(&m, 1_000 + 300), Some((2, 300)));
        assert_eq!(mark_in(&m, 1_000 + 301), Some((3, 500)));
        assert_eq!(mark_in(&m, 1_000 + 600), Some((4, 650)));
        // After the last pulse: the last pulse.
        assert_eq!(mark_in(&m, 1_000 + 9_000), Some((5, 750)));
        assert_eq!(mark_in(&m, 10), None);
    }
}
