//! # LocaliseBot
//!
//! Multi-view 9-DoF object localisation by differentiable silhouette rendering,
//! after Vijayaraghavan et al., "LocaliseBot: Multi-view 3D object localisation
//! with differentiable rendering for robot grasping".
//!
//! The pipeline (see `ARCHITECTURE.md`), one public module per stage:
//!
//! 1. [`io`] — bytes to a [`Mesh`] and [`View`]s (camera, [`Mask`], optional ignore
//!    mask and image) of a [`Scene`];
//! 2. [`raster`] — project a posed mesh into a view; hard silhouettes, soft
//!    silhouettes (SoftRas, and the silhouette-edge variant) and their analytic
//!    backward passes;
//! 3. [`loss`] — each view's target in its object window, and the one objective
//!    `λ1·IoU + λ2·contour` with its gradient and Gauss–Newton model;
//! 4. [`optim`] — initialisation, the coarse orientation search, the coarse-to-fine
//!    schedule, Adam and Levenberg–Marquardt;
//! 5. [`Estimator`] — the pipeline as a step-wise object, ending in a [`FitResult`]
//!    with a [`Verdict`];
//! 6. [`metrics`], [`symmetry`] — pose errors, ADD/ADD-S, IoU, Hausdorff distance.
//!
//! [`app`] holds what is built on the pipeline: synthetic scenes, procedural shapes,
//! overlays, grasps and the paper's evaluation. The core is pure Rust: no file
//! system, no clocks, no threads; the command line (`src/main.rs`) and the
//! WebAssembly binding (`src/wasm.rs`) wrap it.

#![warn(missing_docs)]

mod camera;
mod error;
mod estimator;
mod mask;
mod mesh;
mod pose;
mod verdict;
mod view;
mod window;

pub mod app;
pub mod io;
pub mod loss;
pub mod metrics;
pub mod optim;
pub mod raster;
pub mod so3;
pub mod symmetry;
pub mod uncertainty;
#[cfg(target_arch = "wasm32")]
pub mod wasm;

pub use camera::{Camera, CameraJson, Convention, MAX_SIDE};
pub use error::{Error, Result};
pub use estimator::{
    robust_weights, CameraCorrection, CameraPrior, CameraTest, Estimator, FitResult, FitSettings, FitSetup, Phase,
    PoseOut, Progress, Request, Response, Shard, Termination, ViewFigures, ViewResult, OBJECT_MARGIN,
};
pub use io::scene::{load_scene, Scene, SceneJson, ViewJson};
pub use mask::Mask;
pub use mesh::{Bounds, Mesh};
pub use optim::params::ScaleMode;
pub use pose::{mat3_from_rows, mat3_to_rows, mat4_from_rows, mat4_to_rows, Mat9, Pose, PoseJson, RotationJson, Vec9};
pub use verdict::{judge, Judgement, Verdict, VerdictThresholds};
pub use view::{Rgba, View, ViewSources};
pub use window::{Window, WindowMode};
