//! End to end, every CPU level gives the same bytes: `mra encode`, `decode`, `upscale` and
//! `analyze` run as processes under `MRA_CPU=scalar`, `MRA_CPU=avx2` and the default (the
//! widest build the CPU runs), on generated data, and their outputs are compared byte for
//! byte. Skipped (with a printed line) where the CPU has no AVX2 with FMA; a failure then
//! with `MRA_REQUIRE_AVX2=1`.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::common;

/// The CPU levels compared: a value of `MRA_CPU`, or `None` for the variable unset.
const LEVELS: [Option<&str>; 3] = [Some("scalar"), Some("avx2"), None];

fn run(cpu: Option<&str>, args: &[&str]) -> Vec<u8> {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mra"));
    c.args(args);
    match cpu {
        Some(v) => c.env("MRA_CPU", v),
        None => c.env_remove("MRA_CPU"),
    };
    let o = c.output().unwrap();
    assert!(
        o.status.success(),
        "MRA_CPU={} mra {args:?}: {}",
        cpu.unwrap_or("(unset)"),
        String::from_utf8_lossy(&o.stderr)
    );
    o.stdout
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// One job: the arguments (with `{in}` for the inputs' folder and `{out}` for the output
/// file), and the output's file name (`None`: the job prints to standard output).
struct Job {
    args: &'static [&'static str],
    out: Option<&'static str>,
}

const JOBS: &[Job] = &[
    Job {
        args: &["encode", "{in}/zp.png", "-o", "{out}"],
        out: Some("zp.mra"),
    },
    Job {
        args: &["encode", "{in}/f.tif", "-o", "{out}", "--quality", "70"],
        out: Some("f.mra"),
    },
    Job {
        args: &[
            "encode",
            "{in}/f.tif",
            "-o",
            "{out}",
            "--scheme",
            "cubic",
            "--psnr",
            "45",
        ],
        out: Some("f_cubic.mra"),
    },
    Job {
        args: &[
            "encode",
            "{in}/v.nrrd",
            "-o",
            "{out}",
            "--scheme",
            "chaikin",
        ],
        out: Some("v.mra"),
    },
    Job {
        args: &[
            "encode",
            "{in}/v.nrrd",
            "-o",
            "{out}",
            "--max-error",
            "0.01",
        ],
        out: Some("v_bound.mra"),
    },
    Job {
        args: &["decode", "{in}/zp.mra", "-o", "{out}"],
        out: Some("zp.png"),
    },
    Job {
        args: &["decode", "{in}/f.mra", "-o", "{out}"],
        out: Some("f.tif"),
    },
    Job {
        args: &["decode", "{in}/f.mra", "-o", "{out}", "--level", "1"],
        out: Some("f_half.tif"),
    },
    Job {
        args: &["decode", "{in}/v.mra", "-o", "{out}"],
        out: Some("v.nrrd"),
    },
    Job {
        args: &["upscale", "{in}/zp.png", "-o", "{out}", "--factor", "2"],
        out: Some("zp2.png"),
    },
    Job {
        args: &[
            "upscale",
            "{in}/f.tif",
            "-o",
            "{out}",
            "--factor",
            "2",
            "--scheme",
            "cubic",
            "--mode",
            "interpolate",
        ],
        out: Some("f2.tif"),
    },
    Job {
        args: &[
            "upscale",
            "{in}/f.tif",
            "-o",
            "{out}",
            "--factor",
            "3",
            "--mode",
            "control",
        ],
        out: Some("f3.tif"),
    },
    Job {
        args: &["upscale", "{in}/v.nrrd", "-o", "{out}", "--factor", "2"],
        out: Some("v2.nrrd"),
    },
    Job {
        args: &["analyze", "{in}/f.tif", "-o", "{out}", "--scheme", "cubic"],
        out: Some("f_pyr.tif"),
    },
    Job {
        args: &[
            "analyze",
            "{in}/f.tif",
            "-o",
            "{out}",
            "--scheme",
            "chaikin",
            "--boundary",
            "periodic",
            "--order",
            "standard",
        ],
        out: Some("f_pyr_std.tif"),
    },
    Job {
        args: &["analyze", "{in}/v.nrrd", "-o", "{out}", "--scheme", "haar"],
        out: Some("v_pyr.nrrd"),
    },
    Job {
        args: &["analyze", "{in}/curve.csv", "--scheme", "cubic"],
        out: None,
    },
];

/// The inputs: a zone plate (u8), an f32 terrain of odd size, an f32 phantom volume, a
/// point list, and the `.mra` files the decode jobs read (written once, at the default level).
fn inputs(dir: &Path) {
    let g = |kind: &str, size: &str, dtype: &str, out: &str| {
        run(
            None,
            &[
                "generate",
                kind,
                "--size",
                size,
                "--dtype",
                dtype,
                "-o",
                s(&dir.join(out)),
            ],
        );
    };
    g("zone-plate", "203x150", "u8", "zp.png");
    g("terrain", "131x97", "f32", "f.tif");
    g("phantom", "37x29x23", "f32", "v.nrrd");
    let curve: String = (0..300)
        .map(|i| {
            let t = i as f64 * 0.05;
            format!("{},{}\n", t.cos() * (3.0 + t), (1.7 * t).sin())
        })
        .collect();
    std::fs::write(dir.join("curve.csv"), curve).unwrap();
    for (src, out, extra) in [
        ("zp.png", "zp.mra", &[][..]),
        ("f.tif", "f.mra", &["--scheme", "cubic"][..]),
        ("v.nrrd", "v.mra", &["--scheme", "chaikin"][..]),
    ] {
        let (i, o) = (dir.join(src), dir.join(out));
        let mut a = vec!["encode", s(&i), "-o", s(&o)];
        a.extend_from_slice(extra);
        run(None, &a);
    }
}

#[test]
fn encode_decode_upscale_and_analyze_give_the_same_bytes_at_every_cpu_level() {
    if !common::cpu_has_avx2() {
        return;
    }
    let input = common::scratch_dir("inputs");
    inputs(&input);
    // outputs[level][job]
    let mut outputs: Vec<Vec<Vec<u8>>> = Vec::new();
    for cpu in LEVELS {
        let dir: PathBuf = common::scratch_dir(cpu.unwrap_or("default"));
        let mut got = Vec::new();
        for job in JOBS {
            let out = job.out.map(|f| dir.join(f));
            let args: Vec<String> = job
                .args
                .iter()
                .map(|a| {
                    a.replace("{in}", s(&input))
                        .replace("{out}", out.as_deref().map_or("", s))
                })
                .collect();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let stdout = run(cpu, &args);
            let bytes = match &out {
                Some(p) => std::fs::read(p).unwrap_or_else(|e| panic!("{args:?}: {e}")),
                None => stdout,
            };
            assert!(
                !bytes.is_empty(),
                "MRA_CPU={} {args:?}: empty output",
                cpu.unwrap_or("(unset)")
            );
            got.push(bytes);
        }
        outputs.push(got);
    }
    for (k, job) in JOBS.iter().enumerate() {
        for (l, cpu) in LEVELS.iter().enumerate().skip(1) {
            let (a, b) = (&outputs[0][k], &outputs[l][k]);
            let first = a.iter().zip(b.iter()).position(|(x, y)| x != y);
            assert!(
                a == b,
                "{:?}: MRA_CPU=scalar and MRA_CPU={} differ ({} vs {} bytes, first difference at {first:?})",
                job.args,
                cpu.unwrap_or("(unset)"),
                a.len(),
                b.len()
            );
        }
    }
}
