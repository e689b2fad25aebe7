//! `analyze` / `synthesize` on arrays: exact reconstruction through the pyramid file for
//! every scheme × boundary × order on generated data, pictures, and the shared corpus
//! (skipped when absent).

use std::path::{Path, PathBuf};

use mra::cli::array::{analyze_path as analyze, synthesize_path as synthesize, AnalyzeOptions};
use mra::generate::{generate, Kind};
use mra::io::{self, ReadOptions, SampleType, Samples};
use mra::scheme::{Boundary, Scheme};
use mra::tensor::{Order, PyramidSpec};

use super::common;

fn tmp(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("array_tests");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn spec(scheme: Scheme, boundary: Boundary, order: Order, levels: usize) -> PyramidSpec {
    PyramidSpec {
        scheme,
        boundary,
        levels,
        order,
        axes: vec![],
    }
}

fn opts(spec: PyramidSpec, visual: bool) -> AnalyzeOptions {
    AnalyzeOptions {
        spec,
        visual,
        slice: None,
        read: ReadOptions::default(),
        quiet: true,
    }
}

/// Analyze `input` to a pyramid file and synthesize it back to `out`; return both rasters.
fn through_files(
    input: &Path,
    s: &PyramidSpec,
    tag: &str,
    out_ext: &str,
) -> (io::Raster, io::Raster) {
    let src = io::read(input).unwrap();
    let pyr_ext = if src.dims.len() == 2 { "tif" } else { "nrrd" };
    let pyr = tmp(&format!("{tag}.pyr.{pyr_ext}"));
    analyze(input, &pyr, &opts(s.clone(), false)).unwrap_or_else(|f| panic!("{tag}: {f}"));
    let back = tmp(&format!("{tag}.back.{out_ext}"));
    synthesize(&pyr, &back, true).unwrap_or_else(|f| panic!("{tag}: {f}"));
    (src, io::read(&back).unwrap())
}

fn assert_reconstructed(src: &io::Raster, back: &io::Raster, what: &str) {
    assert_eq!(back.dims, src.dims, "{what}");
    assert_eq!(back.channels, src.channels, "{what}");
    assert_eq!(back.sample_type(), src.sample_type(), "{what}");
    if src.sample_type().is_float() {
        let (a, b) = (src.to_f64(), back.to_f64());
        let scale = a.iter().fold(0f64, |m, v| m.max(v.abs())).max(1.0);
        let err = a
            .iter()
            .zip(&b)
            .fold(0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            err <= 1e-5 * scale,
            "{what}: max error {err} (scale {scale})"
        );
    } else {
        assert!(
            back.samples == src.samples,
            "{what}: integer samples differ"
        );
    }
}

#[test]
fn every_scheme_boundary_and_order_reconstructs_generated_data() {
    let cases = [
        (
            "rgb8",
            Kind::Gradient,
            vec![37, 50],
            3,
            SampleType::U8,
            "png",
        ),
        (
            "gray16",
            Kind::Terrain,
            vec![45, 33],
            1,
            SampleType::U16,
            "png",
        ),
        (
            "float",
            Kind::Terrain,
            vec![40, 41],
            1,
            SampleType::F32,
            "tif",
        ),
        (
            "phantom",
            Kind::Phantom,
            vec![13, 18, 21],
            1,
            SampleType::U16,
            "nrrd",
        ),
    ];
    for (name, kind, dims, ch, ty, ext) in cases {
        let mut r = generate(kind, &dims, ch, 3).unwrap().to_raster(ty).unwrap();
        r.meta.spacing = Some(vec![0.5; dims.len()]);
        let input = tmp(&format!("{name}.{ext}"));
        io::write(&input, &r).unwrap();
        for scheme in Scheme::ALL {
            for boundary in Boundary::ALL {
                for order in [Order::Standard, Order::NonStandard] {
                    let s = spec(scheme, boundary, order, 3);
                    let tag = format!("{name}_{scheme}_{boundary}_{order}");
                    let (src, back) = through_files(&input, &s, &tag, ext);
                    assert_reconstructed(&src, &back, &tag);
                    assert_eq!(back.meta.spacing, src.meta.spacing, "{tag}");
                }
            }
        }
    }
}

#[test]
fn pyramid_file_records_the_spec_and_details_are_small_on_smooth_data() {
    let r = generate(Kind::Gradient, &[64, 64], 1, 1)
        .unwrap()
        .to_raster(SampleType::U16)
        .unwrap();
    let input = tmp("ramp.png");
    io::write(&input, &r).unwrap();
    let pyr = tmp("ramp.pyr.tif");
    let s = spec(Scheme::Cubic, Boundary::Symmetric, Order::NonStandard, 2);
    analyze(&input, &pyr, &opts(s, false)).unwrap();
    let (c, info) = io::pyramid_file::read(&pyr).unwrap();
    assert_eq!(
        (
            info.scheme.as_str(),
            info.boundary.as_str(),
            info.levels,
            info.order.as_str()
        ),
        ("cubic", "symmetric", 2, "non-standard")
    );
    assert_eq!(info.source_type, SampleType::U16);
    assert_eq!(c.dims, vec![64, 64]);
    // a linear ramp is reproduced by the cubic B-spline: the finest details vanish
    // away from the ends (the interior of the finest detail block along x)
    let v = c.to_f32();
    let scale = 65535.0f32;
    let mut worst = 0f32;
    for y in 8..24 {
        for x in 36..60 {
            worst = worst.max(v[y * 64 + x].abs());
        }
    }
    assert!(worst < 1e-3 * scale, "detail {worst}");
}

#[test]
fn visual_pictures_for_images_and_volume_slices() {
    let img = generate(Kind::ZonePlate, &[48, 64], 1, 1)
        .unwrap()
        .to_raster(SampleType::U8)
        .unwrap();
    let input = tmp("zp.png");
    io::write(&input, &img).unwrap();
    for order in [Order::Standard, Order::NonStandard] {
        let out = tmp(&format!("zp_{order}.png"));
        analyze(
            &input,
            &out,
            &opts(spec(Scheme::Haar, Boundary::Periodic, order, 3), true),
        )
        .unwrap();
        let pic = io::read(&out).unwrap();
        assert_eq!(
            (pic.dims.clone(), pic.sample_type()),
            (vec![48, 64], SampleType::U8)
        );
        let Samples::U8(p) = &pic.samples else {
            panic!()
        };
        assert!(
            p.contains(&0) && p.contains(&255),
            "stretched to the full range"
        );
    }
    let vol = generate(Kind::Phantom, &[16, 16, 16], 1, 1)
        .unwrap()
        .to_raster(SampleType::U16)
        .unwrap();
    let input = tmp("ph.nrrd");
    io::write(&input, &vol).unwrap();
    let out = tmp("ph_slice.png");
    let mut o = opts(
        spec(Scheme::Chaikin, Boundary::Symmetric, Order::NonStandard, 2),
        true,
    );
    o.slice = Some(3);
    analyze(&input, &out, &o).unwrap();
    assert_eq!(io::read(&out).unwrap().dims, vec![16, 16]);
    o.slice = Some(16);
    assert!(analyze(&input, &tmp("ph_bad.png"), &o).is_err());
    assert!(!tmp("ph_bad.png").exists());
}

#[test]
fn wrong_extensions_and_non_pyramids_are_errors() {
    let img = generate(Kind::Edges, &[16, 16], 1, 1)
        .unwrap()
        .to_raster(SampleType::U8)
        .unwrap();
    let input = tmp("edges.png");
    io::write(&input, &img).unwrap();
    let s = spec(Scheme::Haar, Boundary::Periodic, Order::Standard, 2);
    let e = analyze(&input, &tmp("edges.pyr.nrrd"), &opts(s, false)).unwrap_err();
    assert!(e.0.contains(".tif"), "{e}");
    assert!(!tmp("edges.pyr.nrrd").exists());
    let e = synthesize(&input, &tmp("edges.back.png"), true).unwrap_err();
    assert!(e.0.contains("edges.png"), "{e}");
}

// ---------------------------------------------------------------- shared corpus

/// Every image, volume and terrain file of the corpus (the DICOM folder as one input).
fn corpus_inputs(c: &Path) -> Vec<(PathBuf, ReadOptions)> {
    let mut out = Vec::new();
    for sub in [
        "images/kodak",
        "images/highbit",
        "images/large",
        "terrain",
        "volumes",
    ] {
        let Ok(rd) = std::fs::read_dir(c.join(sub)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        files.sort();
        for f in files {
            let name = f.file_name().unwrap().to_string_lossy().to_string();
            if name.ends_with(".txt") {
                continue;
            }
            let read = if name.ends_with(".raw") {
                ReadOptions {
                    raw: Some(io::RawSpec {
                        dims: vec![64, 256, 256],
                        sample_type: SampleType::U16,
                        big_endian: false,
                    }),
                    ..Default::default()
                }
            } else {
                ReadOptions::default()
            };
            out.push((f, read));
        }
    }
    out
}

fn corpus_roundtrip(combos: &[(Scheme, Boundary)]) {
    let Some(c) = common::corpus("") else { return };
    let inputs = corpus_inputs(&c);
    assert!(inputs.len() >= 30, "corpus files: {}", inputs.len());
    for (path, read) in &inputs {
        let src = io::read_with(path, read).unwrap();
        for &(scheme, boundary) in combos {
            let s = spec(scheme, boundary, Order::NonStandard, 4);
            let (container, _) = io::array::analyze_raster(src.clone(), &s).unwrap();
            let info = io::pyramid_file::read_info(&container).unwrap();
            let back = io::array::synthesize_raster(container, &info).unwrap();
            assert_reconstructed(&src, &back, &format!("{path:?} {scheme} {boundary}"));
        }
    }
}

fn all_combos() -> Vec<(Scheme, Boundary)> {
    Scheme::ALL
        .iter()
        .flat_map(|&s| Boundary::ALL.iter().map(move |&b| (s, b)))
        .collect()
}

/// Every image, volume and terrain file of the corpus, every scheme × boundary
/// (non-standard order, 4 levels): ~25 s of CPU in release mode.
#[test]
fn corpus_all_files_all_schemes_and_boundaries() {
    corpus_roundtrip(&all_combos());
}

// ---------------------------------------------------------------- the binary

fn mra(args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cli_analyze_synthesize_roundtrip_and_errors() {
    let dir = tmp("cli");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let img = generate(Kind::Strokes, &[40, 52], 1, 2)
        .unwrap()
        .to_raster(SampleType::U8)
        .unwrap();
    let input = dir.join("in.png");
    io::write(&input, &img).unwrap();
    let p = |n: &str| dir.join(n).display().to_string();
    let (code, err) = mra(&[
        "analyze",
        &p("in.png"),
        "-o",
        &p("pyr.tif"),
        "--scheme",
        "cubic",
        "--boundary",
        "periodic",
        "--levels",
        "2",
        "--order",
        "standard",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = mra(&["synthesize", &p("pyr.tif"), "-o", &p("back.png")]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        io::read(&dir.join("back.png")).unwrap().samples,
        img.samples
    );
    let before: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    for args in [
        vec!["analyze", "/nonexistent/in.png", "-o", "OUT.tif"],
        vec!["analyze", "IN", "-o", "OUT.nrrd"],
        vec!["analyze", "IN"],
        vec!["synthesize", "IN", "-o", "OUT.png"],
        vec!["synthesize", "/nonexistent/pyr.tif", "-o", "OUT.png"],
    ] {
        let args: Vec<String> = args
            .iter()
            .map(|a| match *a {
                "IN" => p("in.png"),
                "OUT.tif" | "OUT.nrrd" | "OUT.png" => p(a),
                other => other.to_string(),
            })
            .collect();
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = mra(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{a:?}: {err}");
        let after: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        assert_eq!(after.len(), before.len(), "{a:?} left a file behind");
    }
}
