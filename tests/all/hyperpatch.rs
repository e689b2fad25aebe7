//! Tests of trivariate B-spline hyper-patches (notes §10.2) and free-form deformation:
//! the identity lattice, partition of unity, affine invariance, degree 1 = trilinear
//! interpolation, agreement with the curve module's brute-force basis, derivatives and
//! continuity, and lattice-file errors that name the field.

use mra::curve::basis::basis_brute;
use mra::mesh::{shapes, Mesh};
use mra::solid::ffd::{self, Lattice};
use mra::solid::hyperpatch::HyperPatch;
use mra::ErrorKind;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn v3(&mut self, a: f64, b: f64) -> [f64; 3] {
        [self.range(a, b), self.range(a, b), self.range(a, b)]
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn random_patch(r: &mut Rng, dims: [usize; 3], degrees: [usize; 3]) -> HyperPatch {
    let n = dims.iter().product();
    let pts = (0..n).map(|_| r.v3(-2.0, 2.0)).collect();
    HyperPatch::clamped(pts, dims, degrees).unwrap()
}

/// A lattice over [-1, 2] × [0, 1] × [-3, -1] with some points moved at random.
fn random_lattice(r: &mut Rng, dims: [usize; 3], degrees: [usize; 3]) -> Lattice {
    let mut lat = Lattice::identity([-1.0, 0.0, -3.0], [2.0, 1.0, -1.0], dims, degrees).unwrap();
    for _ in 0..dims.iter().product::<usize>() / 2 {
        let ijk = [0, 1, 2].map(|d| (r.next() * dims[d] as f64) as usize % dims[d]);
        let off = r.v3(-0.4, 0.4);
        let p = lat.point_mut(ijk).unwrap();
        for d in 0..3 {
            p[d] += off[d];
        }
    }
    lat
}

/// A sphere mesh squeezed into the box, its vertices jittered at random.
fn mesh_in_box(r: &mut Rng, lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    let mut m = shapes::sphere(3);
    for p in m.positions.iter_mut() {
        for d in 0..3 {
            let t = 0.5 * (p[d] + 1.0) * 0.9 + 0.05 + r.range(-0.04, 0.04);
            p[d] = lo[d] + t * (hi[d] - lo[d]);
        }
    }
    m
}

#[test]
fn identity_lattice_reproduces_points() {
    let mut r = Rng(0x9e3779b97f4a7c15);
    let (lo, hi) = ([-1.0, 0.0, -3.0], [2.0, 1.0, -1.0]);
    for (dims, degrees) in [
        ([2, 2, 2], [1, 1, 1]),
        ([4, 4, 4], [3, 3, 3]),
        ([5, 3, 7], [2, 1, 4]),
        ([8, 6, 5], [3, 2, 3]),
    ] {
        let lat = Lattice::identity(lo, hi, dims, degrees).unwrap();
        let mut worst: f64 = 0.0;
        for _ in 0..2000 {
            let x = [0, 1, 2].map(|d| r.range(lo[d], hi[d]));
            worst = worst.max(dist(lat.apply(x), x));
        }
        // the box's corners and faces too
        for c in 0..8 {
            let x = [0, 1, 2].map(|d| if c >> d & 1 == 1 { hi[d] } else { lo[d] });
            worst = worst.max(dist(lat.apply(x), x));
        }
        assert!(worst <= 1e-12, "{dims:?} {degrees:?}: worst {worst:e}");
        // and a mesh through the CLI path: identical positions, connectivity untouched
        let m = mesh_in_box(&mut r, lo, hi);
        let lat = Lattice::around(&m, dims, degrees).unwrap();
        let out = lat.deform(&m);
        assert_eq!(out.indices, m.indices);
        assert_eq!(out.offsets, m.offsets);
        for (a, b) in out.positions.iter().zip(&m.positions) {
            assert!(dist(*a, *b) <= 1e-12, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn basis_is_a_partition_of_unity() {
    let mut r = Rng(7);
    for (dims, degrees) in [([4, 5, 6], [3, 2, 1]), ([7, 7, 7], [4, 4, 4])] {
        let n = dims.iter().product();
        let c = [0.25, -1.5, 3.0];
        let p = HyperPatch::clamped(vec![c; n], dims, degrees).unwrap();
        for _ in 0..1000 {
            let q = p.eval(r.v3(0.0, 1.0)).unwrap();
            assert!(dist(q, c) <= 1e-13, "{q:?}");
        }
        for end in [[0.0; 3], [1.0; 3], [0.0, 1.0, 0.5]] {
            assert!(dist(p.eval(end).unwrap(), c) <= 1e-13);
        }
    }
}

#[test]
fn patch_agrees_with_brute_force_basis_and_interpolates_corners() {
    let mut r = Rng(11);
    let dims = [5, 4, 6];
    let degrees = [3, 2, 3];
    let p = random_patch(&mut r, dims, degrees);
    let k = degrees.map(|d| d + 1);
    for _ in 0..200 {
        let uvw = r.v3(0.0, 1.0);
        let q = p.eval(uvw).unwrap();
        let mut e = [0.0; 3];
        for kk in 0..dims[2] {
            let nw = basis_brute(p.knots(2), dims[2], kk, k[2], uvw[2]);
            for j in 0..dims[1] {
                let nv = basis_brute(p.knots(1), dims[1], j, k[1], uvw[1]);
                for i in 0..dims[0] {
                    let nu = basis_brute(p.knots(0), dims[0], i, k[0], uvw[0]);
                    let c = p.points()[p.index([i, j, kk])];
                    for d in 0..3 {
                        e[d] += nu * nv * nw * c[d];
                    }
                }
            }
        }
        assert!(dist(q, e) <= 1e-12, "{q:?} vs {e:?}");
    }
    // clamped knots: the corners of the parameter cube map to the corner control points
    for c in 0..8usize {
        let uvw = [0, 1, 2].map(|d| (c >> d & 1) as f64);
        let ijk = [0, 1, 2].map(|d| (c >> d & 1) * (dims[d] - 1));
        assert!(dist(p.eval(uvw).unwrap(), p.points()[p.index(ijk)]) <= 1e-14);
    }
}

#[test]
fn affine_map_of_the_lattice_moves_the_mesh_by_the_same_map() {
    let mut r = Rng(3);
    for (dims, degrees) in [([4, 4, 4], [3, 3, 3]), ([6, 3, 5], [2, 1, 3])] {
        let lat = random_lattice(&mut r, dims, degrees);
        let (lo, hi) = lat.bounds();
        let m = mesh_in_box(&mut r, lo, hi);
        let a: [[f64; 3]; 3] = [r.v3(-1.0, 1.0), r.v3(-1.0, 1.0), r.v3(-1.0, 1.0)];
        let b = r.v3(-5.0, 5.0);
        let map = |p: [f64; 3]| {
            [0, 1, 2].map(|i| a[i][0] * p[0] + a[i][1] * p[1] + a[i][2] * p[2] + b[i])
        };
        let mut moved = lat.clone();
        let pts: Vec<[f64; 3]> = lat.patch().points().iter().map(|&p| map(p)).collect();
        moved.set_points(pts).unwrap();
        let d1 = lat.deform(&m);
        let d2 = moved.deform(&m);
        let mut worst: f64 = 0.0;
        for (p, q) in d1.positions.iter().zip(&d2.positions) {
            worst = worst.max(dist(map(*p), *q));
        }
        assert!(worst <= 1e-12, "{dims:?}: worst {worst:e}");
        // the identity lattice mapped affinely moves the mesh by the map itself
        let mut id = Lattice::identity(lo, hi, dims, degrees).unwrap();
        let pts: Vec<[f64; 3]> = id.patch().points().iter().map(|&p| map(p)).collect();
        id.set_points(pts).unwrap();
        let d3 = id.deform(&m);
        for (p, q) in m.positions.iter().zip(&d3.positions) {
            assert!(dist(map(*p), *q) <= 1e-12);
        }
    }
}

#[test]
fn degree_one_lattice_is_trilinear_interpolation() {
    let mut r = Rng(5);
    let dims = [3, 4, 2];
    let p = random_patch(&mut r, dims, [1, 1, 1]);
    for _ in 0..1000 {
        let s = r.v3(0.0, 1.0);
        // cell and local coordinates on the uniform clamped knots 0, 1/(n−1), …, 1
        let mut cell = [0usize; 3];
        let mut t = [0.0; 3];
        for d in 0..3 {
            let x = s[d] * (dims[d] - 1) as f64;
            cell[d] = (x.floor() as usize).min(dims[d] - 2);
            t[d] = x - cell[d] as f64;
        }
        let mut e = [0.0; 3];
        for c in 0..8usize {
            let o = [c & 1, c >> 1 & 1, c >> 2 & 1];
            let w: f64 = (0..3)
                .map(|d| if o[d] == 1 { t[d] } else { 1.0 - t[d] })
                .product();
            let q = p.points()[p.index([cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]])];
            for d in 0..3 {
                e[d] += w * q[d];
            }
        }
        let q = p.eval(s).unwrap();
        assert!(dist(q, e) <= 1e-12, "{q:?} vs {e:?}");
    }
}

#[test]
fn jacobian_matches_differences_and_cubic_lattice_is_c2_across_knots() {
    let mut r = Rng(13);
    let dims = [6, 5, 7];
    let p = random_patch(&mut r, dims, [3, 3, 3]);
    let h = 1e-6;
    for _ in 0..200 {
        let s = r.v3(0.01, 0.99);
        let (q, j) = p.eval_jacobian(s).unwrap();
        assert!(dist(q, p.eval(s).unwrap()) <= 1e-13);
        for d in 0..3 {
            let (mut a, mut b) = (s, s);
            a[d] += h;
            b[d] -= h;
            let (qa, qb) = (p.eval(a).unwrap(), p.eval(b).unwrap());
            let fd = [0, 1, 2].map(|c| (qa[c] - qb[c]) / (2.0 * h));
            assert!(dist(fd, j[d]) <= 1e-6 * (1.0 + dist(j[d], [0.0; 3])));
        }
    }
    // value, first and (by differences of the first) second derivative continuous at an
    // interior knot of u
    let knot = p.knots(0)[4];
    assert!(knot > 0.0 && knot < 1.0);
    let eps = 1e-9;
    let s = [knot, 0.37, 0.61];
    let (ql, jl) = p.eval_jacobian([knot - eps, s[1], s[2]]).unwrap();
    let (qr, jr) = p.eval_jacobian([knot + eps, s[1], s[2]]).unwrap();
    assert!(dist(ql, qr) <= 1e-7);
    assert!(dist(jl[0], jr[0]) <= 1e-6);
    let g = 1e-4;
    let second = |x: f64| {
        let (_, a) = p.eval_jacobian([x + g, s[1], s[2]]).unwrap();
        let (_, b) = p.eval_jacobian([x - g, s[1], s[2]]).unwrap();
        [0, 1, 2].map(|c| (a[0][c] - b[0][c]) / (2.0 * g))
    };
    let (sl, sr) = (second(knot - 2.0 * g), second(knot + 2.0 * g));
    assert!(
        dist(sl, sr) <= 1e-2 * (1.0 + dist(sl, [0.0; 3])),
        "{sl:?} {sr:?}"
    );
}

#[test]
fn points_outside_the_box_are_unchanged_and_normals_follow() {
    let mut r = Rng(17);
    let lat = random_lattice(&mut r, [4, 4, 4], [3, 3, 3]);
    for x in [[-1.5, 0.5, -2.0], [3.0, 0.5, -2.0], [0.0, 0.5, 0.0]] {
        assert_eq!(lat.apply(x), x);
    }
    // a uniform scaling lattice maps normals of a sphere to normals of the ellipsoid
    let mut m = shapes::sphere(2);
    m.attributes.vertex_normals = Some(m.positions.clone());
    let (lo, hi) = ffd::bounds(&m).unwrap();
    let mut lat = Lattice::identity(lo, hi, [3, 3, 3], [2, 2, 2]).unwrap();
    let pts: Vec<[f64; 3]> = lat
        .patch()
        .points()
        .iter()
        .map(|p| [2.0 * p[0], p[1], p[2]])
        .collect();
    lat.set_points(pts).unwrap();
    let out = lat.deform(&m);
    let n = out.attributes.vertex_normals.as_ref().unwrap();
    for (p, nv) in m.positions.iter().zip(n) {
        // ellipsoid x²/4 + y² + z² = 1: normal ∝ (x'/4, y, z) with x' = 2x
        let g = [p[0] / 2.0, p[1], p[2]];
        let l = dist(g, [0.0; 3]);
        let g = g.map(|c| c / l);
        assert!(dist(g, *nv) <= 1e-9, "{g:?} vs {nv:?}");
    }
}

#[test]
fn lattice_files_parse_and_bad_ones_name_the_field() {
    let bbox = ([0.0; 3], [1.0; 3]);
    let ok = r#"{"dims":[4,3,2],"degree":[3,2,1],
        "moves":[{"index":[3,2,1],"offset":[0.5,0,0]}]}"#;
    let lat = Lattice::parse(ok, bbox).unwrap();
    let moved = lat.apply([1.0, 1.0, 1.0]);
    assert!(dist(moved, [1.5, 1.0, 1.0]) <= 1e-12);
    // default degree min(3, dims − 1); an explicit box; a full point list
    let lat = Lattice::parse(
        r#"{"dims":[2,2,2],"box":{"min":[0,0,0],"max":[2,2,2]}}"#,
        bbox,
    )
    .unwrap();
    assert_eq!(lat.patch().orders(), [2, 2, 2]);
    let pts: Vec<String> = (0..8)
        .map(|c| format!("[{},{},{}]", c & 1, (c >> 1) & 1, 3 * ((c >> 2) & 1)))
        .collect();
    let full = format!(r#"{{"dims":[2,2,2],"points":[{}]}}"#, pts.join(","));
    let lat = Lattice::parse(&full, bbox).unwrap();
    assert!(dist(lat.apply([0.5, 0.5, 0.5]), [0.5, 0.5, 1.5]) <= 1e-12);

    for (text, place) in [
        ("[1,2]", "lattice: not a JSON object"),
        (r#"{"degree":3}"#, "no \"dims\""),
        (r#"{"dims":[4,4]}"#, "lattice.dims:"),
        (r#"{"dims":[4,1,4]}"#, "lattice.dims[1]:"),
        (r#"{"dims":[4,4,-4]}"#, "lattice.dims[2]:"),
        (r#"{"dims":[4,4,4],"degree":4}"#, "lattice.degree:"),
        (r#"{"dims":[4,4,4],"degree":[1,0,1]}"#, "lattice.degree:"),
        (
            r#"{"dims":[4,4,4],"box":{"min":[0,0,0]}}"#,
            "lattice.box: no \"max\"",
        ),
        (
            r#"{"dims":[4,4,4],"box":{"min":[2,0,0],"max":[1,1,1]}}"#,
            "lattice.box:",
        ),
        (
            r#"{"dims":[4,4,4],"moves":[{"index":[1,4,0],"offset":[0,0,1]}]}"#,
            "lattice.moves[0].index:",
        ),
        (
            r#"{"dims":[4,4,4],"moves":[{},{"index":[0,0,0]}]}"#,
            "lattice.moves[0]: no \"index\"",
        ),
        (
            r#"{"dims":[4,4,4],"moves":[{"index":[0,0,0],"offset":[0,"x",0]}]}"#,
            "lattice.moves[0].offset[1]:",
        ),
        (r#"{"dims":[2,2,2],"points":[[0,0,0]]}"#, "lattice.points:"),
        (r#"{"dims":[2,2,2],"moves":[],"points":[]}"#, "both"),
        (
            r#"{"dims":[2,2,2],"moved":[]}"#,
            "lattice.moved: unknown field",
        ),
    ] {
        let e = Lattice::parse(text, bbox).unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.kind(), ErrorKind::Format, "{text}: {msg}");
        assert!(msg.contains(place), "{text}: {msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }
}

#[test]
fn bad_patches_are_rejected() {
    assert!(HyperPatch::clamped(vec![[0.0; 3]; 7], [2, 2, 2], [1, 1, 1]).is_err());
    assert!(HyperPatch::clamped(vec![[0.0; 3]; 8], [2, 2, 2], [2, 1, 1]).is_err());
    assert!(HyperPatch::clamped(vec![[f64::NAN; 3]; 8], [2, 2, 2], [1, 1, 1]).is_err());
    let p = HyperPatch::clamped(vec![[0.0; 3]; 8], [2, 2, 2], [1, 1, 1]).unwrap();
    assert_eq!(
        p.eval([1.5, 0.0, 0.0]).unwrap_err().kind(),
        ErrorKind::Parameter
    );
    assert!(Lattice::identity([0.0; 3], [1.0; 3], [2, 2, 2], [0, 1, 1]).is_err());
    assert!(Lattice::identity([0.0; 3], [1.0; 3], [4096, 4096, 4096], [1, 1, 1]).is_err());
    // a flat mesh (zero-width box side) still gets an identity lattice
    let m = Mesh::from_faces(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![vec![0u32, 1, 2]],
    )
    .unwrap();
    let lat = Lattice::around(&m, [3, 3, 3], [2, 2, 2]).unwrap();
    for (a, b) in lat.deform(&m).positions.iter().zip(&m.positions) {
        assert!(dist(*a, *b) <= 1e-12);
    }
}
