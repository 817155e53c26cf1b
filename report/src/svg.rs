//! Inline SVG for the HTML report: axes with round ticks, lines, bands,
//! and the reduction of a long series to what a plot can show.
//!
//! A series is given as [`Segment`]s, stretches of equally spaced points
//! of one value (a run of pulses at one interval), so a move of millions
//! of pulses is reduced without its points ever existing:
//! [`reduce`] keeps every point when there are no more than the plot's
//! pixel columns, and otherwise the least and the greatest value in each
//! column (min/max decimation: a spike of one pulse still shows).

use std::fmt::Write as _;

/// `n` points from `x0` to `x1`, equally spaced, all of value `y` (one
/// point at `x0` when `n` is 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub x0: f64,
    pub x1: f64,
    pub n: u64,
    pub y: f64,
}

/// A series reduced for drawing.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Reduced {
    pub points: Vec<(f64, f64)>,
    /// Whether it was reduced to each column's least and greatest value.
    pub decimated: bool,
}

/// `segments` as points to draw in `columns` pixel columns over
/// `x_lo..=x_hi`: every point when they are no more than the columns,
/// otherwise each column's least and greatest value, in column order.
pub fn reduce(segments: &[Segment], x_lo: f64, x_hi: f64, columns: usize) -> Reduced {
    let total = segments.iter().fold(0u64, |n, s| n.saturating_add(s.n));
    if total <= columns as u64 {
        let mut points = Vec::with_capacity(total as usize);
        for s in segments {
            for k in 0..s.n {
                let x = match s.n {
                    1 => s.x0,
                    n => s.x0 + (s.x1 - s.x0) * k as f64 / (n - 1) as f64,
                };
                points.push((x, s.y));
            }
        }
        return Reduced {
            points,
            decimated: false,
        };
    }
    let width = (x_hi - x_lo).max(f64::MIN_POSITIVE);
    let column = |x: f64| {
        let c = ((x - x_lo) / width * columns as f64).floor();
        c.clamp(0.0, (columns - 1) as f64) as usize
    };
    let mut lo = vec![f64::INFINITY; columns];
    let mut hi = vec![f64::NEG_INFINITY; columns];
    for s in segments.iter().filter(|s| s.n > 0) {
        let (a, b) = (column(s.x0), column(s.x1));
        for c in a.min(b)..=a.max(b) {
            lo[c] = lo[c].min(s.y);
            hi[c] = hi[c].max(s.y);
        }
    }
    let mut points = Vec::with_capacity(2 * columns);
    for c in 0..columns {
        if lo[c] > hi[c] {
            continue;
        }
        let x = x_lo + (c as f64 + 0.5) * width / columns as f64;
        points.push((x, lo[c]));
        if hi[c] > lo[c] {
            points.push((x, hi[c]));
        }
    }
    Reduced {
        points,
        decimated: true,
    }
}

/// Round tick values covering `lo..=hi`, about `want` of them.
pub fn ticks(lo: f64, hi: f64, want: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let raw = span / want.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + step * 1e-9 && out.len() < 50 {
        out.push(if t.abs() < step * 1e-9 { 0.0 } else { t });
        t += step;
    }
    out
}

/// A tick's label: no more digits than the step needs.
pub fn tick_label(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// `text` safe inside HTML and SVG, in text or in a quoted attribute.
pub fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            // Control characters are no HTML text (NUL is a parse error).
            '\n' | '\t' => out.push(c),
            c if c.is_control() => out.push('\u{FFFD}'),
            _ => out.push(c),
        }
    }
    out
}

/// A plot area: data coordinates mapped to pixels, with axes drawn.
#[derive(Debug, Clone)]
pub struct Plot {
    pub width: f64,
    pub height: f64,
    left: f64,
    right: f64,
    top: f64,
    bottom: f64,
    pub x: (f64, f64),
    pub y: (f64, f64),
    svg: String,
}

impl Plot {
    /// A plot of `width` by `height` pixels over `x` and `y`, with the
    /// axes' titles.
    pub fn new(width: f64, height: f64, x: (f64, f64), y: (f64, f64), class: &str) -> Plot {
        let fix = |(a, b): (f64, f64)| {
            if b > a && a.is_finite() && b.is_finite() {
                (a, b)
            } else if a.is_finite() {
                (a - 1.0, a + 1.0)
            } else {
                (0.0, 1.0)
            }
        };
        let mut p = Plot {
            width,
            height,
            left: 56.0,
            right: 12.0,
            top: 10.0,
            bottom: 34.0,
            x: fix(x),
            y: fix(y),
            svg: String::new(),
        };
        let _ = write!(
            p.svg,
            r#"<svg class="{}" width="{width}" height="{height}" viewBox="0 0 {width} {height}" role="img">"#,
            esc(class)
        );
        p
    }

    /// Pixel columns of the plot area: the most points a reduced series
    /// draws per value.
    pub fn columns(&self) -> usize {
        (self.width - self.left - self.right).max(1.0) as usize
    }

    pub fn px(&self, x: f64) -> f64 {
        let (a, b) = self.x;
        self.left + (x - a) / (b - a) * (self.width - self.left - self.right)
    }

    pub fn py(&self, y: f64) -> f64 {
        let (a, b) = self.y;
        self.height - self.bottom - (y - a) / (b - a) * (self.height - self.top - self.bottom)
    }

    /// Axes, grid and tick labels, with the axes' titles.
    pub fn axes(&mut self, x_title: &str, y_title: &str) {
        let (x0, x1) = (self.left, self.width - self.right);
        let (y0, y1) = (self.height - self.bottom, self.top);
        for t in ticks(self.y.0, self.y.1, 4) {
            let y = self.py(t);
            let _ = write!(
                self.svg,
                r#"<line class="grid" x1="{x0:.1}" y1="{y:.1}" x2="{x1:.1}" y2="{y:.1}"/><text class="tick" x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
                x0 - 4.0,
                y + 3.5,
                tick_label(t)
            );
        }
        for t in ticks(self.x.0, self.x.1, 6) {
            let x = self.px(t);
            let label = tick_label(t);
            // A label (about 6 px a character) that would pass the
            // drawing's edge ends at it instead.
            let half = label.len() as f64 * 3.0 + 1.0;
            let (lx, anchor) = if x + half > self.width {
                (self.width - 1.0, "end")
            } else if x - half < x0 {
                // Clear of the y axis's lowest label, at the corner.
                (x0 + 1.0, "start")
            } else {
                (x, "middle")
            };
            let _ = write!(
                self.svg,
                r#"<line class="grid" x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{y1:.1}"/><text class="tick" x="{lx:.1}" y="{:.1}" text-anchor="{anchor}">{}</text>"#,
                y0 + 15.0,
                label
            );
        }
        let _ = write!(
            self.svg,
            r#"<rect class="frame" x="{x0:.1}" y="{y1:.1}" width="{:.1}" height="{:.1}"/><text class="axis" x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text class="axis" transform="translate(12 {:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
            x1 - x0,
            y0 - y1,
            (x0 + x1) / 2.0,
            self.height - 4.0,
            esc(x_title),
            (y0 + y1) / 2.0,
            esc(y_title)
        );
    }

    /// A line through `points`, tagged with its point count
    /// (`data-points`) for the report's tests and readers.
    pub fn line(&mut self, class: &str, points: &[(f64, f64)]) {
        let _ = write!(
            self.svg,
            r#"<polyline class="{}" data-points="{}" points=""#,
            esc(class),
            points.len()
        );
        for (x, y) in points {
            let _ = write!(self.svg, "{:.1},{:.1} ", self.px(*x), self.py(*y));
        }
        self.svg.push_str(r#""/>"#);
    }

    /// The area between two series of the same x (a tolerance band).
    /// A dot at each point, so that a series of one point shows.
    pub fn dots(&mut self, class: &str, points: &[(f64, f64)]) {
        let _ = write!(self.svg, r#"<g class="{}">"#, esc(class));
        for &(x, y) in points {
            let _ = write!(
                self.svg,
                r#"<circle cx="{:.1}" cy="{:.1}" r="2.5"/>"#,
                self.px(x),
                self.py(y)
            );
        }
        self.svg.push_str("</g>");
    }

    pub fn band(&mut self, class: &str, lower: &[(f64, f64)], upper: &[(f64, f64)]) {
        if lower.is_empty() {
            return;
        }
        let _ = write!(self.svg, r#"<polygon class="{}" points=""#, esc(class));
        for (x, y) in upper.iter().chain(lower.iter().rev()) {
            let _ = write!(self.svg, "{:.1},{:.1} ", self.px(*x), self.py(*y));
        }
        self.svg.push_str(r#""/>"#);
    }

    /// A vertical marker at `x` with a label (the first divergence).
    pub fn mark(&mut self, class: &str, x: f64, label: &str) {
        let px = self.px(x);
        let _ = write!(
            self.svg,
            r#"<g class="{}" data-x="{x}"><line x1="{px:.1}" y1="{:.1}" x2="{px:.1}" y2="{:.1}"/><text x="{:.1}" y="{:.1}" text-anchor="{}">{}</text></g>"#,
            esc(class),
            self.top,
            self.height - self.bottom,
            px + if px > self.width / 2.0 { -4.0 } else { 4.0 },
            self.top + 11.0,
            if px > self.width / 2.0 {
                "end"
            } else {
                "start"
            },
            esc(label)
        );
    }

    /// A note in the plot's corner (that a series was reduced).
    pub fn note(&mut self, text: &str) {
        let _ = write!(
            self.svg,
            r#"<text class="note" x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
            self.width - self.right - 4.0,
            self.height - self.bottom - 5.0,
            esc(text)
        );
    }

    pub fn finish(mut self) -> String {
        self.svg.push_str("</svg>");
        self.svg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(x0: f64, x1: f64, n: u64, y: f64) -> Segment {
        Segment { x0, x1, n, y }
    }

    #[test]
    fn few_points_are_kept_as_they_are() {
        let r = reduce(
            &[seg(2.0, 4.0, 3, 10.0), seg(5.0, 5.0, 1, 7.0)],
            2.0,
            5.0,
            100,
        );
        assert!(!r.decimated);
        assert_eq!(
            r.points,
            vec![(2.0, 10.0), (3.0, 10.0), (4.0, 10.0), (5.0, 7.0)]
        );
    }

    #[test]
    fn many_points_keep_each_columns_extremes() {
        // A million points at 5, and one spike of 9 in the middle: the
        // spike survives the reduction to 10 columns.
        let segs = [
            seg(0.0, 499_999.0, 500_000, 5.0),
            seg(500_000.0, 500_000.0, 1, 9.0),
            seg(500_001.0, 1_000_000.0, 500_000, 5.0),
        ];
        let r = reduce(&segs, 0.0, 1_000_000.0, 10);
        assert!(r.decimated);
        assert!(r.points.len() <= 20);
        assert!(r.points.iter().any(|p| p.1 == 9.0));
        assert_eq!(r.points.iter().filter(|p| p.1 == 5.0).count(), 10);
    }

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(ticks(41.5, 203.0, 4), vec![50.0, 100.0, 150.0, 200.0]);
        assert_eq!(tick_label(0.30000000000000004), "0.3");
    }

    #[test]
    fn text_is_escaped_for_html_and_attributes() {
        assert_eq!(
            esc(r#"<a href="x">&'"#),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
    }
}
