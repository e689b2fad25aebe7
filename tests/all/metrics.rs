//! `mra compare` against scikit-image and OpenImageIO: the values in
//! tests/reference/compare_fixture.json were computed by
//! tests/reference/compare_reference.py on the committed pairs in tests/reference/compare/.

use std::path::{Path, PathBuf};

use mra::io;
use mra::metrics::{compare, CompareOptions, Convention};
use serde_json::Value;

fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference")
}

fn fixture() -> Value {
    let text = std::fs::read_to_string(reference_dir().join("compare_fixture.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn assert_close(what: &str, got: Option<f64>, want: &Value, tol: f64) {
    match (got, want.as_f64()) {
        (None, None) => {}
        (Some(g), Some(w)) => {
            println!("{what}: |mra − reference| = {:.3e}", (g - w).abs());
            assert!(
                (g - w).abs() <= tol,
                "{what}: mra {g}, reference {w}, difference {} > {tol}",
                (g - w).abs()
            )
        }
        (g, _) => panic!("{what}: mra {g:?}, reference {want}"),
    }
}

#[test]
fn psnr_mse_ssim_agree_with_scikit_image() {
    let f = fixture();
    let cases = f["cases"].as_array().unwrap();
    assert!(cases.len() >= 10);
    for c in cases {
        let name = c["name"].as_str().unwrap();
        let a = io::read(&reference_dir().join(c["a"].as_str().unwrap())).unwrap();
        let b = io::read(&reference_dir().join(c["b"].as_str().unwrap())).unwrap();
        let opts = CompareOptions {
            data_range: c["data_range"].as_f64(),
            convention: Convention::Skimage,
        };
        let m = compare(&a, &b, &opts).unwrap();
        let sk = &c["skimage"];
        assert_close(&format!("{name} PSNR (dB)"), m.psnr, &sk["psnr"], 1e-6);
        let mse = sk["mse"].as_f64().unwrap();
        assert!(
            (m.mse - mse).abs() <= 1e-9 * mse.max(1e-12),
            "{name} MSE: mra {}, skimage {mse}",
            m.mse
        );
        assert_close(&format!("{name} SSIM"), m.ssim, &sk["ssim"], 1e-6);
    }
}

#[test]
fn psnr_agrees_with_openimageio() {
    let f = fixture();
    let mut checked = 0;
    for c in f["cases"].as_array().unwrap() {
        let Some(o) = c.get("oiio") else { continue };
        let name = c["name"].as_str().unwrap();
        let a = io::read(&reference_dir().join(c["a"].as_str().unwrap())).unwrap();
        let b = io::read(&reference_dir().join(c["b"].as_str().unwrap())).unwrap();
        let opts = CompareOptions {
            data_range: None,
            convention: Convention::Oiio,
        };
        let m = compare(&a, &b, &opts).unwrap();
        assert_close(&format!("{name} OIIO PSNR (dB)"), m.psnr, &o["psnr"], 1e-6);
        let max_norm = m.max_abs_error / mra::metrics::oiio_scale(a.sample_type());
        assert!(
            (max_norm - o["max_error"].as_f64().unwrap()).abs() < 1e-6,
            "{name} max error"
        );
        checked += 1;
    }
    assert!(checked >= 10);
}

#[test]
fn identical_inputs_give_null_psnr_and_unit_ssim() {
    let r = mra::generate::generate(mra::generate::Kind::Noise, &[16, 16], 1, 3)
        .unwrap()
        .to_raster(io::SampleType::U8)
        .unwrap();
    for conv in [Convention::Skimage, Convention::Oiio] {
        let m = compare(
            &r,
            &r,
            &CompareOptions {
                data_range: None,
                convention: conv,
            },
        )
        .unwrap();
        assert_eq!(m.mse, 0.0);
        assert_eq!(m.psnr, None);
        assert_eq!(m.max_abs_error, 0.0);
        assert!((m.ssim.unwrap() - 1.0).abs() < 1e-12);
        let json = serde_json::to_value(&m).unwrap();
        assert!(json["psnr"].is_null());
        for key in ["mse", "max_abs_error", "ssim", "data_range"] {
            assert!(json[key].is_number(), "{key}");
        }
    }
}

#[test]
fn different_shapes_are_an_error() {
    let a = mra::generate::generate(mra::generate::Kind::Noise, &[16, 16], 1, 3)
        .unwrap()
        .to_raster(io::SampleType::U8)
        .unwrap();
    let b = mra::generate::generate(mra::generate::Kind::Noise, &[16, 17], 1, 3)
        .unwrap()
        .to_raster(io::SampleType::U8)
        .unwrap();
    let e = compare(&a, &b, &CompareOptions::default()).unwrap_err();
    assert_eq!(e.kind(), mra::ErrorKind::Parameter);
}

#[test]
fn psnr_formula_with_explicit_range() {
    // one sample off by 10 in 100: MSE = 1, PSNR = 10 log10(255²)
    let a = io::Raster::new(
        vec![10, 10],
        1,
        io::Samples::U8(vec![100; 100]),
        io::DataKind::Image,
    )
    .unwrap();
    let mut b = a.clone();
    if let io::Samples::U8(v) = &mut b.samples {
        v[0] = 110;
    }
    let m = compare(&a, &b, &CompareOptions::default()).unwrap();
    assert_eq!(m.mse, 1.0);
    assert!((m.psnr.unwrap() - 20.0 * 255f64.log10()).abs() < 1e-12);
    assert_eq!(m.max_abs_error, 10.0);
    let m = compare(
        &a,
        &b,
        &CompareOptions {
            data_range: Some(100.0),
            convention: Convention::Skimage,
        },
    )
    .unwrap();
    assert!((m.psnr.unwrap() - 40.0).abs() < 1e-12);
}
