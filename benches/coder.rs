//! Coefficient coders on the same real bands: today's (`entropy::band`, format 2) over
//! whole bands against the same coder per code-block (`entropy::codeblocks`, format 3.0:
//! blocks of 64², 128², 256² and their volume sizes, block index counted) and, with
//! `MRA_CODER_QUADS=1`, the quad-coder prototype (`entropy::block`); the HT-style coder
//! (`entropy::block::ht`) in several kinds, its codes trained here on the bands of Kodak
//! 1–12, and with its standard codes (`-- train-ht` writes those); bits and MB/s
//! (run with `RAYON_NUM_THREADS=1` for single-thread figures).
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
use mra::entropy::block::{self, ht, Shape};
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
}

/// The bands of Kodak 1–12, on which the HT-style coder's codes are trained.
static TRAINING: OnceLock<Vec<Bands>> = OnceLock::new();
/// The HT-style coder's trained codes, per kind and `by_level`.
#[allow(clippy::type_complexity)]
static TRAINED: Mutex<Vec<((u8, bool, bool), &'static [ht::Tables])>> = Mutex::new(Vec::new());

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
            }
        }
    }
    (bytes, te, td)
}

/// Count the symbols of every context over `set` (blocks of 64×64, no parent) and
/// write them as the priors (`src/entropy/block/prior.rs`).
fn train(set: &[Bands]) {
    let mut n = block::quad::Counts::default();
    for bs in set {
        for b in &bs.bands {
            let sh = if b.dims.len() >= 3 {
                shape(16, 32, 32)
            } else {
                shape(1, 64, 64)
            };
            block::encode_counting(&b.q32, &b.dims, b.kind, None, sh, Some(&mut n));
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
         //! 64×64 without parent, scaled by [`super::rc::Cdf::from_freqs`]): the contexts\n\
         //! training saw, every `step`-th, are listed; the others start uniform ([`spread`]).\n\n\
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
        table(&n.pattern, block::quad::PCLS),
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
    let want = |k: &str| args.is_empty() || args.iter().any(|a| a == k);
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
        for coder in coders() {
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
    }
}
