//! The one error type of the core.
//!
//! Every message names what a user can act on: the file, the view and the problem.
//! The command line prints it on one line; the wasm binding turns it into a
//! JavaScript `Error` carrying the same text.

use thiserror::Error;

/// Everything that can go wrong between bytes in and a pose out.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A mesh file could not be read or is not supported.
    #[error("mesh '{file}': {problem}")]
    Mesh {
        /// The mesh file's name.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A camera is invalid (non-finite, non-positive focal length, non-orthonormal rotation…).
    #[error("view '{view}': camera: {problem}")]
    Camera {
        /// The view's name.
        view: String,
        /// What is wrong with the camera.
        problem: String,
    },
    /// A mask could not be decoded, has the wrong size or is empty.
    #[error("view '{view}': mask '{file}': {problem}")]
    Mask {
        /// The view's name.
        view: String,
        /// The mask file's name.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// An image could not be decoded or has the wrong size.
    #[error("view '{view}': image '{file}': {problem}")]
    Image {
        /// The view's name.
        view: String,
        /// The image file's name.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A scene, pose or result JSON file is malformed.
    #[error("{file}: {problem}")]
    Json {
        /// The JSON file's name.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A file the scene refers to was not supplied.
    #[error("{file}: file not found (referred to by {referrer})")]
    MissingFile {
        /// The missing file's path as written in the referrer.
        file: String,
        /// Which file or entry referred to it.
        referrer: String,
    },
    /// The object cannot be seen in a view (behind the camera, off the canvas).
    #[error("view '{view}': {problem}")]
    View {
        /// The view's name.
        view: String,
        /// What is wrong.
        problem: String,
    },
    /// A pose is invalid (non-finite, non-positive scale, non-orthonormal rotation).
    #[error("pose: {0}")]
    Pose(String),
    /// Settings or arguments out of range.
    #[error("invalid setting: {0}")]
    Settings(String),
    /// A set of dropped or chosen files does not make one scene (none given, several
    /// scene files or meshes, a view without a mask…).
    #[error("{0}")]
    Files(String),
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
