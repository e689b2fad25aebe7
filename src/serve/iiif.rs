//! The IIIF Image API 3.0 request grammar (`{region}/{size}/{rotation}/{quality}.{format}`)
//! and its resolution against an image of `W × H` pixels into a pixel box and an output
//! size, as the specification's sections 4.1 to 4.5 define them:
//!
//! ```text
//! region   full | square | x,y,w,h | pct:x,y,w,h        (cropped to the image; empty → 400)
//! size     max | w, | ,h | pct:n | w,h | !w,h          (a leading ^ asks for upscaling: refused)
//! rotation n | !n                                      (n ∈ {0, 90, 180, 270}; ! mirrors first)
//! quality  default | color | gray | bitonal
//! format   jpg | png
//! ```
//!
//! `pct:` regions round each edge to the nearest pixel (`x0 = round(px·W/100)`,
//! `x1 = round((px + pw)·W/100)`); `w,` and `,h` keep the region's aspect with
//! `h = round(w·rh/rw)` (at least 1); `!w,h` is the largest size within `w × h` with the
//! region's aspect. A size over the region's is refused (no `^` upscaling), and so is one
//! over the server's `max_area`, `max_width` or `max_height`; `max` is the region scaled
//! down to fit them.

use std::fmt;

/// Why a request is malformed: the part, the text given and what was expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadRequest {
    pub part: &'static str,
    pub value: String,
    pub expected: &'static str,
}

impl fmt::Display for BadRequest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // the value quoted is cut: a hostile request may be long
        let v: String = self.value.chars().take(80).collect();
        write!(
            f,
            "invalid {}: {v:?} (expected {})",
            self.part, self.expected
        )
    }
}

fn bad(part: &'static str, value: &str, expected: &'static str) -> BadRequest {
    BadRequest {
        part,
        value: value.to_string(),
        expected,
    }
}

/// The region part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    Full,
    Square,
    Pixels { x: u64, y: u64, w: u64, h: u64 },
    Percent { x: f64, y: f64, w: f64, h: f64 },
}

/// The size part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Size {
    Max,
    Width(u64),
    Height(u64),
    Percent(f64),
    Exact(u64, u64),
    Fit(u64, u64),
}

/// The rotation part: mirroring (applied first), then a clockwise turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rotation {
    pub mirror: bool,
    /// Quarter turns clockwise, 0 to 3.
    pub quarters: u8,
}

/// The quality part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    Default,
    Color,
    Gray,
    Bitonal,
}

/// The format part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Jpg,
    Png,
}

impl Format {
    /// The media type of the response.
    pub fn mime(self) -> &'static str {
        match self {
            Format::Jpg => "image/jpeg",
            Format::Png => "image/png",
        }
    }
}

/// An image request's four parameters, parsed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageRequest {
    pub region: Region,
    pub size: Size,
    pub rotation: Rotation,
    pub quality: Quality,
    pub format: Format,
}

/// The server's caps on an output (the `maxWidth`, `maxHeight`, `maxArea` of `info.json`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Caps {
    pub max_width: u64,
    pub max_height: u64,
    pub max_area: u64,
}

/// A request resolved against an image: the region in full-resolution pixels
/// (`x, y, w, h`) and the output's size before rotation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resolved {
    pub x: u64,
    pub y: u64,
    pub w: u64,
    pub h: u64,
    pub out_w: u64,
    pub out_h: u64,
}

/// The longest number accepted in any part (a longer one is malformed, not a big value).
const MAX_DIGITS: usize = 12;

fn uint(part: &'static str, s: &str, expected: &'static str) -> Result<u64, BadRequest> {
    if s.is_empty() || s.len() > MAX_DIGITS || !s.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad(part, s, expected));
    }
    s.parse().map_err(|_| bad(part, s, expected))
}

fn float(part: &'static str, s: &str, expected: &'static str) -> Result<f64, BadRequest> {
    let ok = !s.is_empty()
        && s.len() <= MAX_DIGITS
        && s.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        && s.bytes().filter(|&b| b == b'.').count() <= 1
        && s != ".";
    if !ok {
        return Err(bad(part, s, expected));
    }
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| bad(part, s, expected))
}

fn four<T>(
    part: &'static str,
    s: &str,
    expected: &'static str,
    f: impl Fn(&str) -> Result<T, BadRequest>,
) -> Result<[T; 4], BadRequest> {
    let v: Vec<&str> = s.split(',').collect();
    if v.len() != 4 {
        return Err(bad(part, s, expected));
    }
    Ok([f(v[0])?, f(v[1])?, f(v[2])?, f(v[3])?])
}

impl Region {
    pub fn parse(s: &str) -> Result<Region, BadRequest> {
        const E: &str = "full, square, x,y,w,h or pct:x,y,w,h with w, h > 0";
        match s {
            "full" => return Ok(Region::Full),
            "square" => return Ok(Region::Square),
            _ => {}
        }
        if let Some(p) = s.strip_prefix("pct:") {
            let [x, y, w, h] = four("region", p, E, |t| float("region", t, E))?;
            if w <= 0.0 || h <= 0.0 {
                return Err(bad("region", s, E));
            }
            return Ok(Region::Percent { x, y, w, h });
        }
        let [x, y, w, h] = four("region", s, E, |t| uint("region", t, E))?;
        if w == 0 || h == 0 {
            return Err(bad("region", s, E));
        }
        Ok(Region::Pixels { x, y, w, h })
    }
}

impl Size {
    pub fn parse(s: &str) -> Result<Size, BadRequest> {
        const E: &str = "max, w,, ,h, pct:n, w,h or !w,h with sizes > 0";
        if s.starts_with('^') {
            return Err(bad("size", s, "no ^ (upscaling is not supported)"));
        }
        if s == "max" {
            return Ok(Size::Max);
        }
        if let Some(p) = s.strip_prefix("pct:") {
            let n = float("size", p, E)?;
            if n <= 0.0 {
                return Err(bad("size", s, E));
            }
            return Ok(Size::Percent(n));
        }
        let (fit, t) = match s.strip_prefix('!') {
            Some(t) => (true, t),
            None => (false, s),
        };
        let Some((a, b)) = t.split_once(',') else {
            return Err(bad("size", s, E));
        };
        let pos = |v: &str| match uint("size", v, E)? {
            0 => Err(bad("size", s, E)),
            n => Ok(n),
        };
        match (a.is_empty(), b.is_empty(), fit) {
            (false, true, false) => Ok(Size::Width(pos(a)?)),
            (true, false, false) => Ok(Size::Height(pos(b)?)),
            (false, false, false) => Ok(Size::Exact(pos(a)?, pos(b)?)),
            (false, false, true) => Ok(Size::Fit(pos(a)?, pos(b)?)),
            _ => Err(bad("size", s, E)),
        }
    }
}

impl Rotation {
    pub fn parse(s: &str) -> Result<Rotation, BadRequest> {
        const E: &str = "0, 90, 180 or 270, optionally after !";
        let (mirror, t) = match s.strip_prefix('!') {
            Some(t) => (true, t),
            None => (false, s),
        };
        let deg = float("rotation", t, E)?;
        let quarters = match deg {
            d if d == 0.0 || d == 360.0 => 0,
            90.0 => 1,
            180.0 => 2,
            270.0 => 3,
            _ => return Err(bad("rotation", s, E)),
        };
        Ok(Rotation { mirror, quarters })
    }
}

impl ImageRequest {
    /// Parse the four path segments after the identifier (`quality.format` is the last).
    pub fn parse(region: &str, size: &str, rotation: &str, qf: &str) -> Result<Self, BadRequest> {
        let Some((q, f)) = qf.rsplit_once('.') else {
            return Err(bad(
                "quality.format",
                qf,
                "quality.format, e.g. default.jpg",
            ));
        };
        let quality = match q {
            "default" => Quality::Default,
            "color" => Quality::Color,
            "gray" => Quality::Gray,
            "bitonal" => Quality::Bitonal,
            _ => return Err(bad("quality", q, "default, color, gray or bitonal")),
        };
        let format = match f {
            "jpg" => Format::Jpg,
            "png" => Format::Png,
            _ => return Err(bad("format", f, "jpg or png")),
        };
        Ok(ImageRequest {
            region: Region::parse(region)?,
            size: Size::parse(size)?,
            rotation: Rotation::parse(rotation)?,
            quality,
            format,
        })
    }

    /// The region's pixel box and the output size on an image of `width × height`.
    pub fn resolve(&self, width: u64, height: u64, caps: &Caps) -> Result<Resolved, BadRequest> {
        let (x, y, w, h) = region_box(&self.region, width, height)?;
        let (out_w, out_h) = output_size(&self.size, w, h, caps)?;
        Ok(Resolved {
            x,
            y,
            w,
            h,
            out_w,
            out_h,
        })
    }
}

/// `round(v)` of a non-negative finite value as an integer, saturating.
fn round_u64(v: f64) -> u64 {
    if v.is_finite() && v > 0.0 {
        v.round().min(u64::MAX as f64) as u64
    } else {
        0
    }
}

fn region_box(r: &Region, width: u64, height: u64) -> Result<(u64, u64, u64, u64), BadRequest> {
    const E: &str = "a region meeting the image";
    match *r {
        Region::Full => Ok((0, 0, width, height)),
        Region::Square => {
            let s = width.min(height);
            Ok(((width - s) / 2, (height - s) / 2, s, s))
        }
        Region::Pixels { x, y, w, h } => {
            if x >= width || y >= height {
                return Err(bad("region", &format!("{x},{y},{w},{h}"), E));
            }
            Ok((x, y, w.min(width - x), h.min(height - y)))
        }
        Region::Percent { x, y, w, h } => {
            let (fw, fh) = (width as f64, height as f64);
            let x0 = round_u64(x * fw / 100.0);
            let y0 = round_u64(y * fh / 100.0);
            let x1 = round_u64((x + w) * fw / 100.0).min(width);
            let y1 = round_u64((y + h) * fh / 100.0).min(height);
            if x0 >= x1 || y0 >= y1 {
                return Err(bad("region", &format!("pct:{x},{y},{w},{h}"), E));
            }
            Ok((x0, y0, x1 - x0, y1 - y0))
        }
    }
}

/// The size `max` means: the region scaled down (aspect kept) to fit the caps.
fn max_size(w: u64, h: u64, caps: &Caps) -> (u64, u64) {
    let mut s = 1.0f64;
    s = s.min(caps.max_width as f64 / w as f64);
    s = s.min(caps.max_height as f64 / h as f64);
    s = s.min((caps.max_area as f64 / (w as f64 * h as f64)).sqrt());
    if s >= 1.0 {
        return (w, h);
    }
    let ow = ((w as f64 * s).floor() as u64).max(1);
    let oh = ((h as f64 * s).floor() as u64).max(1);
    (ow, oh)
}

fn output_size(s: &Size, w: u64, h: u64, caps: &Caps) -> Result<(u64, u64), BadRequest> {
    let (ow, oh) = match *s {
        Size::Max => return Ok(max_size(w, h, caps)),
        Size::Width(ow) => (ow, round_u64(ow as f64 * h as f64 / w as f64).max(1)),
        Size::Height(oh) => (round_u64(oh as f64 * w as f64 / h as f64).max(1), oh),
        Size::Percent(p) => (
            round_u64(w as f64 * p / 100.0).max(1),
            round_u64(h as f64 * p / 100.0).max(1),
        ),
        Size::Exact(ow, oh) => (ow, oh),
        Size::Fit(bw, bh) => {
            let s = (bw as f64 / w as f64).min(bh as f64 / h as f64);
            let ow = round_u64(w as f64 * s).clamp(1, bw);
            let oh = round_u64(h as f64 * s).clamp(1, bh);
            (ow, oh)
        }
    };
    if ow > w || oh > h {
        return Err(bad(
            "size",
            &format!("{ow}x{oh} of a {w}x{h} region"),
            "at most the region's size (no upscaling)",
        ));
    }
    if ow > caps.max_width || oh > caps.max_height || ow.saturating_mul(oh) > caps.max_area {
        return Err(bad(
            "size",
            &format!("{ow}x{oh}"),
            "within the server's maxWidth, maxHeight and maxArea",
        ));
    }
    Ok((ow, oh))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPS: Caps = Caps {
        max_width: 1 << 20,
        max_height: 1 << 20,
        max_area: 1 << 24,
    };

    fn req(r: &str, s: &str) -> Result<Resolved, BadRequest> {
        ImageRequest::parse(r, s, "0", "default.jpg")?.resolve(1000, 600, &CAPS)
    }

    fn wh(r: Resolved) -> [u64; 6] {
        [r.x, r.y, r.w, r.h, r.out_w, r.out_h]
    }

    #[test]
    fn regions_resolve_as_the_specification_defines_them() {
        // x, y, w, h of the region and the output size at "max"
        for (region, want) in [
            ("full", [0, 0, 1000, 600, 1000, 600]),
            ("square", [200, 0, 600, 600, 600, 600]),
            ("10,20,30,40", [10, 20, 30, 40, 30, 40]),
            // cropped at the image's edge
            ("900,500,300,300", [900, 500, 100, 100, 100, 100]),
            ("pct:10,50,20,50", [100, 300, 200, 300, 200, 300]),
        ] {
            assert_eq!(wh(req(region, "max").unwrap()), want, "{region}");
        }
        assert_eq!(
            wh(req("pct:0.5,0,99.5,100", "max").unwrap())[..4],
            [5, 0, 995, 600]
        );
    }

    #[test]
    fn sizes_resolve_as_the_specification_defines_them() {
        assert_eq!(wh(req("full", "500,").unwrap())[4..], [500, 300]);
        assert_eq!(wh(req("full", ",300").unwrap())[4..], [500, 300]);
        assert_eq!(wh(req("full", "pct:50").unwrap())[4..], [500, 300]);
        assert_eq!(wh(req("full", "200,100").unwrap())[4..], [200, 100]);
        assert_eq!(wh(req("full", "!200,200").unwrap())[4..], [200, 120]);
        assert_eq!(wh(req("full", "!500,100").unwrap())[4..], [167, 100]);
        assert_eq!(wh(req("0,0,7,3", "1,").unwrap())[4..], [1, 1]);
    }

    #[test]
    fn max_is_scaled_down_to_the_caps() {
        let caps = Caps {
            max_width: 500,
            max_height: 1 << 20,
            max_area: 1 << 24,
        };
        let r = ImageRequest::parse("full", "max", "0", "default.png").unwrap();
        assert_eq!(wh(r.resolve(1000, 600, &caps).unwrap())[4..], [500, 300]);
        let r = ImageRequest::parse("full", "1000,", "0", "default.png").unwrap();
        assert!(r.resolve(1000, 600, &caps).is_err());
    }

    #[test]
    fn sizes_over_the_region_and_upscaling_are_refused() {
        assert!(req("full", "1001,").is_err());
        assert!(req("full", ",601").is_err());
        assert!(req("full", "pct:101").is_err());
        assert!(req("10,10,10,10", "11,11").is_err());
        assert!(req("full", "^max").is_err());
        assert!(req("full", "^2000,").is_err());
        assert!(req("full", "99999999999999999999,").is_err());
    }

    #[test]
    fn empty_negative_and_outside_regions_are_refused() {
        for r in [
            "0,0,0,10",
            "0,0,10,0",
            "-1,0,10,10",
            "0,-5,10,10",
            "1000,0,10,10",
            "0,600,10,10",
            "pct:0,0,0,10",
            "pct:100,0,10,10",
            "pct:-1,0,10,10",
            "a,b,c,d",
            "1,2,3",
            "1,2,3,4,5",
            "",
            "full ",
            "1e3,0,1,1",
            "pct:nan,0,1,1",
            "pct:inf,0,1,1",
        ] {
            assert!(req(r, "max").is_err(), "{r}");
        }
    }

    #[test]
    fn malformed_sizes_are_refused() {
        for s in [
            "", ",", "0,", ",0", "0,0", "!0,5", "!5,", "!,5", "pct:0", "pct:", "pct:-5", "w,h",
            "full", "1,2,3", "+5,", "5 ,", "!!5,5",
        ] {
            assert!(Size::parse(s).is_err(), "{s}");
        }
    }

    #[test]
    fn rotations_quarters_and_mirroring_parse_and_others_are_refused() {
        assert_eq!(
            Rotation::parse("90").unwrap(),
            Rotation {
                mirror: false,
                quarters: 1
            }
        );
        assert_eq!(
            Rotation::parse("!270").unwrap(),
            Rotation {
                mirror: true,
                quarters: 3
            }
        );
        assert_eq!(Rotation::parse("0.0").unwrap().quarters, 0);
        for r in ["45", "-90", "", "!", "x", "90!", "!!0", "361"] {
            assert!(Rotation::parse(r).is_err(), "{r}");
        }
    }

    #[test]
    fn qualities_and_formats_parse_and_others_are_refused() {
        let r = ImageRequest::parse("full", "max", "0", "gray.png").unwrap();
        assert_eq!((r.quality, r.format), (Quality::Gray, Format::Png));
        for qf in [
            "default",
            "default.gif",
            "grey.jpg",
            "default.jpg.png",
            ".jpg",
            "color.",
        ] {
            assert!(ImageRequest::parse("full", "max", "0", qf).is_err(), "{qf}");
        }
    }

    #[test]
    fn a_long_value_is_cut_in_the_message() {
        let e = Region::parse(&"9".repeat(10_000)).unwrap_err();
        assert!(e.to_string().len() < 300, "{e}");
    }
}
