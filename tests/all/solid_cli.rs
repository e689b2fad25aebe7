//! The `mra` binary on solids: `mra solid render | polygonize | voxelize | volume`,
//! `mra volume isosurface` and `mra mesh deform` on the corpus scenes and generated volumes;
//! bad scenes and lattices give exit code 2, one line on stderr naming the place, and no
//! output file (not even a partial or temporary one).

use mra::mesh::topology;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mra"))
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mra-solid-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn corpus(rel: &str) -> String {
    format!("{}/corpus/{rel}", env!("CARGO_MANIFEST_DIR"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        text(&o.stderr)
    );
}

/// Exit code 2, one line on stderr containing `needle`.
fn fails(o: &Output, needle: &str) {
    assert_eq!(o.status.code(), Some(2), "stderr: {}", text(&o.stderr));
    let e = text(&o.stderr);
    assert_eq!(e.trim_end().lines().count(), 1, "not one line: {e:?}");
    assert!(e.contains(needle), "{e:?} does not name {needle:?}");
}

/// The folder holds exactly these file names (no output, no temporary files).
fn only(dir: &Path, names: &[&str]) {
    let mut got: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    got.sort();
    let mut want: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(got, want);
}

fn closed_manifold(path: &Path) -> mra::mesh::Mesh {
    let m = mra::mesh::io::read(path).unwrap();
    let r = topology::analyze(&m);
    assert!(m.face_count() > 0);
    assert!(
        r.closed && r.manifold && r.oriented,
        "{}: {r:?}",
        path.display()
    );
    m
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let d = tmpdir("render");
    let out = d.join("csg.png");
    let o = mra(&[
        "solid",
        "render",
        &corpus("scenes/csg20.json"),
        "-o",
        s(&out),
        "--size",
        "96",
    ]);
    ok(&o);
    assert!(text(&o.stdout).contains("96x96 image of 20 primitives"));
    let r = mra::io::read(&out).unwrap();
    assert_eq!(r.dims[..2], [96, 96]);
    // the picture is not blank: background and shaded object both present
    let v = r.to_f32();
    let (lo, hi) = v
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi - lo > 0.2 * hi.max(1e-6), "{lo} {hi}");
    only(&d, &["csg.png"]);
}

#[test]
fn polygonize_gives_a_closed_manifold_mesh_for_every_corpus_scene() {
    let d = tmpdir("polygonize");
    for name in [
        "sphere",
        "sphere_and_box",
        "box_minus_cylinder",
        "blend",
        "csg20",
    ] {
        let out = d.join(format!("{name}.ply"));
        let o = mra(&[
            "solid",
            "polygonize",
            &corpus(&format!("scenes/{name}.json")),
            "-o",
            s(&out),
            "--resolution",
            "40",
            "--normals",
        ]);
        ok(&o);
        let m = closed_manifold(&out);
        assert_eq!(
            m.attributes
                .vertex_normals
                .as_ref()
                .map(|n| n.len())
                .or_else(|| m
                    .attributes
                    .vertex
                    .iter()
                    .find(|p| p.name == "nx")
                    .map(|p| p.values.len())),
            Some(m.vertex_count()),
            "{name}: normals"
        );
    }
}

#[test]
fn volume_of_the_unit_sphere_scene_is_four_thirds_pi() {
    let o = mra(&[
        "solid",
        "volume",
        &corpus("scenes/sphere.json"),
        "--rays",
        "256",
    ]);
    ok(&o);
    let out = text(&o.stdout);
    let v: f64 = out
        .split_whitespace()
        .nth(1)
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{out}"));
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    assert!((v - exact).abs() <= 0.005 * exact, "{v} vs {exact}");
}

#[test]
fn voxelize_then_isosurface_round_trips_through_a_volume_file() {
    let d = tmpdir("voxelize");
    let field = d.join("sphere.nrrd");
    ok(&mra(&[
        "solid",
        "voxelize",
        &corpus("scenes/sphere.json"),
        "-o",
        s(&field),
        "--size",
        "48",
    ]));
    let r = mra::io::read(&field).unwrap();
    assert_eq!(r.dims.len(), 3);
    assert!(r.dims.iter().all(|&n| n >= 48));
    let occ = d.join("part.nrrd");
    ok(&mra(&[
        "solid",
        "voxelize",
        &corpus("scenes/box_minus_cylinder.json"),
        "-o",
        s(&occ),
        "--size",
        "32",
        "--occupancy",
    ]));
    let r = mra::io::read(&occ).unwrap();
    let v = r.to_f32();
    assert!(v.iter().all(|&x| x == 0.0 || x == 255.0));
    assert!(v.contains(&255.0) && v.contains(&0.0));

    // the field volume's zero level is the unit sphere: closed mesh, area ≈ 4π
    let mesh = d.join("sphere.obj");
    let o = mra(&[
        "volume",
        "isosurface",
        s(&field),
        "--level",
        "0",
        "-o",
        s(&mesh),
    ]);
    ok(&o);
    let m = closed_manifold(&mesh);
    let (area, vol) = mra::solid::mc::area_volume(&m);
    let pi = std::f64::consts::PI;
    assert!((area - 4.0 * pi).abs() < 0.02 * 4.0 * pi, "area {area}");
    assert!(
        (vol - 4.0 / 3.0 * pi).abs() < 0.02 * 4.0 / 3.0 * pi,
        "volume {vol}"
    );
    // the occupancy volume: a box with a hole, genus 1 (χ = 0)
    let part = d.join("part.ply");
    ok(&mra(&[
        "volume",
        "isosurface",
        s(&occ),
        "--level",
        "127.5",
        "-o",
        s(&part),
    ]));
    let m = closed_manifold(&part);
    assert_eq!(topology::analyze(&m).euler, 0);
    only(&d, &["sphere.nrrd", "part.nrrd", "sphere.obj", "part.ply"]);
}

#[test]
fn isosurface_of_the_corpus_phantom_is_closed_and_open_mode_stays_manifold() {
    let d = tmpdir("phantom");
    let capped = d.join("head.obj");
    let input = corpus("phantom_64.nrrd");
    let r = mra::io::read(Path::new(&input)).unwrap();
    let v = r.to_f32();
    let (lo, hi) = v
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let level = format!("{}", lo + 0.05 * (hi - lo));
    ok(&mra(&[
        "volume",
        "isosurface",
        &input,
        "--level",
        &level,
        "-o",
        s(&capped),
        "--normals",
    ]));
    closed_manifold(&capped);
    let open = d.join("head_open.obj");
    ok(&mra(&[
        "volume",
        "isosurface",
        &input,
        "--level",
        &level,
        "-o",
        s(&open),
        "--open",
    ]));
    let m = mra::mesh::io::read(&open).unwrap();
    assert!(topology::analyze(&m).manifold);
}

#[test]
fn bad_scenes_fail_with_one_line_naming_the_place_and_no_output() {
    let d = tmpdir("bad");
    let cases = [
        (
            "unknown.json",
            r#"{"root":{"type":"union","children":[{"type":"sphere","center":[0,0,0],"radius":1},{"type":"sphre","center":[0,0,0],"radius":1}]}}"#,
            r#"root.children[1]: unknown primitive "sphre""#,
        ),
        (
            "negative.json",
            r#"{"root":{"type":"sphere","center":[0,0,0],"radius":-2}}"#,
            "root.radius: -2 is not a positive length",
        ),
        (
            "cyclic.json",
            r#"{"defs":{"a":{"type":"union","children":[{"ref":"b"}]},"b":{"type":"union","children":[{"ref":"a"}]}},"root":{"ref":"a"}}"#,
            "cyclic reference",
        ),
        (
            "empty.json",
            r#"{"root":{"type":"intersection","children":[]}}"#,
            "root: empty intersection",
        ),
        ("notjson.json", "{ root: ", "scene JSON"),
    ];
    let names: Vec<&str> = cases.iter().map(|c| c.0).collect();
    for (name, body, needle) in cases {
        let scene = d.join(name);
        std::fs::write(&scene, body).unwrap();
        let out = d.join("out");
        for args in [
            vec![
                "solid",
                "render",
                s(&scene),
                "-o",
                "OUT.png",
                "--size",
                "32",
            ],
            vec!["solid", "polygonize", s(&scene), "-o", "OUT.obj"],
            vec![
                "solid",
                "voxelize",
                s(&scene),
                "-o",
                "OUT.nrrd",
                "--size",
                "16",
            ],
            vec!["solid", "volume", s(&scene), "--rays", "16"],
        ] {
            let args: Vec<String> = args
                .iter()
                .map(|a| match a.strip_prefix("OUT") {
                    Some(ext) => format!("{}{ext}", s(&out)),
                    None => a.to_string(),
                })
                .collect();
            let a: Vec<&str> = args.iter().map(|x| x.as_str()).collect();
            let o = mra(&a);
            fails(&o, needle);
            assert!(text(&o.stderr).contains(name), "file not named");
        }
    }
    only(&d, &names);
}

#[test]
fn isosurface_of_a_non_volume_fails_cleanly() {
    let d = tmpdir("isobad");
    let out = d.join("x.obj");
    let o = mra(&[
        "volume",
        "isosurface",
        &corpus("edges_256.png"),
        "--level",
        "0.5",
        "-o",
        s(&out),
    ]);
    fails(&o, "3-D volume");
    let o = mra(&[
        "volume",
        "isosurface",
        s(&d.join("missing.nrrd")),
        "--level",
        "1",
        "-o",
        s(&out),
    ]);
    fails(&o, "missing.nrrd");
    only(&d, &[]);
}

#[test]
fn mesh_deform_with_the_corpus_lattice_and_bad_lattices() {
    let d = tmpdir("deform");
    let ball = d.join("ball.obj");
    ok(&mra(&[
        "solid",
        "polygonize",
        &corpus("scenes/sphere.json"),
        "-o",
        s(&ball),
        "--resolution",
        "24",
    ]));
    let out = d.join("bulged.obj");
    ok(&mra(&[
        "mesh",
        "deform",
        s(&ball),
        "-o",
        s(&out),
        "--lattice",
        &corpus("lattices/bulge.json"),
    ]));
    let before = mra::mesh::io::read(&ball).unwrap();
    let after = closed_manifold(&out);
    assert_eq!(after.indices, before.indices);
    let top = |m: &mra::mesh::Mesh| m.positions.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    assert!(top(&after) > top(&before) + 0.2, "the bulge raises the top");

    // an identity lattice (no moves) changes nothing beyond rounding
    let id = d.join("id.json");
    std::fs::write(&id, r#"{"dims":[5,4,3],"degree":[3,2,2]}"#).unwrap();
    let same = d.join("same.obj");
    ok(&mra(&[
        "mesh",
        "deform",
        s(&ball),
        "-o",
        s(&same),
        "--lattice",
        s(&id),
    ]));
    let m = mra::mesh::io::read(&same).unwrap();
    for (a, b) in m.positions.iter().zip(&before.positions) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-9);
        }
    }

    let bad = d.join("bad.json");
    std::fs::write(
        &bad,
        r#"{"dims":[4,4,4],"moves":[{"index":[1,9,0],"offset":[0,0,1]}]}"#,
    )
    .unwrap();
    let no = d.join("no.obj");
    let o = mra(&[
        "mesh",
        "deform",
        s(&ball),
        "-o",
        s(&no),
        "--lattice",
        s(&bad),
    ]);
    fails(&o, "lattice.moves[0].index: 9 is outside 0..4");
    assert!(text(&o.stderr).contains("bad.json"));
    only(
        &d,
        &["ball.obj", "bulged.obj", "id.json", "same.obj", "bad.json"],
    );
}

/// `volume isosurface`: the topology check only on request (`--check`), the report as one
/// JSON object with `--json`, PLY positions as `float` unless `--double`.
#[test]
fn isosurface_report_checks_topology_on_request_and_ply_positions_are_float() {
    let d = tmpdir("iso-report");
    let field = d.join("sphere.nrrd");
    ok(&mra(&[
        "solid",
        "voxelize",
        &corpus("scenes/sphere.json"),
        "-o",
        s(&field),
        "--size",
        "40",
    ]));
    let (f32_ply, f64_ply) = (d.join("f.ply"), d.join("d.ply"));
    let run = |out: &Path, extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "volume",
            "isosurface",
            s(&field),
            "--level",
            "0",
            "-o",
            s(out),
            "--json",
        ];
        args.extend_from_slice(extra);
        let o = mra(&args);
        ok(&o);
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let quick = run(&f32_ply, &[]);
    assert!(
        quick["closed"].is_null() && quick["euler"].is_null(),
        "{quick}"
    );
    let checked = run(&f64_ply, &["--check", "--double"]);
    assert_eq!(checked["closed"], true);
    assert_eq!(checked["manifold"], true);
    assert_eq!(checked["euler"], 2);
    assert_eq!(quick["triangles"], checked["triangles"]);
    assert!(quick["triangles"].as_u64().unwrap() > 1000);
    let header = |p: &Path| {
        let b = std::fs::read(p).unwrap();
        let end = b.windows(10).position(|w| w == b"end_header").unwrap();
        text(&b[..end])
    };
    assert!(header(&f32_ply).contains("property float x"));
    assert!(header(&f64_ply).contains("property double x"));
    let (a, b) = (
        mra::mesh::io::read(&f32_ply).unwrap(),
        mra::mesh::io::read(&f64_ply).unwrap(),
    );
    assert_eq!(a.indices, b.indices);
    for (p, q) in a.positions.iter().zip(&b.positions) {
        for k in 0..3 {
            assert_eq!(p[k], q[k] as f32 as f64);
        }
    }
    let area = checked["area"].as_f64().unwrap();
    assert!((area - quick["area"].as_f64().unwrap()).abs() < 1e-9 * area);
    let text_out = mra(&[
        "volume",
        "isosurface",
        s(&field),
        "--level",
        "0",
        "-o",
        s(&f32_ply),
    ]);
    ok(&text_out);
    assert!(!text(&text_out.stdout).contains("closed"));
    let _ = std::fs::remove_dir_all(&d);
}
