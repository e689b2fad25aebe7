//! Ray casting of a scene (§10.6, §10.8): the first entry of each pixel ray's t-list is the
//! visible point; its normal is `−∇F/|∇F|` (§10.3.2); shading is Lambert + Phong:
//! `I = k_a + k_d max(0, n·l) + k_s max(0, r·v)^α`.

use super::field::Node;
use super::scene::{Camera, Scene};
use super::tlist::{first_hit, DEFAULT_STEPS};
use crate::mesh::vec3::{add, cross, dot, norm, scale, sub};
use crate::{Error, Result};
use rayon::prelude::*;

pub use crate::mesh::render::Image;

fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / norm(a).max(1e-300))
}

/// A camera looking at the model's bounds from the front-right-top when the scene has none.
pub fn default_camera(node: &Node) -> Camera {
    let (lo, hi) = node.bounds().unwrap_or(([-1.0; 3], [1.0; 3]));
    let c = scale(add(lo, hi), 0.5);
    let r = 0.5 * norm(sub(hi, lo));
    Camera {
        eye: add(c, scale(unit([0.9, 0.7, 1.6]), 3.2 * r)),
        target: c,
        up: [0.0, 1.0, 0.0],
        fov: 40.0,
    }
}

/// Render `scene` at `width × height`.
pub fn render(scene: &Scene, width: usize, height: usize) -> Result<Image> {
    if width == 0 || height == 0 || width * height > 1 << 26 {
        return Err(Error::parameter(
            "image size",
            format!("{width}x{height}"),
            "1..=8192 pixels per side",
        ));
    }
    let node = &scene.root;
    let cam = scene.camera.clone().unwrap_or_else(|| default_camera(node));
    let fwd = unit(sub(cam.target, cam.eye));
    let right = unit(cross(fwd, cam.up));
    let up = cross(right, fwd);
    let light = scene
        .light
        .unwrap_or_else(|| add(cam.eye, add(scale(up, 2.0), scale(right, -1.0))));
    let tan = (cam.fov.to_radians() * 0.5).tan();
    let aspect = width as f64 / height as f64;
    let far = 1e6;
    let bounds = node.bounds();
    let h = bounds
        .map(|(lo, hi)| 1e-4 * norm(sub(hi, lo)))
        .unwrap_or(1e-4)
        .max(1e-9);
    let mut rgb = vec![0u8; width * height * 3];
    rgb.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(y, row)| {
            for x in 0..width {
                let px = ((x as f64 + 0.5) / width as f64 * 2.0 - 1.0) * tan * aspect;
                let py = (1.0 - (y as f64 + 0.5) / height as f64 * 2.0) * tan;
                let d = unit(add(fwd, add(scale(right, px), scale(up, py))));
                let bg = [(40.0 + 30.0 * (1.0 - py)) as u8, 44, 56];
                let color = match first_hit(node, cam.eye, d, 1e-9, far, DEFAULT_STEPS) {
                    None => bg,
                    Some(t) => {
                        let p = add(cam.eye, scale(d, t));
                        let mut n = node.normal(p, h).unwrap_or(scale(d, -1.0));
                        if dot(n, d) > 0.0 {
                            n = scale(n, -1.0);
                        }
                        let l = unit(sub(light, p));
                        let v = scale(d, -1.0);
                        let diff = dot(n, l).max(0.0);
                        let r = sub(scale(n, 2.0 * dot(n, l)), l);
                        let spec = if diff > 0.0 {
                            dot(r, v).max(0.0).powf(32.0)
                        } else {
                            0.0
                        };
                        let base = [0.85, 0.62, 0.38];
                        let mut c = [0u8; 3];
                        for i in 0..3 {
                            let s = 0.12 * base[i] + 0.78 * diff * base[i] + 0.45 * spec;
                            c[i] = (255.0 * s.clamp(0.0, 1.0)).round() as u8;
                        }
                        c
                    }
                };
                row[3 * x..3 * x + 3].copy_from_slice(&color);
            }
        });
    Ok(Image { width, height, rgb })
}

/// Encode an image as PNG bytes.
pub fn png_bytes(img: &Image) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, img.width as u32, img.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| Error::format(format!("PNG: {e}"), "encodable image"))?;
        w.write_image_data(&img.rgb)
            .map_err(|e| Error::format(format!("PNG: {e}"), "encodable image"))?;
    }
    Ok(out)
}
