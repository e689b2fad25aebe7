//! Window descriptors for patch matching, from summed-area tables, and the coarse-to-fine
//! candidate search.
//!
//! **Descriptor** of a `q × q` window of a height grid `h` (the channel mean), all
//! window sums read from summed-area tables in O(1):
//! * shape: the window cut into `D × D` blocks (`D` = [`BLOCKS`]), block means `b`,
//!   normalised `z = (b − mean b)/(std b · D)` (offset- and scale-free; `Σ z² = 1`);
//! * slope direction: `w_d (ḡ_x, ḡ_y)/(|∇h|‾ + ε)` with `ḡ` the mean central-difference
//!   gradient and `|∇h|‾` the mean gradient magnitude (a unit vector scaled by how
//!   coherent the window's slopes are: 0 on a cone or a flat, 1 on a plane);
//! * curvature: `w_c s(q ∇²h‾ / (|∇h|‾ + ε))` with `∇²h‾` the mean 5-point Laplacian and
//!   `s(x) = x/(1 + |x|)` (convex and concave windows, ridges and valleys, apart);
//! * steepness `G = |∇h|‾`, compared relatively.
//!
//! **Distance** `Σ (v_t − v_e)² + λ ((G_t − G_e)/(G_t + G_e + ε))²` over the vector `v` of
//! shape, direction and curvature entries.

use super::Grid;

/// Blocks per side of a window's shape part.
pub const BLOCKS: usize = 6;
/// Length of the descriptor: shape, direction (2), curvature, steepness.
pub const LEN: usize = BLOCKS * BLOCKS + 4;
const W_DIR: f32 = 0.5;
const W_CURV: f32 = 0.5;

/// Summed-area tables of the heights, the central-difference gradient, its magnitude
/// and the Laplacian of a grid (indices clamped at the ends), each `(h + 1) × (w + 1)`.
pub struct Tables {
    w: usize,
    h_sum: Vec<f64>,
    gx: Vec<f64>,
    gy: Vec<f64>,
    gm: Vec<f64>,
    lap: Vec<f64>,
}

impl Tables {
    /// The tables of the whole grid.
    pub fn new(g: &Grid) -> Tables {
        Tables::region(g, 0, 0, g.h(), g.w())
    }

    /// The tables of the `h × w` region of `g` with top-left `(y0, x0)`; gradients and
    /// Laplacians take their neighbours from the whole grid (indices clamped at its ends),
    /// so a window's descriptor is the same as from [`Tables::new`] up to rounding.
    pub fn region(g: &Grid, y0: usize, x0: usize, h: usize, w: usize) -> Tables {
        let (gh, gw) = (g.h() as i64, g.w() as i64);
        let at =
            |y: i64, x: i64| g.mean_at(y.clamp(0, gh - 1) as usize, x.clamp(0, gw - 1) as usize);
        let n = (h + 1) * (w + 1);
        let mut t = Tables {
            w,
            h_sum: vec![0.0; n],
            gx: vec![0.0; n],
            gy: vec![0.0; n],
            gm: vec![0.0; n],
            lap: vec![0.0; n],
        };
        let s = w + 1;
        for y in 0..h {
            let (mut rh, mut rx, mut ry, mut rm, mut rl) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for x in 0..w {
                let (yi, xi) = ((y0 + y) as i64, (x0 + x) as i64);
                let c = at(yi, xi);
                let dx = 0.5 * (at(yi, xi + 1) - at(yi, xi - 1));
                let dy = 0.5 * (at(yi + 1, xi) - at(yi - 1, xi));
                let l = at(yi + 1, xi) + at(yi - 1, xi) + at(yi, xi + 1) + at(yi, xi - 1) - 4.0 * c;
                rh += c;
                rx += dx;
                ry += dy;
                rm += (dx * dx + dy * dy).sqrt();
                rl += l;
                let (i, up) = ((y + 1) * s + x + 1, y * s + x + 1);
                t.h_sum[i] = t.h_sum[up] + rh;
                t.gx[i] = t.gx[up] + rx;
                t.gy[i] = t.gy[up] + ry;
                t.gm[i] = t.gm[up] + rm;
                t.lap[i] = t.lap[up] + rl;
            }
        }
        t
    }

    /// The descriptor of one `q × q` window of `g` with top-left `(y0, x0)`, without
    /// tables of the whole grid (memory `O(q²)`: how the output's few windows per level
    /// are described).
    pub fn window_descriptor(g: &Grid, y0: usize, x0: usize, q: usize, out: &mut [f32]) {
        Tables::region(g, y0, x0, q, q).descriptor(0, 0, q, out);
    }

    /// Sum of table `v` over rows `[y0, y1)` × columns `[x0, x1)`.
    #[inline]
    fn sum(&self, v: &[f64], y0: usize, x0: usize, y1: usize, x1: usize) -> f64 {
        let s = self.w + 1;
        v[y1 * s + x1] - v[y0 * s + x1] - v[y1 * s + x0] + v[y0 * s + x0]
    }

    /// The descriptor of the `q × q` window with top-left `(y0, x0)`, which must lie
    /// inside the grid; written to `out` (length [`LEN`]).
    pub fn descriptor(&self, y0: usize, x0: usize, q: usize, out: &mut [f32]) {
        let d = BLOCKS;
        let mut b = [0.0f64; BLOCKS * BLOCKS];
        for i in 0..d {
            let (ya, yb) = (y0 + i * q / d, y0 + ((i + 1) * q / d).max(i * q / d + 1));
            for j in 0..d {
                let (xa, xb) = (x0 + j * q / d, x0 + ((j + 1) * q / d).max(j * q / d + 1));
                let area = ((yb - ya) * (xb - xa)) as f64;
                b[i * d + j] = self.sum(&self.h_sum, ya, xa, yb, xb) / area;
            }
        }
        let n = (d * d) as f64;
        let mean = b.iter().sum::<f64>() / n;
        let var = b.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
        let sd = var.sqrt();
        let inv = if sd > 1e-9 * (1.0 + mean.abs()) {
            1.0 / (sd * d as f64)
        } else {
            0.0
        };
        for (o, v) in out.iter_mut().zip(&b) {
            *o = ((v - mean) * inv) as f32;
        }
        let (y1, x1) = (y0 + q, x0 + q);
        let area = (q * q) as f64;
        let gm = self.sum(&self.gm, y0, x0, y1, x1) / area;
        let gx = self.sum(&self.gx, y0, x0, y1, x1) / area;
        let gy = self.sum(&self.gy, y0, x0, y1, x1) / area;
        let lap = self.sum(&self.lap, y0, x0, y1, x1) / area;
        let eps = 1e-9 * (1.0 + mean.abs());
        let k = d * d;
        out[k] = W_DIR * (gx / (gm + eps)) as f32;
        out[k + 1] = W_DIR * (gy / (gm + eps)) as f32;
        let c = q as f64 * lap / (gm + eps);
        out[k + 2] = W_CURV * (c / (1.0 + c.abs())) as f32;
        out[k + 3] = gm as f32;
    }
}

/// `Σ (v_t − v_e)² + λ ((G_t − G_e)/(G_t + G_e + ε))²` for two descriptors.
#[inline]
pub fn distance(t: &[f32], e: &[f32], lambda: f64) -> f64 {
    let k = LEN - 1;
    let mut s = 0.0f32;
    for (a, b) in t[..k].iter().zip(&e[..k]) {
        let d = a - b;
        s += d * d;
    }
    let (gt, ge) = (t[k] as f64, e[k] as f64);
    let r = (gt - ge) / (gt + ge + 1e-9);
    s as f64 + lambda * r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tilted plane: the shape part has unit norm, the direction is the plane's, the
    /// curvature is zero; the same plane raised and steepened differs only in steepness.
    #[test]
    fn a_plane_has_its_direction_and_no_curvature() {
        let g = Grid::new(20, 20, 1, (0..400).map(|i| 3.0 * (i % 20) as f64).collect()).unwrap();
        let t = Tables::new(&g);
        let mut v = vec![0.0f32; LEN];
        t.descriptor(4, 4, 12, &mut v);
        let k = BLOCKS * BLOCKS;
        let norm: f32 = v[..k].iter().map(|z| z * z).sum();
        assert!((norm - 1.0).abs() < 1e-5, "{norm}");
        assert!((v[k] - W_DIR).abs() < 1e-5 && v[k + 1].abs() < 1e-6);
        assert!(v[k + 2].abs() < 1e-6);
        assert!((v[k + 3] - 3.0).abs() < 1e-5);
        let g2 = Grid::new(
            20,
            20,
            1,
            (0..400).map(|i| 9.0 + 6.0 * (i % 20) as f64).collect(),
        )
        .unwrap();
        let mut v2 = vec![0.0f32; LEN];
        Tables::new(&g2).descriptor(4, 4, 12, &mut v2);
        assert!(v[..LEN - 1]
            .iter()
            .zip(&v2[..LEN - 1])
            .all(|(a, b)| (a - b).abs() < 1e-5));
        let r: f64 = (6.0 - 3.0) / (9.0 + 1e-9);
        assert!((distance(&v, &v2, 1.0) - r * r).abs() < 1e-4);
    }

    /// A window described from its own small tables equals the same window read from
    /// the whole grid's tables (edges included, where neighbours are clamped).
    #[test]
    fn window_descriptor_equals_the_whole_grid_tables() {
        let g = Grid::new(
            30,
            26,
            1,
            (0..780)
                .map(|i| ((i % 26) as f64 * 0.7).sin() * 40.0 + ((i / 26) as f64).powi(2) * 0.3)
                .collect(),
        )
        .unwrap();
        let t = Tables::new(&g);
        for (y0, x0) in [(0, 0), (5, 7), (18, 14)] {
            let (mut a, mut b) = (vec![0.0f32; LEN], vec![0.0f32; LEN]);
            t.descriptor(y0, x0, 12, &mut a);
            Tables::window_descriptor(&g, y0, x0, 12, &mut b);
            for (u, v) in a.iter().zip(&b) {
                assert!((u - v).abs() <= 1e-4 * (1.0 + u.abs()), "{u} {v}");
            }
        }
    }
}
