//! The notes' Figure 9.19 protocol for mra's schemes: PSNR after keeping the largest P%
//! of details (no quantization), 5 levels, symmetric boundary, as Markdown table rows.
//! Run: `cargo run --release --example keep_psnr -- IMAGE.png 1 2 5 10 20`
use mra::scheme::{Boundary, Scheme};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let r = mra::io::read(std::path::Path::new(&args[1])).expect("readable image");
    let ps: Vec<f64> = args[2..]
        .iter()
        .map(|p| p.parse().expect("a percentage"))
        .collect();
    for scheme in Scheme::ALL {
        for weighted in [false, true] {
            let row: Vec<String> = ps
                .iter()
                .map(|&p| {
                    let v = mra::codec::keep_psnr(&r, scheme, Boundary::Symmetric, 5, p, weighted)
                        .unwrap();
                    format!("{v:.2}")
                })
                .collect();
            let w = if weighted {
                "gain-weighted"
            } else {
                "raw magnitudes"
            };
            println!("| mra {scheme} ({w}) | {} |", row.join(" | "));
        }
    }
}
