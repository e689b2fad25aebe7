//! The `mETA` chunk: the raster's metadata as UTF-8 `key=value` lines (formats/MRA.md §5).
//! Ancillary: a reader may skip it.

use crate::io::{GeoTag, GeoValue, Metadata};

/// The `meta.extra` key holding the void mask of an encoded raster (§5.1): `m1:` then
/// the base64 of the mask range-coded by the codec's void coder; files written before
/// the coded mask list runs `start:length` (sample indices, channels interleaved)
/// instead.
pub const VOID_RUNS: &str = "nodata.voids";

/// Whether `meta` lists void samples (a filled raster's, or a decoded file's `mETA`).
pub fn lists_voids(meta: &Metadata) -> bool {
    meta.extra.contains_key(VOID_RUNS)
}

fn nums(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn parse_nums(s: &str) -> Option<Vec<f64>> {
    s.split_whitespace().map(|t| t.parse().ok()).collect()
}

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('\n', "\\n")
}

fn unesc(s: &str) -> String {
    let mut out = String::new();
    let mut it = s.chars();
    while let Some(c) = it.next() {
        if c == '\\' {
            match it.next() {
                Some('n') => out.push('\n'),
                Some(o) => out.push(o),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Serialize; empty when there is nothing to say.
pub fn to_bytes(m: &Metadata) -> Vec<u8> {
    let mut lines = Vec::new();
    if let Some(v) = &m.spacing {
        lines.push(format!("spacing={}", nums(v)));
    }
    if let Some(v) = &m.origin {
        lines.push(format!("origin={}", nums(v)));
    }
    if let Some(v) = &m.units {
        lines.push(format!("units={}", esc(v)));
    }
    if let Some(v) = m.nodata {
        lines.push(format!("nodata={v:?}"));
    }
    if let Some(v) = &m.space {
        lines.push(format!("space={}", esc(v)));
    }
    if let Some(d) = &m.directions {
        for (i, v) in d.iter().enumerate() {
            lines.push(format!("direction.{i}={}", nums(v)));
        }
    }
    if let Some(a) = &m.affine {
        lines.push(format!("affine={}", nums(&a.concat())));
    }
    if let Some(v) = &m.description {
        lines.push(format!("description={}", esc(v)));
    }
    for t in &m.geotiff {
        let v = match &t.value {
            GeoValue::Shorts(s) => format!(
                "s:{}",
                s.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
            GeoValue::Doubles(d) => format!("d:{}", nums(d)),
            GeoValue::Ascii(a) => format!("a:{}", esc(a)),
        };
        lines.push(format!("geotiff.{}={v}", t.tag));
    }
    for (k, v) in &m.extra {
        lines.push(format!("extra.{}={}", esc(k).replace('=', "\\e"), esc(v)));
    }
    if lines.is_empty() {
        return Vec::new();
    }
    (lines.join("\n") + "\n").into_bytes()
}

/// Parse leniently: unknown keys and malformed lines are ignored.
pub fn parse(bytes: &[u8]) -> Metadata {
    let mut m = Metadata::default();
    let text = String::from_utf8_lossy(bytes);
    let mut dirs: Vec<(usize, Vec<f64>)> = Vec::new();
    for line in text.lines() {
        let Some((k, v)) = line.split_once('=') else {
            continue;
        };
        match k {
            "spacing" => m.spacing = parse_nums(v),
            "origin" => m.origin = parse_nums(v),
            "units" => m.units = Some(unesc(v)),
            "nodata" => m.nodata = v.parse().ok(),
            "space" => m.space = Some(unesc(v)),
            "description" => m.description = Some(unesc(v)),
            "affine" => {
                if let Some(a) = parse_nums(v).filter(|a| a.len() == 12) {
                    m.affine = Some([
                        [a[0], a[1], a[2], a[3]],
                        [a[4], a[5], a[6], a[7]],
                        [a[8], a[9], a[10], a[11]],
                    ]);
                }
            }
            _ => {
                if let Some(i) = k.strip_prefix("direction.").and_then(|i| i.parse().ok()) {
                    if let Some(n) = parse_nums(v) {
                        dirs.push((i, n));
                    }
                } else if let Some(tag) = k.strip_prefix("geotiff.").and_then(|t| t.parse().ok()) {
                    let value = if let Some(s) = v.strip_prefix("s:") {
                        s.split_whitespace()
                            .map(|x| x.parse().ok())
                            .collect::<Option<Vec<u16>>>()
                            .map(GeoValue::Shorts)
                    } else if let Some(d) = v.strip_prefix("d:") {
                        parse_nums(d).map(GeoValue::Doubles)
                    } else {
                        v.strip_prefix("a:").map(|a| GeoValue::Ascii(unesc(a)))
                    };
                    if let Some(value) = value {
                        m.geotiff.push(GeoTag { tag, value });
                    }
                } else if let Some(key) = k.strip_prefix("extra.") {
                    m.extra.insert(unesc(&key.replace("\\e", "=")), unesc(v));
                }
            }
        }
    }
    if !dirs.is_empty() {
        dirs.sort_by_key(|d| d.0);
        m.directions = Some(dirs.into_iter().map(|d| d.1).collect());
    }
    m
}
