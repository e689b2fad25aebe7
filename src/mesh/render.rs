//! A small software rasteriser for looking at meshes: orthographic camera from an azimuth and
//! elevation (about the +y axis, or +z with `z_up`), z-buffer, Gouraud shading with angle-weighted vertex normals (two-sided
//! headlight plus ambient), optional wireframe, optional back-face tint and supersampling
//! (drawn at `k×` the size and box-filtered down), written as an RGB PNG. [`encode_rgb`] is the
//! crate's one PNG encoder (also used by the 2D canvas of curve pictures).

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
    /// Base colour of faces seen from behind (geometric normal away from the camera); `None`
    /// shades both sides alike.
    pub back_color: Option<[u8; 3]>,
    /// Anti-aliasing: draw at `supersample ×` the size and average `supersample²` pixels into
    /// one (1 to 4; 1 = none).
    pub supersample: usize,
}

/// Base colour of the shaded model (front faces).
pub const FRONT_COLOR: [u8; 3] = [150, 180, 215];
/// Background colour of the pictures.
pub const BACKGROUND: [u8; 3] = [245, 245, 248];

impl Default for Options {
    fn default() -> Self {
        Options {
            width: 800,
            height: 600,
            azimuth: 30.0,
            elevation: 20.0,
            wireframe: false,
            z_up: false,
            back_color: None,
            supersample: 1,
        }
    }
}

/// An 8-bit RGB image, row-major (rows top to bottom), 3 bytes per pixel: what the mesh
/// and the solid renderers draw.
#[derive(Clone, Debug)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

/// Render `mesh` to an RGB image.
pub fn render(mesh: &Mesh, o: &Options) -> Result<Image> {
    let (w, h) = check(o)?;
    let mut cv = Canvas::new(w, h);
    let Some((lo, hi)) = mesh.bounding_box() else {
        return Ok(downsample(w, h, cv.rgb, o.supersample));
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
    let rgb_f = |c: [u8; 3]| c.map(|x| x as f64);
    let front_base = rgb_f(FRONT_COLOR);
    let back_base = o.back_color.map(rgb_f).unwrap_or(front_base);
    let tri = mesh.triangulated();
    for t in tri.faces() {
        let v = [0, 1, 2].map(|k| t[k] as usize);
        // facing: is the geometric normal (b − a) × (c − a) towards the eye?
        let p = |k: usize| mesh.positions[v[k]];
        let gn = vec3::cross(vec3::sub(p(1), p(0)), vec3::sub(p(2), p(0)));
        let base = if vec3::dot(gn, eye) >= 0.0 {
            front_base
        } else {
            back_base
        };
        cv.fill_triangle(v.map(|i| screen[i]), v.map(|i| shade(normals[i])), base);
    }
    if o.wireframe {
        let bias = 1e-3 * radius;
        for f in mesh.faces() {
            for i in 0..f.len() {
                let (p, q) = (screen[f[i] as usize], screen[f[(i + 1) % f.len()] as usize]);
                cv.line(p, q, bias);
            }
        }
    }
    Ok(downsample(w, h, cv.rgb, o.supersample))
}

/// Check the picture options; the size drawn (supersampled).
fn check(o: &Options) -> Result<(usize, usize)> {
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
    if !(1..=4).contains(&o.supersample) {
        return Err(Error::parameter("supersample", o.supersample, "1 to 4"));
    }
    let (w, h) = (o.width * o.supersample, o.height * o.supersample);
    if w > 16384 || h > 16384 {
        return Err(Error::parameter(
            "supersampled image size",
            format!("{w}x{h}"),
            "at most 16384 pixels per side",
        ));
    }
    Ok((w, h))
}

/// The picture being drawn: RGB over the background and a z-buffer (larger z = nearer).
struct Canvas {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
    zbuf: Vec<f64>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        let mut rgb = vec![0u8; w * h * 3];
        for px in rgb.chunks_mut(3) {
            px.copy_from_slice(&BACKGROUND);
        }
        Canvas {
            w,
            h,
            rgb,
            zbuf: vec![f64::NEG_INFINITY; w * h],
        }
    }

    /// Fill the screen triangle `[a, b, c]` (x, y, z) at pixel centres, Gouraud-shading
    /// `base` by the corner shades `s` with barycentric weights `l0, l1, l2` (`l0` at `a`),
    /// where nearer than the z-buffer.
    fn fill_triangle(&mut self, [a, b, c]: [[f64; 3]; 3], s: [f64; 3], base: [f64; 3]) {
        let (w, h) = (self.w, self.h);
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area.abs() < 1e-12 {
            return;
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
                if z > self.zbuf[i] {
                    self.zbuf[i] = z;
                    let sh = l0 * s[0] + l1 * s[1] + l2 * s[2];
                    for (o, b) in self.rgb[3 * i..3 * i + 3].iter_mut().zip(base) {
                        *o = (b * sh).clamp(0.0, 255.0) as u8;
                    }
                }
            }
        }
    }

    /// Draw the edge `p → q` in dark ink where it is within `bias` of the nearest surface.
    fn line(&mut self, p: [f64; 3], q: [f64; 3], bias: f64) {
        let (w, h) = (self.w, self.h);
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
            if z + bias >= self.zbuf[i] {
                self.rgb[3 * i..3 * i + 3].copy_from_slice(&[40, 40, 60]);
            }
        }
    }
}

/// Average `k × k` blocks of a `w × h` RGB picture into one pixel (box filter).
fn downsample(w: usize, h: usize, rgb: Vec<u8>, k: usize) -> Image {
    if k == 1 {
        return Image {
            width: w,
            height: h,
            rgb,
        };
    }
    let (ow, oh) = (w / k, h / k);
    let mut out = vec![0u8; ow * oh * 3];
    for y in 0..oh {
        for x in 0..ow {
            let mut acc = [0u32; 3];
            for dy in 0..k {
                let row = (y * k + dy) * w + x * k;
                for px in rgb[3 * row..3 * (row + k)].chunks(3) {
                    for c in 0..3 {
                        acc[c] += px[c] as u32;
                    }
                }
            }
            let n = (k * k) as u32;
            for c in 0..3 {
                out[3 * (y * ow + x) + c] = ((acc[c] + n / 2) / n) as u8;
            }
        }
    }
    Image {
        width: ow,
        height: oh,
        rgb: out,
    }
}

/// Render and encode as PNG.
pub fn render_png(mesh: &Mesh, o: &Options) -> Result<Vec<u8>> {
    encode_png(&render(mesh, o)?)
}

/// Encode an RGB image as PNG.
pub fn encode_png(img: &Image) -> Result<Vec<u8>> {
    encode_rgb(img.width, img.height, &img.rgb)
}

/// Encode 8-bit RGB pixels (row-major from the top-left, `3 · width · height` bytes) as PNG
/// with the `png` crate's default compression. The crate's one PNG encoder.
pub fn encode_rgb(width: usize, height: usize, rgb: &[u8]) -> Result<Vec<u8>> {
    let (w, h) = (u32::try_from(width), u32::try_from(height));
    let (Ok(w), Ok(h)) = (w, h) else {
        return Err(Error::parameter(
            "image size",
            format!("{width}x{height}"),
            "sides below 2³²",
        ));
    };
    if width.checked_mul(height).and_then(|n| n.checked_mul(3)) != Some(rgb.len()) {
        return Err(Error::parameter(
            "RGB bytes",
            rgb.len(),
            "3 · width · height bytes",
        ));
    }
    let png_err = |e: png::EncodingError| Error::Io(std::io::Error::other(e.to_string()));
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(png_err)?;
        wr.write_image_data(rgb).map_err(png_err)?;
    }
    Ok(out)
}
