//! The `info.json` of an image (IIIF Image API 3.0 §5): its size, the sizes its levels
//! hold, one tile grid of 256² tiles at every level's scale factor, compliance level 2,
//! and the caps on an output.

use super::iiif::Caps;
use super::source::Source;
use serde_json::{json, Value};

/// Width and height of the tiles offered (what viewers ask for).
pub const TILE: u64 = 256;

/// The caps on one output: at most 2²⁴ pixels (4096²), and within the memory budget
/// at 24 bytes a pixel (the resampling planes).
pub fn caps(src: &Source, max_bytes: u64) -> Caps {
    let (w, h) = src.size();
    let area = (1u64 << 24).min(max_bytes / 24).min(w * h).max(1);
    Caps {
        max_width: w,
        max_height: h,
        max_area: area,
    }
}

/// The document, `id` being the image's base URI.
pub fn info_json(src: &Source, id: &str, caps: &Caps) -> Value {
    let (w, h) = src.size();
    // the levels coarse to fine, within the caps
    let mut sizes: Vec<Value> = (0..=src.depth())
        .rev()
        .map(|k| src.level_size(k))
        .filter(|&(lw, lh)| (lw as u64) * (lh as u64) <= caps.max_area)
        .map(|(lw, lh)| json!({"width": lw, "height": lh}))
        .collect();
    sizes.dedup();
    let factors: Vec<u64> = (0..=src.depth()).map(|k| 1u64 << k).collect();
    let mut doc = json!({
        "@context": "http://iiif.io/api/image/3/context.json",
        "id": id,
        "type": "ImageService3",
        "protocol": "http://iiif.io/api/image",
        "profile": "level2",
        "width": w,
        "height": h,
        "sizes": sizes,
        "tiles": [{"width": TILE, "height": TILE, "scaleFactors": factors}],
        "extraQualities": ["color", "gray", "bitonal"],
        "extraFeatures": ["mirroring", "profileLinkHeader"],
        "preferredFormats": ["jpg"],
    });
    if caps.max_area < w * h {
        doc["maxArea"] = json!(caps.max_area);
    }
    doc
}
