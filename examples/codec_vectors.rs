//! Regenerate formats/vectors/: small `.mra` files and a manifest with the SHA-256 of
//! each decoded output (samples as little-endian bytes, interleaved, row-major).
//! Run: `cargo run --release --example codec_vectors`
use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Raster, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};

fn raster(dims: &[usize], channels: usize, ty: SampleType, kind: DataKind) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let p = i / channels;
            let (x, y) = ((p % w) as f64, (p / w) as f64);
            let c = (i % channels) as f64;
            100.0 + 60.0 * (x * 0.4 + c).sin() * (y * 0.3).cos() + 3.0 * ((i * 7919) % 13) as f64
        })
        .collect();
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
}

/// A 16-bit gray raster whose texture doubles in scale every 6 columns (from units to
/// hundreds), so that some lossless bands take the wide magnitude classes of format 2.3.
fn raster_scales(dims: &[usize]) -> Raster {
    let n: usize = dims.iter().product::<usize>();
    let w = *dims.last().unwrap();
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let r = ((i * 7919) % 13) as f64 - 6.0;
            let scale = (1u64 << ((i % w) / 6)) as f64;
            30000.0 + r * scale + ((i * 104729) % 7) as f64 * scale * 0.5
        })
        .collect();
    Raster::new(
        dims.to_vec(),
        1,
        Samples::from_f64(&v, SampleType::U16),
        DataKind::Image,
    )
    .unwrap()
}

/// A raster over most of the 16-bit range with sharp steps, so that lossless details
/// reach thousands and bands take the wide magnitude classes of format 2.3.
fn raster_wide(dims: &[usize], channels: usize, kind: DataKind) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let w = *dims.last().unwrap();
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let p = i / channels;
            let (x, y) = ((p % w) as f64, (p / w) as f64);
            let step = if (p % w) % 5 < 2 { 20000.0 } else { 0.0 };
            30000.0
                + 9000.0 * (x * 0.9).sin() * (y * 0.7 + (i % channels) as f64).cos()
                + step
                + 300.0 * ((i * 7919) % 13) as f64
        })
        .collect();
    Raster::new(
        dims.to_vec(),
        channels,
        Samples::from_f64(&v, SampleType::U16),
        kind,
    )
    .unwrap()
}

/// A 16x12 f32 heightmap with a hole of NaN voids (a lake) and a few single ones, so
/// that the file is 2.4: its `HEAD` flag says the `mETA` lists the voids.
fn raster_voids() -> Raster {
    let mut r = raster(&[12, 16], 1, SampleType::F32, DataKind::Heightmap);
    let mut v = r.samples.to_f64();
    for (i, x) in v.iter_mut().enumerate() {
        let (y, c) = (i / 16, i % 16);
        if (3..7).contains(&y) && (4..9).contains(&c) || i % 37 == 5 {
            *x = f64::NAN;
        }
    }
    r.samples = Samples::from_f64(&v, SampleType::F32);
    r
}

/// name, description, raster, scheme, boundary, rate, level decoded, tile extents
type Case = (
    &'static str,
    &'static str,
    Raster,
    Scheme,
    Boundary,
    Rate,
    usize,
    Vec<usize>,
);

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("formats/vectors");
    std::fs::create_dir_all(&dir).unwrap();
    let cases: Vec<(&str, &str, Raster, Scheme, Boundary, Rate, usize)> = vec![
        (
            "gray8_lossless",
            "13x9 gray u8, lossless",
            raster(&[9, 13], 1, SampleType::U8, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "rgb8_haar_q40",
            "17x11 RGB u8, haar symmetric, quality 40",
            raster(&[11, 17], 3, SampleType::U8, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
        ),
        (
            "rgb8_haar_q40_level1",
            "the previous file decoded with --level 1",
            raster(&[11, 17], 3, SampleType::U8, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            1,
        ),
        (
            "vol_i16_maxerr",
            "8x6x5 volume i16, chaikin, --max-error 2",
            raster(&[5, 6, 8], 1, SampleType::I16, DataKind::Volume),
            Scheme::Chaikin,
            Boundary::Symmetric,
            Rate::MaxError(2.0),
            0,
        ),
        (
            "height_f32_cubic",
            "12x10 heightmap f32, cubic periodic, threshold 1.5",
            raster(&[10, 12], 1, SampleType::F32, DataKind::Heightmap),
            Scheme::Cubic,
            Boundary::Periodic,
            Rate::Threshold(1.5),
            0,
        ),
        (
            "rgba16_lossless",
            "7x5 RGBA u16, lossless (YCoCg-R + alpha; format 2.0)",
            raster(&[5, 7], 4, SampleType::U16, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "lossless23_gray16",
            "48x40 gray u16, texture doubling in scale every 6 columns, lossless (format 2.3: two bands take the wide classes)",
            raster_scales(&[40, 48]),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "lossless23_gray16_level1",
            "the previous file decoded with --level 1",
            raster_scales(&[40, 48]),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            1,
        ),
        (
            "voids24_height_f32",
            "16x12 heightmap f32 with NaN voids, cdf97 symmetric, quality 50 (format 2.4: the HEAD flag of listed voids)",
            raster_voids(),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(50.0),
            0,
        ),
        // format 3.0: the bands in code-blocks (256×256, volumes 32³), two
        // blocks across the finest bands
        (
            "blocks30_rgb8_bpp1",
            "530x40 RGB u8, cdf97 symmetric, --bpp 1, format 3.0 (code-blocks)",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            0,
        ),
        (
            "blocks30_rgb8_bpp1_level1",
            "the previous file decoded with --level 1",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            1,
        ),
        (
            "blocks30_gray16_lossless",
            "520x8 gray u16, lossless, format 3.0 (code-blocks)",
            raster(&[8, 520], 1, SampleType::U16, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "blocks30_vol_u8_q40",
            "140x8x8 volume u8, cdf97 symmetric, quality 40, format 3.0 (code-blocks)",
            raster(&[8, 8, 140], 1, SampleType::U8, DataKind::Volume),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
        ),
        // format 3.1: the same code-blocks coded by block coder 1 (HT, `--effort 1`)
        (
            "blocks31_rgb8_bpp1",
            "530x40 RGB u8, cdf97 symmetric, --bpp 1, format 3.1 (HT block coder, --effort 1)",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            0,
        ),
        (
            "blocks31_rgb8_bpp1_level1",
            "the previous file decoded with --level 1",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            1,
        ),
        (
            "blocks31_gray16_lossless",
            "520x8 gray u16, lossless, format 3.1 (HT block coder, --effort 1)",
            raster(&[8, 520], 1, SampleType::U16, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "blocks31_vol_u16_q40",
            "140x8x8 volume u16, cdf97 symmetric, quality 40, format 3.1 (HT block coder, --effort 1)",
            raster(&[8, 8, 140], 1, SampleType::U16, DataKind::Volume),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
        ),
        // format 3.2: code-blocks that shrink with coarser levels (§15.3): two blocks
        // across every band of the 530-wide file, 256 wide at level 1 to 64 at level 3
        (
            "blocks32_rgb8_bpp1",
            "530x40 RGB u8, cdf97 symmetric, --bpp 1, format 3.2 (per-level code-blocks)",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            0,
        ),
        (
            "blocks32_rgb8_bpp1_level1",
            "the previous file decoded with --level 1",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            1,
        ),
        (
            "blocks32_gray16_lossless",
            "520x8 gray u16, lossless, format 3.2 (per-level code-blocks)",
            raster(&[8, 520], 1, SampleType::U16, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "blocks32_vol_u16_q40",
            "140x8x8 volume u16, cdf97 symmetric, quality 40, format 3.2 (per-level code-blocks)",
            raster(&[8, 8, 140], 1, SampleType::U16, DataKind::Volume),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
        ),
        // format 3.2: the same code-blocks coded by block coder 2 (adaptive, §15.4)
        (
            "blocks32a_rgb8_bpp1",
            "530x40 RGB u8, cdf97 symmetric, --bpp 1, format 3.2 (adaptive block coder)",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            0,
        ),
        (
            "blocks32a_rgb8_bpp1_level1",
            "the previous file decoded with --level 1",
            raster(&[40, 530], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Bpp(1.0),
            1,
        ),
        (
            "blocks32a_gray16_lossless",
            "520x8 gray u16, lossless, format 3.2 (adaptive block coder)",
            raster(&[8, 520], 1, SampleType::U16, DataKind::Image),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
        ),
        (
            "blocks32a_vol_u16_q40",
            "140x8x8 volume u16, cdf97 symmetric, quality 40, format 3.2 (adaptive block coder)",
            raster(&[8, 8, 140], 1, SampleType::U16, DataKind::Volume),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
        ),
    ];
    // format 2.1: tiles (extents slowest axis first); the lossy one is kept as a 2.1
    // encoder wrote it (today's encoder writes lossy tiles compact, 2.2)
    let tiled: Vec<Case> = vec![
        (
            "tiled_gray16_q40",
            "21x18 gray u16 in tiles of 8x8 (x, y), cdf97 symmetric, quality 40 (format 2.1)",
            raster(&[18, 21], 1, SampleType::U16, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
            vec![8, 8],
        ),
        (
            "tiled_gray16_q40_level1",
            "the previous file decoded with --level 1",
            raster(&[18, 21], 1, SampleType::U16, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            1,
            vec![8, 8],
        ),
        (
            "tiled_vol_u8_lossless",
            "9x7x6 volume u8 in tiles of 4x4x4 (x, y, z), lossless (format 2.1, tiles 2.0)",
            raster(&[6, 7, 9], 1, SampleType::U8, DataKind::Volume),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
            vec![4, 4, 4],
        ),
        // format 2.2: compact lossy tiles (TRAT, a form byte per TILE)
        (
            "tiled22_gray16_q40",
            "tiled_gray16_q40's raster and tiles in format 2.2 (compact tiles): the same samples",
            raster(&[18, 21], 1, SampleType::U16, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            0,
            vec![8, 8],
        ),
        (
            "tiled22_gray16_q40_level1",
            "the previous file decoded with --level 1",
            raster(&[18, 21], 1, SampleType::U16, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(40.0),
            1,
            vec![8, 8],
        ),
        (
            "tiled22_rgb8_q50",
            "20x13 RGB u8 in tiles of 8x8 (x, y), cdf97 symmetric, quality 50, format 2.2: four tile classes",
            raster(&[13, 20], 3, SampleType::U8, DataKind::Image),
            Scheme::Cdf97,
            Boundary::Symmetric,
            Rate::Quality(50.0),
            0,
            vec![8, 8],
        ),
        // format 2.3 tiles: a lossless tiled file (2.1) whose tiles are 2.3 files
        (
            "tiled23_vol_u16_lossless",
            "9x7x6 volume u16 over most of the range in tiles of 4x4x4 (x, y, z), lossless (format 2.1, tiles 2.3)",
            raster_wide(&[6, 7, 9], 1, DataKind::Volume),
            Scheme::Haar,
            Boundary::Symmetric,
            Rate::Lossless,
            0,
            vec![4, 4, 4],
        ),
    ];
    // files of an older format or encoder, kept as written: decoded, not encoded again
    // (the lossless ones are 2.0 files, or 2.0 tiles, from before 2.3's classes; the
    // max-error one has the base step of an earlier encoder; the 3.0 and 3.1 ones from
    // before 3.2's per-level code-blocks)
    let frozen = [
        "blocks30_rgb8_bpp1",
        "blocks30_gray16_lossless",
        "blocks30_vol_u8_q40",
        "blocks31_rgb8_bpp1",
        "blocks31_gray16_lossless",
        "blocks31_vol_u16_q40",
        // coder 2's files as its first encoder wrote them (the indices the context
        // coder's rate–distortion choice gave); today's choose by coder 2's own costs
        "blocks32a_rgb8_bpp1",
        "blocks32a_gray16_lossless",
        "blocks32a_vol_u16_q40",
        // the 3.2 volume as its first writer coded it, before volumes took 32³
        // code-blocks (the file names its own block extents: a valid 3.2 file)
        "blocks32_vol_u16_q40",
        "tiled_gray16_q40",
        "gray8_lossless",
        "rgba16_lossless",
        "tiled_vol_u8_lossless",
        "vol_i16_maxerr",
    ];
    let cases = cases
        .into_iter()
        .map(|(a, b, r, s, bd, rate, l)| {
            let t = r.dims.clone();
            (a, b, r, s, bd, rate, l, t)
        })
        .chain(tiled);
    let mut manifest = Vec::new();
    for (name, what, r, scheme, boundary, rate, level, tile) in cases {
        let file = format!("{}.mra", name.trim_end_matches("_level1"));
        let bytes = if frozen.contains(&name.trim_end_matches("_level1")) {
            std::fs::read(dir.join(&file)).unwrap()
        } else {
            // 3.1 and 3.2: written directly, in code-blocks: the 3.1 ones by the HT coder
            // (effort 1), the blocks32a ones by coder 2 (the lowest effort that names it)
            let adaptive = name.starts_with("blocks32a_");
            let ht = name.starts_with("blocks31_");
            let direct = ht || name.starts_with("blocks32");
            let effort = if adaptive {
                let mut efforts = mra::codec::EFFORTS;
                efforts
                    .find(|&e| {
                        mra::codec::Ladder::of(e).coder == mra::entropy::codeblocks::Coder::Adaptive
                    })
                    .expect("an effort of coder 2")
            } else if ht {
                1
            } else {
                // the context coder's files (coder 0), whatever the default effort
                7
            };
            let bytes = codec::encode_tiled(
                &r,
                &EncodeOptions {
                    scheme,
                    boundary,
                    levels: 3,
                    rate,
                    // the 2.x vectors stay 2.x; the 3.0 ones are cut from them
                    format: if direct {
                        codec::Format::Blocks
                    } else {
                        codec::Format::Bands
                    },
                    effort,
                },
                &tile,
            )
            .unwrap();
            let bytes = if name.starts_with("blocks30_") {
                codec::to_blocks(&bytes).unwrap()
            } else {
                bytes
            };
            std::fs::write(dir.join(&file), &bytes).unwrap();
            bytes
        };
        let d = codec::decode(
            &bytes,
            &DecodeOptions {
                level,
                allow_truncated: false,
                ..Default::default()
            },
        )
        .unwrap();
        let raw = mra::io::bytes::encode(&d.raster.samples, false);
        manifest.push(serde_json::json!({
            "name": name,
            "file": file,
            "description": what,
            "level": level,
            "dims": d.raster.dims,
            "channels": d.raster.channels,
            "sample_type": d.raster.sample_type().name(),
            "sha256": mra::format::sha256::hex(&mra::format::sha256::sha256(&raw)),
        }));
    }
    std::fs::write(
        dir.join("manifest.json"),
        serde_json::to_string_pretty(&manifest).unwrap() + "\n",
    )
    .unwrap();
    println!("wrote {} vectors to {}", manifest.len(), dir.display());
}
