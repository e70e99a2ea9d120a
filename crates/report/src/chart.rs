//! One chart as an SVG string (plotters, SVG backend): lines, points, filled
//! bands, horizontal reference lines; linear or log-log axes. The data come already
//! decimated (decimate.rs).

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

/// A colour of the report's palette.
pub type Colour = RGBColor;

/// Colours for up to eight series, then they repeat (colour-blind safe, Okabe-Ito).
pub const PALETTE: [Colour; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
    RGBColor(240, 228, 66),
];

pub fn palette(i: usize) -> Colour {
    PALETTE[i % PALETTE.len()]
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    Line,
    /// Filled circles of this radius \[px\].
    Points(u32),
}

/// One named series: one or more pieces (a line is not drawn across pieces).
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub colour: Colour,
    pub style: Style,
    pub pieces: Vec<Vec<(f64, f64)>>,
}

impl Series {
    pub fn line(name: impl Into<String>, colour: Colour, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            colour,
            style: Style::Line,
            pieces: vec![points],
        }
    }

    pub fn points(name: impl Into<String>, colour: Colour, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            colour,
            style: Style::Points(2),
            pieces: vec![points],
        }
    }

    fn finite_points(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.pieces
            .iter()
            .flatten()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    }
}

/// A filled band between `lower` and `upper` at the same abscissae (e.g. +-3 sigma).
#[derive(Clone, Debug)]
pub struct Band {
    pub name: String,
    pub colour: Colour,
    /// (x, lower, upper).
    pub points: Vec<(f64, f64, f64)>,
}

/// One chart.
#[derive(Clone, Debug)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub bands: Vec<Band>,
    /// Horizontal lines: value, label, colour.
    pub hlines: Vec<(f64, String, Colour)>,
    /// Logarithmic axes (the Allan deviation: both; NIS: y).
    pub log_x: bool,
    pub log_y: bool,
    /// The same metres per pixel on both axes (a ground track).
    pub equal_aspect: bool,
    pub size: (u32, u32),
}

impl Chart {
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            bands: Vec::new(),
            hlines: Vec::new(),
            log_x: false,
            log_y: false,
            equal_aspect: false,
            size: (900, 300),
        }
    }

    pub fn with(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Whether there is anything to draw.
    pub fn is_empty(&self) -> bool {
        self.series
            .iter()
            .all(|s| s.finite_points().next().is_none())
            && self.bands.iter().all(|b| b.points.is_empty())
    }

    /// The data's extent, padded; None when there is nothing finite (or nothing
    /// positive on log axes).
    fn extent(&self) -> Option<((f64, f64), (f64, f64))> {
        let ok = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
        let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
        let mut ys = xs;
        let mut add = |x: f64, y: f64| {
            if ok(x, self.log_x) && ok(y, self.log_y) {
                xs = (xs.0.min(x), xs.1.max(x));
                ys = (ys.0.min(y), ys.1.max(y));
            }
        };
        for s in &self.series {
            for &(x, y) in s.finite_points() {
                add(x, y);
            }
        }
        for b in &self.bands {
            for &(x, lo, hi) in &b.points {
                add(x, lo);
                add(x, hi);
            }
        }
        if !xs.0.is_finite() {
            return None;
        }
        for (v, _, _) in &self.hlines {
            if ok(*v, self.log_y) {
                ys = (ys.0.min(*v), ys.1.max(*v));
            }
        }
        let pad = |(a, b): (f64, f64), frac: f64, log: bool| -> (f64, f64) {
            if log {
                let (la, lb) = (a.log10(), b.log10());
                let d = ((lb - la) * frac).max(0.05);
                (10f64.powf(la - d), 10f64.powf(lb + d))
            } else {
                let d = ((b - a) * frac).max(a.abs().max(b.abs()) * 1e-6).max(1e-9);
                (a - d, b + d)
            }
        };
        let (mut xr, mut yr) = (pad(xs, 0.0, self.log_x), pad(ys, 0.05, self.log_y));
        if self.equal_aspect && !self.log_x && !self.log_y {
            // Widen the narrower span so that both axes have the same scale.
            let (w, h) = (f64::from(self.size.0 - 80), f64::from(self.size.1 - 70));
            let scale = ((xr.1 - xr.0) / w).max((yr.1 - yr.0) / h);
            let (cx, cy) = ((xr.0 + xr.1) / 2.0, (yr.0 + yr.1) / 2.0);
            xr = (cx - scale * w / 2.0, cx + scale * w / 2.0);
            yr = (cy - scale * h / 2.0, cy + scale * h / 2.0);
        }
        Some((xr, yr))
    }

    /// The chart as a standalone SVG document.
    pub fn svg(&self) -> Result<String, String> {
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(err)?;
            match self.extent() {
                None => {
                    root.draw(&Text::new(
                        format!("{}: no data", self.title),
                        (20, 20),
                        ("sans-serif", 14),
                    ))
                    .map_err(err)?;
                }
                Some((xr, yr)) => match (self.log_x, self.log_y) {
                    (true, true) => {
                        self.draw(&root, (xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale())?
                    }
                    (false, true) => self.draw(&root, xr.0..xr.1, (yr.0..yr.1).log_scale())?,
                    (true, false) => self.draw(&root, (xr.0..xr.1).log_scale(), yr.0..yr.1)?,
                    (false, false) => self.draw(&root, xr.0..xr.1, yr.0..yr.1)?,
                },
            }
            root.present().map_err(err)?;
        }
        Ok(out)
    }

    fn drawable(&self, x: f64, y: f64) -> bool {
        x.is_finite() && y.is_finite() && (!self.log_x || x > 0.0) && (!self.log_y || y > 0.0)
    }

    fn draw<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend, plotters::coord::Shift>,
        x: X,
        y: Y,
    ) -> Result<(), String>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let mut c = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        c.configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .light_line_style(RGBColor(235, 235, 235))
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(err)?;
        for b in &self.bands {
            let mut poly: Vec<(f64, f64)> = b.points.iter().map(|p| (p.0, p.2)).collect();
            poly.extend(b.points.iter().rev().map(|p| (p.0, p.1)));
            poly.retain(|(x, y)| self.drawable(*x, *y));
            if poly.len() < 3 {
                continue;
            }
            let colour = b.colour;
            let drawn = c
                .draw_series(std::iter::once(Polygon::new(
                    poly,
                    colour.mix(0.18).filled(),
                )))
                .map_err(err)?;
            if !b.name.is_empty() {
                drawn.label(&b.name).legend(move |(x, y)| {
                    Rectangle::new([(x, y - 4), (x + 16, y + 4)], colour.mix(0.3).filled())
                });
            }
        }
        for s in &self.series {
            let colour = s.colour;
            let mut labelled = false;
            for piece in &s.pieces {
                let pts: Vec<(f64, f64)> = piece
                    .iter()
                    .copied()
                    .filter(|(x, y)| self.drawable(*x, *y))
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                let drawn = match s.style {
                    Style::Line => c
                        .draw_series(LineSeries::new(pts, colour.stroke_width(1)))
                        .map_err(err)?,
                    Style::Points(r) => c
                        .draw_series(pts.into_iter().map(|p| Circle::new(p, r, colour.filled())))
                        .map_err(err)?,
                };
                if !labelled && !s.name.is_empty() {
                    labelled = true;
                    drawn.label(&s.name).legend(move |(x, y)| {
                        Rectangle::new([(x, y - 2), (x + 16, y + 2)], colour.filled())
                    });
                }
            }
        }
        for (v, label, colour) in &self.hlines {
            let colour = *colour;
            let (x0, x1) = (c.x_range().start, c.x_range().end);
            c.draw_series(DashedLineSeries::new(
                vec![(x0, *v), (x1, *v)],
                6,
                4,
                colour.stroke_width(1),
            ))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour));
        }
        let named = self.series.iter().any(|s| !s.name.is_empty())
            || self.bands.iter().any(|b| !b.name.is_empty())
            || !self.hlines.is_empty();
        if named {
            c.configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .label_font(("sans-serif", 11))
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}

fn err(e: impl std::fmt::Display) -> String {
    format!("plotting: {e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chart_is_svg_with_its_parts() {
        let c = Chart::new("speed", "t [s]", "m/s")
            .with(Series::line(
                "v",
                palette(0),
                (0..50)
                    .map(|i| (f64::from(i), f64::from(i).sin()))
                    .collect(),
            ))
            .with(Series::points(
                "rejected",
                palette(1),
                vec![(3.0, 0.5), (f64::NAN, 1.0)],
            ));
        let mut c = c;
        c.bands.push(Band {
            name: "+-3 sigma".into(),
            colour: palette(2),
            points: (0..50).map(|i| (f64::from(i), -1.0, 1.0)).collect(),
        });
        c.hlines.push((0.9, "gate".into(), palette(3)));
        let s = c.svg().unwrap();
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        for part in [
            "speed",
            "rejected",
            "gate",
            "+-3 sigma",
            "<polyline",
            "<circle",
            "<polygon",
        ] {
            assert!(s.contains(part), "{part}");
        }
        assert!(!s.contains("NaN"));
    }

    #[test]
    fn log_axes_and_empty_charts() {
        let mut c = Chart::new("Allan deviation", "tau [s]", "deg/h");
        c.log_x = true;
        c.log_y = true;
        c.series.push(Series::line(
            "x",
            palette(0),
            vec![(0.01, 10.0), (1.0, 1.0), (100.0, 0.3), (1000.0, 0.0)],
        ));
        let s = c.svg().unwrap();
        assert!(s.contains("<polyline") && !s.contains("NaN") && !s.contains("inf"));
        let e = Chart::new("nothing", "t", "y").with(Series::line(
            "a",
            palette(0),
            vec![(1.0, f64::NAN)],
        ));
        assert!(e.is_empty());
        assert!(e.svg().unwrap().contains("no data"));
    }
}
