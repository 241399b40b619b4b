//! A minimal SVG writer with fixed number formatting (two decimals, trailing zeros trimmed), so
//! the same drawing gives the same bytes.

use std::fmt::Write as _;

use super::plot::{Color, Dash};

/// Formats a coordinate: two decimals, trailing zeros and a lone minus on zero removed.
pub(crate) fn num(v: f64) -> String {
    let v = if v.is_finite() {
        v.clamp(-1e6, 1e6)
    } else {
        0.0
    };
    let mut s = format!("{v:.2}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".to_owned();
    }
    s
}

/// Escapes text for an XML text node or attribute value.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' => o.push(' '),
            c => o.push(c),
        }
    }
    o
}

fn dash_attr(dash: Dash, width: f64) -> String {
    let w = width.max(1.0);
    match dash {
        Dash::Solid => String::new(),
        Dash::Dashed => format!(" stroke-dasharray=\"{} {}\"", num(4.0 * w), num(3.0 * w)),
        Dash::Dotted => format!(" stroke-dasharray=\"{} {}\"", num(w), num(2.0 * w)),
    }
}

/// Horizontal anchor of a text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

/// SVG document under construction.
pub(crate) struct Svg {
    buf: String,
    clips: usize,
}

impl Svg {
    /// A `w` × `h` px document with a white background and DejaVu Sans as its font.
    pub(crate) fn new(w: u32, h: u32, font_family: &str) -> Self {
        let mut buf = String::new();
        let _ = write!(
            buf,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" \
             width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"{}, sans-serif\">\n\
             <rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" fill=\"#ffffff\"/>\n",
            esc(font_family)
        );
        Self { buf, clips: 0 }
    }

    /// Starts a group clipped to the rectangle; close it with [`Self::end_group`].
    pub(crate) fn begin_clip(&mut self, x: f64, y: f64, w: f64, h: f64) {
        self.clips += 1;
        let id = self.clips;
        let _ = writeln!(
            self.buf,
            "<clipPath id=\"c{id}\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/></clipPath>\n<g clip-path=\"url(#c{id})\">",
            num(x),
            num(y),
            num(w),
            num(h)
        );
    }

    /// Closes a group.
    pub(crate) fn end_group(&mut self) {
        self.buf.push_str("</g>\n");
    }

    /// A rectangle; `crisp` turns anti-aliasing off (for tiled cells).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn rect(
        &mut self,
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        fill: Option<(Color, f64)>,
        stroke: Option<(Color, f64)>,
        crisp: bool,
    ) {
        let _ = write!(
            self.buf,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"",
            num(x),
            num(y),
            num(w.max(0.0)),
            num(h.max(0.0))
        );
        self.paint(fill, stroke, Dash::Solid);
        if crisp {
            self.buf.push_str(" shape-rendering=\"crispEdges\"");
        }
        self.buf.push_str("/>\n");
    }

    fn paint(&mut self, fill: Option<(Color, f64)>, stroke: Option<(Color, f64)>, dash: Dash) {
        match fill {
            Some((c, op)) => {
                let _ = write!(self.buf, " fill=\"{}\"", c.hex());
                if op < 1.0 {
                    let _ = write!(self.buf, " fill-opacity=\"{}\"", num(op));
                }
            }
            None => self.buf.push_str(" fill=\"none\""),
        }
        if let Some((c, w)) = stroke {
            let _ = write!(
                self.buf,
                " stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\" stroke-linecap=\"round\"{}",
                c.hex(),
                num(w),
                dash_attr(dash, w)
            );
        }
    }

    /// A straight segment.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn line(
        &mut self,
        x1: f64,
        y1: f64,
        x2: f64,
        y2: f64,
        color: Color,
        width: f64,
        dash: Dash,
    ) {
        let _ = writeln!(
            self.buf,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-width=\"{}\"{}/>",
            num(x1),
            num(y1),
            num(x2),
            num(y2),
            color.hex(),
            num(width),
            dash_attr(dash, width)
        );
    }

    fn points(&mut self, pts: &[(f64, f64)]) {
        self.buf.push_str(" points=\"");
        for (i, (x, y)) in pts.iter().enumerate() {
            if i > 0 {
                self.buf.push(' ');
            }
            let _ = write!(self.buf, "{},{}", num(*x), num(*y));
        }
        self.buf.push('"');
    }

    /// An open polyline (stroke only).
    pub(crate) fn polyline(&mut self, pts: &[(f64, f64)], color: Color, width: f64, dash: Dash) {
        if pts.len() < 2 {
            return;
        }
        self.buf.push_str("<polyline");
        self.points(pts);
        self.paint(None, Some((color, width)), dash);
        self.buf.push_str("/>\n");
    }

    /// A closed polygon.
    pub(crate) fn polygon(
        &mut self,
        pts: &[(f64, f64)],
        fill: Option<(Color, f64)>,
        stroke: Option<(Color, f64)>,
        dash: Dash,
    ) {
        if pts.len() < 2 {
            return;
        }
        self.buf.push_str("<polygon");
        self.points(pts);
        self.paint(fill, stroke, dash);
        self.buf.push_str("/>\n");
    }

    /// A filled circle with an optional outline.
    pub(crate) fn circle(
        &mut self,
        cx: f64,
        cy: f64,
        r: f64,
        fill: Color,
        stroke: Option<(Color, f64)>,
    ) {
        let _ = write!(
            self.buf,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\"",
            num(cx),
            num(cy),
            num(r)
        );
        self.paint(Some((fill, 1.0)), stroke, Dash::Solid);
        self.buf.push_str("/>\n");
    }

    /// A text with its baseline at `y`; `rotate_deg` turns it about (x, y).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn text(
        &mut self,
        x: f64,
        y: f64,
        s: &str,
        size_px: f64,
        anchor: Anchor,
        color: Color,
        rotate_deg: f64,
    ) {
        if s.is_empty() {
            return;
        }
        let a = match anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let pos = if rotate_deg == 0.0 {
            format!("x=\"{}\" y=\"{}\"", num(x), num(y))
        } else {
            format!(
                "transform=\"translate({},{}) rotate({})\"",
                num(x),
                num(y),
                num(rotate_deg)
            )
        };
        let _ = writeln!(
            self.buf,
            "<text {pos} font-size=\"{}\" text-anchor=\"{a}\" fill=\"{}\">{}</text>",
            num(size_px),
            color.hex(),
            esc(s)
        );
    }

    /// The finished document.
    pub(crate) fn finish(mut self) -> String {
        self.buf.push_str("</svg>\n");
        self.buf
    }
}
