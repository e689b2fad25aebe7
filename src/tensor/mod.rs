//! Tensor-product engine: N-d arrays, one level along any axis, multilevel pyramids in
//! the standard and the non-standard (Mallat) order. `par.rs` holds the
//! engine's own parallel helpers and the one job queue of the pool, the tiled codec's
//! (other modules call rayon directly where they split work).

mod aligned;
mod array;
mod boxes;
mod cascade;
mod fused;
mod pages;
pub(crate) mod par;
pub mod pyramid;
mod resample;
mod ring;
pub mod stream;
mod transform;
mod window;
mod workspace;

pub use crate::kernel::Kernels;
pub use array::{Array, Axis};
pub use boxes::for_each_run;
pub use pages::{advise_huge_pages, zeroed_vec};
pub use pyramid::{
    analyze, analyze_in, analyze_with, synthesize, synthesize_in, synthesize_with, Engine, Order,
    Pyramid, PyramidSpec, Subband,
};
pub use resample::{map_lanes, resample_axis, resample_axis_in, resample_axis_with};
pub use transform::{transform_axis, transform_axis_with};
pub use window::WindowPlan;
pub(crate) use window::{box_lists, for_each_index, gather, reads_of};
pub use workspace::Planner;
