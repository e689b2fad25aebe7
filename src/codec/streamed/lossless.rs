//! `--lossless` as one transform at any size: the integer 5/3 pyramid streamed a few
//! rows per level at a time ([`super::lift`]), each band's stripes of code-blocks coded
//! as they complete (the stripes of [`super::Coder`], the indices the transform's
//! values, the file's block coder). The file is the whole-array lossless encoder's
//! ([`crate::codec::encode`] of the same raster: the same header, transform values,
//! blocks and bytes; tested), so every 3.x reader reads it; it decodes streamed too
//! (`StreamedDecoder`).

use super::lift::LiftPlan;
use super::Coder;
use crate::codec::lossy::{header_with, Frame};
use crate::codec::options::{EncodeOptions, Format, Rate};
use crate::codec::plan::Plan;
use crate::codec::{lossless, max_error, meta, tiles};
use crate::format::header::Colour;
use crate::format::tag::{HEAD, LEVL, MEND, META};
use crate::format::{self, Mode};
use crate::io::slab::{Shape, SlabSource};
use crate::io::Samples;
use crate::{Error, Result};
use rayon::prelude::*;

/// Whether the options and raster make a lossless file the stream writes: `--lossless`
/// (or a `--max-error` bound that keeps every sample exact) on 8- or 16-bit integer
/// samples ([`lossless::narrow`]: every transform value fits the coder's `i32` rows).
/// The rest of [`super::covers`] (no voids, 2–4 axes, format 3) holds too.
pub(super) fn streams(shape: &Shape, opts: &EncodeOptions) -> bool {
    let exact = match opts.rate {
        Rate::Lossless => true,
        Rate::MaxError(e) => max_error::is_exact(e, shape.sample_type).unwrap_or(false),
        _ => false,
    };
    exact && lossless::narrow(shape.sample_type) && opts.format == Format::Blocks
}

impl Coder<'_> {
    /// Row `y` of band `j`, integer values that are the indices (a lossless file): held
    /// as `i32`, and the stripes it completes coded.
    fn take_indices(&mut self, j: usize, y: usize, data: &[i64]) {
        if self.err.is_some() || self.bands[j].grid.is_empty() {
            return;
        }
        let q = data
            .iter()
            .map(|&v| i32::try_from(v))
            .collect::<std::result::Result<Vec<i32>, _>>();
        let r = match q {
            Ok(q) => {
                self.bands[j].rows.insert(y, q);
                self.landed(j, y)
            }
            Err(_) => Err(Error::parameter(
                "raster",
                "a transform value past 32 bits",
                "8- or 16-bit samples whose lossless transform fits 32 bits",
            )),
        };
        if let Err(e) = r {
            self.err = Some(e);
        }
    }
}

/// The lossless file of the raster `src` hands out in slabs (module doc), written into
/// `out`; returns the bytes written.
pub(super) fn encode<S: SlabSource + ?Sized, W: std::io::Write>(
    src: &mut S,
    opts: &EncodeOptions,
    out: &mut W,
) -> Result<u64> {
    let range = tiles::first_pass(src, false)?.range;
    // after the first pass: the metadata lists the voids it found (`super::voids`)
    let shape = src.shape().clone();
    let nc = shape.channels;
    let colour = if nc >= 3 {
        Colour::YCoCgR
    } else {
        Colour::None
    };
    let frame = Frame {
        dims: &shape.dims,
        channels: nc,
        sample_type: shape.sample_type,
        kind: shape.kind,
    };
    let header = header_with(
        &frame,
        &crate::codec::encode::lossless_options(opts),
        Mode::Lossless,
        colour,
        range,
        &shape.meta,
    )?;
    let plan = Plan::new(&header)?;
    let lp = LiftPlan::new(&plan.pyr, &plan.bands)?;
    let mut chans = (0..nc)
        .map(|_| {
            Ok(Channel {
                coder: Coder::new(&plan, vec![1.0; plan.bands.len()], None),
                spill: Spill::new(plan.bands.len())?,
            })
        })
        .collect::<Result<Vec<Channel>>>()?;
    {
        let mut analyses: Vec<_> = chans
            .iter_mut()
            .map(|ch| lp.analysis(move |j, y, d: &[i64]| ch.take(j, y, d)))
            .collect();
        let d0 = shape.dims[0];
        let row_len = lp.row_len();
        // about 2^20 positions a slab
        let rows = ((1usize << 20) / row_len.max(1)).clamp(1, d0);
        for r0 in (0..d0).step_by(rows) {
            let r1 = (r0 + rows).min(d0);
            let planes = planes_i64(&src.read_rows(r0..r1)?, nc, colour == Colour::YCoCgR)?;
            // the channels' transforms in parallel (each one's stripes too)
            analyses
                .par_iter_mut()
                .zip(planes)
                .map(|(a, p)| {
                    for row in p.chunks(row_len.max(1)) {
                        a.push(row.to_vec())?;
                    }
                    Ok(())
                })
                .collect::<Result<()>>()?;
        }
        for a in analyses {
            let _sink = a.finish()?;
        }
    }
    write_file(out, &header, &meta::to_bytes(&shape.meta), &plan, chans)
}

/// One channel while it streams: its bands' stripes ([`Coder`]) and the scratch file
/// their coded blocks go to.
struct Channel<'p> {
    coder: Coder<'p>,
    spill: Spill,
}

impl Channel<'_> {
    /// Band row `y` of band `j` to the coder, and the stripes it completes to the
    /// scratch file.
    fn take(&mut self, j: usize, y: usize, d: &[i64]) {
        self.coder.take_indices(j, y, d);
        if self.spill.err.is_none() {
            if let Err(e) = self.spill.take(&mut self.coder) {
                self.spill.err = Some(e);
            }
        }
    }
}

/// The coded blocks of a channel's bands moved out of memory as their stripes are
/// coded: appended to a scratch file in the temporary folder (unlinked at once where
/// the system allows, else when dropped), each block's place kept. A lossless file is
/// about as large as its samples' bits: held whole, a 16384² RGB u16 file alone would
/// be most of a gigabyte.
struct Spill {
    file: std::io::BufWriter<std::fs::File>,
    path: std::path::PathBuf,
    at: u64,
    /// per band, each block's `(offset, length)` in the file
    places: Vec<Vec<(u64, u64)>>,
    /// per band, the stripes moved
    moved: Vec<usize>,
    err: Option<Error>,
}

impl Spill {
    fn new(bands: usize) -> Result<Spill> {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!(".mra-lossless-{}-{n}.tmp", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)?;
        let _ = std::fs::remove_file(&path);
        Ok(Spill {
            file: std::io::BufWriter::with_capacity(1 << 20, file),
            path,
            at: 0,
            places: vec![Vec::new(); bands],
            moved: vec![0; bands],
            err: None,
        })
    }

    /// Move the coded stripes of `k`'s bands not yet moved (each band's in order).
    fn take(&mut self, k: &mut Coder<'_>) -> Result<()> {
        use std::io::Write;
        for (j, b) in k.bands.iter_mut().enumerate() {
            let per: usize = b.grid.counts[1..].iter().product();
            while self.moved[j] < b.stripes() && b.coded[self.moved[j]] {
                let s = self.moved[j];
                for st in &mut b.streams[s * per..(s + 1) * per] {
                    self.file.write_all(st)?;
                    self.places[j].push((self.at, st.len() as u64));
                    self.at += st.len() as u64;
                    *st = Vec::new();
                }
                self.moved[j] += 1;
            }
        }
        Ok(())
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Write the file: signature, `HEAD`, `mETA` (when `meta` is not empty), the `LEVL`
/// chunks ([`Plan::put_levels`]'s bytes, every band's step ratio 1) with the blocks read
/// back from the channels' scratch files, and `MEND`; returns the bytes written.
fn write_file<W: std::io::Write>(
    out: &mut W,
    header: &crate::format::Header,
    meta: &[u8],
    plan: &Plan,
    mut chans: Vec<Channel<'_>>,
) -> Result<u64> {
    use std::io::{Read, Seek, SeekFrom, Write};
    for ch in &mut chans {
        if let Some(e) = ch.coder.err.take().or(ch.spill.err.take()) {
            return Err(e);
        }
        if ch.coder.bands.iter().any(|b| b.coded.contains(&false)) {
            return Err(Error::parameter(
                "raster",
                "a band",
                "every stripe of code-blocks complete at the end of the stream",
            ));
        }
        ch.spill.take(&mut ch.coder)?;
        ch.spill.file.flush().map_err(Error::from)?;
    }
    let mut n = format::SIGNATURE.len() as u64;
    out.write_all(&format::SIGNATURE)?;
    n += format::write_chunk(out, HEAD, &[&header.to_bytes()])?;
    if !meta.is_empty() {
        n += format::write_chunk(out, META, &[meta])?;
    }
    let mut buf = vec![0u8; 1 << 20];
    for (level, js) in plan.level_groups() {
        // the entries' heads in memory, the blocks' bytes in the scratch files
        let mut pieces: Vec<Piece> = vec![Piece::Head((level as u16).to_le_bytes().to_vec())];
        for &j in &js {
            for (c, ch) in chans.iter().enumerate() {
                let places = &ch.spill.places[j];
                let mut idx = Vec::new();
                format::put_varint(&mut idx, places.len() as u64);
                for p in places {
                    format::put_varint(&mut idx, p.1);
                }
                let len = idx.len() as u64 + places.iter().map(|p| p.1).sum::<u64>();
                let mut head = 1.0f32.to_le_bytes().to_vec();
                format::put_varint(&mut head, len);
                head.extend_from_slice(&idx);
                pieces.push(Piece::Head(head));
                for &(at, len) in places {
                    match pieces.last_mut() {
                        Some(Piece::Spilled(pc, pat, plen)) if *pc == c && *pat + *plen == at => {
                            *plen += len
                        }
                        _ => pieces.push(Piece::Spilled(c, at, len)),
                    }
                }
            }
        }
        let total: u64 = pieces.iter().map(Piece::len).sum();
        let total = u32::try_from(total).map_err(|_| {
            Error::parameter(
                "raster",
                "a level of over 4 GiB coded",
                "a LEVL chunk under 4 GiB",
            )
        })?;
        let kind = LEVL;
        out.write_all(&total.to_le_bytes())?;
        out.write_all(kind)?;
        let mut crc = crate::format::crc::Crc32c::new();
        crc.update(kind);
        for p in &pieces {
            match p {
                Piece::Head(h) => {
                    out.write_all(h)?;
                    crc.update(h);
                }
                Piece::Spilled(c, at, len) => {
                    let f = chans[*c].spill.file.get_mut();
                    f.seek(SeekFrom::Start(*at))?;
                    let mut left = *len;
                    while left > 0 {
                        let k = left.min(buf.len() as u64) as usize;
                        f.read_exact(&mut buf[..k])?;
                        out.write_all(&buf[..k])?;
                        crc.update(&buf[..k]);
                        left -= k as u64;
                    }
                }
            }
        }
        out.write_all(&crc.finish().to_le_bytes())?;
        n += total as u64 + 12;
    }
    n += format::write_chunk(out, MEND, &[])?;
    Ok(n)
}

/// A piece of a `LEVL` chunk's payload: bytes in memory, or `(channel, offset,
/// length)` in a channel's scratch file.
enum Piece {
    Head(Vec<u8>),
    Spilled(usize, u64, u64),
}

impl Piece {
    fn len(&self) -> u64 {
        match self {
            Piece::Head(h) => h.len() as u64,
            Piece::Spilled(_, _, len) => *len,
        }
    }
}

/// The channel planes of interleaved 8- or 16-bit samples `s` (`c` channels) as
/// integers, the first three through YCoCg-R when `ycocg` (as the whole-array encoder
/// maps them).
fn planes_i64(s: &Samples, c: usize, ycocg: bool) -> Result<Vec<Vec<i64>>> {
    fn split<T: Copy + Into<i64>>(v: &[T], c: usize, ycocg: bool) -> Vec<Vec<i64>> {
        let n = v.len() / c.max(1);
        let mut planes: Vec<Vec<i64>> = (0..c).map(|_| Vec::with_capacity(n)).collect();
        for px in v.chunks_exact(c) {
            let first = if ycocg {
                let (y, co, cg) = lossless::ycocg_r(px[0].into(), px[1].into(), px[2].into());
                planes[0].push(y);
                planes[1].push(co);
                planes[2].push(cg);
                3
            } else {
                0
            };
            for (p, &x) in planes[first..].iter_mut().zip(&px[first..]) {
                p.push(x.into());
            }
        }
        planes
    }
    Ok(match s {
        Samples::U8(v) => split(v, c, ycocg),
        Samples::I8(v) => split(v, c, ycocg),
        Samples::U16(v) => split(v, c, ycocg),
        Samples::I16(v) => split(v, c, ycocg),
        other => {
            return Err(Error::parameter(
                "sample type",
                other.sample_type(),
                "8- or 16-bit integer samples for a streamed lossless file",
            ))
        }
    })
}
