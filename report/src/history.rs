//! The HTML page of a results store (see [`history_html`]).

use super::plots::us;
use super::svg::{esc, reduce, Plot, Segment};
use crate::store::{mean_sd, Distribution, History};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Bins of a measurement's histogram.
const BINS: usize = 40;

/// One self-contained HTML page of a store's history, offline as
/// [`super::html`]'s: yield per revision, the revisions' measurement
/// distributions side by side against each band with their Cpk, each
/// scenario's pass rate across boards (lowest first), and the pass rate
/// of every board test over time.
pub fn history_html(h: &History, title: &str, store: &str) -> String {
    let mut s = String::with_capacity(256 << 10);
    super::html::head(&mut s, title);
    let _ = writeln!(
        s,
        r#"<p class="detail">{}: {} runs, {} boards{}.</p>"#,
        esc(store),
        h.runs,
        h.boards,
        h.span.as_ref().map_or(String::new(), |(a, b)| format!(
            ", from {} to {}",
            esc(a),
            esc(b)
        ))
    );
    yields(&mut s, h);
    boards(&mut s, h);
    revisions(&mut s, h);
    scenarios(&mut s, h);
    trend(&mut s, h);
    let _ = write!(
        s,
        "<footer>Made by ppmc {} from the results store {}. A board test is one board in one run; it passed when none of its scenarios failed, erred or was not run. Cpk is the distance from the mean to the nearer limit in three standard deviations.</footer>\n</body></html>\n",
        esc(crate::VERSION),
        esc(store)
    );
    s
}

fn yields(s: &mut String, h: &History) {
    s.push_str(r#"<section class="yield"><h2>Yield per revision</h2>"#);
    let (w, row) = (820.0, 26.0);
    let height = h.revisions.len() as f64 * row + 8.0;
    let _ = write!(
        s,
        r#"<svg class="yield" width="{w}" height="{height}" viewBox="0 0 {w} {height}" role="img">"#
    );
    for (i, r) in h.revisions.iter().enumerate() {
        let y = 4.0 + i as f64 * row;
        let bar = r.rate() * 360.0;
        let _ = write!(
            s,
            r#"<g class="rev" data-rev="{0}" data-yield="{1:.4}"><text x="4" y="{2:.1}">{0}</text><rect class="zone out" x="120" y="{3:.1}" width="360" height="16"/><rect class="zone in" x="120" y="{3:.1}" width="{4:.1}" height="16"/><text x="490" y="{2:.1}">{5:.1}% of {6} board {9}, {7} {10}{8}</text></g>"#,
            esc(&r.rev),
            r.rate(),
            y + 13.0,
            y,
            bar,
            r.rate() * 100.0,
            r.tests,
            r.boards,
            if r.flaky > 0 {
                format!(", {} flaky", r.flaky)
            } else {
                String::new()
            },
            if r.tests == 1 { "test" } else { "tests" },
            if r.boards == 1 { "board" } else { "boards" },
        );
    }
    s.push_str("</svg></section>\n");
}

/// Every board, the ones whose last test failed first: serial, revision,
/// station, board tests, last verdict and when; each row opens the list
/// of its board tests.
fn boards(s: &mut String, h: &History) {
    let boards = h.boards();
    let _ = write!(
        s,
        r#"<section class="boards"><h2>Boards ({})</h2><p class="detail">Every board the store has seen, those whose last test failed first. A board test is one board in one run.</p><table class="boards"><tr><th>board</th><th>revision</th><th>station</th><th>board tests</th><th>last verdict</th><th>last seen</th></tr>"#,
        boards.len()
    );
    for (k, b) in boards.iter().enumerate() {
        let verdict = if b.last_passed { "passed" } else { "failed" };
        let _ = write!(
            s,
            r##"<tr class="{verdict}" data-board="{0}"><td><a href="#board-{k}">{0}</a></td><td>{1}</td><td>{2}</td><td>{3}</td><td><span class="chip {verdict}">{verdict}</span></td><td>{4}</td></tr>"##,
            esc(&b.board),
            esc(&b.rev),
            esc(&b.station),
            b.tests.len(),
            esc(&b.last_seen),
        );
    }
    s.push_str("</table>");
    for (k, b) in boards.iter().enumerate() {
        let _ = write!(
            s,
            r#"<details class="board-tests" id="board-{k}"><summary>{} : {} board tests</summary><table><tr><th>run</th><th>started</th><th>revision</th><th>station</th><th>scenarios passed</th><th>verdict</th></tr>"#,
            esc(&b.board),
            b.tests.len()
        );
        for &i in b.tests.iter().rev() {
            let t = &h.trend[i];
            let verdict = if t.passed() { "passed" } else { "failed" };
            let _ = write!(
                s,
                r#"<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} of {}</td><td><span class="chip {verdict}">{verdict}</span></td></tr>"#,
                t.run,
                esc(&t.started),
                esc(&t.rev),
                esc(&t.station),
                t.passed,
                t.results
            );
        }
        s.push_str("</table></details>");
    }
    s.push_str("</section>\n");
}

/// Each measurement of each scenario, the revisions side by side on one
/// scale with its band; the lowest Cpk first.
fn revisions(s: &mut String, h: &History) {
    s.push_str(r#"<section class="revisions"><h2>Measurements by revision</h2><p class="detail">Each measurement of a scenario, a row per revision: where its values fall in the band (green inside, amber the marginal zone, red outside), as a histogram, the mean a dark tick. Lowest Cpk first.</p>"#);
    let mut groups: BTreeMap<(&str, &str), Vec<&Distribution>> = BTreeMap::new();
    for d in &h.measurements {
        groups
            .entry((d.scenario.as_str(), d.name.as_str()))
            .or_default()
            .push(d);
    }
    // First the measurements with a value outside its band, then those
    // whose revisions sit furthest apart in the band, then the lowest Cpk.
    let outside = |g: &[&Distribution]| {
        g.iter()
            .flat_map(|d| d.positions.iter().map(move |&p| (d, p)))
            .any(|(d, p)| p < 0.0 || (d.two_sided && p > 1.0))
    };
    let apart = |g: &[&Distribution]| {
        let means: Vec<f64> = g.iter().map(|d| mean_sd(&d.positions).0).collect();
        let hi = means.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = means.iter().copied().fold(f64::INFINITY, f64::min);
        hi - lo
    };
    let worst = |g: &[&Distribution]| {
        g.iter()
            .filter_map(|d| d.cpk())
            .fold(f64::INFINITY, f64::min)
    };
    let mut groups: Vec<_> = groups.into_iter().collect();
    groups.sort_by(|a, b| {
        outside(&b.1)
            .cmp(&outside(&a.1))
            .then(apart(&b.1).total_cmp(&apart(&a.1)))
            .then(worst(&a.1).total_cmp(&worst(&b.1)))
            .then(a.0.cmp(&b.0))
    });
    for ((scenario, name), group) in groups {
        let first = group[0];
        let band_of = |d: &Distribution| {
            format!(
                "{} to {}",
                us(d.lo_ns),
                d.hi_ns.map_or("no upper limit".into(), us)
            )
        };
        // Rows of one measurement may be held to other bands (boards
        // strapped to other clocks): each row then names its own.
        let rows_differ = group
            .iter()
            .any(|d| (d.lo_ns, d.hi_ns) != (first.lo_ns, first.hi_ns));
        let band = if group.iter().any(|d| d.bands_differ) {
            "each value against its own band: the boards' clocks differ".to_string()
        } else if rows_differ {
            "each row against its own band, in the table: the boards' straps differ".to_string()
        } else {
            format!(
                "band {} to {}",
                us(first.lo_ns),
                first.hi_ns.map_or("no upper limit".into(), us)
            )
        };
        let _ = write!(
            s,
            r#"<div class="measure-group" data-scenario="{}" data-measure="{}"><h4>{} in {} ({})</h4>"#,
            esc(scenario),
            esc(name),
            esc(name),
            esc(scenario),
            esc(&band)
        );
        s.push_str(&distribution_svg(&group));
        s.push_str(r#"<table class="dist"><tr><th>revision</th><th>band</th><th>n</th><th>out of band</th><th>mean</th><th>sd</th><th>min</th><th>max</th><th>Cpk</th></tr>"#);
        for d in &group {
            let out = d.out_of_band();
            let _ = write!(
                s,
                r#"<tr data-rev="{}"><td>{}</td><td>{}</td><td>{}</td><td{}>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>"#,
                esc(&d.rev),
                esc(&d.rev),
                esc(&if d.bands_differ {
                    "per board".to_string()
                } else {
                    band_of(d)
                }),
                d.values.len(),
                if out > 0 { r#" class="out""# } else { "" },
                out,
                esc(&us(d.mean_ns.round() as u64)),
                esc(&us(d.sd_ns().round() as u64)),
                esc(&us(d.min_ns)),
                esc(&us(d.max_ns)),
                cpk_text(d.cpk())
            );
        }
        s.push_str("</table></div>");
    }
    s.push_str("</section>\n");
}

/// The revisions' values placed in their bands (0 the lower limit, 1 the
/// upper), one row each, on one scale.
fn distribution_svg(group: &[&Distribution]) -> String {
    let (w, label, row) = (700.0, 110.0, 34.0);
    let first = group[0];
    let place = |ns: u64| match first.hi_ns {
        Some(hi) if hi > first.lo_ns => {
            (ns as f64 - first.lo_ns as f64) / (hi - first.lo_ns) as f64
        }
        _ => (ns as f64 - first.lo_ns as f64) / first.lo_ns.max(1) as f64,
    };
    let two_sided = group.iter().all(|d| d.two_sided);
    let (mut p0, mut p1) = (0.0f64, if two_sided { 1.0f64 } else { 0.0 });
    for d in group {
        for &p in &d.positions {
            p0 = p0.min(p);
            p1 = p1.max(p);
        }
    }
    let pad = ((p1 - p0) * 0.08).max(0.02);
    let (x0, x1) = (p0 - pad, p1 + pad);
    let x = |p: f64| label + (p - x0) / (x1 - x0) * (w - label - 10.0);
    let height = group.len() as f64 * row + 22.0;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg class="distribution" width="{w}" height="{height}" viewBox="0 0 {w} {height}" role="img">"#
    );
    let (m_lo, m_hi) = (
        place(first.marginal_lo_ns),
        first.marginal_hi_ns.map_or(x1, place),
    );
    let top = if two_sided { 1.0 } else { x1 };
    for (i, d) in group.iter().enumerate() {
        let y = 4.0 + i as f64 * row;
        let zones = [
            ("out", x0, 0.0),
            ("marginal", 0.0, m_lo),
            ("in", m_lo, m_hi.min(top)),
            ("marginal", m_hi.min(top), top),
            ("out", top, x1),
        ];
        let _ = write!(
            s,
            r#"<g class="rev" data-rev="{0}" data-mean-ns="{1:.1}" data-cpk="{2}"><text x="4" y="{3:.1}">{0}</text>"#,
            esc(&d.rev),
            d.mean_ns,
            d.cpk().map_or("none".to_string(), |c| format!("{c:.3}")),
            y + 17.0,
        );
        for (class, a, b) in zones {
            let (xa, xb) = (x(a.max(x0)), x(b.min(x1)));
            if xb > xa {
                let _ = write!(
                    s,
                    r#"<rect class="zone {class}" x="{xa:.1}" y="{y:.1}" width="{:.1}" height="26"/>"#,
                    xb - xa
                );
            }
        }
        // The histogram: BINS bins over the values' own range (one bar
        // when they are all one), tallest 24 px.
        let (d0, d1) = (
            d.positions.iter().copied().fold(f64::INFINITY, f64::min),
            d.positions
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max),
        );
        let bins_n = if d1 > d0 { BINS } else { 1 };
        let mut bins = vec![0u64; bins_n];
        for &p in &d.positions {
            let b = match bins_n {
                1 => 0,
                n => ((p - d0) / (d1 - d0) * n as f64) as usize,
            };
            bins[b.min(bins_n - 1)] += 1;
        }
        let tallest = bins.iter().copied().max().unwrap_or(1).max(1) as f64;
        for (b, &n) in bins.iter().enumerate().filter(|(_, n)| **n > 0) {
            let bh = n as f64 / tallest * 24.0;
            let (a, z) = match bins_n {
                1 => (x(d0) - 1.5, x(d0) + 1.5),
                n => {
                    let step = (d1 - d0) / n as f64;
                    (x(d0 + b as f64 * step), x(d0 + (b + 1) as f64 * step))
                }
            };
            let _ = write!(
                s,
                r#"<rect class="hist" x="{a:.1}" y="{:.1}" width="{:.1}" height="{bh:.1}"/>"#,
                y + 26.0 - bh,
                (z - a).max(1.5)
            );
        }
        let mean = d.positions.iter().sum::<f64>() / d.positions.len().max(1) as f64;
        let xm = x(mean);
        let _ = write!(
            s,
            r#"<line class="value" x1="{xm:.1}" y1="{:.1}" x2="{xm:.1}" y2="{:.1}"/></g>"#,
            y - 1.0,
            y + 27.0
        );
    }
    let yb = group.len() as f64 * row + 16.0;
    let lower = if group.iter().any(|d| d.bands_differ) {
        "lower limit".to_string()
    } else {
        us(first.lo_ns)
    };
    let _ = write!(
        s,
        r#"<text class="tick" x="{:.1}" y="{yb:.1}" text-anchor="middle">{}</text>"#,
        x(0.0),
        esc(&lower)
    );
    if let (true, Some(hi)) = (two_sided, first.hi_ns) {
        let upper = if group.iter().any(|d| d.bands_differ) {
            "upper limit".to_string()
        } else {
            us(hi)
        };
        let _ = write!(
            s,
            r#"<text class="tick" x="{:.1}" y="{yb:.1}" text-anchor="middle">{}</text>"#,
            x(1.0),
            esc(&upper)
        );
    }
    s.push_str("</svg>");
    s
}

fn scenarios(s: &mut String, h: &History) {
    let shaky = h
        .scenarios
        .iter()
        .filter(|r| r.rate() < 1.0 || r.flaky > 0)
        .count();
    let _ = write!(
        s,
        r#"<section class="scenario-rates"><h2>Scenarios across boards</h2><p class="detail">{shaky} of {} scenarios did not pass every time; lowest pass rate first.</p><table class="rates"><tr><th>scenario</th><th>section</th><th>pass rate</th><th>results</th><th>flaky</th><th>failed</th><th>errors</th><th>not run</th><th>boards</th></tr>"#,
        h.scenarios.len()
    );
    for r in &h.scenarios {
        let _ = write!(
            s,
            r#"<tr data-scenario="{}" data-rate="{:.4}"><td>{}</td><td>{}</td><td>{:.1}%</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>"#,
            esc(&r.scenario),
            r.rate(),
            esc(&r.scenario),
            esc(&r.section),
            r.rate() * 100.0,
            r.results,
            r.flaky,
            r.failed,
            r.errors,
            r.not_run,
            r.boards
        );
    }
    s.push_str("</table></section>\n");
}

/// The pass rate of every board test, oldest first, one line per revision.
fn trend(s: &mut String, h: &History) {
    let _ = write!(
        s,
        r#"<section class="trend"><h2>Over time</h2><p class="detail">Each revision's yield so far after each of its board tests, oldest first ({} tests{}): a dot per board test, at the share of that revision's tests until then that passed.</p>"#,
        h.trend.len(),
        h.trend
            .first()
            .zip(h.trend.last())
            .map_or(String::new(), |(a, b)| format!(
                ", {} to {}",
                esc(&a.started),
                esc(&b.started)
            ))
    );
    let n = h.trend.len().max(2) as f64;
    // 0 % at the bottom, 100 % below the top frame: a line at 100 % is
    // not drawn on the frame.
    let mut p = Plot::new(940.0, 240.0, (0.5, n + 0.5), (0.0, 105.0), "trend");
    p.axes("board test, oldest first", "yield so far (%)");
    let cols = p.columns();
    let mut series: BTreeMap<&str, (u64, u64, Vec<Segment>)> = BTreeMap::new();
    for (i, t) in h.trend.iter().enumerate() {
        let (tests, passed, segs) = series.entry(t.rev.as_str()).or_default();
        *tests += 1;
        *passed += u64::from(t.passed());
        let x = (i + 1) as f64;
        segs.push(Segment {
            x0: x,
            x1: x,
            n: 1,
            y: *passed as f64 * 100.0 / *tests as f64,
        });
    }
    let mut decimated = false;
    let mut legend = Vec::new();
    for (k, (rev, (tests, passed, segs))) in series.iter().enumerate() {
        let r = reduce(segs, 0.5, n + 0.5, cols);
        decimated |= r.decimated;
        let class = format!("series s{}", k % 6);
        p.line(&class, &r.points);
        p.dots(&class, &r.points);
        legend.push(format!(
            r#"<span class="key s{}">{}: {:.1} % of {tests}</span>"#,
            k % 6,
            esc(rev),
            *passed as f64 * 100.0 / (*tests).max(1) as f64
        ));
    }
    if decimated {
        p.note("reduced: least and greatest per pixel column");
    }
    s.push_str(&p.finish());
    let _ = write!(s, r#"<p class="legend">{}</p>"#, legend.join(" "));
    let total: u64 = h.trend.iter().map(|t| t.results).sum();
    let _ = write!(
        s,
        r#"<p class="detail">{} results in all; the newest test: {}.</p></section>"#,
        total,
        h.trend.last().map_or("none".into(), |t| format!(
            "{} on {} ({})",
            esc(&t.board),
            esc(&t.rev),
            esc(&t.started)
        ))
    );
}

/// A Cpk as the tables show it: two decimals, `> 100` past that (values
/// that all sit at one place in bands that scale with them), and `(no
/// spread)` when there is none.
pub fn cpk_text(cpk: Option<f64>) -> String {
    match cpk {
        None => "(no spread)".to_string(),
        Some(c) if c > 100.0 => "> 100".to_string(),
        Some(c) => format!("{c:.2}"),
    }
}
