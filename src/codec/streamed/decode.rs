//! The streamed whole decode ([`StreamedDecoder`]): the band rows of a one-piece lossy
//! code-block file pulled through the streamed synthesis a batch of stripes at a time.

use crate::codec::tiles;
use crate::entropy::codeblocks::{parent_box, Grid};
use crate::entropy::{BandKind, Parent};
use crate::format::{Header, Mode};
use crate::io::slab::Shape;
use crate::io::Samples;
use crate::tensor::stream::StreamPlan;
use crate::{Error, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::Range;

mod lossless;

/// Whether a whole decode of the file of header `h` goes through [`StreamedDecoder`]
/// in [`crate::codec::SlabDecoder`]: a one-piece lossy file of code-blocks (no residual
/// layer, no voids, any block coder) of 2 or 3 axes over the one-piece limit
/// ([`tiles::default_tile`] would cut it). Under the limit the whole-array decode is
/// kept: measured side by side on idle cores, the stripes saved memory (flower peak
/// RSS 74 → 62 MB) but not time, and lost the parallel speed-up of small images
/// (kodim01 at effort 7 on 2 threads 0.024 → 0.040 s).
pub fn decodes_streamed(h: &Header) -> bool {
    !h.is_tiled()
        && h.version.has_blocks()
        && (h.mode == Mode::Lossy || lossless::decodes(h))
        && !h.voids
        && (2..=3).contains(&h.dims.len())
        && h.levels > 0
        && tiles::default_tile(&h.dims, h.channels) != h.dims
}

/// Rows of the output a slab of [`StreamedDecoder`] holds (about 2^16 positions: its
/// planes stay in cache and under the allocator's mapping threshold, so that they are
/// reused rather than mapped and faulted in afresh).
fn slab_rows(row_len: usize, d0: usize) -> usize {
    ((1usize << 16) / row_len.max(1)).clamp(1, d0.max(1))
}

/// A whole decode of a one-piece lossy code-block file in bounded memory: the band rows
/// pulled through the streamed synthesis ([`StreamPlan::synthesis`]), each batch of
/// stripes of code-blocks (as many stripes as threads, decoded in parallel by
/// [`crate::entropy::codeblocks::decode_blocks_into`], any block coder) decoded when its
/// first row is asked for and kept while it is read (the last [`KEPT_STRIPES`] batches
/// of a band with children, as indices; the last one of a band without, dequantized),
/// the channels synthesized in parallel and the rows converted to samples a slab at a
/// time. The synthesis runs on a thread of its own that hands the slabs over; the
/// samples are those of the whole-array decode (the stream's synthesis gives its bits,
/// the blocks decode to the same indices in any batch).
pub struct StreamedDecoder {
    shape: Shape,
    rx: std::sync::mpsc::Receiver<Result<Samples>>,
    done: bool,
}

/// Decoded batches of stripes a band with children keeps (an older one asked again is
/// decoded again).
const KEPT_STRIPES: usize = 2;

impl StreamedDecoder {
    /// Read the file at `path` (its chunks checked, the code-blocks' bytes held) and
    /// start the synthesis.
    pub fn open(path: &std::path::Path) -> Result<StreamedDecoder> {
        let f = std::fs::File::open(path)?;
        let len = f.metadata()?.len();
        let p = crate::codec::container::read_chunks(std::io::BufReader::new(f), len, 0, false)?;
        StreamedDecoder::of(p)
    }

    /// Start the synthesis of the read file `p` (an error when the stream does not decode it).
    pub(in crate::codec) fn of(p: crate::codec::container::Parsed) -> Result<StreamedDecoder> {
        let h = &p.header;
        let what = format!("a {:?} file of {:?} in {} levels", h.mode, h.dims, h.levels);
        StreamedDecoder::streaming(p)?.map_err(|_| {
            Error::format(
                what,
                "a lossy 3.0 file of 2 or 3 axes without voids, laid out as the stream lays out its pyramid",
            )
        })
    }

    /// [`StreamedDecoder::of`], the file handed back when it is not one the stream
    /// decodes (its pyramid laid out otherwise than [`StreamPlan`] lays it out).
    pub(in crate::codec) fn streaming(
        p: crate::codec::container::Parsed,
    ) -> Result<std::result::Result<StreamedDecoder, crate::codec::container::Parsed>> {
        let h = &p.header;
        let integer = lossless::decodes(h);
        if !h.version.has_blocks()
            || !(h.mode == Mode::Lossy || integer)
            || h.voids
            || h.dims.len() < 2
        {
            return Ok(Err(p));
        }
        let shape = Shape {
            dims: h.dims.clone(),
            channels: h.channels,
            sample_type: h.sample_type,
            kind: h.kind,
            meta: p.meta.clone(),
        };
        if integer {
            let rx = lossless::start(p)?;
            return Ok(Ok(StreamedDecoder {
                shape,
                rx,
                done: false,
            }));
        }
        // the plan is checked here, before the thread starts
        let sp = StreamPlan::new(&h.dims, &p.plan.pyr.spec)?;
        if sp.bands() != p.plan.bands.as_slice() {
            return Ok(Err(p));
        }
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        drop(sp);
        std::thread::spawn(move || {
            let r = StreamPlan::new(&p.header.dims, &p.plan.pyr.spec)
                .and_then(|sp| synthesize(&p, &sp, &mut |s| tx.send(Ok(s)).is_ok()));
            if let Err(e) = r {
                let _ = tx.send(Err(e));
            }
        });
        Ok(Ok(StreamedDecoder {
            shape,
            rx,
            done: false,
        }))
    }

    /// The output's extents, type and metadata.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The next rows of the output, `None` after the last.
    pub fn next_slab(&mut self) -> Result<Option<Samples>> {
        if self.done {
            return Ok(None);
        }
        match self.rx.recv() {
            Ok(r) => r.map(Some),
            Err(_) => {
                self.done = true;
                Ok(None)
            }
        }
    }
}

/// Pull every row of the file `p` through the synthesis `sp` and hand its samples to
/// `send` a slab at a time (until it returns false).
fn synthesize(
    p: &crate::codec::container::Parsed,
    sp: &StreamPlan,
    send: &mut dyn FnMut(Samples) -> bool,
) -> Result<()> {
    let h = &p.header;
    let nc = h.channels;
    let errs: Vec<Failed> = (0..nc).map(|_| Failed::default()).collect();
    let mut sources = (0..nc)
        .map(|c| BandSource::new(p, c, errs[c].clone()))
        .collect::<Result<Vec<_>>>()?;
    let mut syn: Vec<_> = sources
        .iter_mut()
        .map(|s| sp.synthesis(move |j: usize, r: usize, out: &mut [f32]| s.fill(j, r, out)))
        .collect();
    let (d0, row_len) = (h.dims[0], sp.row_len());
    let rows = slab_rows(row_len, d0);
    for r0 in (0..d0).step_by(rows) {
        let n = (r0 + rows).min(d0) - r0;
        let mut planes: Vec<Vec<f32>> = (0..nc).map(|_| vec![0f32; n * row_len]).collect();
        // the channels' syntheses in parallel (each one's stripes too)
        let done: Vec<Result<()>> = syn
            .par_iter_mut()
            .zip(planes.par_iter_mut())
            .zip(&errs)
            .map(|((s, plane), err)| {
                for row in plane.chunks_mut(row_len.max(1)) {
                    s.pull(row)?;
                    if let Some(e) = err.take() {
                        return Err(e);
                    }
                }
                Ok(())
            })
            .collect();
        done.into_iter().collect::<Result<()>>()?;
        let samples = crate::codec::plan::to_samples(
            planes,
            n * row_len,
            h.colour == crate::format::header::Colour::YCoCg,
            (h.min, h.max),
            h.sample_type,
        );
        if !send(samples) {
            return Ok(());
        }
    }
    Ok(())
}

/// The first error of a channel's band source, read by the loop that pulls its rows.
#[derive(Clone, Default)]
pub(super) struct Failed(std::sync::Arc<std::sync::Mutex<Option<Error>>>);

impl Failed {
    pub(super) fn is_set(&self) -> bool {
        self.0.lock().map_or(true, |e| e.is_some())
    }

    fn set(&self, e: Error) {
        if let Ok(mut g) = self.0.lock() {
            g.get_or_insert(e);
        }
    }

    pub(super) fn take(&self) -> Option<Error> {
        self.0.lock().ok().and_then(|mut g| g.take())
    }
}

/// A batch of decoded stripes of a band: its first row and its rows in raster order,
/// dequantized (a band without children: what the synthesis reads) or as indices (a
/// band with children: its children's context, dequantized as it is read).
struct Batch {
    y0: usize,
    values: Values,
}

enum Values {
    Samples(Vec<f32>),
    Indices(Vec<i64>),
}

/// The band rows of one channel of a file, decoded a batch of stripes of code-blocks
/// at a time (the stripes of a batch in parallel, [`entropy::codeblocks::decode_blocks_into`]).
pub(super) struct BandSource<'a> {
    p: &'a crate::codec::container::Parsed,
    c: usize,
    grids: Vec<Grid>,
    /// each band's blocks (byte ranges in its entry); `None`: the band is absent
    sets: Vec<Option<Vec<Range<usize>>>>,
    steps: Vec<f64>,
    deltas: Vec<f64>,
    /// whether each band is another's parent
    parent: Vec<bool>,
    /// rows of a batch of each band (whole stripes)
    batch_rows: Vec<usize>,
    /// decoded batches of each band, by batch number
    kept: Vec<BTreeMap<usize, Batch>>,
    /// each band's last dropped batch, whose buffer the next one reuses (a fresh one
    /// of a megabyte or more would be mapped and faulted in afresh)
    spare: Vec<Option<Values>>,
    err: Failed,
}

impl<'a> BandSource<'a> {
    pub(super) fn new(
        p: &'a crate::codec::container::Parsed,
        c: usize,
        err: Failed,
    ) -> Result<BandSource<'a>> {
        let plan = &p.plan;
        let nb = plan.bands.len();
        let grids: Vec<Grid> = (0..nb)
            .map(|j| plan.grid(j).expect("a format 3 plan has code-blocks"))
            .collect();
        let sets = (0..nb)
            .map(|j| {
                p.bands[c][j]
                    .as_ref()
                    .map(|bc| {
                        crate::format::bands::parse_blocks(
                            &bc.data,
                            &grids[j].dims,
                            &grids[j].block,
                        )
                        .map(|s| s.streams)
                        .map_err(|e| {
                            Error::format(format!("band {j} of channel {c}: {e}"), "a valid band")
                        })
                    })
                    .transpose()
            })
            .collect::<Result<Vec<_>>>()?;
        let steps = (0..nb)
            .map(|j| p.bands[c][j].as_ref().map_or(0.0, |bc| bc.step))
            .collect();
        let deltas = (0..nb)
            .map(|j| crate::codec::plan::band_delta(&p.header, plan, j))
            .collect();
        let parent = (0..nb).map(|j| plan.parents.contains(&Some(j))).collect();
        // a batch of as many stripes as threads in an image, so that its stripes
        // decode in parallel (a volume's stripe is many planes: one a batch, its
        // blocks in parallel, keeps a 1024³ decode under 1 GiB — 1.63 GB on 2 threads
        // with two); a band of odd stripes (blocks one row tall) in one batch, since a
        // batch's parent rows must start at half its first row
        let threads = rayon::current_num_threads().max(1);
        let batch_rows = grids
            .iter()
            .map(|g| {
                let per = if g.dims.len() > 2 { 1 } else { threads };
                let t = g.block[0].max(1);
                if t % 2 == 1 {
                    g.dims[0].max(1)
                } else {
                    t.saturating_mul(per)
                }
            })
            .collect();
        Ok(BandSource {
            p,
            c,
            grids,
            sets,
            steps,
            deltas,
            parent,
            batch_rows,
            kept: (0..nb).map(|_| BTreeMap::new()).collect(),
            spare: (0..nb).map(|_| None).collect(),
            err,
        })
    }

    /// Row `r` of band `j`, dequantized, into `out` (zeros after an error).
    fn fill(&mut self, j: usize, r: usize, out: &mut [f32]) {
        if self.err.is_set() || self.sets[j].is_none() {
            out.fill(0.0);
            return;
        }
        let b = r / self.batch_rows[j];
        if let Err(e) = self.ensure(j, b) {
            self.err.set(e);
            out.fill(0.0);
            return;
        }
        let len = out.len();
        let batch = &self.kept[j][&b];
        let at = (r - batch.y0) * len;
        match &batch.values {
            Values::Samples(v) => out.copy_from_slice(&v[at..at + len]),
            Values::Indices(q) => crate::codec::plan::dequantize_row(
                &q[at..at + len],
                self.steps[j],
                self.deltas[j],
                out,
            ),
        }
    }

    /// Row `r` of band `j` as indices (a lossless file: the transform's values) into
    /// `out` (zeros after an error).
    pub(super) fn fill_indices(&mut self, j: usize, r: usize, out: &mut [i64]) {
        if self.err.is_set() || self.sets[j].is_none() {
            out.fill(0);
            return;
        }
        let b = r / self.batch_rows[j];
        if let Err(e) = self.ensure(j, b) {
            self.err.set(e);
            out.fill(0);
            return;
        }
        let len = out.len();
        let batch = &self.kept[j][&b];
        let at = (r - batch.y0) * len;
        match &batch.values {
            Values::Indices(q) => out.copy_from_slice(&q[at..at + len]),
            Values::Samples(_) => unreachable!("a lossless band keeps its indices"),
        }
    }

    /// The rows of band `j`'s batch `b`.
    fn batch(&self, j: usize, b: usize) -> Range<usize> {
        let n = self.batch_rows[j];
        let d0 = self.grids[j].dims[0];
        (b * n).min(d0)..((b + 1) * n).min(d0)
    }

    /// The parent band of `j` and the rows of it that `rows` of `j` read.
    fn parent_rows(&self, j: usize, rows: &Range<usize>) -> Option<(usize, Range<usize>)> {
        let plan = &self.p.plan;
        if plan.bands[j].level == 0 {
            return None;
        }
        let pj = plan.parents[j]?;
        let pd = &self.grids[pj].dims;
        if pd.contains(&0) {
            return None;
        }
        Some((
            pj,
            parent_box(std::slice::from_ref(rows), &pd[..1])[0].clone(),
        ))
    }

    /// Decode batch `b` of band `j` (and the parent batches it reads) unless kept.
    fn ensure(&mut self, j: usize, b: usize) -> Result<()> {
        if self.kept[j].contains_key(&b) {
            return Ok(());
        }
        let rows = self.batch(j, b);
        // the parent's rows the batch reads, as one array of extents `pdims`
        let mut par: Option<(Vec<usize>, Vec<i64>)> = None;
        if let Some((pj, prows)) = self.parent_rows(j, &rows) {
            if self.sets[pj].is_some() {
                let plen: usize = self.grids[pj].dims[1..].iter().product();
                let mut v = Vec::with_capacity(prows.len() * plen);
                for y in prows.clone() {
                    let pb = y / self.batch_rows[pj];
                    self.ensure(pj, pb)?;
                    let batch = &self.kept[pj][&pb];
                    let Values::Indices(q) = &batch.values else {
                        unreachable!("a parent band keeps its indices")
                    };
                    let at = (y - batch.y0) * plen;
                    v.extend_from_slice(&q[at..at + plen]);
                }
                let mut pdims = self.grids[pj].dims.clone();
                pdims[0] = prows.len();
                par = Some((pdims, v));
            }
        }
        let g = &self.grids[j];
        let per: usize = g.counts[1..].iter().product();
        let tall = g.block[0];
        let mut ldims = g.dims.clone();
        ldims[0] = rows.len();
        let local = Grid::new(&ldims, &g.block);
        let first = rows.start / tall * per;
        let which: Vec<usize> = (0..local.len()).collect();
        let data = &self.p.bands[self.c][j]
            .as_ref()
            .expect("a band with blocks is present")
            .data;
        let set = self.sets[j].as_ref().expect("checked by the caller");
        let streams: Vec<&[u8]> = which
            .iter()
            .map(|&i| set.get(first + i).map(|r| &data[r.clone()]).unwrap_or(&[]))
            .collect();
        let kind = if self.p.plan.bands[j].level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        let parent = par.as_ref().map(|(dims, data)| Parent { data, dims });
        let h = &self.p.header;
        let (coding, coder) = (
            crate::codec::plan::coding_of(h),
            crate::codec::plan::coder_of(h),
        );
        let row_len = *g.dims.last().expect("a band of 2 or 3 axes");
        let n = ldims.iter().product::<usize>();
        let failed = |e: Error| {
            Error::format(
                format!("band {j} of channel {}: {e}", self.c),
                "a valid band",
            )
        };
        let spare = self.spare[j].take();
        let values = if self.parent[j] || self.p.header.mode == Mode::Lossless {
            let mut q = match spare {
                Some(Values::Indices(v)) => v,
                _ => Vec::new(),
            };
            q.clear();
            q.resize(n, 0);
            let put = crate::entropy::codeblocks::Put {
                wide: |o: &mut [i64], q: &[i64]| o.copy_from_slice(q),
                narrow: |o: &mut [i64], q: &[i32]| {
                    for (o, &x) in o.iter_mut().zip(q) {
                        *o = x as i64;
                    }
                },
            };
            let out: Vec<&mut [i64]> = q.chunks_mut(row_len.max(1)).collect();
            crate::entropy::codeblocks::decode_blocks_into(
                out,
                &local,
                &which,
                &streams,
                (kind, parent),
                coding,
                coder,
                &put,
            )
            .map_err(failed)?;
            Values::Indices(q)
        } else {
            let (step, delta) = (self.steps[j], self.deltas[j]);
            let mut x = match spare {
                Some(Values::Samples(v)) => v,
                _ => Vec::new(),
            };
            x.clear();
            x.resize(n, 0.0);
            let put = crate::codec::plan::dequantizing_put(step, delta);
            let out: Vec<&mut [f32]> = x.chunks_mut(row_len.max(1)).collect();
            crate::entropy::codeblocks::decode_blocks_into(
                out,
                &local,
                &which,
                &streams,
                (kind, parent),
                coding,
                coder,
                &put,
            )
            .map_err(failed)?;
            Values::Samples(x)
        };
        // a band without children is read in order: its last batch is enough
        let keep = if self.parent[j] { KEPT_STRIPES } else { 1 };
        let kept = &mut self.kept[j];
        kept.insert(
            b,
            Batch {
                y0: rows.start,
                values,
            },
        );
        while kept.len() > keep {
            let old = *kept.keys().find(|&&k| k != b).expect("more than one");
            if let Some(batch) = kept.remove(&old) {
                self.spare[j] = Some(batch.values);
            }
        }
        Ok(())
    }
}
