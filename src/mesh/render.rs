//! A small software rasteriser for looking at meshes: orthographic camera from an azimuth and
//! elevation (about the +y axis, or +z with `z_up`), z-buffer, Gouraud shading with angle-weighted vertex normals (two-sided
//! headlight plus ambient), optional wireframe, written as an RGB PNG.

use super::normals::{vertex_normals, Weighting};
use super::{vec3, Mesh};
use crate::{Error, Result};

/// Picture options.
#[derive(Clone, Debug)]
pub struct Options {
    pub width: usize,
    pub height: usize,
    /// Camera azimuth around +z, degrees.
    pub azimuth: f64,
    /// Camera elevation above the xy-plane, degrees.
    pub elevation: f64,
    pub wireframe: bool,
    /// The model's up axis is +z (default: +y, as in most OBJ/PLY files).
    pub z_up: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            width: 800,
            height: 600,
            azimuth: 30.0,
            elevation: 20.0,
            wireframe: false,
            z_up: false,
        }
    }
}

/// An RGB image, row-major, 3 bytes per pixel.
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

/// Render `mesh` to an RGB image.
pub fn render(mesh: &Mesh, o: &Options) -> Result<Image> {
    if o.width == 0 || o.height == 0 || o.width > 16384 || o.height > 16384 {
        return Err(Error::parameter(
            "image size",
            format!("{}x{}", o.width, o.height),
            "1 to 16384 pixels per side",
        ));
    }
    if !(o.azimuth.is_finite() && o.elevation.is_finite()) {
        return Err(Error::parameter(
            "view",
            format!("{},{}", o.azimuth, o.elevation),
            "finite angles",
        ));
    }
    let (w, h) = (o.width, o.height);
    let mut rgb = vec![0u8; w * h * 3];
    for px in rgb.chunks_mut(3) {
        px.copy_from_slice(&[245, 245, 248]);
    }
    let Some((lo, hi)) = mesh.bounding_box() else {
        return Ok(Image {
            width: w,
            height: h,
            rgb,
        });
    };
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = 0.5 * vec3::norm(vec3::sub(hi, lo)).max(1e-300);
    let (az, el) = (o.azimuth.to_radians(), o.elevation.to_radians());
    // camera frame: view direction d points from the camera to the scene
    let (eye, up0) = if o.z_up {
        (
            [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()],
            [0.0, 0.0, 1.0],
        )
    } else {
        (
            [el.cos() * az.sin(), el.sin(), el.cos() * az.cos()],
            [0.0, 1.0, 0.0],
        )
    };
    let d = vec3::scale(eye, -1.0);
    let up0 = if el.cos().abs() < 1e-6 {
        vec3::cross(up0, [1.0, 0.0, 0.0])
    } else {
        up0
    };
    let right = vec3::normalized(vec3::cross(d, up0));
    let up = vec3::cross(right, d);
    let scale = 0.95 * (w.min(h) as f64) / (2.0 * radius);
    let project = |p: [f64; 3]| {
        let q = vec3::sub(p, centre);
        [
            w as f64 / 2.0 + scale * vec3::dot(q, right),
            h as f64 / 2.0 - scale * vec3::dot(q, up),
            vec3::dot(q, eye), // larger = nearer
        ]
    };
    let screen: Vec<[f64; 3]> = mesh.positions.iter().map(|&p| project(p)).collect();
    let normals = vertex_normals(mesh, Weighting::Angle);
    let shade = |n: [f64; 3]| {
        let l = vec3::dot(n, eye).abs();
        0.25 + 0.75 * l
    };
    let mut zbuf = vec![f64::NEG_INFINITY; w * h];
    let base = [150.0, 180.0, 215.0];
    let tri = mesh.triangulated();
    for t in tri.faces() {
        let (a, b, c) = (
            screen[t[0] as usize],
            screen[t[1] as usize],
            screen[t[2] as usize],
        );
        let (sa, sb, sc) = (
            shade(normals[t[0] as usize]),
            shade(normals[t[1] as usize]),
            shade(normals[t[2] as usize]),
        );
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area.abs() < 1e-12 {
            continue;
        }
        let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
        let x1 = (a[0].max(b[0]).max(c[0]).ceil() as usize).min(w - 1);
        let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
        let y1 = (a[1].max(b[1]).max(c[1]).ceil() as usize).min(h - 1);
        for y in y0..=y1 {
            let py = y as f64 + 0.5;
            for x in x0..=x1 {
                let px = x as f64 + 0.5;
                let l0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / area;
                let l1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / area;
                let l2 = 1.0 - l0 - l1;
                if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                    continue;
                }
                let z = l0 * a[2] + l1 * b[2] + l2 * c[2];
                let i = y * w + x;
                if z > zbuf[i] {
                    zbuf[i] = z;
                    let s = l0 * sa + l1 * sb + l2 * sc;
                    for k in 0..3 {
                        rgb[3 * i + k] = (base[k] * s).clamp(0.0, 255.0) as u8;
                    }
                }
            }
        }
    }
    if o.wireframe {
        let bias = 1e-3 * radius;
        for f in mesh.faces() {
            for i in 0..f.len() {
                let (p, q) = (screen[f[i] as usize], screen[f[(i + 1) % f.len()] as usize]);
                let steps = ((q[0] - p[0]).abs().max((q[1] - p[1]).abs()).ceil() as usize).max(1);
                for s in 0..=steps {
                    let t = s as f64 / steps as f64;
                    let x = p[0] + t * (q[0] - p[0]);
                    let y = p[1] + t * (q[1] - p[1]);
                    let z = p[2] + t * (q[2] - p[2]);
                    if x < 0.0 || y < 0.0 || x >= w as f64 || y >= h as f64 {
                        continue;
                    }
                    let i = y as usize * w + x as usize;
                    if z + bias >= zbuf[i] {
                        rgb[3 * i..3 * i + 3].copy_from_slice(&[40, 40, 60]);
                    }
                }
            }
        }
    }
    Ok(Image {
        width: w,
        height: h,
        rgb,
    })
}

/// Render and encode as PNG.
pub fn render_png(mesh: &Mesh, o: &Options) -> Result<Vec<u8>> {
    let img = render(mesh, o)?;
    Ok(encode_png(&img))
}

/// Encode an RGB image as PNG (the `png` crate, default compression).
pub fn encode_png(img: &Image) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, img.width as u32, img.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        // writing to a Vec cannot fail and the sizes match by construction
        let mut w = enc.write_header().expect("in-memory PNG header");
        w.write_image_data(&img.rgb).expect("in-memory PNG data");
    }
    out
}
