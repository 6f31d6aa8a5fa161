//! A minimal hand-written SVG line plot (no fonts or plotting crates needed: the text is left to
//! the SVG viewer). Panels side by side; y axes logarithmic, x axes logarithmic or linear.

use std::fmt::Write as _;

/// One line of a panel.
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// CSS colour.
    pub color: String,
    /// `(x, y)` points, in row order; `y > 0` (non-positive values are clamped to the axis).
    pub points: Vec<(f64, f64)>,
}

/// One panel.
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// The lines.
    pub series: Vec<Series>,
}

const PW: f64 = 420.0;
const PH: f64 = 340.0;
const ML: f64 = 70.0;
const MR: f64 = 15.0;
const MT: f64 = 40.0;
const MB: f64 = 50.0;
const LEGEND_H: f64 = 70.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Axis range: decades for a log axis, "nice" bounds for a linear one.
fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals {
        let v = if log { v.max(1e-300).log10() } else { v };
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if log {
        (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
    } else {
        let lo = lo.min(0.0);
        (lo, if hi > lo { hi } else { lo + 1.0 })
    }
}

/// The SVG document.
pub fn render(panels: &[Panel]) -> String {
    let width = PW * panels.len() as f64;
    let height = PH + LEGEND_H;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" \
         viewBox=\"0 0 {width} {height}\" font-family=\"sans-serif\" font-size=\"11\">"
    );
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    for (k, p) in panels.iter().enumerate() {
        let ox = PW * k as f64;
        let (x0, x1) = range(
            p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)),
            p.x_log,
        );
        // y: floor the data a little below the smallest positive value.
        let (y0, y1) = range(
            p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
            true,
        );
        let (l, r, t, b) = (ox + ML, ox + PW - MR, MT, PH - MB);
        let fx = |x: f64| {
            let v = if p.x_log { x.max(1e-300).log10() } else { x };
            l + (v - x0) / (x1 - x0) * (r - l)
        };
        let fy = |y: f64| {
            let v = y.max(10f64.powf(y0)).log10();
            b - (v - y0) / (y1 - y0) * (b - t)
        };
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"13\" font-weight=\"bold\">{}</text>",
            (l + r) / 2.0,
            esc(&p.title)
        );
        let _ = writeln!(
            s,
            "<rect x=\"{l}\" y=\"{t}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
            r - l,
            b - t
        );
        // y ticks: decades.
        let mut e = y0;
        while e <= y1 + 1e-9 {
            let y = b - (e - y0) / (y1 - y0) * (b - t);
            let _ = writeln!(
                s,
                "<line x1=\"{l}\" y1=\"{y}\" x2=\"{r}\" y2=\"{y}\" stroke=\"#ddd\"/>\
                 <text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{}</text>",
                l - 4.0,
                y + 4.0,
                e as i64
            );
            e += 1.0;
        }
        // x ticks: decades (log) or 5 intervals (linear).
        let ticks: Vec<(f64, String)> = if p.x_log {
            let mut v = Vec::new();
            let mut e = x0;
            while e <= x1 + 1e-9 {
                v.push((10f64.powf(e), format!("{}", 10f64.powf(e))));
                e += 1.0;
            }
            v
        } else {
            (0..=5)
                .map(|i| {
                    let x = x0 + (x1 - x0) * i as f64 / 5.0;
                    (x, format!("{x}"))
                })
                .collect()
        };
        for (x, lab) in ticks {
            let xp = fx(x);
            let _ = writeln!(
                s,
                "<line x1=\"{xp}\" y1=\"{t}\" x2=\"{xp}\" y2=\"{b}\" stroke=\"#ddd\"/>\
                 <text x=\"{xp}\" y=\"{}\" text-anchor=\"middle\">{lab}</text>",
                b + 15.0
            );
        }
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            (l + r) / 2.0,
            b + 32.0,
            esc(&p.x_label)
        );
        let _ = writeln!(
            s,
            "<text transform=\"translate({},{}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            ox + 16.0,
            (t + b) / 2.0,
            esc(&p.y_label)
        );
        for ser in &p.series {
            let pts: Vec<String> = ser
                .points
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", fx(x), fy(y)))
                .collect();
            if pts.len() > 1 {
                let _ = writeln!(
                    s,
                    "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.8\" points=\"{}\"/>",
                    ser.color,
                    pts.join(" ")
                );
            }
            for &(x, y) in &ser.points {
                let _ = writeln!(
                    s,
                    "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.8\" fill=\"{}\"/>",
                    fx(x),
                    fy(y),
                    ser.color
                );
            }
        }
    }
    // Shared legend (union of the series names, first colour wins).
    let mut seen: Vec<(&str, &str)> = Vec::new();
    for p in panels {
        for ser in &p.series {
            if !seen.iter().any(|(n, _)| *n == ser.name) {
                seen.push((&ser.name, &ser.color));
            }
        }
    }
    for (i, (name, color)) in seen.iter().enumerate() {
        let x = 20.0 + 230.0 * (i % 5) as f64;
        let y = PH + 15.0 + 22.0 * (i / 5) as f64;
        let _ = writeln!(
            s,
            "<line x1=\"{x}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"{color}\" stroke-width=\"3\"/>\
             <text x=\"{}\" y=\"{}\">{}</text>",
            x + 25.0,
            x + 30.0,
            y + 4.0,
            esc(name)
        );
    }
    let _ = writeln!(s, "</svg>");
    s
}
