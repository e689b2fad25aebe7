//! The `mra` binary on point lists: outputs, round trips, and one-line errors with exit 2.

use std::process::Output;

use super::common;

fn mra(args: &[&str], stdin: &str) -> Output {
    common::mra_with_stdin(None, args, stdin.as_bytes())
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn tmpdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mra-cli-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn analyze_prints_the_haar_example_of_the_notes() {
    let o = mra(
        &["analyze", "--scheme", "haar", "--levels", "2", "-"],
        "5\n7\n10\n14\n13\n13\n8\n6\n",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(
        text(&o.stdout),
        "C,9.0\nC,10.0\nD2,-3.0\nD2,3.0\nD1,-1.0\nD1,-2.0\nD1,0.0\nD1,1.0\n"
    );
}

#[test]
fn analyze_then_synthesize_returns_the_points_for_every_scheme_and_boundary() {
    let pts: String = (0..37)
        .map(|i| {
            let t = i as f64 * 0.37;
            format!("{},{},{}\n", t.sin() * 3.0, (2.0 * t).cos(), t * 0.1)
        })
        .collect();
    for scheme in ["haar", "chaikin", "cubic"] {
        for boundary in ["interpolating", "periodic", "symmetric"] {
            let a = mra(
                &["analyze", "--scheme", scheme, "--boundary", boundary, "-"],
                &pts,
            );
            assert!(
                a.status.success(),
                "{scheme} {boundary}: {}",
                text(&a.stderr)
            );
            let s = mra(
                &[
                    "synthesize",
                    "--scheme",
                    scheme,
                    "--boundary",
                    boundary,
                    "-",
                ],
                &text(&a.stdout),
            );
            assert!(
                s.status.success(),
                "{scheme} {boundary}: {}",
                text(&s.stderr)
            );
            let want = mra::points::parse(&pts).unwrap();
            let got = mra::points::parse(&text(&s.stdout)).unwrap();
            assert_eq!(got.dim, 3);
            for (x, y) in want.data.iter().zip(&got.data) {
                assert!((x - y).abs() < 1e-12, "{scheme} {boundary}: {x} vs {y}");
            }
        }
    }
}

/// The wide schemes take the short lanes they once refused ("16 points allow at most 0"):
/// 16 points at one level with interpolating ends, cubic-wide's 31 points at three and 16
/// periodic, each analysed and synthesized back.
#[test]
fn wide_schemes_analyze_short_point_lists() {
    for (scheme, boundary, n, levels) in [
        ("linear-wide", "interpolating", 16, "1"),
        ("chaikin-wide", "interpolating", 16, "1"),
        ("cubic-wide", "interpolating", 16, "1"),
        ("cubic-wide", "interpolating", 31, "3"),
        ("cubic-wide", "periodic", 16, "1"),
    ] {
        let pts: String = (0..n)
            .map(|i| format!("{},{}\n", (i as f64 * 0.4).sin(), i as f64 * 0.25))
            .collect();
        let args = ["--scheme", scheme, "--boundary", boundary];
        let a = mra(
            &[&["analyze"], &args[..], &["--levels", levels, "-"]].concat(),
            &pts,
        );
        assert!(
            a.status.success(),
            "{scheme} {boundary} {n}: {}",
            text(&a.stderr)
        );
        let s = mra(
            &[&["synthesize"], &args[..], &["-"]].concat(),
            &text(&a.stdout),
        );
        assert!(
            s.status.success(),
            "{scheme} {boundary} {n}: {}",
            text(&s.stderr)
        );
        let want = mra::points::parse(&pts).unwrap();
        let got = mra::points::parse(&text(&s.stdout)).unwrap();
        assert_eq!(got.data.len(), want.data.len());
        for (x, y) in want.data.iter().zip(&got.data) {
            assert!((x - y).abs() < 1e-12, "{scheme} {boundary} {n}: {x} vs {y}");
        }
    }
}

#[test]
fn synthesize_with_the_wrong_scheme_is_an_error() {
    let pts: String = (0..20).map(|i| format!("{i}\n")).collect();
    let a = mra(
        &[
            "analyze",
            "--scheme",
            "cubic",
            "--boundary",
            "interpolating",
            "--levels",
            "1",
            "-",
        ],
        &pts,
    );
    assert!(a.status.success());
    let s = mra(&["synthesize", "--scheme", "haar", "-"], &text(&a.stdout));
    assert_eq!(s.status.code(), Some(2));
    assert_eq!(text(&s.stderr).lines().count(), 1);
}

#[test]
fn subdivide_writes_atomically_to_a_file() {
    let d = tmpdir("subdivide");
    let out = d.join("out.csv");
    let o = mra(
        &[
            "subdivide",
            "--scheme",
            "chaikin",
            "--closed",
            "--steps",
            "2",
            "-",
            "-o",
            out.to_str().unwrap(),
        ],
        "0,0\n1,0\n1,1\n0,1\n",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let got = mra::points::parse(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(got.len(), 16);
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
}

#[test]
fn bad_input_gives_one_line_and_exit_2() {
    let cases: &[(&[&str], &str)] = &[
        (&["analyze", "-"], "1,2\n3,abc\n"),
        (&["analyze", "-"], "1,2\n3\n"),
        (&["analyze", "-"], "# only a comment\n"),
        (&["analyze", "--levels", "20", "-"], "1\n2\n3\n"),
        (&["analyze", "--scheme", "wavelet9", "-"], "1\n"),
        (&["analyze", "--frobnicate", "-"], "1\n"),
        (&["analyze", "/no/such/file.csv"], ""),
        (&["subdivide", "--scheme", "cubic", "-"], "0\n1\n"),
        (&["synthesize", "-"], "X,1\n"),
        (&["synthesize", "-"], "C,1\nD2,1\n"),
    ];
    for (args, input) in cases {
        let o = mra(args, input);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("mra: "), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn demo_runs_and_reports_exact_reconstruction() {
    let d = tmpdir("demo");
    let o = mra(&["demo", "--json", "--out", d.to_str().unwrap()], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    assert!(rows.len() >= 4);
    for r in rows {
        if let Some(p) = r["output"].as_str() {
            let len = std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
            assert!(len > 0, "{p} missing or empty");
        }
    }
    // the number after `key` in a row's result ("… max error 1.2e-7, …")
    let after = |result: &str, key: &str| -> f64 {
        let at = result
            .find(key)
            .unwrap_or_else(|| panic!("no {key:?} in {result:?}"));
        let tail = &result[at + key.len()..];
        let end = tail.find([',', ' ', ';']).unwrap_or(tail.len());
        tail[..end]
            .parse()
            .unwrap_or_else(|e| panic!("{key:?} in {result:?}: {e}"))
    };
    let rows_of = |job: &str| -> Vec<(String, String)> {
        rows.iter()
            .filter(|r| r["job"] == job)
            .map(|r| {
                (
                    r["data"].as_str().unwrap().to_string(),
                    r["result"].as_str().unwrap().to_string(),
                )
            })
            .collect()
    };
    // pyramids round trip to rounding error: f64 curve, f32 images (0…255) and a volume
    // (−1000…1000)
    let curve = rows_of("analyze+synthesize curve");
    assert_eq!(curve.len(), 1);
    let e = after(&curve[0].1, "max reconstruction error ");
    assert!(e <= 1e-12, "{curve:?}");
    let images = rows_of("image pyramid forward+inverse");
    assert_eq!(
        images.len(),
        mra::scheme::Scheme::ALL.len(),
        "one row per scheme"
    );
    for (data, result) in &images {
        let e = after(result, "max error ");
        assert!(e <= 1e-3, "{data}: {result}");
    }
    let volume = rows_of("volume pyramid forward+inverse");
    assert_eq!(volume.len(), 1);
    let e = after(&volume[0].1, "max error ");
    assert!(e <= 1e-2, "{volume:?}");
    let sub = rows_of("subdivide");
    assert!(sub[0].1.ends_with("corners kept: true"), "{sub:?}");
    // the codec rows meet their targets: lossless is exact, the bound holds, the PSNR is met
    let codec = rows_of("encode+decode");
    assert_eq!(codec.len(), 3, "{codec:?}");
    for (data, result) in &codec {
        let e = after(result, "max error ");
        if data.contains("--lossless") {
            assert_eq!(e, 0.0, "{result}");
            assert!(result.contains("PSNR inf"), "{result}");
        } else if data.contains("--max-error 4") {
            assert!(e <= 4.0 && e > 0.0, "{result}");
        } else {
            assert!(data.contains("--psnr 40"), "{data}");
            assert!(after(result, "PSNR ") >= 40.0, "{result}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn encode_and_decode_report_json_and_decode_keeps_frames() {
    let d = tmpdir("frames");
    let (vol, mra_file, part) = (d.join("v.nrrd"), d.join("v.mra"), d.join("part.nrrd"));
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let o = mra(&["generate", "phantom", "-o", &s(&vol), "--size", "16"], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = mra(&["encode", &s(&vol), "-o", &s(&mra_file), "--json"], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let e: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(e["dims"], serde_json::json!([16, 16, 16]));
    assert_eq!(
        e["bytes"].as_u64().unwrap(),
        std::fs::metadata(&mra_file).unwrap().len()
    );
    // slices 4..9 of the volume, as the whole decoded volume has them
    let o = mra(
        &[
            "decode",
            &s(&mra_file),
            "-o",
            &s(&part),
            "--frames",
            "4..9",
            "--json",
        ],
        "",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // x, y, z: the 5 kept frames are the slowest axis, printed last
    assert_eq!(j["dims"], serde_json::json!([16, 16, 5]));
    assert_eq!(j["complete"], serde_json::json!(true));
    let whole = mra::io::read(&vol).unwrap();
    let cut = mra::io::read(&part).unwrap();
    let full = mra::codec::decode_file(&mra_file, &Default::default()).unwrap();
    assert_eq!(cut.dims, vec![5, 16, 16]);
    let per = 16 * 16;
    assert_eq!(
        cut.samples.to_f64(),
        full.raster.samples.to_f64()[4 * per..9 * per].to_vec()
    );
    assert_eq!(whole.dims, vec![16, 16, 16]);
    // a bad range: one line, exit 2, no output
    let bad = d.join("bad.nrrd");
    for r in ["9..4", "4..99", "x..3"] {
        let o = mra(
            &["decode", &s(&mra_file), "-o", &s(&bad), "--frames", r],
            "",
        );
        assert_eq!(o.status.code(), Some(2), "{r}");
        assert_eq!(text(&o.stderr).lines().count(), 1, "{r}");
        assert!(!bad.exists(), "{r}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `mra info --json`: the colour transform and the error bound are `null` where the file
/// has none, named or given where it has one.
#[test]
fn info_json_names_the_colour_transform_and_bound_or_gives_null() {
    let d = tmpdir("info");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (gray, rgb) = (d.join("g.png"), d.join("c.png"));
    for (out, ch) in [(&gray, "1"), (&rgb, "3")] {
        let args = [
            "generate",
            "noise",
            "-o",
            &s(out),
            "--size",
            "32",
            "--channels",
            ch,
        ];
        let o = mra(&args, "");
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    let info = |input: &std::path::Path, opts: &[&str]| -> serde_json::Value {
        let f = d.join("x.mra");
        let mut args = vec!["encode".to_string(), s(input), "-o".into(), s(&f)];
        args.extend(opts.iter().map(|a| a.to_string()));
        let args: Vec<&str> = args.iter().map(|a| a.as_str()).collect();
        let o = mra(&args, "");
        assert!(o.status.success(), "{}", text(&o.stderr));
        let o = mra(&["info", &s(&f), "--json"], "");
        assert!(o.status.success(), "{}", text(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let j = info(&gray, &["--quality", "50"]);
    assert_eq!(j["colour"], serde_json::Value::Null);
    assert_eq!(j["max_error"], serde_json::Value::Null);
    let j = info(&gray, &["--max-error", "2"]);
    assert_eq!(j["max_error"], serde_json::json!(2.0));
    let j = info(&rgb, &["--quality", "50"]);
    assert_eq!(j["colour"], serde_json::json!("YCoCg"));
    let j = info(&rgb, &["--lossless"]);
    assert_eq!(j["colour"], serde_json::json!("YCoCg-R"));
    assert_eq!(j["max_error"], serde_json::Value::Null);
    let _ = std::fs::remove_dir_all(&d);
}

/// A 4×3×2 (x, y, z) u8 NRRD with spacing 0.5, 0.75, 2 and origin (1, 2, 3).
fn small_nrrd(path: &std::path::Path) {
    let mut b = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\nspace dimension: 3\n\
space directions: (0.5,0,0) (0,0.75,0) (0,0,2)\nspace origin: (1,2,3)\n\
encoding: raw\n\n"
        .to_vec();
    b.extend((0..24u8).map(|i| i * 10));
    std::fs::write(path, b).unwrap();
}

/// `mra info` reads any file (and `.mra` files), `info-file` is the same command, and
/// every vector is printed x, y, z (fastest first) in text and JSON.
#[test]
fn info_reads_any_file_and_prints_every_vector_x_y_z() {
    let d = tmpdir("info-xyz");
    let f = d.join("v.nrrd");
    small_nrrd(&f);
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let o = mra(&["info", &s(&f), "--json"], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["dims"], serde_json::json!([4, 3, 2]));
    assert_eq!(j["spacing"], serde_json::json!([0.5, 0.75, 2.0]));
    assert_eq!(j["origin"], serde_json::json!([1.0, 2.0, 3.0]));
    assert_eq!(j["axis_order"], "x, y, z (fastest first)");
    let old = mra(&["info-file", &s(&f), "--json"], "");
    assert_eq!(old.stdout, o.stdout);
    let t = text(&mra(&["info", &s(&f)], "").stdout);
    assert!(t.contains("dims (x, y, z) [4, 3, 2]"), "{t}");
    assert!(t.contains("spacing (x, y, z) [0.5, 0.75, 2.0]"), "{t}");
    assert!(t.contains("origin (x, y, z) [1.0, 2.0, 3.0]"), "{t}");
    // an .mra file: its header
    let png = d.join("z.png");
    let m = d.join("z.mra");
    assert!(mra(
        &["generate", "zone-plate", "-o", &s(&png), "--size", "32"],
        ""
    )
    .status
    .success());
    assert!(mra(&["encode", &s(&png), "-o", &s(&m)], "")
        .status
        .success());
    let o = mra(&["info", &s(&m), "--json"], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["levels"].as_u64().is_some_and(|l| l >= 1), "{j}");
    assert!(j["mode"].is_string(), "{j}");
    // help lists `info` and hides the old name
    let help = text(&mra(&["--help"], "").stdout);
    assert!(
        help.contains("info") && !help.contains("info-file"),
        "{help}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `upscale` and `downscale` read headerless input with --dims/--dtype; `upscale --json`
/// (old name `--report`) prints the compute time and the output's dims x, y, z.
#[test]
fn upscale_reads_raw_input_and_reports_json_dims_x_y_z() {
    let d = tmpdir("upscale-raw");
    let raw = d.join("v.raw");
    let v: Vec<u8> = (0..8 * 6 * 4u16)
        .flat_map(|i| ((i * 37) % 1000).to_le_bytes())
        .collect();
    std::fs::write(&raw, v).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let out = d.join("v2.nrrd");
    for flag in ["--json", "--report"] {
        let o = mra(
            &[
                "upscale",
                &s(&raw),
                "--dims",
                "8x6x4",
                "--dtype",
                "u16",
                "-o",
                &s(&out),
                "--factor",
                "2",
                flag,
                "--quiet",
            ],
            "",
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["dims"], serde_json::json!([16, 12, 8]));
        assert!(j["compute_seconds"].as_f64().unwrap() >= 0.0);
        let r = mra::io::read(&out).unwrap();
        assert_eq!(r.dims, vec![8, 12, 16]);
        assert_eq!(r.sample_type(), mra::io::SampleType::U16);
    }
    let half = d.join("h.nrrd");
    let o = mra(
        &[
            "downscale",
            &s(&raw),
            "--dims",
            "8x6x4",
            "--dtype",
            "u16",
            "-o",
            &s(&half),
        ],
        "",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(mra::io::read(&half).unwrap().dims, vec![2, 3, 4]);
    let _ = std::fs::remove_dir_all(&d);
}

/// `decode --level` beyond the file's levels is an error naming them (no clamp, no
/// output); the deepest level the file holds decodes.
#[test]
fn decode_of_a_level_the_file_lacks_names_the_levels_it_holds() {
    let d = tmpdir("decode-level");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (png, m, out) = (d.join("z.png"), d.join("z.mra"), d.join("o.png"));
    assert!(mra(
        &["generate", "zone-plate", "-o", &s(&png), "--size", "64"],
        ""
    )
    .status
    .success());
    assert!(
        mra(&["encode", &s(&png), "-o", &s(&m), "--levels", "3"], "")
            .status
            .success()
    );
    let o = mra(&["decode", &s(&m), "-o", &s(&out), "--level", "9"], "");
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("9 of a file with levels 0 to 3"), "{err}");
    assert!(!out.exists());
    let o = mra(&["decode", &s(&m), "-o", &s(&out), "--level", "3"], "");
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(mra::io::read(&out).unwrap().dims, vec![8, 8]);
    let _ = std::fs::remove_dir_all(&d);
}

/// `encode --psnr P --data-range R` reaches P measured with R (as `compare
/// --data-range R` measures it): with R below the default range, a larger file than
/// the default gives, and a higher PSNR over R.
#[test]
fn encode_psnr_with_a_data_range_meets_the_target_over_that_range() {
    let d = tmpdir("psnr-range");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let src = d.join("p.nrrd");
    assert!(mra(
        &[
            "generate",
            "phantom",
            "-o",
            &s(&src),
            "--size",
            "32",
            "--dtype",
            "i16"
        ],
        ""
    )
    .status
    .success());
    // a range well below the i16 phantom's (0 … 32767, which is also scikit-image's
    // default for it): the same dB target is harder over it
    let r = mra::io::read(&src).unwrap();
    let (lo, hi) = r.samples.min_max().unwrap();
    assert!(hi - lo > 10000.0);
    let range = "3000".to_string();
    let size = |args: &[&str], name: &str| -> (u64, f64) {
        let (m, back) = (
            d.join(format!("{name}.mra")),
            d.join(format!("{name}.nrrd")),
        );
        let mut a = vec!["encode".to_string(), s(&src), "-o".into(), s(&m)];
        a.extend(args.iter().map(|x| x.to_string()));
        let a: Vec<&str> = a.iter().map(|x| x.as_str()).collect();
        let o = mra(&a, "");
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(mra(&["decode", &s(&m), "-o", &s(&back)], "")
            .status
            .success());
        let o = mra(
            &[
                "compare",
                &s(&src),
                &s(&back),
                "--data-range",
                &range,
                "--json",
            ],
            "",
        );
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (
            std::fs::metadata(&m).unwrap().len(),
            j["psnr"].as_f64().unwrap_or(f64::INFINITY),
        )
    };
    let (with_range, psnr) = size(&["--psnr", "40", "--data-range", &range], "r");
    assert!(psnr >= 39.9, "PSNR over the data range {psnr}");
    let (by_dtype, psnr_dtype) = size(&["--psnr", "40"], "t");
    assert!(with_range > by_dtype, "{with_range} vs {by_dtype}");
    assert!(psnr_dtype < psnr, "{psnr_dtype} vs {psnr}");
    let o = mra(
        &[
            "encode",
            &s(&src),
            "-o",
            &s(&d.join("x.mra")),
            "--data-range",
            "100",
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&d);
}

/// An empty or garbage OBJ, PLY or OFF is an error (exit 2, one line naming the file),
/// not an empty mesh.
#[test]
fn empty_or_garbage_meshes_are_errors() {
    let d = tmpdir("empty-mesh");
    let cases: [(&str, &[u8]); 6] = [
        ("empty.obj", b""),
        ("garbage.obj", b"hello world\nthis is not a mesh\n\x00\xff\xfe"),
        ("comments.obj", b"# only a comment\n\n"),
        (
            "zero.ply",
            b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        ),
        ("garbage.ply", b"\x89PNG not a ply"),
        ("zero.off", b"OFF\n0 0 0\n"),
    ];
    for (name, bytes) in cases {
        let p = d.join(name);
        std::fs::write(&p, bytes).unwrap();
        let o = mra(&["mesh", "info", p.to_str().unwrap()], "");
        assert_eq!(o.status.code(), Some(2), "{name}: {}", text(&o.stdout));
        let err = text(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name), "{err}");
        assert!(mra::mesh::io::read(&p).is_err(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `.jpg` outputs: 8-bit gray and RGB at the asked quality (higher quality, larger file,
/// closer to the source); other sample types are refused with no file left.
#[test]
fn jpeg_output_follows_the_quality_and_refuses_16_bit() {
    let d = tmpdir("jpeg-out");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let src = d.join("g.png");
    assert!(mra(
        &["generate", "gradient", "-o", &s(&src), "--size", "64x48"],
        ""
    )
    .status
    .success());
    let mut sizes = Vec::new();
    let mut psnrs = Vec::new();
    for q in ["95", "20"] {
        let out = d.join(format!("q{q}.jpg"));
        let o = mra(&["convert", &s(&src), "-o", &s(&out), "--quality", q], "");
        assert!(o.status.success(), "{}", text(&o.stderr));
        let r = mra::io::read(&out).unwrap();
        assert_eq!((r.dims.clone(), r.channels), (vec![48, 64], 3));
        sizes.push(std::fs::metadata(&out).unwrap().len());
        let c = mra(&["compare", &s(&src), &s(&out), "--json"], "");
        let j: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
        psnrs.push(j["psnr"].as_f64().unwrap_or(f64::INFINITY));
    }
    assert!(sizes[0] > sizes[1], "{sizes:?}");
    assert!(psnrs[0] > psnrs[1] && psnrs[0] > 35.0, "{psnrs:?}");
    let wide = d.join("w.png");
    assert!(mra(
        &[
            "generate",
            "noise",
            "-o",
            &s(&wide),
            "--size",
            "16",
            "--dtype",
            "u16"
        ],
        ""
    )
    .status
    .success());
    let bad = d.join("w.jpg");
    let o = mra(&["convert", &s(&wide), "-o", &s(&bad)], "");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("8-bit"), "{}", text(&o.stderr));
    assert!(!bad.exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `terrain synth` of an example in metres (ASC) under a base in degrees (HGT) is
/// refused, and goes through with `--example-cell` (or `--any-units`).
#[test]
fn terrain_synth_takes_an_explicit_example_cell_past_a_unit_mismatch() {
    let d = tmpdir("synth-units");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (base, ex) = (d.join("base.hgt"), d.join("ex.asc"));
    for (p, size, ty) in [(&base, "65", "i16"), (&ex, "129", "f32")] {
        let o = mra(
            &[
                "generate",
                "terrain",
                "-o",
                &s(p),
                "--size",
                size,
                "--dtype",
                ty,
            ],
            "",
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    let out = d.join("out.tif");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "terrain".to_string(),
            "synth".into(),
            "--base".into(),
            s(&base),
            "--example".into(),
            s(&ex),
            "--levels".into(),
            "1".into(),
            "-o".into(),
            s(&out),
        ];
        a.extend(extra.iter().map(|x| x.to_string()));
        let a: Vec<&str> = a.iter().map(|x| x.as_str()).collect();
        mra(&a, "")
    };
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("unit"), "{}", text(&o.stderr));
    assert!(!out.exists());
    let o = run(&["--example-cell", "0.0078125"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let r = mra::io::read(&out).unwrap();
    assert_eq!(r.dims, vec![130, 130]);
    let _ = std::fs::remove_file(&out);
    let o = run(&["--any-units"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.exists());
    let o = run(&["--example-cell", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&d);
}

fn mra_bytes(args: &[&str], stdin: &[u8]) -> Output {
    common::mra_with_stdin(None, args, stdin)
}

/// `-` reads a raster from standard input (format by signature) and writes one to
/// standard output in `--format`; the samples pass unchanged.
#[test]
fn rasters_pass_through_standard_input_and_output() {
    let d = tmpdir("stdio");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let png = d.join("z.png");
    assert!(mra(
        &["generate", "zone-plate", "-o", &s(&png), "--size", "40x24"],
        ""
    )
    .status
    .success());
    let bytes = std::fs::read(&png).unwrap();
    let o = mra_bytes(&["convert", "-", "-o", "-", "--format", "tif"], &bytes);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(o.stdout.starts_with(b"II*\0") || o.stdout.starts_with(b"MM\0*"));
    let tif = d.join("z.tif");
    std::fs::write(&tif, &o.stdout).unwrap();
    let (a, b) = (mra::io::read(&png).unwrap(), mra::io::read(&tif).unwrap());
    assert_eq!((a.dims.clone(), a.samples.clone()), (b.dims, b.samples));
    // upscale from a pipe to a pipe
    let o = mra_bytes(
        &[
            "upscale", "-", "-o", "-", "--format", "png", "--factor", "2", "--quiet",
        ],
        &bytes,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let up = d.join("up.png");
    std::fs::write(&up, &o.stdout).unwrap();
    assert_eq!(mra::io::read(&up).unwrap().dims, vec![48, 80]);
    // info of standard input
    let o = mra_bytes(&["info", "-", "--json"], &bytes);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["dims"], serde_json::json!([40, 24]));
    // -o - without --format, and an unknown format: one line, exit 2, nothing written
    for extra in [&[][..], &["--format", "xyz"][..]] {
        let mut args = vec!["convert", "-", "-o", "-"];
        args.extend_from_slice(extra);
        let o = mra_bytes(&args, &bytes);
        assert_eq!(o.status.code(), Some(2));
        assert!(o.stdout.is_empty());
        assert_eq!(text(&o.stderr).trim_end().lines().count(), 1);
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn decode_reads_an_mra_file_from_standard_input_and_reports_on_stderr_when_piping() {
    let d = tmpdir("decode-stdin");
    let (png, mra_file) = (d.join("z.png"), d.join("z.mra"));
    let (ps, ms) = (png.to_str().unwrap(), mra_file.to_str().unwrap());
    assert!(
        mra(&["generate", "zone-plate", "-o", ps, "--size", "48x32"], "")
            .status
            .success()
    );
    assert!(mra(&["encode", ps, "-o", ms, "--quality", "60"], "")
        .status
        .success());
    let from_file = d.join("file.png");
    assert!(mra(&["decode", ms, "-o", from_file.to_str().unwrap()], "")
        .status
        .success());
    let bytes = std::fs::read(&mra_file).unwrap();
    // from a pipe to a file: the same image as from the file
    let from_pipe = d.join("pipe.png");
    let o = mra_bytes(&["decode", "-", "-o", from_pipe.to_str().unwrap()], &bytes);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (a, b) = (
        mra::io::read(&from_file).unwrap(),
        mra::io::read(&from_pipe).unwrap(),
    );
    assert_eq!((a.dims.clone(), a.samples.clone()), (b.dims, b.samples));
    // from a pipe to a pipe with --json: standard output is the PNG alone, the report on
    // standard error
    let o = mra_bytes(
        &[
            "decode", "-", "-o", "-", "--format", "png", "--json", "--level", "1",
        ],
        &bytes,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(o.stdout.starts_with(b"\x89PNG\r\n\x1a\n"));
    let half = d.join("half.png");
    std::fs::write(&half, &o.stdout).unwrap();
    assert_eq!(mra::io::read(&half).unwrap().dims, vec![16, 24]);
    let j: serde_json::Value = serde_json::from_str(text(&o.stderr).trim()).unwrap();
    assert_eq!(j["dims"], serde_json::json!([24, 16]));
    assert_eq!(j["complete"], serde_json::json!(true));
    // a level the piped file lacks, and bytes that are no .mra file: one line, exit 2
    let o = mra_bytes(&["decode", "-", "-o", "x.png", "--level", "9"], &bytes);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("levels 0 to"),
        "{}",
        text(&o.stderr)
    );
    let o = mra_bytes(
        &["decode", "-", "-o", "-", "--format", "png"],
        b"not an mra file",
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
    assert_eq!(text(&o.stderr).trim_end().lines().count(), 1);
    assert!(text(&o.stderr).contains("standard input"));
    // info of an .mra file on standard input reads its header
    let o = mra_bytes(&["info", "-", "--json"], &bytes);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["file_bytes"], serde_json::json!(bytes.len()));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn upscale_to_standard_output_with_json_keeps_the_report_out_of_the_raster() {
    let d = tmpdir("upscale-stdout-json");
    let png = d.join("z.png");
    assert!(mra(
        &[
            "generate",
            "zone-plate",
            "-o",
            png.to_str().unwrap(),
            "--size",
            "40x24"
        ],
        ""
    )
    .status
    .success());
    let o = mra(
        &[
            "upscale",
            png.to_str().unwrap(),
            "-o",
            "-",
            "--format",
            "png",
            "--factor",
            "2",
            "--json",
            "--quiet",
        ],
        "",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    // standard output is exactly one PNG: it decodes, and nothing follows its IEND chunk
    assert!(o.stdout.starts_with(b"\x89PNG\r\n\x1a\n"));
    let iend = o.stdout.windows(4).rposition(|w| w == b"IEND").unwrap();
    assert_eq!(o.stdout.len(), iend + 8, "bytes after the PNG's IEND chunk");
    let up = d.join("up.png");
    std::fs::write(&up, &o.stdout).unwrap();
    assert_eq!(mra::io::read(&up).unwrap().dims, vec![48, 80]);
    let j: serde_json::Value = serde_json::from_str(text(&o.stderr).trim()).unwrap();
    assert_eq!(j["dims"], serde_json::json!([80, 48]));
    // to a file, the report stays on standard output
    let out = d.join("up2.png");
    let o = mra(
        &[
            "upscale",
            png.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--factor",
            "2",
            "--json",
            "--quiet",
        ],
        "",
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["dims"], serde_json::json!([80, 48]));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn info_of_a_jpeg_reads_its_header_and_not_its_pixels() {
    let d = tmpdir("info-jpeg");
    let (png, jpg) = (d.join("z.png"), d.join("z.jpg"));
    assert!(mra(
        &[
            "generate",
            "gradient",
            "-o",
            png.to_str().unwrap(),
            "--size",
            "40x24"
        ],
        ""
    )
    .status
    .success());
    assert!(mra(
        &[
            "convert",
            png.to_str().unwrap(),
            "-o",
            jpg.to_str().unwrap()
        ],
        ""
    )
    .status
    .success());
    let good = std::fs::read(&jpg).unwrap();
    // the entropy-coded data replaced by zeros: the pixels are garbage, the header alone
    // answers (no range, which only the pixels could give)
    let sos = good.windows(2).position(|w| w == [0xFF, 0xDA]).unwrap();
    let len = u16::from_be_bytes([good[sos + 2], good[sos + 3]]) as usize;
    let mut blank = good.clone();
    let n = blank.len();
    blank[sos + 2 + len..n - 2].fill(0);
    let blank_path = d.join("blank.jpg");
    std::fs::write(&blank_path, &blank).unwrap();
    for p in [&jpg, &blank_path] {
        let o = mra(&["info", p.to_str().unwrap(), "--json"], "");
        assert!(o.status.success(), "{}", text(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["format"], "JPEG");
        assert_eq!(j["dims"], serde_json::json!([40, 24]));
        assert_eq!(j["channels"], serde_json::json!(3));
        assert_eq!(j["dtype"], "u8");
        assert_eq!(j["header_only"], serde_json::json!(true));
        assert!(j["min"].is_null() && j["max"].is_null(), "{j}");
        let t = text(&mra(&["info", p.to_str().unwrap()], "").stdout);
        assert!(
            t.contains("40x24 RGB u8") && t.contains("header only"),
            "{t}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn generate_denoise_mesh_and_curve_refuse_an_output_extension_they_do_not_write() {
    let d = tmpdir("out-ext");
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    std::fs::write(
        d.join("pts.csv"),
        "0,0\n1,1\n2,0\n3,1\n4,0\n5,1\n6,0\n7,1\n",
    )
    .unwrap();
    std::fs::write(
        d.join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
    )
    .unwrap();
    assert!(mra(
        &["generate", "zone-plate", "-o", &p("z.png"), "--size", "32"],
        ""
    )
    .status
    .success());
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (
            vec!["generate".into(), "zone-plate".into()],
            "z.obj",
            "invalid output extension for generate",
        ),
        (
            vec!["denoise".into(), p("pts.csv")],
            "pts.png",
            "invalid output extension for denoise",
        ),
        (
            vec!["denoise".into(), p("z.png")],
            "z.csv",
            "invalid output extension for denoise",
        ),
        (
            vec!["mesh".into(), "smooth".into(), p("tri.obj")],
            "tri.png",
            "invalid output extension for mesh smooth",
        ),
        (
            vec!["mesh".into(), "render".into(), p("tri.obj")],
            "tri2.obj",
            "invalid output extension for mesh render",
        ),
        (
            vec![
                "curve".into(),
                "plot".into(),
                "--kind".into(),
                "bezier".into(),
                p("pts.csv"),
            ],
            "plot.csv",
            "invalid output extension for curve plot",
        ),
        (
            vec![
                "curve".into(),
                "eval".into(),
                "--kind".into(),
                "bezier".into(),
                p("pts.csv"),
            ],
            "eval.png",
            "invalid output extension for curve eval",
        ),
    ];
    for (args, out, want) in &cases {
        let mut a: Vec<&str> = args.iter().map(String::as_str).collect();
        let o_path = p(out);
        a.extend_from_slice(&["-o", &o_path]);
        let o = mra(&a, "");
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {err}");
        assert!(err.contains(want), "{a:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!d.join(out).exists(), "{a:?} wrote {out}");
    }
    // the same commands with a matching extension run
    for (args, out) in [
        (vec!["denoise", &p("pts.csv") as &str], "pts_d.csv"),
        (vec!["mesh", "smooth", &p("tri.obj")], "tri_s.obj"),
        (
            vec!["mesh", "render", &p("tri.obj"), "--size", "32x24"],
            "tri.png",
        ),
    ] {
        let mut a = args.clone();
        let o_path = p(out);
        a.extend_from_slice(&["-o", &o_path]);
        let o = mra(&a, "");
        assert!(o.status.success(), "{a:?}: {}", text(&o.stderr));
        assert!(d.join(out).exists(), "{a:?}");
    }
    // an output that is the input is refused before anything runs
    let o = mra(&["mesh", "smooth", &p("tri.obj"), "-o", &p("tri.obj")], "");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("the output is the input"));
    let o = mra(&["denoise", &p("z.png"), "-o", &p("z.png")], "");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("the output is the input"));
    let _ = std::fs::remove_dir_all(&d);
}
