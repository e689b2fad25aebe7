//! Pictures of a curve with its control polygon and knot points, as SVG text or PNG.
//! Points of any dimension are drawn by their first two coordinates.

use crate::surface::raster::Canvas;
use crate::Result;
use std::fmt::Write;

/// What to draw, in model coordinates.
#[derive(Debug, Clone, Default)]
pub struct PlotData {
    /// The sampled curve.
    pub curve: Vec<[f64; 2]>,
    /// The control polygon.
    pub polygon: Vec<[f64; 2]>,
    /// Curve points at the knots of the valid range.
    pub knots: Vec<[f64; 2]>,
}

const CURVE: [u8; 3] = [31, 94, 180];
const POLYGON: [u8; 3] = [150, 150, 150];
const KNOT: [u8; 3] = [214, 80, 40];

/// Model-to-image mapping: uniform scale, y up, 6% margin.
struct View {
    s: f64,
    ox: f64,
    oy: f64,
    h: f64,
}

impl View {
    fn new(d: &PlotData, w: usize, h: usize) -> View {
        let all = d.curve.iter().chain(&d.polygon).chain(&d.knots);
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in all {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
        if x0 > x1 {
            (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
        }
        let (mw, mh) = (w as f64 * 0.88, h as f64 * 0.88);
        let s = (mw / (x1 - x0).max(1e-300)).min(mh / (y1 - y0).max(1e-300));
        let s = if s.is_finite() { s } else { 1.0 };
        let ox = (w as f64 - s * (x1 - x0)) / 2.0 - s * x0;
        let oy = (h as f64 - s * (y1 - y0)) / 2.0 - s * y0;
        View {
            s,
            ox,
            oy,
            h: h as f64,
        }
    }
    fn map(&self, p: [f64; 2]) -> [f64; 2] {
        [self.ox + self.s * p[0], self.h - (self.oy + self.s * p[1])]
    }
}

/// An SVG document (plain text) of the plot.
pub fn svg(d: &PlotData, width: usize, height: usize) -> String {
    let v = View::new(d, width, height);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let path = |pts: &[[f64; 2]]| -> String {
        pts.iter()
            .map(|p| {
                let q = v.map(*p);
                format!("{:.3},{:.3}", q[0], q[1])
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let rgb = |c: [u8; 3]| format!("rgb({},{},{})", c[0], c[1], c[2]);
    let _ = writeln!(
        s,
        r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.2" stroke-dasharray="5,3"/>"#,
        path(&d.polygon),
        rgb(POLYGON)
    );
    for p in &d.polygon {
        let q = v.map(*p);
        let _ = writeln!(
            s,
            r#"<circle cx="{:.3}" cy="{:.3}" r="3.5" fill="{}"/>"#,
            q[0],
            q[1],
            rgb(POLYGON)
        );
    }
    let _ = writeln!(
        s,
        r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="2.5" stroke-linejoin="round"/>"#,
        path(&d.curve),
        rgb(CURVE)
    );
    for p in &d.knots {
        let q = v.map(*p);
        let _ = writeln!(
            s,
            r#"<circle cx="{:.3}" cy="{:.3}" r="3" fill="{}"/>"#,
            q[0],
            q[1],
            rgb(KNOT)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The same plot rasterised to a PNG.
pub fn png(d: &PlotData, width: usize, height: usize) -> Result<Vec<u8>> {
    let v = View::new(d, width, height);
    let mut c = Canvas::new(width, height, [255, 255, 255])?;
    let poly: Vec<[f64; 2]> = d.polygon.iter().map(|p| v.map(*p)).collect();
    c.polyline(&poly, 1.2, POLYGON);
    for p in &poly {
        c.disc(p[0], p[1], 3.5, POLYGON);
    }
    let curve: Vec<[f64; 2]> = d.curve.iter().map(|p| v.map(*p)).collect();
    c.polyline(&curve, 2.5, CURVE);
    for p in &d.knots {
        let q = v.map(*p);
        c.disc(q[0], q[1], 3.0, KNOT);
    }
    c.to_png()
}
