//! ESRI ASCII grid (`.asc`): six header lines (`ncols`, `nrows`, `xllcorner` or
//! `xllcenter`, `yllcorner` or `yllcenter`, `cellsize`, optional `NODATA_value`), then
//! `nrows` rows of `ncols` numbers, north row first. All-integer grids read as i32,
//! others as f64; `NODATA_value` becomes `meta.nodata`, the corner / centre and cell
//! size go into `meta.extra` (`asc.xllcorner`, …) and `meta.spacing`.

use std::io::Write;
use std::path::Path;

use super::bytes::{self, sample_count};
use super::{DataKind, Raster, Samples};
use crate::{Error, Result};

fn bad(what: impl std::fmt::Display) -> Error {
    Error::format(what, "a valid ESRI ASCII grid")
}

/// Read an ESRI ASCII grid.
pub fn read(path: &Path) -> Result<Raster> {
    let raw = bytes::read_all(path)?;
    let text = std::str::from_utf8(&raw).map_err(|_| bad("file is not text"))?;
    let mut tokens = text.split_ascii_whitespace().peekable();
    let mut header: Vec<(String, String)> = Vec::new();
    while let Some(&t) = tokens.peek() {
        if t.starts_with(|c: char| c.is_ascii_alphabetic()) {
            let key = tokens.next().unwrap().to_ascii_lowercase();
            let val = tokens
                .next()
                .ok_or_else(|| bad(format!("no value for {key}")))?;
            header.push((key, val.to_string()));
        } else {
            break;
        }
    }
    let get = |k: &str| {
        header
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.as_str())
    };
    let num = |k: &str| -> Result<usize> {
        get(k)
            .ok_or_else(|| bad(format!("no {k} in the header")))?
            .parse::<usize>()
            .map_err(|_| bad(format!("{k} is not a count")))
    };
    let (ncols, nrows) = (num("ncols")?, num("nrows")?);
    let n = sample_count(&[nrows, ncols], 1)?;
    // at least two bytes of text per value: check before allocating
    if n as u64 > raw.len() as u64 / 2 + 1 {
        return Err(bad(format!(
            "header declares {nrows}x{ncols} values but the file holds {} bytes",
            raw.len()
        )));
    }
    let samples = read_values(&text[header_end(text)..], nrows, ncols)?;
    let mut r = Raster::new(vec![nrows, ncols], 1, samples, DataKind::Heightmap)?;
    for (k, v) in &header {
        if k != "ncols" && k != "nrows" {
            r.meta.extra.insert(format!("asc.{k}"), v.clone());
        }
    }
    if let Some(nd) = get("nodata_value") {
        r.meta.nodata = nd.parse().ok();
    }
    if let Some(cs) = get("cellsize").and_then(|c| c.parse::<f64>().ok()) {
        r.meta.spacing = Some(vec![cs, cs]);
    } else if let (Some(dx), Some(dy)) = (
        get("dx").and_then(|c| c.parse::<f64>().ok()),
        get("dy").and_then(|c| c.parse::<f64>().ok()),
    ) {
        r.meta.spacing = Some(vec![dy, dx]);
    }
    Ok(r)
}

/// The data lines: exactly `nrows` rows of `ncols` numbers (blank lines skipped), as i32 when
/// every value is an integer, else f64.
fn read_values(data: &str, nrows: usize, ncols: usize) -> Result<Samples> {
    let n = nrows * ncols;
    let mut ints: Option<Vec<i32>> = Some(Vec::with_capacity(n));
    let mut floats: Vec<f64> = Vec::with_capacity(n);
    // The data must be `nrows` lines of exactly `ncols` values: a row with more or
    // fewer values would shift every later row, so it is an error, not a re-wrap.
    let mut row = 0usize;
    for line in data.lines() {
        let mut count = 0usize;
        for t in line.split_ascii_whitespace() {
            let v: f64 = t
                .parse()
                .map_err(|_| bad(format!("value {t:?} is not a number")))?;
            count += 1;
            if row < nrows && count <= ncols {
                floats.push(v);
                if let Some(iv) = ints.as_mut() {
                    match t.parse::<i32>() {
                        Ok(i) => iv.push(i),
                        Err(_) => ints = None,
                    }
                }
            }
        }
        if count == 0 {
            continue;
        }
        if row >= nrows {
            return Err(bad(format!(
                "more than the {nrows} rows the header declares"
            )));
        }
        if count != ncols {
            return Err(bad(format!(
                "data row {} has {count} values, the header declares ncols {ncols}",
                row + 1
            )));
        }
        row += 1;
    }
    if floats.len() < n {
        return Err(bad(format!(
            "{} values for {nrows}x{ncols} cells ({row} rows of {nrows})",
            floats.len()
        )));
    }
    Ok(match ints {
        Some(v) => Samples::I32(v),
        None => Samples::F64(floats),
    })
}

/// Byte offset of the first data line: past the leading lines whose first token is a
/// header key (starts with a letter) and any blank lines.
fn header_end(text: &str) -> usize {
    let mut pos = 0usize;
    for line in text.split_inclusive('\n') {
        match line.split_ascii_whitespace().next() {
            None => {}
            Some(t) if t.starts_with(|c: char| c.is_ascii_alphabetic()) => {}
            Some(_) => break,
        }
        pos += line.len();
    }
    pos
}

/// Write a single-channel 2-D raster as an ESRI ASCII grid (integers as integers,
/// floats in shortest round-trip form). Header fields come from `meta.extra["asc.*"]`
/// when present, else corner 0,0 and the spacing (or 1).
pub fn write<W: Write>(w: &mut W, r: &Raster) -> Result<()> {
    if r.dims.len() != 2 || r.channels != 1 {
        return Err(Error::Unsupported {
            what: "ASC output",
            value: format!("{} (expected a single-channel 2-D grid)", r.summary()),
        });
    }
    let mut s = format!("ncols {}\nnrows {}\n", r.width(), r.height());
    let ex = |k: &str| r.meta.extra.get(&format!("asc.{k}"));
    let x = ex("xllcorner").map(|v| ("xllcorner", v.clone()));
    let x = x.or_else(|| ex("xllcenter").map(|v| ("xllcenter", v.clone())));
    let (xk, xv) = x.unwrap_or(("xllcorner", "0".into()));
    let y = ex("yllcorner").map(|v| ("yllcorner", v.clone()));
    let y = y.or_else(|| ex("yllcenter").map(|v| ("yllcenter", v.clone())));
    let (yk, yv) = y.unwrap_or(("yllcorner", "0".into()));
    s += &format!("{xk} {xv}\n{yk} {yv}\n");
    let cs = ex("cellsize").cloned().unwrap_or_else(|| {
        r.meta
            .spacing
            .as_ref()
            .map(|sp| sp[1].to_string())
            .unwrap_or_else(|| "1".into())
    });
    s += &format!("cellsize {cs}\n");
    if let Some(nd) = ex("nodata_value") {
        s += &format!("NODATA_value {nd}\n");
    } else if let Some(nd) = r.meta.nodata {
        s += &format!("NODATA_value {nd}\n");
    }
    w.write_all(s.as_bytes())?;
    let wdt = r.width();
    let mut line = String::new();
    for row in 0..r.height() {
        line.clear();
        for col in 0..wdt {
            if col > 0 {
                line.push(' ');
            }
            let i = row * wdt + col;
            match &r.samples {
                Samples::F64(v) => line += &v[i].to_string(),
                Samples::F32(v) => line += &v[i].to_string(),
                Samples::F16(v) => line += &v[i].to_string(),
                other => line += &(other.get_f64(i) as i64).to_string(),
            }
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}
