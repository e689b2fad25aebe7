//! Print the synthesis gain of every band of a 512×512 pyramid for each scheme.
use mra::scheme::{Boundary, Scheme};
use mra::tensor::{Order, Pyramid, PyramidSpec};

fn main() {
    for scheme in Scheme::ALL {
        let spec = PyramidSpec {
            scheme,
            boundary: Boundary::Symmetric,
            levels: 5,
            order: Order::NonStandard,
            axes: vec![0, 1],
        };
        let pyr = Pyramid::plan(&[512, 512], &spec).unwrap();
        let bands = pyr.subbands();
        let g = mra::quantize::band_gains(&pyr, &bands);
        let s: Vec<String> = bands
            .iter()
            .zip(&g)
            .map(|(b, g)| {
                format!(
                    "L{}{:?}:{:.3}",
                    b.level,
                    b.high.iter().map(|&h| h as u8).collect::<Vec<_>>(),
                    g
                )
            })
            .collect();
        println!("{scheme}: {}", s.join(" "));
    }
}
