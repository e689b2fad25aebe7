//! Inputs and outputs at their edges: ASCII grids whose rows disagree with the header,
//! arguments out of their range (library and command line), bit-exact NaN payloads
//! through the lossless codec, and outputs that are links, FIFOs, devices, sockets, or
//! that meet a file-size limit. Every input is made by the test.

use std::path::{Path, PathBuf};
use std::process::Command;

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{self, DataKind, Raster, SampleType, Samples};
use mra::ErrorKind;

use super::common;

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

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Exit 2, one line on stderr, nothing on stdout, `out` not written, no temporary file.
fn refused(args: &[&str], out: &Path) -> String {
    let (code, stdout, stderr) = mra(args);
    assert_eq!(code, 2, "{args:?}: {stderr}");
    assert!(stdout.is_empty(), "{args:?}: {stdout}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    assert!(!out.exists(), "{args:?}: output written");
    assert!(
        mra::fsutil::leftover_temps(out).is_empty(),
        "{args:?}: temporary file left"
    );
    stderr
}

fn gray(h: usize, w: usize, ty: SampleType) -> Raster {
    let v: Vec<f64> = (0..h * w)
        .map(|i| ((i * 37) % 251) as f64 + (i / w) as f64)
        .collect();
    Raster::new(vec![h, w], 1, Samples::from_f64(&v, ty), DataKind::Image).unwrap()
}

// ---------------------------------------------------------------- ESRI ASCII rows

const ASC_HEADER: &str = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 30\n";

#[test]
fn asc_rows_with_more_or_fewer_values_than_ncols_are_refused() {
    let dir = common::scratch_dir("asc_rows");
    let cases = [
        ("long_row.asc", "1 2 3 4\n5 6\n", "data row 1 has 4 values"),
        ("short_row.asc", "1 2\n3 4 5 6\n", "data row 1 has 2 values"),
        (
            "extra_row.asc",
            "1 2 3\n4 5 6\n7 8 9\n",
            "more than the 2 rows",
        ),
        ("missing_row.asc", "1 2 3\n", "3 values for 2x3 cells"),
        ("empty.asc", "", "0 values for 2x3 cells"),
    ];
    for (name, data, why) in cases {
        let p = dir.join(name);
        std::fs::write(&p, format!("{ASC_HEADER}{data}")).unwrap();
        let e = io::read(&p).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Format, "{name}: {e}");
        assert!(e.to_string().contains(why), "{name}: {e}");
        let out = dir.join("out.tif");
        let err = refused(&["convert", &s(&p), "-o", &s(&out)], &out);
        assert!(err.contains(name) && err.contains(why), "{err}");
    }
    // well-formed rows (blank lines and trailing spaces allowed) still read
    let p = dir.join("ok.asc");
    std::fs::write(&p, format!("{ASC_HEADER}1 2 3 \n\n4 5 6\n")).unwrap();
    let r = io::read(&p).unwrap();
    assert_eq!(r.samples, Samples::I32(vec![1, 2, 3, 4, 5, 6]));
    assert_eq!(r.meta.spacing, Some(vec![30.0, 30.0]));
}

// ---------------------------------------------------------------- arguments

#[test]
fn library_rules_refuse_nonsense_parameters() {
    use mra::metrics::{compare, CompareOptions};
    use mra::terrain::Shading;
    let ok = Shading::default();
    ok.validate().unwrap();
    for bad in [
        Shading {
            z_factor: f64::NAN,
            ..ok.clone()
        },
        Shading {
            z_factor: -1.0,
            ..ok.clone()
        },
        Shading {
            z_factor: f64::INFINITY,
            ..ok.clone()
        },
        Shading {
            azimuth: f64::NAN,
            ..ok.clone()
        },
        Shading {
            cell: (1.0, 0.0),
            ..ok.clone()
        },
        Shading {
            cell: (f64::NAN, 1.0),
            ..ok.clone()
        },
        Shading {
            altitude: 91.0,
            ..ok.clone()
        },
    ] {
        assert_eq!(
            bad.validate().unwrap_err().kind(),
            ErrorKind::Parameter,
            "{bad:?}"
        );
    }
    let a = gray(8, 8, SampleType::U8);
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let o = CompareOptions {
            data_range: Some(r),
            ..Default::default()
        };
        let e = compare(&a, &a, &o).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parameter, "{r}: {e}");
    }
    let e = mra::generate::generate(mra::generate::Kind::Noise, &[8, 8], 0, 1).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter, "{e}");
    for sigma in [f64::NAN, -1.0, f64::INFINITY] {
        let mut x = mra::tensor::Array::from_shape_vec(&[8, 8], a.to_f64()).unwrap();
        let o = mra::denoise::DenoiseOptions {
            sigma: Some(sigma),
            ..Default::default()
        };
        let e = mra::denoise::denoise(&mut x, &[0, 1], &o).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Parameter, "{sigma}: {e}");
    }
    let o = EncodeOptions {
        rate: Rate::MaxError(1e308),
        ..Default::default()
    };
    let e = codec::encode(&a, &o).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Parameter, "{e}");
}

#[test]
fn the_command_line_refuses_nonsense_arguments_before_writing() {
    let dir = common::scratch_dir("bad_args");
    let png = dir.join("in.png");
    io::write(&png, &gray(32, 32, SampleType::U8)).unwrap();
    let (png, out_png) = (s(&png), dir.join("out.png"));
    let o = s(&out_png);
    let mut cases: Vec<Vec<String>> = Vec::new();
    let v = |a: &[&str]| a.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    for flag in ["--z-factor", "--cell", "--azimuth"] {
        for value in ["NaN", "inf", "-inf"] {
            cases.push(v(&[
                "terrain",
                "render",
                &png,
                "-o",
                &o,
                &format!("{flag}={value}"),
            ]));
        }
    }
    for flag in ["--z-factor", "--cell"] {
        for value in ["-1", "0"] {
            cases.push(v(&[
                "terrain",
                "render",
                &png,
                "-o",
                &o,
                &format!("{flag}={value}"),
            ]));
        }
    }
    for value in ["0", "-1", "NaN"] {
        cases.push(v(&[
            "compare",
            &png,
            &png,
            &format!("--data-range={value}"),
        ]));
    }
    for value in ["NaN", "-1"] {
        cases.push(v(&["denoise", &png, "-o", &o, &format!("--sigma={value}")]));
    }
    cases.push(v(&["generate", "noise", "--channels", "0", "-o", &o]));
    let mra_out = dir.join("out.mra");
    cases.push(v(&[
        "encode",
        &png,
        "--max-error",
        "1e308",
        "-o",
        &s(&mra_out),
    ]));
    for args in &cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let err = refused(&a, &out_png);
        assert!(
            err.contains("invalid") && err.contains("expected"),
            "{args:?}: {err}"
        );
        assert!(!mra_out.exists());
    }
    // a large finite bound still makes a file that decodes
    let (code, _, err) = mra(&["encode", &png, "--max-error", "1e300", "-o", &s(&mra_out)]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = mra(&["decode", &s(&mra_out), "-o", &o]);
    assert_eq!(code, 0, "{err}");
}

// ---------------------------------------------------------------- NaN payloads

/// NaNs of every kind: canonical, negative, payloads, signalling; among ordinary values.
fn nan_bits_f32() -> Vec<u32> {
    vec![
        0x7fc0_0000, // the canonical quiet NaN (a void)
        0xffc0_0000, // negative quiet NaN
        0x7fc0_1234, // quiet NaN with a payload
        0xffff_ffff, // all ones
        0x7f80_0001, // signalling NaN, smallest payload
        0x7fa0_0000, // signalling NaN
        0xff80_4321, // negative signalling NaN
    ]
}

fn nan_bits_f64() -> Vec<u64> {
    vec![
        0x7ff8_0000_0000_0000,
        0xfff8_0000_0000_0000,
        0x7ff8_dead_beef_0001,
        0xffff_ffff_ffff_ffff,
        0x7ff0_0000_0000_0001,
        0x7ff4_0000_0000_0000,
        0xfff0_0000_0000_abcd,
    ]
}

fn nan_bits_f16() -> Vec<u16> {
    vec![0x7e00, 0xfe00, 0x7e21, 0xffff, 0x7c01, 0x7d00, 0xfc07]
}

/// A 16×12 field of type `ty` with the NaNs of `nan_bits_*` scattered (every 7th sample
/// in turn), `seed` choosing their places.
fn with_nans(ty: SampleType, seed: usize) -> Raster {
    let (h, w) = (16, 12);
    let v: Vec<f64> = (0..h * w)
        .map(|i| ((i * 7919 + seed) % 1000) as f64 * 0.37 - 100.0)
        .collect();
    let mut r = Raster::new(vec![h, w], 1, Samples::from_f64(&v, ty), DataKind::Image).unwrap();
    let places = (0..h * w).filter(|i| (i + seed).is_multiple_of(7));
    match &mut r.samples {
        Samples::F32(x) => {
            let n = nan_bits_f32();
            for (k, i) in places.enumerate() {
                x[i] = f32::from_bits(n[k % n.len()]);
            }
        }
        Samples::F64(x) => {
            let n = nan_bits_f64();
            for (k, i) in places.enumerate() {
                x[i] = f64::from_bits(n[k % n.len()]);
            }
        }
        Samples::F16(x) => {
            let n = nan_bits_f16();
            for (k, i) in places.enumerate() {
                x[i] = half::f16::from_bits(n[k % n.len()]);
            }
        }
        _ => unreachable!(),
    }
    r
}

fn bits(s: &Samples) -> Vec<u64> {
    match s {
        Samples::F32(x) => x.iter().map(|v| v.to_bits() as u64).collect(),
        Samples::F64(x) => x.iter().map(|v| v.to_bits()).collect(),
        Samples::F16(x) => x.iter().map(|v| v.to_bits() as u64).collect(),
        _ => unreachable!(),
    }
}

#[test]
fn lossless_floats_keep_nan_payloads_signs_and_signalling_nans() {
    for ty in [SampleType::F32, SampleType::F64, SampleType::F16] {
        for seed in 0..3 {
            let mut r = with_nans(ty, seed);
            if seed == 2 {
                // a numeric nodata value: NaNs are then samples, not voids
                r.meta.nodata = Some(-100.0);
            }
            for rate in [Rate::Lossless, Rate::MaxError(0.0)] {
                let o = EncodeOptions {
                    rate,
                    ..Default::default()
                };
                let files = [
                    codec::encode(&r, &o).unwrap(),
                    codec::encode_tiled(&r, &o, &[8, 8]).unwrap(),
                ];
                for (k, f) in files.iter().enumerate() {
                    let d = codec::decode(f, &DecodeOptions::default()).unwrap();
                    assert_eq!(
                        bits(&d.raster.samples),
                        bits(&r.samples),
                        "{ty:?} seed {seed} {rate:?} file {k}"
                    );
                }
            }
        }
    }
}

#[test]
fn encode_lossless_then_decode_keeps_nan_bits_through_the_command_line() {
    let dir = common::scratch_dir("nan_cli");
    for (ty, name) in [(SampleType::F32, "f32.tif"), (SampleType::F64, "f64.nrrd")] {
        let r = with_nans(ty, 1);
        let src = dir.join(name);
        io::write(&src, &r).unwrap();
        assert_eq!(bits(&io::read(&src).unwrap().samples), bits(&r.samples));
        let m = dir.join(format!("{name}.mra"));
        let back = dir.join(format!("back_{name}"));
        let (code, _, err) = mra(&["encode", &s(&src), "--lossless", "-o", &s(&m)]);
        assert_eq!(code, 0, "{err}");
        let (code, _, err) = mra(&["decode", &s(&m), "-o", &s(&back)]);
        assert_eq!(code, 0, "{err}");
        assert_eq!(
            bits(&io::read(&back).unwrap().samples),
            bits(&r.samples),
            "{name}"
        );
    }
}

// ---------------------------------------------------------------- outputs

#[cfg(unix)]
mod unix_outputs {
    use super::*;
    use std::os::unix::fs::{symlink, FileTypeExt, OpenOptionsExt};

    fn png_in(dir: &Path) -> (PathBuf, Raster) {
        let r = gray(24, 20, SampleType::U8);
        let p = dir.join("in.png");
        io::write(&p, &r).unwrap();
        (p, r)
    }

    #[test]
    fn a_symbolic_link_is_written_through_and_stays_a_link() {
        let dir = common::scratch_dir("out_link");
        let (src, r) = png_in(&dir);
        let target = dir.join("real.tif");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.tif");
        symlink("real.tif", &link).unwrap();
        let (code, _, err) = mra(&["convert", &s(&src), "-o", &s(&link)]);
        assert_eq!(code, 0, "{err}");
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(io::read(&target).unwrap().samples, r.samples);
        // a dangling link names the file to create
        let link2 = dir.join("new.png");
        symlink("made.png", &link2).unwrap();
        let (code, _, err) = mra(&["convert", &s(&src), "-o", &s(&link2)]);
        assert_eq!(code, 0, "{err}");
        assert!(std::fs::symlink_metadata(&link2)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(io::read(&dir.join("made.png")).unwrap().samples, r.samples);
        assert!(mra::fsutil::leftover_temps(&target).is_empty());
    }

    #[test]
    fn a_fifo_is_written_through_once_the_bytes_are_complete() {
        let dir = common::scratch_dir("out_fifo");
        let (src, r) = png_in(&dir);
        let fifo = dir.join("pipe.tif");
        let st = Command::new("mkfifo").arg(&fifo).status();
        if !st.map(|s| s.success()).unwrap_or(false) {
            common::skip(format_args!("a_fifo_is_written_through: no mkfifo"));
            return;
        }
        let f2 = fifo.clone();
        let reader = std::thread::spawn(move || std::fs::read(&f2).unwrap());
        let (code, _, err) = mra(&["convert", &s(&src), "-o", &s(&fifo)]);
        // unblock the reader if the command never opened the FIFO (ENXIO when it did)
        let _ = std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(0o4000) // O_NONBLOCK
            .open(&fifo);
        let bytes = reader.join().unwrap();
        assert_eq!(code, 0, "{err}");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        let copy = dir.join("copy.tif");
        std::fs::write(&copy, &bytes).unwrap();
        assert_eq!(io::read(&copy).unwrap().samples, r.samples);
    }

    #[test]
    fn a_character_device_is_written_through_and_a_socket_refused() {
        let dir = common::scratch_dir("out_dev");
        let (src, _) = png_in(&dir);
        let null = dir.join("null.png");
        symlink("/dev/null", &null).unwrap();
        let (code, _, err) = mra(&["convert", &s(&src), "-o", &s(&null)]);
        assert_eq!(code, 0, "{err}");
        assert!(std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
        let sock = dir.join("sock.png");
        let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        let (code, _, err) = mra(&["convert", &s(&src), "-o", &s(&sock)]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(&s(&sock)) && err.contains("socket"), "{err}");
        assert!(std::fs::metadata(&sock).unwrap().file_type().is_socket());
    }

    /// Run `mra args` under a file-size limit of 8 blocks (4 or 8 KiB by the shell's
    /// unit): a write past it fails with EFBIG instead of killing the process.
    fn under_size_limit(args: &[&str]) -> (i32, String) {
        let out = Command::new("sh")
            .arg("-c")
            .arg("ulimit -f 8 && exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_mra"))
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }

    #[test]
    fn a_file_size_limit_or_a_full_disk_is_an_error_naming_the_output() {
        let dir = common::scratch_dir("out_full");
        // 64 KiB of 16-bit noise: no output of it fits in 8 KiB
        let v: Vec<f64> = (0..128 * 256)
            .map(|i: u64| ((i.wrapping_mul(2654435761) >> 7) % 65536) as f64)
            .collect();
        let r = Raster::new(
            vec![128, 256],
            1,
            Samples::from_f64(&v, SampleType::U16),
            DataKind::Image,
        )
        .unwrap();
        let raw = dir.join("in.nrrd");
        io::write(&raw, &r).unwrap();
        let m = dir.join("in.mra");
        let (code, _, err) = mra(&["encode", &s(&raw), "--lossless", "-o", &s(&m)]);
        assert_eq!(code, 0, "{err}");
        let cases: Vec<(Vec<String>, PathBuf)> = vec![
            (vec!["convert".into(), s(&raw)], dir.join("c.tif")),
            (
                vec!["encode".into(), s(&raw), "--lossless".into()],
                dir.join("e.mra"),
            ),
            (
                vec!["encode".into(), s(&raw), "--quality=90".into()],
                dir.join("q.mra"),
            ),
            (vec!["decode".into(), s(&m)], dir.join("d.nrrd")),
            (vec!["decode".into(), s(&m)], dir.join("d.tif")),
            (vec!["decode".into(), s(&m)], dir.join("d.png")),
            (
                vec!["upscale".into(), s(&raw), "--factor=2".into()],
                dir.join("u.nrrd"),
            ),
            (vec!["downscale".into(), s(&raw)], dir.join("dn.nrrd")),
        ];
        for (args, out) in &cases {
            let mut a: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = s(out);
            a.extend(["-o", &o]);
            let (code, err) = under_size_limit(&a);
            assert_eq!(code, 2, "{a:?}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{a:?}: {err}");
            assert!(err.contains(&o), "{a:?}: names the output: {err}");
            assert!(!out.exists(), "{a:?}");
            assert!(mra::fsutil::leftover_temps(out).is_empty(), "{a:?}");
        }
        // a full device (through a link with the extension the command wants)
        if Path::new("/dev/full").exists() {
            for (args, name) in [
                (vec!["encode", &s(&raw) as &str, "--lossless"], "full.mra"),
                (vec!["decode", &s(&m) as &str], "full.nrrd"),
                (vec!["convert", &s(&raw) as &str], "full.tif"),
            ] {
                let link = dir.join(name);
                symlink("/dev/full", &link).unwrap();
                let mut a = args.clone();
                let l = s(&link);
                a.extend(["-o", &l]);
                let (code, _, err) = mra(&a);
                assert_eq!(code, 2, "{a:?}: {err}");
                assert!(err.contains(&l), "{a:?}: names the output: {err}");
                assert!(!err.contains(&format!("{}:", a[1])), "{a:?}: {err}");
            }
        }
    }
}
