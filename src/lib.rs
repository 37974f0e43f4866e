//! # LocaliseBot
//!
//! Multi-view 9-DoF object localisation by differentiable silhouette rendering,
//! after Vijayaraghavan et al., "LocaliseBot: Multi-view 3D object localisation
//! with differentiable rendering for robot grasping".
//!
//! The pipeline (see `ARCHITECTURE.md`):
//!
//! 1. [`io`] — bytes to [`Mesh`], [`Mask`], [`Camera`], [`Scene`];
//! 2. [`raster`] — project a posed mesh into each view; hard silhouettes, soft
//!    (SoftRas) silhouettes and their analytic backward pass;
//! 3. [`loss`] — IoU and contour (Hausdorff) losses against the masks;
//! 4. [`optim`] — coarse orientation search, then gradient refinement;
//! 5. [`metrics`] — pose errors, ADD/ADD-S, IoU, Hausdorff distance.
//!
//! The core is pure Rust: no file system, no clocks, no threads; the command line
//! (`src/main.rs`) and the WebAssembly binding (`src/wasm.rs`) wrap it.

#![warn(missing_docs)]

pub mod camera;
pub mod error;
pub mod estimator;
pub mod eval;
pub mod grasp;
pub mod io;
pub mod loss;
pub mod mask;
pub mod mesh;
pub mod metrics;
pub mod optim;
pub mod overlay;
pub mod pose;
pub mod raster;
pub mod result;
pub mod shapes;
pub mod so3;
pub mod symmetry;
pub mod synth;
pub mod verdict;
pub mod view;
#[cfg(target_arch = "wasm32")]
pub mod wasm;

pub use camera::{Camera, CameraJson, Convention};
pub use error::{Error, Result};
pub use estimator::{Estimator, FitSettings, Phase, Progress, ScaleMode, Termination};
pub use io::scene::{load_scene, Scene, SceneJson, ViewJson};
pub use mask::Mask;
pub use mesh::{Bounds, Mesh};
pub use pose::{Pose, PoseJson};
pub use result::FitResult;
pub use view::{Rgba, View};
