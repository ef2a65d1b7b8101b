//! Line and point plots as SVG.

use crate::escape;
use std::fmt::Write as _;

const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    Line,
    DashedLine,
    Points,
    /// Vertical bars from the x axis (or the bottom of a log axis).
    Bars,
}

#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub style: SeriesStyle,
}

/// A 2-D plot: series over shared axes, optional log-scale y, optional horizontal
/// reference lines (confidence bands, thresholds).
#[derive(Debug, Clone)]
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub log_y: bool,
    pub log_x: bool,
    pub hlines: Vec<(f64, String)>,
    pub width: f64,
    pub height: f64,
    /// A metre as long across as up (a view of a robot, not a graph).
    pub equal_aspect: bool,
}

impl Plot {
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Plot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            log_y: false,
            log_x: false,
            hlines: Vec::new(),
            width: 900.0,
            height: 320.0,
            equal_aspect: false,
        }
    }

    /// Draw to scale: one unit as many pixels on x as on y, the narrower range widened
    /// about its middle (linear axes only). For views of a robot, whose shape the
    /// default stretch would distort.
    pub fn equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }

    /// The plot's height in pixels.
    pub fn height(mut self, height: f64) -> Self {
        self.height = height;
        self
    }

    pub fn series(
        mut self,
        name: impl Into<String>,
        x: &[f64],
        y: &[f64],
        style: SeriesStyle,
    ) -> Self {
        self.series.push(Series {
            name: name.into(),
            x: x.to_vec(),
            y: y.to_vec(),
            style,
        });
        self
    }

    pub fn line(self, name: impl Into<String>, x: &[f64], y: &[f64]) -> Self {
        self.series(name, x, y, SeriesStyle::Line)
    }

    pub fn hline(mut self, y: f64, label: impl Into<String>) -> Self {
        self.hlines.push((y, label.into()));
        self
    }

    pub fn log_y(mut self) -> Self {
        self.log_y = true;
        self
    }

    pub fn log_x(mut self) -> Self {
        self.log_x = true;
        self
    }

    fn tx(&self, v: f64) -> f64 {
        if self.log_x { v.max(1e-300).log10() } else { v }
    }

    fn ty(&self, v: f64) -> f64 {
        if self.log_y { v.max(1e-300).log10() } else { v }
    }

    /// Data range after the axis transforms, padded; finite values only.
    fn ranges(&self) -> (f64, f64, f64, f64) {
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for s in &self.series {
            for (&x, &y) in s.x.iter().zip(&s.y) {
                if (self.log_x && x <= 0.0) || (self.log_y && y <= 0.0) {
                    continue;
                }
                let (a, b) = (self.tx(x), self.ty(y));
                if a.is_finite() && b.is_finite() {
                    x0 = x0.min(a);
                    x1 = x1.max(a);
                    y0 = y0.min(b);
                    y1 = y1.max(b);
                }
            }
        }
        for (y, _) in &self.hlines {
            let b = self.ty(*y);
            if b.is_finite() {
                y0 = y0.min(b);
                y1 = y1.max(b);
            }
        }
        if self.series.iter().any(|s| s.style == SeriesStyle::Bars) && !self.log_y {
            y0 = y0.min(0.0);
        }
        if !x0.is_finite() {
            (x0, x1) = (0.0, 1.0);
        }
        if !y0.is_finite() {
            (y0, y1) = (0.0, 1.0);
        }
        if x1 - x0 < 1e-300 {
            x1 = x0 + 1.0;
        }
        if y1 - y0 < 1e-300 {
            (y0, y1) = (y0 - 0.5, y1 + 0.5);
        }
        let pad = 0.05 * (y1 - y0);
        (x0, x1, y0 - pad, y1 + pad)
    }

    pub fn to_svg(&self) -> String {
        let f = self.frame();
        let mut s = String::new();
        self.write_axes(&mut s, &f);
        self.write_ticks(&mut s, &f);
        self.write_hlines(&mut s, &f);
        // Measured data are drawn last, above the model curves: a fit that matches
        // them well must not hide them. Legend order and colours stay as given.
        let measured = |se: &Series| se.name.to_ascii_lowercase().starts_with("measured");
        let order = (0..self.series.len())
            .filter(|&i| !measured(&self.series[i]))
            .chain((0..self.series.len()).filter(|&i| measured(&self.series[i])));
        for i in order {
            let color = PALETTE[i % PALETTE.len()];
            self.write_series(&mut s, &f, &self.series[i], color);
        }
        for (i, se) in self.series.iter().enumerate() {
            write_legend_entry(&mut s, &f, i, &se.name, PALETTE[i % PALETTE.len()]);
        }
        s.push_str("</svg>");
        s
    }

    /// Margins (room for the legend on the right) and the padded data ranges.
    fn frame(&self) -> Frame {
        let (w, h) = (self.width, self.height);
        let (x0, x1, y0, y1) = self.ranges();
        // Room for the widest y tick label and, left of it, the rotated axis title.
        let widest = widest_label(y0, y1, self.log_y);
        let (ml, mr, mt, mb) = ((widest + 34.0).max(60.0), 160.0, 30.0, 45.0);
        let (pw, ph) = (w - ml - mr, h - mt - mb);
        let (mut x0, mut x1, mut y0, mut y1) = (x0, x1, y0, y1);
        if self.equal_aspect && !self.log_x && !self.log_y {
            // Units per pixel: the larger of the two for both axes.
            let per = ((x1 - x0) / pw).max((y1 - y0) / ph);
            let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
            (x0, x1) = (cx - 0.5 * per * pw, cx + 0.5 * per * pw);
            (y0, y1) = (cy - 0.5 * per * ph, cy + 0.5 * per * ph);
        }
        Frame {
            w,
            h,
            ml,
            mt,
            pw,
            ph,
            x0,
            x1,
            y0,
            y1,
        }
    }

    /// Screen x of data value `x`.
    fn px(&self, f: &Frame, x: f64) -> f64 {
        f.ml + (self.tx(x) - f.x0) / (f.x1 - f.x0) * f.pw
    }

    /// Screen y of data value `y`.
    fn py(&self, f: &Frame, y: f64) -> f64 {
        f.mt + f.ph - (self.ty(y) - f.y0) / (f.y1 - f.y0) * f.ph
    }

    /// The `<svg>` opening, plot frame, title and axis labels.
    fn write_axes(&self, s: &mut String, f: &Frame) {
        let Frame {
            w,
            h,
            ml,
            mt,
            pw,
            ph,
            ..
        } = *f;
        let _ = write!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-size=\"12\" font-family=\"sans-serif\">\
             <rect x=\"{ml}\" y=\"{mt}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#888\"/>\
             <text x=\"{}\" y=\"18\" text-anchor=\"middle\" font-weight=\"bold\">{}</text>\
             <text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\
             <text transform=\"translate({},{}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            ml + pw / 2.0,
            escape(&self.title),
            ml + pw / 2.0,
            h - 8.0,
            escape(&self.x_label),
            ml - 22.0 - widest_label(f.y0, f.y1, self.log_y),
            mt + ph / 2.0,
            escape(&self.y_label)
        );
    }

    /// Ticks at round values (1, 2 or 5 times a power of ten; powers of ten on a log
    /// axis), about five per axis, labelled with no more digits than the step needs.
    fn write_ticks(&self, s: &mut String, f: &Frame) {
        let Frame {
            ml,
            mt,
            pw,
            ph,
            x0,
            x1,
            y0,
            y1,
            ..
        } = *f;
        for (xv, label) in axis_ticks(x0, x1, self.log_x) {
            let sx = ml + (xv - x0) / (x1 - x0) * pw;
            let _ = write!(
                s,
                "<line x1=\"{sx}\" y1=\"{}\" x2=\"{sx}\" y2=\"{}\" stroke=\"#888\"/><text x=\"{sx}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
                mt + ph,
                mt + ph + 4.0,
                mt + ph + 16.0,
                escape(&label)
            );
        }
        for (yv, label) in axis_ticks(y0, y1, self.log_y) {
            let sy = mt + ph - (yv - y0) / (y1 - y0) * ph;
            let _ = write!(
                s,
                "<line x1=\"{ml}\" y1=\"{sy}\" x2=\"{}\" y2=\"{sy}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                ml + pw,
                ml - 4.0,
                sy + 4.0,
                escape(&label)
            );
        }
    }

    /// Dashed horizontal reference lines, labelled on the right.
    fn write_hlines(&self, s: &mut String, f: &Frame) {
        let Frame { ml, pw, .. } = *f;
        for (y, label) in &self.hlines {
            let sy = self.py(f, *y);
            if sy.is_finite() {
                let _ = write!(
                    s,
                    "<line x1=\"{ml}\" y1=\"{sy}\" x2=\"{}\" y2=\"{sy}\" stroke=\"#999\" stroke-dasharray=\"4 3\"/>\
                     <text x=\"{}\" y=\"{}\" fill=\"#666\">{}</text>",
                    ml + pw,
                    ml + pw + 4.0,
                    sy + 4.0,
                    escape(label)
                );
            }
        }
    }

    /// One series in its style; points that the axes cannot show are dropped.
    fn write_series(&self, s: &mut String, f: &Frame, se: &Series, color: &str) {
        let Frame { mt, pw, ph, .. } = *f;
        let pts: Vec<(f64, f64)> =
            se.x.iter()
                .zip(&se.y)
                .filter(|(x, y)| {
                    x.is_finite()
                        && y.is_finite()
                        && !(self.log_y && **y <= 0.0)
                        && !(self.log_x && **x <= 0.0)
                })
                .map(|(&x, &y)| (self.px(f, x), self.py(f, y)))
                .collect();
        match se.style {
            SeriesStyle::Line | SeriesStyle::DashedLine => {
                // Thin long series so the file stays small: at most ~4 points per pixel.
                let step = (pts.len() as f64 / (4.0 * pw)).ceil().max(1.0) as usize;
                let mut d = String::new();
                for (k, (x, y)) in pts
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| k % step == 0 || *k + 1 == pts.len())
                {
                    let _ = write!(d, "{}{:.1},{:.1}", if k == 0 { "M" } else { "L" }, x, y);
                }
                let dash = if se.style == SeriesStyle::DashedLine {
                    " stroke-dasharray=\"6 3\""
                } else {
                    ""
                };
                let _ = write!(
                    s,
                    "<path d=\"{d}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"1.3\"{dash}/>"
                );
            }
            SeriesStyle::Points => {
                for (x, y) in &pts {
                    let _ = write!(
                        s,
                        "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{color}\"/>"
                    );
                }
            }
            SeriesStyle::Bars => {
                let base = if self.log_y {
                    mt + ph
                } else {
                    self.py(f, 0.0).clamp(mt, mt + ph)
                };
                let bw = (pw / (pts.len().max(1) as f64) * 0.6).clamp(1.0, 30.0);
                for (x, y) in &pts {
                    let (top, hgt) = if *y < base {
                        (*y, base - y)
                    } else {
                        (base, y - base)
                    };
                    let _ = write!(
                        s,
                        "<rect x=\"{:.1}\" y=\"{top:.1}\" width=\"{bw:.1}\" height=\"{hgt:.1}\" fill=\"{color}\"/>",
                        x - bw / 2.0
                    );
                }
            }
        }
    }
}

/// Plot geometry in pixels and the data ranges it maps (after the axis transforms).
#[derive(Debug, Clone, Copy)]
struct Frame {
    w: f64,
    h: f64,
    /// Left and top margins.
    ml: f64,
    mt: f64,
    /// Width and height of the plotting area.
    pw: f64,
    ph: f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

/// The `i`-th legend entry, right of the plotting area.
fn write_legend_entry(s: &mut String, f: &Frame, i: usize, name: &str, color: &str) {
    let Frame { ml, mt, pw, .. } = *f;
    let ly = mt + 14.0 + 16.0 * i as f64;
    let _ = write!(
        s,
        "<rect x=\"{}\" y=\"{}\" width=\"12\" height=\"3\" fill=\"{color}\"/><text x=\"{}\" y=\"{}\">{}</text>",
        ml + pw + 8.0,
        ly - 4.0,
        ml + pw + 24.0,
        ly,
        escape(name)
    );
}

/// Round tick positions in `lo..=hi` (axis units: log10 of the value on a log axis)
/// with their labels. A linear axis steps by 1, 2 or 5 times a power of ten, about
/// five ticks; a log axis ticks whole decades (every second or more when there are
/// many), and a range narrower than a decade falls back to round linear steps of
/// the exponent's value.
pub(crate) fn axis_ticks(lo: f64, hi: f64, log: bool) -> Vec<(f64, String)> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return Vec::new();
    }
    if log {
        let (first, last) = (lo.ceil() as i64, hi.floor() as i64);
        if last > first {
            let every = ((last - first) as f64 / 6.0).ceil().max(1.0) as i64;
            return (first..=last)
                .filter(|e| (e - first) % every == 0)
                .map(|e| (e as f64, tick(10f64.powi(e as i32), 0.0)))
                .collect();
        }
        // Less than a decade: round values between 10^lo and 10^hi.
        return linear_ticks(10f64.powf(lo), 10f64.powf(hi))
            .into_iter()
            .filter(|&(v, _)| v > 0.0)
            .map(|(v, l)| (v.log10(), l))
            .collect();
    }
    linear_ticks(lo, hi)
}

fn linear_ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let range = hi - lo;
    let mag = 10f64.powf((range / 5.0).log10().floor());
    // The round step giving the tick count nearest five.
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .min_by(|a, b| {
            let miss = |s: f64| (range / s - 5.0).abs();
            miss(*a).total_cmp(&miss(*b))
        })
        .unwrap_or(mag);
    // A hair of tolerance: an end that is a tick up to rounding keeps its tick.
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            (v, tick(v, step))
        })
        .collect()
}

/// Width in pixels of the widest tick label of an axis at the plot's 12 px
/// sans-serif, estimated at 7 px a character.
fn widest_label(lo: f64, hi: f64, log: bool) -> f64 {
    axis_ticks(lo, hi, log)
        .iter()
        .map(|(_, l)| 7.0 * l.chars().count() as f64)
        .fold(0.0, f64::max)
}

/// A tick label: as many decimals as `step` needs (all significant ones when 0),
/// exponent notation outside 1e-3 .. 1e5.
fn tick(v: f64, step: f64) -> String {
    let a = v.abs();
    if a < 1e-12 * step.max(1e-300) || v == 0.0 {
        return "0".to_string();
    }
    if !(1e-3..1e5).contains(&a) {
        let t = format!("{v:.1e}");
        return t.replace(".0e", "e");
    }
    let decimals = if step > 0.0 {
        (-(step.log10().floor()) as i64).clamp(0, 6) as usize
    } else {
        4
    };
    let t = format!("{v:.decimals$}");
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    };
    if t == "-0" { "0".to_string() } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside_the_range() {
        let t = axis_ticks(-0.0137, 0.2511, false);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0", "0.05", "0.1", "0.15", "0.2", "0.25"]);
        let t = axis_ticks(812.3, 1187.9, false);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["900", "1000", "1100"]);
        // Decades on a log axis: 10^-3 .. 10^2.
        let t = axis_ticks(-3.2, 2.5, true);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.001", "0.01", "0.1", "1", "10", "100"]);
        // Narrower than a decade: round values of the quantity itself.
        let t = axis_ticks(2f64.log10(), 8f64.log10(), true);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["2", "3", "4", "5", "6", "7", "8"]);
        assert!(axis_ticks(1.0, 1.0, false).is_empty());
    }

    #[test]
    fn measured_is_drawn_over_the_fit_and_labels_clear_the_title() {
        let t = [0.0, 1.0, 2.0];
        let svg = Plot::new("fit", "t (s)", "CoM x (m)")
            .line("measured", &t, &[1e-4, 2e-4, -3e-4])
            .line("after", &t, &[1e-4, 2e-4, -3e-4])
            .to_svg();
        let measured = svg.find("stroke=\"#1f77b4\" stroke-width");
        let after = svg.find("stroke=\"#d62728\" stroke-width");
        assert!(measured.unwrap() > after.unwrap(), "measured drawn last");
        // The y title sits left of the widest tick label ("-3e-4" or "-2.5e-4").
        let title_x: f64 = svg
            .split("<text transform=\"translate(")
            .nth(1)
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let label_left = svg
            .split("text-anchor=\"end\">")
            .skip(1)
            .map(|l| l.split('<').next().unwrap().chars().count() as f64 * 7.0)
            .fold(0.0, f64::max);
        let ml: f64 = svg
            .split("<rect x=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            title_x + 6.0 < ml - 4.0 - label_left,
            "{title_x} vs {ml} - {label_left}"
        );
    }
}
