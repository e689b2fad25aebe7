//! Coefficient coders on the same real bands: today's (`entropy::band`, format 2) over
//! whole bands against the same coder per code-block (`entropy::codeblocks`, format 3.0:
//! blocks of 64², 128², 256² and their volume sizes, block index counted) and, with
//! `MRA_CODER_QUADS=1`, the quad-coder prototype (`entropy::block`); the HT-style coder
//! (`entropy::block::ht`) in several kinds, its codes trained here on the bands of Kodak
//! 1–12, and with its standard codes (`-- train-ht` writes those); the rANS quad coder
//! (`entropy::block::rans`, static tables trained here) and ideal code lengths of its
//! symbols under other models (tables per band or block, adaptive counts, sign
//! contexts); bits and MB/s (run with `RAYON_NUM_THREADS=1` for single-thread figures).
//! `only-today`, `only-ht`, `only-rans` keep those rows.
//!
//! The bands are those `mra encode` writes: each input is encoded by the library
//! (`--bpp 1` for the photographs and the CT, `--lossless` for the 16-bit images), its
//! bands read back from the file (`coder/bands.rs`); then every coder encodes and
//! decodes every band on one thread, best total of `MRA_CODER_REPS` (default 3) runs.
//! MB/s are of raw samples (the input's bytes) per second of coding alone.
//!
//! Run: `MRA_CORPUS=/work/shared/corpus cargo bench --bench coder [-- kodak flower ct lossless16]`
#[path = "coder/bands.rs"]
mod bands;

use bands::Bands;
use mra::codec::{encode, EncodeOptions, Rate};
use mra::entropy::band::Coding;
use mra::entropy::block::{self, ht, rans, Shape};
use mra::entropy::codeblocks;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

/// A coder under test.
#[derive(Clone, Copy)]
enum Coder {
    Today,
    /// today's coder per code-block (fresh models, block-local neighbours and parent
    /// box), 2-D side and volume block (Z, Y, X)
    TodayBlocks {
        side: usize,
        vol: [usize; 3],
    },
    Block {
        plane: Shape,
        volume: Shape,
        parent: bool,
    },
    /// the HT-style coder (`entropy::block::ht`): blocks, the codes' kind, the codes
    /// trained here on Kodak 1–12 (one set, or one per level 0, 1, ≥ 2 with `by_level`)
    /// or the library's standard ones
    Ht {
        plane: Shape,
        volume: Shape,
        kind: ht::Kind,
        by_level: bool,
        standard: bool,
    },
    /// the rANS quad coder (`entropy::block::rans`), blocks 256² / 32×64×64, its tables
    /// trained here on Kodak 1–12
    Rans {
        kind: rans::Kind,
    },
    /// a block coder of format 3.1/3.2 (`codeblocks::Coder`) over the file's code-blocks
    /// (256² / 32×64×64, parent boxes, `i64` indices narrowed as a file's are)
    File(codeblocks::Coder),
}

/// The bands of Kodak 1–12, on which the HT-style coder's codes are trained.
static TRAINING: OnceLock<Vec<Bands>> = OnceLock::new();
/// The HT-style coder's trained codes, per kind and `by_level`.
#[allow(clippy::type_complexity)]
static TRAINED: Mutex<Vec<((u8, bool, bool), &'static [ht::Tables])>> = Mutex::new(Vec::new());

/// The rANS coder's trained tables, per kind.
static TRAINED_RANS: Mutex<Vec<(bool, &'static rans::Tables)>> = Mutex::new(Vec::new());

/// Blocks of 256² / 32×64×64 for a band of `dims`.
fn big_blocks(dims: &[usize]) -> Shape {
    if dims.len() >= 3 {
        shape(32, 64, 64)
    } else {
        shape(1, 256, 256)
    }
}

/// The rANS coder's tables of `kind` trained on the Kodak 1–12 bands.
fn trained_rans(kind: rans::Kind) -> &'static rans::Tables {
    let mut t = TRAINED_RANS.lock().unwrap();
    if let Some((_, v)) = t.iter().find(|(k, _)| *k == kind.parent) {
        return v;
    }
    let set = TRAINING.get().expect("training bands");
    let mut n = rans::Counts::new(kind);
    let flat = rans::Tables::from_counts(&n);
    for bs in set {
        for (i, b) in bs.bands.iter().enumerate() {
            let par = bs.parent32(i);
            block::encode_rans(
                &b.q32,
                &b.dims,
                b.kind,
                par,
                big_blocks(&b.dims),
                &flat,
                Some(&mut n),
            );
        }
    }
    let v: &'static rans::Tables = Box::leak(Box::new(rans::Tables::from_counts(&n)));
    t.push((kind.parent, v));
    v
}

/// Estimated bits of a table sent for counts `n` (used symbols only): 7 bits for the
/// number of used symbols, per used symbol the Elias-gamma code of its index gap and 5
/// bits of log-quantised frequency; 1 bit per context for "used".
fn table_bits(n: &[u32]) -> f64 {
    let mut bits = 1.0;
    if n.iter().all(|&c| c == 0) {
        return bits;
    }
    bits += 7.0;
    let mut last = 0usize;
    for (s, &c) in n.iter().enumerate() {
        if c > 0 {
            let gap = (s + 1 - last) as u32;
            bits += 2.0 * gap.ilog2() as f64 + 1.0 + 5.0;
            last = s + 1;
        }
    }
    bits
}

/// Ideal bits of symbols with counts `n` coded by their own frequencies.
fn own_bits(n: &[u32]) -> f64 {
    let tot: u32 = n.iter().sum();
    n.iter()
        .filter(|&&c| c > 0)
        .map(|&c| c as f64 * (tot as f64 / c as f64).log2())
        .sum()
}

/// Estimated sizes of other ways to code the rANS coder's symbols (`kind`, blocks
/// 256² / 32×64×64) over `set`, in bytes: the raw bits and block lengths as coded,
/// the symbols' ideal code length under each model.
fn estimates(set: &[Bands], kind: rans::Kind) -> Vec<(String, f64)> {
    let t = trained_rans(kind);
    let nq = kind.quad_codes();
    let size = |code: usize| if code < nq { rans::QSYM } else { rans::MSYM };
    let codes = nq + 26;
    let signs = codes;
    let prior: Vec<Vec<f64>> = (0..codes)
        .map(|c| (0..size(c)).map(|s| (-t.cost(c, s)).exp2()).collect())
        .collect();
    let names = [
        "static trained tables (ideal)".to_string(),
        "tables per band, measured on the band (+ est. table bits)".to_string(),
        "tables per block, measured on the block (+ est. table bits)".to_string(),
        "adaptive counts per block from uniform (KT ½)".to_string(),
        "adaptive counts per block from trained, weight 16".to_string(),
        "adaptive counts per block from trained, weight 64".to_string(),
        "adaptive counts per band from trained, weight 16".to_string(),
        "adaptive counts per block from trained, weight 64, + adaptive sign contexts (W, N)"
            .to_string(),
        "adaptive counts per block from trained, weight 32, halved above 512".to_string(),
    ];
    let mut tot = vec![0.0f64; names.len()];
    let mut other = 0.0f64;
    for bs in set {
        for (i, b) in bs.bands.iter().enumerate() {
            let par = bs.parent32(i);
            let mut n = rans::Counts::new(kind);
            n.trace = Some(Vec::new());
            let out = block::encode_rans(
                &b.q32,
                &b.dims,
                b.kind,
                par,
                big_blocks(&b.dims),
                t,
                Some(&mut n),
            );
            other += out.len() as f64 - n.rans_bytes as f64;
            let tr = n.trace.take().unwrap();
            let mut band_n = vec![vec![0u32; 81]; codes];
            let mut blk_n = vec![vec![0u32; 81]; codes];
            let fresh = |w: f64| -> Vec<Vec<f64>> {
                (0..codes)
                    .map(|c| {
                        if w == 0.0 {
                            vec![0.5; size(c)]
                        } else {
                            prior[c].iter().map(|p| p * w).collect()
                        }
                    })
                    .collect()
            };
            let weights = [0.0, 16.0, 64.0];
            let mut ad: Vec<Vec<Vec<f64>>> = weights.iter().map(|&w| fresh(w)).collect();
            let mut ad_sum: Vec<Vec<f64>> = ad
                .iter()
                .map(|a| a.iter().map(|r| r.iter().sum()).collect())
                .collect();
            let mut band_ad = fresh(16.0);
            let mut band_ad_sum: Vec<f64> = band_ad.iter().map(|r| r.iter().sum()).collect();
            let close_block = |blk_n: &mut Vec<Vec<u32>>, tot: &mut Vec<f64>| {
                tot[2] += blk_n
                    .iter()
                    .map(|r| own_bits(r) + table_bits(r))
                    .sum::<f64>();
                for r in blk_n.iter_mut() {
                    r.fill(0);
                }
            };
            let mut sign_n = [[0.5f64; 2]; 9];
            let mut half = fresh(32.0);
            let mut half_sum: Vec<f64> = half.iter().map(|r| r.iter().sum()).collect();
            let mut first = true;
            for &e in &tr {
                if e == u32::MAX {
                    if !first {
                        close_block(&mut blk_n, &mut tot);
                    }
                    first = false;
                    for (k, &w) in weights.iter().enumerate() {
                        ad[k] = fresh(w);
                        ad_sum[k] = ad[k].iter().map(|r| r.iter().sum()).collect();
                    }
                    sign_n = [[0.5f64; 2]; 9];
                    half = fresh(32.0);
                    half_sum = half.iter().map(|r| r.iter().sum()).collect();
                    continue;
                }
                let (c, sy) = ((e >> 8) as usize, (e & 0xff) as usize);
                if c >= signs {
                    // a raw sign bit: its cost under adaptive counts in its context
                    let n = &mut sign_n[c - signs];
                    tot[7] += ((n[0] + n[1]) / n[sy]).log2() - 1.0;
                    n[sy] += 1.0;
                    continue;
                }
                tot[8] += (half_sum[c] / half[c][sy]).log2();
                half[c][sy] += 1.0;
                half_sum[c] += 1.0;
                if half_sum[c] > 512.0 {
                    half[c].iter_mut().for_each(|v| *v *= 0.5);
                    half_sum[c] *= 0.5;
                }
                tot[0] += t.cost(c, sy);
                band_n[c][sy] += 1;
                blk_n[c][sy] += 1;
                for k in 0..weights.len() {
                    tot[3 + k] += (ad_sum[k][c] / ad[k][c][sy]).log2();
                    ad[k][c][sy] += 1.0;
                    ad_sum[k][c] += 1.0;
                }
                tot[6] += (band_ad_sum[c] / band_ad[c][sy]).log2();
                band_ad[c][sy] += 1.0;
                band_ad_sum[c] += 1.0;
            }
            close_block(&mut blk_n, &mut tot);
            tot[1] += band_n
                .iter()
                .map(|r| own_bits(r) + table_bits(r))
                .sum::<f64>();
        }
    }
    tot[7] += tot[5];
    names
        .into_iter()
        .zip(tot)
        .map(|(n, b)| (n, other + b / 8.0))
        .collect()
}

/// The codes of `kind` trained on the Kodak 1–12 bands, per level group.
fn trained_tables(kind: ht::Kind, by_level: bool) -> &'static [ht::Tables] {
    let key = (kind.levels, kind.parent, by_level);
    let mut t = TRAINED.lock().unwrap();
    if let Some((_, v)) = t.iter().find(|(k, _)| *k == key) {
        return v;
    }
    let set = TRAINING.get().expect("training bands");
    let groups = if by_level { 3 } else { 1 };
    let v: Vec<ht::Tables> = (0..groups)
        .map(|g| ht_counts(set, kind, |b| !by_level || b.level.min(2) == g).tables())
        .collect();
    let v: &'static [ht::Tables] = Vec::leak(v);
    t.push((key, v));
    v
}

impl Coder {
    fn name(&self) -> String {
        match self {
            Coder::Today => "today (band, format 2)".into(),
            Coder::TodayBlocks { side, vol } => format!(
                "today's coder in code-blocks {side}×{side} / {}×{}×{} (+ index)",
                vol[0], vol[1], vol[2]
            ),
            Coder::Block {
                plane,
                volume,
                parent,
            } => format!(
                "quads {}×{} / {}×{}×{}, window 2^{}, {}{}",
                plane.y,
                plane.x,
                volume.z,
                volume.y,
                volume.x,
                plane.limit,
                if plane.trained { "trained" } else { "uniform" },
                if *parent { ", parent" } else { "" }
            ),
            Coder::Ht {
                plane,
                volume,
                kind,
                by_level,
                standard,
            } => format!(
                "HT-style {}×{} / {}×{}×{}, L = {}{}, {} codes{}",
                plane.y,
                plane.x,
                volume.z,
                volume.y,
                volume.x,
                kind.levels,
                if kind.parent { ", parent" } else { "" },
                if *standard { "standard" } else { "trained" },
                if *by_level { " per level" } else { "" }
            ),
            Coder::File(c) => format!("coder {} ({}) in the file's code-blocks", c.id(), c.name()),
            Coder::Rans { kind } => format!(
                "rANS 2 lanes 256² / 32×64×64, L = 3{}, static tables trained",
                if kind.parent { ", parent" } else { "" }
            ),
        }
    }
}

fn shape(z: usize, y: usize, x: usize) -> Shape {
    Shape::new(z, y, x)
}

fn limited(s: Shape, limit: u8) -> Shape {
    Shape { limit, ..s }
}

fn trained(s: Shape) -> Shape {
    Shape { trained: true, ..s }
}

fn coders() -> Vec<Coder> {
    let b = |p: Shape, v: Shape, parent| Coder::Block {
        plane: p,
        volume: v,
        parent,
    };
    let t = |p: Shape, v: Shape, limit| {
        b(
            trained(limited(p, limit)),
            trained(limited(v, limit)),
            false,
        )
    };
    let tb = |side, vol| Coder::TodayBlocks { side, vol };
    let mut v = vec![
        Coder::Today,
        tb(64, [16, 32, 32]),
        tb(128, [32, 32, 32]),
        tb(256, [32, 64, 64]),
    ];
    let ht = |levels, parent, by_level| Coder::Ht {
        plane: shape(1, 256, 256),
        volume: shape(32, 64, 64),
        kind: ht::Kind { levels, parent },
        by_level,
        standard: false,
    };
    v.extend([
        ht(2, false, false),
        ht(3, false, false),
        ht(4, false, false),
        ht(3, true, false),
        ht(4, true, false),
        ht(3, false, true),
        ht(4, true, true),
        Coder::Ht {
            plane: shape(1, 128, 128),
            volume: shape(32, 32, 32),
            kind: ht::Kind {
                levels: 4,
                parent: true,
            },
            by_level: false,
            standard: false,
        },
        Coder::Ht {
            plane: shape(1, 256, 256),
            volume: shape(32, 64, 64),
            kind: ht::Tables::standard().kind,
            by_level: false,
            standard: true,
        },
        Coder::Rans {
            kind: rans::Kind { parent: false },
        },
        Coder::Rans {
            kind: rans::Kind { parent: true },
        },
        Coder::File(codeblocks::Coder::Ht),
        Coder::File(codeblocks::Coder::Adaptive),
    ]);
    if std::env::var_os("MRA_CODER_QUADS").is_none() {
        return v;
    }
    v.extend([
        b(
            limited(shape(1, 64, 64), 6),
            limited(shape(16, 32, 32), 6),
            false,
        ),
        t(shape(1, 64, 64), shape(16, 32, 32), 5),
        t(shape(1, 64, 64), shape(16, 32, 32), 6),
        t(shape(1, 64, 64), shape(16, 32, 32), 7),
        t(shape(1, 32, 32), shape(8, 16, 16), 6),
        t(shape(1, 128, 128), shape(32, 32, 32), 6),
        t(shape(1, 64, 64), shape(4, 64, 64), 6),
    ]);
    v
}

/// Bytes of the LEB128 form of `n`.
fn leb_len(n: usize) -> usize {
    (usize::BITS - n.max(1).leading_zeros()).div_ceil(7) as usize
}

fn corpus() -> PathBuf {
    std::env::var_os("MRA_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus"))
}

/// Encode `path` at `rate` with the library's defaults and read its bands back.
fn bands_of(path: &Path, rate: Rate) -> Bands {
    let r = mra::io::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let bytes = encode(
        &r,
        &EncodeOptions {
            rate,
            // today's coder re-codes format 2 bands to the file's bytes
            format: mra::codec::Format::Bands,
            ..Default::default()
        },
    )
    .unwrap();
    Bands::of_file(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Total bytes, encode seconds and decode seconds of `coder` over every band of `set`,
/// the decode checked against the indices.
fn run(coder: Coder, set: &[Bands]) -> (usize, f64, f64) {
    let (mut bytes, mut te, mut td) = (0, 0.0, 0.0);
    for bs in set {
        for (i, b) in bs.bands.iter().enumerate() {
            match coder {
                Coder::Today => {
                    let t = Instant::now();
                    let s = bs.encode_today(i);
                    te += t.elapsed().as_secs_f64();
                    let t = Instant::now();
                    let back = bs.decode_today(i, &s).unwrap();
                    td += t.elapsed().as_secs_f64();
                    assert_eq!(s, b.stream, "today's coder re-encodes the file's stream");
                    assert_eq!(back, b.q);
                    bytes += s.len() + leb_len(s.len());
                }
                Coder::TodayBlocks { side, vol } => {
                    let grid = codeblocks::Grid::new(
                        &b.dims,
                        &codeblocks::block_shape(b.dims.len(), side, vol),
                    );
                    let par = bs.parent(i);
                    let t = Instant::now();
                    // format 3.0 codes every block with the chosen classes (§9.1)
                    let (c, ctx) = (Coding::Chosen, codeblocks::Coder::Context);
                    let s = codeblocks::encode_blocks(&b.q, &grid, b.kind, par, c, ctx);
                    te += t.elapsed().as_secs_f64();
                    let refs: Vec<&[u8]> = s.iter().map(|v| v.as_slice()).collect();
                    let all: Vec<usize> = (0..grid.len()).collect();
                    let mut back = vec![0i64; b.q.len()];
                    let t = Instant::now();
                    codeblocks::decode_blocks(&mut back, &grid, &all, &refs, b.kind, par, c, ctx)
                        .unwrap();
                    td += t.elapsed().as_secs_f64();
                    assert_eq!(back, b.q);
                    bytes += s.iter().map(|v| v.len() + leb_len(v.len())).sum::<usize>()
                        + leb_len(s.len());
                }
                Coder::File(coder) => {
                    let grid = codeblocks::Grid::new(
                        &b.dims,
                        &codeblocks::block_shape(b.dims.len(), 256, [32, 64, 64]),
                    );
                    let par = bs.parent(i);
                    let t = Instant::now();
                    let c = Coding::Chosen;
                    let s = codeblocks::encode_blocks(&b.q, &grid, b.kind, par, c, coder);
                    te += t.elapsed().as_secs_f64();
                    let refs: Vec<&[u8]> = s.iter().map(|v| v.as_slice()).collect();
                    let all: Vec<usize> = (0..grid.len()).collect();
                    let mut back = vec![0i64; b.q.len()];
                    let t = Instant::now();
                    codeblocks::decode_blocks(&mut back, &grid, &all, &refs, b.kind, par, c, coder)
                        .unwrap();
                    td += t.elapsed().as_secs_f64();
                    assert_eq!(back, b.q);
                    bytes += s.iter().map(|v| v.len() + leb_len(v.len())).sum::<usize>()
                        + leb_len(s.len());
                }
                Coder::Block {
                    plane,
                    volume,
                    parent,
                } => {
                    let sh = if b.dims.len() >= 3 { volume } else { plane };
                    let par = if parent { bs.parent32(i) } else { None };
                    let t = Instant::now();
                    let s = block::encode(&b.q32, &b.dims, b.kind, par, sh);
                    te += t.elapsed().as_secs_f64();
                    let t = Instant::now();
                    let back = block::decode(&s, &b.dims, b.kind, par, sh).unwrap();
                    td += t.elapsed().as_secs_f64();
                    assert_eq!(back, b.q32);
                    bytes += s.len();
                }
                Coder::Ht {
                    plane,
                    volume,
                    kind,
                    by_level,
                    standard,
                } => {
                    let sh = if b.dims.len() >= 3 { volume } else { plane };
                    let t = if standard {
                        ht::Tables::standard()
                    } else {
                        let v = trained_tables(kind, by_level);
                        &v[if by_level { b.level.min(2) } else { 0 }]
                    };
                    let par = bs.parent32(i);
                    let t0 = Instant::now();
                    let s = block::encode_ht(&b.q32, &b.dims, b.kind, par, sh, t, None);
                    te += t0.elapsed().as_secs_f64();
                    let t0 = Instant::now();
                    let back = block::decode_ht(&s, &b.dims, b.kind, par, sh, t).unwrap();
                    td += t0.elapsed().as_secs_f64();
                    assert_eq!(back, b.q32);
                    bytes += s.len();
                }
                Coder::Rans { kind } => {
                    let sh = big_blocks(&b.dims);
                    let t = trained_rans(kind);
                    let par = bs.parent32(i);
                    let t0 = Instant::now();
                    let s = block::encode_rans(&b.q32, &b.dims, b.kind, par, sh, t, None);
                    te += t0.elapsed().as_secs_f64();
                    let t0 = Instant::now();
                    let back = block::decode_rans(&s, &b.dims, b.kind, par, sh, t).unwrap();
                    td += t0.elapsed().as_secs_f64();
                    assert_eq!(back, b.q32);
                    bytes += s.len();
                }
            }
        }
    }
    (bytes, te, td)
}

/// Count the symbols of every context over `set` (blocks of 256² / 32×64×64, the
/// parent as a context, as coder 2 codes a file's code-blocks) and write them as the
/// priors (`src/entropy/block/prior.rs`).
fn train(set: &[Bands]) {
    let mut n = block::quad::Counts::default();
    for bs in set {
        for (i, b) in bs.bands.iter().enumerate() {
            let sh = Shape {
                trained: false,
                ..big_blocks(&b.dims)
            };
            let par = bs.parent32(i);
            block::encode_counting(&b.q32, &b.dims, b.kind, par, sh, Some(&mut n));
        }
    }
    // the contexts training saw, every `step`-th up to the last seen; the others have no
    // counts and start uniform (`rc::spread`)
    let table = |rows: &[[u32; 16]], step: usize| -> String {
        let seen = |f: &[u32; 16]| f.iter().any(|&c| c > 0);
        let end = rows.iter().rposition(seen).map_or(0, |i| i + 1);
        assert!(
            rows.iter()
                .enumerate()
                .all(|(i, f)| (i % step == 0 && i < end) || !seen(f)),
            "a context seen off every {step}-th"
        );
        let kept: Vec<String> = rows[..end]
            .iter()
            .step_by(step)
            .map(|f| {
                let c = block::rc::Cdf::from_freqs(f).cumulative();
                let v: Vec<String> = c.iter().map(|x| x.to_string()).collect();
                format!("[{}]", v.join(", "))
            })
            .collect();
        format!("spread(&[{}], {step})", kept.join(", "))
    };
    let text = format!(
        "//! Initial CDFs of the quad coder's contexts ([`super::quad`]), and how many symbols\n\
         //! each is worth. Generated by `cargo bench --bench coder -- train` (the symbol\n\
         //! frequencies of every context over the bands of Kodak 1–12 at `--bpp 1`, blocks of\n\
         //! 256² / 32×64×64 with the parent, scaled by [`super::rc::Cdf::from_freqs`]): the\n\
         //! contexts training saw are listed; the others start uniform ([`spread`]). Coder 2's\n\
         //! initial tables (formats/MRA.md §15.4).\n\n\
         use super::rc::spread;\n\n\
         /// The symbols a prior counts as seen (the adaptation starts at the rate they give).\n\
         pub const WEIGHT: u8 = 14;\n\n\
         /// Pattern contexts.\n\
         #[rustfmt::skip]\n\
         pub const PATTERN: [[u16; 16]; {}] = {};\n\n\
         /// Magnitude contexts.\n\
         #[rustfmt::skip]\n\
         pub const MAGNITUDE: [[u16; 16]; {}] = {};\n",
        n.pattern.len(),
        table(&n.pattern, 1),
        n.magnitude.len(),
        table(&n.magnitude, 1)
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/entropy/block/prior.rs");
    std::fs::write(&path, text).unwrap();
    println!("wrote {}", path.display());
}

/// Count the HT-style coder's symbols of codes `kind` over the bands of `set` that
/// `take` keeps (blocks of 256² / 32×64×64).
fn ht_counts(set: &[Bands], kind: ht::Kind, take: impl Fn(&bands::Band) -> bool) -> ht::Counts {
    let mut n = ht::Counts::new(kind);
    let flat = n.tables();
    for bs in set {
        for (i, b) in bs.bands.iter().enumerate().filter(|(_, b)| take(b)) {
            let sh = if b.dims.len() >= 3 {
                shape(32, 64, 64)
            } else {
                shape(1, 256, 256)
            };
            let par = bs.parent32(i);
            block::encode_ht(&b.q32, &b.dims, b.kind, par, sh, &flat, Some(&mut n));
        }
    }
    n
}

/// Write the joint codes trained on `set` as the standard ones
/// (`src/entropy/block/ht_table.rs`).
fn train_ht(set: &[Bands], kind: ht::Kind) {
    let (q, m) = ht_counts(set, kind, |_| true).lengths();
    let rows = |t: &[Vec<u8>]| -> String {
        let r: Vec<String> = t
            .iter()
            .map(|l| {
                let v: Vec<String> = l.iter().map(|x| x.to_string()).collect();
                format!("[{}]", v.join(", "))
            })
            .collect();
        format!("[\n    {},\n]", r.join(",\n    "))
    };
    let text = format!(
        "//! Code lengths of the HT-style coder's default codes ([`super::ht::Tables::standard`]).\n\
         //! Generated by `cargo bench --bench coder -- train-ht`: the Huffman code lengths\n\
         //! ([`super::vlc::lengths`]) of the symbol counts of every code over the bands of\n\
         //! Kodak 1–12 at `--bpp 1`, blocks of 256×256.\n\n\
         /// The codes' kind ([`super::ht::Kind`]): levels per quad position.\n\
         pub const LEVELS: u8 = {};\n\
         /// The codes' kind: whether the parent is a context.\n\
         pub const PARENT: bool = {};\n\n\
         /// Quad code lengths per context, then the run context.\n\
         #[rustfmt::skip]\n\
         pub const QUAD: [[u8; {}]; {}] = {};\n\n\
         /// Magnitude code lengths per class.\n\
         #[rustfmt::skip]\n\
         pub const MAGNITUDE: [[u8; 16]; {}] = {};\n",
        kind.levels,
        kind.parent,
        kind.symbols(),
        q.len(),
        rows(&q),
        m.len(),
        rows(&m)
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/entropy/block/ht_table.rs");
    std::fs::write(&path, text).unwrap();
    println!("wrote {}", path.display());
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let want = |k: &str| args.iter().all(|a| a.starts_with("only-")) || args.iter().any(|a| a == k);
    let only: Vec<&str> = args
        .iter()
        .filter_map(|a| a.strip_prefix("only-"))
        .collect();
    let reps: usize = std::env::var("MRA_CODER_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let root = corpus();
    if !root.is_dir() {
        eprintln!("skipped: no corpus at {} (set MRA_CORPUS)", root.display());
        return;
    }
    let kodak = |ks: std::ops::RangeInclusive<usize>| -> Vec<Bands> {
        ks.map(|k| root.join(format!("images/kodak/kodim{k:02}.png")))
            .filter(|p| p.is_file())
            .map(|p| bands_of(&p, Rate::Bpp(1.0)))
            .collect()
    };
    if args.iter().any(|a| a == "train") {
        train(&kodak(1..=12));
        return;
    }
    let training = TRAINING.get_or_init(|| kodak(1..=12));
    if args.iter().any(|a| a == "train-ht") {
        let env = |k: &str, d: u8| {
            std::env::var(k)
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(d)
        };
        let kind = ht::Kind {
            levels: env("MRA_HT_LEVELS", 3),
            parent: env("MRA_HT_PARENT", 0) == 1,
        };
        train_ht(training, kind);
        return;
    }
    let mut sets: Vec<(&str, Vec<Bands>)> = Vec::new();
    if want("kodak") {
        sets.push(("Kodak 13–24, --bpp 1", kodak(13..=24)));
    }
    if want("flower") {
        let p = root.join("images/large/flower_foveon_rgb8.png");
        sets.push((
            "flower 2268×1512 RGB, --bpp 1",
            vec![bands_of(&p, Rate::Bpp(1.0))],
        ));
    }
    if want("ct") {
        let p = root.join("volumes/ct_pancreas_256.nrrd");
        sets.push((
            "CT 256×256×134 i16, --bpp 1",
            vec![bands_of(&p, Rate::Bpp(1.0))],
        ));
    }
    if want("lossless16") {
        let set = ["artificial_gray16.png", "flower_foveon_gray16_linear.png"]
            .iter()
            .map(|f| bands_of(&root.join("images/highbit").join(f), Rate::Lossless))
            .collect();
        sets.push(("16-bit gray pair, --lossless", set));
    }
    println!("| input | coder | bytes | bits vs today | encode MB/s | decode MB/s |");
    println!("|---|---|---|---|---|---|");
    for (name, set) in &sets {
        let raw: usize = set.iter().map(|b| b.raw_bytes).sum();
        let mb = raw as f64 / 1e6;
        let mut today = 0;
        for coder in coders().into_iter().filter(|c| {
            only.is_empty()
                || only.iter().any(|o| match (*o, c) {
                    ("today", Coder::Today) => true,
                    ("ht", Coder::Ht { standard, .. }) => *standard,
                    ("rans", Coder::Rans { .. }) => true,
                    ("blocks", Coder::TodayBlocks { side: 256, .. }) => true,
                    ("file", Coder::File(_)) => true,
                    _ => false,
                })
        }) {
            let (mut best_e, mut best_d, mut bytes) = (f64::INFINITY, f64::INFINITY, 0);
            for _ in 0..reps {
                let (b, te, td) = run(coder, set);
                bytes = b;
                best_e = best_e.min(te);
                best_d = best_d.min(td);
            }
            if let Coder::Today = coder {
                today = bytes;
            }
            println!(
                "| {name} | {} | {bytes} | {:+.2}% | {:.0} | {:.0} |",
                coder.name(),
                (bytes as f64 / today as f64 - 1.0) * 100.0,
                mb / best_e,
                mb / best_d
            );
        }
        for parent in [false, true] {
            for (what, b) in estimates(set, rans::Kind { parent }) {
                println!(
                    "| {name} | est. rANS symbols{}: {what} | {b:.0} | {:+.2}% | | |",
                    if parent { ", parent" } else { "" },
                    (b / today as f64 - 1.0) * 100.0
                );
            }
        }
    }
}
