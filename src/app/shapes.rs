//! Procedural meshes the project makes itself, so that tests, benchmarks and the web
//! page's examples need no third-party model:
//!
//! - [`toy_plane`]: a toy aeroplane (fuselage with a canopy, swept wings with
//!   dihedral, tailplane, tail fin, and one engine pod under the left wing only), about
//!   0.32 m long and 0.30 m across, ~3k triangles, closed. The pod breaks the mirror
//!   symmetry, so no rotation but the identity maps it onto itself and a few
//!   silhouettes fix its orientation;
//! - [`blob_mesh`]: a bumpy, asymmetric deformed sphere of chosen size (the
//!   benchmark's meshes);
//! - [`cube_mesh`]: an axis-aligned cube (the fully symmetric case).
//!
//! Axes follow glTF: +Y up, the aeroplane's nose towards +Z, its left wing towards +X;
//! units are metres. Every mesh is closed (each edge shared by exactly two
//! triangles) and wound counter-clockwise seen from outside. Built with plain f64
//! arithmetic: the same mesh natively and in WebAssembly (to the last bits of `sin`/`cos`).

use crate::mesh::Mesh;
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// The named shapes, as the command line offers them (`synth --shape NAME`).
pub const NAMES: [&str; 3] = ["toy", "blob", "cube"];

/// The shape called `name` (one of [`NAMES`]); `None` for an unknown name.
pub fn by_name(name: &str) -> Option<Mesh> {
    match name {
        "toy" => Some(toy_plane()),
        "blob" => Some(blob_mesh(22, 50)),
        "cube" => Some(cube_mesh(0.2)),
        _ => None,
    }
}

/// A closed tube through `rings` (loops of the same number of points, in the same
/// rotational order), each end closed by a fan to a pole: `start`/`end` when given,
/// else the end ring's centroid. Wound outwards (by the sign of the enclosed volume).
fn loft(rings: &[Vec<DVec3>], start: Option<DVec3>, end: Option<DVec3>) -> Mesh {
    let k = rings[0].len();
    debug_assert!(rings.len() >= 2 && k >= 3 && rings.iter().all(|r| r.len() == k));
    let centroid = |r: &[DVec3]| r.iter().copied().sum::<DVec3>() / r.len() as f64;
    let mut positions = vec![start.unwrap_or_else(|| centroid(&rings[0]))];
    positions.extend(rings.iter().flatten().copied());
    positions.push(end.unwrap_or_else(|| centroid(rings.last().unwrap())));
    let last = positions.len() as u32 - 1;
    let at = |i: usize, j: usize| (1 + i * k + j % k) as u32;
    let n = rings.len();
    let mut triangles = Vec::with_capacity(2 * k * n);
    for j in 0..k {
        triangles.push([0, at(0, j + 1), at(0, j)]);
        triangles.push([last, at(n - 1, j), at(n - 1, j + 1)]);
        for i in 0..n - 1 {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let mut mesh = Mesh { positions, triangles };
    if signed_volume(&mesh) < 0.0 {
        mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    mesh
}

/// The volume a closed mesh encloses, positive when it is wound outwards.
pub fn signed_volume(mesh: &Mesh) -> f64 {
    let p = |i: u32| mesh.positions[i as usize];
    mesh.triangles
        .iter()
        .map(|&[a, b, c]| p(a).dot(p(b).cross(p(c))) / 6.0)
        .sum()
}

/// The parts as one mesh (they may intersect: a silhouette is their union).
fn merge(parts: &[Mesh]) -> Mesh {
    let mut out = Mesh::default();
    for m in parts {
        let base = out.positions.len() as u32;
        out.positions.extend(&m.positions);
        out.triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    out
}

/// `k` points of the ellipse `centre + a·cos θ·u + b·sin θ·v`, θ from 0 in steps of 2π/k.
fn ellipse(centre: DVec3, u: DVec3, v: DVec3, a: f64, b: f64, k: usize) -> Vec<DVec3> {
    (0..k)
        .map(|j| {
            let t = TAU * j as f64 / k as f64;
            centre + u * (a * t.cos()) + v * (b * t.sin())
        })
        .collect()
}

/// A tapered, swept lifting surface (wing, tailplane or fin) from `root` outwards
/// along `span_dir`: lens-shaped sections of the given chords (along z) and thickness,
/// the tip `sweep` behind the root (−z) and `rise` above it (+y) at `span`.
/// `both_sides` mirrors it through the root (a wing: tip, root, tip).
struct Surface {
    root: DVec3,
    span_dir: DVec3,
    thick_dir: DVec3,
    span: f64,
    root_chord: f64,
    tip_chord: f64,
    thickness: f64,
    sweep: f64,
    rise: f64,
    both_sides: bool,
}

impl Surface {
    fn mesh(&self) -> Mesh {
        const K: usize = 16;
        let section = |s: f64| {
            // s in [-1, 1]: signed fraction of the span.
            let f = s.abs();
            let chord = self.root_chord + (self.tip_chord - self.root_chord) * f;
            let centre = self.root + self.span_dir * (self.span * s) + DVec3::new(0.0, self.rise * f, -self.sweep * f);
            let t = self.thickness * (1.0 - 0.4 * f);
            ellipse(centre, DVec3::Z, self.thick_dir, chord / 2.0, t / 2.0, K)
        };
        let stations: &[f64] = if self.both_sides {
            &[-1.0, -0.5, 0.0, 0.5, 1.0]
        } else {
            &[0.0, 0.5, 1.0]
        };
        loft(&stations.iter().map(|&s| section(s)).collect::<Vec<_>>(), None, None)
    }
}

/// A toy aeroplane (see the module doc): ~0.32 m nose to tail (z), ~0.30 m wing tip to
/// wing tip (x), ~0.1 m tall (y); the engine pod hangs under the left (+x) wing and
/// reaches ahead of its leading edge. 3,300 or so triangles, closed, five intersecting
/// parts.
pub fn toy_plane() -> Mesh {
    // Fuselage: elliptic sections along z, tail (z = −0.16) to nose (z = +0.16); the
    // tail cone sweeps up, a canopy bulges from the top over the wing.
    const K: usize = 24;
    const RINGS: usize = 44;
    let mut rings = Vec::with_capacity(RINGS);
    for i in 0..RINGS {
        let s = 0.02 + 0.95 * i as f64 / (RINGS - 1) as f64; // 0.02 … 0.97
        let z = -0.16 + 0.32 * s;
        let r = if s < 0.55 {
            let u = s / 0.55;
            0.006 + 0.016 * u * u * (3.0 - 2.0 * u)
        } else {
            0.022 * (1.0 - ((s - 0.55) / 0.45).powi(2)).max(0.0).sqrt()
        };
        let lift = if s < 0.5 { 0.014 * (1.0 - s / 0.5).powi(2) } else { 0.0 };
        let canopy = if (0.5..0.8).contains(&s) {
            0.011 * (PI * (s - 0.5) / 0.3).sin()
        } else {
            0.0
        };
        let ring = (0..K)
            .map(|j| {
                let t = TAU * j as f64 / K as f64;
                let (sin, cos) = (t.sin(), t.cos());
                let top = sin.max(0.0).powi(3) * canopy;
                DVec3::new(r * cos, lift + 1.15 * r * sin + top, z)
            })
            .collect();
        rings.push(ring);
    }
    let fuselage = loft(
        &rings,
        Some(DVec3::new(0.0, 0.014 * 0.96f64.powi(2), -0.16)),
        Some(DVec3::new(0.0, 0.0, 0.16)),
    );

    let wing = Surface {
        root: DVec3::new(0.0, -0.006, 0.02),
        span_dir: DVec3::X,
        thick_dir: DVec3::Y,
        span: 0.15,
        root_chord: 0.10,
        tip_chord: 0.045,
        thickness: 0.012,
        sweep: 0.06,
        rise: 0.02,
        both_sides: true,
    }
    .mesh();
    let tailplane = Surface {
        root: DVec3::new(0.0, 0.012, -0.13),
        span_dir: DVec3::X,
        thick_dir: DVec3::Y,
        span: 0.055,
        root_chord: 0.05,
        tip_chord: 0.028,
        thickness: 0.006,
        sweep: 0.025,
        rise: 0.0,
        both_sides: true,
    }
    .mesh();
    let fin = Surface {
        root: DVec3::new(0.0, 0.01, -0.125),
        span_dir: DVec3::Y,
        thick_dir: DVec3::X,
        span: 0.07,
        root_chord: 0.06,
        tip_chord: 0.03,
        thickness: 0.007,
        sweep: 0.03,
        rise: 0.0,
        both_sides: false,
    }
    .mesh();

    // The engine pod under the left wing: a spindle along z, z = −0.03 … 0.13.
    let pod_rings: Vec<Vec<DVec3>> = (1..16)
        .map(|i| {
            let s = i as f64 / 16.0;
            let r = 0.017 * (PI * s).sin().powf(0.6);
            let centre = DVec3::new(0.075, -0.014, -0.03 + 0.16 * s);
            ellipse(centre, DVec3::X, DVec3::Y, r, r, 12)
        })
        .collect();
    let pod = loft(
        &pod_rings,
        Some(DVec3::new(0.075, -0.014, -0.03)),
        Some(DVec3::new(0.075, -0.014, 0.13)),
    );

    merge(&[fuselage, wing, tailplane, fin, pod])
}

/// A closed, asymmetric, bumpy "blob" (a deformed UV sphere of radius about 1) with
/// `2·n_lon·(n_lat − 2)` triangles — the benchmark's meshes of chosen sizes.
/// `n_lat ≥ 3` rings of latitude (poles included), `n_lon ≥ 3` meridians.
pub fn blob_mesh(n_lat: usize, n_lon: usize) -> Mesh {
    let (n_lat, n_lon) = (n_lat.max(3), n_lon.max(3));
    let mut positions = Vec::with_capacity(2 + (n_lat - 2) * n_lon);
    let radius = |d: DVec3| {
        1.0 + 0.25 * (2.0 * d.x + 0.5).sin() * (1.5 * d.y).cos() + 0.15 * (3.0 * d.z + d.x).sin() + 0.2 * d.x.max(0.0)
    };
    positions.push(DVec3::Y * radius(DVec3::Y));
    for i in 1..n_lat - 1 {
        let theta = std::f64::consts::PI * i as f64 / (n_lat - 1) as f64;
        for j in 0..n_lon {
            let phi = std::f64::consts::TAU * j as f64 / n_lon as f64;
            let d = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            positions.push(d * radius(d));
        }
    }
    positions.push(-DVec3::Y * radius(-DVec3::Y));
    let last = positions.len() as u32 - 1;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut triangles = Vec::with_capacity(2 * n_lon * (n_lat - 2));
    for j in 0..n_lon {
        triangles.push([0, ring(1, j + 1), ring(1, j)]);
        triangles.push([last, ring(n_lat - 2, j), ring(n_lat - 2, j + 1)]);
    }
    for i in 1..n_lat - 2 {
        for j in 0..n_lon {
            triangles.push([ring(i, j), ring(i, j + 1), ring(i + 1, j)]);
            triangles.push([ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)]);
        }
    }
    Mesh { positions, triangles }
}

/// An axis-aligned cube of side `side` centred on the origin: 8 vertices, 12 triangles.
pub fn cube_mesh(side: f64) -> Mesh {
    let h = side / 2.0;
    let positions = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -h } else { h },
                if i & 2 == 0 { -h } else { h },
                if i & 4 == 0 { -h } else { h },
            )
        })
        .collect();
    // Two triangles per face, counter-clockwise seen from outside.
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // -z
        [4, 5, 7],
        [4, 7, 6], // +z
        [0, 1, 5],
        [0, 5, 4], // -y
        [2, 6, 7],
        [2, 7, 3], // +y
        [0, 4, 6],
        [0, 6, 2], // -x
        [1, 3, 7],
        [1, 7, 5], // +x
    ];
    Mesh { positions, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::metrics::hard_iou;
    use crate::pose::Pose;
    use crate::raster::hard;
    use std::collections::HashMap;

    /// Closed and consistently wound: every directed edge once, and its reverse once.
    fn assert_closed_and_oriented(name: &str, m: &Mesh) {
        m.validate(name).unwrap();
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &directed {
            assert_eq!(n, 1, "{name}: edge {a}→{b} used {n} times in the same direction");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{name}: edge {a}–{b} is not shared by exactly two triangles"
            );
        }
        assert!(signed_volume(m) > 0.0, "{name}: wound inwards");
    }

    #[test]
    fn every_shape_is_closed_and_wound_outwards() {
        for name in NAMES {
            assert_closed_and_oriented(name, &by_name(name).unwrap());
        }
        assert_closed_and_oriented("blob 11×25", &blob_mesh(11, 25));
        assert!(by_name("teapot").is_none());
    }

    #[test]
    fn blob_has_the_promised_size() {
        for (lat, lon) in [(11, 25), (21, 50)] {
            assert_eq!(blob_mesh(lat, lon).triangles.len(), 2 * lon * (lat - 2));
        }
    }

    #[test]
    fn cube_has_the_given_side_and_volume() {
        let c = cube_mesh(0.2);
        let b = c.bounds().unwrap();
        assert!((b.size() - DVec3::splat(0.2)).abs().max_element() < 1e-15);
        assert!((signed_volume(&c) - 0.008).abs() < 1e-15);
        assert!(crate::symmetry::is_symmetric(&c));
    }

    #[test]
    fn toy_plane_is_aeroplane_sized_in_metres() {
        let m = toy_plane();
        let n = m.triangles.len();
        assert!((1000..=5000).contains(&n), "{n} triangles");
        let b = m.bounds().unwrap();
        let size = b.size();
        assert!((0.29..0.34).contains(&size.z), "length {}", size.z);
        assert!((0.28..0.32).contains(&size.x), "span {}", size.x);
        assert!((0.07..0.13).contains(&size.y), "height {}", size.y);
        let d = m.diameter();
        assert!((0.2..0.5).contains(&d), "diameter {d}");
        // The nose is the part furthest forward, the fin the highest.
        let nose = m.positions.iter().max_by(|a, b| a.z.total_cmp(&b.z)).unwrap();
        let top = m.positions.iter().max_by(|a, b| a.y.total_cmp(&b.y)).unwrap();
        assert!(nose.x.abs() < 1e-9 && nose.z > 0.15, "{nose}");
        assert!(top.z < -0.1, "the highest point is on the fin: {top}");
    }

    /// Hard silhouette of `mesh` (at the identity pose) seen from far along `dir`
    /// (nearly orthographic, so that a mirror symmetric object looks the same from both sides).
    fn silhouette(mesh: &Mesh, dir: DVec3, up: DVec3) -> crate::Mask {
        let cam = Camera::look_at(dir * 30.0, DVec3::ZERO, up, 160, 160, 12_000.0);
        hard::render(mesh, &Pose::default(), &cam)
    }

    #[test]
    fn toy_plane_has_no_symmetry_its_silhouettes_from_opposite_sides_differ() {
        let m = toy_plane();
        assert!(
            !crate::symmetry::is_symmetric(&m),
            "no half or quarter turn maps it onto itself"
        );
        for (axis, up) in [(DVec3::X, DVec3::Y), (DVec3::Y, DVec3::Z), (DVec3::Z, DVec3::Y)] {
            let (a, b) = (silhouette(&m, axis, up), silhouette(&m, -axis, up));
            assert!(a.area() > 500 && b.area() > 500, "{axis}: the aeroplane is in view");
            let iou = hard_iou(&a, &b);
            assert!(iou < 0.9, "seen from ±{axis} the silhouettes are alike (IoU {iou:.3})");
        }
        // The mirror symmetric aeroplane without its pod would look the same from
        // above and below, and from the front and behind: the pod makes the difference.
        let mut no_pod = m.clone();
        let pod_start = m.positions.len() - (2 + 15 * 12);
        no_pod.triangles.retain(|t| t.iter().all(|&i| (i as usize) < pod_start));
        for (axis, up) in [(DVec3::Y, DVec3::Z), (DVec3::Z, DVec3::Y)] {
            let iou = hard_iou(&silhouette(&no_pod, axis, up), &silhouette(&no_pod, -axis, up));
            assert!(iou > 0.95, "{axis}: without the pod, IoU {iou:.3}");
        }
    }
}
