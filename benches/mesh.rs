//! Mesh benchmarks (`cargo bench --bench mesh`): one Loop step on ≈1.3 M triangles, one
//! Catmull-Clark step on 1 M quads, OBJ load of the triangle mesh, quadric simplification to
//! 10 %, angle-weighted vertex normals — each on all threads and on one thread. The input
//! meshes are generated (closed torus grids) and written to `target/mesh_bench/` as OBJ so the
//! peer script (`benches/peers/mesh_peers.py`) times other libraries on the same files.
//!
//! Options: `--quick` (smaller meshes), `--json` (one JSON object on stdout), `--no-simplify`,
//! `--only simplify` (only the simplification: writes `tri.obj`, times it, best of 3),
//! `--hausdorff A B` (print the symmetric vertex-to-surface distance of two mesh files).

use mra::mesh::features::Tags;
use mra::mesh::{io, normals, shapes, simplify, HalfEdgeMesh, Mesh};
use std::time::Instant;

fn best_of<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..n {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.unwrap())
}

/// Simplify to 10 % of the faces (best of `reps`), write the result, and describe it with its
/// symmetric vertex-to-surface Hausdorff distance to the input.
fn simplify_run(tri: &Mesh, dir: &std::path::Path, reps: usize) -> (f64, String) {
    let target = tri.face_count() / 10;
    let (t, s) = best_of(reps, || simplify::simplify(tri, target).unwrap());
    let err = simplify::vertex_to_surface_distance(tri, &s)
        .max(simplify::vertex_to_surface_distance(&s, tri));
    io::write(dir.join("tri_simplified_mra.obj"), &s).unwrap();
    (
        t,
        format!(
            "{} → {} triangles, Hausdorff (vertex) {err:.3e}",
            tri.face_count(),
            s.face_count()
        ),
    )
}

fn loop_step(m: &Mesh) -> Mesh {
    let he = HalfEdgeMesh::build(m).unwrap();
    let tags = Tags::boundary_only(&he);
    mra::mesh::loop_subdivision::step(m, &he, &tags, Default::default())
        .unwrap()
        .0
}

fn cc_step(m: &Mesh) -> Mesh {
    let he = HalfEdgeMesh::build(m).unwrap();
    let tags = Tags::boundary_only(&he);
    mra::mesh::catmull_clark::step(m, &he, &tags).unwrap().0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let json = args.iter().any(|a| a == "--json");
    if let Some(i) = args.iter().position(|a| a == "--hausdorff") {
        // symmetric vertex-to-surface Hausdorff distance between two mesh files
        let a = io::read(&args[i + 1]).unwrap();
        let b = io::read(&args[i + 2]).unwrap();
        let d = simplify::vertex_to_surface_distance(&a, &b)
            .max(simplify::vertex_to_surface_distance(&b, &a));
        println!("{d:e}");
        return;
    }
    let only_simplify = args
        .windows(2)
        .any(|w| w[0] == "--only" && w[1] == "simplify");
    let (nt, nq) = if quick { (200, 200) } else { (806, 1000) };
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mesh_bench"));
    std::fs::create_dir_all(&dir).unwrap();
    let tri = shapes::torus_triangles(nt, nt, 3.0, 1.0);
    let tri_path = dir.join("tri.obj");
    if only_simplify {
        // timed before writing tri.obj: the system's write-back of a fresh 68 MB file would
        // compete with the timing
        let (t, what) = simplify_run(&tri, &dir, 3);
        io::write(&tri_path, &tri).unwrap();
        if json {
            println!(
                "{}",
                serde_json::json!({"simplify_10pct": {"seconds": t, "note": what}})
            );
        } else {
            println!("{:<36} {t:>8.3} s   {what}", "simplify_10pct");
        }
        return;
    }
    io::write(&tri_path, &tri).unwrap();
    let quad = shapes::torus(nq, nq, 3.0, 1.0);
    let quad_path = dir.join("quad.obj");
    io::write(&quad_path, &quad).unwrap();
    let obj_bytes = std::fs::metadata(&tri_path).unwrap().len();
    let threads = rayon::current_num_threads();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let reps = 3;
    let mut results: Vec<(String, f64, String)> = Vec::new();
    let mut record = |name: &str, secs: f64, what: String| {
        if !json {
            println!("{name:<36} {secs:>8.3} s   {what}");
        }
        results.push((name.to_string(), secs, what));
    };
    let (t, out) = best_of(reps, || loop_step(&tri));
    record(
        "loop_step",
        t,
        format!(
            "{} → {} triangles, {threads} threads",
            tri.face_count(),
            out.face_count()
        ),
    );
    let (t, _) = one.install(|| best_of(reps, || loop_step(&tri)));
    record("loop_step_1thread", t, "1 thread".into());
    let (t, out) = best_of(reps, || cc_step(&quad));
    record(
        "catmull_clark_step",
        t,
        format!(
            "{} → {} quads, {threads} threads",
            quad.face_count(),
            out.face_count()
        ),
    );
    let (t, _) = one.install(|| best_of(reps, || cc_step(&quad)));
    record("catmull_clark_step_1thread", t, "1 thread".into());
    let (t, m) = best_of(reps, || io::read(&tri_path).unwrap());
    assert_eq!(m.face_count(), tri.face_count());
    record(
        "obj_load",
        t,
        format!(
            "{:.1} MB, {:.0} MB/s",
            obj_bytes as f64 / 1e6,
            obj_bytes as f64 / 1e6 / t
        ),
    );
    let (t, _) = best_of(reps, || {
        normals::vertex_normals(&tri, normals::Weighting::Angle)
    });
    record(
        "vertex_normals_angle",
        t,
        format!("{} triangles", tri.face_count()),
    );
    let (t, _) = best_of(reps, || mra::mesh::Edges::build(&tri));
    record("edges_build", t, format!("{} triangles", tri.face_count()));
    let (t, _) = best_of(reps, || HalfEdgeMesh::build(&tri).unwrap());
    record(
        "halfedge_build",
        t,
        format!("{} triangles", tri.face_count()),
    );
    if args.iter().any(|a| a == "--no-simplify") {
        return;
    }
    let (t, what) = simplify_run(&tri, &dir, 2);
    record("simplify_10pct", t, what);
    if json {
        let obj: serde_json::Map<String, serde_json::Value> = results
            .iter()
            .map(|(n, t, w)| (n.clone(), serde_json::json!({"seconds": t, "note": w})))
            .collect();
        println!("{}", serde_json::Value::Object(obj));
    }
}
