//! SVG line and point plots, for run reports and sweeps.

use super::escape;
use std::fmt::Write as _;

/// An SVG plot of named series of (x, y) points on linear axes: joined by lines if
/// `lines`, with a dot at each point if `dots`.
pub fn plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
    lines: bool,
    dots: bool,
) -> String {
    let (w, h, m) = (640.0, 400.0, 60.0);
    let pts = series.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, f64::NEG_INFINITY);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    // Empty or flat ranges (or NaN) get a unit span.
    if x1.partial_cmp(&x0) != Some(std::cmp::Ordering::Greater) {
        x1 = x0 + 1.0;
    }
    if y1.partial_cmp(&y0) != Some(std::cmp::Ordering::Greater) {
        y1 = y0 + 1.0;
    }
    let sx = |x: f64| m + (x - x0) / (x1 - x0) * (w - 2.0 * m);
    let sy = |y: f64| h - m - (y - y0) / (y1 - y0) * (h - 2.0 * m);
    let colours = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
    ];
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">
<rect width="{w}" height="{h}" fill="white"/>
<text x="{}" y="20" text-anchor="middle" font-size="14">{}</text>
<line x1="{m}" y1="{}" x2="{}" y2="{}" stroke="black"/><line x1="{m}" y1="{m}" x2="{m}" y2="{}" stroke="black"/>
<text x="{}" y="{}" text-anchor="middle">{}</text>
<text x="15" y="{}" transform="rotate(-90 15 {})" text-anchor="middle">{}</text>
<text x="{m}" y="{}" text-anchor="middle">{}</text><text x="{}" y="{}" text-anchor="middle">{}</text>
<text x="{}" y="{}" text-anchor="end">{}</text><text x="{}" y="{m}" text-anchor="end">{}</text>
"#,
        w / 2.0,
        escape(title),
        h - m,
        w - m,
        h - m,
        h - m,
        w / 2.0,
        h - 15.0,
        escape(xlabel),
        h / 2.0,
        h / 2.0,
        escape(ylabel),
        h - m + 15.0,
        tick(x0),
        w - m,
        h - m + 15.0,
        tick(x1),
        m - 5.0,
        h - m,
        tick(y0),
        m - 5.0,
        tick(y1),
    );
    for (k, (name, p)) in series.iter().enumerate() {
        let c = colours[k % colours.len()];
        if lines {
            let line: Vec<String> = p
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
                .collect();
            let _ = writeln!(
                s,
                r#"<polyline fill="none" stroke="{c}" stroke-width="2" points="{}"/>"#,
                line.join(" ")
            );
        }
        for &(x, y) in p.iter().filter(|_| dots) {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{c}"/>"#,
                sx(x),
                sy(y)
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" fill="{c}">{}</text>"#,
            w - m + 5.0 - 120.0,
            m + 15.0 * k as f64,
            escape(name)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// An axis end's label: four significant digits, in exponent form outside 1e-3 to 1e5
/// (so that a millimetre's fraction does not print as 0.000).
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::tick;

    /// Four significant digits whatever the scale, never a bare 0.000 for a non-zero end.
    #[test]
    fn ticks_keep_four_significant_digits() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(1.465), "1.465");
        assert_eq!(tick(-5933.08), "-5933");
        assert_eq!(tick(0.0021), "0.002100");
        assert_eq!(tick(-0.000123), "-1.230e-4");
        assert_eq!(tick(2.5e7), "2.500e7");
    }
}
