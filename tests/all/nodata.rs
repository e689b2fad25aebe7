//! Nodata through every command that filters: an i16 tile with SRTM voids (−32768) and a
//! float DEM with NaN holes, generated here, through upscale, downscale, denoise,
//! transfer, terrain synth, compare and encode / decode. Voids never enter a filter: no
//! valid output leaves the valid input range where the command resamples, outputs whose
//! footprint is all void are void again, and the rest are not.

use std::path::{Path, PathBuf};
use std::process::Command;

use mra::io::{self, DataKind, Raster, SampleType, Samples};

use super::common;

const VOID: f64 = -32768.0;

fn tmp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("nodata_tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn mra(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "mra {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (0, String::from_utf8_lossy(&out.stdout).into_owned())
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Is `(y, x)` in the 16 × 16 hole at rows and columns 20..36, or one of the single
/// voids?
fn in_hole(y: usize, x: usize) -> bool {
    (20..36).contains(&y) && (20..36).contains(&x)
}

fn single_void(y: usize, x: usize) -> bool {
    (y * 7 + x * 13) % 97 == 5 && !in_hole(y, x)
}

/// A 64 × 64 relief between 100 and 900 with a hole and scattered voids.
fn heights(void: f64) -> Vec<f64> {
    (0..64 * 64)
        .map(|i| {
            let (y, x) = (i / 64, i % 64);
            if in_hole(y, x) || single_void(y, x) {
                void
            } else {
                500.0 + 300.0 * (x as f64 * 0.15).sin() * (y as f64 * 0.11).cos() + (x + y) as f64
            }
        })
        .collect()
}

fn i16_tile() -> Raster {
    let v = heights(VOID);
    let mut r = Raster::new(
        vec![64, 64],
        1,
        Samples::from_f64(&v, SampleType::I16),
        DataKind::Heightmap,
    )
    .unwrap();
    r.meta.nodata = Some(VOID);
    r
}

fn f32_dem() -> Raster {
    let v = heights(f64::NAN);
    Raster::new(
        vec![64, 64],
        1,
        Samples::from_f64(&v, SampleType::F32),
        DataKind::Heightmap,
    )
    .unwrap()
}

fn is_void(v: f64, nodata: Option<f64>) -> bool {
    v.is_nan() || Some(v) == nodata
}

fn valid_range(r: &Raster) -> (f64, f64) {
    let nd = r.meta.nodata;
    r.to_f64()
        .into_iter()
        .filter(|&v| !is_void(v, nd))
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)))
}

/// What a resampled output must show: every sample void or within `[lo, hi]`; the
/// hole's centre void; the valid corner valid.
fn check_resampled(what: &str, out: &Raster, range: (f64, f64), nodata: Option<f64>) {
    let (lo, hi) = range;
    let (h, w) = (out.dims[0], out.dims[1]);
    let v = out.to_f64();
    let mut voids = 0;
    for (i, &x) in v.iter().enumerate() {
        if is_void(x, nodata) {
            voids += 1;
        } else {
            assert!(
                (lo..=hi).contains(&x),
                "{what}: sample {i} = {x} outside the valid input range {lo}..{hi}"
            );
        }
    }
    // the hole spans rows / columns 20..36 of 64: its centre stays void
    let c = (28 * h / 64) * w + 28 * w / 64;
    assert!(is_void(v[c], nodata), "{what}: hole centre {}", v[c]);
    assert!(!is_void(v[0], nodata), "{what}: corner {}", v[0]);
    // about the hole's share of the grid is void, not the whole grid
    let share = voids as f64 / v.len() as f64;
    assert!((0.03..0.12).contains(&share), "{what}: void share {share}");
}

fn sweep(name: &str, input: Raster, ext: &str) {
    let d = tmp_dir(name);
    let src = d.join(format!("in.{ext}"));
    io::write(&src, &input).unwrap();
    let r = io::read(&src).unwrap();
    let nd = r.meta.nodata;
    let range = valid_range(&r);
    let in_voids: Vec<bool> = r.to_f64().iter().map(|&v| is_void(v, nd)).collect();

    // resamplings
    let up = d.join(format!("up.{ext}"));
    mra(&["upscale", s(&src), "-o", s(&up), "--factor", "2"]);
    check_resampled("upscale", &io::read(&up).unwrap(), range, nd);
    let down = d.join(format!("down.{ext}"));
    mra(&["downscale", s(&src), "-o", s(&down)]);
    check_resampled("downscale", &io::read(&down).unwrap(), range, nd);

    // encode / decode: lossy keeps the void positions, the coarse level too
    let enc = d.join("t.mra");
    mra(&["encode", s(&src), "-o", s(&enc), "--quality", "40"]);
    let dec = d.join(format!("dec.{ext}"));
    mra(&["decode", s(&enc), "-o", s(&dec)]);
    let back = io::read(&dec).unwrap();
    let bv: Vec<bool> = back.to_f64().iter().map(|&v| is_void(v, nd)).collect();
    assert_eq!(bv, in_voids, "decode: void positions");
    check_resampled("decode", &back, range, nd);
    let dec1 = d.join(format!("dec1.{ext}"));
    mra(&["decode", s(&enc), "-o", s(&dec1), "--level", "1"]);
    check_resampled("decode --level 1", &io::read(&dec1).unwrap(), range, nd);
    // and the PSNR `compare` reports for the decoded tile counts valid samples only
    let (_, json) = mra(&["compare", s(&src), s(&dec), "--json"]);
    let v: serde_json::Value = serde_json::from_str(json.trim()).unwrap();
    let psnr = v["psnr"].as_f64().unwrap();
    assert!(psnr > 30.0 && psnr < 200.0, "compare: {json}");

    // denoise: voids stay exactly where they were, the rest is not pulled off by them
    let dn = d.join(format!("dn.{ext}"));
    mra(&["denoise", s(&src), "-o", s(&dn)]);
    let o = io::read(&dn).unwrap();
    let ov = o.to_f64();
    for (i, (&x, &void)) in ov.iter().zip(&in_voids).enumerate() {
        assert_eq!(is_void(x, nd), void, "denoise: sample {i} = {x}");
        if !void {
            assert!(
                x > range.0 - 100.0 && x < range.1 + 100.0,
                "denoise: sample {i} = {x}"
            );
        }
    }

    // synthesis from the tile: voids filled, every output plausible
    for (cmd, args) in [
        (
            "transfer",
            vec![
                "transfer",
                "--from",
                s(&src),
                "--to",
                s(&src),
                "--levels",
                "1",
            ],
        ),
        (
            "terrain synth",
            vec![
                "terrain",
                "synth",
                "--base",
                s(&src),
                "--example",
                s(&src),
                "--levels",
                "1",
            ],
        ),
    ] {
        let out = d.join(format!("{}.{ext}", cmd.replace(' ', "_")));
        let mut a = args.clone();
        a.extend(["-o", s(&out)]);
        mra(&a);
        let o = io::read(&out).unwrap();
        let margin = 0.25 * (range.1 - range.0);
        for (i, x) in o.to_f64().into_iter().enumerate() {
            assert!(
                x.is_finite() && x > range.0 - margin && x < range.1 + margin,
                "{cmd}: sample {i} = {x}"
            );
        }
    }
}

#[test]
fn every_filtering_command_keeps_srtm_voids_out_of_its_filters() {
    sweep("i16", i16_tile(), "tif");
}

#[test]
fn every_filtering_command_keeps_nan_holes_out_of_its_filters() {
    sweep("f32", f32_dem(), "tif");
}

#[test]
fn compare_counts_only_samples_valid_in_both_inputs() {
    let d = tmp_dir("compare");
    let a = i16_tile();
    // b = a + 2 on valid samples, and voids at other places too
    let mut vb: Vec<f64> = a
        .to_f64()
        .iter()
        .map(|&v| if v == VOID { VOID } else { v + 2.0 })
        .collect();
    for v in vb.iter_mut().take(64 * 4) {
        *v = VOID;
    }
    let mut b = Raster::new(
        vec![64, 64],
        1,
        Samples::from_f64(&vb, SampleType::I16),
        DataKind::Heightmap,
    )
    .unwrap();
    b.meta.nodata = Some(VOID);
    let (pa, pb) = (d.join("a.tif"), d.join("b.tif"));
    io::write(&pa, &a).unwrap();
    io::write(&pb, &b).unwrap();
    let (_, json) = mra(&["compare", s(&pa), s(&pb), "--json"]);
    let v: serde_json::Value = serde_json::from_str(json.trim()).unwrap();
    assert_eq!(v["mse"].as_f64(), Some(4.0), "{json}");
    assert_eq!(v["max_abs_error"].as_f64(), Some(2.0), "{json}");
}

#[test]
fn a_lossless_file_with_voids_decodes_bit_exact() {
    let d = tmp_dir("lossless");
    let src = d.join("t.tif");
    io::write(&src, &i16_tile()).unwrap();
    let enc = d.join("t.mra");
    mra(&["encode", s(&src), "-o", s(&enc), "--lossless"]);
    let dec = d.join("back.tif");
    mra(&["decode", s(&enc), "-o", s(&dec)]);
    assert_eq!(io::read(&dec).unwrap().samples, i16_tile().samples);
}

/// The fine samples of coarse cell `j` when `n` samples become `m` over the same extent:
/// those whose centre (`i + ½`, in fine cells) lies in the coarse cell `[j·n/m, (j+1)·n/m]`;
/// the nearest one when none does.
fn cell_footprint(n: usize, m: usize, j: usize) -> std::ops::RangeInclusive<usize> {
    let s = n as f64 / m as f64;
    let (a, b) = (j as f64 * s, (j + 1) as f64 * s);
    let first = (a - 0.5 - 1e-9).ceil().max(0.0) as usize;
    let last = ((b - 0.5 + 1e-9).floor().max(0.0) as usize).min(n - 1);
    if first > last {
        let near = (((j as f64 + 0.5) * s - 0.5).round().max(0.0) as usize).min(n - 1);
        near..=near
    } else {
        first..=last
    }
}

#[test]
fn downscale_of_every_corpus_srtm_tile_keeps_valid_samples_in_range_and_marks_all_void_cells() {
    let Some(dir) = common::corpus("terrain") else {
        return;
    };
    let mut tiles: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p
                .file_name()
                .unwrap()
                .to_string_lossy()
                .to_ascii_lowercase();
            name.ends_with(".hgt") || name.starts_with("srtm")
        })
        .collect();
    tiles.sort();
    assert!(
        tiles.len() >= 2,
        "SRTM tiles in {}: {tiles:?}",
        dir.display()
    );
    let d = tmp_dir("srtm_sweep");
    let mut with_voids = 0;
    for tile in &tiles {
        let input = io::read(tile).unwrap();
        let nd = input.meta.nodata;
        let (h, w) = (input.dims[0], input.dims[1]);
        let fine = input.to_f64();
        let (lo, hi) = valid_range(&input);
        let voids = fine.iter().filter(|&&v| is_void(v, nd)).count();
        with_voids += usize::from(voids > 0);
        for levels in ["1", "2"] {
            let what = format!("{} --levels {levels}", tile.display());
            let out_path = d.join("out.tif");
            mra(&["downscale", s(tile), "-o", s(&out_path), "--levels", levels]);
            let out = io::read(&out_path).unwrap();
            assert_eq!(out.meta.nodata, nd, "{what}: nodata value");
            let (oh, ow) = (out.dims[0], out.dims[1]);
            assert!(oh < h && ow < w, "{what}: {oh}x{ow} from {h}x{w}");
            let v = out.to_f64();
            let (mut marked, mut kept) = (0usize, 0usize);
            for y in 0..oh {
                let rows = cell_footprint(h, oh, y);
                for x in 0..ow {
                    let cols = cell_footprint(w, ow, x);
                    let all_void = rows
                        .clone()
                        .all(|fy| cols.clone().all(|fx| is_void(fine[fy * w + fx], nd)));
                    let o = v[y * ow + x];
                    assert_eq!(
                        is_void(o, nd),
                        all_void,
                        "{what}: output ({x}, {y}) = {o}, footprint rows {rows:?} columns {cols:?}"
                    );
                    if all_void {
                        marked += 1;
                    } else {
                        kept += 1;
                        assert!(
                            (lo..=hi).contains(&o),
                            "{what}: output ({x}, {y}) = {o} outside the valid input range {lo}..{hi}"
                        );
                    }
                }
            }
            assert_eq!(marked + kept, oh * ow);
            if voids == 0 {
                assert_eq!(marked, 0, "{what}");
            }
        }
    }
    assert!(
        with_voids >= 1,
        "no corpus SRTM tile with voids among {tiles:?}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
