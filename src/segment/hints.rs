//! Boxes from the geometry (SPEC §3): a view with a photograph and neither box nor
//! mask is given the box the other views imply. Their boxes' (or masks') centres are
//! triangulated into the object's centre, their extents give its radius (half the
//! box's longest side at the centre's depth, the median over the views), and the
//! sphere of that radius is projected into the view, a little loose.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::metrics::median;
use crate::optim::init::nearest_point;
use crate::view::PixelBox;
use glam::DVec3;

/// How much larger than the projected sphere's square the proposed box is.
const LOOSENESS: f64 = 1.15;

/// The sphere around the object that `hinted` views (camera, box) imply: centre and
/// radius, world units.
///
/// Errors: fewer than two views, rays that do not meet (parallel cameras), or a centre
/// behind one of the cameras.
pub fn sphere_from_boxes(hinted: &[(&Camera, PixelBox, &str)]) -> Result<(DVec3, f64)> {
    let geometry = |problem: String| Error::Settings(format!("boxes from the geometry: {problem}"));
    if hinted.len() < 2 {
        return Err(geometry(format!(
            "{} view(s) with a box or a mask; two are needed",
            hinted.len()
        )));
    }
    let rays: Vec<(DVec3, DVec3)> = hinted
        .iter()
        .map(|(c, b, _)| {
            let p = b.centre();
            (c.centre(), c.ray_direction(p.x, p.y))
        })
        .collect();
    let centre = nearest_point(&rays).ok_or_else(|| {
        geometry("the views' boxes do not triangulate (their cameras look along parallel rays)".into())
    })?;
    let mut radii = Vec::with_capacity(hinted.len());
    for (c, b, name) in hinted {
        let z = c.to_camera(centre).z;
        if z <= 0.0 {
            return Err(Error::View {
                view: name.to_string(),
                problem: "the object the boxes triangulate is behind this camera (check its extrinsics)".into(),
            });
        }
        radii.push(0.5 * b.size().max_element() * z / c.fx.min(c.fy));
    }
    Ok((centre, median(&radii)))
}

/// The box of the sphere `(centre, radius)` in `camera`, loosened, clipped to the image.
///
/// Errors (naming `view`): the sphere behind or around the camera, or outside its image.
pub fn box_of_sphere(view: &str, camera: &Camera, centre: DVec3, radius: f64) -> Result<PixelBox> {
    let pc = camera.to_camera(centre);
    if pc.z <= radius.max(0.0) {
        return Err(Error::View {
            view: view.into(),
            problem: "the object the other views' boxes place is behind (or around) this camera: draw a box on it"
                .into(),
        });
    }
    let p = camera.project(pc);
    let r = LOOSENESS * radius * camera.fx.max(camera.fy) / pc.z;
    PixelBox::new(
        view,
        [p.x + 0.5 - r, p.y + 0.5 - r, p.x + 0.5 + r, p.y + 0.5 + r],
        camera.width,
        camera.height,
    )
    .map_err(|_| Error::View {
        view: view.into(),
        problem: "the object the other views' boxes place is outside this photograph: draw a box on it".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sphere_two_boxes_imply_gives_the_third_view_its_box() {
        let target = DVec3::new(0.1, -0.05, 0.02);
        let radius = 0.08;
        let cam = |eye: DVec3| Camera::look_at(eye, target, DVec3::Z, 640, 480, 600.0);
        let cams = [
            cam(DVec3::new(0.8, 0.0, 0.3)),
            cam(DVec3::new(0.0, 0.9, 0.4)),
            cam(DVec3::new(-0.7, -0.5, 0.5)),
        ];
        // Each view's box: the sphere's projected square.
        let boxes: Vec<PixelBox> = cams
            .iter()
            .map(|c| {
                let pc = c.to_camera(target);
                let (p, r) = (c.project(pc), radius * 600.0 / pc.z);
                PixelBox::new(
                    "v",
                    [p.x + 0.5 - r, p.y + 0.5 - r, p.x + 0.5 + r, p.y + 0.5 + r],
                    640,
                    480,
                )
                .unwrap()
            })
            .collect();
        let hinted = [(&cams[0], boxes[0], "a"), (&cams[1], boxes[1], "b")];
        let (c, r) = sphere_from_boxes(&hinted).unwrap();
        assert!((c - target).length() < 1e-9, "{c}");
        assert!((r - radius).abs() < 1e-3 * radius, "{r}");
        let b = box_of_sphere("c", &cams[2], c, r).unwrap();
        assert!((b.centre() - boxes[2].centre()).length() < 1e-6);
        assert!((b.size().x / boxes[2].size().x - LOOSENESS).abs() < 1e-3);
        // One view, or a camera that sees the object behind it, is refused by name.
        assert!(sphere_from_boxes(&hinted[..1])
            .unwrap_err()
            .to_string()
            .contains("two are needed"));
        let behind = Camera::look_at(
            target + DVec3::new(0.0, 0.0, -0.5),
            target - DVec3::Z,
            DVec3::Y,
            640,
            480,
            600.0,
        );
        let e = box_of_sphere("d", &behind, c, r).unwrap_err().to_string();
        assert!(e.contains("view 'd'") && e.contains("behind"), "{e}");
    }
}
