//! A shaded preview of a mesh: orthographic camera on a sphere around the model (azimuth,
//! elevation), z-buffer, normals interpolated across each triangle, Lambert lighting from a key
//! and a fill light plus ambient; back faces in a warmer tint. Rendered at 2× and box-filtered
//! down for anti-aliasing.

// Index loops follow the formulas of the notes (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

use super::mesh::Mesh;
use super::raster::Canvas;
use super::{cross, dot, normalize, sub};
use crate::Result;

/// Camera and picture settings.
#[derive(Debug, Clone, Copy)]
pub struct View {
    pub width: usize,
    pub height: usize,
    /// Degrees about the z axis.
    pub azimuth: f64,
    /// Degrees above the xy plane.
    pub elevation: f64,
}

impl Default for View {
    fn default() -> Self {
        View {
            width: 640,
            height: 480,
            azimuth: 35.0,
            elevation: 25.0,
        }
    }
}

/// Largest picture side for a render (it is drawn at twice this size before filtering).
pub const MAX_RENDER_SIDE: usize = 2_048;

/// Render `m` to an RGB canvas.
pub fn render(m: &Mesh, view: View) -> Result<Canvas> {
    for (what, v) in [("render width", view.width), ("render height", view.height)] {
        if v == 0 || v > MAX_RENDER_SIDE {
            return Err(crate::Error::LimitsExceeded {
                what,
                requested: v as u64,
                limit: MAX_RENDER_SIDE as u64,
            });
        }
    }
    if let Some(bad) = m
        .faces
        .iter()
        .flatten()
        .find(|&&i| i as usize >= m.positions.len())
    {
        return Err(crate::Error::parameter(
            "face vertex index",
            bad,
            "an index below the number of vertices",
        ));
    }
    let ss = 2;
    let (w, h) = (view.width * ss, view.height * ss);
    let mut big = Canvas::new(w, h, [255, 255, 255])?;
    // camera basis: forward f points from the camera to the model
    let (az, el) = (view.azimuth.to_radians(), view.elevation.to_radians());
    let eye = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
    let f = [-eye[0], -eye[1], -eye[2]];
    let world_up = if el.cos().abs() < 1e-6 {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let right = normalize(cross(f, world_up)).unwrap_or([1.0, 0.0, 0.0]);
    let up = cross(right, f);
    let proj: Vec<[f64; 3]> = m
        .positions
        .iter()
        .map(|p| [dot(*p, right), dot(*p, up), dot(*p, eye)])
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &proj {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let s = (w as f64 * 0.9 / (x1 - x0).max(1e-300)).min(h as f64 * 0.9 / (y1 - y0).max(1e-300));
    let s = if s.is_finite() && s > 0.0 { s } else { 1.0 };
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let screen: Vec<[f64; 3]> = proj
        .iter()
        .map(|p| {
            [
                w as f64 / 2.0 + s * (p[0] - cx),
                h as f64 / 2.0 - s * (p[1] - cy),
                p[2],
            ]
        })
        .collect();
    let mut depth = vec![f64::NEG_INFINITY; w * h];
    let key = normalize([
        0.4 * right[0] + 0.7 * up[0] + eye[0],
        0.4 * right[1] + 0.7 * up[1] + eye[1],
        0.4 * right[2] + 0.7 * up[2] + eye[2],
    ])
    .unwrap();
    let fill = normalize([
        -0.6 * right[0] + eye[0],
        -0.6 * right[1] + eye[1],
        -0.6 * right[2] + eye[2],
    ])
    .unwrap();
    for face in &m.faces {
        for t in 1..face.len() - 1 {
            let ids = [face[0] as usize, face[t] as usize, face[t + 1] as usize];
            let (a, b, c) = (screen[ids[0]], screen[ids[1]], screen[ids[2]]);
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if area.abs() < 1e-12 {
                continue;
            }
            // facing: geometric normal towards the eye?
            let gn = cross(
                sub(m.positions[ids[1]], m.positions[ids[0]]),
                sub(m.positions[ids[2]], m.positions[ids[0]]),
            );
            let front = dot(gn, eye) >= 0.0;
            let xmin = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
            let xmax = (a[0].max(b[0]).max(c[0]).ceil() as isize).min(w as isize - 1);
            let ymin = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
            let ymax = (a[1].max(b[1]).max(c[1]).ceil() as isize).min(h as isize - 1);
            if xmax < 0 || ymax < 0 {
                continue;
            }
            for y in ymin..=ymax as usize {
                for x in xmin..=xmax as usize {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let l0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / area;
                    let l1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / area;
                    let l2 = 1.0 - l0 - l1;
                    if l0 < -1e-9 || l1 < -1e-9 || l2 < -1e-9 {
                        continue;
                    }
                    let z = l0 * a[2] + l1 * b[2] + l2 * c[2];
                    let k = y * w + x;
                    if z <= depth[k] {
                        continue;
                    }
                    depth[k] = z;
                    let (n0, n1, n2) = (m.normals[ids[0]], m.normals[ids[1]], m.normals[ids[2]]);
                    let mut n = [
                        l0 * n0[0] + l1 * n1[0] + l2 * n2[0],
                        l0 * n0[1] + l1 * n1[1] + l2 * n2[1],
                        l0 * n0[2] + l1 * n1[2] + l2 * n2[2],
                    ];
                    n = normalize(n).unwrap_or(n);
                    if dot(n, eye) < 0.0 {
                        n = [-n[0], -n[1], -n[2]];
                    }
                    let lum = 0.18 + 0.62 * dot(n, key).max(0.0) + 0.25 * dot(n, fill).max(0.0);
                    let base = if front {
                        [120.0, 160.0, 215.0]
                    } else {
                        [225.0, 170.0, 110.0]
                    };
                    let col = [
                        (base[0] * lum).min(255.0) as u8,
                        (base[1] * lum).min(255.0) as u8,
                        (base[2] * lum).min(255.0) as u8,
                    ];
                    big.set(x, y, col);
                }
            }
        }
    }
    // 2× box filter down
    let mut out = Canvas::new(view.width, view.height, [255, 255, 255])?;
    for y in 0..view.height {
        for x in 0..view.width {
            let mut acc = [0u32; 3];
            for dy in 0..ss {
                for dx in 0..ss {
                    let i = ((y * ss + dy) * w + x * ss + dx) * 3;
                    for c in 0..3 {
                        acc[c] += big.rgb[i + c] as u32;
                    }
                }
            }
            let n = (ss * ss) as u32;
            out.set(
                x,
                y,
                [(acc[0] / n) as u8, (acc[1] / n) as u8, (acc[2] / n) as u8],
            );
        }
    }
    Ok(out)
}
