//! (in progress)
use super::Mesh;
use crate::{Error, Result};

pub fn simplify(_mesh: &Mesh, _faces: usize) -> Result<Mesh> {
    Err(Error::Unsupported {
        what: "simplification",
        value: "not yet".into(),
    })
}
