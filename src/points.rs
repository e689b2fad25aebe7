//! Point lists as text: one point per line, coordinates separated by commas (or
//! white space), `#` starts a comment. Every point has the same dimension.
//!
//! Tagged lists (the output of `mra analyze` on points) start each line with a tag:
//! `C` for the coarsest points, then `D<L>` … `D1` for the details, coarsest first.

use crate::{Error, Result};

/// Points read from text: `n` points of `dim` coordinates, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Points {
    pub dim: usize,
    pub data: Vec<f64>,
}

impl Points {
    pub fn len(&self) -> usize {
        self.data.len() / self.dim.max(1)
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
}

/// Parse untagged points: the point-table reader of the curves
/// ([`crate::curve::csv::parse_list`]: commas, semicolons or white space between
/// coordinates, an optional header line), without a weight column.
pub fn parse(text: &str) -> Result<Points> {
    let t = crate::curve::csv::parse_list(text)?;
    if t.weights.is_some() {
        return Err(Error::format(
            "a weight column (w)",
            "coordinates only in a point list",
        ));
    }
    Ok(Points {
        dim: t.dim,
        data: t.points,
    })
}

/// A tagged list: coarse points and detail bands `details[0]` = `D<L>` (coarsest) …
/// `details[L−1]` = `D1` (finest).
#[derive(Clone, Debug, PartialEq)]
pub struct Tagged {
    pub dim: usize,
    pub coarse: Vec<f64>,
    pub details: Vec<Vec<f64>>,
}

fn fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|f| !f.is_empty())
}

fn strip_comment(line: &str) -> &str {
    match line.find('#') {
        Some(i) => &line[..i],
        None => line,
    }
}

fn parse_number(field: &str, line_no: usize) -> Result<f64> {
    field
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            Error::format(
                format!("line {line_no}: bad number {field:?}"),
                "a finite decimal number",
            )
        })
}

/// Parse the tagged format written by [`write_tagged`].
pub fn parse_tagged(text: &str) -> Result<Tagged> {
    let mut dim = 0;
    let mut coarse = Vec::new();
    let mut bands: Vec<(usize, Vec<f64>)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = strip_comment(raw).trim();
        if line.is_empty() {
            continue;
        }
        let mut it = fields(line);
        let tag = it.next().unwrap_or_default();
        let vals: Vec<f64> = it.map(|f| parse_number(f, i + 1)).collect::<Result<_>>()?;
        if dim == 0 {
            dim = vals.len();
        }
        if vals.len() != dim || dim == 0 {
            return Err(Error::format(
                format!(
                    "line {}: {} coordinates where earlier points have {dim}",
                    i + 1,
                    vals.len()
                ),
                "every point with the same dimension",
            ));
        }
        if tag == "C" {
            if !bands.is_empty() {
                return Err(Error::format(
                    format!("line {}: C after D lines", i + 1),
                    "all C lines first",
                ));
            }
            coarse.extend(vals);
        } else if let Some(l) = tag
            .strip_prefix('D')
            .and_then(|l| l.parse::<usize>().ok())
            .filter(|&l| l >= 1)
        {
            match bands.last_mut() {
                Some((cur, v)) if *cur == l => v.extend(vals),
                Some((cur, _)) if l != *cur - 1 => {
                    return Err(Error::format(
                        format!("line {}: D{l} after D{cur}", i + 1),
                        "detail bands in order D<L> … D1",
                    ))
                }
                _ => bands.push((l, vals)),
            }
        } else {
            return Err(Error::format(
                format!("line {}: bad tag {tag:?}", i + 1),
                "C or D<level>",
            ));
        }
    }
    if coarse.is_empty() {
        return Err(Error::format("no C lines", "the coarse points first"));
    }
    if let Some((l, _)) = bands.last() {
        if *l != 1 {
            return Err(Error::format(
                format!("the finest band is D{l}"),
                "bands down to D1",
            ));
        }
    }
    Ok(Tagged {
        dim,
        coarse,
        details: bands.into_iter().map(|(_, v)| v).collect(),
    })
}

/// Write points, one per line, comma-separated, in the shortest form that parses back
/// to the same `f64`.
pub fn write(dim: usize, data: &[f64], out: &mut dyn std::io::Write) -> std::io::Result<()> {
    for p in data.chunks(dim) {
        let line: Vec<String> = p.iter().map(|v| format!("{v:?}")).collect();
        writeln!(out, "{}", line.join(","))?;
    }
    Ok(())
}

/// Write a tagged list.
pub fn write_tagged(t: &Tagged, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    let levels = t.details.len();
    let mut put = |tag: &str, data: &[f64]| -> std::io::Result<()> {
        for p in data.chunks(t.dim) {
            let line: Vec<String> = p.iter().map(|v| format!("{v:?}")).collect();
            writeln!(out, "{tag},{}", line.join(","))?;
        }
        Ok(())
    };
    put("C", &t.coarse)?;
    for (k, band) in t.details.iter().enumerate() {
        put(&format!("D{}", levels - k), band)?;
    }
    Ok(())
}
