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
    for _ in 0..steps {
        let he = HalfEdgeMesh::build(&cur)?;
        let tags = feat.resolve(&he)?;
        let (next, f) = step(&cur, &he, scheme, &tags)?;
        cur = next;
        feat = f;
    }
    Ok((cur, feat))
}
