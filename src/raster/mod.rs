//! Rasterisation: projection of the posed mesh, hard (binary) silhouettes and
//! soft (SoftRas) silhouettes with their analytic backward pass.

pub mod edge;
pub mod hard;
pub mod project;
pub mod shade;
pub mod soft;
pub mod soft_backward;
mod tiles;
