//! `mra encode`, `mra decode`, `mra info`: the `.mra` codec on the command line.

use std::io::Write;
use std::path::PathBuf;

use clap::Args;

use super::io_cmds::{read_input, write_output_as, RawArgs};
use super::{CliResult, Failure};
use crate::codec::{self, DecodeOptions, EncodeOptions, Format, Rate};
use crate::scheme::{Boundary, Scheme};

/// Compress an image, volume or heightmap into an `.mra` file.
#[derive(Args, Debug)]
#[command(
    after_help = "Rate: pick one of --keep, --threshold, --quality, --psnr, --bpp, --max-error and --lossless (default --quality 50).\n\nExample:\n  mra generate zone-plate -o z.png --size 256\n  mra encode z.png -o z.mra --psnr 40 && mra decode z.mra -o z2.png && mra compare z.png z2.png\n  mra encode ct.nrrd -o ct.mra --psnr 45 --data-range 2510   # CT: PSNR over the data's own range\n  mra encode photo.ppm -o fast.mra --bpp 1 --effort 1   # fastest encode and decode, HT coder\n  mra encode photo.ppm -o small.mra --bpp 1 --effort 9  # smallest file, context coder"
)]
pub struct EncodeArgs {
    /// Input file or folder (any format `mra info-file` reads).
    pub input: PathBuf,
    /// Output `.mra` file (`-`: standard output; the summary then goes to standard error).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Scheme: cdf97, linear-wide, linear, chaikin-wide, cubic-wide, haar, chaikin,
    /// cubic. cdf97 (the default) wins on photographs, CT and terrain: a near-orthogonal
    /// basis with 4 zeros at π keeps the energy in few coefficients and does not amplify
    /// quantization noise; linear-wide is the best B-spline synthesis, 0.2–0.3 dB behind.
    #[arg(long, default_value = "cdf97")]
    pub scheme: Scheme,
    /// Boundary: interpolating, periodic, symmetric.
    #[arg(long, default_value = "symmetric")]
    pub boundary: Boundary,
    /// Levels (each axis does what its length allows).
    #[arg(long, default_value_t = 6)]
    pub levels: usize,
    /// Keep the largest P% of details (gain-weighted).
    #[arg(long, group = "rate", value_name = "P")]
    pub keep: Option<f64>,
    /// Zero details whose gain-weighted magnitude is below T.
    #[arg(long, group = "rate", value_name = "T")]
    pub threshold: Option<f64>,
    /// Quality 1..100: quantizer step (max − min)·2^(−Q/10) (the default, 50).
    #[arg(long, group = "rate", value_name = "Q")]
    pub quality: Option<f64>,
    /// Smallest file reaching this PSNR in dB (as `mra compare` measures it).
    #[arg(long, group = "rate", value_name = "DB")]
    pub psnr: Option<f64>,
    /// Peak-to-peak data range R of the --psnr target (as `mra compare --data-range`;
    /// default scikit-image's by sample type, e.g. 65535 for int16).
    #[arg(long, requires = "psnr", value_name = "R")]
    pub data_range: Option<f64>,
    /// Largest file within B bits per pixel / voxel.
    #[arg(long, group = "rate", value_name = "B")]
    pub bpp: Option<f64>,
    /// Every decoded sample within E of the source.
    #[arg(long, group = "rate", value_name = "E")]
    pub max_error: Option<f64>,
    /// Bit-exact (integer 5/3 lifting, YCoCg-R colour).
    #[arg(long, group = "rate")]
    pub lossless: bool,
    /// Tile extents, fastest axis first: `N` (every axis), `X,Y[,Z]`, or `whole` (one
    /// tile). Default: one tile up to 2^24 positions or 2^26 samples (positions ×
    /// channels); above that limit images and volumes of integer or float samples,
    /// voids or not, at every rate mode (8- and 16-bit only at --lossless) are one
    /// transform streamed a slab at a time (format 3, bounded memory; `codec::default_layout`),
    /// the others (4 axes, 32-bit lossless) tiles of 1024 per axis in 2-D and 128 in 3-D
    /// and 4-D. Each tile is coded on its own at the step of the whole raster.
    #[arg(long, value_name = "T")]
    pub tile: Option<String>,
    /// Format of a one-piece file: 3 (the default: every band cut into independent
    /// code-blocks, 256×256, volumes 32×32×32, decoded in parallel and only those a
    /// `--region` needs; formats/MRA.md §15) or 2 (one stream per band, for readers
    /// older than format 3). Tiled files are format 2 either way.
    #[arg(long, value_name = "V", default_value_t = 3,
          value_parser = clap::value_parser!(u8).range(2..=3))]
    pub format: u8,
    /// Format 3.0 in one piece whatever the size (without it, rasters over the
    /// one-piece limit of `--tile` that are not streamed as one transform are cut into
    /// format 2 tiles). Format 3.0 itself is the default.
    #[arg(long, conflicts_with = "format")]
    pub blocks: bool,
    /// Effort 1..9, speed against size (as `cjxl -e`): 1–3 the HT-style block coder
    /// (format 3.1, about 4× faster decode for 7–10% more bits) without rate–distortion
    /// optimisation, `--bpp` within 3% under the budget; 4–6 the adaptive quad coder
    /// (format 3.2, about 3% more bits, 1.4–2.4× faster decode) on optimised indices;
    /// 7–9 the adaptive context coder. `--lossless` keeps the context coder at 4–6.
    /// The default is the library's (`codec::DEFAULT_EFFORT`).
    #[arg(long, value_name = "N", default_value_t = codec::DEFAULT_EFFORT,
          value_parser = clap::value_parser!(u8).range(1..=9))]
    pub effort: u8,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Print one JSON object (output, bytes, bits per position, shape, seconds); on
    /// standard error when `-o -` sends the file to standard output.
    #[arg(long)]
    pub json: bool,
    /// No spinner or progress bar (they are drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
}

/// Decompress an `.mra` file.
#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  mra generate zone-plate -o z.png --size 256 && mra encode z.png -o z.mra --quality 60\n  mra decode z.mra -o z.png --level 2   # 64x64 preview from the coarse chunks only\n  cat z.mra | mra decode - -o - --format png --json > z.png 2> report.json\n\nWith -o - the image alone goes to standard output; --json then prints on standard error."
)]
pub struct DecodeArgs {
    /// Input `.mra` file (`-`: standard input).
    pub input: PathBuf,
    /// Output file; the extension picks the format (.png .tif .exr .nrrd .hgt …).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Reconstruct at 1/2^k resolution from the coarse chunks only.
    #[arg(long, default_value_t = 0)]
    pub level: usize,
    /// Decode what a truncated file holds instead of failing.
    #[arg(long)]
    pub allow_truncated: bool,
    /// Keep frames a..b (end excluded) of a sequence (or slices of a volume).
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// Decode only the box x0:x1,y0:y1[,z0:z1] (ends excluded, full-resolution samples):
    /// x first, the fastest axis, as every vector mra prints (the library takes the
    /// ranges slowest first); a tiled file is read only where its tiles meet the box.
    #[arg(long, value_name = "X0:X1,Y0:Y1")]
    pub region: Option<String>,
    /// Print one JSON object (output, shape, complete, seconds); on standard error when
    /// `-o -` sends the image to standard output.
    #[arg(long)]
    pub json: bool,
    /// No spinner or progress bar (they are drawn only on a terminal anyway).
    #[arg(long)]
    pub quiet: bool,
    /// Format of `-o -` (standard output), as an extension: png, jpg, tif, nrrd, …
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
}

/// Show an `.mra` file's header and its bytes per level and per chunk.
#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  mra generate zone-plate -o z.png --size 256 && mra encode z.png -o z.mra && mra info z.mra --json"
)]
pub struct InfoArgs {
    /// An `.mra` file.
    pub input: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

pub fn encode(a: EncodeArgs) -> CliResult {
    if let Some(t) = a
        .tile
        .as_deref()
        .filter(|t| a.blocks && t.trim() != "whole")
    {
        return Err(Failure(format!(
            "--blocks --tile {t}: code-blocks (format 3.0) are written in one-piece files only: \
             leave out --tile or give --tile whole"
        )));
    }
    let rate = a.rate();
    let opts = EncodeOptions {
        scheme: a.scheme,
        boundary: a.boundary,
        levels: a.levels,
        rate,
        format: Format::of_major(a.format as usize).map_err(|e| Failure(e.to_string()))?,
        effort: a.effort,
    };
    let read_opts = a.raw.options()?;
    // a raw volume or raw NRRD cut into tiles is read a slab of tiles at a time
    let slabs = if super::io_cmds::is_std(&a.input) {
        None
    } else {
        crate::io::stream::open(&a.input, &read_opts)
            .map_err(|e| Failure::context(a.input.display(), e))?
    };
    let (shape, tile, bytes, seconds) = match slabs {
        Some(mut src) => encode_slabs(&a, &mut src, &opts)?,
        None => encode_whole(&a, &read_opts, &opts)?,
    };
    let positions = shape.positions();
    let bpp = bytes as f64 * 8.0 / positions as f64;
    if a.json {
        let raw = positions * shape.channels * shape.sample_type.size();
        let v = serde_json::json!({
            "input": a.input.display().to_string(),
            "output": a.output.display().to_string(),
            "bytes": bytes,
            "bits_per_position": bpp,
            "ratio": raw as f64 / bytes as f64,
            "axis_order": super::io_cmds::AXIS_ORDER,
            "dims": super::io_cmds::xyz(&shape.dims),
            "channels": shape.channels,
            "dtype": shape.sample_type.name(),
            "scheme": a.scheme.name(),
            "boundary": a.boundary.name(),
            "tile": super::io_cmds::xyz(&tile),
            "seconds": seconds,
        });
        return super::io_cmds::report(&a.output, &v.to_string());
    }
    let line = format!(
        "{}: {} bytes, {:.4} bits per position ({})",
        if super::io_cmds::is_std(&a.output) {
            "standard output".to_string()
        } else {
            a.output.display().to_string()
        },
        bytes,
        bpp,
        crate::io::summary(&shape.dims, shape.channels, shape.sample_type, shape.kind)
    );
    super::io_cmds::report(&a.output, &line)
}

/// What an encode produced: the shape coded, the tile extents, the file's bytes and the
/// seconds spent coding.
type Encoded = (crate::io::slab::Shape, Vec<usize>, usize, f64);

/// Encode a source read a slab of tiles at a time.
fn encode_slabs(
    a: &EncodeArgs,
    src: &mut crate::io::stream::Slabs,
    opts: &EncodeOptions,
) -> Result<Encoded, Failure> {
    let shape = crate::io::slab::SlabSource::shape(src).clone();
    let tile = match a.tile.as_deref() {
        None if a.blocks => shape.dims.clone(),
        None => codec::default_layout(&shape, opts),
        Some(s) => tile_extents(s, &shape.dims)?,
    };
    let t = std::time::Instant::now();
    let mut n = 0;
    if super::io_cmds::is_std(&a.output) {
        // the container seeks back to its index: made in memory, then written
        let mut w = std::io::Cursor::new(Vec::new());
        n = codec::encode_stream(src, opts, &tile, &mut w)
            .map_err(|e| Failure::context(a.input.display(), e))?;
        super::io_cmds::write_stdout(w.get_ref())?;
    } else {
        let input = a.input.display().to_string();
        super::io_cmds::write_streamed(&a.output, &input, |w| {
            n = codec::encode_stream(src, opts, &tile, w)?;
            Ok(())
        })?;
    }
    Ok((shape, tile, n as usize, t.elapsed().as_secs_f64()))
}

/// Encode a raster read whole.
fn encode_whole(
    a: &EncodeArgs,
    read_opts: &crate::io::ReadOptions,
    opts: &EncodeOptions,
) -> Result<Encoded, Failure> {
    let r = read_input(&a.input, read_opts)?;
    let tile = match a.tile.as_deref() {
        None if a.blocks => r.dims.clone(),
        None => codec::default_layout(&crate::io::slab::Shape::of(&r), opts),
        Some(s) => tile_extents(s, &r.dims)?,
    };
    let t = std::time::Instant::now();
    let bytes =
        codec::encode_tiled(&r, opts, &tile).map_err(|e| Failure::context(a.input.display(), e))?;
    let seconds = t.elapsed().as_secs_f64();
    if super::io_cmds::is_std(&a.output) {
        super::io_cmds::write_stdout(&bytes)?;
    } else {
        crate::fsutil::write_atomic(&a.output, |w| w.write_all(&bytes))
            .map_err(|e| Failure::context(a.output.display(), e))?;
    }
    Ok((crate::io::slab::Shape::of(&r), tile, bytes.len(), seconds))
}

impl EncodeArgs {
    /// The rate control chosen (quality 50 when none is).
    fn rate(&self) -> Rate {
        if let Some(p) = self.keep {
            Rate::Keep(p)
        } else if let Some(t) = self.threshold {
            Rate::Threshold(t)
        } else if let Some(q) = self.quality {
            Rate::Quality(q)
        } else if let Some(d) = self.psnr {
            match self.data_range {
                Some(r) => Rate::PsnrRange(d, r),
                None => Rate::Psnr(d),
            }
        } else if let Some(b) = self.bpp {
            Rate::Bpp(b)
        } else if let Some(e) = self.max_error {
            Rate::MaxError(e)
        } else if self.lossless {
            Rate::Lossless
        } else {
            Rate::Quality(50.0)
        }
    }
}

/// `--tile`: `N`, `X,Y[,Z…]` (fastest axis first) or `whole`, as extents slowest axis
/// first, each capped at the axis extent.
fn tile_extents(s: &str, dims: &[usize]) -> Result<Vec<usize>, Failure> {
    let bad = || {
        Failure(format!(
            "--tile {s}: expected N, one extent per axis X,Y[,Z] (fastest first, each ≥ 1), or whole"
        ))
    };
    if s.trim() == "whole" {
        return Ok(dims.to_vec());
    }
    let v: Vec<usize> = s
        .split(',')
        .map(|t| t.trim().parse::<usize>().ok().filter(|&n| n >= 1))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    let fastest_first: Vec<usize> = match v.len() {
        1 => vec![v[0]; dims.len()],
        n if n == dims.len() => v,
        _ => return Err(bad()),
    };
    Ok(fastest_first
        .iter()
        .rev()
        .zip(dims)
        .map(|(&t, &d)| t.min(d))
        .collect())
}

/// `--region x0:x1,y0:y1[,…]` (ends excluded, x first: the fastest axis) as the
/// library's ranges, slowest axis first.
pub fn region_ranges(s: &str) -> Result<Vec<std::ops::Range<usize>>, Failure> {
    let bad = || {
        Failure(format!(
            "--region {s}: expected x0:x1,y0:y1[,z0:z1], whole numbers with x0 < x1"
        ))
    };
    s.split(',')
        .map(|p| {
            let (a, b) = p.split_once(':').ok_or_else(bad)?;
            let (a, b): (usize, usize) = (
                a.trim().parse().map_err(|_| bad())?,
                b.trim().parse().map_err(|_| bad())?,
            );
            if a >= b {
                return Err(bad());
            }
            Ok(a..b)
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|mut r| {
            r.reverse();
            r
        })
}

/// `A..B` (end excluded) as a pair.
fn frame_range(s: &str) -> Result<(usize, usize), Failure> {
    let bad = || {
        Failure(format!(
            "--frames {s}: expected A..B, two whole numbers with A < B"
        ))
    };
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (usize, usize) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= b {
        return Err(bad());
    }
    Ok((a, b))
}

pub fn decode(a: DecodeArgs) -> CliResult {
    let from_stdin = super::io_cmds::is_std(&a.input);
    let name = if from_stdin {
        "standard input".to_string()
    } else {
        a.input.display().to_string()
    };
    // standard input is read whole, within the memory budget; a file is read chunk by chunk
    let stdin = if from_stdin {
        Some(super::io_cmds::stdin_bytes()?)
    } else {
        None
    };
    // a level the file does not hold is the library's error (crate::Error::Level)
    let mut range = a.frames.as_deref().map(frame_range).transpose()?;
    let mut region = a.region.as_deref().map(region_ranges).transpose()?;
    if let (Some((f0, f1)), 0) = (range, a.level) {
        // frames at full resolution: a region along the slowest axis, so that a tiled
        // file is read only where the frames are
        let head = match &stdin {
            Some(bytes) => codec::info(bytes).map(|i| i.dims),
            None => codec::header_of_file(&a.input).map(|h| h.dims),
        }
        .map_err(|e| Failure::context(&name, e))?;
        if head.len() >= 2 && f1 <= head[0] {
            let mut reg = region
                .take()
                .unwrap_or_else(|| head.iter().map(|&d| 0..d).collect());
            if reg.len() == head.len() {
                reg[0] = f0..f1;
                region = Some(reg);
                range = None;
            } else {
                region = Some(reg);
            }
        }
    }
    let opts = DecodeOptions {
        level: a.level,
        allow_truncated: a.allow_truncated,
        region,
    };
    let t = std::time::Instant::now();
    if stdin.is_none()
        && range.is_none()
        && !super::io_cmds::is_std(&a.output)
        && crate::io::stream::streams_output(&a.output)
    {
        // raw, NRRD, TIFF and PNM outputs are written a slab of rows at a time
        let mut got = None;
        super::io_cmds::write_streamed(&a.output, &name, |w| {
            let mut d = codec::SlabDecoder::open(&a.input, &opts)?;
            let shape = d.shape().clone();
            crate::io::stream::write_slabs(&a.output, w, &shape, &mut || d.next_slab())?;
            got = Some(codec::SlabDecode {
                shape,
                complete: d.complete(),
                bytes_read: d.bytes_read(),
            });
            Ok(())
        })?;
        let d = got.expect("set by a successful decode");
        return decode_report(
            &a,
            &name,
            &d.shape,
            d.complete,
            t.elapsed().as_secs_f64(),
            Some(d.bytes_read),
        );
    }
    let d = match &stdin {
        Some(bytes) => codec::decode(bytes, &opts),
        None => codec::decode_file(&a.input, &opts),
    }
    .map_err(|e| Failure::context(&name, e))?;
    drop(stdin);
    let raster = match range {
        Some((f0, f1)) => {
            codec::frames(d.raster, f0, f1).map_err(|e| Failure::context(&name, e))?
        }
        None => d.raster,
    };
    let seconds = t.elapsed().as_secs_f64();
    write_output_as(&a.output, &raster, false, None, a.format.as_deref())?;
    let shape = crate::io::slab::Shape::of(&raster);
    decode_report(&a, &name, &shape, d.complete, seconds, None)
}

/// The end of `mra decode`: the truncation note and the `--json` report.
fn decode_report(
    a: &DecodeArgs,
    name: &str,
    shape: &crate::io::slab::Shape,
    complete: bool,
    seconds: f64,
    bytes_read: Option<u64>,
) -> CliResult {
    if !complete {
        eprintln!("mra: {name}: truncated file, decoded what it holds");
    }
    if a.json {
        let v = serde_json::json!({
            "input": a.input.display().to_string(),
            "output": a.output.display().to_string(),
            "axis_order": super::io_cmds::AXIS_ORDER,
            "dims": super::io_cmds::xyz(&shape.dims),
            "channels": shape.channels,
            "dtype": shape.sample_type.name(),
            "level": a.level,
            "complete": complete,
            "seconds": seconds,
        });
        let mut v = v;
        if let Some(b) = bytes_read {
            // written in slabs: the bytes of the .mra file read (a region reads its tiles)
            v["bytes_read"] = b.into();
        }
        super::io_cmds::report(&a.output, &v.to_string())?;
    }
    Ok(())
}

pub fn info(a: InfoArgs) -> CliResult {
    let bytes = std::fs::read(&a.input).map_err(|e| Failure::context(a.input.display(), e))?;
    info_bytes(&a.input.display().to_string(), &bytes, a.json)
}

/// `mra info` of the `.mra` bytes of `name` (a file, or standard input).
pub fn info_bytes(name: &str, bytes: &[u8], json: bool) -> CliResult {
    let a = InfoArgs {
        input: PathBuf::from(name),
        json,
    };
    let i = codec::info(bytes).map_err(|e| Failure::context(name, e))?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&i).map_err(|e| Failure(e.to_string()))?
        );
        return Ok(());
    }
    let dims: Vec<String> = i.dims.iter().rev().map(|d| d.to_string()).collect();
    println!("{} (.mra {})", a.input.display(), i.version);
    let colour = match &i.colour {
        Some(c) => format!(", colour transform {c}"),
        None => String::new(),
    };
    println!(
        "  {} {} x{} channels {}{colour}",
        i.kind,
        dims.join("x"),
        i.channels,
        i.sample_type,
    );
    let bound = match i.max_error {
        Some(e) => format!(", max error {e}"),
        None => String::new(),
    };
    println!(
        "  mode {}, {} {} {} levels, step {:.6}{bound}, range {}..{}",
        i.mode, i.scheme, i.boundary, i.levels, i.step, i.range[0], i.range[1]
    );
    if i.tiles > 1 {
        let t: Vec<String> = i.tile.iter().rev().map(|d| d.to_string()).collect();
        println!("  {} tiles of {}", i.tiles, t.join("x"));
    }
    if let Some(c) = &i.coder {
        println!("  code-blocks coded by the {c} coder");
    }
    println!(
        "  {} bytes, {:.4} bits per position{}",
        i.file_bytes,
        i.bits_per_position,
        if i.complete { "" } else { " (truncated)" }
    );
    for (l, b, bpp) in &i.levels_bytes {
        let name = if *l == 0 {
            "coarse".to_string()
        } else {
            format!("level {l}")
        };
        println!("  {name:>9}: {b:>10} bytes {bpp:>8.4} bits/position");
    }
    for c in &i.chunks {
        match (c.channel, c.band) {
            (Some(ch), Some(b)) => println!(
                "    {} @{} {} bytes: channel {ch} band {b} level {} ({} coefficients)",
                c.kind,
                c.offset,
                c.bytes,
                c.level.unwrap_or(0),
                c.coefficients.unwrap_or(0)
            ),
            _ => match c.tile {
                Some(t) => println!("    {} @{} {} bytes: tile {t}", c.kind, c.offset, c.bytes),
                None => println!("    {} @{} {} bytes", c.kind, c.offset, c.bytes),
            },
        }
    }
    Ok(())
}
