//! The sweep's plot as SVG: each configuration's error against its frame
//! time on log–log axes, the Pareto front joined and labelled.

use std::fmt::Write;

/// One plotted configuration.
pub struct PlotPoint {
    /// Frame time in ms (x).
    pub ms: f64,
    /// Error (y).
    pub error: f64,
    /// Its label.
    pub label: String,
}

const W: f64 = 820.0;
const H: f64 = 520.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 240.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;

/// Log10 range covering `values` (positive, finite), widened to whole
/// decade fractions and never empty.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(0.05);
    (lo - pad, hi + pad)
}

/// Tick values inside the log10 range: 1, 2, 5 × 10^k; where fewer than
/// two of those fall inside, every 1..9 × 10^k; where still fewer, five
/// evenly spaced (in log) values rounded to 3 significant digits.
fn ticks(range: (f64, f64)) -> Vec<f64> {
    let inside = |mantissas: &[f64]| -> Vec<f64> {
        let mut out = Vec::new();
        for k in range.0.floor() as i32..=range.1.ceil() as i32 {
            for m in mantissas {
                let v = m * 10f64.powi(k);
                if (range.0..=range.1).contains(&v.log10()) {
                    out.push(v);
                }
            }
        }
        out
    };
    let coarse = inside(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 2 {
        return coarse;
    }
    let fine = inside(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if fine.len() >= 2 {
        return fine;
    }
    (0..5)
        .map(|i| {
            let v = 10f64.powf(range.0 + (range.1 - range.0) * (i as f64 + 0.5) / 5.0);
            let digits = 10f64.powi(2 - v.log10().floor() as i32);
            (v * digits).round() / digits
        })
        .collect()
}

/// A tick's label: at most 3 significant digits, no trailing zeros.
fn tick_label(v: f64) -> String {
    let decimals = (2 - v.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The SVG document: `points` (non-positive or non-finite ones are left
/// out), `front` (indices into `points`, by cost) joined in red.
pub fn svg(
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[PlotPoint],
    front: &[usize],
) -> String {
    let shown =
        |p: &PlotPoint| p.ms.is_finite() && p.ms > 0.0 && p.error.is_finite() && p.error > 0.0;
    let xr = log_range(points.iter().filter(|p| shown(p)).map(|p| p.ms));
    let yr = log_range(points.iter().filter(|p| shown(p)).map(|p| p.error));
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let x = |v: f64| LEFT + (v.log10() - xr.0) / (xr.1 - xr.0) * pw;
    let y = |v: f64| TOP + ph - (v.log10() - yr.0) / (yr.1 - yr.0) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" font-size="15" text-anchor="middle">{}</text>"#,
        LEFT + pw / 2.0,
        escape(title)
    );
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>"##
    );
    for t in ticks(xr) {
        let _ = writeln!(
            s,
            r##"<line x1="{0:.1}" y1="{TOP}" x2="{0:.1}" y2="{1}" stroke="#ddd"/><text x="{0:.1}" y="{2}" text-anchor="middle">{3}</text>"##,
            x(t),
            TOP + ph,
            TOP + ph + 16.0,
            tick_label(t)
        );
    }
    for t in ticks(yr) {
        let _ = writeln!(
            s,
            r##"<line x1="{LEFT}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#ddd"/><text x="{2}" y="{3:.1}" text-anchor="end">{4}</text>"##,
            y(t),
            LEFT + pw,
            LEFT - 6.0,
            y(t) + 4.0,
            tick_label(t)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        LEFT + pw / 2.0,
        H - 18.0,
        escape(x_label)
    );
    let _ = writeln!(
        s,
        r#"<text x="18" y="{0}" text-anchor="middle" transform="rotate(-90 18 {0})">{1}</text>"#,
        TOP + ph / 2.0,
        escape(y_label)
    );
    let on_front: Vec<&PlotPoint> = front
        .iter()
        .filter_map(|&i| points.get(i))
        .filter(|p| shown(p))
        .collect();
    if on_front.len() > 1 {
        let path: Vec<String> = on_front
            .iter()
            .map(|p| format!("{:.1},{:.1}", x(p.ms), y(p.error)))
            .collect();
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#c0392b" stroke-width="1.5"/>"##,
            path.join(" ")
        );
    }
    for (i, p) in points.iter().enumerate().filter(|(_, p)| shown(p)) {
        let front_point = front.contains(&i);
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="{}"><title>{}</title></circle>"##,
            x(p.ms),
            y(p.error),
            if front_point { 4.5 } else { 3.5 },
            if front_point { "#c0392b" } else { "#7f8c8d" },
            escape(&format!(
                "{}: {:.2} ms, error {:.4}",
                p.label, p.ms, p.error
            ))
        );
    }
    // The front's labels in the right margin, in order of cost.
    let _ = writeln!(
        s,
        r##"<text x="{}" y="{}" fill="#c0392b">Pareto front (cheapest first)</text>"##,
        W - RIGHT + 12.0,
        TOP + 4.0
    );
    for (k, p) in on_front.iter().enumerate() {
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" font-size="10">{}</text>"#,
            W - RIGHT + 12.0,
            TOP + 20.0 + 13.0 * k as f64,
            escape(&p.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shown_point_is_drawn_inside_the_frame() {
        let points: Vec<PlotPoint> = [
            (5.0, 0.3),
            (20.0, 0.1),
            (80.0, 0.04),
            (0.0, 0.1),
            (9.0, f64::NAN),
        ]
        .iter()
        .enumerate()
        .map(|(i, &(ms, error))| PlotPoint {
            ms,
            error,
            label: format!("c{i} <a&b>"),
        })
        .collect();
        let doc = svg("t", "ms", "err", &points, &[0, 1, 2]);
        assert!(doc.starts_with("<svg") && doc.ends_with("</svg>\n"));
        assert_eq!(
            doc.matches("<circle").count(),
            3,
            "zero and NaN points are left out"
        );
        assert_eq!(doc.matches("<polyline").count(), 1);
        assert!(doc.contains("c0 &lt;a&amp;b&gt;") && !doc.contains("<a&b>"));
        for c in doc.split("<circle cx=\"").skip(1) {
            let cx: f64 = c.split('"').next().unwrap().parse().unwrap();
            let cy: f64 = c
                .split("cy=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            assert!(
                (LEFT..=W - RIGHT).contains(&cx) && (TOP..=H - BOTTOM).contains(&cy),
                "{cx} {cy}"
            );
        }
    }

    #[test]
    fn ticks_fall_inside_the_range() {
        assert_eq!(ticks((0.5, 2.1)), vec![5.0, 10.0, 20.0, 50.0, 100.0]);
        // A narrower range (0.224-0.447) gets every 1..9 × 10^k...
        let labels: Vec<String> = ticks((-0.65, -0.35)).into_iter().map(tick_label).collect();
        assert_eq!(labels, ["0.3", "0.4"]);
        // ...and one without two of those (0.126-0.178, errors as a sweep
        // on DOG gives) five rounded values inside it.
        let narrow = ticks((-0.9, -0.75));
        assert_eq!(narrow.len(), 5, "{narrow:?}");
        assert!(
            narrow.iter().all(|v| (-0.9..=-0.75).contains(&v.log10())),
            "{narrow:?}"
        );
        assert_eq!(tick_label(narrow[0]), "0.13");
        assert_eq!(tick_label(0.14125), "0.141");
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(20.0), "20");
    }
}
