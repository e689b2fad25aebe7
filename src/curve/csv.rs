//! Control points as text: one point per line, coordinates separated by commas (or spaces /
//! semicolons), `#` starts a comment. A blank line ends a row of a patch net. An optional header
//! line names the columns (`x,y,z` or `x,y,w`); a column named `w` holds the weights of rational
//! curves and surfaces.
//!
//! ```text
//! # x, y, w
//! 1, 0, 1
//! 1, 1, 0.7071067811865476
//! 0, 1, 1
//! ```

use crate::{Error, Result};

/// A net of points: `rows` rows of `cols` points, `dim` coordinates each, with optional weights.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTable {
    pub dim: usize,
    pub rows: usize,
    pub cols: usize,
    /// Row-major points: row r, column c at `(r·cols + c)·dim`.
    pub points: Vec<f64>,
    /// One weight per point when the header names a `w` column.
    pub weights: Option<Vec<f64>>,
}

/// Largest accepted number of points (a guard against runaway input).
pub const MAX_POINTS: usize = 50_000_000;

/// Parse a point table (see the module doc).
pub fn parse(text: &str) -> Result<PointTable> {
    parse_net(text, true)
}

/// Parse a plain point list: [`parse`] with blank lines ignored (one row of every point).
pub fn parse_list(text: &str) -> Result<PointTable> {
    parse_net(text, false)
}

/// [`parse`]; a blank line ends a row of the net when `rows` is set.
fn parse_net(text: &str, rows_on_blank: bool) -> Result<PointTable> {
    let mut header: Option<Vec<String>> = None;
    let mut rows: Vec<Vec<Vec<f64>>> = vec![Vec::new()];
    let mut width: Option<usize> = None;
    let mut total = 0usize;
    for (ln, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            // a blank line (not a comment-only line) ends a row
            if rows_on_blank && raw.trim().is_empty() && !rows.last().is_none_or(|r| r.is_empty()) {
                rows.push(Vec::new());
            }
            continue;
        }
        let toks: Vec<&str> = line
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .collect();
        let nums: std::result::Result<Vec<f64>, _> =
            toks.iter().map(|t| t.parse::<f64>()).collect();
        let nums = match nums {
            Ok(v) => v,
            Err(_)
                if header.is_none()
                    && total == 0
                    && toks.iter().all(|t| t.parse::<f64>().is_err()) =>
            {
                header = Some(toks.iter().map(|t| t.to_ascii_lowercase()).collect());
                width = Some(toks.len());
                continue;
            }
            Err(_) => {
                return Err(Error::format(
                    format!("line {}: {:?} is not a list of numbers", ln + 1, line),
                    "numbers separated by commas, one point per line",
                ))
            }
        };
        if let Some(x) = nums.iter().find(|x| !x.is_finite()) {
            return Err(Error::format(
                format!("line {}: coordinate {}", ln + 1, x),
                "finite numbers",
            ));
        }
        match width {
            None => width = Some(nums.len()),
            Some(w) if w != nums.len() => {
                return Err(Error::format(
                    format!(
                        "line {}: {} values after lines of {}",
                        ln + 1,
                        nums.len(),
                        w
                    ),
                    "the same number of coordinates on every line",
                ))
            }
            _ => {}
        }
        total += 1;
        if total > MAX_POINTS {
            return Err(Error::LimitsExceeded {
                what: "number of points",
                requested: total as u64,
                limit: MAX_POINTS as u64,
            });
        }
        rows.last_mut().unwrap().push(nums);
    }
    if rows.last().is_some_and(|r| r.is_empty()) {
        rows.pop();
    }
    let width = width.unwrap_or(0);
    if total == 0 || width == 0 {
        return Err(Error::format(
            "no points",
            "at least one line of coordinates",
        ));
    }
    table(header.as_deref(), &rows, width, total)
}

/// The point table of the parsed `rows` (lines of `width` values, `total` in all): rows of
/// equal length, the column named `w` (if the header has one) split off as the weights.
fn table(
    header: Option<&[String]>,
    rows: &[Vec<Vec<f64>>],
    width: usize,
    total: usize,
) -> Result<PointTable> {
    let cols = rows[0].len();
    if let Some((i, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != cols) {
        return Err(Error::format(
            format!(
                "row {} of the net has {} points, row 1 has {}",
                i + 1,
                r.len(),
                cols
            ),
            "rows of equal length separated by blank lines",
        ));
    }
    let wcol = header.and_then(|h| h.iter().position(|c| c == "w"));
    let dim = width - wcol.is_some() as usize;
    if dim == 0 {
        return Err(Error::format(
            "only a weight column",
            "at least one coordinate",
        ));
    }
    let mut points = Vec::with_capacity(total * dim);
    let mut weights = wcol.map(|_| Vec::with_capacity(total));
    for r in rows {
        for p in r {
            for (j, v) in p.iter().enumerate() {
                if Some(j) == wcol {
                    weights.as_mut().unwrap().push(*v);
                } else {
                    points.push(*v);
                }
            }
        }
    }
    Ok(PointTable {
        dim,
        rows: rows.len(),
        cols,
        points,
        weights,
    })
}

/// Parse a list of numbers (knots, parameters) separated by commas, spaces or newlines.
pub fn parse_numbers(text: &str, what: &'static str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        for t in line
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|t| !t.is_empty())
        {
            let v: f64 = t.parse().map_err(|_| {
                Error::format(
                    format!("{what}: {t:?} is not a number"),
                    "numbers separated by commas",
                )
            })?;
            if !v.is_finite() {
                return Err(Error::format(format!("{what}: {v}"), "finite numbers"));
            }
            out.push(v);
        }
    }
    Ok(out)
}

/// Write points (`dim` each) as CSV lines, with an optional weight column.
pub fn write_points(out: &mut String, points: &[f64], dim: usize, weights: Option<&[f64]>) {
    use std::fmt::Write;
    for (i, p) in points.chunks(dim).enumerate() {
        let mut first = true;
        for x in p {
            if !first {
                out.push(',');
            }
            first = false;
            let _ = write!(out, "{}", x);
        }
        if let Some(w) = weights {
            let _ = write!(out, ",{}", w[i]);
        }
        out.push('\n');
    }
}
