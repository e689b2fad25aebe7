//! A tiny RGB canvas for 2D pictures: anti-aliased thick lines and discs (curve plots), encoded
//! with the crate's one PNG encoder, [`crate::mesh::render::encode_rgb`].

// Index loops follow the formulas of the notes (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use crate::{Error, Result};

/// An RGB image with 8 bits per channel, row-major from the top-left corner.
#[derive(Debug, Clone)]
pub struct Canvas {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

/// Largest accepted side of a preview image.
pub const MAX_SIDE: usize = 8_192;

impl Canvas {
    /// A canvas filled with `bg`.
    pub fn new(width: usize, height: usize, bg: [u8; 3]) -> Result<Self> {
        for (what, v) in [("image width", width), ("image height", height)] {
            if v == 0 || v > MAX_SIDE {
                return Err(Error::LimitsExceeded {
                    what,
                    requested: v as u64,
                    limit: MAX_SIDE as u64,
                });
            }
        }
        let mut rgb = Vec::with_capacity(width * height * 3);
        for _ in 0..width * height {
            rgb.extend_from_slice(&bg);
        }
        Ok(Canvas { width, height, rgb })
    }

    /// Blend `color` into pixel `(x, y)` with coverage `a ∈ [0, 1]`.
    #[inline]
    pub fn blend(&mut self, x: isize, y: isize, color: [u8; 3], a: f64) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height || a <= 0.0 {
            return;
        }
        let a = a.min(1.0);
        let i = (y as usize * self.width + x as usize) * 3;
        for c in 0..3 {
            let old = self.rgb[i + c] as f64;
            self.rgb[i + c] = (old + (color[c] as f64 - old) * a).round() as u8;
        }
    }

    /// Set pixel `(x, y)`.
    #[inline]
    pub fn set(&mut self, x: usize, y: usize, color: [u8; 3]) {
        let i = (y * self.width + x) * 3;
        self.rgb[i..i + 3].copy_from_slice(&color);
    }

    /// An anti-aliased disc of radius `r` (coverage from the distance to the rim).
    pub fn disc(&mut self, cx: f64, cy: f64, r: f64, color: [u8; 3]) {
        let (x0, x1) = (
            (cx - r - 1.0).floor() as isize,
            (cx + r + 1.0).ceil() as isize,
        );
        let (y0, y1) = (
            (cy - r - 1.0).floor() as isize,
            (cy + r + 1.0).ceil() as isize,
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
                self.blend(x, y, color, (r + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }

    /// An anti-aliased segment of width `w`: coverage from the distance to the segment.
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], w: f64, color: [u8; 3]) {
        let r = w / 2.0;
        let (x0, x1) = (a[0].min(b[0]) - r - 1.0, a[0].max(b[0]) + r + 1.0);
        let (y0, y1) = (a[1].min(b[1]) - r - 1.0, a[1].max(b[1]) + r + 1.0);
        let d = [b[0] - a[0], b[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        for y in y0.floor() as isize..=y1.ceil() as isize {
            for x in x0.floor() as isize..=x1.ceil() as isize {
                let p = [x as f64 + 0.5 - a[0], y as f64 + 0.5 - a[1]];
                let t = if len2 > 0.0 {
                    ((p[0] * d[0] + p[1] * d[1]) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let dist = ((p[0] - t * d[0]).powi(2) + (p[1] - t * d[1]).powi(2)).sqrt();
                let cov = (r + 0.5 - dist).clamp(0.0, 1.0);
                self.blend(x, y, color, cov);
            }
        }
    }

    /// A polyline through `pts`.
    pub fn polyline(&mut self, pts: &[[f64; 2]], w: f64, color: [u8; 3]) {
        for s in pts.windows(2) {
            self.line(s[0], s[1], w, color);
        }
    }

    /// Encode as an 8-bit RGB PNG.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        crate::mesh::render::encode_rgb(self.width, self.height, &self.rgb)
    }
}
