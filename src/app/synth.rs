//! Synthetic scenes: cameras placed around a posed mesh, looking at it, with masks
//! rendered by the hard rasteriser — for tests, benchmarks, examples and the
//! accuracy evaluation. Deterministic for a given seed.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::hard;
use crate::raster::shade::render_shaded;
use crate::view::Rgba;
use glam::{DMat3, DQuat, DVec3};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

pub use crate::app::shapes::blob_mesh;

/// How to make a synthetic scene.
#[derive(Debug, Clone)]
pub struct SynthSettings {
    /// Number of views (default 4).
    pub views: usize,
    /// Image width in pixels (default 256).
    pub width: u32,
    /// Image height in pixels (default 256).
    pub height: u32,
    /// Random seed (default 0).
    pub seed: u64,
    /// Largest per-axis log-scale deviation of a random pose (default 0.2, i.e. ×0.82…×1.22).
    pub max_log_scale: f64,
    /// Fraction of the canvas' half-size the object's bounding sphere may span (default 0.7).
    pub fill: f64,
    /// Also render shaded "photographs" (default false).
    pub images: bool,
}

impl Default for SynthSettings {
    fn default() -> Self {
        SynthSettings {
            views: 4,
            width: 256,
            height: 256,
            seed: 0,
            max_log_scale: 0.2,
            fill: 0.7,
            images: false,
        }
    }
}

/// A synthetic scene: the true pose and one camera and mask per view.
#[derive(Debug, Clone)]
pub struct SynthScene {
    /// The pose the masks were rendered at.
    pub pose: Pose,
    /// Cameras, OpenCV axes.
    pub cameras: Vec<Camera>,
    /// Hard silhouettes, one per camera.
    pub masks: Vec<Mask>,
    /// Shaded renders, one per camera, when asked for.
    pub images: Vec<Rgba>,
}

impl SynthScene {
    /// The scene's views, named `view0`, `view1`, … (no images).
    pub fn views(&self) -> Vec<crate::view::View> {
        self.cameras
            .iter()
            .zip(&self.masks)
            .enumerate()
            .map(|(i, (c, m))| {
                crate::view::View::new(&format!("view{i}"), *c, m.clone(), None, None, &Default::default())
                    .expect("synthesize keeps the object inside every canvas: masks are not empty")
            })
            .collect()
    }

    /// The scene's views as a segmenter would give them: view i's mask roughened
    /// ([`roughen`]: σ `sigma_px`, correlation `correlation_px`, seeded `seed + i`), with
    /// its shaded render as the photograph when there is one, the mask's outline to be
    /// refined by it ([`crate::view::View::with_colour_refinement`]).
    ///
    /// Errors: a mask roughened away ([`Error::EmptyMask`]).
    pub fn segmented_views(&self, sigma_px: f64, correlation_px: f64, seed: u64) -> Result<Vec<crate::view::View>> {
        self.cameras
            .iter()
            .zip(&self.masks)
            .enumerate()
            .map(|(i, (c, m))| {
                let rough = roughen(m, sigma_px, correlation_px, seed + i as u64);
                let image = self.images.get(i).cloned();
                crate::view::View::new(&format!("view{i}"), *c, rough, None, image, &Default::default())
                    .map(crate::view::View::with_colour_refinement)
            })
            .collect()
    }
}

/// The hard silhouette of `mesh` at `pose` in `camera`: the mask a perfect segmenter
/// would give (what [`synthesize`] draws; pixel centres inside the projected mesh).
pub fn render_mask(mesh: &Mesh, pose: &Pose, camera: &Camera) -> Mask {
    hard::render(mesh, pose, camera)
}

/// A rotation drawn uniformly from SO(3).
pub fn random_rotation(rng: &mut SmallRng) -> DMat3 {
    // Shoemake's method.
    let (u1, u2, u3): (f64, f64, f64) = (rng.gen(), rng.gen(), rng.gen());
    let tau = std::f64::consts::TAU;
    let q = DQuat::from_xyzw(
        (1.0 - u1).sqrt() * (tau * u2).sin(),
        (1.0 - u1).sqrt() * (tau * u2).cos(),
        u1.sqrt() * (tau * u3).sin(),
        u1.sqrt() * (tau * u3).cos(),
    );
    DMat3::from_quat(q.normalize())
}

/// A random pose for `mesh`: uniform rotation, per-axis scale within
/// `exp(±max_log_scale)`, and the object's centre within a tenth of its radius of the origin.
pub fn random_pose(mesh: &Mesh, max_log_scale: f64, rng: &mut SmallRng) -> Pose {
    let b = mesh.bounds().unwrap_or(crate::mesh::Bounds {
        min: DVec3::ZERO,
        max: DVec3::ZERO,
    });
    let radius = (b.size().length() * 0.5).max(1e-9);
    let rotation = random_rotation(rng);
    let scale = DVec3::new(
        rng.gen_range(-max_log_scale..=max_log_scale).exp(),
        rng.gen_range(-max_log_scale..=max_log_scale).exp(),
        rng.gen_range(-max_log_scale..=max_log_scale).exp(),
    );
    let jitter = DVec3::new(
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
    ) * 0.1
        * radius;
    let translation = -(rotation * (scale * b.centre())) + jitter;
    Pose {
        rotation,
        translation,
        scale,
    }
}

/// Makes a synthetic scene of `mesh` at `pose` (random when `None`).
pub fn synthesize(mesh: &Mesh, settings: &SynthSettings, pose: Option<Pose>) -> Result<SynthScene> {
    if settings.views == 0 || settings.views > 64 {
        return Err(Error::Settings(format!(
            "views must be between 1 and 64, got {}",
            settings.views
        )));
    }
    if settings.width < 8 || settings.height < 8 {
        return Err(Error::Settings("width and height must be at least 8 pixels".into()));
    }
    let mut rng = SmallRng::seed_from_u64(settings.seed);
    let pose = match pose {
        Some(p) => p,
        None => random_pose(mesh, settings.max_log_scale, &mut rng),
    };
    pose.validate()?;
    let b = mesh.bounds().ok_or_else(|| Error::Mesh {
        file: "mesh".into(),
        problem: "has no vertices".into(),
    })?;
    // World-space bounding sphere of the posed mesh.
    let centre = pose.apply(b.centre());
    let radius = mesh
        .positions
        .iter()
        .map(|p| pose.apply(*p).distance(centre))
        .fold(0.0, f64::max)
        .max(1e-9);
    let (w, h) = (settings.width, settings.height);
    let f = 1.1 * w.max(h) as f64;
    let half = 0.5 * w.min(h) as f64 * settings.fill;
    let az0: f64 = rng.gen_range(0.0..360.0);
    let mut cameras = Vec::with_capacity(settings.views);
    let mut masks = Vec::with_capacity(settings.views);
    for i in 0..settings.views {
        let az = (az0 + 360.0 * i as f64 / settings.views as f64 + rng.gen_range(-15.0..15.0)).to_radians();
        let el = rng.gen_range(-20.0f64..60.0).to_radians();
        let dir = DVec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin());
        // Distance at which the bounding sphere spans `half` pixels, with some variety.
        let mut dist = radius * (1.0 + (f / half).powi(2)).sqrt() * rng.gen_range(1.0..1.3);
        let up = if el.abs() > 80f64.to_radians() {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let mut tries = 0;
        loop {
            let cam = Camera::look_at(centre + dir * dist, centre, up, w, h, f);
            let mask = render_mask(mesh, &pose, &cam);
            if mask.area() > 0 && !mask.touches_border() {
                cameras.push(cam);
                masks.push(mask);
                break;
            }
            tries += 1;
            dist *= 1.25;
            if tries > 20 {
                return Err(Error::View {
                    view: format!("view{i}"),
                    problem: "could not fit the object inside the canvas".into(),
                });
            }
        }
    }
    let images = if settings.images {
        cameras
            .iter()
            .map(|c| render_shaded(mesh, &pose, c, [230, 190, 40]))
            .collect()
    } else {
        Vec::new()
    };
    Ok(SynthScene {
        pose,
        cameras,
        masks,
        images,
    })
}

/// A mask with its boundary displaced along the normal by a smooth random field, as
/// a segmentation network's error looks: `ν(x)` is bilinear between independent
/// N(0, σ²) values on a grid of `correlation_px` pixels, and a pixel is object when
/// its signed distance to the contour (negative inside) is below ν there. σ = 0
/// returns the mask unchanged. Deterministic for a seed.
pub fn roughen(mask: &Mask, sigma_px: f64, correlation_px: f64, seed: u64) -> Mask {
    if sigma_px.is_nan() || sigma_px <= 0.0 || mask.area() == 0 {
        return mask.clone();
    }
    let (w, h) = (mask.width as usize, mask.height as usize);
    let inside: Vec<bool> = mask.data.iter().map(|&v| v != 0).collect();
    let outside: Vec<bool> = inside.iter().map(|&v| !v).collect();
    let to_object = crate::loss::edt::distance(w, h, &inside);
    let to_background = crate::loss::edt::distance(w, h, &outside);
    let cell = correlation_px.max(1.0);
    let (gw, gh) = (
        (w as f64 / cell).ceil() as usize + 2,
        (h as f64 / cell).ceil() as usize + 2,
    );
    let mut rng = SmallRng::seed_from_u64(seed);
    let grid: Vec<f64> = (0..gw * gh)
        .map(|_| {
            let u: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
            let v: f64 = rng.gen();
            sigma_px * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        })
        .collect();
    let mut out = Mask::empty(mask.width, mask.height);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let sd = if inside[i] {
                0.5 - to_background[i]
            } else {
                to_object[i] - 0.5
            };
            let (gx, gy) = (x as f64 / cell, y as f64 / cell);
            let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
            let (fx, fy) = (gx - x0 as f64, gy - y0 as f64);
            let g = |xx: usize, yy: usize| grid[yy * gw + xx];
            let nu = (1.0 - fy) * ((1.0 - fx) * g(x0, y0) + fx * g(x0 + 1, y0))
                + fy * ((1.0 - fx) * g(x0, y0 + 1) + fx * g(x0 + 1, y0 + 1));
            out.data[i] = u8::from(sd < nu);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughen_moves_the_boundary_by_about_sigma_and_keeps_the_shape() {
        let m = blob_mesh(11, 25);
        let s = synthesize(
            &m,
            &SynthSettings {
                views: 1,
                ..Default::default()
            },
            None,
        )
        .unwrap();
        let mask = &s.masks[0];
        assert_eq!(&roughen(mask, 0.0, 8.0, 1), mask);
        let r = roughen(mask, 1.5, 8.0, 1);
        let changed = mask.data.iter().zip(&r.data).filter(|(a, b)| a != b).count() as f64;
        let perimeter = crate::metrics::contour(mask).area() as f64;
        // Changed pixels ≈ perimeter × mean |ν| (≈ 0.6 σ after bilinear smoothing).
        assert!(
            changed > 0.3 * perimeter && changed < 2.5 * perimeter,
            "{changed} vs {perimeter}"
        );
        assert_ne!(roughen(mask, 1.5, 8.0, 2), r);
        assert!((r.area() as f64 - mask.area() as f64).abs() < 0.1 * mask.area() as f64);
    }

    #[test]
    fn synthetic_scene_keeps_the_object_inside_every_view() {
        let m = blob_mesh(11, 25);
        let settings = SynthSettings {
            views: 5,
            width: 96,
            height: 64,
            seed: 3,
            ..Default::default()
        };
        let s = synthesize(&m, &settings, None).unwrap();
        assert_eq!(s.cameras.len(), 5);
        for (c, k) in s.cameras.iter().zip(&s.masks) {
            assert!(k.area() > 100 && !k.touches_border());
            assert!(c.to_camera(s.pose.translation).z > 0.0);
        }
        assert_eq!(s.views()[4].name(), "view4");
        // Deterministic for a seed.
        assert_eq!(synthesize(&m, &settings, None).unwrap().pose, s.pose);
    }
}

/// Occludes `fraction` of a mask's object pixels with a rectangular occluder sliding
/// in from one side of the object's box (the side chosen by `seed`), as clutter or a
/// gripper would: returns the cut mask and the occluder's pixels (the ignore mask a
/// user who knows the occluder would give). A `fraction` of 0 changes nothing.
pub fn occlude(mask: &Mask, fraction: f64, seed: u64) -> (Mask, Mask) {
    let mut occluder = Mask::empty(mask.width, mask.height);
    let Some((x0, y0, x1, y1)) = mask.bbox() else {
        return (mask.clone(), occluder);
    };
    let target = (fraction.clamp(0.0, 1.0) * mask.area() as f64).round() as usize;
    let side = seed % 4;
    let (w, h) = (mask.width, mask.height);
    // Pixels of the object's box, ordered by how soon the occluder reaches them.
    let depth = |x: u32, y: u32| match side {
        0 => x - x0,
        1 => x1 - x,
        2 => y - y0,
        _ => y1 - y,
    };
    let span = match side {
        0 | 1 => x1 - x0,
        _ => y1 - y0,
    };
    // The smallest depth d whose band [0, d) covers `target` object pixels.
    let mut per_depth = vec![0usize; span as usize + 2];
    for y in y0..=y1 {
        for x in x0..=x1 {
            if mask.get(x, y) {
                per_depth[depth(x, y) as usize] += 1;
            }
        }
    }
    let (mut d, mut covered) = (0usize, 0usize);
    while covered < target && d < per_depth.len() {
        covered += per_depth[d];
        d += 1;
    }
    let mut cut = mask.clone();
    for y in 0..h {
        for x in 0..w {
            let inside_box = match side {
                0 | 1 => (y0..=y1).contains(&y) && ((x0..=x1).contains(&x)),
                _ => (x0..=x1).contains(&x) && (y0..=y1).contains(&y),
            };
            if inside_box && (depth(x, y) as usize) < d {
                let i = (y * w + x) as usize;
                occluder.data[i] = 1;
                cut.data[i] = 0;
            }
        }
    }
    (cut, occluder)
}

#[cfg(test)]
mod occlusion_tests {
    use super::*;

    #[test]
    fn occlusion_hides_the_asked_fraction() {
        let mut m = Mask::empty(50, 40);
        for y in 10..30 {
            for x in 5..45 {
                m.data[y * 50 + x] = 1;
            }
        }
        for seed in 0..4 {
            let (cut, occ) = occlude(&m, 0.3, seed);
            let hidden = m.area() - cut.area();
            assert!(
                (hidden as f64 / m.area() as f64 - 0.3).abs() < 0.06,
                "seed {seed}: {hidden}"
            );
            // The occluder covers exactly the hidden pixels of the object.
            assert!(m
                .data
                .iter()
                .zip(&cut.data)
                .zip(&occ.data)
                .all(|((&a, &b), &o)| (a != b) == (a == 1 && o == 1)));
        }
        assert_eq!(occlude(&m, 0.0, 1).0, m);
    }
}
