//! One entry point for the subdivision schemes of ch. 8: build the half-edge structure, resolve
//! the sharp tags, run one step of the chosen scheme, and repeat with the child tags.

use super::features::{Features, Tags};
use super::halfedge::HalfEdgeMesh;
use super::loop_subdivision::LoopWeights;
use super::Mesh;
use crate::{Error, Result};

/// The subdivision schemes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Loop (§8.2), triangles only.
    Loop(LoopWeights),
    /// Catmull-Clark (§8.3), any polygons.
    CatmullClark,
    /// Doo-Sabin (§8.1), any polygons; no sharp tags.
    DooSabin,
    /// Modified Butterfly (§8.4), triangles only, interpolating.
    Butterfly,
}

impl Scheme {
    /// Parse a command-line name (`loop`, `loop-warren`, `catmull-clark`, `doo-sabin`, `butterfly`).
    pub fn parse(s: &str) -> Result<Scheme> {
        Ok(match s {
            "loop" => Scheme::Loop(LoopWeights::Loop),
            "loop-warren" => Scheme::Loop(LoopWeights::Warren),
            "catmull-clark" | "cc" => Scheme::CatmullClark,
            "doo-sabin" => Scheme::DooSabin,
            "butterfly" => Scheme::Butterfly,
            _ => {
                return Err(Error::parameter(
                    "scheme",
                    s,
                    "loop, loop-warren, catmull-clark, doo-sabin or butterfly",
                ))
            }
        })
    }

    /// True when the scheme accepts this mesh's faces.
    pub fn applies_to(self, mesh: &Mesh) -> bool {
        match self {
            Scheme::Loop(_) | Scheme::Butterfly => mesh.is_triangle_mesh(),
            _ => true,
        }
    }
}

/// One step with already resolved tags; returns the refined mesh and its child tags.
pub fn step(
    mesh: &Mesh,
    he: &HalfEdgeMesh,
    scheme: Scheme,
    tags: &Tags,
) -> Result<(Mesh, Features)> {
    match scheme {
        Scheme::Loop(w) => super::loop_subdivision::step(mesh, he, tags, w),
        Scheme::CatmullClark => super::catmull_clark::step(mesh, he, tags),
        Scheme::Butterfly => super::butterfly::step(mesh, he, tags),
        Scheme::DooSabin => {
            if tags.any_interior_sharp || tags.corner.iter().any(|&c| c) {
                return Err(Error::Unsupported {
                    what: "sharp tags with",
                    value: "Doo-Sabin subdivision".into(),
                });
            }
            Ok((super::doo_sabin::step(mesh, he)?, Features::default()))
        }
    }
}

/// `steps` steps of `scheme` with sharp `features` (boundary edges are always sharp).
pub fn subdivide(mesh: &Mesh, scheme: Scheme, steps: usize, features: &Features) -> Result<Mesh> {
    Ok(subdivide_with_features(mesh, scheme, steps, features)?.0)
}

/// Like [`subdivide`], also returning the tags of the final mesh.
pub fn subdivide_with_features(
    mesh: &Mesh,
    scheme: Scheme,
    steps: usize,
    features: &Features,
) -> Result<(Mesh, Features)> {
    if steps > 12 {
        return Err(Error::parameter("steps", steps, "at most 12"));
    }
    let mut cur = mesh.clone();
    cur.attributes = Default::default();
    let mut feat = features.clone();
    for s in 0..steps {
        let he = HalfEdgeMesh::build(&cur)?;
        if s == 0 {
            check_budget(&cur, he.edges.len(), scheme, steps)?;
        }
        let tags = feat.resolve(&he)?;
        let (next, f) = step(&cur, &he, scheme, &tags)?;
        cur = next;
        feat = f;
    }
    Ok((cur, feat))
}

/// Vertex, edge, face and corner counts of a mesh.
#[derive(Clone, Copy, Debug)]
struct Counts {
    v: u64,
    e: u64,
    f: u64,
    c: u64,
}

impl Counts {
    /// The counts after one step of `scheme`: Loop and Butterfly `V + E, 2E + 3F, 4F, 12F`
    /// (triangles); Catmull-Clark `V + E + F, 2E + C, C, 4C`; Doo-Sabin `C` vertices, at
    /// most `F + E + V` faces and `C + 6E` corners, and (bounded by) as many edges as
    /// corners.
    fn after(self, scheme: Scheme) -> Counts {
        let Counts { v, e, f, c } = self;
        let (a, b) = (u64::saturating_add, u64::saturating_mul);
        match scheme {
            Scheme::Loop(_) | Scheme::Butterfly => Counts {
                v: a(v, e),
                e: a(b(e, 2), b(f, 3)),
                f: b(f, 4),
                c: b(f, 12),
            },
            Scheme::CatmullClark => Counts {
                v: a(a(v, e), f),
                e: a(b(e, 2), c),
                f: c,
                c: b(c, 4),
            },
            Scheme::DooSabin => {
                let c2 = a(c, b(e, 6));
                Counts {
                    v: c,
                    e: c2,
                    f: a(a(f, e), v),
                    c: c2,
                }
            }
        }
    }

    /// Bytes of the mesh: positions (24 a vertex), corner indices and face offsets (4).
    fn mesh_bytes(self) -> u64 {
        self.v
            .saturating_mul(24)
            .saturating_add(self.c.saturating_add(self.f).saturating_mul(4))
    }

    /// Bytes of its half-edge structure: six `u32` a half-edge (at most two an edge),
    /// 20 an edge, 8 a corner, 4 a vertex and a face.
    fn structure_bytes(self) -> u64 {
        self.e
            .saturating_mul(68)
            .saturating_add(self.c.saturating_mul(8))
            .saturating_add(self.v.saturating_add(self.f).saturating_mul(4))
    }
}

/// What a step holds beyond the itemised bytes of [`check_budget`] (its edge points and
/// tags, the features, the writer), as a factor: the peak resident size of 5 steps on a
/// 4,802-triangle grid was 1.7× the itemised bytes with Loop and 2.3× with
/// Catmull-Clark.
const STEP_OVERHEAD: f64 = 2.5;

/// Bytes of `mesh` as [`check_budget`] counts them: positions (24 a vertex), corner
/// indices and face offsets (4).
pub(super) fn mesh_bytes(mesh: &Mesh) -> u64 {
    counts(mesh, 0).mesh_bytes()
}

/// The most bytes one step of `scheme` from `mesh` holds, as [`check_budget`] counts
/// them: [`STEP_OVERHEAD`] × (the mesh read + its half-edge structure + the mesh made),
/// its edges bounded by its corners (every edge borders a face).
pub(super) fn step_bytes(mesh: &Mesh, scheme: Scheme) -> u64 {
    let cur = counts(mesh, mesh.corner_count());
    let bytes = cur
        .mesh_bytes()
        .saturating_add(cur.structure_bytes())
        .saturating_add(cur.after(scheme).mesh_bytes());
    (bytes as f64 * STEP_OVERHEAD).min(u64::MAX as f64) as u64
}

fn counts(mesh: &Mesh, edges: usize) -> Counts {
    Counts {
        v: mesh.vertex_count() as u64,
        e: edges as u64,
        f: mesh.face_count() as u64,
        c: mesh.corner_count() as u64,
    }
}

/// Check `steps` steps of `scheme` from `mesh` (of `edges` edges) against the memory
/// budget ([`crate::limits`]) before the first: [`STEP_OVERHEAD`] times the largest of,
/// over the steps, the mesh a step reads, its half-edge structure and the mesh it makes.
fn check_budget(mesh: &Mesh, edges: usize, scheme: Scheme, steps: usize) -> Result<()> {
    let mut cur = counts(mesh, edges);
    let mut most = 0u64;
    for _ in 0..steps {
        let next = cur.after(scheme);
        let bytes = cur
            .mesh_bytes()
            .saturating_add(cur.structure_bytes())
            .saturating_add(next.mesh_bytes());
        most = most.max(bytes);
        cur = next;
    }
    let most = (most as f64 * STEP_OVERHEAD).min(u64::MAX as f64) as u64;
    crate::limits::check("subdivided mesh bytes (memory budget MRA_MAX_BYTES)", most)
}
