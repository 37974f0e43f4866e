//! Applications of the pipeline, apart from it: synthetic scenes and the project's
//! procedural shapes (tests, benchmarks, examples), overlays and the 3D view's geometry
//! for display, parallel-jaw grasps and the paper's evaluation. The pipeline modules
//! never depend on these.

pub mod eval;
pub mod grasp;
pub mod overlay;
pub mod scene_view;
pub mod shapes;
pub mod synth;
