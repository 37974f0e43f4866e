//! The grasp's wire form: an entry of `scene.json`'s `grasps` list, parsed and
//! validated into a [`Grasp`] (the model-frame grasp that `crate::app::grasp` carries
//! to the world, projects and scores).
//!
//! # The JSON form
//!
//! ```json
//! { "centre": [0.0, 0.0, 0.1], "approach": [0, 0, -1], "closing": [1, 0, 0],
//!   "width": 0.05, "depth": 0.02, "score": 0.9 }
//! ```
//!
//! All in the OBJECT (model) frame and model units:
//! * `centre` (3 numbers; `center` is accepted): the point midway between the two
//!   finger contacts.
//! * `approach` (3): the direction the gripper moves along to reach the object (from
//!   the palm towards the centre). Must have length 1 ± 0.01; it is normalised.
//! * `closing` (3): the direction the fingers close along (the line through both
//!   contacts; its sign does not matter). Length 1 ± 0.01, normalised; it must be
//!   perpendicular to `approach` within 3° (|cos| ≤ 0.05), and `approach` is then
//!   made exactly perpendicular to it (Gram–Schmidt, `closing` kept).
//! * `width` (> 0): the opening between the fingers.
//! * `depth` (> 0): how far the fingers reach along `approach` (palm to centre).
//! * `score` (optional, finite): a confidence, carried along but unused by the metric.
//!
//! Unknown keys are an error (a misspelt key would otherwise be silently ignored).

use crate::error::{Error, Result};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How far from 1 the length of `approach`/`closing` may be before it is an error.
const UNIT_TOLERANCE: f64 = 0.01;
/// Largest |cos| between `approach` and `closing` (about 3° from perpendicular).
const PERPENDICULAR_TOLERANCE: f64 = 0.05;

/// A parallel-jaw grasp in the object (model) frame; see the module docs for the JSON
/// form and how a pose acts on it. Built only through validation ([`Grasp::new`],
/// [`Grasp::from_json`] or deserialising), so `approach` and `closing` are orthonormal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GraspJson", into = "GraspJson")]
pub struct Grasp {
    /// Midpoint between the finger contacts (model units).
    pub centre: DVec3,
    /// Unit direction the gripper moves along to reach the object.
    pub approach: DVec3,
    /// Unit direction the fingers close along, perpendicular to `approach`.
    pub closing: DVec3,
    /// Opening between the fingers (model units, > 0).
    pub width: f64,
    /// Finger depth along `approach` (model units, > 0).
    pub depth: f64,
    /// Optional confidence.
    pub score: Option<f64>,
}

/// The wire form of a [`Grasp`] (see the module docs), before validation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspJson {
    /// Midpoint between the finger contacts.
    #[serde(alias = "center")]
    pub centre: [f64; 3],
    /// Direction the gripper moves along to reach the object (unit).
    pub approach: [f64; 3],
    /// Direction the fingers close along (unit, ⟂ approach).
    pub closing: [f64; 3],
    /// Opening between the fingers.
    pub width: f64,
    /// Finger depth along the approach.
    pub depth: f64,
    /// Optional confidence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub score: Option<f64>,
}

impl TryFrom<GraspJson> for Grasp {
    type Error = String;
    fn try_from(j: GraspJson) -> std::result::Result<Grasp, String> {
        Grasp::validated(
            DVec3::from_array(j.centre),
            DVec3::from_array(j.approach),
            DVec3::from_array(j.closing),
            j.width,
            j.depth,
            j.score,
        )
    }
}

impl From<Grasp> for GraspJson {
    fn from(g: Grasp) -> GraspJson {
        GraspJson {
            centre: g.centre.to_array(),
            approach: g.approach.to_array(),
            closing: g.closing.to_array(),
            width: g.width,
            depth: g.depth,
            score: g.score,
        }
    }
}

fn unit(name: &str, v: DVec3) -> std::result::Result<DVec3, String> {
    let n = v.length();
    if (n - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!(
            "{name} must be a unit vector, got {:?} (length {n:.4})",
            v.to_array()
        ));
    }
    Ok(v / n)
}

impl Grasp {
    /// A validated grasp (rules of the module docs; `approach` is orthogonalised
    /// against `closing`). The error names the offending field.
    pub fn new(centre: DVec3, approach: DVec3, closing: DVec3, width: f64, depth: f64) -> Result<Grasp> {
        Self::validated(centre, approach, closing, width, depth, None).map_err(|problem| Error::Json {
            file: "grasp".into(),
            problem,
        })
    }

    fn validated(
        centre: DVec3,
        approach: DVec3,
        closing: DVec3,
        width: f64,
        depth: f64,
        score: Option<f64>,
    ) -> std::result::Result<Grasp, String> {
        for (name, v) in [("centre", centre), ("approach", approach), ("closing", closing)] {
            if !v.is_finite() {
                return Err(format!("{name} contains a non-finite number"));
            }
        }
        let approach = unit("approach", approach)?;
        let closing = unit("closing", closing)?;
        let cos = approach.dot(closing);
        if cos.abs() > PERPENDICULAR_TOLERANCE {
            return Err(format!(
                "closing must be perpendicular to approach, but they are {:.1}° apart",
                cos.clamp(-1.0, 1.0).acos().to_degrees()
            ));
        }
        let approach = (approach - cos * closing).normalize();
        if !(width.is_finite() && width > 0.0) {
            return Err(format!("width must be positive, got {width}"));
        }
        if !(depth.is_finite() && depth > 0.0) {
            return Err(format!("depth must be positive, got {depth}"));
        }
        if let Some(s) = score.filter(|s| !s.is_finite()) {
            return Err(format!("score must be finite, got {s}"));
        }
        Ok(Grasp {
            centre,
            approach,
            closing,
            width,
            depth,
            score,
        })
    }

    /// Parses and validates one entry of `scene.json`'s `grasps` list. Errors are
    /// [`Error::Json`] with file `"grasp"` and the problem (use [`grasps_from_json`] to
    /// have the scene file and the entry's index named).
    pub fn from_json(value: &serde_json::Value) -> Result<Grasp> {
        Self::parse(value).map_err(|problem| Error::Json {
            file: "grasp".into(),
            problem,
        })
    }

    fn parse(value: &serde_json::Value) -> std::result::Result<Grasp, String> {
        let j = GraspJson::deserialize(value).map_err(|e| e.to_string())?;
        Grasp::try_from(j)
    }

    /// The JSON form (the inverse of [`Grasp::from_json`]; `score` only when present).
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::json!({
            "centre": self.centre.to_array(),
            "approach": self.approach.to_array(),
            "closing": self.closing.to_array(),
            "width": self.width,
            "depth": self.depth,
        });
        if let (Some(s), Some(map)) = (self.score, v.as_object_mut()) {
            map.insert("score".into(), serde_json::json!(s));
        }
        v
    }

    /// The two finger contacts `centre ∓ (width/2)·closing` (model frame).
    pub fn contacts(&self) -> [DVec3; 2] {
        let h = 0.5 * self.width * self.closing;
        [self.centre - h, self.centre + h]
    }
}

/// Parses every entry of a `grasps` list; an error names `file` and the entry, e.g.
/// `scene.json: grasps[2]: width must be positive, got -1`.
pub fn grasps_from_json(values: &[serde_json::Value], file: &str) -> Result<Vec<Grasp>> {
    values
        .iter()
        .enumerate()
        .map(|(i, v)| {
            Grasp::parse(v).map_err(|p| Error::Json {
                file: file.into(),
                problem: format!("grasps[{i}]: {p}"),
            })
        })
        .collect()
}
