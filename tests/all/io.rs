//! Readers and writers: round trips per format and sample type, files written by other
//! tools (tests/reference/io_reference.py), the shared corpus (skipped when absent), and
//! bad input through the library and the `mra` binary.

use std::path::{Path, PathBuf};
use std::process::Command;

use mra::generate::rng::SplitMix64;
use mra::io::{self, DataKind, Raster, RawSpec, ReadOptions, SampleType, Samples};
use mra::ErrorKind;

use super::common;

/// `name` in a folder of its own: tests run in parallel, and two of them (or one test
/// twice) never write the same file.
fn tmp(name: &str) -> PathBuf {
    common::scratch_file(name)
}

/// A new, empty folder of its own.
fn tmp_dir(name: &str) -> PathBuf {
    common::scratch_dir(name)
}

/// Pseudo-random samples covering the type's whole range (floats: ±1000 with fractions).
fn random(dims: &[usize], channels: usize, ty: SampleType, seed: u64) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let mut rng = SplitMix64::new(seed);
    let (lo, hi) = ty.range();
    let v: Vec<f64> = (0..n)
        .map(|_| {
            if ty.is_float() {
                (rng.next_f64() - 0.5) * 2000.0
            } else {
                (lo + rng.next_f64() * (hi - lo + 1.0)).floor().min(hi)
            }
        })
        .collect();
    let kind = if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
}

fn roundtrip(r: &Raster, name: &str) -> Raster {
    let p = tmp(name);
    io::write(&p, r).unwrap_or_else(|e| panic!("write {name}: {e}"));
    let back = io::read(&p).unwrap_or_else(|e| panic!("read {name}: {e}"));
    assert_eq!(back.dims, r.dims, "{name} dims");
    assert_eq!(back.channels, r.channels, "{name} channels");
    assert_eq!(back.sample_type(), r.sample_type(), "{name} type");
    assert!(back.samples == r.samples, "{name} samples differ");
    back
}

const ALL_TYPES: [SampleType; 9] = SampleType::ALL;

#[test]
fn png_roundtrip_8_and_16_bit_all_channel_counts() {
    for ty in [SampleType::U8, SampleType::U16] {
        for c in 1..=4 {
            let r = random(&[9, 13], c, ty, c as u64);
            roundtrip(&r, &format!("rt_{ty}_{c}.png"));
        }
    }
}

#[test]
fn pnm_roundtrip() {
    for ty in [SampleType::U8, SampleType::U16] {
        roundtrip(&random(&[7, 5], 1, ty, 1), &format!("rt_{ty}.pgm"));
        roundtrip(&random(&[7, 5], 3, ty, 2), &format!("rt_{ty}.ppm"));
        roundtrip(&random(&[7, 5], 4, ty, 3), &format!("rt_{ty}.pam"));
    }
}

#[test]
fn tiff_roundtrip_every_type_rgb_and_stacks_with_metadata() {
    for ty in ALL_TYPES {
        if ty == SampleType::F16 {
            continue;
        }
        roundtrip(&random(&[6, 11], 1, ty, 4), &format!("rt_{ty}_gray.tif"));
        let mut vol = random(&[3, 6, 5], 1, ty, 5);
        vol.meta.spacing = Some(vec![3.0, 0.5, 0.25]);
        vol.meta.units = Some("mm".into());
        vol.meta.origin = Some(vec![1.5, -2.0, 7.0]);
        vol.meta.extra.insert("scheme".into(), "haar".into());
        let back = roundtrip(&vol, &format!("rt_{ty}_stack.tif"));
        assert_eq!(back.kind, DataKind::Volume);
        assert_eq!(back.meta.spacing, vol.meta.spacing);
        assert_eq!(back.meta.units, vol.meta.units);
        assert_eq!(back.meta.origin, vol.meta.origin);
        assert_eq!(
            back.meta.extra.get("scheme").map(String::as_str),
            Some("haar")
        );
    }
    for ty in [
        SampleType::U8,
        SampleType::U16,
        SampleType::U32,
        SampleType::F32,
        SampleType::F64,
    ] {
        roundtrip(&random(&[4, 7], 3, ty, 6), &format!("rt_{ty}_rgb.tif"));
        roundtrip(&random(&[4, 7], 4, ty, 7), &format!("rt_{ty}_rgba.tif"));
    }
    for ty in [
        SampleType::U16,
        SampleType::I32,
        SampleType::F32,
        SampleType::F64,
    ] {
        let r = random(&[3, 40, 37], 1, ty, 10);
        let p = tmp(&format!("rt_{ty}_deflate.tif"));
        io::write_with(&p, &r, &io::WriteOptions { compress: true }).unwrap();
        assert_eq!(io::read(&p).unwrap().samples, r.samples, "{ty} deflate");
    }
    for ty in [SampleType::U8, SampleType::U16, SampleType::F32] {
        roundtrip(&random(&[4, 7], 2, ty, 8), &format!("rt_{ty}_graya.tif"));
        roundtrip(
            &random(&[3, 4, 7], 2, ty, 9),
            &format!("rt_{ty}_graya_stack.tif"),
        );
    }
}

#[test]
fn exr_roundtrip_half_float_uint() {
    for c in [1, 2, 3, 4] {
        for ty in [SampleType::F16, SampleType::F32] {
            let r = random(&[5, 6], c, ty, 8);
            roundtrip(&r, &format!("rt_{ty}_{c}.exr"));
        }
    }
    roundtrip(&random(&[5, 6], 1, SampleType::U32, 9), "rt_u32.exr");
}

#[test]
fn nrrd_roundtrip_types_encodings_detached_and_metadata() {
    for ty in ALL_TYPES {
        if ty == SampleType::F16 {
            continue;
        }
        for gzip in [false, true] {
            for ext in ["nrrd", "nhdr"] {
                let mut r = random(&[3, 4, 5], 1, ty, 10);
                r.meta.space = Some("left-posterior-superior".into());
                r.meta.directions = Some(vec![
                    vec![0.5, 0.0, 0.0],
                    vec![0.0, 0.75, 0.0],
                    vec![0.0, 0.0, 2.0],
                ]);
                r.meta.origin = Some(vec![-10.0, 20.5, 3.0]);
                r.meta.extra.insert("mra.scheme".into(), "chaikin".into());
                let p = tmp(&format!("rt_{ty}_{gzip}.{ext}"));
                io::write_with(&p, &r, &io::WriteOptions { compress: gzip }).unwrap();
                let back = io::read(&p).unwrap();
                assert_eq!(back.dims, r.dims);
                assert!(back.samples == r.samples, "{ty} gzip={gzip} {ext}");
                assert_eq!(back.meta.spacing, Some(vec![2.0, 0.75, 0.5]));
                assert_eq!(back.meta.origin, r.meta.origin);
                assert_eq!(back.meta.directions, r.meta.directions);
                assert_eq!(back.meta.space, r.meta.space);
                assert_eq!(
                    back.meta.extra.get("mra.scheme").map(String::as_str),
                    Some("chaikin")
                );
            }
        }
    }
    roundtrip(&random(&[4, 6], 3, SampleType::U8, 11), "rt_rgb.nrrd");
    roundtrip(&random(&[4, 6], 1, SampleType::F32, 12), "rt_2d.nrrd");
}

#[test]
fn nrrd_big_endian_written_by_hand() {
    let vals: [i16; 6] = [-300, 0, 1, 2, 32767, -32768];
    let mut bytes =
        b"NRRD0004\ntype: short\ndimension: 2\nsizes: 3 2\nendian: big\nencoding: raw\n\n".to_vec();
    for v in vals {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    let p = tmp("be.nrrd");
    std::fs::write(&p, bytes).unwrap();
    let r = io::read(&p).unwrap();
    assert_eq!(r.dims, vec![2, 3]);
    assert_eq!(r.samples, Samples::I16(vals.to_vec()));
}

#[test]
fn nifti_roundtrip_plain_and_gzip() {
    for (ty, c) in [
        (SampleType::U8, 1),
        (SampleType::I16, 1),
        (SampleType::U16, 1),
        (SampleType::I32, 1),
        (SampleType::F32, 1),
        (SampleType::F64, 1),
        (SampleType::U8, 3),
    ] {
        for ext in ["nii", "nii.gz"] {
            let mut r = random(&[3, 4, 5], c, ty, 13);
            r.meta.spacing = Some(vec![2.5, 0.75, 0.5]);
            r.meta.affine = Some([
                [0.5, 0.0, 0.0, -20.0],
                [0.0, 0.75, 0.0, 10.0],
                [0.0, 0.0, 2.5, -5.0],
            ]);
            let back = roundtrip(&r, &format!("rt_{ty}_{c}.{ext}"));
            assert_eq!(back.meta.spacing, r.meta.spacing);
            assert_eq!(back.meta.affine, r.meta.affine);
        }
    }
}

#[test]
fn heightmap_formats_roundtrip() {
    let mut h = random(&[11, 11], 1, SampleType::I16, 14);
    if let Samples::I16(v) = &mut h.samples {
        v[5] = io::hgt::VOID;
    }
    let back = roundtrip(&h, "rt.hgt");
    assert_eq!(back.meta.nodata, Some(-32768.0));
    assert_eq!(io::hgt::void_count(&back), 1);

    let mut a = random(&[4, 6], 1, SampleType::I32, 15);
    a.meta.nodata = Some(-9999.0);
    let back = roundtrip(&a, "rt_int.asc");
    assert_eq!(back.meta.nodata, Some(-9999.0));
    roundtrip(&random(&[4, 6], 1, SampleType::F64, 16), "rt_float.asc");

    roundtrip(&random(&[8, 8], 1, SampleType::U16, 17), "rt.r16");
    roundtrip(&random(&[8, 8], 1, SampleType::F32, 18), "rt.r32");
    // non-square .r16 needs its dims
    let r = random(&[4, 8], 1, SampleType::U16, 19);
    let p = tmp("rect.r16");
    io::write(&p, &r).unwrap();
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
    let spec = RawSpec {
        dims: vec![4, 8],
        sample_type: SampleType::U16,
        big_endian: false,
    };
    let back = io::read_with(
        &p,
        &ReadOptions {
            raw: Some(spec),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(back.samples, r.samples);
}

#[test]
fn raw_reads_both_byte_orders() {
    let vals: Vec<u16> = (0..24).map(|i| i * 2731).collect();
    for big in [false, true] {
        let bytes: Vec<u8> = vals
            .iter()
            .flat_map(|v| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            })
            .collect();
        let p = tmp(&format!("vol_{big}.raw"));
        std::fs::write(&p, bytes).unwrap();
        let spec = RawSpec {
            dims: vec![2, 3, 4],
            sample_type: SampleType::U16,
            big_endian: big,
        };
        let r = io::read_with(
            &p,
            &ReadOptions {
                raw: Some(spec),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(r.dims, vec![2, 3, 4]);
        assert_eq!(r.samples, Samples::U16(vals.clone()));
    }
    let r = random(&[2, 3, 4], 1, SampleType::F64, 20);
    let p = tmp("f64.raw");
    io::write(&p, &r).unwrap();
    let spec = RawSpec {
        dims: vec![2, 3, 4],
        sample_type: SampleType::F64,
        big_endian: false,
    };
    assert_eq!(
        io::read_with(
            &p,
            &ReadOptions {
                raw: Some(spec),
                ..Default::default()
            }
        )
        .unwrap()
        .samples,
        r.samples
    );
}

#[test]
fn folder_of_slices_reads_as_volume() {
    let dir = tmp_dir("slices");
    let vol = random(&[4, 6, 5], 1, SampleType::U16, 21);
    for z in 0..4 {
        let Samples::U16(v) = &vol.samples else {
            unreachable!()
        };
        let slice = Raster::new(
            vec![6, 5],
            1,
            Samples::U16(v[z * 30..(z + 1) * 30].to_vec()),
            DataKind::Image,
        )
        .unwrap();
        io::write(&dir.join(format!("slice_{z:03}.png")), &slice).unwrap();
    }
    let r = io::read(&dir).unwrap();
    assert_eq!(r.dims, vec![4, 6, 5]);
    assert_eq!(r.kind, DataKind::Volume);
    assert_eq!(r.samples, vol.samples);
}

#[test]
fn files_written_by_other_tools() {
    let refdir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference");
    let text = std::fs::read_to_string(refdir.join("io_fixture.json")).unwrap();
    let f: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cases = f["cases"].as_array().unwrap();
    assert!(cases.len() >= 15);
    for c in cases {
        let file = c["file"].as_str().unwrap();
        let r = io::read(&refdir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let dims: Vec<usize> = c["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as usize)
            .collect();
        assert_eq!(r.dims, dims, "{file}");
        assert_eq!(r.channels as u64, c["channels"].as_u64().unwrap(), "{file}");
        assert_eq!(
            r.sample_type().name(),
            c["dtype"].as_str().unwrap(),
            "{file}"
        );
        let want: Vec<f64> = c["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(r.to_f64(), want, "{file} values");
        if let Some(sp) = c.get("spacing") {
            let want: Vec<f64> = sp
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let got = r
                .meta
                .spacing
                .clone()
                .unwrap_or_else(|| panic!("{file}: spacing lost (expected {want:?})"));
            assert_eq!(got.len(), want.len(), "{file} spacing {got:?} vs {want:?}");
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() < 1e-6, "{file} spacing {got:?} vs {want:?}");
            }
        }
        if let Some(o) = c.get("origin") {
            let want: Vec<f64> = o
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let got = r
                .meta
                .origin
                .clone()
                .unwrap_or_else(|| panic!("{file}: origin lost (expected {want:?})"));
            assert_eq!(got.len(), want.len(), "{file} origin {got:?} vs {want:?}");
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() < 1e-6, "{file} origin {got:?} vs {want:?}");
            }
        }
        if let Some(tags) = c.get("geotiff_tags") {
            let want: Vec<u16> = tags
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t.as_u64().unwrap() as u16)
                .collect();
            let got: Vec<u16> = r.meta.geotiff.iter().map(|g| g.tag).collect();
            assert_eq!(got, want, "{file}");
            // and they survive a rewrite
            let back = roundtrip(&r, "geotiff_rewrite.tif");
            assert_eq!(back.meta.geotiff, r.meta.geotiff);
        }
    }
}

// ---------------------------------------------------------------- bad input

fn write_bytes(name: &str, bytes: &[u8]) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A valid file of `r` in format `ext`, as bytes.
fn encoded(r: &Raster, ext: &str) -> Vec<u8> {
    let p = tmp(&format!("enc.{ext}"));
    io::write(&p, r).unwrap();
    std::fs::read(&p).unwrap()
}

#[test]
fn truncated_files_are_format_errors() {
    let img = random(&[32, 32], 1, SampleType::U16, 22);
    let vol = random(&[4, 8, 8], 1, SampleType::I16, 23);
    for (ext, r) in [
        ("png", &img),
        ("tif", &img),
        ("nrrd", &vol),
        ("nii", &vol),
        ("exr", &random(&[16, 16], 1, SampleType::F32, 24)),
    ] {
        let b = encoded(r, ext);
        let p = write_bytes(&format!("trunc.{ext}"), &b[..b.len() * 2 / 3]);
        let e = io::read(&p).expect_err(ext);
        assert!(
            matches!(e.kind(), ErrorKind::Format | ErrorKind::Unsupported),
            "{ext}: {e}"
        );
    }
    let hgt = random(&[11, 11], 1, SampleType::I16, 25);
    let b = encoded(&hgt, "hgt");
    let p = write_bytes("trunc.hgt", &b[..b.len() - 2]);
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
    // gzip-encoded NRRD cut short
    let p = tmp("gz.nrrd");
    io::write_with(&p, &vol, &io::WriteOptions { compress: true }).unwrap();
    let b = std::fs::read(&p).unwrap();
    let p = write_bytes("trunc_gz.nrrd", &b[..b.len() - 40]);
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
}

#[test]
fn nrrd_sizes_beyond_the_data_fail_before_allocating() {
    let p = write_bytes(
        "big.nrrd",
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 512 512 100\nencoding: raw\n\n0123456789",
    );
    let e = io::read(&p).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Format);
    assert!(e.to_string().contains("10"), "{e}");
    let p = write_bytes(
        "absurd.nrrd",
        b"NRRD0004\ntype: double\ndimension: 3\nsizes: 4000000000 4000000000 4000000000\nencoding: gzip\n\n",
    );
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::LimitsExceeded);
    let p = write_bytes(
        "nosizes.nrrd",
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4\nencoding: raw\n\n",
    );
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
}

#[test]
fn raw_size_mismatch_is_an_error() {
    let p = write_bytes("short.raw", &[0u8; 100]);
    let spec = RawSpec {
        dims: vec![2, 8, 8],
        sample_type: SampleType::U16,
        big_endian: false,
    };
    let e = io::read_with(
        &p,
        &ReadOptions {
            raw: Some(spec),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Format);
    assert!(e.to_string().contains("256"), "{e}");
    // and without a layout at all
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Parameter);
}

#[test]
fn unsupported_sample_types_are_reported() {
    let p = write_bytes(
        "i64.nrrd",
        b"NRRD0004\ntype: long long\ndimension: 1\nsizes: 2\nencoding: raw\n\n0123456789abcdef",
    );
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Unsupported);
    let half = random(&[4, 4], 1, SampleType::F16, 26);
    for ext in ["png", "tif", "nrrd", "pgm"] {
        let p = tmp(&format!("half.{ext}"));
        let e = io::write(&p, &half).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Unsupported, "{ext}");
        assert!(!p.exists(), "{ext}: no output file after a failed write");
        assert!(
            mra::fsutil::leftover_temps(&p).is_empty(),
            "{ext}: temp file removed"
        );
    }
}

#[test]
fn missing_files_folders_and_mismatched_extensions() {
    let e = io::read(Path::new("/nonexistent/mra/file.png")).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
    let dir = tmp_dir("no_dicom");
    std::fs::write(dir.join("notes.txt"), "hello").unwrap();
    let e = io::read(&dir).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Format);
    assert!(e.to_string().contains("DICOM"), "{e}");
    let png = encoded(&random(&[4, 4], 1, SampleType::U8, 27), "png");
    let p = write_bytes("png_named.tif", &png);
    let e = io::read(&p).unwrap_err();
    assert!(e.to_string().contains("extension"), "{e}");
    let p = write_bytes("png_named.hgt", &png);
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
    let p = write_bytes("garbage.png", b"not a png at all");
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
    let p = write_bytes("garbage", b"no extension, no magic");
    assert_eq!(io::read(&p).unwrap_err().kind(), ErrorKind::Format);
}

// ---------------------------------------------------------------- the binary

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

#[test]
fn cli_bad_input_is_one_line_exit_2_and_no_output() {
    let dir = tmp_dir("cli_bad");
    let vol = random(&[4, 8, 8], 1, SampleType::I16, 28);
    let nrrd = encoded(&vol, "nrrd");
    let png = encoded(&random(&[32, 32], 3, SampleType::U8, 29), "png");
    let tif = encoded(&random(&[32, 32], 1, SampleType::F32, 30), "tif");
    let hgt = encoded(&random(&[11, 11], 1, SampleType::I16, 31), "hgt");
    let cases: Vec<(PathBuf, Vec<String>)> = vec![
        (write_bytes("c_trunc.png", &png[..png.len() / 2]), vec![]),
        (write_bytes("c_trunc.tif", &tif[..tif.len() / 2]), vec![]),
        (write_bytes("c_trunc.nrrd", &nrrd[..nrrd.len() - 7]), vec![]),
        (write_bytes("c_trunc.hgt", &hgt[..hgt.len() - 1]), vec![]),
        (
            write_bytes(
                "c_big.nrrd",
                b"NRRD0004\ntype: float\ndimension: 2\nsizes: 1000 1000\nencoding: raw\n\nxx",
            ),
            vec![],
        ),
        (
            write_bytes("c_short.raw", &[0u8; 99]),
            vec![
                "--dims".into(),
                "10x10".into(),
                "--dtype".into(),
                "u8".into(),
            ],
        ),
        (
            write_bytes(
                "c_i64.nrrd",
                b"NRRD0004\ntype: int64\ndimension: 1\nsizes: 1\nencoding: raw\n\n01234567",
            ),
            vec![],
        ),
        (PathBuf::from("/nonexistent/mra/in.png"), vec![]),
        (tmp_dir("c_empty_dir"), vec![]),
    ];
    for (input, extra) in cases {
        let out = dir.join("out.tif");
        let mut args: Vec<String> = vec![
            "convert".into(),
            input.display().to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        args.extend(extra);
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, stdout, stderr) = mra(&a);
        assert_eq!(code, 2, "{input:?}: {stderr}");
        assert!(stdout.is_empty());
        assert_eq!(stderr.trim_end().lines().count(), 1, "{input:?}: {stderr}");
        assert!(
            stderr.contains(&input.display().to_string()),
            "{input:?}: error names the file: {stderr}"
        );
        assert!(!out.exists(), "{input:?}: no output file");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "{input:?}: nothing left behind: {left:?}");
    }
    // a write that fails (f16 has no PNG form) leaves nothing either
    let exr = tmp("c_half.exr");
    io::write(&exr, &random(&[8, 8], 1, SampleType::F16, 32)).unwrap();
    let out = dir.join("out.png");
    let (code, _, stderr) = mra(&[
        "convert",
        exr.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none());
}

#[test]
fn cli_generate_compare_info_and_convert() {
    let dir = tmp_dir("cli_ok");
    let a = dir.join("zone.png");
    let b = dir.join("noise.png");
    assert_eq!(
        mra(&[
            "generate",
            "zone-plate",
            "-o",
            a.to_str().unwrap(),
            "--size",
            "64"
        ])
        .0,
        0
    );
    assert_eq!(
        mra(&[
            "generate",
            "noise",
            "-o",
            b.to_str().unwrap(),
            "--size",
            "64"
        ])
        .0,
        0
    );
    let (code, out, err) = mra(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    for key in ["mse", "psnr", "max_abs_error", "ssim", "data_range"] {
        assert!(v[key].is_number(), "{key} in {out}");
    }
    assert_eq!(v["data_range"].as_f64(), Some(255.0));
    let (_, out, _) = mra(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert!(v["psnr"].is_null());
    let (code, out, _) = mra(&["info-file", a.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["dims"], serde_json::json!([64, 64]));
    assert_eq!(v["dtype"], "u8");
    let c = dir.join("zone.nrrd");
    assert_eq!(
        mra(&["convert", a.to_str().unwrap(), "-o", c.to_str().unwrap()]).0,
        0
    );
    assert_eq!(io::read(&c).unwrap().samples, io::read(&a).unwrap().samples);
    let (code, _, err) = mra(&[
        "compare",
        a.to_str().unwrap(),
        dir.join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("x.png"));
}

// ---------------------------------------------------------------- shared corpus

#[test]
fn corpus_images_load_with_stated_shapes() {
    let Some(c) = common::corpus("images") else {
        return;
    };
    let mut n = 0;
    for i in 1..=24 {
        let p = c.join(format!("kodak/kodim{i:02}.png"));
        let r = io::read(&p).unwrap();
        assert!(
            r.dims == vec![512, 768] || r.dims == vec![768, 512],
            "{p:?}"
        );
        assert_eq!((r.channels, r.sample_type()), (3, SampleType::U8));
        n += 1;
    }
    assert_eq!(n, 24);
    for f in ["artificial_gray16.png", "flower_foveon_gray16_linear.png"] {
        let r = io::read(&c.join("highbit").join(f)).unwrap();
        assert_eq!((r.channels, r.sample_type()), (1, SampleType::U16), "{f}");
    }
}

#[test]
fn corpus_volumes_agree_across_formats() {
    let Some(v) = common::corpus("volumes") else {
        return;
    };
    let nrrd = io::read(&v.join("ct_pancreas_256.nrrd")).unwrap();
    assert_eq!(nrrd.dims, vec![134, 256, 256]);
    assert_eq!(nrrd.sample_type(), SampleType::I16);
    assert_eq!(nrrd.samples.min_max(), Some((-1000.0, 1510.0)));
    assert_eq!(nrrd.meta.spacing, Some(vec![3.0, 2.1484375, 2.1484375]));
    assert_eq!(nrrd.meta.space.as_deref(), Some("left-posterior-superior"));
    let o = nrrd.meta.origin.clone().unwrap();
    assert!((o[0] + 274.462890625).abs() < 1e-6 && (o[2] - 85.91).abs() < 1e-9);

    let stack = io::read(&v.join("ct_pancreas_256_stack.tif")).unwrap();
    assert_eq!(stack.dims, vec![134, 256, 256]);
    assert_eq!(stack.sample_type(), SampleType::U16);
    let sp = stack.meta.spacing.clone().unwrap();
    assert!(
        (sp[0] - 3.0).abs() < 1e-9 && (sp[2] - 2.1484375).abs() < 1e-6,
        "{sp:?}"
    );
    // TIFF value = HU + 1000, voxel by voxel
    let (hu, tv) = (nrrd.to_f64(), stack.to_f64());
    assert!(hu.iter().zip(&tv).all(|(h, t)| h + 1000.0 == *t));

    let raw = io::read_with(
        &v.join("ct_pancreas_crop_256x256x64_u16le.raw"),
        &ReadOptions {
            raw: Some(RawSpec {
                dims: vec![64, 256, 256],
                sample_type: SampleType::U16,
                big_endian: false,
            }),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(raw.samples.min_max(), Some((0.0, 2365.0)));

    let dicom = io::read(&v.join("ct_pancreas_dicom")).unwrap();
    assert_eq!(dicom.dims, vec![24, 512, 512]);
    assert_eq!(dicom.sample_type(), SampleType::I16);
    assert_eq!(dicom.samples.min_max(), Some((-1000.0, 1365.0)));
    assert_eq!(dicom.meta.spacing, Some(vec![3.0, 1.07421875, 1.07421875]));
    assert!((dicom.meta.origin.clone().unwrap()[2] - 295.91).abs() < 1e-6);
    // the raw crop starts at z = 205.91 mm, rows 172.., columns 127..: DICOM slice k is
    // crop slice 30 + k, and crop value = HU + 1000
    let (rv, dv) = (raw.to_f64(), dicom.to_f64());
    for k in 0..24 {
        for y in 0..256 {
            for x in 0..256 {
                let r = rv[((30 + k) * 256 + y) * 256 + x];
                let d = dv[(k * 512 + 172 + y) * 512 + 127 + x];
                assert_eq!(r, d + 1000.0, "slice {k} row {y} col {x}");
            }
        }
    }

    let mni = io::read(&v.join("mni152_t1_2009a_1mm.nii.gz")).unwrap();
    assert_eq!(mni.dims, vec![189, 233, 197]);
    assert_eq!(mni.sample_type(), SampleType::U8);
    assert_eq!(mni.samples.min_max(), Some((0.0, 255.0)));
    assert_eq!(mni.meta.spacing, Some(vec![1.0, 1.0, 1.0]));
}

#[test]
fn corpus_terrain_loads_with_voids_and_geotags() {
    let Some(t) = common::corpus("terrain") else {
        return;
    };
    let nh = io::read(&t.join("N44W072.hgt")).unwrap();
    assert_eq!(nh.dims, vec![1201, 1201]);
    assert_eq!(nh.samples.min_max(), Some((115.0, 1908.0)));
    assert_eq!(io::hgt::void_count(&nh), 0);
    let png = io::read(&t.join("N44W072_u16.png")).unwrap();
    assert_eq!(png.sample_type(), SampleType::U16);
    assert_eq!(png.to_f64(), nh.to_f64());

    let kauai = io::read(&t.join("N22W160.hgt")).unwrap();
    assert_eq!(kauai.meta.nodata, Some(-32768.0));
    assert_eq!(io::hgt::void_count(&kauai), 4279);
    let vals = kauai.to_f64();
    assert_eq!(vals.iter().filter(|&&v| v == 0.0).count(), 1_312_291);
    let valid = vals.iter().filter(|&&v| v != -32768.0);
    let (lo, hi) = valid.fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert_eq!((lo, hi), (-34.0, 1579.0));

    let msh = io::read(&t.join("mt_st_helens_30m_f32.tif")).unwrap();
    assert_eq!(msh.dims, vec![460, 317]);
    assert_eq!(msh.sample_type(), SampleType::F32);
    assert_eq!(msh.samples.min_max(), Some((694.0, 2543.0)));
    assert_eq!(msh.meta.spacing, Some(vec![30.0, 30.0]));
    let tags: Vec<u16> = msh.meta.geotiff.iter().map(|g| g.tag).collect();
    assert_eq!(tags, vec![33550, 33922, 34735]);
    let back = roundtrip(&msh, "msh_rewrite.tif");
    assert_eq!(back.meta.geotiff, msh.meta.geotiff);

    let asc = io::read(&t.join("srtmgl3_boulder_co.asc")).unwrap();
    assert_eq!(asc.dims, vec![144, 240]);
    assert_eq!(asc.samples.min_max(), Some((1943.0, 3286.0)));
    assert_eq!(asc.meta.nodata, Some(0.0));
    let back = roundtrip(&asc, "boulder.asc");
    assert_eq!(back.meta.extra, asc.meta.extra);
}

#[test]
fn committed_corpus_files_match_their_generate_commands() {
    use mra::generate::{generate, Kind};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus");
    type Case = (&'static str, Kind, Vec<usize>, usize, u64, SampleType);
    let cases: [Case; 8] = [
        (
            "zone_plate_256.png",
            Kind::ZonePlate,
            vec![256, 256],
            1,
            1,
            SampleType::U8,
        ),
        (
            "gradient_rgb16_256.png",
            Kind::Gradient,
            vec![256, 256],
            3,
            1,
            SampleType::U16,
        ),
        (
            "edges_256.png",
            Kind::Edges,
            vec![256, 256],
            1,
            1,
            SampleType::U8,
        ),
        (
            "strokes_256.png",
            Kind::Strokes,
            vec![256, 256],
            1,
            1,
            SampleType::U8,
        ),
        (
            "noise_rgb_128.png",
            Kind::Noise,
            vec![128, 128],
            3,
            1,
            SampleType::U8,
        ),
        (
            "phantom_64.nrrd",
            Kind::Phantom,
            vec![64, 64, 64],
            1,
            1,
            SampleType::U16,
        ),
        (
            "terrain_257.png",
            Kind::Terrain,
            vec![257, 257],
            1,
            7,
            SampleType::U16,
        ),
        (
            "terrain_129_f32.tif",
            Kind::Terrain,
            vec![129, 129],
            1,
            7,
            SampleType::F32,
        ),
    ];
    for (file, kind, dims, channels, seed, ty) in cases {
        let want = generate(kind, &dims, channels, seed)
            .unwrap()
            .to_raster(ty)
            .unwrap();
        let got = io::read(&dir.join(file)).unwrap();
        assert_eq!(got.dims, want.dims, "{file}");
        assert!(
            got.samples == want.samples,
            "{file}: regenerate it (corpus/README.md)"
        );
        assert!(
            std::fs::metadata(dir.join(file)).unwrap().len() < 200_000,
            "{file}"
        );
    }
}

// ---------------------------------------------------------------- pyramid files

#[test]
fn pyramid_container_keeps_source_type_and_metadata() {
    use mra::io::pyramid_file::{self, PyramidInfo};
    for (dims, ty, ext) in [
        (vec![6, 7], SampleType::U16, "tif"),
        (vec![3, 6, 7], SampleType::I16, "nrrd"),
    ] {
        let mut src = random(&dims, 1, ty, 40);
        src.meta.spacing = Some(vec![0.5; dims.len()]);
        src.meta.nodata = Some(-7.0);
        src.meta.description = Some("first line\nsecond".into());
        src.meta.extra.insert("dicom.modality".into(), "CT".into());
        let info = PyramidInfo {
            scheme: "cubic".into(),
            boundary: "symmetric".into(),
            levels: 3,
            order: "non-standard".into(),
            axes: (0..dims.len()).collect(),
            source_type: ty,
            source_kind: src.kind,
        };
        // coefficients = the samples + 0.25 (any f32 data will do here)
        let coeffs: Vec<f32> = src.to_f32().iter().map(|v| v + 0.25).collect();
        let c = pyramid_file::container(&src, coeffs, &info).unwrap();
        let p = tmp(&format!("pyr.{ext}"));
        pyramid_file::write(&p, &c).unwrap();
        let wrong = tmp(&format!(
            "pyr.{}",
            if ext == "tif" { "nrrd" } else { "tif" }
        ));
        assert!(pyramid_file::write(&wrong, &c).is_err());
        let (back, info2) = pyramid_file::read(&p).unwrap();
        assert_eq!(info2, info);
        assert_eq!(back.sample_type(), SampleType::F32);
        let values: Vec<f32> = back.to_f32().iter().map(|v| v - 0.25).collect();
        let restored = pyramid_file::restore(&back, &values, &info2).unwrap();
        assert_eq!(restored.samples, src.samples, "{ext}");
        assert_eq!(restored.meta.spacing, src.meta.spacing);
        assert_eq!(restored.meta.nodata, src.meta.nodata);
        assert_eq!(restored.meta.description, src.meta.description);
        assert_eq!(
            restored
                .meta
                .extra
                .get("dicom.modality")
                .map(String::as_str),
            Some("CT")
        );
        assert!(restored.meta.extra.keys().all(|k| !k.starts_with("mra.")));
    }
    // a plain TIFF is not a pyramid
    let p = tmp("plain.tif");
    io::write(&p, &random(&[4, 4], 1, SampleType::F32, 41)).unwrap();
    assert_eq!(
        mra::io::pyramid_file::read(&p).unwrap_err().kind(),
        ErrorKind::Format
    );
}

#[test]
fn pyramid_pictures_stretch_each_block() {
    use mra::io::visual::{picture, slice, standard_blocks, Block};
    // 4×4: coarse 2×2 block with values 10..13, details ±1, ±2
    let mut data = vec![0f32; 16];
    data[0] = 10.0;
    data[1] = 11.0;
    data[4] = 12.0;
    data[5] = 13.0;
    data[2] = 2.0;
    data[3] = -2.0;
    data[8] = 1.0;
    let blocks = standard_blocks(&[vec![4, 2], vec![4, 2]]);
    assert_eq!(blocks.len(), 4);
    assert_eq!(blocks.iter().filter(|b| b.coarse).count(), 1);
    let pic = picture(&data, &[4, 4], 1, &blocks).unwrap();
    let Samples::U8(p) = &pic.samples else {
        panic!()
    };
    assert_eq!((p[0], p[5]), (0, 255), "coarse block stretched to 0..255");
    assert_eq!((p[2], p[3]), (255, 1), "detail ±max → 255 / 1");
    assert_eq!(p[8], 255, "its own block's max");
    assert_eq!(p[15], 128, "zero detail is mid-grey");
    let vol = vec![1f32; 2 * 4 * 4];
    let blocks3 = vec![Block {
        ranges: vec![0..1, 0..4, 0..4],
        coarse: true,
    }];
    let (s, b) = slice(&vol, &[2, 4, 4], 1, &blocks3, 0).unwrap();
    assert_eq!((s.len(), b.len()), (16, 1));
    let (_, b) = slice(&vol, &[2, 4, 4], 1, &blocks3, 1).unwrap();
    assert!(b.is_empty());
}

#[test]
fn corrupted_files_give_errors_not_panics() {
    let img = random(&[12, 10], 3, SampleType::U16, 50);
    let gray = random(&[12, 10], 1, SampleType::I16, 51);
    let vol = random(&[3, 6, 5], 1, SampleType::F32, 52);
    let mut encoded_files: Vec<(&str, Vec<u8>)> = vec![
        ("png", encoded(&img, "png")),
        ("tif", encoded(&img, "tif")),
        (
            "exr",
            encoded(&random(&[12, 10], 3, SampleType::F16, 53), "exr"),
        ),
        ("ppm", encoded(&img, "ppm")),
        ("nrrd", encoded(&vol, "nrrd")),
        ("nii", encoded(&vol, "nii")),
        ("asc", encoded(&gray, "asc")),
    ];
    let p = tmp("gz_src.nrrd");
    io::write_with(&p, &vol, &io::WriteOptions { compress: true }).unwrap();
    encoded_files.push(("nrrd", std::fs::read(&p).unwrap()));
    let mut rng = SplitMix64::new(99);
    for (ext, bytes) in &encoded_files {
        let mut variants: Vec<Vec<u8>> = Vec::new();
        for k in 1..16 {
            variants.push(bytes[..bytes.len() * k / 16].to_vec());
        }
        for _ in 0..40 {
            let mut b = bytes.clone();
            for _ in 0..1 + rng.next_u64() % 4 {
                let i = (rng.next_u64() % b.len() as u64) as usize;
                b[i] = rng.next_u64() as u8;
            }
            variants.push(b);
        }
        for (i, v) in variants.iter().enumerate() {
            let path = write_bytes(&format!("corrupt_{i}.{ext}"), v);
            // Ok (a flipped sample value) or Err, but never a panic
            let _ = io::read(&path);
        }
    }
    // zero sizes are errors, not empty rasters
    for (name, text) in [
        (
            "zero.nrrd",
            &b"NRRD0004\ntype: uint8\ndimension: 2\nsizes: 0 4\nencoding: raw\n\n"[..],
        ),
        (
            "zero.asc",
            &b"ncols 0\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n"[..],
        ),
    ] {
        let p = write_bytes(name, text);
        assert_eq!(
            io::read(&p).unwrap_err().kind(),
            ErrorKind::Format,
            "{name}"
        );
    }
}
