//! Solid modelling (notes chapter 10): implicit models, CSG, polygonisation.
//!
//! Convention of the notes (§10.4): a solid is `F(p) > 0` inside, `F(p) < 0` outside,
//! `F(p) = 0` on its surface. Union is `max`, intersection `min`, difference
//! `min(F_A, −F_B)`; blending adds skeletal fields and subtracts a threshold (§10.5).
//!
//! ```text
//! field.rs      primitives, skeletal fields (Blinn, metaball, Wyvill), Booleans, blends, gradients
//! scene.rs      the JSON scene format, with errors naming the place
//! tlist.rs      interval lists along rays, exact ray–primitive hits, CSG combination, volume
//! mc.rs         marching cubes on a sampled grid (shared vertices, manifold output)
//! render.rs     ray casting with Lambert + Phong shading
//! voxel.rs      sampling a scene on a grid / into a volume raster
//! hyperpatch.rs trivariate tensor-product B-spline volumes (§10.2)
//! ffd.rs        free-form deformation of meshes by a hyper-patch lattice (Sederberg–Parry)
//! ```

pub mod ffd;
pub mod field;
pub mod hyperpatch;
pub mod mc;
pub mod render;
pub mod scene;
pub mod tlist;
pub mod voxel;

pub use field::{Falloff, Node, Skeleton};
pub use scene::Scene;
