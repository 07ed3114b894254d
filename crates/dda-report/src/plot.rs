//! SVG line and point plots, for run reports and sweeps.

use super::escape;
use std::fmt::Write as _;

/// An SVG plot of named series of (x, y) points on linear axes: joined by lines if
/// `lines`, with a dot at each point if `dots` (and at a series' only point). The axes span "nice" ranges (the data's,
/// the y axis from 0 or below, widened to whole steps of 1, 2 or 5 times a power of ten)
/// with a labelled tick and a grid line at every step; labels keep inside the picture.
pub fn plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
    lines: bool,
    dots: bool,
) -> String {
    // Picture size, and the margins: left (tick labels and the y label), right, top
    // (title), bottom (tick labels and the x label).
    let (w, h) = (640.0, 400.0);
    let (ml, mr, mt, mb) = (78.0, 20.0, 32.0, 50.0);
    let pts = series
        .iter()
        .flat_map(|(_, p)| p.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, f64::NEG_INFINITY);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        (x0, x1) = (0.0, 1.0);
    }
    let (xt, yt) = (Ticks::new(x0, x1), Ticks::new(y0, y1.max(y0)));
    let (x0, x1, y0, y1) = (xt.lo, xt.hi, yt.lo, yt.hi);
    let sx = |x: f64| ml + (x - x0) / (x1 - x0) * (w - ml - mr);
    let sy = |y: f64| h - mb - (y - y0) / (y1 - y0) * (h - mt - mb);
    let colours = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f",
        "#bcbd22", "#17becf",
    ];
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">
<rect width="{w}" height="{h}" fill="white"/>
<text x="{}" y="20" text-anchor="middle" font-size="14">{}</text>
<text x="{}" y="{}" text-anchor="middle">{}</text>
<text x="14" y="{}" transform="rotate(-90 14 {})" text-anchor="middle">{}</text>
"#,
        w / 2.0,
        escape(title),
        ml + (w - ml - mr) / 2.0,
        h - 12.0,
        escape(xlabel),
        mt + (h - mt - mb) / 2.0,
        mt + (h - mt - mb) / 2.0,
        escape(ylabel),
    );
    for v in xt.values() {
        let x = sx(v);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{}" stroke="#e0e0e0"/><text class="tick" x="{x:.1}" y="{}" text-anchor="middle">{}</text>"##,
            h - mb,
            h - mb + 16.0,
            xt.label(v)
        );
    }
    for v in yt.values() {
        let y = sy(v);
        let _ = writeln!(
            s,
            r##"<line x1="{ml}" y1="{y:.1}" x2="{}" y2="{y:.1}" stroke="#e0e0e0"/><text class="tick" x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            w - mr,
            ml - 5.0,
            y + 4.0,
            yt.label(v)
        );
    }
    let _ = writeln!(
        s,
        r#"<line x1="{ml}" y1="{}" x2="{}" y2="{}" stroke="black"/><line x1="{ml}" y1="{mt}" x2="{ml}" y2="{}" stroke="black"/>"#,
        h - mb,
        w - mr,
        h - mb,
        h - mb
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
        // A series of one point has no line to draw: its dot stands for it.
        for &(x, y) in p.iter().filter(|_| dots || p.len() == 1) {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{c}"/>"#,
                sx(x),
                sy(y)
            );
        }
        if !name.is_empty() {
            let _ = writeln!(
                s,
                r#"<text x="{}" y="{}" fill="{c}" text-anchor="end">{}</text>"#,
                w - mr - 5.0,
                mt + 14.0 + 15.0 * k as f64,
                escape(name)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

/// An axis's ticks: from `lo` to `hi` by `step`, all whole multiples of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ticks {
    /// The axis's start: the data's smallest value rounded down to a step.
    pub lo: f64,
    /// The axis's end: the data's largest rounded up to a step.
    pub hi: f64,
    /// 1, 2 or 5 times a power of ten: four to ten steps over the range.
    pub step: f64,
}

impl Ticks {
    /// The ticks of a range from `lo` to `hi`. A flat range at v spans 0 to 2 v, with v
    /// in its middle (a run of one step: its one time, 1 ms, on an axis from 0 to 2 ms);
    /// a flat range at 0, an empty one, and one narrower than 1e-300, whose steps would
    /// be subnormal numbers or zero, get a unit span.
    pub fn new(lo: f64, hi: f64) -> Self {
        let (lo, hi) = if hi > lo && (hi - lo).is_finite() && hi - lo >= 1e-300 {
            (lo, hi)
        } else if hi == lo && lo.is_finite() && 2.0 * lo.abs() >= 1e-300 {
            (lo - lo.abs(), lo + lo.abs())
        } else if lo.is_finite() {
            (lo, lo + 1.0)
        } else {
            (0.0, 1.0)
        };
        let raw = (hi - lo) / 5.0;
        let mag = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|f| f * mag)
            .find(|&s| s >= raw)
            .unwrap_or(10.0 * mag);
        Ticks {
            lo: (lo / step).floor() * step,
            hi: (hi / step).ceil() * step,
            step,
        }
    }

    /// The tick values, from `lo` to `hi`.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        let n = ((self.hi - self.lo) / self.step).round() as i64;
        (0..=n).map(move |k| {
            let v = self.lo + k as f64 * self.step;
            // Whole multiples of the step, without the rounding of the sum.
            (v / self.step).round() * self.step
        })
    }

    /// The label of tick `v`: as many decimals as the step needs, or exponent form
    /// outside 1e-3 to 1e5, with the digits that tell one tick from the next (a survey
    /// grid's 4000010 and 4000020, 10 m apart, print in full).
    pub fn label(&self, v: f64) -> String {
        let a = self.step.abs().max(v.abs());
        if v == 0.0 {
            return "0".into();
        }
        let decimals = (-self.step.log10().floor()).max(0.0) as usize;
        if (1e-4..1e5).contains(&self.step) && a >= 1e5 {
            return format!("{v:.decimals$}");
        }
        if !(1e-3..1e5).contains(&a) || self.step < 1e-4 {
            let digits = (v.abs().log10().floor() - self.step.log10().floor()).clamp(1.0, 15.0);
            return format!("{v:.*e}", digits as usize);
        }
        format!("{v:.decimals$}")
    }
}

#[cfg(test)]
mod tests {
    use super::{Ticks, plot};

    /// Ticks are whole steps of 1, 2 or 5 times a power of ten, four to ten of them,
    /// covering the range, labelled with the decimals their step needs.
    #[test]
    fn ticks_are_nice_and_cover_the_range() {
        for (lo, hi) in [
            (0.0, 15930492.342),
            (0.0, 1.465),
            (-0.0021, 0.0007),
            (0.002, 0.1),
            (3.0, 3.0),
            (0.0, 1e-320),
            (0.0, 5e-324),
            (-2.0e-310, 1.0e-310),
        ] {
            let t = Ticks::new(lo, hi);
            let v: Vec<f64> = t.values().collect();
            assert!(t.lo <= lo && t.hi >= hi.max(lo), "{lo} {hi}: {t:?}");
            assert!((4..=11).contains(&v.len()), "{lo} {hi}: {v:?}");
            let m = t.step / 10f64.powf(t.step.log10().floor());
            assert!(
                [1.0, 2.0, 5.0].iter().any(|f| (m - f).abs() < 1e-9),
                "{t:?}"
            );
        }
        let t = Ticks::new(0.0, 1.465);
        assert_eq!((t.step, t.hi), (0.5, 1.5));
        assert_eq!(t.label(1.5), "1.5");
        let t = Ticks::new(0.0, 0.7);
        assert_eq!(t.step, 0.2);
        assert_eq!(t.label(0.6000000000000001), "0.6");
        let big = Ticks::new(0.0, 15930492.342);
        assert_eq!(big.label(4e6), "4.0e6");
        // Coordinates of a survey grid: ticks 10 m apart at 4e6 m, and 1e5 m apart at
        // 4e8 m, each told from the next.
        let grid = Ticks::new(4_000_003.0, 4_000_047.0);
        assert_eq!(grid.step, 10.0);
        assert_eq!(grid.label(4_000_010.0), "4000010");
        let far = Ticks::new(4.0e8, 4.0e8 + 5.0e5);
        assert_eq!(far.step, 1.0e5);
        assert_eq!(far.label(4.001e8), "4.001e8");
    }

    /// A run of one step has one point a history: the plot shows it as a dot, on a time
    /// axis from 0 to twice its time (not a line of one point, which draws nothing, on
    /// an axis from its time to a second later).
    #[test]
    fn a_series_of_one_point_is_a_dot_in_the_middle_of_its_axis() {
        let svg = plot(
            "t",
            "x",
            "y",
            &[("".into(), vec![(1e-3, 5.0)])],
            true,
            false,
        );
        let dots: Vec<&str> = svg.lines().filter(|l| l.starts_with("<circle")).collect();
        assert_eq!(dots.len(), 1, "{svg}");
        // The plot area spans x = 78 to 620 px: its middle is 349.
        assert!(dots[0].contains(r#"cx="349.0""#), "{}", dots[0]);
        let t = Ticks::new(1e-3, 1e-3);
        assert_eq!((t.lo, t.hi), (0.0, 2e-3));
        let t = Ticks::new(-4.0, -4.0);
        assert_eq!((t.lo, t.hi), (-8.0, 0.0));
        // Two points make a line without dots.
        let two = plot(
            "t",
            "x",
            "y",
            &[("".into(), vec![(0.0, 1.0), (1.0, 2.0)])],
            true,
            false,
        );
        assert!(!two.contains("<circle"));
    }

    /// Every tick label of a plot is a whole number of the picture's text and lies within
    /// it (an anchor at least the label's estimated half width, 7 px a character, from
    /// the edges).
    #[test]
    fn tick_labels_stay_inside_the_picture() {
        let svg = plot(
            "t",
            "x",
            "y",
            &[("a".into(), vec![(0.0, 0.0), (0.1, 15930492.342)])],
            true,
            false,
        );
        for line in svg.lines().filter(|l| l.contains("class=\"tick\"")) {
            let text = line.rsplit('>').nth(1).unwrap().trim_end_matches("</text");
            let x: f64 = line
                .split("<text class=\"tick\" x=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            let width = 7.0 * text.len() as f64;
            if line.contains("text-anchor=\"end\"") {
                assert!(x - width >= 0.0, "{text} at {x}");
            } else {
                assert!(
                    x - width / 2.0 >= 0.0 && x + width / 2.0 <= 640.0,
                    "{text} at {x}"
                );
            }
        }
    }
}
