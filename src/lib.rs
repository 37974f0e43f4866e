//! # LocaliseBot
//!
//! Multi-view 9-DoF object localisation by differentiable silhouette rendering, after
//! Vijayaraghavan et al., "LocaliseBot: Multi-view 3D object localisation with
//! differentiable rendering for robot grasping". Given a few calibrated views of an
//! object (masks, or photographs) and its mesh, [`Estimator`] finds the object's pose
//! `X_w = R·(s ⊙ X_o) + t` (rotation, translation, per-axis scale) by fitting the mesh's
//! rendered silhouette to every view, and says how sure it is.
//!
//! ```
//! use localisebot::app::{shapes, synth};
//! use localisebot::{metrics, Estimator, FitSettings, Verdict};
//!
//! // A scene made in code: the project's toy aeroplane seen by 3 cameras at a random pose.
//! let mesh = shapes::toy_plane();
//! let settings = synth::SynthSettings { views: 3, width: 160, height: 120, seed: 7, ..Default::default() };
//! let scene = synth::synthesize(&mesh, &settings, None)?;
//!
//! // Fit from no initial pose: search orientations, refine coarse to fine, judge.
//! let mut fit = Estimator::new(mesh.clone(), scene.views(), None, FitSettings::default())?;
//! while !fit.is_done() {
//!     fit.step()?; // one unit of work: a UI can draw every iteration
//! }
//! let result = fit.result(0.0, Some(&scene.pose));
//! assert_eq!(result.verdict, Some(Verdict::Ok));
//! let errors = metrics::pose_errors(&mesh, &fit.pose(), &scene.pose);
//! assert!(errors.add_rel < 0.01, "ADD {:.3} % of the diameter", 100.0 * errors.add_rel);
//! # Ok::<(), localisebot::Error>(())
//! ```
//!
//! Real scenes come from files: [`load_scene`] reads a `scene.json` (SPEC §3) with a
//! resolver for the files it names, and [`io`] reads meshes (glTF, OBJ, PLY), masks and
//! images, and imports BOP and NeRF datasets. [`FitSettings`] holds every choice the fit
//! makes, with its vocabulary at the crate root ([`Optimiser`], [`Sampling`],
//! [`WindowMode`], [`RasterKind`], [`ScaleMode`], …); [`FitSettings::default`] is the
//! one default of the command line, the browser and the npm package. A finished fit
//! gives a [`FitResult`] (pose, per-view figures, a [`Verdict`], the pose's
//! [`Uncertainty`]) and can suggest the next view ([`Estimator::suggest_views`]).
//! [`app`] holds what is built on the fit: synthetic scenes, procedural shapes,
//! overlays, grasps and the paper's evaluation; [`metrics`] the pose errors and IoUs.
//!
//! The pipeline's stages are modules of their own (`ARCHITECTURE.md`): `raster`
//! (projection, hard and soft silhouettes and their analytic derivatives), `loss` (the
//! views' targets and the objective `λ1·IoU + λ2·contour`), `optim` (initialisation,
//! orientation search, schedule, Adam and Levenberg–Marquardt), `uncertainty`, `so3` and
//! `symmetry`. They are public for the project's kernel tests and benchmarks (oracles
//! and finite-difference checks of every gradient) but hidden from this manual and
//! carry no stability promise. The core is pure Rust — no file system, no clock — and
//! uses threads (rayon) only natively; the command line (`src/main.rs`) and the
//! WebAssembly binding (module `wasm`, on wasm32) wrap it.

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
pub mod limits;
pub mod metrics;

// Stage modules: public for the kernel tests and benchmarks, not part of the manual.
#[doc(hidden)]
pub mod loss;
#[doc(hidden)]
pub mod optim;
#[doc(hidden)]
pub mod raster;
pub mod segment;
#[doc(hidden)]
pub mod so3;
#[doc(hidden)]
pub mod symmetry;
#[doc(hidden)]
pub mod uncertainty;
#[cfg(target_arch = "wasm32")]
pub mod wasm;

pub use camera::{Camera, CameraJson, Convention, MAX_SIDE};
pub use error::{Error, Result};
pub use estimator::{
    competes, Alternative, AlternativeOut, CameraCorrection, CameraPrior, CameraTest, Estimator, FitResult,
    FitSettings, FitSetup, MaskReport, Phase, PoseOut, Progress, Request, Response, Shard, Termination, ViewFigures,
    ViewResult, ALTERNATIVE_FACTOR, ALTERNATIVE_SLACK, OBJECT_MARGIN,
};
pub use io::scene::{load_scene, Scene, SceneJson, ViewJson};
pub use limits::Limits;
pub use loss::objective::ObjectiveSettings;
pub use mask::Mask;
pub use mesh::{Bounds, Mesh};
pub use optim::adam::AdamSettings;
pub use optim::params::ScaleMode;
pub use optim::schedule::{Optimiser, StageSettings};
pub use optim::search::{Sampling, SearchSettings};
pub use pose::{mat3_from_rows, mat3_to_rows, mat4_from_rows, mat4_to_rows, Mat9, Pose, PoseJson, RotationJson, Vec9};
pub use raster::silhouette::{RasterKind, SoftSettings};
pub use uncertainty::{NoiseModel, RankedView, StdDev, Uncertainty, Viewpoints};
pub use verdict::{judge, Judgement, Verdict, VerdictThresholds};
pub use view::{PhotoView, PixelBox, Rgba, View, ViewSources};
pub use window::{Window, WindowMode};
