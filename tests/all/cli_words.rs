//! The `mra` binary as a new user meets it: `-` as standard input and output for the
//! codec, `--quiet` and `--json` where they were missing, and what help and messages say.

use std::path::Path;
use std::process::Output;

use super::common;

/// `mra ARGS` run in `dir` with `stdin` on its standard input.
fn mra_in(dir: &Path, args: &[&str], stdin: &[u8]) -> Output {
    common::mra_with_stdin(Some(dir), args, stdin)
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A 64² zone plate written by `mra generate` in `dir`.
fn zone_plate(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("z.png");
    ok(&mra_in(
        dir,
        &["generate", "zone-plate", "-o", "z.png", "--size", "64"],
        b"",
    ));
    p
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn encode_to_standard_output_pipes_into_decode() {
    let dir = common::scratch_dir("encode_stdout");
    let png = zone_plate(&dir);
    let enc = mra_in(&dir, &["encode", "z.png", "-o", "-", "--psnr", "40"], b"");
    ok(&enc);
    // the .mra bytes on standard output, the summary on standard error, no file `-`
    assert!(
        enc.stdout.starts_with(&mra::format::SIGNATURE),
        "stdout is not .mra"
    );
    assert!(
        err(&enc).contains("standard output:") && err(&enc).contains("bytes"),
        "{}",
        err(&enc)
    );
    assert_eq!(names(&dir), vec!["z.png".to_string()]);
    // mra encode x.png -o - | mra decode - -o - --format png
    let dec = mra_in(
        &dir,
        &["decode", "-", "-o", "-", "--format", "png"],
        &enc.stdout,
    );
    ok(&dec);
    assert!(dec.stdout.starts_with(b"\x89PNG\r\n\x1a\n"));
    let back = dir.join("back.png");
    std::fs::write(&back, &dec.stdout).unwrap();
    let a = mra::io::read(&png).unwrap();
    let b = mra::io::read(&back).unwrap();
    assert_eq!(a.dims, b.dims);
    let m = mra::metrics::compare(&a, &b, &Default::default()).unwrap();
    assert!(m.psnr.is_none_or(|p| p >= 40.0), "{:?} dB", m.psnr);
    // standard input to standard output, the --json report on standard error
    let png_bytes = std::fs::read(&png).unwrap();
    let enc2 = mra_in(
        &dir,
        &["encode", "-", "-o", "-", "--psnr", "40", "--json"],
        &png_bytes,
    );
    ok(&enc2);
    assert_eq!(
        enc2.stdout, enc.stdout,
        "the same file from a pipe as from the file"
    );
    let v: serde_json::Value = serde_json::from_str(err(&enc2).trim()).unwrap();
    assert_eq!(v["bytes"].as_u64(), Some(enc.stdout.len() as u64));
    assert_eq!(
        names(&dir),
        vec!["back.png".to_string(), "z.png".to_string()]
    );
}

#[test]
fn quiet_is_accepted_by_encode_decode_and_downscale() {
    let dir = common::scratch_dir("quiet");
    zone_plate(&dir);
    let o = mra_in(&dir, &["encode", "z.png", "-o", "z.mra", "--quiet"], b"");
    ok(&o);
    assert!(err(&o).is_empty(), "{}", err(&o));
    ok(&mra_in(
        &dir,
        &["decode", "z.mra", "-o", "d.png", "--quiet"],
        b"",
    ));
    ok(&mra_in(
        &dir,
        &["downscale", "z.png", "-o", "h.png", "--quiet"],
        b"",
    ));
    assert!(dir.join("d.png").is_file() && dir.join("h.png").is_file());
}

#[test]
fn downscale_and_convert_print_json() {
    let dir = common::scratch_dir("json");
    zone_plate(&dir);
    let out = ok(&mra_in(
        &dir,
        &[
            "downscale",
            "z.png",
            "-o",
            "h.png",
            "--levels",
            "2",
            "--json",
        ],
        b"",
    ));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["dims"], serde_json::json!([16, 16]));
    assert_eq!(v["output"], "h.png");
    assert_eq!(v["dtype"], "u8");
    assert!(v["seconds"].as_f64().is_some_and(|s| s >= 0.0));
    let out = ok(&mra_in(
        &dir,
        &["convert", "z.png", "-o", "z.tif", "--json"],
        b"",
    ));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["dims"], serde_json::json!([64, 64]));
    assert_eq!(v["output"], "z.tif");
    // with -o - the report goes to standard error, the raster alone to standard output
    let o = mra_in(
        &dir,
        &["convert", "z.png", "-o", "-", "--format", "tif", "--json"],
        b"",
    );
    ok(&o);
    assert!(o.stdout.starts_with(b"II*\0") || o.stdout.starts_with(b"MM\0*"));
    let v: serde_json::Value = serde_json::from_str(err(&o).trim()).unwrap();
    assert_eq!(v["dims"], serde_json::json!([64, 64]));
}

#[test]
fn a_png_decoded_as_mra_is_named_a_png() {
    let dir = common::scratch_dir("png_as_mra");
    zone_plate(&dir);
    let o = mra_in(&dir, &["decode", "z.png", "-o", "d.png"], b"");
    assert_eq!(o.status.code(), Some(2));
    let e = err(&o);
    assert!(
        e.contains("z.png") && e.contains("this is a PNG file"),
        "{e}"
    );
    assert!(!e.contains("[89, 50"), "{e}");
    assert!(!dir.join("d.png").exists());
}

#[test]
fn help_names_scheme_keep_and_the_lossless_transform() {
    let dir = common::scratch_dir("help");
    let top = ok(&mra_in(&dir, &["--help"], b""));
    let line = top
        .lines()
        .find(|l| l.trim_start().starts_with("scheme "))
        .expect("a scheme line");
    assert!(line.contains("keep"), "{line}");
    let enc = ok(&mra_in(&dir, &["encode", "--help"], b""));
    assert!(enc.contains("5/3") && !enc.contains("S-transform"), "{enc}");
}

#[test]
fn info_ranges_leave_nodata_out() {
    let dir = common::scratch_dir("info_nodata");
    std::fs::write(
        dir.join("g.asc"),
        "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n1 2 -9999\n4 5 6\n",
    )
    .unwrap();
    let out = ok(&mra_in(&dir, &["info", "g.asc", "--json"], b""));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["min"].as_f64(), Some(1.0), "{out}");
    assert_eq!(v["max"].as_f64(), Some(6.0), "{out}");
    assert_eq!(v["nodata_count"].as_u64(), Some(1), "{out}");
    let text = ok(&mra_in(&dir, &["info", "g.asc"], b""));
    assert!(text.contains("range 1 … 6 (nodata excluded)"), "{text}");
}

#[test]
fn denoise_of_a_clean_input_says_so() {
    let dir = common::scratch_dir("denoise_clean");
    // a flat 32² gray image: nothing to remove
    let mut pgm = b"P5\n32 32\n255\n".to_vec();
    pgm.extend(std::iter::repeat_n(100u8, 32 * 32));
    std::fs::write(dir.join("flat.pgm"), &pgm).unwrap();
    let o = mra_in(&dir, &["denoise", "flat.pgm", "-o", "d.pgm"], b"");
    ok(&o);
    assert!(err(&o).contains("no sample changed"), "{}", err(&o));
    assert_eq!(std::fs::read(dir.join("d.pgm")).unwrap(), pgm);
}

#[test]
fn terrain_preview_panels_are_labelled_and_the_demo_shows_before_after() {
    let dir = common::scratch_dir("preview_labels");
    for (name, size, seed) in [("base.png", "48x48", "3"), ("ex.png", "192x192", "9")] {
        ok(&mra_in(
            &dir,
            &[
                "generate", "terrain", "--size", size, "--seed", seed, "-o", name,
            ],
            b"",
        ));
    }
    ok(&mra_in(
        &dir,
        &[
            "terrain",
            "synth",
            "--base",
            "base.png",
            "--example",
            "ex.png",
            "-o",
            "out.tif",
            "--preview",
            "prev.png",
        ],
        b"",
    ));
    let out = mra::io::read(&dir.join("out.tif")).unwrap();
    let prev = mra::io::read(&dir.join("prev.png")).unwrap();
    let (h, w) = (prev.dims[0], prev.dims[1]);
    // a strip for the labels above panels of the result's height
    let top = h - out.dims[0];
    assert!(top >= 7, "{:?} over {:?}", prev.dims, out.dims);
    let px = |y: usize, x: usize| prev.samples.get_f64(y * w + x);
    let dark: Vec<usize> = (0..w)
        .filter(|&x| (0..top).any(|y| px(y, x) == 0.0))
        .collect();
    // three labels: dark pixels in the strip, starting near each panel's left edge
    assert!(dark.first().is_some_and(|&x| x < 8), "{dark:?}");
    assert!(dark.iter().any(|&x| x > w / 2), "{dark:?}");
    assert!((0..w).all(|x| px(0, x) == 255.0), "the first row is margin");

    let demo = dir.join("demo");
    let o = ok(&mra_in(
        &dir,
        &["demo", "--json", "--out", demo.to_str().unwrap()],
        b"",
    ));
    let rows: serde_json::Value = serde_json::from_str(&o).unwrap();
    let pic = rows
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["job"] == "before/after")
        .expect("a before/after row");
    assert_eq!(
        pic["output"],
        demo.join("zone_plate_before_after.png").to_str().unwrap()
    );
    let ba = mra::io::read(&demo.join("zone_plate_before_after.png")).unwrap();
    assert_eq!(ba.dims[0], 512);
    assert!(ba.dims[1] > 2 * 512, "{:?}", ba.dims);
}
