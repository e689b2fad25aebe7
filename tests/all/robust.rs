//! Every reader, through the `mra` binary under a memory cap, on inputs made here: cut
//! short at several points, and with headers that declare far more than the file holds.
//! Each run must exit 2 with exactly one line on stderr, and leave no output (nor any
//! temporary file) behind. Also: bounded reads (`/dev/zero` and FIFO data files, a
//! `.nii.gz` that inflates past its header), argument bounds, the one-line error
//! convention, temporary files removed on signals, and open subdivision of few points.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use super::common;

const BIN: &str = env!("CARGO_BIN_EXE_mra");

/// Address-space cap for every run (`ulimit -v`, KiB): 1 GiB, far below the 4 GB the
/// inflated headers declare.
const CAP_KIB: u64 = 1 << 20;

/// A fresh, empty folder for one test.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mra-robust-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run `mra args…` in `dir` under the memory cap (and a 60 s timeout, so a hang fails).
fn run_in(dir: &Path, args: &[&str]) -> Output {
    run_env(dir, args, &[])
}

fn run_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new("sh");
    c.arg("-c")
        .arg(format!(
            "ulimit -v {CAP_KIB} && exec timeout 60 \"$0\" \"$@\""
        ))
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null());
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

/// Run unbounded, for making inputs; must succeed.
fn make(dir: &Path, args: &[&str]) {
    let o = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "mra {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The failure convention: exit 2, one line `mra: …` on stderr naming `name`, no output
/// file and no temporary file of it.
fn assert_refused(dir: &Path, o: &Output, name: &str, out: &str, what: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{what}: exit {:?}, stderr {err:?}",
        o.status
    );
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{what}: stderr is not one line: {err:?}");
    assert!(lines[0].starts_with("mra: "), "{what}: {err:?}");
    assert!(
        lines[0].contains(name),
        "{what}: the message names the file: {err:?}"
    );
    assert!(lines[0].len() < 600, "{what}: message too long: {err:?}");
    let target = dir.join(out);
    assert!(!target.exists(), "{what}: output {out} left behind");
    let temps = mra::fsutil::leftover_temps(&target);
    assert!(temps.is_empty(), "{what}: temporary files left: {temps:?}");
}

fn write(dir: &Path, name: &str, bytes: &[u8]) {
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// Cut `good` at each fraction of its length and check that reading it through
/// `args(name)` is refused.
fn refuse_truncations(
    dir: &Path,
    good: &[u8],
    ext: &str,
    cuts: &[usize],
    args: &dyn Fn(&str) -> Vec<String>,
    out: &str,
) {
    for &cut in cuts {
        assert!(cut < good.len(), "{ext}: cut {cut} of {}", good.len());
        let name = format!("cut{cut}.{ext}");
        write(dir, &name, &good[..cut]);
        let a = args(&name);
        let a: Vec<&str> = a.iter().map(|s| s.as_str()).collect();
        let o = run_in(dir, &a);
        assert_refused(
            dir,
            &o,
            &name,
            out,
            &format!("{ext} cut at {cut} of {}", good.len()),
        );
    }
}

fn convert_to_tif(name: &str) -> Vec<String> {
    vec!["convert".into(), name.into(), "-o".into(), "out.tif".into()]
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

fn png_chunk(kind: &[u8], data: &[u8]) -> Vec<u8> {
    let mut v = (data.len() as u32).to_be_bytes().to_vec();
    v.extend_from_slice(kind);
    v.extend_from_slice(data);
    let mut k = kind.to_vec();
    k.extend_from_slice(data);
    v.extend_from_slice(&crc32(&k).to_be_bytes());
    v
}

/// A generated 64×64 zone plate in `dir`, then converted to `ext`; its bytes.
fn sample(dir: &Path, ext: &str) -> Vec<u8> {
    if !dir.join("zp.png").exists() {
        make(
            dir,
            &["generate", "zone-plate", "--size", "64", "-o", "zp.png"],
        );
    }
    let name = format!("good.{ext}");
    if ext == "exr" {
        make(
            dir,
            &["convert", "zp.png", "-o", &name, "--dtype-out", "f32"],
        );
    } else if ext != "png" {
        make(dir, &["convert", "zp.png", "-o", &name]);
    } else {
        std::fs::copy(dir.join("zp.png"), dir.join(&name)).unwrap();
    }
    std::fs::read(dir.join(name)).unwrap()
}

/// A real JPEG (RGB, 64×64) written by the `image` crate.
fn jpeg_bytes() -> Vec<u8> {
    let mut px = Vec::new();
    for y in 0..64u32 {
        for x in 0..64u32 {
            px.extend_from_slice(&[(x * 4) as u8, (y * 4) as u8, ((x * y) % 251) as u8]);
        }
    }
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 90)
        .encode(&px, 64, 64, image::ExtendedColorType::Rgb8)
        .unwrap();
    out
}

#[test]
fn png_cut_short_or_declaring_65536_squared_is_refused_in_one_line() {
    let d = folder("png");
    let good = sample(&d, "png");
    let n = good.len();
    refuse_truncations(
        &d,
        &good,
        "png",
        &[5, 30, n / 2, n - 20],
        &convert_to_tif,
        "out.tif",
    );
    // IHDR 65536×65536 gray u8 in a 4 KB file
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&65536u32.to_be_bytes());
    ihdr.extend_from_slice(&65536u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    png.extend(png_chunk(b"IHDR", &ihdr));
    png.extend(png_chunk(b"IDAT", &[0x78, 0x9c].repeat(2000)));
    png.extend(png_chunk(b"IEND", &[]));
    write(&d, "huge.png", &png);
    let o = run_in(&d, &["convert", "huge.png", "-o", "out.tif"]);
    assert_refused(&d, &o, "huge.png", "out.tif", "PNG 65536²");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("65536×65536"),
        "names the declared size: {err}"
    );
    let o = run_in(&d, &["info-file", "huge.png"]);
    assert_refused(&d, &o, "huge.png", "out.tif", "info-file PNG 65536²");
}

#[test]
fn pnm_cut_short_or_declaring_65536_by_65535_is_refused() {
    let d = folder("pnm");
    let good = sample(&d, "pgm");
    let n = good.len();
    refuse_truncations(
        &d,
        &good,
        "pgm",
        &[2, 8, n / 2, n - 1],
        &convert_to_tif,
        "out.tif",
    );
    let mut pgm = b"P5\n65536 65535\n255\n".to_vec();
    pgm.extend(vec![7u8; 1024]);
    write(&d, "huge.pgm", &pgm);
    let o = run_in(&d, &["convert", "huge.pgm", "-o", "out.tif"]);
    assert_refused(&d, &o, "huge.pgm", "out.tif", "PGM 65536×65535");
}

#[test]
fn jpeg_cut_short_or_declaring_65535_squared_is_refused_from_the_header() {
    let d = folder("jpeg");
    let good = jpeg_bytes();
    write(&d, "good.jpg", &good);
    let o = run_in(&d, &["info-file", "good.jpg"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let n = good.len();
    refuse_truncations(
        &d,
        &good,
        "jpg",
        &[4, 100, n / 3, n / 2, n - 2],
        &convert_to_tif,
        "out.tif",
    );
    // SOF0 patched to 65535×65535 in a ~2 KB file: refused at once, by the header alone
    let sof = good
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("baseline SOF0");
    let mut huge = good.clone();
    huge[sof + 5..sof + 9].copy_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF]);
    huge.truncate(2048.min(huge.len() - 2));
    huge.extend_from_slice(&[0xFF, 0xD9]);
    write(&d, "huge.jpg", &huge);
    let t = std::time::Instant::now();
    let o = run_in(&d, &["info-file", "huge.jpg"]);
    assert_refused(&d, &o, "huge.jpg", "out.tif", "JPEG 65535²");
    assert!(t.elapsed().as_secs() < 20, "the header alone decides");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("65535×65535"), "{err}");
}

#[test]
fn tiff_and_exr_cut_short_are_refused() {
    let d = folder("tiff-exr");
    for ext in ["tif", "exr"] {
        let good = sample(&d, ext);
        let n = good.len();
        let to_png = |name: &str| -> Vec<String> {
            vec!["convert".into(), name.into(), "-o".into(), "out.png".into()]
        };
        refuse_truncations(&d, &good, ext, &[6, 40, n / 2, n - 8], &to_png, "out.png");
    }
}

#[test]
fn tiff_declaring_65536_squared_in_a_small_file_is_refused() {
    let d = folder("tiff-huge");
    // little-endian TIFF, one IFD: 65536×65536 u8 gray, one strip of 1000 bytes
    let mut t = b"II*\0".to_vec();
    t.extend_from_slice(&8u32.to_le_bytes());
    let entries: [(u16, u16, u32, u32); 8] = [
        (256, 4, 1, 65536), // ImageWidth
        (257, 4, 1, 65536), // ImageLength
        (258, 3, 1, 8),     // BitsPerSample
        (259, 3, 1, 1),     // Compression none
        (262, 3, 1, 1),     // BlackIsZero
        (273, 4, 1, 200),   // StripOffsets
        (278, 4, 1, 65536), // RowsPerStrip
        (279, 4, 1, 1000),  // StripByteCounts
    ];
    t.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, ty, count, value) in entries {
        t.extend_from_slice(&tag.to_le_bytes());
        t.extend_from_slice(&ty.to_le_bytes());
        t.extend_from_slice(&count.to_le_bytes());
        if ty == 3 {
            t.extend_from_slice(&(value as u16).to_le_bytes());
            t.extend_from_slice(&[0, 0]);
        } else {
            t.extend_from_slice(&value.to_le_bytes());
        }
    }
    t.extend_from_slice(&0u32.to_le_bytes());
    t.resize(1200, 9);
    write(&d, "huge.tif", &t);
    let o = run_in(&d, &["convert", "huge.tif", "-o", "out.png"]);
    assert_refused(&d, &o, "huge.tif", "out.png", "TIFF 65536²");
}

#[test]
fn exr_declaring_a_huge_data_window_is_refused() {
    let d = folder("exr-huge");
    let mut good = sample(&d, "exr");
    let key = b"dataWindow\0box2i\0";
    let at = good
        .windows(key.len())
        .position(|w| w == key)
        .expect("dataWindow attribute")
        + key.len()
        + 4;
    // xMin yMin xMax yMax: make the window 65536 × 65536
    good[at + 8..at + 12].copy_from_slice(&65535i32.to_le_bytes());
    good[at + 12..at + 16].copy_from_slice(&65535i32.to_le_bytes());
    write(&d, "huge.exr", &good);
    let o = run_in(&d, &["convert", "huge.exr", "-o", "out.png"]);
    assert_refused(&d, &o, "huge.exr", "out.png", "EXR 65536²");
}

#[test]
fn nrrd_and_nifti_cut_short_or_inflated_are_refused() {
    let d = folder("nrrd-nifti");
    for ext in ["nrrd", "nii", "nii.gz"] {
        let good = sample(&d, ext);
        let n = good.len();
        refuse_truncations(
            &d,
            &good,
            ext,
            &[10, n / 2, n - 3],
            &convert_to_tif,
            "out.tif",
        );
    }
    // NRRD: 65536³ f32 declared, 100 bytes of data
    let mut nrrd =
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 65536 65536 65536\nencoding: raw\n\n"
            .to_vec();
    nrrd.extend(vec![0u8; 100]);
    write(&d, "huge.nrrd", &nrrd);
    let o = run_in(&d, &["convert", "huge.nrrd", "-o", "out.tif"]);
    assert_refused(&d, &o, "huge.nrrd", "out.tif", "NRRD 65536³");
    // NRRD: 30000² u8 (within the sample limit), gzip data of 30 bytes
    let nrrd = b"NRRD0004\ntype: uint8\ndimension: 2\nsizes: 30000 30000\nencoding: gzip\n\n\x1f\x8b\x08\0\0\0\0\0\0\x03\x03\0\0\0\0\0\0\0\0\0";
    write(&d, "gz.nrrd", nrrd);
    let o = run_in(&d, &["convert", "gz.nrrd", "-o", "out.tif"]);
    assert_refused(&d, &o, "gz.nrrd", "out.tif", "NRRD gzip 30000²");
    // NIfTI: 32767³ i16 declared in a 1 KB file
    let mut nii = nifti_header([32767, 32767, 32767], 4);
    nii.extend(vec![0u8; 700]);
    write(&d, "huge.nii", &nii);
    let o = run_in(&d, &["convert", "huge.nii", "-o", "out.tif"]);
    assert_refused(&d, &o, "huge.nii", "out.tif", "NIfTI 32767³");
}

/// A NIfTI-1 header (352 bytes, little endian) of `dims` (x, y, z) and `datatype`.
fn nifti_header(dims: [i16; 3], datatype: i16) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim = [3, dims[0], dims[1], dims[2], 1, 1, 1, 1];
    for (i, v) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    let bitpix: i16 = if datatype == 2 { 8 } else { 16 };
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    for i in 0..8 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

#[test]
fn a_nii_gz_that_inflates_far_past_its_header_is_read_only_as_far_as_the_header_needs() {
    let d = folder("nii-bomb");
    // header: 32³ u8; then 1.5 GB of zeros as 1536 copies of one gzip member of 1 MiB
    let mut first = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    let mut head = nifti_header([32, 32, 32], 2);
    head.extend(vec![5u8; 32 * 32 * 32]);
    first.write_all(&head).unwrap();
    let mut bomb = first.finish().unwrap();
    let mut zeros = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    zeros.write_all(&vec![0u8; 1 << 20]).unwrap();
    let member = zeros.finish().unwrap();
    for _ in 0..1536 {
        bomb.extend_from_slice(&member);
    }
    write(&d, "bomb.nii.gz", &bomb);
    let t = std::time::Instant::now();
    let o = run_in(&d, &["convert", "bomb.nii.gz", "-o", "out.nrrd"]);
    assert!(
        o.status.success(),
        "read within a 1 GiB cap: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        t.elapsed().as_secs() < 30,
        "stopped early, not inflated whole"
    );
    let o = run_in(&d, &["info-file", "out.nrrd", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["dims"], serde_json::json!([32, 32, 32]));
    assert_eq!(v["min"], serde_json::json!(5.0));
    assert_eq!(v["max"], serde_json::json!(5.0));
}

#[test]
fn nhdr_data_files_are_read_only_as_far_as_the_header_needs() {
    let d = folder("nhdr");
    // /dev/zero: exactly 64×48 bytes are read
    write(
        &d,
        "zero.nhdr",
        b"NRRD0004\ntype: uint8\ndimension: 2\nsizes: 64 48\nencoding: raw\ndata file: /dev/zero\n",
    );
    let o = run_in(&d, &["info-file", "zero.nhdr", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // dims x, y (fastest first), as every printed vector
    assert_eq!(v["dims"], serde_json::json!([64, 48]));
    assert_eq!(v["max"], serde_json::json!(0.0));
    // /dev/zero with an absurd size: refused before reading
    write(
        &d,
        "zerobig.nhdr",
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4096 4096 4096\nencoding: raw\ndata file: /dev/zero\n",
    );
    let o = run_in(&d, &["convert", "zerobig.nhdr", "-o", "out.tif"]);
    assert_refused(&d, &o, "zerobig.nhdr", "out.tif", "/dev/zero 4096³ f32");
    // the same within a budget of 1 MiB given by MRA_MAX_BYTES: refused, naming the budget
    let o = run_env(
        &d,
        &["convert", "zero.nhdr", "-o", "out.tif"],
        &[("MRA_MAX_BYTES", "1K")],
    );
    assert_refused(&d, &o, "zero.nhdr", "out.tif", "budget of 1 KiB");
    assert!(String::from_utf8_lossy(&o.stderr).contains("MRA_MAX_BYTES"));
    // a FIFO with no writer: refused at once instead of blocking
    let fifo = d.join("pipe");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if made.map(|s| s.success()).unwrap_or(false) {
        write(
            &d,
            "fifo.nhdr",
            b"NRRD0004\ntype: uint8\ndimension: 2\nsizes: 64 48\nencoding: raw\ndata file: pipe\n",
        );
        let t = std::time::Instant::now();
        let o = run_in(&d, &["convert", "fifo.nhdr", "-o", "out.tif"]);
        assert_refused(&d, &o, "fifo.nhdr", "out.tif", "FIFO data file");
        assert!(t.elapsed().as_secs() < 30);
    } else {
        println!("skipped the FIFO case: mkfifo is not available");
    }
}

#[test]
fn hgt_and_asc_cut_short_or_inflated_are_refused() {
    let d = folder("hgt-asc");
    // SRTM3: 1201² big-endian i16
    let hgt = vec![0u8; 1201 * 1201 * 2];
    write(&d, "N10E010.hgt", &hgt);
    let o = run_in(&d, &["info-file", "N10E010.hgt"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for cut in [1, 1000, hgt.len() / 2, hgt.len() - 1] {
        write(&d, "N11E010.hgt", &hgt[..cut]);
        let o = run_in(&d, &["convert", "N11E010.hgt", "-o", "out.tif"]);
        assert_refused(
            &d,
            &o,
            "N11E010.hgt",
            "out.tif",
            &format!("HGT cut at {cut}"),
        );
    }
    let asc = b"ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n1 2 3 4\n5 6 7 8\n9 10 11 12\n";
    write(&d, "good.asc", asc);
    let o = run_in(&d, &["info-file", "good.asc"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    refuse_truncations(
        &d,
        asc,
        "asc",
        &[4, 12, 70, asc.len() - 6],
        &convert_to_tif,
        "out.tif",
    );
    let huge = b"ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n";
    write(&d, "huge.asc", huge);
    let o = run_in(&d, &["convert", "huge.asc", "-o", "out.tif"]);
    assert_refused(&d, &o, "huge.asc", "out.tif", "ASC 100000²");
}

#[test]
fn meshes_and_point_lists_cut_short_or_inflated_are_refused() {
    let d = folder("mesh-csv");
    let to_ply = |name: &str| -> Vec<String> {
        vec![
            "mesh".into(),
            "convert".into(),
            name.into(),
            "-o".into(),
            "out.ply".into(),
        ]
    };
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    write(&d, "good.obj", obj);
    make(&d, &["mesh", "convert", "good.obj", "-o", "good.ply"]);
    let o = run_in(&d, &["mesh", "convert", "good.obj", "-o", "check.ply"]);
    assert!(o.status.success());
    // a face that names vertices the file does not have, and a vertex line cut short
    write(&d, "bad.obj", &obj[..obj.len() - 3]);
    let o = run_in(
        &d,
        &to_ply("bad.obj")
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>(),
    );
    assert_refused(&d, &o, "bad.obj", "out.ply", "OBJ cut in a face");
    write(
        &d,
        "far.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000\n",
    );
    let o = run_in(
        &d,
        &to_ply("far.obj")
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>(),
    );
    assert_refused(&d, &o, "far.obj", "out.ply", "OBJ face index 10⁹");
    let to_obj = |name: &str| -> Vec<String> {
        vec![
            "mesh".into(),
            "convert".into(),
            name.into(),
            "-o".into(),
            "out.obj".into(),
        ]
    };
    let ply = std::fs::read(d.join("good.ply")).unwrap();
    let n = ply.len();
    refuse_truncations(&d, &ply, "ply", &[3, 40, n / 2, n - 2], &to_obj, "out.obj");
    let huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 4000000000\nproperty list uchar int vertex_indices\nend_header\n\0\0\0\0";
    write(&d, "huge.ply", huge);
    let o = run_in(
        &d,
        &to_obj("huge.ply")
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>(),
    );
    assert_refused(&d, &o, "huge.ply", "out.obj", "PLY 4·10⁹ vertices");

    // point lists: a value cut in half, a ragged row, text that is not numbers
    for (name, text) in [
        ("cut.csv", &b"0,0\n1,1\n2,0\n3,"[..]),
        ("ragged.csv", b"0,0\n1,1,1\n2,0\n3,1\n"),
        ("words.csv", b"x,y\nzero,one\n\x01\x02\x03\n"),
    ] {
        write(&d, name, text);
        let o = run_in(&d, &["subdivide", name, "-o", "out.csv"]);
        assert_refused(&d, &o, name, "out.csv", name);
    }
}

#[test]
fn mra_containers_cut_short_are_refused() {
    let d = folder("container");
    sample(&d, "png");
    make(&d, &["encode", "zp.png", "-o", "zp.mra"]);
    let good = std::fs::read(d.join("zp.mra")).unwrap();
    let n = good.len();
    let decode = |name: &str| -> Vec<String> {
        vec!["decode".into(), name.into(), "-o".into(), "out.png".into()]
    };
    refuse_truncations(&d, &good, "mra", &[3, 16, n / 2, n - 1], &decode, "out.png");
}

#[test]
fn upscale_and_subdivide_refuse_outputs_over_the_budget_before_allocating() {
    let d = folder("bounds");
    sample(&d, "png");
    let t = std::time::Instant::now();
    let o = run_in(
        &d,
        &["upscale", "zp.png", "-o", "big.png", "--factor", "1000"],
    );
    assert_refused(&d, &o, "zp.png", "big.png", "upscale ×1000");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("64000x64000") && err.contains("budget"),
        "{err}"
    );
    assert!(t.elapsed().as_secs() < 20);
    write(&d, "p.csv", b"0,0\n1,1\n2,0\n3,1\n4,0\n");
    let o = run_in(
        &d,
        &["subdivide", "p.csv", "--steps", "30", "-o", "out.csv"],
    );
    assert_refused(&d, &o, "p.csv", "out.csv", "subdivide --steps 30");
    assert!(String::from_utf8_lossy(&o.stderr).contains("budget"));
    let o = run_in(&d, &["solid", "volume", "s.json", "--rays", "1000000"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("16384") && err.lines().count() == 1, "{err}");
}

#[test]
fn upscale_takes_every_offered_order() {
    let d = folder("orders");
    sample(&d, "png");
    for k in 1..=12 {
        let out = format!("o{k}.png");
        let o = run_in(
            &d,
            &[
                "upscale",
                "zp.png",
                "-o",
                &out,
                "--factor",
                "2",
                "--order",
                &k.to_string(),
            ],
        );
        assert!(
            o.status.success(),
            "order {k}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let o = run_in(&d, &["info-file", &out, "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["dims"], serde_json::json!([128, 128]), "order {k}");
    }
    let o = run_in(
        &d,
        &[
            "upscale", "zp.png", "-o", "x.png", "--order", "13", "--factor", "2",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn argument_errors_are_one_line_that_names_what_is_wrong() {
    let d = folder("args");
    sample(&d, "png");
    // missing required arguments are named
    let o = run_in(&d, &["upscale", "zp.png"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--output"), "{err}");
    // a negative value is a value, and invalid
    let o = run_in(&d, &["encode", "zp.png", "-o", "z.mra", "--bpp", "-1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("invalid") && err.contains("-1"), "{err}");
    assert!(!err.contains("unexpected argument"), "{err}");
    assert!(!d.join("z.mra").exists());
    // no subcommand: the help, on stderr, exit 2
    let o = run_in(&d, &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
    assert!(String::from_utf8_lossy(&o.stderr).contains("Usage: mra"));
    // --help itself is still a success on stdout
    let o = run_in(&d, &["--help"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("MRA_MAX_BYTES"));
}

#[test]
fn an_error_quoting_binary_bytes_prints_one_bounded_line() {
    let d = folder("binary");
    // an NRRD encoding of 3000 bytes with control characters: the message quotes it
    let mut nrrd = b"NRRD0004\ntype: uint8\ndimension: 1\nsizes: 4\nencoding: ".to_vec();
    for i in 0..3000u32 {
        let b = (i % 96) as u8;
        nrrd.push(if b < 32 && b != b'\n' && b != b'\r' {
            b
        } else {
            b'A' + (b % 26)
        });
    }
    nrrd.extend_from_slice(b"\n\n\x01\x02\x03\x04");
    write(&d, "bin.nrrd", &nrrd);
    let o = run_in(&d, &["convert", "bin.nrrd", "-o", "out.tif"]);
    assert_refused(&d, &o, "bin.nrrd", "out.tif", "binary in the message");
    let err = String::from_utf8_lossy(&o.stderr);
    let line = err.trim_end();
    assert!(line.chars().all(|c| !c.is_control()), "{err:?}");
    assert!(line.contains("more characters"), "cut short: {err:?}");
}

#[test]
fn progress_shows_after_a_second_on_a_terminal_and_never_off_one() {
    let d = folder("progress");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/scenes/sphere_and_box.json");
    let scene = scene.to_str().unwrap();
    // off a terminal: nothing on stderr, even for a long run
    // 8000² rays take several seconds (3000² took 0.75 s on a fast machine, under the bar's
    // one-second reveal)
    let o = run_in(&d, &["solid", "volume", scene, "--rays", "8000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // on a terminal (script(1) gives the command a pseudo-terminal): a bar of rays
    let cmd = format!("{BIN} solid volume {scene} --rays 8000");
    match Command::new("script")
        .args(["-qefc", &cmd, "/dev/null"])
        .current_dir(&d)
        .stdin(Stdio::null())
        .output()
    {
        Ok(o) if o.status.success() => {
            let shown = String::from_utf8_lossy(&o.stdout);
            assert!(shown.contains("rays ["), "no bar drawn: {shown:?}");
            assert!(shown.contains("volume "), "{shown:?}");
        }
        other => println!("skipped the terminal case: script(1) did not run ({other:?})"),
    }
}

#[test]
fn open_cubic_subdivision_refines_four_and_five_points() {
    let d = folder("open-cubic");
    // four points: a clamped cubic Bézier; one midpoint inserted into knots 0⁴ 1⁴
    write(&d, "p4.csv", b"0,0\n1,1\n2,0\n3,1\n");
    let o = run_in(&d, &["subdivide", "--scheme", "cubic", "p4.csv"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pts: Vec<Vec<f64>> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| l.split(',').map(|t| t.trim().parse().unwrap()).collect())
        .collect();
    let want = [[0.0, 0.0], [0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.0, 1.0]];
    assert_eq!(pts.len(), want.len());
    for (p, w) in pts.iter().zip(&want) {
        assert!(
            (p[0] - w[0]).abs() < 1e-12 && (p[1] - w[1]).abs() < 1e-12,
            "{pts:?}"
        );
    }
    // five points: 2·5 − 3 = 7, ends kept
    write(&d, "p5.csv", b"0,0\n1,2\n2,0\n3,2\n4,0\n");
    let o = run_in(
        &d,
        &["subdivide", "--scheme", "cubic", "--steps", "2", "p5.csv"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2 * 7 - 3);
    assert!(lines[0].starts_with('0') && lines[lines.len() - 1].starts_with('4'));
    // three points are still too few for a cubic
    write(&d, "p3.csv", b"0,0\n1,1\n2,0\n");
    let o = run_in(
        &d,
        &["subdivide", "--scheme", "cubic", "p3.csv", "-o", "o.csv"],
    );
    assert_refused(&d, &o, "p3.csv", "o.csv", "three points");
    assert!(String::from_utf8_lossy(&o.stderr).contains("at least 4"));
}

#[test]
fn temporary_outputs_are_removed_on_sigterm_and_sigint() {
    let d = folder("signals");
    sample(&d, "png");
    for sig in ["TERM", "INT"] {
        // a slow write: upscale to a large TIFF, killed while it runs
        let child = Command::new(BIN)
            .args([
                "upscale", "zp.png", "-o", "big.tif", "--factor", "128", "--mode", "control",
            ])
            .current_dir(&d)
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let pid = child.id().to_string();
        let target = d.join("big.tif");
        // wait for the temporary file to appear (or the command to finish)
        let t = std::time::Instant::now();
        while mra::fsutil::leftover_temps(&target).is_empty()
            && !target.exists()
            && t.elapsed().as_secs() < 60
        {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let _ = Command::new("kill")
            .args([&format!("-{sig}"), &pid])
            .status();
        let out = child.wait_with_output().unwrap();
        if target.exists() {
            println!("SIG{sig}: the write finished before the signal; nothing to check");
            let _ = std::fs::remove_file(&target);
            continue;
        }
        assert!(!out.status.success(), "SIG{sig}: killed");
        assert!(
            mra::fsutil::leftover_temps(&target).is_empty(),
            "SIG{sig}: temporary files left"
        );
    }
}

/// The chunks of an `.mra` file after its signature: (type, start, end past the CRC).
fn mra_chunks(bytes: &[u8]) -> Vec<([u8; 4], usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 12 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        out.push((bytes[at + 4..at + 8].try_into().unwrap(), at, at + 12 + len));
        at += 12 + len;
    }
    out
}

#[test]
fn decode_at_level_1_of_a_file_missing_or_swapping_level_2_is_refused() {
    let d = folder("level-gap");
    sample(&d, "png");
    make(&d, &["encode", "zp.png", "-o", "zp.mra"]);
    let good = std::fs::read(d.join("zp.mra")).unwrap();
    let levels: Vec<_> = mra_chunks(&good)
        .into_iter()
        .filter(|c| &c.0 == b"LEVL")
        .collect();
    let (_, s2, e2) = levels[levels.len() - 2];
    let (_, s1, e1) = levels[levels.len() - 1];
    write(&d, "missing.mra", &[&good[..s2], &good[e2..]].concat());
    write(
        &d,
        "swapped.mra",
        &[&good[..s2], &good[s1..e1], &good[s2..e2], &good[e1..]].concat(),
    );
    for name in ["missing.mra", "swapped.mra"] {
        let o = run_in(&d, &["decode", name, "-o", "out.png", "--level", "1"]);
        assert_refused(&d, &o, name, "out.png", &format!("{name} at level 1"));
        assert!(String::from_utf8_lossy(&o.stderr).contains("LEVL chunk of level 2"));
    }
}

#[test]
fn an_mra_declaring_8000_squared_decodes_within_the_budget_or_not_at_all() {
    let d = folder("mra-budget");
    sample(&d, "png");
    make(&d, &["encode", "zp.png", "-o", "zp.mra", "--levels", "4"]);
    let good = std::fs::read(d.join("zp.mra")).unwrap();
    let cs = mra_chunks(&good);
    let (_, s, e) = cs[0];
    let mut head = good[s + 8..e - 4].to_vec();
    for at in [5, 9] {
        head[at..at + 4].copy_from_slice(&8000u32.to_le_bytes());
    }
    // the tile extents (one tile) follow the 52 + 4N bytes of fields
    for at in [60, 64] {
        head[at..at + 4].copy_from_slice(&8000u32.to_le_bytes());
    }
    let mut forged = good[..s].to_vec();
    mra::format::put_chunk(&mut forged, b"HEAD", &head);
    forged.extend_from_slice(&good[e..cs.last().unwrap().1]);
    // an ancillary chunk long enough that the declared samples pass the length check
    mra::format::put_chunk(&mut forged, b"pADs", &vec![0u8; 24_000]);
    mra::format::put_chunk(&mut forged, b"MEND", &[]);
    write(&d, "huge.mra", &forged);
    let o = run_env(
        &d,
        &["decode", "huge.mra", "-o", "out.png"],
        &[("MRA_MAX_BYTES", "16M")],
    );
    assert_refused(&d, &o, "huge.mra", "out.png", "8000² under 16 MB");
    assert!(String::from_utf8_lossy(&o.stderr).contains("MRA_MAX_BYTES"));
    // the header alone is readable
    let o = run_env(&d, &["info", "huge.mra"], &[("MRA_MAX_BYTES", "16M")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // 8000² at level 4 is a 500² preview, but the decoder's planes are the full
    // pyramid's: still over 16 MB
    let o = run_env(
        &d,
        &["decode", "huge.mra", "-o", "out.png", "--level", "4"],
        &[("MRA_MAX_BYTES", "16M")],
    );
    assert_refused(
        &d,
        &o,
        "huge.mra",
        "out.png",
        "8000² at level 4 under 16 MB",
    );
}

#[test]
fn tiff_generate_and_mesh_subdivide_keep_to_the_budget() {
    let d = folder("budgets");
    make(
        &d,
        &[
            "generate",
            "terrain",
            "--size",
            "1025",
            "--dtype",
            "f32",
            "-o",
            "t.tif",
            "--compress",
        ],
    );
    let env = [("MRA_MAX_BYTES", "2M")];
    let o = run_env(&d, &["convert", "t.tif", "-o", "out.png"], &env);
    assert_refused(&d, &o, "t.tif", "out.png", "TIFF of 4 MB under 2 MB");
    assert!(String::from_utf8_lossy(&o.stderr).contains("MRA_MAX_BYTES"));
    let o = run_env(
        &d,
        &[
            "generate",
            "zone-plate",
            "--size",
            "20000x20000",
            "-o",
            "g.png",
        ],
        &[("MRA_MAX_BYTES", "256M")],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("MRA_MAX_BYTES"), "{err}");
    assert!(!d.join("g.png").exists());
    // a 50 × 50 grid of 4,802 triangles: 8 Loop steps make 315 million
    write(&d, "grid.obj", common::grid_obj(50, 7, 0.1).as_bytes());
    let args = [
        "mesh",
        "subdivide",
        "grid.obj",
        "-o",
        "out.obj",
        "--scheme",
        "loop",
        "--steps",
        "8",
    ];
    let o = run_env(&d, &args, &[("MRA_MAX_BYTES", "256M")]);
    assert_refused(&d, &o, "grid.obj", "out.obj", "8 Loop steps under 256 MB");
    assert!(String::from_utf8_lossy(&o.stderr).contains("MRA_MAX_BYTES"));
    // two steps fit
    let o = run_env(
        &d,
        &{
            let mut a = args;
            a[8] = "2";
            a
        },
        &[("MRA_MAX_BYTES", "256M")],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Adaptive subdivision keeps to the budget too: under 64 KiB the 4,802-triangle grid is
/// refused before the first level (one line naming MRA_MAX_BYTES, exit 2, no output);
/// 8 adaptive Loop steps of one face fit 256 MB where 8 uniform steps do not (the bound
/// follows the refined patches, not the whole mesh).
#[test]
fn adaptive_mesh_subdivision_keeps_to_the_budget() {
    let d = folder("budget-adaptive");
    write(&d, "grid.obj", common::grid_obj(50, 7, 0.1).as_bytes());
    let args = [
        "mesh",
        "subdivide",
        "grid.obj",
        "-o",
        "out.obj",
        "--scheme",
        "loop",
        "--steps",
        "2",
        "--adaptive",
        "0",
    ];
    let o = run_env(&d, &args, &[("MRA_MAX_BYTES", "64K")]);
    assert_refused(&d, &o, "grid.obj", "out.obj", "adaptive Loop under 64 KiB");
    assert!(String::from_utf8_lossy(&o.stderr).contains("MRA_MAX_BYTES"));
    let mut eight = args;
    eight[8] = "8";
    let o = run_env(&d, &eight, &[("MRA_MAX_BYTES", "256M")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(d.join("out.obj").exists());
    std::fs::remove_file(d.join("out.obj")).unwrap();
    let uniform = &eight[..9];
    let o = run_env(&d, uniform, &[("MRA_MAX_BYTES", "256M")]);
    assert_refused(
        &d,
        &o,
        "grid.obj",
        "out.obj",
        "8 uniform Loop steps under 256 MB",
    );
}

#[test]
fn exr_declaring_100000_squared_is_refused_by_info_convert_and_encode() {
    let d = folder("exr-100k");
    let mut good = sample(&d, "exr");
    let key = b"dataWindow\0box2i\0";
    let at = good
        .windows(key.len())
        .position(|w| w == key)
        .expect("dataWindow attribute")
        + key.len()
        + 4;
    good[at + 8..at + 12].copy_from_slice(&99_999i32.to_le_bytes());
    good[at + 12..at + 16].copy_from_slice(&99_999i32.to_le_bytes());
    write(&d, "huge.exr", &good);
    for (args, out) in [
        (vec!["info", "huge.exr"], "none"),
        (vec!["convert", "huge.exr", "-o", "out.png"], "out.png"),
        (vec!["encode", "huge.exr", "-o", "out.mra"], "out.mra"),
    ] {
        let o = run_in(&d, &args);
        assert_refused(&d, &o, "huge.exr", out, &format!("{args:?}"));
    }
}
