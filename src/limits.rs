//! What an input may be, checked before anything is allocated for it: the sizes
//! ([`Limits`]: file bytes, pixels per view and in all, views, a mesh's vertices and
//! triangles; settable, natively and in wasm) read from headers and declared counts,
//! the nesting of JSON ([`MAX_JSON_DEPTH`]), and the magnitudes a number from outside
//! may have ([`MAX_LENGTH`], the focal and scale ranges, [`MAX_BOX_PX`]), beyond which
//! the maths would overflow or lose every digit. A refusal names the file (or view),
//! the limit and how to raise it.
//!
//! The table of limits is in README ("Limits").

use crate::error::{Error, Result};

/// Sizes an input may have. [`Limits::DEFAULT`] is what every reader uses unless told
/// otherwise (the CLI's `--limit NAME=VALUE`, the binding's `FileSet.setLimit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Bytes of one file (`file_bytes`).
    pub file_bytes: u64,
    /// Pixels of one view: its camera's width × height (`view_pixels`).
    pub view_pixels: u64,
    /// Pixels of all a scene's views together (`total_pixels`).
    pub total_pixels: u64,
    /// Views of a scene (`views`).
    pub views: u64,
    /// Vertices of a mesh, as its file declares them (`vertices`).
    pub vertices: u64,
    /// Triangles of a mesh, as its file declares them, polygons counted as fans (`triangles`).
    pub triangles: u64,
}

/// Deepest nesting of arrays and objects accepted in any JSON file (scene, camera,
/// pose, glTF, BOP, NeRF); none of the formats needs more than 8.
pub const MAX_JSON_DEPTH: usize = 64;

/// Largest magnitude of a length from outside (mesh coordinates, translations of
/// cameras and poses, in the file's unit): beyond it, squared distances lose the
/// object's size to rounding, and overflow at 1e154.
pub const MAX_LENGTH: f64 = 1e12;

/// Smallest and largest focal length, pixels.
pub const FOCAL_RANGE_PX: (f64, f64) = (1e-3, 1e8);

/// Largest magnitude of a principal point coordinate, pixels.
pub const MAX_PRINCIPAL_PX: f64 = 1e8;

/// Smallest and largest factor of a pose's scale.
pub const SCALE_RANGE: (f64, f64) = (1e-6, 1e6);

/// Largest magnitude of a box hint's coordinate, pixels (a box may reach past the
/// image, never this far).
pub const MAX_BOX_PX: f64 = 1e6;

impl Limits {
    /// The defaults: 1 GiB files; 64 Mpx a view (a 50-Mpx phone photograph fits),
    /// 256 Mpx in all (twenty-two 12-Mpx photographs); 256 views; 10 million vertices and
    /// triangles (scans decimated for use; a 1-million-triangle scan is well inside).
    pub const DEFAULT: Limits = Limits {
        file_bytes: 1 << 30,
        view_pixels: 64 << 20,
        total_pixels: 256 << 20,
        views: 256,
        vertices: 10_000_000,
        triangles: 10_000_000,
    };

    /// The names [`Limits::set`] knows, with a line on each.
    pub const NAMES: [(&'static str, &'static str); 6] = [
        ("file_bytes", "bytes of one file"),
        ("view_pixels", "pixels of one view (width × height)"),
        ("total_pixels", "pixels of all views together"),
        ("views", "views of a scene"),
        ("vertices", "vertices of a mesh"),
        ("triangles", "triangles of a mesh"),
    ];

    /// Sets the limit `name` (see [`Limits::NAMES`]) to `value` (at least 1).
    pub fn set(&mut self, name: &str, value: u64) -> Result<()> {
        if value == 0 {
            return Err(Error::Settings(format!("limit {name}: must be at least 1")));
        }
        let slot = match name {
            "file_bytes" => &mut self.file_bytes,
            "view_pixels" => &mut self.view_pixels,
            "total_pixels" => &mut self.total_pixels,
            "views" => &mut self.views,
            "vertices" => &mut self.vertices,
            "triangles" => &mut self.triangles,
            _ => {
                let known: Vec<&str> = Self::NAMES.iter().map(|(n, _)| *n).collect();
                return Err(Error::Settings(format!(
                    "unknown limit '{name}' (known: {})",
                    known.join(", ")
                )));
            }
        };
        *slot = value;
        Ok(())
    }

    /// Sets a limit from `NAME=VALUE` text (the CLI's `--limit`).
    pub fn set_text(&mut self, text: &str) -> Result<()> {
        let (name, value) = text
            .split_once('=')
            .ok_or_else(|| Error::Settings(format!("limit '{text}': expected NAME=VALUE")))?;
        let value: u64 = value
            .trim()
            .replace('_', "")
            .parse()
            .map_err(|_| Error::Settings(format!("limit '{text}': the value must be a whole number")))?;
        self.set(name.trim(), value)
    }

    /// The refusal of `what` (`value`, over the limit `name`); `file` names the input.
    pub fn refusal(file: &str, what: &str, value: u64, name: &str, limit: u64) -> Error {
        Error::Limit {
            file: file.into(),
            problem: format!(
                "{what} {value} exceeds the limit of {limit} ({name}; raise it with --limit {name}=N, \
                 or FileSet.setLimit('{name}', N) in the page's package)"
            ),
        }
    }

    /// Checks a file's size before it is read.
    pub fn check_file(&self, file: &str, bytes: u64) -> Result<()> {
        if bytes > self.file_bytes {
            return Err(Self::refusal(
                file,
                "the file's size in bytes",
                bytes,
                "file_bytes",
                self.file_bytes,
            ));
        }
        Ok(())
    }

    /// Checks a mesh's declared counts before its data is read.
    pub fn check_mesh(&self, file: &str, vertices: u64, triangles: u64) -> Result<()> {
        if vertices > self.vertices {
            return Err(Self::refusal(
                file,
                "the mesh's vertex count",
                vertices,
                "vertices",
                self.vertices,
            ));
        }
        if triangles > self.triangles {
            return Err(Self::refusal(
                file,
                "the mesh's triangle count",
                triangles,
                "triangles",
                self.triangles,
            ));
        }
        Ok(())
    }

    /// Checks a scene's view count.
    pub fn check_views(&self, file: &str, views: u64) -> Result<()> {
        if views > self.views {
            return Err(Self::refusal(file, "the number of views", views, "views", self.views));
        }
        Ok(())
    }

    /// Checks one view's pixels and the running total (including it), before its
    /// mask or image is decoded.
    pub fn check_pixels(&self, view: &str, width: u32, height: u32, total: u64) -> Result<()> {
        let px = width as u64 * height as u64;
        let name = format!("view '{view}'");
        if px > self.view_pixels {
            return Err(Self::refusal(
                &name,
                &format!("a camera of {width}×{height}: pixels"),
                px,
                "view_pixels",
                self.view_pixels,
            ));
        }
        if total > self.total_pixels {
            return Err(Self::refusal(
                &name,
                "the pixels of this and the earlier views",
                total,
                "total_pixels",
                self.total_pixels,
            ));
        }
        Ok(())
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

/// Checks that JSON `text` nests arrays and objects at most [`MAX_JSON_DEPTH`] deep
/// (a scan of the bytes, strings skipped, before any parser allocates).
pub fn check_json_depth(file: &str, text: &[u8]) -> Result<()> {
    let (mut depth, mut in_string, mut escaped) = (0usize, false, false);
    for &b in text {
        if in_string {
            match b {
                _ if escaped => escaped = false,
                b'\\' => escaped = true,
                b'"' => in_string = false,
                _ => {}
            }
            continue;
        }
        match b {
            b'"' => in_string = true,
            b'[' | b'{' => {
                depth += 1;
                if depth > MAX_JSON_DEPTH {
                    return Err(Error::Limit {
                        file: file.into(),
                        problem: format!("JSON nested deeper than {MAX_JSON_DEPTH} levels (arrays and objects)"),
                    });
                }
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    Ok(())
}

/// `None` when `v` is a length this crate can work with (finite, |v| ≤ [`MAX_LENGTH`]),
/// else the problem.
pub fn length_problem(v: f64) -> Option<String> {
    if !v.is_finite() {
        Some("is not a finite number".into())
    } else if v.abs() > MAX_LENGTH {
        Some(format!("{v:e} is beyond ±{MAX_LENGTH:e} (the largest length accepted)"))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_set_by_name_and_refusals_name_the_limit() {
        let mut l = Limits::DEFAULT;
        l.set_text("triangles=2_000").unwrap();
        assert_eq!(l.triangles, 2000);
        assert!(l
            .set_text("pixels=3")
            .unwrap_err()
            .to_string()
            .contains("unknown limit 'pixels'"));
        assert!(l.set_text("views=0").is_err() && l.set_text("views").is_err() && l.set_text("views=-1").is_err());
        let e = l.check_mesh("scan.ply", 10, 2001).unwrap_err().to_string();
        assert!(
            e.contains("scan.ply") && e.contains("2001") && e.contains("--limit triangles=N"),
            "{e}"
        );
        assert!(l.check_mesh("scan.ply", 10, 2000).is_ok());
        let e = Limits::DEFAULT
            .check_pixels("a", 16384, 16384, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("view 'a'") && e.contains("view_pixels"), "{e}");
        let e = Limits::DEFAULT
            .check_pixels("b", 4032, 3024, 300 << 20)
            .unwrap_err()
            .to_string();
        assert!(e.contains("total_pixels"), "{e}");
        assert!(Limits::DEFAULT.check_pixels("c", 4032, 3024, 8 * 4032 * 3024).is_ok());
    }

    #[test]
    fn json_depth_counts_brackets_outside_strings() {
        let deep = "[".repeat(MAX_JSON_DEPTH + 1);
        let e = check_json_depth("s.json", deep.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("s.json") && e.contains("deeper than 64"), "{e}");
        let ok = format!("{}{}", "[".repeat(MAX_JSON_DEPTH), "]".repeat(MAX_JSON_DEPTH));
        check_json_depth("s.json", ok.as_bytes()).unwrap();
        let quoted = format!("{{\"a\": \"{}\\\"[\"}}", "[".repeat(500));
        check_json_depth("s.json", quoted.as_bytes()).unwrap();
    }

    #[test]
    fn lengths_beyond_the_limit_or_not_finite_are_problems() {
        assert!(length_problem(1e12).is_none() && length_problem(-0.0).is_none() && length_problem(1e-310).is_none());
        assert!(length_problem(1.1e12).is_some() && length_problem(f64::NAN).is_some());
    }
}
