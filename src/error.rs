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
    /// A mask (or ignore mask) whose size is not its camera's.
    #[error("view '{view}': mask '{file}': is {}×{} but the camera is {}×{}{}", size.0, size.1, expected.0, expected.1, resized_hint(*size, *expected))]
    MaskSize {
        /// The view's name.
        view: String,
        /// The mask file's name.
        file: String,
        /// Its width and height.
        size: (u32, u32),
        /// The camera's width and height.
        expected: (u32, u32),
    },
    /// A mask with no object pixel (or none outside the ignore mask).
    #[error("view '{view}': mask '{file}': {}", if *ignored { "every object pixel is in the ignore mask: nothing is left to fit" } else { "is empty: no pixel is marked as object" })]
    EmptyMask {
        /// The view's name.
        view: String,
        /// The mask file's name.
        file: String,
        /// Whether the mask has object pixels, all of them ignored.
        ignored: bool,
    },
    /// An image whose size is not its camera's.
    #[error("view '{view}': image '{file}': is {}×{} but the camera is {}×{}{}", size.0, size.1, expected.0, expected.1, resized_hint(*size, *expected))]
    ImageSize {
        /// The view's name.
        view: String,
        /// The image file's name.
        file: String,
        /// Its width and height.
        size: (u32, u32),
        /// The camera's width and height.
        expected: (u32, u32),
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
    /// An input beyond a stated limit (see [`crate::limits`]), refused before it was
    /// read or allocated.
    #[error("{file}: {problem}")]
    Limit {
        /// The file (or view) refused.
        file: String,
        /// Which limit, the value and how to raise it.
        problem: String,
    },
}

/// What to add when a photograph or mask is its camera's picture resized (the same aspect, to
/// within a pixel either way): by how much to scale the intrinsics. Empty otherwise.
fn resized_hint(size: (u32, u32), camera: (u32, u32)) -> String {
    let k = size.0 as f64 / camera.0 as f64;
    let same_aspect = (camera.1 as f64 * k - size.1 as f64).abs() <= 1.0;
    if size.0 == 0 || camera.0 == 0 || !same_aspect || size == camera {
        return String::new();
    }
    format!(
        " (the same shape, {k:.4}× the size: if the pictures were resized after calibration, scale \
         the camera with it — width and height {}×{}, fx and fy times {k:.4}, cx and cy to (c + 0.5)·{k:.4} − 0.5)",
        size.0, size.1
    )
}

/// Result with the crate's [`Error`](enum@Error).
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resized_photograph_is_told_how_to_scale_its_camera() {
        let e = |size, expected| {
            Error::ImageSize {
                view: "left".into(),
                file: "a.jpg".into(),
                size,
                expected,
            }
            .to_string()
        };
        let half = e((2016, 1512), (4032, 3024));
        assert!(
            half.starts_with(
                "view 'left': image 'a.jpg': is 2016×1512 but the camera is 4032×3024 (the same shape, 0.5000×"
            ) && half
                .contains("width and height 2016×1512, fx and fy times 0.5000, cx and cy to (c + 0.5)·0.5000 − 0.5"),
            "{half}"
        );
        // An odd side rounded by the resizer is still the same shape.
        assert!(e((1001, 751), (2002, 1501)).contains("0.5000×"));
        // Another shape: the sizes alone.
        assert_eq!(
            e((640, 640), (640, 480)),
            "view 'left': image 'a.jpg': is 640×640 but the camera is 640×480"
        );
        assert!(!e((0, 0), (640, 480)).contains("same shape"));
    }
}
