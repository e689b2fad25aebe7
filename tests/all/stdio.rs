//! `-` as a file argument, for every command that reads or writes a file: standard input
//! and standard output, piped between commands, `-o -` giving the bytes `-o FILE` writes,
//! and `-o -` of a format the name cannot tell refused in one line naming `--format`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use super::common;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mra-stdio-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `mra args` in `dir` with `stdin` fed from a thread.
fn run(dir: &Path, args: &[&str], stdin: &[u8]) -> Output {
    common::mra_with_stdin(Some(dir), args, stdin)
}

fn ok(dir: &Path, args: &[&str], stdin: &[u8]) -> Vec<u8> {
    let o = run(dir, args, stdin);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o.stdout
}

fn corpus(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("corpus")
        .join(rel)
        .to_str()
        .unwrap()
        .to_string()
}

/// `args` with `-o NAME` (a file in `dir`) and with `-o -` (plus `--format EXT` when
/// given) write the same bytes.
fn same_as_file(dir: &Path, args: &[&str], name: &str, format: Option<&str>) {
    let mut to_file = args.to_vec();
    to_file.extend(["-o", name]);
    ok(dir, &to_file, b"");
    let file = std::fs::read(dir.join(name)).unwrap();
    let mut to_std = args.to_vec();
    to_std.extend(["-o", "-"]);
    if let Some(f) = format {
        to_std.extend(["--format", f]);
    }
    let piped = ok(dir, &to_std, b"");
    assert!(!file.is_empty(), "{args:?}");
    assert!(piped == file, "{args:?}: -o - differs from -o {name}");
}

/// An `n × n` grid of triangles as OBJ text.
fn grid_obj(n: usize) -> String {
    common::grid_obj(n, 5, 0.2)
}

/// `mra generate … -o - | mra encode - -o - | mra decode - -o - --format png`, as three
/// processes joined by pipes, gives the PNG the same commands give through files.
#[test]
fn generate_encode_decode_pipe_equals_the_same_through_files() {
    let d = dir("pipe");
    let gen = [
        "generate",
        "zone-plate",
        "--size",
        "48x32",
        "-o",
        "-",
        "--format",
        "png",
    ];
    let exe = env!("CARGO_BIN_EXE_mra");
    let mut a = Command::new(exe)
        .args(gen)
        .current_dir(&d)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut b = Command::new(exe)
        .args(["encode", "-", "-o", "-", "--psnr", "40"])
        .current_dir(&d)
        .stdin(Stdio::from(a.stdout.take().unwrap()))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let c = Command::new(exe)
        .args(["decode", "-", "-o", "-", "--format", "png"])
        .current_dir(&d)
        .stdin(Stdio::from(b.stdout.take().unwrap()))
        .output()
        .unwrap();
    assert!(a.wait().unwrap().success());
    assert!(b.wait().unwrap().success());
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    assert!(c.stdout.starts_with(b"\x89PNG"));
    ok(
        &d,
        &["generate", "zone-plate", "--size", "48x32", "-o", "z.png"],
        b"",
    );
    ok(&d, &["encode", "z.png", "-o", "z.mra", "--psnr", "40"], b"");
    ok(&d, &["decode", "z.mra", "-o", "d.png"], b"");
    assert!(c.stdout == std::fs::read(d.join("d.png")).unwrap());
    let _ = std::fs::remove_dir_all(&d);
}

/// `generate`, `terrain synth|render|highpass`, `transfer` and `denoise` (raster and point
/// list) write to standard output what they write to a file.
#[test]
fn raster_commands_write_to_standard_output_what_they_write_to_a_file() {
    let d = dir("rasters");
    same_as_file(
        &d,
        &["generate", "gradient", "--size", "20x12"],
        "g.png",
        Some("png"),
    );
    same_as_file(
        &d,
        &["generate", "phantom", "--size", "12"],
        "p.nrrd",
        Some("nrrd"),
    );
    ok(
        &d,
        &[
            "generate", "terrain", "--size", "17x9", "--seed", "3", "-o", "base.tif", "--dtype",
            "f32",
        ],
        b"",
    );
    ok(
        &d,
        &[
            "generate", "terrain", "--size", "40x24", "--seed", "9", "-o", "ex.tif", "--dtype",
            "f32",
        ],
        b"",
    );
    same_as_file(&d, &["terrain", "render", "ex.tif"], "r.png", None);
    same_as_file(
        &d,
        &["terrain", "highpass", "ex.tif", "--levels", "1"],
        "h.tif",
        Some("tif"),
    );
    same_as_file(
        &d,
        &[
            "terrain",
            "synth",
            "--base",
            "base.tif",
            "--example",
            "ex.tif",
            "--levels",
            "1",
            "--any-units",
            "--patch",
            "4",
            "--overlap",
            "1",
        ],
        "s.tif",
        Some("tif"),
    );
    same_as_file(
        &d,
        &[
            "transfer",
            "--from",
            "ex.tif",
            "--to",
            "ex.tif",
            "--levels",
            "1",
            "--patch",
            "4",
            "--overlap",
            "1",
        ],
        "t.tif",
        Some("tif"),
    );
    ok(
        &d,
        &["generate", "noise", "--size", "24x16", "-o", "n.png"],
        b"",
    );
    same_as_file(&d, &["denoise", "n.png"], "dn.png", Some("png"));
    std::fs::write(
        d.join("pts.csv"),
        "0,0\n1,2\n2,1\n3,3\n4,2\n5,5\n6,4\n7,6\n",
    )
    .unwrap();
    same_as_file(&d, &["denoise", "pts.csv", "--levels", "1"], "dp.csv", None);
    // standard input: a raster told by its signature, a point list otherwise
    let png = std::fs::read(d.join("n.png")).unwrap();
    let piped = ok(&d, &["denoise", "-", "-o", "-", "--format", "png"], &png);
    assert!(piped == std::fs::read(d.join("dn.png")).unwrap());
    let csv = std::fs::read(d.join("pts.csv")).unwrap();
    let piped = ok(&d, &["denoise", "-", "--levels", "1", "-o", "-"], &csv);
    assert!(piped == std::fs::read(d.join("dp.csv")).unwrap());
    let ex = std::fs::read(d.join("ex.tif")).unwrap();
    let piped = ok(&d, &["terrain", "render", "-", "-o", "-"], &ex);
    assert!(piped == std::fs::read(d.join("r.png")).unwrap());
    let _ = std::fs::remove_dir_all(&d);
}

/// Every `mesh` command with an output, `solid render|polygonize|voxelize`, `volume
/// isosurface`, `surface`, `curve` and `analyze|synthesize` of an array: `-o -` gives the
/// file's bytes; meshes, scenes and control points are read from standard input too.
#[test]
fn mesh_solid_surface_and_curve_commands_take_standard_input_and_output() {
    let d = dir("geometry");
    std::fs::write(d.join("g.obj"), grid_obj(6)).unwrap();
    for (args, name, fmt) in [
        (
            &["mesh", "subdivide", "g.obj", "--scheme", "loop"][..],
            "s.obj",
            "obj",
        ),
        (&["mesh", "smooth", "g.obj"][..], "m.ply", "ply"),
        (
            &["mesh", "simplify", "g.obj", "--faces", "20"][..],
            "x.off",
            "off",
        ),
        (&["mesh", "normals", "g.obj"][..], "n.obj", "obj"),
        (&["mesh", "convert", "g.obj", "--ascii"][..], "c.ply", "ply"),
        (&["mesh", "orient", "g.obj"][..], "o.obj", "obj"),
    ] {
        same_as_file(&d, args, name, Some(fmt));
    }
    same_as_file(
        &d,
        &["mesh", "render", "g.obj", "--size", "64x48"],
        "r.png",
        None,
    );
    // a mesh on standard input, told by its first bytes
    let ply = std::fs::read(d.join("c.ply")).unwrap();
    let back = ok(
        &d,
        &["mesh", "convert", "-", "-o", "-", "--format", "obj"],
        &ply,
    );
    let via_file = ok(
        &d,
        &["mesh", "convert", "c.ply", "-o", "-", "--format", "obj"],
        b"",
    );
    assert!(back == via_file);
    let scene = corpus("scenes/sphere_and_box.json");
    same_as_file(
        &d,
        &["solid", "render", &scene, "--size", "32"],
        "sr.png",
        None,
    );
    same_as_file(
        &d,
        &["solid", "polygonize", &scene, "--resolution", "12"],
        "sp.obj",
        Some("obj"),
    );
    same_as_file(
        &d,
        &["solid", "voxelize", &scene, "--size", "10"],
        "sv.nrrd",
        Some("nrrd"),
    );
    let json = std::fs::read(&scene).unwrap();
    let piped = ok(
        &d,
        &["solid", "render", "-", "--size", "32", "-o", "-"],
        &json,
    );
    assert!(piped == std::fs::read(d.join("sr.png")).unwrap());
    same_as_file(
        &d,
        &["volume", "isosurface", "sv.nrrd", "--level", "0.5"],
        "iso.ply",
        Some("ply"),
    );
    same_as_file(
        &d,
        &[
            "surface",
            "primitive",
            "--shape",
            "torus",
            "--resolution",
            "8,6",
        ],
        "t.obj",
        Some("obj"),
    );
    same_as_file(
        &d,
        &["surface", "render", "t.obj", "--size", "40x30"],
        "t.png",
        None,
    );
    let wave = corpus("curves/wave.csv");
    same_as_file(
        &d,
        &["curve", "eval", "--samples", "7", &wave],
        "e.csv",
        None,
    );
    same_as_file(
        &d,
        &["curve", "plot", &wave, "--size", "80x60"],
        "p.svg",
        Some("svg"),
    );
    same_as_file(
        &d,
        &[
            "curve",
            "style",
            "--style",
            &corpus("curves/zigzag.csv"),
            "--base",
            &corpus("curves/arc.csv"),
            "--levels",
            "2",
        ],
        "st.csv",
        None,
    );
    let pts = std::fs::read(&wave).unwrap();
    let piped = ok(
        &d,
        &["curve", "eval", "--samples", "7", "-", "-o", "-"],
        &pts,
    );
    assert!(piped == std::fs::read(d.join("e.csv")).unwrap());
    ok(
        &d,
        &[
            "generate",
            "gradient",
            "--size",
            "16x8",
            "--channels",
            "1",
            "-o",
            "a.png",
        ],
        b"",
    );
    same_as_file(
        &d,
        &["analyze", "a.png", "--levels", "1"],
        "pyr.tif",
        Some("tif"),
    );
    same_as_file(&d, &["synthesize", "pyr.tif"], "back.png", Some("png"));
    let _ = std::fs::remove_dir_all(&d);
}

/// `-o -` of a command whose output format the name would give, without `--format`, or
/// with one the command does not write: one line naming `--format`, exit 2, nothing on
/// standard output.
#[test]
fn standard_output_without_a_format_is_refused_naming_format() {
    let d = dir("no-format");
    std::fs::write(d.join("g.obj"), grid_obj(4)).unwrap();
    ok(
        &d,
        &["generate", "terrain", "--size", "17", "-o", "t.png"],
        b"",
    );
    for args in [
        &["generate", "zone-plate", "-o", "-"][..],
        &["terrain", "highpass", "t.png", "-o", "-"][..],
        &["denoise", "t.png", "-o", "-"][..],
        &["mesh", "smooth", "g.obj", "-o", "-"][..],
        &["mesh", "smooth", "g.obj", "-o", "-", "--format", "png"][..],
        &["generate", "zone-plate", "-o", "-", "--format", "obj"][..],
        &[
            "solid",
            "polygonize",
            &corpus("scenes/sphere_and_box.json"),
            "-o",
            "-",
        ][..],
    ] {
        let o = run(&d, args, b"");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains("--format"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
