//! Grasp rectangles in the image: the OCID/Cornell angle, the polygon IoU of two
//! rectangles, the "correct grasp" test and the `.txt` annotation format.
//!
//! A rectangle is `[DVec2; 4]`, its corners in pixels in order (p0→p1 is the opening,
//! p1→p2 a jaw). The reference is grasp_det_seg_cnn (FORMATS.md §5):
//! `prepare_frcnn_format` for the angle `θ = arctan((y1−y0)/(x0−x1))`, `θ° = deg(θ) + 90`
//! in [0, 180), and `calc_jacc_IOU` for correctness (|Δθ| < 30° modulo 180° and
//! shapely polygon IoU > 0.25). The IoU here clips convex polygons (Sutherland–Hodgman)
//! and measures areas with the shoelace formula.

use crate::error::{Error, Result};
use glam::DVec2;
use std::fmt::Write;

/// Largest angle difference (degrees, modulo 180°) of a correct grasp (exclusive).
pub const ANGLE_TOLERANCE_DEG: f64 = 30.0;
/// IoU a correct grasp must exceed.
pub const IOU_THRESHOLD: f64 = 0.25;

/// The rectangle's angle in degrees, in [0, 180): the angle of edge p0→p1 with the
/// image y axis flipped, plus 90° (`degrees(arctan((y1−y0)/(x0−x1))) + 90`). A vertical
/// p0→p1 gives 0. NaN when p0 = p1.
pub fn rectangle_angle_deg(r: &[DVec2; 4]) -> f64 {
    let (dy, dx) = (r[1].y - r[0].y, r[0].x - r[1].x);
    if dx == 0.0 && dy == 0.0 {
        return f64::NAN;
    }
    ((dy / dx).atan().to_degrees() + 90.0).rem_euclid(180.0)
}

/// The difference of two undirected angles in degrees, in [0, 90]
/// (`min(|a − b| mod 180, 180 − |a − b| mod 180)`); NaN if either is.
pub fn angle_difference_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).abs().rem_euclid(180.0);
    d.min(180.0 - d)
}

/// Signed shoelace area (positive for counter-clockwise in x-right/y-up axes).
fn signed_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() * 0.5
}

/// The rectangle's (unsigned) area in square pixels; 0 for a degenerate one.
pub fn rectangle_area(r: &[DVec2; 4]) -> f64 {
    signed_area(r).abs()
}

/// Sutherland–Hodgman: the part of `subject` on the left of the directed line a→b.
fn clip_half_plane(subject: &[DVec2], a: DVec2, b: DVec2) -> Vec<DVec2> {
    let e = b - a;
    let side = |p: DVec2| e.perp_dot(p - a);
    let mut out = Vec::with_capacity(subject.len() + 2);
    for i in 0..subject.len() {
        let (p, q) = (subject[i], subject[(i + 1) % subject.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            out.push(p + (q - p) * (sp / (sp - sq)));
        }
    }
    out
}

/// The area of the intersection of two convex polygons (either orientation).
fn convex_intersection_area(a: &[DVec2], b: &[DVec2]) -> f64 {
    let mut clip: Vec<DVec2> = b.to_vec();
    if signed_area(&clip) < 0.0 {
        clip.reverse();
    }
    let mut poly: Vec<DVec2> = a.to_vec();
    for i in 0..clip.len() {
        if poly.len() < 3 {
            return 0.0;
        }
        poly = clip_half_plane(&poly, clip[i], clip[(i + 1) % clip.len()]);
    }
    if poly.len() < 3 {
        0.0
    } else {
        signed_area(&poly).abs()
    }
}

/// Intersection over union of two rectangles (any convex quadrilaterals, corners in
/// either orientation; a self-intersecting corner order is outside the contract).
/// 0 when either is degenerate or a corner is not finite.
pub fn rectangle_iou(a: &[DVec2; 4], b: &[DVec2; 4]) -> f64 {
    if !a.iter().chain(b).all(|p| p.is_finite()) {
        return 0.0;
    }
    let (area_a, area_b) = (rectangle_area(a), rectangle_area(b));
    if area_a <= 0.0 || area_b <= 0.0 {
        return 0.0;
    }
    let inter = convex_intersection_area(a, b).min(area_a).min(area_b);
    inter / (area_a + area_b - inter)
}

/// The OCID/Cornell test: the angles differ by less than [`ANGLE_TOLERANCE_DEG`]
/// modulo 180° and the IoU exceeds [`IOU_THRESHOLD`]. False for degenerate input.
pub fn grasp_correct(est: &[DVec2; 4], gt: &[DVec2; 4]) -> bool {
    angle_difference_deg(rectangle_angle_deg(est), rectangle_angle_deg(gt)) < ANGLE_TOLERANCE_DEG
        && rectangle_iou(est, gt) > IOU_THRESHOLD
}

/// Rectangles in the OCID/Cornell `.txt` form: one corner `"x y"` per line, four lines
/// per grasp, numbers in Rust's shortest round-trip notation.
pub fn rectangles_to_txt(rects: &[[DVec2; 4]]) -> String {
    let mut s = String::new();
    for p in rects.iter().flatten() {
        let _ = writeln!(s, "{} {}", p.x, p.y);
    }
    s
}

/// Parses the OCID/Cornell `.txt` form: one corner `"x y"` per line (separated by
/// whitespace), every four corners one rectangle; blank lines are ignored. A rectangle
/// with a NaN/infinite corner is skipped, as the Cornell loaders do (some Cornell
/// `cpos` files hold NaN). Errors ([`Error::Json`], file `"grasp rectangles"`) name the
/// line: not two numbers, or a corner count that is not a multiple of 4.
pub fn rectangles_from_txt(text: &str) -> Result<Vec<[DVec2; 4]>> {
    let err = |problem: String| Error::Json {
        file: "grasp rectangles".into(),
        problem,
    };
    let mut corners = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        let (Some(x), Some(y), None) = (tokens.next(), tokens.next(), tokens.next()) else {
            if line.trim().is_empty() {
                continue;
            }
            return Err(err(format!("line {}: expected \"x y\", got {line:?}", i + 1)));
        };
        let num = |t: &str| {
            t.parse::<f64>()
                .map_err(|_| err(format!("line {}: {t:?} is not a number", i + 1)))
        };
        corners.push(DVec2::new(num(x)?, num(y)?));
    }
    if corners.len() % 4 != 0 {
        return Err(err(format!(
            "{} corners is not a multiple of 4 (each rectangle has 4 lines)",
            corners.len()
        )));
    }
    Ok(corners
        .chunks_exact(4)
        .filter(|c| c.iter().all(|p| p.is_finite()))
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotated(c: DVec2, w: f64, h: f64, deg: f64) -> [DVec2; 4] {
        let r = DVec2::from_angle(deg.to_radians());
        [(-w, -h), (w, -h), (w, h), (-w, h)].map(|(x, y)| c + r.rotate(DVec2::new(x, y) * 0.5))
    }

    /// Independent oracle: the fraction of a fine grid of sample points inside both.
    fn iou_by_sampling(a: &[DVec2; 4], b: &[DVec2; 4]) -> f64 {
        let inside = |r: &[DVec2; 4], p: DVec2| {
            let s: Vec<f64> = (0..4).map(|i| (r[(i + 1) % 4] - r[i]).perp_dot(p - r[i])).collect();
            s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
        };
        let (mut both, mut any) = (0usize, 0usize);
        let n = 600;
        for i in 0..n {
            for j in 0..n {
                let p = DVec2::new(
                    -10.0 + 20.0 * (i as f64 + 0.5) / n as f64,
                    -10.0 + 20.0 * (j as f64 + 0.5) / n as f64,
                );
                let (ia, ib) = (inside(a, p), inside(b, p));
                both += (ia && ib) as usize;
                any += (ia || ib) as usize;
            }
        }
        both as f64 / any as f64
    }

    #[test]
    fn iou_of_rotated_rectangles_matches_sampling() {
        for (deg_a, deg_b, shift) in [
            (0.0, 30.0, 0.5),
            (10.0, 80.0, -1.0),
            (45.0, 45.0, 2.0),
            (0.0, 90.0, 0.0),
        ] {
            let a = rotated(DVec2::ZERO, 8.0, 4.0, deg_a);
            let b = rotated(DVec2::new(shift, 0.3), 6.0, 5.0, deg_b);
            let exact = rectangle_iou(&a, &b);
            assert!(
                (exact - iou_by_sampling(&a, &b)).abs() < 5e-3,
                "{deg_a} {deg_b} {shift}: {exact}"
            );
            assert!((exact - rectangle_iou(&b, &a)).abs() < 1e-12);
        }
    }

    #[test]
    fn angle_follows_the_ocid_formula() {
        // p0→p1 pointing right: arctan(0/−w) = −0 → 90°.
        let r = rotated(DVec2::ZERO, 4.0, 2.0, 0.0);
        assert!((rectangle_angle_deg(&r) - 90.0).abs() < 1e-9);
        // Image-y is down, so a counter-clockwise rotation on screen (y up) is negative here.
        let r = rotated(DVec2::ZERO, 4.0, 2.0, -30.0);
        assert!((rectangle_angle_deg(&r) - 120.0).abs() < 1e-9);
        // Vertical edge.
        let v = [
            DVec2::new(0.0, 0.0),
            DVec2::new(0.0, 5.0),
            DVec2::new(1.0, 5.0),
            DVec2::new(1.0, 0.0),
        ];
        assert_eq!(rectangle_angle_deg(&v), 0.0);
        assert!((angle_difference_deg(175.0, 5.0) - 10.0).abs() < 1e-12);
    }

    #[test]
    fn txt_errors_name_the_line() {
        let e = rectangles_from_txt("1 2\n3 x\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("\"x\""), "{e}");
        let e = rectangles_from_txt("1 2\n3 4 5\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        let e = rectangles_from_txt("1 2\n3 4\n5 6\n").unwrap_err().to_string();
        assert!(e.contains("3 corners"), "{e}");
        let ok = rectangles_from_txt("NaN NaN\n1 1\n2 2\n3 3\n0 0\n1 0\n1 1\n0 1\n").unwrap();
        assert_eq!(ok.len(), 1);
        assert_eq!(ok[0][2], DVec2::new(1.0, 1.0));
    }
}
