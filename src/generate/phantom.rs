//! A 3-D Shepp–Logan-style head phantom: a sum of ten ellipsoids with the contrasts of
//! Toft's "modified Shepp–Logan" (so that brain structures are visible), positioned as
//! in Kak & Slaney's 3-D extension. Coordinates run over [−1, 1] on every axis; each
//! ellipsoid adds its value inside `((x−x0)/a)² + ((y−y0)/b)² + ((z−z0)/c)² ≤ 1` after
//! rotating (x, y) by −φ about the z axis. Values lie in [0, 1].

use super::Field;
use crate::io::DataKind;

/// One ellipsoid: added `value`, semi-axes `(a, b, c)`, centre `(x0, y0, z0)`, rotation
/// `phi` (degrees) about the z axis.
struct Ellipsoid {
    value: f64,
    axes: [f64; 3],
    centre: [f64; 3],
    phi: f64,
}

/// The ellipsoid of `value`, semi-axes `(a, b, c)`, centre `(x0, y0, z0)`, rotation
/// `phi` (degrees).
const fn e(value: f64, axes: [f64; 3], centre: [f64; 3], phi: f64) -> Ellipsoid {
    Ellipsoid {
        value,
        axes,
        centre,
        phi,
    }
}

const ELLIPSOIDS: [Ellipsoid; 10] = [
    e(1.0, [0.69, 0.92, 0.81], [0.0, 0.0, 0.0], 0.0),
    e(-0.8, [0.6624, 0.874, 0.78], [0.0, -0.0184, 0.0], 0.0),
    e(-0.2, [0.11, 0.31, 0.22], [0.22, 0.0, 0.0], -18.0),
    e(-0.2, [0.16, 0.41, 0.28], [-0.22, 0.0, 0.0], 18.0),
    e(0.1, [0.21, 0.25, 0.41], [0.0, 0.35, -0.15], 0.0),
    e(0.1, [0.046, 0.046, 0.05], [0.0, 0.1, 0.25], 0.0),
    e(0.1, [0.046, 0.046, 0.05], [0.0, -0.1, 0.25], 0.0),
    e(0.1, [0.046, 0.023, 0.05], [-0.08, -0.605, 0.0], 0.0),
    e(0.1, [0.023, 0.023, 0.02], [0.0, -0.606, 0.0], 0.0),
    e(0.1, [0.023, 0.046, 0.02], [0.06, -0.605, 0.0], 0.0),
];

/// The phantom sampled at voxel centres of a `[D, H, W]` grid; y points up (row 0 is
/// y = +1), z = −1 at slice 0.
pub fn shepp_logan(d: usize, h: usize, w: usize) -> Field {
    let coord = |i: usize, n: usize| (2.0 * i as f64 + 1.0) / n as f64 - 1.0;
    let mut data = Vec::with_capacity(d * h * w);
    let rot: Vec<(f64, f64)> = ELLIPSOIDS
        .iter()
        .map(|e| {
            let phi = e.phi.to_radians();
            (phi.cos(), phi.sin())
        })
        .collect();
    for k in 0..d {
        let z = coord(k, d);
        for i in 0..h {
            let y = -coord(i, h);
            for j in 0..w {
                let x = coord(j, w);
                let mut v = 0.0;
                for (e, &(c, s)) in ELLIPSOIDS.iter().zip(&rot) {
                    let (dx, dy, dz) = (x - e.centre[0], y - e.centre[1], z - e.centre[2]);
                    let (u, t) = (c * dx + s * dy, -s * dx + c * dy);
                    let [a, b, cz] = e.axes;
                    if (u / a).powi(2) + (t / b).powi(2) + (dz / cz).powi(2) <= 1.0 {
                        v += e.value;
                    }
                }
                data.push(v.clamp(0.0, 1.0));
            }
        }
    }
    Field::new(&[d, h, w], 1, data, DataKind::Volume)
}
