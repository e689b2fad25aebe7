//! Metadata through every command that changes the grid or copies a file: spacing,
//! origin, directions, GeoTIFF tags and DICOM geometry, on generated data, through the
//! `mra` binary; and the output path check every command passes.

use std::path::{Path, PathBuf};
use std::process::Command;

use mra::io::{self, DataKind, GeoTag, GeoValue, Raster, SampleType, Samples};

fn tmp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("metadata_tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn mra(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(args: &[&str]) {
    let (code, _, err) = mra(args);
    assert_eq!(code, 0, "mra {args:?}: {err}");
}

/// Exit 2 with one line on stderr; returns the line.
fn fails(args: &[&str]) -> String {
    let (code, _, err) = mra(args);
    assert_eq!(code, 2, "mra {args:?} should fail: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// A smooth i16 volume `[D, H, W]` with LPS geometry: spacing (1.5, 3.2, 3.2), origin
/// (−100, −50, 20), axis-aligned directions.
fn volume(d: usize, h: usize, w: usize) -> Raster {
    let v: Vec<f64> = (0..d * h * w)
        .map(|i| {
            let (z, y, x) = (i / (h * w), i / w % h, i % w);
            (100.0 * (x as f64 * 0.2).sin() + 50.0 * (y as f64 * 0.1).cos() + z as f64).round()
        })
        .collect();
    let mut r = Raster::new(
        vec![d, h, w],
        1,
        Samples::from_f64(&v, SampleType::I16),
        DataKind::Volume,
    )
    .unwrap();
    r.meta.spacing = Some(vec![1.5, 3.2, 3.2]);
    r.meta.origin = Some(vec![-100.0, -50.0, 20.0]);
    r.meta.space = Some("left-posterior-superior".into());
    r.meta.directions = Some(vec![
        vec![3.2, 0.0, 0.0],
        vec![0.0, 3.2, 0.0],
        vec![0.0, 0.0, 1.5],
    ]);
    r.meta.units = Some("mm".into());
    r
}

#[test]
fn decode_at_level_1_doubles_the_spacing_and_moves_the_origin_to_the_first_coarse_centre() {
    let d = tmp_dir("decode_level");
    let (src, enc, out) = (d.join("v.nrrd"), d.join("v.mra"), d.join("v1.nrrd"));
    io::write(&src, &volume(16, 32, 32)).unwrap();
    ok(&[
        "encode",
        s(&src),
        "-o",
        s(&enc),
        "--scheme",
        "haar",
        "--quality",
        "90",
    ]);
    ok(&["decode", s(&enc), "-o", s(&out), "--level", "1"]);
    let r = io::read(&out).unwrap();
    assert_eq!(r.dims, vec![8, 16, 16]);
    assert_eq!(r.meta.spacing, Some(vec![3.0, 6.4, 6.4]));
    // a Haar coarse sample is the mean of fine samples 2j, 2j+1: its centre is half a
    // fine cell further along each axis
    let o = r.meta.origin.clone().unwrap();
    assert!(
        close(&o, &[-100.0 + 1.6, -50.0 + 1.6, 20.0 + 0.75], 1e-9),
        "{o:?}"
    );
    let dirs = r.meta.directions.clone().unwrap();
    assert!(close(&dirs[0], &[6.4, 0.0, 0.0], 1e-9), "{dirs:?}");
    assert!(close(&dirs[2], &[0.0, 0.0, 3.0], 1e-9), "{dirs:?}");
    // the physical extent is kept: size × spacing along each axis
    let (a, b) = (volume(16, 32, 32), r);
    for i in 0..3 {
        let ea = a.dims[i] as f64 * a.meta.spacing.as_ref().unwrap()[i];
        let eb = b.dims[i] as f64 * b.meta.spacing.as_ref().unwrap()[i];
        assert!((ea - eb).abs() < 1e-9);
    }
    // a cubic B-spline coarse sample sits on fine sample 2i: spacing doubles, the
    // origin stays; Chaikin's sits at 2i − ½
    for (scheme, shift) in [("cubic", 0.0), ("chaikin", -0.5)] {
        let enc = d.join(format!("{scheme}.mra"));
        let out = d.join(format!("{scheme}1.nrrd"));
        ok(&["encode", s(&src), "-o", s(&enc), "--scheme", scheme]);
        ok(&["decode", s(&enc), "-o", s(&out), "--level", "1"]);
        let r = io::read(&out).unwrap();
        assert_eq!(r.meta.spacing, Some(vec![3.0, 6.4, 6.4]), "{scheme}");
        let o = r.meta.origin.clone().unwrap();
        let want = [
            -100.0 + shift * 3.2,
            -50.0 + shift * 3.2,
            20.0 + shift * 1.5,
        ];
        assert!(close(&o, &want, 1e-9), "{scheme}: {o:?}");
    }
}

#[test]
fn decode_frames_moves_the_origin_to_the_first_kept_frame() {
    let d = tmp_dir("decode_frames");
    let (src, enc, out) = (d.join("v.nrrd"), d.join("v.mra"), d.join("f.nrrd"));
    io::write(&src, &volume(16, 8, 8)).unwrap();
    ok(&["encode", s(&src), "-o", s(&enc), "--lossless"]);
    ok(&["decode", s(&enc), "-o", s(&out), "--frames", "5..9"]);
    let r = io::read(&out).unwrap();
    assert_eq!(r.dims, vec![4, 8, 8]);
    assert_eq!(r.meta.spacing, Some(vec![1.5, 3.2, 3.2]));
    let o = r.meta.origin.clone().unwrap();
    assert!(close(&o, &[-100.0, -50.0, 20.0 + 5.0 * 1.5], 1e-9), "{o:?}");
    // the samples are frames 5..9 of the source
    let src = io::read(&src).unwrap().to_f64();
    assert_eq!(r.to_f64(), src[5 * 64..9 * 64].to_vec());
}

/// A float DEM `[H, W]` with GeoTIFF tags: 30 m pixels, PixelIsArea, corner
/// (500000, 4000000).
fn geotiff(h: usize, w: usize) -> Raster {
    let v: Vec<f32> = (0..h * w)
        .map(|i| 700.0 + ((i / w) as f32 * 0.3).sin() * 200.0 + (i % w) as f32)
        .collect();
    let mut r = Raster::new(vec![h, w], 1, Samples::F32(v), DataKind::Heightmap).unwrap();
    r.meta.geotiff = vec![
        GeoTag {
            tag: 33550,
            value: GeoValue::Doubles(vec![30.0, 30.0, 0.0]),
        },
        GeoTag {
            tag: 33922,
            value: GeoValue::Doubles(vec![0.0, 0.0, 0.0, 500000.0, 4000000.0, 0.0]),
        },
        GeoTag {
            tag: 34735,
            value: GeoValue::Shorts(vec![1, 1, 0, 2, 1024, 0, 1, 1, 1025, 0, 1, 1]),
        },
    ];
    r
}

fn doubles(r: &Raster, tag: u16) -> Vec<f64> {
    match r
        .meta
        .geotiff
        .iter()
        .find(|t| t.tag == tag)
        .map(|t| &t.value)
    {
        Some(GeoValue::Doubles(d)) => d.clone(),
        other => panic!("tag {tag}: {other:?}"),
    }
}

/// GDAL's GeoTransform from ModelPixelScale and the first ModelTiepoint.
fn geo_transform(r: &Raster) -> [f64; 6] {
    let (sc, t) = (doubles(r, 33550), doubles(r, 33922));
    [
        t[3] - t[0] * sc[0],
        sc[0],
        0.0,
        t[4] + t[1] * sc[1],
        0.0,
        -sc[1],
    ]
}

#[test]
fn a_geotiff_decoded_at_level_1_gets_the_pixel_scale_and_tiepoint_of_its_new_grid() {
    let d = tmp_dir("geotiff_level");
    let (src, enc, out) = (d.join("dem.tif"), d.join("dem.mra"), d.join("dem1.tif"));
    io::write(&src, &geotiff(64, 48)).unwrap();
    ok(&["encode", s(&src), "-o", s(&enc), "--scheme", "haar"]);
    ok(&["decode", s(&enc), "-o", s(&out), "--level", "1"]);
    let r = io::read(&out).unwrap();
    assert_eq!(r.dims, vec![32, 24]);
    assert_eq!(doubles(&r, 33550), vec![60.0, 60.0, 0.0]);
    assert_eq!(r.meta.spacing, Some(vec![60.0, 60.0]));
    // PixelIsArea: the corner of the grid stays where it was
    assert_eq!(
        geo_transform(&r),
        [500000.0, 60.0, 0.0, 4000000.0, 0.0, -60.0]
    );
}

#[test]
fn upscale_and_downscale_of_a_geotiff_keep_its_tags_on_the_new_grid() {
    let d = tmp_dir("geotiff_scale");
    let src = d.join("dem.tif");
    io::write(&src, &geotiff(40, 30)).unwrap();
    let up = d.join("up.tif");
    ok(&["upscale", s(&src), "-o", s(&up), "--factor", "2"]);
    let r = io::read(&up).unwrap();
    assert_eq!(r.dims, vec![80, 60]);
    assert_eq!(r.meta.geotiff.len(), 3, "{:?}", r.meta.geotiff);
    assert_eq!(
        geo_transform(&r),
        [500000.0, 15.0, 0.0, 4000000.0, 0.0, -15.0]
    );
    let down = d.join("down.tif");
    ok(&["downscale", s(&src), "-o", s(&down)]);
    let r = io::read(&down).unwrap();
    let (sy, sx) = (
        30.0 * 40.0 / r.dims[0] as f64,
        30.0 * 30.0 / r.dims[1] as f64,
    );
    let gt = geo_transform(&r);
    assert!(
        close(&gt, &[500000.0, sx, 0.0, 4000000.0, 0.0, -sy], 1e-9),
        "{gt:?}"
    );
    assert!(r.meta.geotiff.iter().any(|t| t.tag == 34735));
}

/// The value of TIFF tag `tag` of the first page, as bytes (little-endian classic TIFF).
fn tiff_tag_bytes(file: &[u8], tag: u16) -> Option<Vec<u8>> {
    let u16_at = |p: usize| u16::from_le_bytes([file[p], file[p + 1]]);
    let u32_at = |p: usize| u32::from_le_bytes(file[p..p + 4].try_into().unwrap());
    assert_eq!(&file[..4], b"II*\0");
    let ifd = u32_at(4) as usize;
    for e in 0..u16_at(ifd) as usize {
        let at = ifd + 2 + 12 * e;
        if u16_at(at) != tag {
            continue;
        }
        let size = match u16_at(at + 2) {
            1 | 2 | 6 | 7 => 1,
            3 | 8 => 2,
            4 | 9 | 11 => 4,
            _ => 8,
        };
        let n = u32_at(at + 4) as usize * size;
        let off = if n <= 4 {
            at + 8
        } else {
            u32_at(at + 8) as usize
        };
        return Some(file[off..off + n].to_vec());
    }
    None
}

#[test]
fn the_tiff_writer_keeps_a_json_description_intact_and_stores_its_own_keys_apart() {
    let d = tmp_dir("tiff_json");
    let p = d.join("j.tif");
    let mut r = geotiff(4, 5);
    let json = r#"{"shape": [4, 5]}"#;
    r.meta.description = Some(json.into());
    r.meta.spacing = Some(vec![2.0, 3.0]);
    r.meta.nodata = Some(-9999.0);
    io::write(&p, &r).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let desc = tiff_tag_bytes(&bytes, 270).unwrap();
    assert_eq!(&desc[..], format!("{json}\0").as_bytes());
    let own = String::from_utf8(tiff_tag_bytes(&bytes, io::tiff::MRA_TAG).unwrap()).unwrap();
    assert!(
        own.contains("mra.spacing=2,3") && own.contains("mra.nodata=-9999"),
        "{own}"
    );
    let back = io::read(&p).unwrap();
    assert_eq!(back.meta.description.as_deref(), Some(json));
    assert_eq!(back.meta.spacing, Some(vec![2.0, 3.0]));
    assert_eq!(back.meta.nodata, Some(-9999.0));
    // a resampled copy drops the description that states the old shape
    let up = d.join("up.tif");
    ok(&["upscale", s(&p), "-o", s(&up), "--factor", "2"]);
    let bytes = std::fs::read(&up).unwrap();
    assert_eq!(tiff_tag_bytes(&bytes, 270), None);
    assert_eq!(io::read(&up).unwrap().meta.spacing, Some(vec![1.0, 1.5]));
}

#[test]
fn an_hgt_tile_converted_to_tiff_carries_a_tiepoint_and_pixel_scale() {
    let d = tmp_dir("hgt_tif");
    let side = 121;
    let mut b = Vec::with_capacity(side * side * 2);
    for i in 0..side * side {
        b.extend_from_slice(&((i % 500) as i16).to_be_bytes());
    }
    let hgt = d.join("N37W122.hgt");
    std::fs::write(&hgt, &b).unwrap();
    let tif = d.join("n37.tif");
    ok(&["convert", s(&hgt), "-o", s(&tif)]);
    let r = io::read(&tif).unwrap();
    let step = 1.0 / 120.0;
    assert_eq!(doubles(&r, 33550), vec![step, step, 0.0]);
    assert_eq!(doubles(&r, 33922), vec![0.0, 0.0, 0.0, -122.0, 38.0, 0.0]);
    assert_eq!(r.meta.nodata, Some(-32768.0));
    // downscaled: PixelIsPoint, so the first sample moves by the offset of the first
    // coarse centre
    let down = d.join("down.tif");
    ok(&["downscale", s(&hgt), "-o", s(&down)]);
    let r = io::read(&down).unwrap();
    let sc = doubles(&r, 33550);
    let t = doubles(&r, 33922);
    let ratio = 121.0 / r.dims[1] as f64;
    assert!((sc[0] - step * ratio).abs() < 1e-12, "{sc:?}");
    let first = (ratio - 1.0) / 2.0 * step;
    assert!((t[3] - (-122.0 + first)).abs() < 1e-9, "{t:?}");
    assert!((t[4] - (38.0 - first)).abs() < 1e-9, "{t:?}");
}

// ---------------------------------------------------------------- DICOM

/// One explicit-VR little-endian element.
fn element(out: &mut Vec<u8>, group: u16, elem: u16, vr: &[u8; 2], value: &[u8]) {
    let mut v = value.to_vec();
    if v.len() % 2 == 1 {
        v.push(if vr == b"UI" || vr == b"OB" { 0 } else { b' ' });
    }
    out.extend_from_slice(&group.to_le_bytes());
    out.extend_from_slice(&elem.to_le_bytes());
    out.extend_from_slice(vr);
    if matches!(vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
        out.extend_from_slice(&[0, 0]);
        out.extend_from_slice(&(v.len() as u32).to_le_bytes());
    } else {
        out.extend_from_slice(&(v.len() as u16).to_le_bytes());
    }
    out.extend_from_slice(&v);
}

/// A 4×3 CT slice at `z` (mm), rows along −y (oblique-free), PixelSpacing (0.8, 0.7),
/// values `base + i`; `pixel_len` overrides the PixelData length field.
fn dicom_slice(z: f64, base: u16, pixel_len: Option<u32>) -> Vec<u8> {
    let mut meta = Vec::new();
    element(&mut meta, 0x0002, 0x0001, b"OB", &[0, 1]);
    element(
        &mut meta,
        0x0002,
        0x0002,
        b"UI",
        b"1.2.840.10008.5.1.4.1.1.2",
    );
    element(
        &mut meta,
        0x0002,
        0x0003,
        b"UI",
        format!("1.2.3.4.{}", base).as_bytes(),
    );
    element(&mut meta, 0x0002, 0x0010, b"UI", b"1.2.840.10008.1.2.1");
    element(&mut meta, 0x0002, 0x0012, b"UI", b"1.2.3.4.5");
    let mut f = vec![0u8; 128];
    f.extend_from_slice(b"DICM");
    element(
        &mut f,
        0x0002,
        0x0000,
        b"UL",
        &(meta.len() as u32).to_le_bytes(),
    );
    f.extend_from_slice(&meta);
    element(&mut f, 0x0008, 0x0016, b"UI", b"1.2.840.10008.5.1.4.1.1.2");
    element(
        &mut f,
        0x0008,
        0x0018,
        b"UI",
        format!("1.2.3.4.{}", base).as_bytes(),
    );
    element(&mut f, 0x0008, 0x0060, b"CS", b"CT");
    element(&mut f, 0x0018, 0x0050, b"DS", b"2.5");
    element(&mut f, 0x0020, 0x000E, b"UI", b"1.2.3.99");
    element(
        &mut f,
        0x0020,
        0x0032,
        b"DS",
        format!("-120.5\\-80.25\\{z}").as_bytes(),
    );
    element(&mut f, 0x0020, 0x0037, b"DS", b"1\\0\\0\\0\\1\\0");
    element(&mut f, 0x0028, 0x0002, b"US", &1u16.to_le_bytes());
    element(&mut f, 0x0028, 0x0010, b"US", &3u16.to_le_bytes());
    element(&mut f, 0x0028, 0x0011, b"US", &4u16.to_le_bytes());
    element(&mut f, 0x0028, 0x0030, b"DS", b"0.8\\0.7");
    element(&mut f, 0x0028, 0x0100, b"US", &16u16.to_le_bytes());
    element(&mut f, 0x0028, 0x0101, b"US", &16u16.to_le_bytes());
    element(&mut f, 0x0028, 0x0103, b"US", &0u16.to_le_bytes());
    let px: Vec<u8> = (0..12u16).flat_map(|i| (base + i).to_le_bytes()).collect();
    element(&mut f, 0x7FE0, 0x0010, b"OW", &px);
    if let Some(len) = pixel_len {
        let at = f.len() - px.len() - 4;
        f[at..at + 4].copy_from_slice(&len.to_le_bytes());
    }
    f
}

fn series(name: &str, zs: &[f64]) -> PathBuf {
    let d = tmp_dir(name);
    let dir = d.join("series");
    std::fs::create_dir_all(&dir).unwrap();
    for (i, z) in zs.iter().enumerate() {
        std::fs::write(
            dir.join(format!("s{i:02}.dcm")),
            dicom_slice(*z, 100 * i as u16, None),
        )
        .unwrap();
    }
    dir
}

#[test]
fn a_dicom_series_converted_to_nrrd_keeps_its_origin_and_orientation() {
    let dir = series("dicom_ok", &[10.0, 12.5, 15.0, 17.5]);
    let out = dir.parent().unwrap().join("ct.nrrd");
    ok(&["convert", s(&dir), "-o", s(&out)]);
    let text = String::from_utf8_lossy(&std::fs::read(&out).unwrap()).into_owned();
    assert!(text.contains("space: left-posterior-superior"), "{text}");
    assert!(text.contains("space origin: (-120.5,-80.25,10)"), "{text}");
    assert!(
        text.contains("space directions: (0.7,0,0) (0,0.8,0) (0,0,2.5)"),
        "{text}"
    );
    let r = io::read(&out).unwrap();
    assert_eq!(r.dims, vec![4, 3, 4]);
    assert_eq!(r.meta.spacing, Some(vec![2.5, 0.8, 0.7]));
    assert_eq!(r.meta.origin, Some(vec![-120.5, -80.25, 10.0]));
    // encode → decode keeps them too
    let enc = dir.parent().unwrap().join("ct.mra");
    let dec = dir.parent().unwrap().join("ct_back.nrrd");
    ok(&["encode", s(&dir), "-o", s(&enc), "--lossless"]);
    ok(&["decode", s(&enc), "-o", s(&dec)]);
    let b = io::read(&dec).unwrap();
    assert_eq!(b.meta.origin, r.meta.origin);
    assert_eq!(b.meta.directions, r.meta.directions);
    assert_eq!(b.to_f64(), r.to_f64());
}

#[test]
fn a_dicom_series_with_a_missing_or_repeated_slice_is_refused_unless_accepted() {
    let dir = series("dicom_gap", &[355.91, 358.91, 364.91]);
    let out = dir.parent().unwrap().join("gap.nrrd");
    let e = fails(&["convert", s(&dir), "-o", s(&out)]);
    assert!(
        e.contains("series") && e.contains("355.91 / 358.91 / 364.91") && e.contains("uneven"),
        "{e}"
    );
    assert!(!out.exists());
    ok(&["convert", s(&dir), "-o", s(&out), "--allow-uneven-slices"]);
    let r = io::read(&out).unwrap();
    // the real mean step, (364.91 − 355.91) / 2
    let sp = r.meta.spacing.clone().unwrap();
    assert!((sp[0] - 4.5).abs() < 1e-9, "{sp:?}");

    let dir = series("dicom_dup", &[0.0, 2.0, 2.0, 4.0, 6.0]);
    let out = dir.parent().unwrap().join("dup.nrrd");
    let e = fails(&["convert", s(&dir), "-o", s(&out)]);
    assert!(
        e.contains("repeated") && e.contains("0 / 2 / 2 / 4 / 6"),
        "{e}"
    );
    assert!(!out.exists());
}

#[test]
fn a_dicom_pixel_data_length_beyond_the_file_is_refused_before_allocating() {
    let d = tmp_dir("dicom_len");
    for (name, len) in [
        ("huge.dcm", 0xFFFF_FFF0u32),
        ("short.dcm", 12),
        ("long.dcm", 26),
    ] {
        let p = d.join(name);
        let mut b = dicom_slice(0.0, 7, Some(len));
        if len == 26 {
            b.extend_from_slice(&[0, 0]);
        }
        std::fs::write(&p, &b).unwrap();
        let out = d.join(format!("{name}.nrrd"));
        let e = fails(&["info-file", s(&p)]);
        assert!(
            e.contains(name) && e.contains("PixelData") || e.contains("declares"),
            "{e}"
        );
        fails(&["convert", s(&p), "-o", s(&out)]);
        assert!(!out.exists());
    }
    // the unaltered slice reads
    let p = d.join("good.dcm");
    std::fs::write(&p, dicom_slice(0.0, 7, None)).unwrap();
    let r = io::read(&p).unwrap();
    assert_eq!(r.to_f64(), (7..19).map(f64::from).collect::<Vec<_>>());
}

// ---------------------------------------------------------------- output paths

#[test]
fn an_output_that_is_the_input_or_has_the_wrong_extension_is_refused() {
    let d = tmp_dir("outputs");
    let png = d.join("v.png");
    let r = Raster::new(
        vec![8, 8],
        1,
        Samples::U8((0..64).collect()),
        DataKind::Image,
    )
    .unwrap();
    io::write(&png, &r).unwrap();
    let before = std::fs::read(&png).unwrap();
    let e = fails(&["encode", s(&png), "-o", s(&png)]);
    assert!(e.contains("the output is the input"), "{e}");
    // the same file through another path and through a symbolic link
    let other = d.join(".").join("v.png");
    fails(&["upscale", s(&png), "-o", s(&other), "--factor", "2"]);
    #[cfg(unix)]
    {
        let link = d.join("link.png");
        std::os::unix::fs::symlink(&png, &link).unwrap();
        let e = fails(&["convert", s(&png), "-o", s(&link)]);
        assert!(e.contains("the output is the input"), "{e}");
    }
    assert_eq!(std::fs::read(&png).unwrap(), before);
    // encode writes .mra, decode a raster
    let e = fails(&["encode", s(&png), "-o", s(&d.join("v2.png"))]);
    assert!(e.contains("expected .mra"), "{e}");
    assert!(!d.join("v2.png").exists());
    let enc = d.join("v.mra");
    ok(&["encode", s(&png), "-o", s(&enc)]);
    let e = fails(&["decode", s(&enc), "-o", s(&d.join("back.mra"))]);
    assert!(e.contains("invalid output extension"), "{e}");
    let kept = std::fs::read(&enc).unwrap();
    fails(&["decode", s(&enc), "-o", s(&enc)]);
    assert_eq!(std::fs::read(&enc).unwrap(), kept);
}

// ---------------------------------------------------------------- the shared corpus

/// `../shared/corpus` (or `MRA_CORPUS`); `None` (test skipped) when absent, unless
/// `MRA_REQUIRE_CORPUS=1`, which makes a missing corpus file a failure.
fn corpus_file(rel: &str) -> Option<PathBuf> {
    let root = std::env::var_os("MRA_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus"));
    let p = root.join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var("MRA_REQUIRE_CORPUS").as_deref() != Ok("1"),
        "MRA_REQUIRE_CORPUS=1 but {} is missing",
        p.display()
    );
    super::common::skip(format_args!("{} not found", p.display()));
    None
}

#[test]
fn corpus_geotiff_decoded_at_level_1_has_60_m_pixels_at_the_same_corner() {
    let Some(src) = corpus_file("terrain/mt_st_helens_30m_f32.tif") else {
        return;
    };
    let d = tmp_dir("corpus_helens");
    // Haar's coarse pixel is the mean of 2×2 fine pixels: the same corner; CDF 9/7's
    // coarse sample sits on fine sample 2i, so its pixel starts half a fine pixel before
    for (scheme, shift) in [("haar", 0.0), ("cdf97", -15.0)] {
        let (enc, out) = (
            d.join(format!("h_{scheme}.mra")),
            d.join(format!("h1_{scheme}.tif")),
        );
        ok(&["encode", s(&src), "-o", s(&enc), "--scheme", scheme]);
        ok(&["decode", s(&enc), "-o", s(&out), "--level", "1"]);
        let (a, b) = (io::read(&src).unwrap(), io::read(&out).unwrap());
        assert_eq!(b.dims, vec![230, 159]);
        let (ga, gb) = (geo_transform(&a), geo_transform(&b));
        assert_eq!(ga[1], 30.0);
        assert_eq!(
            gb,
            [ga[0] + shift, 60.0, 0.0, ga[3] - shift, 0.0, -60.0],
            "{scheme}"
        );
    }
}

#[test]
fn corpus_dicom_series_to_nrrd_keeps_origin_and_orientation() {
    let Some(dir) = corpus_file("volumes/ct_pancreas_dicom") else {
        return;
    };
    let d = tmp_dir("corpus_dicom");
    let out = d.join("ct.nrrd");
    ok(&["convert", s(&dir), "-o", s(&out)]);
    let (a, b) = (io::read(&dir).unwrap(), io::read(&out).unwrap());
    assert!(a.meta.origin.is_some() && a.meta.directions.is_some());
    assert_eq!(b.meta.origin, a.meta.origin);
    assert_eq!(b.meta.directions, a.meta.directions);
    assert_eq!(b.meta.space.as_deref(), Some("left-posterior-superior"));
    assert_eq!(b.meta.spacing, a.meta.spacing);
}

#[test]
fn corpus_srtm_tile_with_voids_downscales_within_its_valid_range() {
    let Some(src) = corpus_file("terrain/N22W160.hgt") else {
        return;
    };
    let d = tmp_dir("corpus_kauai");
    let out = d.join("k.tif");
    ok(&["downscale", s(&src), "-o", s(&out)]);
    let r = io::read(&out).unwrap();
    assert_eq!(r.meta.nodata, Some(-32768.0));
    let v = r.to_f64();
    let valid: Vec<f64> = v.iter().copied().filter(|&x| x != -32768.0).collect();
    assert!(valid.len() < v.len(), "the largest voids stay void");
    let (lo, hi) = valid
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(lo >= -34.0 && hi <= 1579.0, "{lo}..{hi}");
    // and the GeoTIFF tags of the tile name follow the coarse grid
    let t = doubles(&r, 33922);
    assert!(
        t[3] > -160.0 && t[3] < -159.99 && t[4] < 23.0 && t[4] > 22.99,
        "{t:?}"
    );
}

/// A WGS 84 GeoTIFF written with the `tiff` crate as GDAL writes one: 0.000833° pixels
/// from corner (−122.5, 46.5), GTModelType geographic, PixelIsArea, GeographicType 4326,
/// angular unit degree, vertical unit metre; 16-bit heights.
fn wgs84_geotiff(path: &Path, h: usize, w: usize) {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let data: Vec<i16> = (0..h * w)
        .map(|i| (1000 + (i / w) * 7 + (i % w) * 3) as i16)
        .collect();
    let f = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(f).unwrap();
    let mut img = enc
        .new_image::<colortype::GrayI16>(w as u32, h as u32)
        .unwrap();
    let e = img.encoder();
    e.write_tag(Tag::Unknown(33550), &[0.000833f64, 0.000833, 0.0][..])
        .unwrap();
    e.write_tag(
        Tag::Unknown(33922),
        &[0.0f64, 0.0, 0.0, -122.5, 46.5, 0.0][..],
    )
    .unwrap();
    let keys: [u16; 24] = [
        1, 1, 0, 5, // directory header: 5 keys
        1024, 0, 1, 2, // GTModelType: geographic
        1025, 0, 1, 1, // GTRasterType: PixelIsArea
        2048, 0, 1, 4326, // GeographicType: WGS 84
        2054, 0, 1, 9102, // GeogAngularUnits: degree
        4099, 0, 1, 9001, // VerticalUnits: metre
    ];
    e.write_tag(Tag::Unknown(34735), &keys[..]).unwrap();
    img.write_data(&data).unwrap();
}

#[test]
fn a_wgs84_geotiff_reads_in_degrees_with_its_origin_and_keeps_them_through_commands() {
    let d = tmp_dir("geotiff_wgs84");
    let src = d.join("wgs84.tif");
    wgs84_geotiff(&src, 40, 60);
    let r = io::read(&src).unwrap();
    let px = 0.000833;
    assert_eq!(r.meta.units.as_deref(), Some("degree"));
    assert_eq!(r.meta.spacing, Some(vec![px, px]));
    assert_eq!(
        r.meta.extra.get("elevation_units").map(String::as_str),
        Some("m")
    );
    // PixelIsArea: the first sample's centre is half a pixel inside the corner
    let o = r.meta.origin.clone().unwrap();
    assert!(
        close(&o, &[-122.5 + px / 2.0, 46.5 - px / 2.0], 1e-12),
        "{o:?}"
    );
    assert_eq!(r.meta.directions, Some(vec![vec![px, 0.0], vec![0.0, -px]]));
    // `mra info` shows the unit and the origin
    let (code, out, err) = mra(&["info", s(&src), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["units"], "degree", "{out}");
    assert!(v["origin"].is_array(), "{out}");
    // round trip through TIFF: the same metadata, tags verbatim
    let copy = d.join("copy.tif");
    ok(&["convert", s(&src), "-o", s(&copy)]);
    let c = io::read(&copy).unwrap();
    assert_eq!(c.meta.units, r.meta.units);
    assert_eq!(c.meta.origin, r.meta.origin);
    assert_eq!(c.meta.directions, r.meta.directions);
    assert_eq!(c.meta.geotiff, r.meta.geotiff);
    // upscaled ×2: the origin stays the one the rewritten tags give
    let up = d.join("up.tif");
    ok(&["upscale", s(&src), "-o", s(&up), "--factor", "2"]);
    let u = io::read(&up).unwrap();
    assert_eq!(u.meta.units.as_deref(), Some("degree"));
    let g = io::geokeys::georeference(&u.meta.geotiff).unwrap();
    let (uo, go) = (u.meta.origin.clone().unwrap(), g.origin.unwrap());
    assert!(close(&uo, &go, 1e-12), "{uo:?} vs {go:?}");
    assert!(
        close(&uo, &[-122.5 + px / 4.0, 46.5 - px / 4.0], 1e-12),
        "{uo:?}"
    );
}

#[test]
fn terrain_synth_with_units_that_differ_names_the_options_that_fix_it() {
    let d = tmp_dir("geotiff_synth");
    let base = d.join("base.tif");
    wgs84_geotiff(&base, 24, 24);
    // an example in metres, without a unit: its cell cannot be compared with degrees
    let ex = d.join("example.asc");
    let n = 128;
    let mut text = format!("ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize 30\n");
    for y in 0..n {
        let row: Vec<String> = (0..n)
            .map(|x| ((x * 7 + y * 13) % 50 + (x * y) % 11).to_string())
            .collect();
        text += &row.join(" ");
        text.push('\n');
    }
    std::fs::write(&ex, text).unwrap();
    let out = d.join("out.tif");
    let e = fails(&[
        "terrain",
        "synth",
        "--base",
        s(&base),
        "--example",
        s(&ex),
        "-o",
        s(&out),
    ]);
    assert!(
        e.contains("\"degree\"") && e.contains("--example-cell") && e.contains("--any-units"),
        "{e}"
    );
    assert!(!out.exists());
    // the fix it names works: the example's cell in degrees
    ok(&[
        "terrain",
        "synth",
        "--base",
        s(&base),
        "--example",
        s(&ex),
        "-o",
        s(&out),
        "--example-cell",
        "0.0002",
    ]);
    let r = io::read(&out).unwrap();
    assert_eq!(r.meta.units.as_deref(), Some("degree"));
}

#[test]
fn a_dicom_whose_preamble_looks_like_tiff_reads_as_dicom() {
    let d = tmp_dir("dicom_tiff_preamble");
    // a dual-format file: the 128-byte preamble holds a little-endian TIFF header
    let mut b = dicom_slice(5.0, 40, None);
    b[..8].copy_from_slice(b"II*\0\x08\0\0\0");
    let p = d.join("ct.dcm");
    std::fs::write(&p, &b).unwrap();
    assert_eq!(io::Format::detect(&p).unwrap(), io::Format::Dicom);
    let r = io::read(&p).unwrap();
    assert_eq!(r.dims, vec![3, 4]);
    assert_eq!(r.to_f64(), (40..52).map(f64::from).collect::<Vec<_>>());
    // its geometry survives a conversion
    let out = d.join("ct.nrrd");
    ok(&["convert", s(&p), "-o", s(&out)]);
    let n = io::read(&out).unwrap();
    assert_eq!(n.meta.spacing, r.meta.spacing);
    assert_eq!(n.meta.origin, r.meta.origin);
    assert_eq!(n.to_f64(), r.to_f64());
}
