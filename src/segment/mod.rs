//! Masks from photographs (SPEC §3, "Photographs without masks"): the stage before the
//! fit when a view gives its photograph and a box — or only its photograph — instead
//! of a mask. [`hints`] places the boxes the geometry implies; [`prompt`] says what
//! the segmenter is asked ([`SegmentJob`]: a square crop of the photograph and a box,
//! points and the previous mask in its pixels) and how a fitted pose prompts again;
//! [`photo`] runs the rounds of segmenting and fitting ([`PhotoFit`]) in which the
//! geometry corrects the segmenter. The segmenter itself — a neural network run by an
//! inference engine — is outside the core: anything that answers jobs
//! ([`Segmenter`]): natively [`SamSegmenter`] (the `localisebot-segment` crate), in the browser its own
//! wasm module in the page's Workers.

pub mod hints;
pub mod photo;
pub mod prompt;
#[cfg(not(target_arch = "wasm32"))]
pub mod sam;

pub use photo::{run, PhotoFit, PhotoSettings, Segmenter};
pub use prompt::{Crop, MaskCandidate, PromptPoint, SegmentJob, SegmentOutput};
#[cfg(not(target_arch = "wasm32"))]
pub use sam::SamSegmenter;
