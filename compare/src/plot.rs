//! The plot (`plot.svg`): accuracy and time per solve against N and sigma.

use crate::common::Problem;
use crate::measure::{Stats, METHODS};
use crate::rows::Row;
use crate::svg;
use std::path::{Path, PathBuf};

/// Writes `plot.svg` into `out` (a warning if it cannot) and returns its path.
pub fn write(out: &Path, all: &[(Row, Vec<Problem>)], results: &[Vec<Stats>]) -> PathBuf {
    let series = |group: usize, x: fn(&Row) -> f64, y: fn(&Stats) -> Option<f64>| {
        METHODS
            .iter()
            .filter_map(|&m| {
                let pts: Vec<(f64, f64)> = all
                    .iter()
                    .zip(results)
                    .filter(|((r, _), _)| r.group == group)
                    .filter_map(|((r, _), st)| {
                        st.iter()
                            .find(|s| s.method == m)
                            .and_then(y)
                            .filter(|v| v.is_finite())
                            .map(|v| (x(r), v))
                    })
                    .collect();
                (!pts.is_empty()).then(|| svg::Series {
                    name: m.name().to_string(),
                    color: m.color().to_string(),
                    points: pts,
                })
            })
            .collect::<Vec<_>>()
    };
    let panels = [
        svg::Panel {
            title: "Median rotation error vs N (general, 2 px)".into(),
            x_label: "N".into(),
            y_label: "median rotation error (deg)".into(),
            x_log: true,
            series: series(0, |r| r.n as f64, |s| Some(s.med_rot)),
        },
        svg::Panel {
            title: "Median rotation error vs sigma (general, N = 10)".into(),
            x_label: "sigma (px)".into(),
            y_label: "median rotation error (deg)".into(),
            x_log: false,
            series: series(1, |r| r.sigma, |s| Some(s.med_rot)),
        },
        svg::Panel {
            title: "Time per solve vs N (general, 2 px)".into(),
            x_label: "N".into(),
            y_label: "median time per solve (us)".into(),
            x_log: true,
            series: series(0, |r| r.n as f64, |s| s.us),
        },
    ];
    let plot = svg::render(&panels);
    let svg_path = out.join("plot.svg");
    if let Err(e) = std::fs::write(&svg_path, plot) {
        eprintln!("warning: cannot write {}: {e}", svg_path.display());
    }
    svg_path
}
