//! Hillshaded relief. Horn's 3 × 3 gradient, with cell sizes `dx`, `dy` and the
//! vertical exaggeration `z`:
//! `∂h/∂x = ((c + 2f + i) − (a + 2d + g)) / (8 dx)`, `∂h/∂y = ((g + 2h + i) − (a + 2b + c)) / (8 dy)`
//! (rows run south, so +y is south); the shade is `max(0, n·s)` for the unit normal
//! `n ∝ (−z ∂h/∂east, −z ∂h/∂north, 1)` and the sun direction
//! `s = (sin α cos β, cos α cos β, sin β)` (azimuth `α` clockwise from north, altitude `β`;
//! equal to `cos θ cos slope + sin θ sin slope cos(α − aspect)`, the form GDAL's
//! `gdaldem hillshade` uses: 315° lights from the north-west). The optional colour ramp maps
//! elevation through a hypsometric tint (green, yellow, brown, white) multiplied by the shade.

use super::Grid;
use crate::{Error, Result};

/// Lighting and colouring.
#[derive(Clone, Debug, PartialEq)]
pub struct Shading {
    /// Sun azimuth in degrees, clockwise from north.
    pub azimuth: f64,
    /// Sun altitude above the horizon in degrees.
    pub altitude: f64,
    /// Vertical exaggeration.
    pub z_factor: f64,
    /// Cell size `(dy, dx)` in the heights' unit.
    pub cell: (f64, f64),
    /// Hypsometric colour ramp (RGB output) instead of gray.
    pub colour: bool,
}

impl Shading {
    /// Check the lighting: azimuth finite, altitude 0 to 90°, vertical exaggeration and
    /// both cell sizes finite and > 0 (a NaN or zero would shade every cell alike).
    pub fn validate(&self) -> Result<()> {
        if !self.azimuth.is_finite() {
            return Err(Error::parameter(
                "azimuth",
                self.azimuth,
                "a finite angle in degrees",
            ));
        }
        if !(0.0..=90.0).contains(&self.altitude) {
            return Err(Error::parameter(
                "altitude",
                self.altitude,
                "0 to 90 degrees",
            ));
        }
        if !(self.z_factor.is_finite() && self.z_factor > 0.0) {
            return Err(Error::parameter(
                "z-factor",
                self.z_factor,
                "a finite exaggeration > 0",
            ));
        }
        for c in [self.cell.0, self.cell.1] {
            if !(c.is_finite() && c > 0.0) {
                return Err(Error::parameter("cell", c, "a finite cell size > 0"));
            }
        }
        Ok(())
    }
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            azimuth: 315.0,
            altitude: 45.0,
            z_factor: 1.0,
            cell: (1.0, 1.0),
            colour: false,
        }
    }
}

/// Hypsometric tint at `t ∈ [0, 1]` (low → high).
fn ramp(t: f64) -> [f64; 3] {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [0.33, 0.55, 0.30]),
        (0.3, [0.62, 0.72, 0.42]),
        (0.55, [0.85, 0.78, 0.52]),
        (0.8, [0.62, 0.47, 0.33]),
        (1.0, [0.97, 0.97, 0.97]),
    ];
    let t = t.clamp(0.0, 1.0);
    for w in STOPS.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let u = (t - t0) / (t1 - t0);
            return [0, 1, 2].map(|k| c0[k] + u * (c1[k] - c0[k]));
        }
    }
    STOPS[4].1
}

/// Shade channel 0 (or the channel mean) of `g`: returns 8-bit samples, 1 channel
/// (gray) or 3 (colour), row-major.
pub fn hillshade(g: &Grid, s: &Shading) -> Vec<u8> {
    let (h, w) = (g.h(), g.w());
    let (alt, az) = (s.altitude.to_radians(), s.azimuth.to_radians());
    let sun = [az.sin() * alt.cos(), az.cos() * alt.cos(), alt.sin()];
    let (lo, hi) = g.range();
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let at = |y: i64, x: i64| {
        g.mean_at(
            y.clamp(0, h as i64 - 1) as usize,
            x.clamp(0, w as i64 - 1) as usize,
        )
    };
    let ch = if s.colour { 3 } else { 1 };
    let mut out = Vec::with_capacity(h * w * ch);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let (a, b, c) = (at(y - 1, x - 1), at(y - 1, x), at(y - 1, x + 1));
            let (d, f) = (at(y, x - 1), at(y, x + 1));
            let (gg, hh, i) = (at(y + 1, x - 1), at(y + 1, x), at(y + 1, x + 1));
            let dzdx = ((c + 2.0 * f + i) - (a + 2.0 * d + gg)) / (8.0 * s.cell.1);
            let dzdy = ((gg + 2.0 * hh + i) - (a + 2.0 * b + c)) / (8.0 * s.cell.0);
            // unit normal (east, north, up) and the sun's direction
            let (ge, gn) = (s.z_factor * dzdx, -s.z_factor * dzdy);
            let norm = (ge * ge + gn * gn + 1.0).sqrt();
            let shade = ((-ge * sun[0] - gn * sun[1] + sun[2]) / norm).max(0.0);
            if s.colour {
                let tint = ramp((at(y, x) - lo) / span);
                // keep some ambient light so that shadowed slopes keep their tint
                let l = 0.35 + 0.65 * shade;
                out.extend(tint.map(|v| (v * l * 255.0).round().clamp(0.0, 255.0) as u8));
            } else {
                out.push((shade * 255.0).round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane facing the sun is brighter than one facing away; a flat grid shades
    /// to `cos θ`.
    #[test]
    fn slopes_facing_the_sun_are_lit() {
        let flat = Grid::zeros(5, 5, 1);
        let s = Shading::default();
        let v = hillshade(&flat, &s);
        let want = (45f64.to_radians().cos() * 255.0).round() as u8;
        assert!(v.iter().all(|&p| p == want));
        // rising towards the east (x): faces west; rising towards the south faces north
        let west = Grid::new(5, 5, 1, (0..25).map(|i| (i % 5) as f64).collect()).unwrap();
        let east = Grid::new(5, 5, 1, (0..25).map(|i| -((i % 5) as f64)).collect()).unwrap();
        // sun in the north-west lights the west-facing slope
        assert!(hillshade(&west, &s)[12] > hillshade(&east, &s)[12]);
        let north = Grid::new(5, 5, 1, (0..25).map(|i| (i / 5) as f64).collect()).unwrap();
        let south = Grid::new(5, 5, 1, (0..25).map(|i| -((i / 5) as f64)).collect()).unwrap();
        assert!(hillshade(&north, &s)[12] > hillshade(&south, &s)[12]);
    }
}
