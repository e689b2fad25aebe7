//! The one-transform file streamed (`codec::encode_streamed`, what `mra encode` writes
//! above the one-piece limit) against the whole-array encode of the same raster, on a
//! raster under the limit: `cargo run --release --example stream_vs_whole -- RAW DIMS
//! [BPP] [LEVELS]`, a raw little-endian u16 file of extents DIMS (slowest first, joined
//! by x, e.g. 4096x4096 or 256x512x512), at `--bpp BPP` (default 1). Prints each file's
//! bytes, bits per position and PSNR (peak 65535), and the difference.
use mra::codec::{self, DecodeOptions, EncodeOptions, Format, Rate};
use mra::io::slab::MemorySlabs;
use mra::io::{DataKind, Raster, Samples};

fn psnr(a: &[u16], b: &Samples) -> f64 {
    let Samples::U16(b) = b else {
        panic!("u16 samples")
    };
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum();
    let mse = se / a.len() as f64;
    10.0 * (65535f64 * 65535.0 / mse.max(1e-30)).log10()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let raw = std::fs::read(&args[1]).expect("RAW");
    let dims: Vec<usize> = args[2]
        .split('x')
        .map(|t| t.parse().expect("DIMS: extents joined by x"))
        .collect();
    let bpp: f64 = args.get(3).map_or(1.0, |s| s.parse().expect("BPP"));
    let samples: Vec<u16> = raw
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    let kind = if dims.len() >= 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    let r = Raster::new(dims.clone(), 1, Samples::U16(samples.clone()), kind).expect("raster");
    let mut o = EncodeOptions {
        rate: Rate::Bpp(bpp),
        format: Format::Blocks,
        ..EncodeOptions::default()
    };
    if let Some(l) = args.get(4) {
        o.levels = l.parse().expect("LEVELS");
    }
    let n = r.positions() as f64;
    let report = |label: &str, f: &[u8]| {
        let d = codec::decode(f, &DecodeOptions::default()).expect("decode");
        let p = psnr(&samples, &d.raster.samples);
        println!(
            "{label}: {} B, {:.4} bpp, {:.3} dB",
            f.len(),
            f.len() as f64 * 8.0 / n,
            p
        );
        (f.len() as f64 * 8.0 / n, p)
    };
    let t = std::time::Instant::now();
    let whole = codec::encode(&r, &o).expect("whole encode");
    let tw = t.elapsed().as_secs_f64();
    let (bw, pw) = report("whole   ", &whole);
    drop(whole);
    let t = std::time::Instant::now();
    let mut s = Vec::new();
    codec::encode_streamed(&mut MemorySlabs::new(&r), &o, &mut s).expect("streamed encode");
    let ts = t.elapsed().as_secs_f64();
    let (bs, ps) = report("streamed", &s);
    println!(
        "streamed − whole: {:+.3} dB, {:+.2}% bits (encode {tw:.1} s whole, {ts:.1} s streamed)",
        ps - pw,
        100.0 * (bs / bw - 1.0)
    );
}
