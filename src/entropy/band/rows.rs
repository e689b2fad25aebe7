//! A detail band without parent coded and decoded a row at a time, the caller driving
//! ([`RowEncoder::push`], [`RowDecoder::next_row`]): the stream of
//! [`super::encode_stream_rows`] and [`super::decode_rows`] (the same bytes and rows),
//! for a caller that produces or consumes the rows in its own loop (a `--max-error`
//! residual beside a streamed decode). Only the rows the contexts read are held
//! ([`super::Window`]).

use super::{decode_value, encode_value, open, opened, Classes, Coding, Ctx, Models, Row, Window};
use crate::entropy::range::{Decoder, Encoder};
use crate::entropy::walk::Walk;
use crate::Result;

/// One class set's coder of a band handed over a row at a time.
struct OneCoder {
    e: Encoder,
    m: Box<Models>,
    r: Row,
    q: Window,
}

impl OneCoder {
    fn new(walk: Walk, coding: Coding, classes: Classes) -> Self {
        let mut e = Encoder::new();
        open(&mut e, coding, classes);
        OneCoder {
            e,
            m: Box::new(Models::new(classes)),
            r: Row::new(walk.cols, classes),
            q: Window::new(walk, false),
        }
    }

    /// Code row `g` (raster order over the planes' rows), `row` its indices.
    fn push(&mut self, walk: Walk, g: usize, row: &[i64]) {
        let ctx = Ctx { walk, parent: None };
        let (p, y) = (g / walk.rows, g % walk.rows);
        self.q.row_mut(g).copy_from_slice(row);
        ctx.prepare(&mut self.r, self.q.neighbours(&ctx, p, y, g), y, 0);
        let (mut w1, mut w2) = (0, 0);
        for (x, &v) in self.q.row(g).iter().enumerate() {
            encode_value(&mut self.e, &mut self.m, v, self.r.context(x, w1, w2));
            w2 = w1;
            w1 = v;
        }
    }
}

/// A detail band without parent of extents `dims`, coded as its rows are pushed (rows
/// of the last axis, in raster order); [`RowEncoder::finish`] gives the bytes of
/// [`super::encode_stream_rows`] of the same rows (in [`Coding::Chosen`] both class
/// sets coded side by side, the shorter kept, the narrow one on a tie).
pub struct RowEncoder {
    walk: Walk,
    coders: Vec<OneCoder>,
    next: usize,
}

impl RowEncoder {
    pub fn new(dims: &[usize], coding: Coding) -> Self {
        let walk = Walk::new(dims);
        let mut coders = vec![OneCoder::new(walk, coding, Classes::Narrow)];
        if coding == Coding::Chosen {
            coders.push(OneCoder::new(walk, coding, Classes::Wide));
        }
        RowEncoder {
            walk,
            coders,
            next: 0,
        }
    }

    /// The length of a row (the last extent).
    pub fn cols(&self) -> usize {
        self.walk.cols
    }

    /// Code the next row (`row.len()` = [`RowEncoder::cols`]).
    pub fn push(&mut self, row: &[i64]) {
        debug_assert_eq!(row.len(), self.walk.cols);
        debug_assert!(self.next < self.walk.planes * self.walk.rows);
        let (walk, g) = (self.walk, self.next);
        match self.coders.as_mut_slice() {
            [a, b] => {
                rayon::join(|| a.push(walk, g, row), || b.push(walk, g, row));
            }
            coders => coders.iter_mut().for_each(|k| k.push(walk, g, row)),
        }
        self.next += 1;
    }

    /// The stream, once every row is pushed.
    pub fn finish(self) -> Vec<u8> {
        debug_assert_eq!(self.next, self.walk.planes * self.walk.rows);
        let mut streams = self.coders.into_iter().map(|k| k.e.finish_short());
        let narrow = streams.next().expect("the narrow coder");
        match streams.next() {
            Some(wide) if wide.len() < narrow.len() => wide,
            _ => narrow,
        }
    }
}

/// A detail band without parent of extents `dims` decoded from `data` a row at a time
/// as the caller asks ([`super::decode_rows`]'s rows).
pub struct RowDecoder<'a> {
    d: Decoder<'a>,
    walk: Walk,
    m: Box<Models>,
    r: Row,
    q: Window,
    next: usize,
}

impl<'a> RowDecoder<'a> {
    pub fn new(data: &'a [u8], dims: &[usize], coding: Coding) -> Self {
        let mut d = Decoder::new_short(data);
        let classes = opened(&mut d, coding);
        let walk = Walk::new(dims);
        RowDecoder {
            d,
            walk,
            m: Box::new(Models::new(classes)),
            r: Row::new(walk.cols, classes),
            q: Window::new(walk, false),
            next: 0,
        }
    }

    /// The length of a row (the last extent).
    pub fn cols(&self) -> usize {
        self.walk.cols
    }

    /// The next row; an error past the last row or on an exponent over 62.
    pub fn next_row(&mut self) -> Result<&[i64]> {
        let w = self.walk;
        let g = self.next;
        if g >= w.planes * w.rows {
            return Err(crate::Error::format(
                format!("row {g} of a band of {} rows", w.planes * w.rows),
                "no rows past the band's",
            ));
        }
        let ctx = Ctx {
            walk: w,
            parent: None,
        };
        let (p, y) = (g / w.rows, g % w.rows);
        ctx.prepare(&mut self.r, self.q.neighbours(&ctx, p, y, g), y, 0);
        let out = self.q.row_mut(g);
        let (mut w1, mut w2) = (0, 0);
        for (x, o) in out.iter_mut().enumerate() {
            let v = decode_value(&mut self.d, &mut self.m, self.r.context(x, w1, w2))?;
            *o = v;
            w2 = w1;
            w1 = v;
        }
        self.next += 1;
        Ok(self.q.row(g))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entropy::walk::testing::sample;

    /// Rows pushed give the bytes of `encode_stream_rows`, and come back from
    /// `RowDecoder` as `decode_rows` gives them, in 2-D and 3-D, in both codings.
    #[test]
    fn rows_pushed_give_the_stream_of_encode_stream_rows() {
        for dims in [vec![7usize, 13], vec![3, 5, 9], vec![1, 1], vec![4, 1, 6]] {
            let n: usize = dims.iter().product();
            let cols = *dims.last().unwrap();
            let mut q = sample(n, n as u64 + 3, 40);
            q[0] = 5000;
            for coding in [Coding::Narrow, Coding::Chosen] {
                let whole = super::super::encode_stream_rows(&dims, None, coding, |g, out| {
                    out.copy_from_slice(&q[g * cols..(g + 1) * cols])
                });
                let mut e = RowEncoder::new(&dims, coding);
                for row in q.chunks(cols) {
                    e.push(row);
                }
                let bytes = e.finish();
                assert_eq!(bytes, whole, "{dims:?} {coding:?}");
                let mut d = RowDecoder::new(&bytes, &dims, coding);
                let mut back = Vec::new();
                for _ in 0..n / cols {
                    back.extend_from_slice(d.next_row().unwrap());
                }
                assert_eq!(back, q, "{dims:?} {coding:?}");
                assert!(d.next_row().is_err());
            }
        }
    }
}
