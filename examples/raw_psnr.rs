//! PSNR of two raw little-endian u16 files of the same length, read in chunks (for the
//! huge rasters of `benches/huge.py`, which `mra compare` would read whole):
//! `raw_psnr A B [PEAK]` prints `psnr <dB> mse <mse> max <max |a−b|>`; the peak
//! defaults to 65535 (`mra compare`'s data range for u16).

use std::io::Read;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: raw_psnr A B [PEAK]");
        std::process::exit(2);
    }
    let peak: f64 = args
        .get(3)
        .map_or(65535.0, |p| p.parse().expect("a number"));
    let open = |p: &str| std::io::BufReader::new(std::fs::File::open(p).expect(p));
    let (mut a, mut b) = (open(&args[1]), open(&args[2]));
    let (mut ba, mut bb) = (vec![0u8; 1 << 22], vec![0u8; 1 << 22]);
    let (mut sum, mut n, mut max) = (0f64, 0u64, 0u32);
    loop {
        let k = a.read(&mut ba).expect("read A");
        if k == 0 {
            break;
        }
        b.read_exact(&mut bb[..k]).expect("B as long as A");
        let mut part = 0u64;
        for (x, y) in ba[..k].chunks_exact(2).zip(bb[..k].chunks_exact(2)) {
            let d =
                u16::from_le_bytes([x[0], x[1]]).abs_diff(u16::from_le_bytes([y[0], y[1]])) as u32;
            max = max.max(d);
            part += (d * d) as u64;
        }
        sum += part as f64;
        n += (k / 2) as u64;
    }
    let mse = sum / n.max(1) as f64;
    println!(
        "psnr {:.4} mse {mse:.4} max {max}",
        10.0 * (peak * peak / mse).log10()
    );
}
