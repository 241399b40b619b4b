//! Plots: [`Plot`] is one set of axes, [`Figure`] a titled grid of plots written as SVG and PNG.
//!
//! A [`Plot`] holds any mix of
//! - named lines y(x) (time series, or XY paths in a plane) — [`Plot::line`], [`Plot::line_styled`];
//! - markers — [`Plot::scatter`];
//! - horizontal reference lines (limits) — [`Plot::hline`]; vertical event markers — [`Plot::vline`];
//! - polygons: unfilled outlines (obstacles, keep-out zones) and filled shapes —
//!   [`Plot::outline`], [`Plot::polygon`], [`Plot::polygon_styled`];
//! - a categorical outcome map over two parameters (capture envelopes) — [`Plot::outcomes`],
//!   drawn as tiles when the points form a grid fine enough to tile, else as dots.
//!
//! with axis labels (put the unit in them: `"t [s]"`), a title, a legend (placed in the corner
//! covering the fewest data points unless told otherwise), optional log-y and equal aspect
//! (1 m on x is as long as 1 m on y — for trajectories in a plane).
//!
//! Choices: x is tight to the data for pure line plots (time series), other axes get 5 %
//! padding; ticks are 1-2-2.5-5 × 10ⁿ; non-finite points (and y ≤ 0 on a log axis) break a
//! line instead of failing; points closer than 0.5 px to the previous kept point are dropped
//! (invisible, keeps SVGs of 10⁵-sample runs small). Colours follow the Okabe–Ito palette
//! (distinguishable with colour-vision deficiency).

use std::io;
use std::path::Path;

use super::fsio::write_atomic;
use super::raster::{FONT_FAMILY, svg_to_png, text_width_px};
use super::svg::{Anchor, Svg};
use super::ticks::{Tick, linear_ticks, log_ticks};

/// An sRGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Color {
    /// Red, 0–255.
    pub r: u8,
    /// Green, 0–255.
    pub g: u8,
    /// Blue, 0–255.
    pub b: u8,
}

impl Color {
    /// A colour from its components.
    pub const fn rgb(r: u8, g: u8, b: u8) -> Self {
        Self { r, g, b }
    }
    /// Black.
    pub const BLACK: Color = Color::rgb(0, 0, 0);
    /// Dark grey used for text and frames.
    pub const DARK_GRAY: Color = Color::rgb(0x33, 0x33, 0x33);
    /// Mid grey (event markers, obstacle outlines).
    pub const GRAY: Color = Color::rgb(0x77, 0x77, 0x77);
    /// Light grey (grid).
    pub const LIGHT_GRAY: Color = Color::rgb(0xdd, 0xdd, 0xdd);
    /// White.
    pub const WHITE: Color = Color::rgb(0xff, 0xff, 0xff);
    /// Red used for limits.
    pub const RED: Color = Color::rgb(0xc0, 0x1c, 0x28);

    /// `#rrggbb`.
    pub fn hex(&self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.r, self.g, self.b)
    }
}

/// Series colours in order (Okabe–Ito): blue, vermillion, bluish green, reddish purple,
/// orange, sky blue, black, yellow.
pub const PALETTE: [Color; 8] = [
    Color::rgb(0x00, 0x72, 0xb2),
    Color::rgb(0xd5, 0x5e, 0x00),
    Color::rgb(0x00, 0x9e, 0x73),
    Color::rgb(0xcc, 0x79, 0xa7),
    Color::rgb(0xe6, 0x9f, 0x00),
    Color::rgb(0x56, 0xb4, 0xe9),
    Color::rgb(0x00, 0x00, 0x00),
    Color::rgb(0xf0, 0xe4, 0x42),
];

/// Stroke pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Dash {
    /// Continuous.
    #[default]
    Solid,
    /// Dashes 4 × width long.
    Dashed,
    /// Dots one width long.
    Dotted,
}

/// Style of a line; `color: None` takes the next palette colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineStyle {
    /// Colour, or `None` for the next palette colour.
    pub color: Option<Color>,
    /// Stroke width in px.
    pub width_px: f64,
    /// Stroke pattern.
    pub dash: Dash,
}

impl Default for LineStyle {
    fn default() -> Self {
        Self {
            color: None,
            width_px: 2.0,
            dash: Dash::Solid,
        }
    }
}

impl LineStyle {
    /// The default style, dashed.
    pub fn dashed() -> Self {
        Self {
            dash: Dash::Dashed,
            ..Self::default()
        }
    }

    /// The default style, dotted.
    pub fn dotted() -> Self {
        Self {
            dash: Dash::Dotted,
            ..Self::default()
        }
    }
}

/// Style of a polygon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolygonStyle {
    /// Fill colour and opacity (0–1), or `None` for no fill.
    pub fill: Option<(Color, f64)>,
    /// Outline colour, or `None` for no outline.
    pub stroke: Option<Color>,
    /// Outline width in px.
    pub width_px: f64,
    /// Outline pattern.
    pub dash: Dash,
    /// `true`: the last point joins the first; `false`: an open polyline (fill ignored).
    pub closed: bool,
}

/// Where the legend goes (inside the axes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Legend {
    /// Outside (right of the axes) for plots with an outcome map, which fills the axes;
    /// otherwise the corner whose legend box covers the fewest drawn data points (ties: top
    /// right, top left, bottom right, bottom left).
    #[default]
    Best,
    /// Top right corner.
    TopRight,
    /// Top left corner.
    TopLeft,
    /// Bottom right corner.
    BottomRight,
    /// Bottom left corner.
    BottomLeft,
    /// To the right of the axes (the axes get narrower).
    Outside,
    /// No legend.
    Off,
}

#[derive(Clone, Debug)]
enum Item {
    Line {
        name: String,
        pts: Vec<(f64, f64)>,
        color: Color,
        width: f64,
        dash: Dash,
    },
    Scatter {
        name: String,
        pts: Vec<(f64, f64)>,
        color: Color,
    },
    Polygon {
        name: String,
        pts: Vec<(f64, f64)>,
        style: PolygonStyle,
    },
    HLine {
        y: f64,
        label: String,
        color: Color,
        dash: Dash,
        width: f64,
    },
    VLine {
        x: f64,
        label: String,
    },
    Outcomes {
        pts: Vec<(f64, f64, usize)>,
        cats: Vec<(String, Color)>,
        /// Legend counts per category (default: the points drawn here).
        totals: Option<Vec<usize>>,
    },
}

/// One set of axes. Build with chained calls; see the module docs.
#[derive(Clone, Debug, Default)]
pub struct Plot {
    title: String,
    x_label: String,
    y_label: String,
    log_y: bool,
    equal_aspect: bool,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
    legend: Legend,
    items: Vec<Item>,
    next_color: usize,
}

const TITLE_PX: f64 = 18.0;
const PANEL_TITLE_PX: f64 = 15.0;
const LABEL_PX: f64 = 14.0;
const TICK_PX: f64 = 12.0;
const LEGEND_PX: f64 = 12.0;
const MARKER_LABEL_PX: f64 = 11.0;
const PAD: f64 = 10.0;
const TICK_LEN: f64 = 5.0;
const LEGEND_ROW: f64 = LEGEND_PX + 6.0;
const LEGEND_SWATCH: f64 = 24.0;
/// Points of a line closer than this to the last kept point are dropped (px).
const THIN_PX: f64 = 0.5;

/// A data interval (lo, hi), or `None` when nothing was seen.
type Span = Option<(f64, f64)>;

fn finite(p: &(f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

impl Plot {
    /// An empty plot with a title (may be empty).
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            ..Self::default()
        }
    }

    /// Label of the x axis, with units (e.g. `"t [s]"`).
    pub fn x_label(mut self, label: impl Into<String>) -> Self {
        self.x_label = label.into();
        self
    }

    /// Label of the y axis, with units (e.g. `"x_LVLH [m]"`).
    pub fn y_label(mut self, label: impl Into<String>) -> Self {
        self.y_label = label.into();
        self
    }

    /// Logarithmic y axis (base 10); values ≤ 0 are not drawn. Equal aspect is ignored.
    pub fn log_y(mut self) -> Self {
        self.log_y = true;
        self
    }

    /// Equal scales on x and y (the shorter range is widened about its centre).
    pub fn equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }

    /// Fixed x range `[lo, hi]` in data units (ignored unless finite with lo < hi).
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi));
        self
    }

    /// Fixed y range `[lo, hi]` in data units (ignored unless finite with lo < hi, and lo > 0 on
    /// a log axis).
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi));
        self
    }

    /// Legend placement.
    pub fn legend(mut self, legend: Legend) -> Self {
        self.legend = legend;
        self
    }

    fn take_color(&mut self, c: Option<Color>) -> Color {
        c.unwrap_or_else(|| {
            let c = PALETTE[self.next_color % PALETTE.len()];
            self.next_color += 1;
            c
        })
    }

    /// A line through `points` (x, y) in data units, next palette colour, 2 px; an empty `name`
    /// leaves it out of the legend.
    pub fn line(
        self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        self.line_styled(name, points, LineStyle::default())
    }

    /// A line with an explicit style.
    pub fn line_styled(
        mut self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
        style: LineStyle,
    ) -> Self {
        let color = self.take_color(style.color);
        self.items.push(Item::Line {
            name: name.into(),
            pts: points.into_iter().collect(),
            color,
            width: style.width_px.max(0.1),
            dash: style.dash,
        });
        self
    }

    /// Dots (radius 3 px) at `points`, next palette colour.
    pub fn scatter(
        mut self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        let color = self.take_color(None);
        self.items.push(Item::Scatter {
            name: name.into(),
            pts: points.into_iter().collect(),
            color,
        });
        self
    }

    /// A horizontal reference line at `y` (a limit, a requirement): red, dashed, listed in the
    /// legend as `label`.
    pub fn hline(self, y: f64, label: impl Into<String>) -> Self {
        self.hline_styled(
            y,
            label,
            LineStyle {
                color: Some(Color::RED),
                width_px: 1.5,
                dash: Dash::Dashed,
            },
        )
    }

    /// A horizontal reference line with an explicit style (`color: None` = red).
    pub fn hline_styled(mut self, y: f64, label: impl Into<String>, style: LineStyle) -> Self {
        self.items.push(Item::HLine {
            y,
            label: label.into(),
            color: style.color.unwrap_or(Color::RED),
            dash: style.dash,
            width: style.width_px.max(0.1),
        });
        self
    }

    /// A vertical event marker at `x` (grey, dotted) labelled along the line at the top.
    pub fn vline(mut self, x: f64, label: impl Into<String>) -> Self {
        self.items.push(Item::VLine {
            x,
            label: label.into(),
        });
        self
    }

    /// A closed, unfilled outline (an obstacle, a keep-out boundary): grey, 1.5 px.
    pub fn outline(
        self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        self.polygon_styled(
            name,
            points,
            PolygonStyle {
                fill: None,
                stroke: Some(Color::GRAY),
                width_px: 1.5,
                dash: Dash::Solid,
                closed: true,
            },
        )
    }

    /// A filled polygon: `fill` at 35 % opacity with a 1 px outline of the same colour.
    pub fn polygon(
        self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
        fill: Color,
    ) -> Self {
        self.polygon_styled(
            name,
            points,
            PolygonStyle {
                fill: Some((fill, 0.35)),
                stroke: Some(fill),
                width_px: 1.0,
                dash: Dash::Solid,
                closed: true,
            },
        )
    }

    /// A polygon or open polyline with an explicit style.
    pub fn polygon_styled(
        mut self,
        name: impl Into<String>,
        points: impl IntoIterator<Item = (f64, f64)>,
        style: PolygonStyle,
    ) -> Self {
        self.items.push(Item::Polygon {
            name: name.into(),
            pts: points.into_iter().filter(finite).collect(),
            style,
        });
        self
    }

    /// A categorical outcome map: each point (p1, p2, k) is coloured by category `k`
    /// (`categories[k]`, palette colours in order); the legend lists every category with its
    /// count. Points with `k` out of range are skipped.
    pub fn outcomes<S: AsRef<str>>(
        self,
        points: impl IntoIterator<Item = (f64, f64, usize)>,
        categories: &[S],
    ) -> Self {
        let cats: Vec<(String, Color)> = categories
            .iter()
            .enumerate()
            .map(|(i, s)| (s.as_ref().to_owned(), PALETTE[i % PALETTE.len()]))
            .collect();
        self.outcomes_colored(points, &cats)
    }

    /// A categorical outcome map with explicit colours per category.
    pub fn outcomes_colored<S: AsRef<str>>(
        mut self,
        points: impl IntoIterator<Item = (f64, f64, usize)>,
        categories: &[(S, Color)],
    ) -> Self {
        let cats: Vec<(String, Color)> = categories
            .iter()
            .map(|(s, c)| (s.as_ref().to_owned(), *c))
            .collect();
        let pts = points
            .into_iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite() && p.2 < cats.len())
            .collect();
        self.items.push(Item::Outcomes {
            pts,
            cats,
            totals: None,
        });
        self
    }

    /// The counts the legend shows for the last outcome map, per category (e.g. the totals over
    /// every panel of small multiples, when only one panel carries the legend).
    pub fn outcome_counts(mut self, totals: Vec<usize>) -> Self {
        if let Some(Item::Outcomes { totals: t, .. }) = self
            .items
            .iter_mut()
            .rev()
            .find(|i| matches!(i, Item::Outcomes { .. }))
        {
            *t = Some(totals);
        }
        self
    }

    /// This plot alone in a figure with no figure title.
    pub fn into_figure(self) -> Figure {
        Figure::new("").plot(self)
    }

    /// Renders this plot alone ([`Self::into_figure`]) to PNG at `path`.
    pub fn write_png(&self, path: &Path) -> io::Result<()> {
        self.clone().into_figure().write_png(path)
    }

    /// Renders this plot alone to SVG at `path`.
    pub fn write_svg(&self, path: &Path) -> io::Result<()> {
        self.clone().into_figure().write_svg(path)
    }

    // ---------------------------------------------------------------- layout and drawing

    fn y_ok(&self, y: f64) -> bool {
        y.is_finite() && (!self.log_y || y > 0.0)
    }

    /// Cell size (dx, dy) of an outcome map: the smallest positive gap between distinct
    /// parameter values on each axis (a grid's spacing); 1/10 of the span, or 1, if none.
    fn cell_size(pts: &[(f64, f64, usize)]) -> (f64, f64) {
        let gap = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.dedup();
            let min_gap = v
                .windows(2)
                .map(|w| w[1] - w[0])
                .filter(|g| *g > 0.0)
                .fold(f64::INFINITY, f64::min);
            if min_gap.is_finite() {
                min_gap
            } else if let (Some(a), Some(b)) = (v.first(), v.last()) {
                if b > a {
                    (b - a) / 10.0
                } else {
                    a.abs().max(1.0) / 10.0
                }
            } else {
                1.0
            }
        };
        (
            gap(pts.iter().map(|p| p.0).collect()),
            gap(pts.iter().map(|p| p.1).collect()),
        )
    }

    /// Data bounds (x, y) over everything drawn, before padding.
    fn bounds(&self) -> (Span, Span) {
        let mut bx: Option<(f64, f64)> = None;
        let mut by: Option<(f64, f64)> = None;
        let add = |b: &mut Option<(f64, f64)>, v: f64| {
            *b = Some(match *b {
                None => (v, v),
                Some((lo, hi)) => (lo.min(v), hi.max(v)),
            });
        };
        for it in &self.items {
            match it {
                Item::Line { pts, .. } | Item::Scatter { pts, .. } | Item::Polygon { pts, .. } => {
                    for &(x, y) in pts {
                        if x.is_finite() && self.y_ok(y) {
                            add(&mut bx, x);
                            add(&mut by, y);
                        }
                    }
                }
                Item::HLine { y, .. } => {
                    if self.y_ok(*y) {
                        add(&mut by, *y);
                    }
                }
                Item::VLine { x, .. } => {
                    if x.is_finite() {
                        add(&mut bx, *x);
                    }
                }
                Item::Outcomes { pts, .. } => {
                    let (dx, dy) = Self::cell_size(pts);
                    for &(x, y, _) in pts {
                        add(&mut bx, x - dx / 2.0);
                        add(&mut bx, x + dx / 2.0);
                        if self.y_ok(y - dy / 2.0) {
                            add(&mut by, y - dy / 2.0);
                        }
                        if self.y_ok(y + dy / 2.0) {
                            add(&mut by, y + dy / 2.0);
                        }
                    }
                }
            }
        }
        (bx, by)
    }

    /// Padded, non-degenerate (x, y) ranges before equal-aspect adjustment.
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let (bx, by) = self.bounds();
        let lines_only = self.items.iter().all(|i| {
            matches!(
                i,
                Item::Line { .. } | Item::HLine { .. } | Item::VLine { .. }
            )
        });
        let x_pad = if lines_only && !self.equal_aspect {
            0.0
        } else {
            0.05
        };
        let lin = |b: Option<(f64, f64)>, pad: f64| match b {
            None => (0.0, 1.0),
            Some((lo, hi)) if hi > lo => {
                let p = (hi - lo) * pad;
                (lo - p, hi + p)
            }
            Some((v, _)) => {
                let h = if v == 0.0 { 1.0 } else { v.abs() * 0.1 };
                (v - h, v + h)
            }
        };
        let xr = self.x_range.unwrap_or_else(|| lin(bx, x_pad));
        let yr = match self.y_range {
            Some(r) if !self.log_y || r.0 > 0.0 => r,
            _ if self.log_y => match by {
                None => (1.0, 10.0),
                Some((lo, hi)) if hi > lo => {
                    let f = (hi / lo).powf(0.05);
                    (lo / f, hi * f)
                }
                Some((v, _)) => (v / 10.0, v * 10.0),
            },
            _ => lin(by, 0.05),
        };
        (xr, yr)
    }

    fn has_legend_entries(&self) -> bool {
        !self.legend_entries().is_empty()
    }

    /// Whether the legend goes right of the axes.
    fn legend_outside(&self) -> bool {
        match self.legend {
            Legend::Outside => self.has_legend_entries(),
            Legend::Best => self
                .items
                .iter()
                .any(|i| matches!(i, Item::Outcomes { .. })),
            _ => false,
        }
    }

    /// Legend box (width, height) in px.
    fn legend_size(&self, entries: &[(String, Swatch)]) -> (f64, f64) {
        let text_w = entries
            .iter()
            .map(|(s, _)| text_width_px(s, LEGEND_PX))
            .fold(0.0, f64::max);
        (
            8.0 + LEGEND_SWATCH + 6.0 + text_w + 8.0,
            6.0 + LEGEND_ROW * entries.len() as f64 + 2.0,
        )
    }

    fn legend_entries(&self) -> Vec<(String, Swatch)> {
        let mut out = Vec::new();
        for it in &self.items {
            match it {
                Item::Line {
                    name,
                    color,
                    width,
                    dash,
                    ..
                } if !name.is_empty() => {
                    out.push((name.clone(), Swatch::Line(*color, *width, *dash)))
                }
                Item::Scatter { name, color, .. } if !name.is_empty() => {
                    out.push((name.clone(), Swatch::Dot(*color)))
                }
                Item::Polygon { name, style, .. } if !name.is_empty() => {
                    if style.closed && style.fill.is_some() {
                        out.push((name.clone(), Swatch::Patch(style.fill, style.stroke)));
                    } else {
                        out.push((
                            name.clone(),
                            Swatch::Line(
                                style.stroke.unwrap_or(Color::GRAY),
                                style.width_px,
                                style.dash,
                            ),
                        ));
                    }
                }
                Item::HLine {
                    label,
                    color,
                    dash,
                    width,
                    ..
                } if !label.is_empty() => {
                    out.push((label.clone(), Swatch::Line(*color, *width, *dash)))
                }
                Item::Outcomes { pts, cats, totals } => {
                    for (k, (name, c)) in cats.iter().enumerate() {
                        let n = totals
                            .as_ref()
                            .and_then(|t| t.get(k).copied())
                            .unwrap_or_else(|| pts.iter().filter(|p| p.2 == k).count());
                        out.push((
                            format!("{name} ({n})"),
                            Swatch::Patch(Some((*c, 1.0)), None),
                        ));
                    }
                }
                _ => {}
            }
        }
        out
    }

    /// Computes the axes frame inside the cell (x, y, w, h) in px.
    fn frame(&self, cell: (f64, f64, f64, f64)) -> Frame {
        let (cx, cy, cw, ch) = cell;
        let top = cy
            + PAD
            + if self.title.is_empty() {
                4.0
            } else {
                PANEL_TITLE_PX + 10.0
            };
        let bottom = cy + ch
            - PAD
            - if self.x_label.is_empty() {
                0.0
            } else {
                LABEL_PX + 8.0
            }
            - (TICK_PX + TICK_LEN + 6.0);
        let legend_w = if self.legend_outside() {
            self.legend_size(&self.legend_entries()).0 + 10.0
        } else {
            0.0
        };
        let right = cx + cw - PAD - 14.0 - legend_w;
        let (xr0, yr0) = self.ranges();
        let ah = (bottom - top).max(20.0);
        let y_label_w = if self.y_label.is_empty() {
            0.0
        } else {
            LABEL_PX + 8.0
        };
        let left_for = |yr: (f64, f64)| {
            let yt = self.y_ticks(yr, ah);
            let w = yt
                .iter()
                .map(|t| text_width_px(&t.label, TICK_PX))
                .fold(0.0, f64::max);
            cx + PAD + y_label_w + w + TICK_LEN + 4.0
        };
        let mut left = left_for(yr0);
        for _ in 0..2 {
            let aw = (right - left).max(20.0);
            let (_, yr) = self.aspect(xr0, yr0, aw, ah);
            left = left_for(yr);
        }
        let (x, y) = (left.round(), top.round());
        let (w, h) = ((right - left).max(20.0).round(), ah.round());
        let (xr, yr) = self.aspect(xr0, yr0, w, h);
        Frame {
            x,
            y,
            w,
            h,
            xr,
            yr,
            log_y: self.log_y,
        }
    }

    fn aspect(&self, xr: (f64, f64), yr: (f64, f64), w: f64, h: f64) -> ((f64, f64), (f64, f64)) {
        if !self.equal_aspect || self.log_y {
            return (xr, yr);
        }
        let (sx, sy) = (w / (xr.1 - xr.0), h / (yr.1 - yr.0));
        if sx > sy {
            let half = w / sy / 2.0;
            let c = (xr.0 + xr.1) / 2.0;
            ((c - half, c + half), yr)
        } else {
            let half = h / sx / 2.0;
            let c = (yr.0 + yr.1) / 2.0;
            (xr, (c - half, c + half))
        }
    }

    fn y_ticks(&self, yr: (f64, f64), h: f64) -> Vec<Tick> {
        if self.log_y {
            log_ticks(yr.0, yr.1)
        } else {
            linear_ticks(yr.0, yr.1, ((h / 55.0) as usize).clamp(3, 10))
        }
    }

    /// Draws the plot into the cell (x, y, w, h) in px: the grid, the data clipped to the
    /// axes (outcome maps, polygons, lines and scatters, marker lines, in that order from the
    /// bottom), the frame with its ticks, the labels and title, and the legend.
    fn draw(&self, svg: &mut Svg, cell: (f64, f64, f64, f64)) {
        let f = self.frame(cell);
        let xt = linear_ticks(f.xr.0, f.xr.1, ((f.w / 90.0) as usize).clamp(3, 10));
        let yt = self.y_ticks(f.yr, f.h);
        draw_grid(svg, &f, &xt, &yt);

        // Data, clipped to the axes.
        svg.begin_clip(f.x, f.y, f.w, f.h);
        let mut drawn: Vec<(f64, f64)> = Vec::new();
        self.draw_outcomes(svg, &f, &mut drawn);
        self.draw_polygons(svg, &f, &mut drawn);
        self.draw_lines(svg, &f, &mut drawn);
        self.draw_markers(svg, &f);
        svg.end_group();

        draw_axes(svg, &f, &xt, &yt);
        self.draw_labels(svg, &f, cell);
        self.draw_legend(svg, &f, &drawn);
    }

    /// The outcome maps: a cell per point where it is at least 3 px wide and high (and the y
    /// axis is linear), else a dot; their px centres into `drawn`.
    fn draw_outcomes(&self, svg: &mut Svg, f: &Frame, drawn: &mut Vec<(f64, f64)>) {
        for it in &self.items {
            if let Item::Outcomes { pts, cats, .. } = it {
                let (dx, dy) = Self::cell_size(pts);
                let (wpx, hpx) = (dx * f.sx(), self.cell_h_px(f, dy));
                for &(x, y, k) in pts {
                    let (px, py) = (f.px(x), f.py(y));
                    if wpx >= 3.0 && hpx >= 3.0 && !self.log_y {
                        svg.rect(
                            px - wpx / 2.0,
                            py - hpx / 2.0,
                            wpx,
                            hpx,
                            Some((cats[k].1, 1.0)),
                            None,
                            true,
                        );
                    } else {
                        svg.circle(px, py, 3.5, cats[k].1, None);
                    }
                    drawn.push((px, py));
                }
            }
        }
    }

    /// The polygons and open polylines; their px vertices into `drawn`.
    fn draw_polygons(&self, svg: &mut Svg, f: &Frame, drawn: &mut Vec<(f64, f64)>) {
        for it in &self.items {
            if let Item::Polygon { pts, style, .. } = it {
                let p: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|p| self.y_ok(p.1))
                    .map(|&(x, y)| (f.px(x), f.py(y)))
                    .collect();
                let stroke = style.stroke.map(|c| (c, style.width_px));
                if style.closed {
                    svg.polygon(&p, style.fill, stroke, style.dash);
                } else if let Some(s) = style.stroke {
                    svg.polyline(&p, s, style.width_px, style.dash);
                }
                drawn.extend(p);
            }
        }
    }

    /// The lines ([`Self::segments`]) and scatters; their px points into `drawn`.
    fn draw_lines(&self, svg: &mut Svg, f: &Frame, drawn: &mut Vec<(f64, f64)>) {
        for it in &self.items {
            match it {
                Item::Line {
                    pts,
                    color,
                    width,
                    dash,
                    ..
                } => {
                    for seg in self.segments(f, pts) {
                        svg.polyline(&seg, *color, *width, *dash);
                        drawn.extend(seg);
                    }
                }
                Item::Scatter { pts, color, .. } => {
                    for &(x, y) in pts {
                        if x.is_finite() && self.y_ok(y) {
                            let (px, py) = (f.px(x), f.py(y));
                            svg.circle(px, py, 3.0, *color, Some((Color::WHITE, 0.5)));
                            drawn.push((px, py));
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// The horizontal reference lines and the labelled vertical markers.
    fn draw_markers(&self, svg: &mut Svg, f: &Frame) {
        for it in &self.items {
            match it {
                Item::HLine {
                    y,
                    color,
                    dash,
                    width,
                    ..
                } if self.y_ok(*y) => {
                    let py = f.py(*y);
                    svg.line(f.x, py, f.x + f.w, py, *color, *width, *dash);
                }
                Item::VLine { x, label } if x.is_finite() => {
                    let px = f.px(*x);
                    svg.line(px, f.y, px, f.y + f.h, Color::GRAY, 1.5, Dash::Dotted);
                    svg.text(
                        px - 4.0,
                        f.y + 6.0,
                        label,
                        MARKER_LABEL_PX,
                        Anchor::End,
                        Color::GRAY,
                        -90.0,
                    );
                }
                _ => {}
            }
        }
    }

    /// The x label under the axes, the y label left of them and the panel title above, in the
    /// cell (x, y, w, h) in px.
    fn draw_labels(&self, svg: &mut Svg, f: &Frame, cell: (f64, f64, f64, f64)) {
        let (cx, _, _, ch) = cell;
        if !self.x_label.is_empty() {
            svg.text(
                f.x + f.w / 2.0,
                cell.1 + ch - PAD - 3.0,
                &self.x_label,
                LABEL_PX,
                Anchor::Middle,
                Color::BLACK,
                0.0,
            );
        }
        if !self.y_label.is_empty() {
            svg.text(
                cx + PAD + LABEL_PX * 0.8,
                f.y + f.h / 2.0,
                &self.y_label,
                LABEL_PX,
                Anchor::Middle,
                Color::BLACK,
                -90.0,
            );
        }
        if !self.title.is_empty() {
            svg.text(
                f.x + f.w / 2.0,
                f.y - 9.0,
                &self.title,
                PANEL_TITLE_PX,
                Anchor::Middle,
                Color::BLACK,
                0.0,
            );
        }
    }

    fn cell_h_px(&self, f: &Frame, dy: f64) -> f64 {
        dy * f.h / (f.yr.1 - f.yr.0)
    }

    /// Maps a line to px polylines, breaking at invalid points and dropping points closer than
    /// [`THIN_PX`] to the last kept one (the last point of each piece is always kept).
    fn segments(&self, f: &Frame, pts: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
        let mut out = Vec::new();
        let mut cur: Vec<(f64, f64)> = Vec::new();
        let mut pending: Option<(f64, f64)> = None;
        let flush = |cur: &mut Vec<(f64, f64)>,
                     pending: &mut Option<(f64, f64)>,
                     out: &mut Vec<Vec<(f64, f64)>>| {
            if let Some(p) = pending.take() {
                cur.push(p);
            }
            if cur.len() >= 2 {
                out.push(std::mem::take(cur));
            } else {
                cur.clear();
            }
        };
        for &(x, y) in pts {
            if !(x.is_finite() && self.y_ok(y)) {
                flush(&mut cur, &mut pending, &mut out);
                continue;
            }
            let p = (f.px(x), f.py(y));
            match cur.last() {
                Some(&(lx, ly)) if (p.0 - lx).hypot(p.1 - ly) < THIN_PX => pending = Some(p),
                _ => {
                    pending = None;
                    cur.push(p);
                }
            }
        }
        flush(&mut cur, &mut pending, &mut out);
        out
    }

    /// The top-left corner (px) of a legend box `size` (w, h px): right of the axes when the
    /// legend is outside, the corner asked for, or for [`Legend::Best`] the corner whose box
    /// covers the fewest of the `drawn` points (ties: top right, top left, bottom right, bottom
    /// left); 8 px in from the frame.
    fn legend_position(&self, f: &Frame, drawn: &[(f64, f64)], (bw, bh): (f64, f64)) -> (f64, f64) {
        let m = 8.0;
        let corner = |l: Legend| -> (f64, f64) {
            let xl = f.x + m;
            let xr = f.x + f.w - m - bw;
            let yt = f.y + m;
            let yb = f.y + f.h - m - bh;
            match l {
                Legend::TopLeft => (xl, yt),
                Legend::BottomRight => (xr, yb),
                Legend::BottomLeft => (xl, yb),
                _ => (xr, yt),
            }
        };
        match self.legend {
            _ if self.legend_outside() => (f.x + f.w + 10.0, f.y),
            Legend::Best => {
                let order = [
                    Legend::TopRight,
                    Legend::TopLeft,
                    Legend::BottomRight,
                    Legend::BottomLeft,
                ];
                let cover = |l: Legend| {
                    let (x, y) = corner(l);
                    drawn
                        .iter()
                        .filter(|p| p.0 >= x && p.0 <= x + bw && p.1 >= y && p.1 <= y + bh)
                        .count()
                };
                let mut best = order[0];
                let mut best_n = cover(best);
                for &l in &order[1..] {
                    let n = cover(l);
                    if n < best_n {
                        best = l;
                        best_n = n;
                    }
                }
                corner(best)
            }
            l => corner(l),
        }
    }

    /// The legend (unless off or empty): a box at [`Self::legend_position`] with a swatch and a
    /// label per entry.
    fn draw_legend(&self, svg: &mut Svg, f: &Frame, drawn: &[(f64, f64)]) {
        if self.legend == Legend::Off || !self.has_legend_entries() {
            return;
        }
        let entries = self.legend_entries();
        let row = LEGEND_ROW;
        let sw = LEGEND_SWATCH;
        let (bw, bh) = self.legend_size(&entries);
        let (x, y) = self.legend_position(f, drawn, (bw, bh));
        svg.rect(
            x,
            y,
            bw,
            bh,
            Some((Color::WHITE, 0.85)),
            Some((Color::rgb(0xaa, 0xaa, 0xaa), 1.0)),
            false,
        );
        for (i, (label, s)) in entries.iter().enumerate() {
            let cy = y + 6.0 + row * (i as f64 + 0.5);
            let sx = x + 8.0;
            match *s {
                Swatch::Line(c, w, d) => svg.line(sx, cy, sx + sw, cy, c, w.min(4.0), d),
                Swatch::Dot(c) => svg.circle(sx + sw / 2.0, cy, 3.5, c, None),
                Swatch::Patch(fill, stroke) => svg.rect(
                    sx + 4.0,
                    cy - 5.0,
                    sw - 8.0,
                    10.0,
                    fill,
                    stroke.map(|c| (c, 1.0)),
                    false,
                ),
            }
            svg.text(
                sx + sw + 6.0,
                cy + LEGEND_PX * 0.35,
                label,
                LEGEND_PX,
                Anchor::Start,
                Color::DARK_GRAY,
                0.0,
            );
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Swatch {
    Line(Color, f64, Dash),
    Dot(Color),
    Patch(Option<(Color, f64)>, Option<Color>),
}

/// The grid: a light line at every x tick and every y tick (fainter at a minor y tick).
fn draw_grid(svg: &mut Svg, f: &Frame, xt: &[Tick], yt: &[Tick]) {
    for t in xt {
        let px = f.px(t.value).round() + 0.5;
        svg.line(px, f.y, px, f.y + f.h, Color::LIGHT_GRAY, 1.0, Dash::Solid);
    }
    for t in yt {
        let py = f.py(t.value).round() + 0.5;
        let c = if t.major {
            Color::LIGHT_GRAY
        } else {
            Color::rgb(0xf0, 0xf0, 0xf0)
        };
        svg.line(f.x, py, f.x + f.w, py, c, 1.0, Dash::Solid);
    }
}

/// The axes' frame, and the ticks and their labels under it (x) and left of it (y; a minor y
/// tick is shorter).
fn draw_axes(svg: &mut Svg, f: &Frame, xt: &[Tick], yt: &[Tick]) {
    svg.rect(
        f.x + 0.5,
        f.y + 0.5,
        f.w - 1.0,
        f.h - 1.0,
        None,
        Some((Color::DARK_GRAY, 1.0)),
        false,
    );
    let bottom = f.y + f.h;
    for t in xt {
        let px = f.px(t.value).round() + 0.5;
        svg.line(
            px,
            bottom,
            px,
            bottom + TICK_LEN,
            Color::DARK_GRAY,
            1.0,
            Dash::Solid,
        );
        svg.text(
            px,
            bottom + TICK_LEN + 3.0 + TICK_PX * 0.8,
            &t.label,
            TICK_PX,
            Anchor::Middle,
            Color::DARK_GRAY,
            0.0,
        );
    }
    for t in yt {
        let py = f.py(t.value).round() + 0.5;
        let len = if t.major { TICK_LEN } else { TICK_LEN * 0.6 };
        svg.line(f.x - len, py, f.x, py, Color::DARK_GRAY, 1.0, Dash::Solid);
        svg.text(
            f.x - TICK_LEN - 3.0,
            py + TICK_PX * 0.35,
            &t.label,
            TICK_PX,
            Anchor::End,
            Color::DARK_GRAY,
            0.0,
        );
    }
}

/// The axes rectangle in px and the data ranges it shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    /// Left edge, px.
    pub x: f64,
    /// Top edge, px.
    pub y: f64,
    /// Width, px.
    pub w: f64,
    /// Height, px.
    pub h: f64,
    /// x range shown, data units.
    pub xr: (f64, f64),
    /// y range shown, data units.
    pub yr: (f64, f64),
    /// Log10 y axis.
    pub log_y: bool,
}

impl Frame {
    fn sx(&self) -> f64 {
        self.w / (self.xr.1 - self.xr.0)
    }
    /// Data x → px column.
    pub(crate) fn px(&self, x: f64) -> f64 {
        self.x + (x - self.xr.0) * self.sx()
    }
    /// Data y → px row (down).
    pub(crate) fn py(&self, y: f64) -> f64 {
        let (lo, hi, v) = if self.log_y {
            (self.yr.0.log10(), self.yr.1.log10(), y.log10())
        } else {
            (self.yr.0, self.yr.1, y)
        };
        self.y + self.h - (v - lo) / (hi - lo) * self.h
    }
}

/// A titled grid of [`Plot`]s, filled row by row.
#[derive(Clone, Debug)]
pub struct Figure {
    title: String,
    cols: usize,
    size_px: Option<(u32, u32)>,
    plots: Vec<Plot>,
}

impl Figure {
    /// An empty figure; an empty `title` draws no title band.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            cols: 1,
            size_px: None,
            plots: Vec::new(),
        }
    }

    /// Number of grid columns (≥ 1; default 1: plots stacked vertically).
    pub fn cols(mut self, cols: usize) -> Self {
        self.cols = cols.max(1);
        self
    }

    /// Total size in px (clamped to 64–8192 each). Default: 900 px wide for one column
    /// (520 px per extra column), 520 px tall for a single plot, else 300 px per row, plus the
    /// title band.
    pub fn size_px(mut self, width: u32, height: u32) -> Self {
        self.size_px = Some((width.clamp(64, 8192), height.clamp(64, 8192)));
        self
    }

    /// Adds a plot (next grid cell).
    pub fn plot(mut self, plot: Plot) -> Self {
        self.plots.push(plot);
        self
    }

    /// Adds a plot (next grid cell), by reference.
    pub fn push(&mut self, plot: Plot) -> &mut Self {
        self.plots.push(plot);
        self
    }

    fn rows(&self) -> usize {
        self.plots.len().div_ceil(self.cols).max(1)
    }

    fn title_h(&self) -> f64 {
        if self.title.is_empty() {
            0.0
        } else {
            TITLE_PX + 18.0
        }
    }

    /// (width, height) in px.
    pub fn size(&self) -> (u32, u32) {
        self.size_px.unwrap_or_else(|| {
            let cols = self.cols.min(self.plots.len().max(1));
            let w = 900 + 520 * (cols as u32 - 1);
            let rows = self.rows() as u32;
            let h = if self.plots.len() <= 1 {
                520
            } else {
                300 * rows
            };
            (w, h + self.title_h() as u32)
        })
    }

    fn cells(&self) -> Vec<(f64, f64, f64, f64)> {
        let (w, h) = self.size();
        let cols = self.cols.min(self.plots.len().max(1));
        let top = self.title_h();
        let cw = f64::from(w) / cols as f64;
        let chh = (f64::from(h) - top) / self.rows() as f64;
        (0..self.plots.len())
            .map(|i| {
                (
                    (i % cols) as f64 * cw,
                    top + (i / cols) as f64 * chh,
                    cw,
                    chh,
                )
            })
            .collect()
    }

    /// The axes frames of the plots, in px (for tests).
    #[cfg(test)]
    pub(crate) fn frames(&self) -> Vec<Frame> {
        self.plots
            .iter()
            .zip(self.cells())
            .map(|(p, c)| p.frame(c))
            .collect()
    }

    /// The figure as an SVG document (text as `<text>` in DejaVu Sans / sans-serif).
    pub fn to_svg(&self) -> String {
        let (w, h) = self.size();
        let mut svg = Svg::new(w, h, FONT_FAMILY);
        if !self.title.is_empty() {
            svg.text(
                f64::from(w) / 2.0,
                8.0 + TITLE_PX,
                &self.title,
                TITLE_PX,
                Anchor::Middle,
                Color::BLACK,
                0.0,
            );
        }
        for (p, c) in self.plots.iter().zip(self.cells()) {
            p.draw(&mut svg, c);
        }
        svg.finish()
    }

    /// The figure as PNG bytes (RGBA, 1 px per SVG px), rendered with the bundled font.
    pub fn to_png(&self) -> io::Result<Vec<u8>> {
        svg_to_png(&self.to_svg())
    }

    /// Writes the SVG to `path` atomically.
    pub fn write_svg(&self, path: &Path) -> io::Result<()> {
        write_atomic(path, self.to_svg().as_bytes())
    }

    /// Writes the PNG to `path` atomically.
    pub fn write_png(&self, path: &Path) -> io::Result<()> {
        let png = self
            .to_png()
            .map_err(|e| io::Error::new(e.kind(), format!("render {}: {e}", path.display())))?;
        write_atomic(path, &png)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use resvg::tiny_skia::Pixmap;

    const BLUE: Color = Color::rgb(0, 0, 255);

    fn decode(png: &[u8]) -> Pixmap {
        Pixmap::decode_png(png).expect("PNG decodes")
    }

    /// RGB of pixel (col, row); the background is opaque, so premultiplied = straight.
    fn rgb(p: &Pixmap, col: u32, row: u32) -> (u8, u8, u8) {
        let c = p.pixel(col, row).unwrap();
        (c.red(), c.green(), c.blue())
    }

    fn line_figure(title: &str) -> Figure {
        Figure::new(title).size_px(800, 500).plot(
            Plot::new("")
                .x_label("t [s]")
                .y_label("x [m]")
                .x_range(0.0, 10.0)
                .y_range(0.0, 10.0)
                .legend(Legend::Off)
                .line_styled(
                    "x",
                    (0..=100).map(|i| (f64::from(i) * 0.1, 2.5)),
                    LineStyle {
                        color: Some(BLUE),
                        width_px: 6.0,
                        dash: Dash::Solid,
                    },
                ),
        )
    }

    /// Reference: the affine map data → px of the axes frame, row = y₀ + h·(1 − (v − lo)/(hi − lo)),
    /// written out here; the rasteriser (resvg) places the 6 px stroke centred on that row.
    #[test]
    fn val_png_line_at_known_value_lands_on_expected_row() {
        let fig = line_figure("Line at x = 2.5 m");
        let png = fig.to_png().unwrap();
        let p = decode(&png);
        assert_eq!((p.width(), p.height()), (800, 500));
        let f = fig.frames()[0];
        let expected_row = f.y + f.h * (1.0 - 2.5 / 10.0);
        let col = (f.x + f.w * 0.55) as u32;
        let rows: Vec<u32> = (0..p.height())
            .filter(|&r| {
                let (r_, g, b) = rgb(&p, col, r);
                b > 200 && r_ < 80 && g < 80
            })
            .collect();
        assert!((5..=7).contains(&rows.len()), "stroke rows {rows:?}");
        assert!(
            rows.windows(2).all(|w| w[1] == w[0] + 1),
            "contiguous {rows:?}"
        );
        let centre = rows.iter().map(|&r| f64::from(r) + 0.5).sum::<f64>() / rows.len() as f64;
        assert!(
            (centre - expected_row).abs() <= 0.75,
            "stroke centre {centre} px vs expected {expected_row} px"
        );
        // Away from the line the plot area is background white, not blank-everywhere-else.
        assert_eq!(rgb(&p, col, (f.y + f.h * 0.1) as u32), (255, 255, 255));
        // The frame's top edge is drawn on row f.y (1 px, dark).
        let (r, g, b) = rgb(&p, col, f.y as u32);
        assert!(r < 120 && g < 120 && b < 120, "frame pixel {:?}", (r, g, b));
    }

    /// Reference: the title is centred at w/2; its width is the sum of DejaVu Sans advances
    /// (checked against the font's hmtx table in `raster`), so the inked columns must lie within
    /// w/2 ± width/2 (glyph side bearings make the ink slightly narrower).
    #[test]
    fn invariant_title_text_is_rendered_centred() {
        let title = "Relative position, LVLH frame";
        let p = decode(&line_figure(title).to_png().unwrap());
        let band = (TITLE_PX + 18.0) as u32;
        let dark: Vec<(u32, u32)> = (0..band)
            .flat_map(|r| (0..p.width()).map(move |c| (c, r)))
            .filter(|&(c, r)| {
                let (r_, g, b) = rgb(&p, c, r);
                u32::from(r_) + u32::from(g) + u32::from(b) < 3 * 100
            })
            .collect();
        assert!(
            dark.len() > 150,
            "only {} dark pixels in the title band",
            dark.len()
        );
        let half = text_width_px(title, TITLE_PX) / 2.0;
        let (cmin, cmax) = dark
            .iter()
            .fold((u32::MAX, 0), |(a, b), &(c, _)| (a.min(c), b.max(c)));
        assert!(
            f64::from(cmin) >= 400.0 - half - 1.0 && f64::from(cmin) <= 400.0 - half + 4.0,
            "{cmin}"
        );
        assert!(
            f64::from(cmax) <= 400.0 + half + 1.0 && f64::from(cmax) >= 400.0 + half - 4.0,
            "{cmax}"
        );
        // Without a title, the same band holds no text.
        let p = decode(&Figure::new("").size_px(800, 500).to_png().unwrap());
        assert!((0..band).all(|r| (0..800).all(|c| rgb(&p, c, r) == (255, 255, 255))));
    }

    fn busy_figure() -> Figure {
        let t: Vec<f64> = (0..2000).map(|i| f64::from(i) * 0.05).collect();
        let series = |k: f64| {
            t.iter()
                .map(move |&t| (t, (k * t * 0.1).sin() * 10.0 * k))
                .collect::<Vec<_>>()
        };
        let grid: Vec<(f64, f64, usize)> = (0..12u32)
            .flat_map(|i| {
                (0..9u32)
                    .map(move |j| (f64::from(i) * 0.5, f64::from(j) * 2.0, (i * j) as usize % 3))
            })
            .collect();
        Figure::new("Guo 2016 — capture <case> & \"nominal\"")
            .cols(2)
            .plot(
                Plot::new("x(t)")
                    .x_label("t [s]")
                    .y_label("x [m]")
                    .line("chaser", series(1.0))
                    .line("target", series(0.5))
                    .hline(8.0, "limit 8 m")
                    .vline(42.0, "capture")
                    .vline(f64::NAN, "never"),
            )
            .plot(
                Plot::new("distance")
                    .x_label("t [s]")
                    .y_label("d [m]")
                    .log_y()
                    .line("d", t.iter().map(|&t| (t, 100.0 * (-t / 20.0).exp()))),
            )
            .plot(
                Plot::new("path in the orbital plane")
                    .x_label("x [m]")
                    .y_label("z [m]")
                    .equal_aspect()
                    .outline(
                        "keep-out",
                        (0..40).map(|i| {
                            let a = f64::from(i) / 40.0 * std::f64::consts::TAU;
                            (2.0 * a.cos(), 2.0 * a.sin())
                        }),
                    )
                    .polygon(
                        "target",
                        [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)],
                        PALETTE[2],
                    )
                    .line(
                        "chaser",
                        (0..200).map(|i| {
                            let s = f64::from(i) / 200.0;
                            (10.0 * (1.0 - s), 3.0 * (1.0 - s) * (6.0 * s).sin())
                        }),
                    )
                    .scatter("waypoints", [(10.0, 0.0), (5.0, 1.0), (f64::NAN, 1.0)]),
            )
            .plot(
                Plot::new("capture envelope")
                    .x_label("v₀ [m/s]")
                    .y_label("ω₀ [deg/s]")
                    .outcomes(grid, &["captured", "missed", "collided"]),
            )
    }

    #[test]
    fn invariant_identical_input_gives_identical_svg_and_png_bytes() {
        let (a, b) = (busy_figure(), busy_figure());
        assert_eq!(a.to_svg(), b.to_svg());
        assert_eq!(a.to_png().unwrap(), b.to_png().unwrap());
        // And through the files, in another thread (no hidden shared state).
        let d = crate::report::scratch("fig-det");
        a.write_png(&d.join("a.png")).unwrap();
        let d2 = d.clone();
        std::thread::spawn(move || busy_figure().write_png(&d2.join("b.png")).unwrap())
            .join()
            .unwrap();
        assert_eq!(
            std::fs::read(d.join("a.png")).unwrap(),
            std::fs::read(d.join("b.png")).unwrap()
        );
    }

    /// Reference: XML well-formedness by roxmltree (an independent XML parser), and the
    /// escaping rules of XML 1.0 §2.4 for the title.
    #[test]
    fn invariant_svg_is_well_formed_and_escapes_text() {
        let svg = busy_figure().to_svg();
        let doc = resvg::usvg::roxmltree::Document::parse(&svg).expect("well-formed XML");
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg");
        assert_eq!(root.attribute("width"), Some("1420"));
        let texts: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text().map(str::to_owned))
            .collect();
        assert!(texts.contains(&"Guo 2016 — capture <case> & \"nominal\"".to_owned()));
        for want in [
            "x(t)",
            "t [s]",
            "d [m]",
            "chaser",
            "limit 8 m",
            "capture",
            "10¹",
            "captured (60)",
        ] {
            assert!(texts.iter().any(|t| t == want), "missing text {want:?}");
        }
        assert!(
            !texts.iter().any(|t| t == "never"),
            "a NaN event marker is not drawn"
        );
        // 12 × 9 grid of outcome tiles.
        let tiles = doc
            .descendants()
            .filter(|n| {
                n.has_tag_name("rect") && n.attribute("shape-rendering") == Some("crispEdges")
            })
            .count();
        assert_eq!(tiles, 108);
    }

    /// Reference: equal aspect means px per data unit equal on both axes; a log axis maps each
    /// decade to the same height.
    #[test]
    fn invariant_equal_aspect_and_log_scale_geometry() {
        let fig = busy_figure();
        let fr = fig.frames();
        let f = fr[2];
        let (sx, sy) = (f.w / (f.xr.1 - f.xr.0), f.h / (f.yr.1 - f.yr.0));
        assert!((sx / sy - 1.0).abs() < 1e-12, "sx {sx} sy {sy}");
        let g = fr[1];
        let d1 = g.py(1.0) - g.py(10.0);
        let d2 = g.py(10.0) - g.py(100.0);
        assert!(d1 > 0.0 && (d1 - d2).abs() < 1e-9, "{d1} {d2}");
        // Data fits: the log range holds 100·e^(−t/20) over t ∈ [0, 99.95 s].
        assert!(g.yr.0 <= 100.0 * (-99.95f64 / 20.0).exp() && g.yr.1 >= 100.0);
    }

    /// Reference: a tile is drawn without anti-aliasing in its category's colour, so the pixel at
    /// a tile's centre is exactly that colour (Okabe–Ito blue for category 0).
    #[test]
    fn invariant_outcome_tiles_have_category_colours() {
        let grid: Vec<(f64, f64, usize)> = (0..4)
            .flat_map(|i| (0..4).map(move |j| (f64::from(i), f64::from(j), usize::from(i >= 2))))
            .collect();
        let fig = Plot::new("")
            .outcomes(grid, &["captured", "missed"])
            .legend(Legend::Off)
            .into_figure()
            .size_px(600, 400);
        let f = fig.frames()[0];
        let p = decode(&fig.to_png().unwrap());
        let at = |x: f64, y: f64| rgb(&p, f.px(x) as u32, f.py(y) as u32);
        let c0 = PALETTE[0];
        let c1 = PALETTE[1];
        assert_eq!(at(0.0, 1.0), (c0.r, c0.g, c0.b));
        assert_eq!(at(3.0, 2.0), (c1.r, c1.g, c1.b));
    }

    #[test]
    fn regress_degenerate_inputs_render_without_panic() {
        let figs = [
            Figure::new("empty"),
            Plot::new("no data").into_figure(),
            Plot::new("one point").line("p", [(1.0, 1.0)]).into_figure(),
            Plot::new("all NaN")
                .line("n", [(f64::NAN, 1.0), (2.0, f64::INFINITY)])
                .into_figure(),
            Plot::new("log of non-positive")
                .log_y()
                .line("z", [(0.0, 0.0), (1.0, -1.0)])
                .into_figure(),
            Plot::new("constant")
                .line("c", [(0.0, 5.0), (1.0, 5.0)])
                .x_range(3.0, 3.0)
                .into_figure(),
        ];
        for f in figs {
            let png = f.to_png().unwrap();
            let p = decode(&png);
            assert!(p.width() > 0 && p.height() > 0);
        }
        // NaN in the middle breaks the line into two polylines.
        let svg = Plot::new("")
            .line(
                "b",
                [
                    (0.0, 0.0),
                    (1.0, 1.0),
                    (f64::NAN, 0.0),
                    (2.0, 0.0),
                    (3.0, 1.0),
                ],
            )
            .into_figure()
            .to_svg();
        assert_eq!(svg.matches("<polyline").count(), 2);
    }

    /// Reference: thinning keeps points at least THIN_PX apart, at most THIN_PX + (largest step
    /// between samples) apart, so the count is bounded by the px length L of the curve (summed
    /// here independently from the raw samples): L/(THIN_PX + step) ≲ kept ≲ L/THIN_PX + 2.
    #[test]
    fn invariant_dense_series_are_thinned() {
        let n = 100_000;
        let pts: Vec<(f64, f64)> = (0..n)
            .map(|i| (f64::from(i), (f64::from(i) * 1e-3).sin()))
            .collect();
        let fig = Plot::new("")
            .line("s", pts.clone())
            .into_figure()
            .size_px(800, 400);
        let f = fig.frames()[0];
        let px: Vec<(f64, f64)> = pts.iter().map(|&(x, y)| (f.px(x), f.py(y))).collect();
        let steps: Vec<f64> = px
            .windows(2)
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .collect();
        let len: f64 = steps.iter().sum();
        let max_step = steps.iter().copied().fold(0.0, f64::max);
        let svg = fig.to_svg();
        let kept = svg
            .lines()
            .find(|l| l.starts_with("<polyline"))
            .unwrap()
            .matches(',')
            .count() as f64;
        assert!(kept <= len / THIN_PX + 2.0, "{kept} kept, L = {len} px");
        assert!(
            kept >= len / (THIN_PX + max_step) - 2.0,
            "{kept} kept, L = {len} px"
        );
        assert!(kept < f64::from(n) / 2.0, "{kept}");
    }
}
