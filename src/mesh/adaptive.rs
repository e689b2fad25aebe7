//! (in progress)
use super::subdivide::Scheme;
use super::{Features, Mesh};
use crate::{Error, Result};

pub fn faces_in_box(_mesh: &Mesh, _lo: [f64; 3], _hi: [f64; 3]) -> Vec<u32> {
    Vec::new()
}

pub fn subdivide(
    _mesh: &Mesh,
    _scheme: Scheme,
    _steps: usize,
    _sel: &[u32],
    _f: &Features,
) -> Result<Mesh> {
    Err(Error::Unsupported {
        what: "adaptive subdivision",
        value: "not yet".into(),
    })
}
