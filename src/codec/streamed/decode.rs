//! The streamed whole decode ([`StreamedDecoder`]): the band rows of a one-piece lossy
//! or lossless code-block file pulled through the streamed synthesis a batch of stripes at
//! a time (a lossless file through the integer synthesis, [`lossless`]).

mod lossless;
mod residual;

use crate::codec::tiles;
use crate::entropy::codeblocks::{parent_box, Grid};
use crate::entropy::{BandKind, Parent};
use crate::format::{Header, Mode};
use crate::io::slab::Shape;
use crate::io::Samples;
use crate::tensor::stream::StreamPlan;
use crate::{Error, Result};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::sync::{Arc, Mutex};

/// Whether a whole decode of the file of header `h` goes through [`StreamedDecoder`]
/// in [`crate::codec::SlabDecoder`]: a one-piece lossy or `--max-error` file of
/// code-blocks (its residual layer added slab by slab, [`residual`]; voids marked from
/// the coded mask after it, [`super::voids::marking`]; any block coder) of 2 or 3 axes
/// over the one-piece limit
/// ([`tiles::default_tile`] would cut it). Under the limit the whole-array decode is
/// kept: measured side by side on idle cores, the stripes saved memory (flower peak
/// RSS 74 → 62 MB) but not time, and lost the parallel speed-up of small images
/// (kodim01 at effort 7 on 2 threads 0.024 → 0.040 s).
pub fn decodes_streamed(h: &Header) -> bool {
    !h.is_tiled()
        && h.version.has_blocks()
        && (matches!(h.mode, Mode::Lossy | Mode::MaxError) || lossless::decodes(h))
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
    rx: Slabs,
    done: bool,
}

/// Where [`StreamedDecoder`]'s slabs come from: the synthesis, or the synthesis through
/// the marking of voids ([`super::voids::marking`]).
enum Slabs {
    Plain(std::sync::mpsc::Receiver<Result<Samples>>),
    Marked(std::sync::mpsc::Receiver<super::voids::Marked>),
}

impl StreamedDecoder {
    /// Read the file at `path` (its chunks checked; a one-piece 3.0 file's code-blocks
    /// left in the file, each batch read from it as it is decoded,
    /// [`crate::codec::block_file`]) and start the synthesis.
    pub fn open(path: &std::path::Path) -> Result<StreamedDecoder> {
        StreamedDecoder::of(crate::codec::indexed_read::read_for_stream(path)?)
    }

    /// Start the synthesis of the read file `p` (an error when the stream does not decode it).
    pub(in crate::codec) fn of(p: crate::codec::container::Parsed) -> Result<StreamedDecoder> {
        let h = &p.header;
        let what = format!("a {:?} file of {:?} in {} levels", h.mode, h.dims, h.levels);
        StreamedDecoder::streaming(p)?.map_err(|_| {
            Error::format(
                what,
                "a lossy 3.0 file of 2 or 3 axes (voids listed as a coded mask), laid out as the stream lays out its pyramid",
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
            || !(matches!(h.mode, Mode::Lossy | Mode::MaxError) || integer)
            || h.dims.len() < 2
        {
            return Ok(Err(p));
        }
        // voids: the coded mask (a run list of older files is marked by the whole decode)
        let voids = match h.voids {
            true => match crate::codec::voids::coded_bytes(&p.meta) {
                Some(coded) => Some(coded),
                None => return Ok(Err(p)),
            },
            false => None,
        };
        let mut shape = Shape {
            dims: h.dims.clone(),
            channels: h.channels,
            sample_type: h.sample_type,
            kind: h.kind,
            meta: p.meta.clone(),
        };
        // the key goes as the whole decode drops it once the voids are marked
        shape.meta.extra.remove(crate::format::meta::VOID_RUNS);
        if integer {
            let rx = lossless::start(p)?;
            return Ok(Ok(StreamedDecoder::marking(shape, rx, voids)));
        }
        // the plan is checked here, before the thread starts
        let sp = StreamPlan::new(&h.dims, &p.plan.pyr.spec)?;
        if sp.bands() != p.plan.bands.as_slice() {
            return Ok(Err(p));
        }
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        drop(sp);
        std::thread::spawn(move || {
            // a --max-error file's residual added to each slab of its base
            let r = residual::Residuals::new(&p).and_then(|mut resi| {
                let sp = StreamPlan::new(&p.header.dims, &p.plan.pyr.spec)?;
                synthesize(&p, &sp, &mut |mut s| match resi.add(&mut s) {
                    Ok(()) => tx.send(Ok(s)).is_ok(),
                    Err(e) => {
                        let _ = tx.send(Err(e));
                        false
                    }
                })
            });
            if let Err(e) = r {
                let _ = tx.send(Err(e));
            }
        });
        Ok(Ok(StreamedDecoder::marking(shape, rx, voids)))
    }

    /// The decoder of the slabs `rx` of a raster of `shape`, the voids of the coded
    /// mask `voids` marked when there is one.
    fn marking(
        shape: Shape,
        rx: std::sync::mpsc::Receiver<Result<Samples>>,
        voids: Option<Vec<u8>>,
    ) -> StreamedDecoder {
        let rx = match voids {
            Some(coded) => {
                let marker = shape.meta.nodata.unwrap_or(f64::NAN);
                Slabs::Marked(super::voids::marking(
                    rx,
                    &shape.dims,
                    shape.channels,
                    coded,
                    marker,
                ))
            }
            None => Slabs::Plain(rx),
        };
        StreamedDecoder {
            shape,
            rx,
            done: false,
        }
    }

    /// The output's extents, type and metadata.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The next rows of the output, `None` after the last.
    pub fn next_slab(&mut self) -> Result<Option<Samples>> {
        Ok(self.next_slab_voids()?.map(|(s, _)| s))
    }

    /// [`StreamedDecoder::next_slab`] and its void flags (one per sample) when the file
    /// lists voids.
    pub(in crate::codec) fn next_slab_voids(
        &mut self,
    ) -> Result<Option<(Samples, Option<Vec<bool>>)>> {
        if self.done {
            return Ok(None);
        }
        let got = match &self.rx {
            Slabs::Plain(rx) => rx.recv().map(|r| r.map(|s| (s, None))),
            Slabs::Marked(rx) => rx.recv().map(|r| r.map(|(s, f)| (s, Some(f)))),
        };
        match got {
            Ok(r) => r.map(Some),
            Err(_) => {
                self.done = true;
                Ok(None)
            }
        }
    }
}

/// Pull every row of the file `p` through the synthesis `sp` and hand its samples to
/// `send` a slab at a time (until it returns false). The slabs go in runs
/// ([`Schedule`]); while one run is synthesized (the channels in parallel), the batches
/// the next runs first read are decoded beside it (`rayon::join`: one after the other
/// on one thread, side by side on two, a batch's blocks in parallel either way).
fn synthesize(
    p: &crate::codec::container::Parsed,
    sp: &StreamPlan,
    send: &mut (dyn FnMut(Samples) -> bool + Send),
) -> Result<()> {
    let h = &p.header;
    let nc = h.channels;
    let errs: Vec<Failed> = (0..nc).map(|_| Failed::default()).collect();
    let sources = (0..nc)
        .map(|c| BandSource::new(p, c, errs[c].clone()))
        .collect::<Result<Vec<_>>>()?;
    let (d0, row_len) = (h.dims[0], sp.row_len());
    let rows = slab_rows(row_len, d0);
    let sched = Schedule::new(sp, &sources, rows);
    let decode_run = |k: usize| -> Result<Vec<Vec<Decoded>>> {
        sources
            .iter()
            .zip(&sched.decode)
            .map(|(s, d)| s.decode_all(&d[k]))
            .collect()
    };
    let settle = |got: Vec<Vec<Decoded>>, end: usize| {
        for ((s, got), last) in sources.iter().zip(got).zip(&sched.last) {
            s.settle(got, last, end);
        }
    };
    settle(decode_run(0)?, 0);
    let mut syn: Vec<_> = sources
        .iter()
        .map(|s| sp.synthesis(move |j: usize, r: usize, out: &mut [f32]| s.fill(j, r, out)))
        .collect();
    let runs = sched.starts.len() - 1;
    // the slabs' planes, reused (fresh ones of megabytes would be faulted in at every slab)
    let mut planes: Vec<Vec<f32>> = (0..nc).map(|_| vec![0f32; rows * row_len]).collect();
    for k in 0..runs {
        let slabs = sched.starts[k]..sched.starts[k + 1];
        let (made, next) = rayon::join(
            || -> Result<bool> {
                for slab in slabs {
                    let r0 = slab * rows;
                    let n = (r0 + rows).min(d0) - r0;
                    let mut bufs: Vec<&mut [f32]> =
                        planes.iter_mut().map(|p| &mut p[..n * row_len]).collect();
                    let done: Vec<Result<()>> = syn
                        .par_iter_mut()
                        .zip(bufs.par_iter_mut())
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
                    let bufs: Vec<&[f32]> = bufs.into_iter().map(|p| &*p).collect();
                    let samples = crate::codec::plan::slab_samples(
                        &bufs,
                        h.colour == crate::format::header::Colour::YCoCg,
                        (h.min, h.max),
                        h.sample_type,
                    );
                    if !send(samples) {
                        return Ok(false);
                    }
                }
                Ok(true)
            },
            || decode_run(k + 1),
        );
        if !made? {
            return Ok(());
        }
        settle(next?, sched.starts[k + 1]);
    }
    Ok(())
}

/// A batch `(band, batch number)` of one channel.
type BatchId = (usize, usize);

/// Batches of a band [`BandSource::ensure`] keeps.
const KEPT_ON_DEMAND: usize = 2;

/// A decoded batch and its name.
type Decoded = (BatchId, Arc<Batch>);

/// Slabs a run's decode looks ahead past the next run's start at least.
const LOOKAHEAD: usize = 8;

/// When each batch of each channel is decoded and dropped, from the order the synthesis
/// reads band rows ([`StreamPlan::pulls_by_row`]): a batch is first read at some slab
/// (as a band row, or as the parent of a batch first read there) and last read at
/// another. The slabs are cut into runs at every first and every last read + 1; before
/// run `k` starts, every batch it reads is decoded (by the previous run's side decode,
/// which takes every batch first read before the start of the run after `k`, or
/// [`LOOKAHEAD`] slabs past the start of `k`, whichever is later); after it ends, every
/// batch last read in it goes. A band without children so holds its stripe being read
/// and the next one, never a third.
struct Schedule {
    /// The slab each run starts at, then the number of slabs.
    starts: Vec<usize>,
    /// Per channel: the batches decoded before the first run (0), then by run `k`'s side
    /// decode (`k + 1`), in the order first read (a parent before its children).
    decode: Vec<Vec<Vec<BatchId>>>,
    /// Per channel: the slab each batch is last read at.
    last: Vec<HashMap<BatchId, usize>>,
}

impl Schedule {
    fn new(sp: &StreamPlan, sources: &[BandSource], rows: usize) -> Schedule {
        let (order, ends) = sp.pulls_by_row();
        let slabs = ends.len().div_ceil(rows.max(1));
        // per channel: the batches in the order first read, with that slab
        let mut firsts: Vec<Vec<(BatchId, usize)>> = Vec::new();
        let mut last: Vec<HashMap<BatchId, usize>> = Vec::new();
        for s in sources {
            let (mut first, mut lst) = (Vec::new(), HashMap::new());
            let mut at = 0;
            for (r, &end) in ends.iter().enumerate() {
                for &(j, row) in &order[at..end] {
                    s.read(j, row / s.batch_rows[j], r / rows, &mut first, &mut lst);
                }
                at = end;
            }
            firsts.push(first);
            last.push(lst);
        }
        let mut starts: Vec<usize> = firsts
            .iter()
            .flatten()
            .map(|&(_, f)| f)
            .chain(last.iter().flat_map(|l| l.values().map(|&e| e + 1)))
            .chain([0, slabs])
            .filter(|&e| e <= slabs)
            .collect();
        starts.sort_unstable();
        starts.dedup();
        let at = |i: usize| starts.get(i).copied().unwrap_or(slabs);
        // everything first read before `until[i]` is decoded by step `i`
        let runs = starts.len() - 1;
        let until: Vec<usize> = (0..runs)
            .map(|k| at(k + 1).max(at(k) + LOOKAHEAD))
            .chain([usize::MAX])
            .collect();
        let decode = firsts
            .iter()
            .map(|first| {
                let mut steps: Vec<Vec<BatchId>> = vec![Vec::new(); runs + 1];
                let mut i = 0;
                for &(id, f) in first {
                    while f >= until[i] {
                        i += 1;
                    }
                    steps[i].push(id);
                }
                steps
            })
            .collect();
        Schedule {
            starts,
            decode,
            last,
        }
    }
}

/// The first error of a channel's band source, read by the loop that pulls its rows.
#[derive(Clone, Default)]
pub(super) struct Failed(std::sync::Arc<std::sync::Mutex<Option<Error>>>);

impl Failed {
    fn is_set(&self) -> bool {
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
/// band with children: its children's context, dequantized as it is read; every band
/// of a lossless file, the transform's values).
struct Batch {
    y0: usize,
    values: Values,
}

enum Values {
    Samples(Vec<f32>),
    Indices(Vec<i64>),
    /// Indices of a lossless band that all fit in `i32` (half the memory of
    /// [`Values::Indices`], which a batch with a value past `i32` keeps instead).
    Narrow(Vec<i32>),
}

/// The decoded batches a channel holds, and each band's last dropped one, whose buffer
/// the next one reuses (a fresh one of a megabyte or more would be mapped and faulted
/// in afresh); and the buffer a batch's coded bytes are read into from a file
/// ([`crate::codec::block_file`]), reused from batch to batch.
struct Held {
    kept: Vec<BTreeMap<usize, Arc<Batch>>>,
    spare: Vec<Option<Values>>,
    bytes: Vec<u8>,
}

/// The band rows of one channel of a file, decoded a batch of stripes of code-blocks
/// at a time (every block of a batch in parallel, [`decode_grid`]) when [`Schedule`]
/// says, read by the synthesis ([`BandSource::fill`]) while the next batches decode.
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
    held: Mutex<Held>,
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
                        // the entry's length: its bytes', or the file's entry's (the
                        // index alone held, [`crate::codec::block_file`])
                        let len = match &p.blocks_in {
                            Some(f) => f.entry_len(c, j).unwrap_or(0),
                            None => bc.data.len() as u64,
                        };
                        crate::format::bands::parse_index(
                            &bc.data,
                            len,
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
        // a batch of one stripe (its blocks decode in parallel, [`decode_grid`]; two
        // stripes a batch took a 1024³ decode on 2 threads to 1.63 GB); a band of odd
        // stripes (blocks one row tall) in one batch, since a batch's parent rows must
        // start at half its first row
        let batch_rows = grids
            .iter()
            .map(|g| {
                let t = g.block[0].max(1);
                if t % 2 == 1 {
                    g.dims[0].max(1)
                } else {
                    t
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
            held: Mutex::new(Held {
                kept: (0..nb).map(|_| BTreeMap::new()).collect(),
                spare: (0..nb).map(|_| None).collect(),
                bytes: Vec::new(),
            }),
            err,
        })
    }

    /// Note that the synthesis reads batch `b` of band `j` at slab `slab` (and, the
    /// first time, its parent batches, first): `first` lists the batches in the order
    /// first read, `last` the slab each is last read at.
    fn read(
        &self,
        j: usize,
        b: usize,
        slab: usize,
        first: &mut Vec<(BatchId, usize)>,
        last: &mut HashMap<BatchId, usize>,
    ) {
        if self.sets[j].is_none() {
            return;
        }
        if let Some(e) = last.get_mut(&(j, b)) {
            *e = slab;
            return;
        }
        last.insert((j, b), slab);
        if let Some((pj, prows)) = self.parent_rows(j, &self.batch(j, b)) {
            let n = self.batch_rows[pj];
            for pb in prows.start / n..prows.end.div_ceil(n) {
                self.read(pj, pb, slab, first, last);
            }
        }
        first.push(((j, b), slab));
    }

    /// Row `r` of band `j`, dequantized, into `out` (zeros after an error, or when the
    /// band is absent).
    fn fill(&self, j: usize, r: usize, out: &mut [f32]) {
        if self.sets[j].is_none() {
            out.fill(0.0);
            return;
        }
        let b = r / self.batch_rows[j];
        let batch = self
            .held
            .lock()
            .ok()
            .and_then(|h| h.kept[j].get(&b).cloned());
        let Some(batch) = batch else {
            self.err.set(Error::format(
                format!(
                    "band {j} of channel {}: row {r} read before it was decoded",
                    self.c
                ),
                "the streamed decode's schedule",
            ));
            out.fill(0.0);
            return;
        };
        let len = out.len();
        let at = (r - batch.y0) * len;
        match &batch.values {
            Values::Samples(v) => out.copy_from_slice(&v[at..at + len]),
            Values::Indices(q) => crate::codec::plan::dequantize_row(
                &q[at..at + len],
                self.steps[j],
                self.deltas[j],
                out,
            ),
            Values::Narrow(_) => unreachable!("a lossy band is dequantized from i64 indices"),
        }
    }

    /// Row `r` of band `j` as indices (a lossless file: the transform's values) into
    /// `out` (zeros after an error), its batch decoded when first asked ([`Self::ensure`]).
    pub(super) fn fill_indices(&self, j: usize, r: usize, out: &mut [i64]) {
        if self.err.is_set() || self.sets[j].is_none() {
            out.fill(0);
            return;
        }
        let batch = match self.ensure(j, r / self.batch_rows[j]) {
            Ok(a) => a,
            Err(e) => {
                self.err.set(e);
                out.fill(0);
                return;
            }
        };
        let len = out.len();
        let at = (r - batch.y0) * len;
        match &batch.values {
            Values::Indices(q) => out.copy_from_slice(&q[at..at + len]),
            Values::Narrow(q) => {
                for (o, &x) in out.iter_mut().zip(&q[at..at + len]) {
                    *o = x as i64;
                }
            }
            Values::Samples(_) => unreachable!("a lossless band keeps its indices"),
        }
    }

    /// Batch `b` of band `j`, decoded now (its parent batches first) unless held: the
    /// path of a synthesis without a [`Schedule`] (the lossless stream's). A band keeps
    /// its last [`KEPT_ON_DEMAND`] batches; an older one asked again is decoded again.
    fn ensure(&self, j: usize, b: usize) -> Result<Arc<Batch>> {
        if let Some(a) = self
            .held
            .lock()
            .ok()
            .and_then(|h| h.kept[j].get(&b).cloned())
        {
            return Ok(a);
        }
        let mut fresh: Vec<Decoded> = Vec::new();
        if let Some((pj, prows)) = self.parent_rows(j, &self.batch(j, b)) {
            if self.sets[pj].is_some() {
                let n = self.batch_rows[pj];
                for pb in prows.start / n..prows.end.div_ceil(n) {
                    fresh.push(((pj, pb), self.ensure(pj, pb)?));
                }
            }
        }
        let batch = Arc::new(self.decode(j, b, &fresh)?);
        if let Ok(mut held) = self.held.lock() {
            let held = &mut *held;
            held.kept[j].insert(b, batch.clone());
            while held.kept[j].len() > KEPT_ON_DEMAND {
                let oldest = *held.kept[j].keys().next().expect("more than one held");
                if let Some(old) = held.kept[j]
                    .remove(&oldest)
                    .and_then(|a| Arc::try_unwrap(a).ok())
                {
                    held.spare[j] = Some(old.values);
                }
            }
        }
        Ok(batch)
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

    /// Decode the batches `ids` in order (a parent before its children).
    fn decode_all(&self, ids: &[BatchId]) -> Result<Vec<Decoded>> {
        let mut done: Vec<Decoded> = Vec::with_capacity(ids.len());
        for &(j, b) in ids {
            let batch = self.decode(j, b, &done)?;
            done.push(((j, b), Arc::new(batch)));
        }
        Ok(done)
    }

    /// Hold the decoded batches `got`, then drop every batch last read before slab
    /// `end` (`last`), its buffer kept for the band's next batch.
    fn settle(&self, got: Vec<Decoded>, last: &HashMap<BatchId, usize>, end: usize) {
        let Ok(mut held) = self.held.lock() else {
            return;
        };
        let held = &mut *held;
        for ((j, b), batch) in got {
            held.kept[j].insert(b, batch);
        }
        for (j, kept) in held.kept.iter_mut().enumerate() {
            let gone: Vec<usize> = kept
                .keys()
                .copied()
                .filter(|&b| last.get(&(j, b)).is_none_or(|&e| e < end))
                .collect();
            for b in gone {
                if let Some(batch) = kept.remove(&b).and_then(|a| Arc::try_unwrap(a).ok()) {
                    held.spare[j] = Some(batch.values);
                }
            }
        }
    }

    /// Batch `b` of band `j` from the batches `fresh` or those held.
    fn decoded(&self, j: usize, b: usize, fresh: &[Decoded]) -> Result<Arc<Batch>> {
        let found = match fresh.iter().find(|(id, _)| *id == (j, b)) {
            Some((_, a)) => Some(a.clone()),
            None => self
                .held
                .lock()
                .ok()
                .and_then(|h| h.kept[j].get(&b).cloned()),
        };
        found.ok_or_else(|| {
            Error::format(
                format!(
                    "band {j} of channel {}: batch {b} read before it was decoded",
                    self.c
                ),
                "the streamed decode's schedule",
            )
        })
    }

    /// Batch `b` of band `j`, its parent's rows from the batches `fresh` or those held.
    fn decode(&self, j: usize, b: usize, fresh: &[Decoded]) -> Result<Batch> {
        let rows = self.batch(j, b);
        // the parent's rows the batch reads, as one array of extents `pdims`
        let mut par: Option<(Vec<usize>, Vec<i64>)> = None;
        if let Some((pj, prows)) = self.parent_rows(j, &rows) {
            if self.sets[pj].is_some() {
                let plen: usize = self.grids[pj].dims[1..].iter().product();
                let mut v = Vec::with_capacity(prows.len() * plen);
                let mut got: Option<(usize, Arc<Batch>)> = None;
                for y in prows.clone() {
                    let pb = y / self.batch_rows[pj];
                    if got.as_ref().is_none_or(|g| g.0 != pb) {
                        got = Some((pb, self.decoded(pj, pb, fresh)?));
                    }
                    let batch = &got.as_ref().expect("just set").1;
                    let at = (y - batch.y0) * plen;
                    match &batch.values {
                        Values::Indices(q) => v.extend_from_slice(&q[at..at + plen]),
                        Values::Narrow(q) => v.extend(q[at..at + plen].iter().map(|&x| x as i64)),
                        Values::Samples(_) => unreachable!("a parent band keeps its indices"),
                    }
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
        let set = self.sets[j].as_ref().expect("checked by the caller");
        let mine = &set[first.min(set.len())..(first + local.len()).min(set.len())];
        // the batch's blocks follow one another in the entry: held, or read from the
        // file in one read into the channel's reused buffer
        let mut bytes = Vec::new();
        let (data, base) = match &self.p.blocks_in {
            Some(f) => {
                let span = match (mine.first(), mine.last()) {
                    (Some(a), Some(b)) => a.start..b.end,
                    _ => 0..0,
                };
                bytes = self
                    .held
                    .lock()
                    .map(|mut h| std::mem::take(&mut h.bytes))
                    .unwrap_or_default();
                f.read(self.c, j, span.clone(), &mut bytes)?;
                (&bytes[..], span.start)
            }
            None => {
                let data = &self.p.bands[self.c][j]
                    .as_ref()
                    .expect("a band with blocks is present")
                    .data;
                (&data[..], 0)
            }
        };
        let streams: Vec<&[u8]> = (0..local.len())
            .map(|i| {
                mine.get(i)
                    .map(|r| &data[r.start - base..r.end - base])
                    .unwrap_or(&[])
            })
            .collect();
        let kind = if self.p.plan.bands[j].level == 0 {
            BandKind::Coarse
        } else {
            BandKind::Detail
        };
        let parent = par.as_ref().map(|(dims, data)| Parent { data, dims });
        let h = &self.p.header;
        let cc = (
            crate::codec::plan::coding_of(h),
            crate::codec::plan::coder_of(h),
        );
        let n = ldims.iter().product::<usize>();
        let failed = |e: Error| {
            Error::format(
                format!("band {j} of channel {}: {e}", self.c),
                "a valid band",
            )
        };
        let spare = self.held.lock().ok().and_then(|mut h| h.spare[j].take());
        let values = if self.p.header.mode == Mode::Lossless {
            // `i32` unless a value is past it (then decoded again as `i64`)
            let past = std::sync::atomic::AtomicBool::new(false);
            let put = crate::entropy::codeblocks::Put {
                wide: |o: &mut [i32], q: &[i64]| {
                    for (o, &x) in o.iter_mut().zip(q) {
                        match i32::try_from(x) {
                            Ok(v) => *o = v,
                            Err(_) => past.store(true, std::sync::atomic::Ordering::Relaxed),
                        }
                    }
                },
                narrow: |o: &mut [i32], q: &[i32]| o.copy_from_slice(q),
            };
            let q = match spare {
                Some(Values::Narrow(v)) => v,
                _ => Vec::new(),
            };
            let pt = par.as_ref().map(|(dims, data)| Parent { data, dims });
            let q = decode_grid(q, n, &local, &streams, (kind, pt), cc, &put).map_err(failed)?;
            if !past.load(std::sync::atomic::Ordering::Relaxed) {
                Values::Narrow(q)
            } else {
                let put = crate::entropy::codeblocks::Put {
                    wide: |o: &mut [i64], q: &[i64]| o.copy_from_slice(q),
                    narrow: |o: &mut [i64], q: &[i32]| {
                        for (o, &x) in o.iter_mut().zip(q) {
                            *o = x as i64;
                        }
                    },
                };
                let pt = par.as_ref().map(|(dims, data)| Parent { data, dims });
                let q = decode_grid(Vec::new(), n, &local, &streams, (kind, pt), cc, &put);
                Values::Indices(q.map_err(failed)?)
            }
        } else if self.parent[j] {
            let put = crate::entropy::codeblocks::Put {
                wide: |o: &mut [i64], q: &[i64]| o.copy_from_slice(q),
                narrow: |o: &mut [i64], q: &[i32]| {
                    for (o, &x) in o.iter_mut().zip(q) {
                        *o = x as i64;
                    }
                },
            };
            let q = match spare {
                Some(Values::Indices(v)) => v,
                _ => Vec::new(),
            };
            let q = decode_grid(q, n, &local, &streams, (kind, parent), cc, &put);
            Values::Indices(q.map_err(failed)?)
        } else {
            let put = crate::codec::plan::dequantizing_put(self.steps[j], self.deltas[j]);
            let x = match spare {
                Some(Values::Samples(v)) => v,
                _ => Vec::new(),
            };
            let x = decode_grid(x, n, &local, &streams, (kind, parent), cc, &put);
            Values::Samples(x.map_err(failed)?)
        };
        drop(streams);
        if self.p.blocks_in.is_some() {
            if let Ok(mut h) = self.held.lock() {
                h.bytes = bytes;
            }
        }
        Ok(Batch {
            y0: rows.start,
            values,
        })
    }
}

/// Decode every block of the grid `local` (block `i` from `streams[i]`) of a band of
/// kind and parent `kp` into `buf` (reused), resized to the grid's `n` samples in raster
/// order, through `put`: each block is decoded on the pool on its own
/// ([`crate::entropy::codeblocks::decode_blocks_over`] over the block's box, its rows
/// the pieces of the grid's rows it covers), so that a stripe one block tall (a
/// volume's batch) decodes on every thread. A block's indices do not depend on the
/// others': the same samples on any thread count.
fn decode_grid<T, W, N>(
    mut buf: Vec<T>,
    n: usize,
    local: &Grid,
    streams: &[&[u8]],
    (kind, parent): (BandKind, Option<Parent>),
    (coding, coder): (
        crate::entropy::band::Coding,
        crate::entropy::codeblocks::Coder,
    ),
    put: &crate::entropy::codeblocks::Put<W, N>,
) -> Result<Vec<T>>
where
    T: Send + Clone + Default,
    W: Fn(&mut [T], &[i64]) + Sync,
    N: Fn(&mut [T], &[i32]) + Sync,
{
    buf.clear();
    buf.resize(n, T::default());
    let nd = local.dims.len();
    let row_len = local.dims[nd - 1].max(1);
    let wide = local.block[nd - 1];
    // each block's rows: the pieces of the grid's rows inside its box, in raster order
    let mut pieces: Vec<Vec<&mut [T]>> = (0..local.len()).map(|_| Vec::new()).collect();
    let mut idx = vec![0usize; nd - 1];
    for row in buf.chunks_mut(row_len) {
        let mut base = 0;
        for (&i, (&n, &b)) in idx.iter().zip(local.counts.iter().zip(&local.block)) {
            base = base * n + i / b;
        }
        let base = base * local.counts[nd - 1];
        for (b, piece) in row.chunks_mut(wide).enumerate() {
            pieces[base + b].push(piece);
        }
        for k in (0..nd - 1).rev() {
            idx[k] += 1;
            if idx[k] < local.dims[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    let parent = parent.as_ref().map(|p| (p.data, p.dims));
    let failed: Vec<Result<()>> = pieces
        .into_par_iter()
        .enumerate()
        .map(|(i, rows)| {
            let bounds = local.bounds(i);
            let over = crate::entropy::codeblocks::Over {
                rows: &bounds,
                parent: None,
            };
            let parent = parent.map(|(data, dims)| Parent { data, dims });
            crate::entropy::codeblocks::decode_blocks_over(
                rows,
                &over,
                local,
                &[i],
                &streams[i..=i],
                (kind, parent),
                (coding, coder),
                put,
            )
        })
        .collect();
    failed.into_iter().collect::<Result<()>>()?;
    Ok(buf)
}
