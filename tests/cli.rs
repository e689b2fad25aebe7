//! The `mra` binary on point lists: outputs, round trips, and one-line errors with exit 2.

use std::io::Write;
use std::process::{Command, Output, Stdio};

fn mra(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the child may exit (on bad arguments) before reading: a broken pipe is fine here
    let _ = child.stdin.take().unwrap().write_all(stdin.as_bytes());
    child.wait_with_output().unwrap()
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
    assert_eq!(images.len(), 3, "one row per scheme");
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
    assert_eq!(j["dims"], serde_json::json!([5, 16, 16]));
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
