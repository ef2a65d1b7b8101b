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
        }
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
        for (i, se) in self.series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            self.write_series(&mut s, &f, se, color);
            write_legend_entry(&mut s, &f, i, &se.name, color);
        }
        s.push_str("</svg>");
        s
    }

    /// Margins (room for the legend on the right) and the padded data ranges.
    fn frame(&self) -> Frame {
        let (w, h) = (self.width, self.height);
        let (ml, mr, mt, mb) = (70.0, 160.0, 30.0, 45.0);
        let (pw, ph) = (w - ml - mr, h - mt - mb);
        let (x0, x1, y0, y1) = self.ranges();
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
             <text transform=\"translate(16,{}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            ml + pw / 2.0,
            escape(&self.title),
            ml + pw / 2.0,
            h - 8.0,
            escape(&self.x_label),
            mt + ph / 2.0,
            escape(&self.y_label)
        );
    }

    /// Ticks: 5 on each axis, in data units (powers of ten on a log axis).
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
        for k in 0..=4 {
            let f = k as f64 / 4.0;
            let (xv, yv) = (x0 + f * (x1 - x0), y0 + f * (y1 - y0));
            let (sx, sy) = (ml + f * pw, mt + ph - f * ph);
            let xl = if self.log_x { 10f64.powf(xv) } else { xv };
            let yl = if self.log_y { 10f64.powf(yv) } else { yv };
            let _ = write!(
                s,
                "<line x1=\"{sx}\" y1=\"{}\" x2=\"{sx}\" y2=\"{}\" stroke=\"#888\"/><text x=\"{sx}\" y=\"{}\" text-anchor=\"middle\">{}</text>\
                 <line x1=\"{ml}\" y1=\"{sy}\" x2=\"{}\" y2=\"{sy}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                mt + ph,
                mt + ph + 4.0,
                mt + ph + 16.0,
                tick(xl),
                ml + pw,
                ml - 4.0,
                sy + 4.0,
                tick(yl)
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

fn tick(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.2e}")
    } else {
        let t = format!("{v:.4}");
        let t = t.trim_end_matches('0').trim_end_matches('.');
        if t == "-0" {
            "0".to_string()
        } else {
            t.to_string()
        }
    }
}
