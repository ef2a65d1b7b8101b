//! twinloop-report: HTML reports people would rather look at than read.
//!
//! A [`Report`] is a single self-contained HTML file: headings, paragraphs, tables
//! and [`Plot`]s drawn as inline SVG. No JavaScript and nothing fetched from the
//! network, so a report opens anywhere and can be attached to an issue or mail.

mod plot;

pub use plot::{Plot, Series, SeriesStyle};

use std::fmt::Write as _;
use std::path::Path;

/// A number for people: 6 significant digits, no float noise
/// (3.1474699999999998 -> 3.14747), exponent form outside 1e-4..1e7.
pub fn number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    if (1e-4..1e7).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

/// Escape text for HTML.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            _ => o.push(c),
        }
    }
    o
}

enum Block {
    Heading(u8, String),
    Paragraph(String),
    Table {
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Plot(String),
    Pre(String),
    /// A paragraph that is a link: (text, href).
    Link(String, String),
}

/// An HTML report under construction.
pub struct Report {
    title: String,
    blocks: Vec<Block>,
}

impl Report {
    pub fn new(title: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// A section heading (level 2).
    pub fn heading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading(2, text.into()));
        self
    }

    /// A sub-section heading (level 3).
    pub fn subheading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading(3, text.into()));
        self
    }

    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// A paragraph that is a link to `href` (e.g. a file written beside the report).
    pub fn link(&mut self, text: impl Into<String>, href: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Link(text.into(), href.into()));
        self
    }

    /// Preformatted text (e.g. the command that made the report).
    pub fn preformatted(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Pre(text.into()));
        self
    }

    pub fn table(&mut self, header: Vec<String>, rows: Vec<Vec<String>>) -> &mut Self {
        self.blocks.push(Block::Table { header, rows });
        self
    }

    pub fn plot(&mut self, plot: &Plot) -> &mut Self {
        self.blocks.push(Block::Plot(plot.to_svg()));
        self
    }

    pub fn to_html(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\n\
             body{{font-family:system-ui,sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;color:#222}}\n\
             table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\n\
             th{{background:#f3f3f3}}td:first-child,th:first-child{{text-align:left}}\n\
             pre{{background:#f6f6f6;padding:0.6em;overflow-x:auto}}svg{{display:block;margin:1em 0}}\n\
             </style></head><body>\n<h1>{}</h1>\n",
            escape(&self.title),
            escape(&self.title)
        );
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(h, "<h{l}>{}</h{l}>", escape(t));
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(h, "<p>{}</p>", escape(t));
                }
                Block::Pre(t) => {
                    let _ = writeln!(h, "<pre>{}</pre>", escape(t));
                }
                Block::Link(t, href) => {
                    let _ = writeln!(h, "<p><a href=\"{}\">{}</a></p>", escape(href), escape(t));
                }
                Block::Table { header, rows } => {
                    h.push_str("<table><tr>");
                    for c in header {
                        let _ = write!(h, "<th>{}</th>", escape(c));
                    }
                    h.push_str("</tr>\n");
                    for r in rows {
                        h.push_str("<tr>");
                        for c in r {
                            let _ = write!(h, "<td>{}</td>", escape(c));
                        }
                        h.push_str("</tr>\n");
                    }
                    h.push_str("</table>\n");
                }
                Block::Plot(svg) => {
                    h.push_str(svg);
                    h.push('\n');
                }
            }
        }
        h.push_str("</body></html>\n");
        h
    }

    /// Writes the page to `path` (beside it first, renamed when complete:
    /// docs/architecture.md, "Outputs"); the error names the file.
    pub fn write(&self, path: &Path) -> Result<(), twinloop_io::IoError> {
        twinloop_io::output::write_atomic(path, self.to_html())
    }
}
