//! Symmetries of an object and what they do to pose errors: the rotations of the
//! cube group that map a mesh onto itself (a symmetric object's pose is only known
//! up to them), and the equivalent of a true pose closest to an estimate, against
//! which errors are measured (so CLI, page and evaluation report the same figures).

use crate::mesh::Mesh;
use crate::metrics::{add, strided, MAX_QUERY_POINTS};
use crate::pose::Pose;
use glam::{DMat3, DVec3};
use kiddo::{KdTree, SquaredEuclidean};

/// The rotations of the cube group (the 24 signed permutation matrices of
/// determinant +1) that map the mesh onto itself about its bounding box's centre:
/// every rotated vertex lies within 2 % of the diameter of a vertex (read on at most
/// [`MAX_QUERY_POINTS`] of them, evenly strided, on a big mesh). Always holds the
/// identity; more than one element means the object is symmetric, and a pose is then
/// only determined up to these rotations (ADD-S is the fair measure).
pub fn symmetries(mesh: &Mesh) -> Vec<DMat3> {
    let mut out = vec![DMat3::IDENTITY];
    let Some(b) = mesh.bounds() else { return out };
    let pts = mesh.used_points();
    if pts.len() < 3 {
        return out;
    }
    let c = b.centre();
    let tol = 0.02 * b.size().length();
    let mut tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in pts.iter().enumerate() {
        tree.add(&(*p - c).to_array(), i as u64);
    }
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for perm in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
        for signs in 0..8u32 {
            let sign = |k: u32| if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
            let m = DMat3::from_cols(
                axes[perm[0]] * sign(0),
                axes[perm[1]] * sign(1),
                axes[perm[2]] * sign(2),
            );
            if (m.determinant() - 1.0).abs() > 1e-9 || m == DMat3::IDENTITY {
                continue;
            }
            let maps = strided(&pts, MAX_QUERY_POINTS).all(|p| {
                let q = m * (*p - c);
                tree.nearest_one::<SquaredEuclidean>(&q.to_array()).distance <= tol * tol
            });
            if maps {
                out.push(m);
            }
        }
    }
    out
}

/// Whether the object has a symmetry of the cube group (see [`symmetries`]).
pub fn is_symmetric(mesh: &Mesh) -> bool {
    symmetries(mesh).len() > 1
}

/// The pose `gt ∘ S` (first the model symmetry S about the mesh's box centre `c`,
/// then `gt`): the same physical object as `gt`. S is a signed permutation, so
/// `diag(s)·S = S·diag(|Sᵀs|)` and the result is again rotation, translation and
/// per-axis scale.
pub fn compose_symmetry(gt: &Pose, s: DMat3, c: DVec3) -> Pose {
    let scale = (s.transpose() * gt.scale).abs();
    let rotation = gt.rotation * s;
    // gt(S(X − c) + c) = R·(s_gt ⊙ (S X)) + R·(s_gt ⊙ (c − S c)) + t.
    let translation = gt.translation + gt.rotation * (gt.scale * (c - s * c));
    Pose {
        rotation,
        translation,
        scale,
    }
}

/// Among the symmetric equivalents of `gt`, the one closest to `est` (by ADD).
pub fn closest_equivalent(mesh: &Mesh, syms: &[DMat3], est: &Pose, gt: &Pose) -> Pose {
    let c = mesh.bounds().map_or(DVec3::ZERO, |b| b.centre());
    syms.iter()
        .map(|s| compose_symmetry(gt, *s, c))
        .min_by(|a, b| add(mesh, est, a).total_cmp(&add(mesh, est, b)))
        .unwrap_or(*gt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetry_of_box_and_blob() {
        let cube = Mesh::cuboid(DVec3::splat(1.0));
        assert!(is_symmetric(&cube));
        assert_eq!(symmetries(&cube).len(), 24, "a cube has the whole group");
        assert!(!is_symmetric(&crate::app::synth::blob_mesh(12, 25)));
        // An equivalent pose is the same physical object: ADD between them is ~0,
        // for an anisotropic scale too.
        let gt = Pose {
            rotation: crate::so3::exp(DVec3::new(0.3, -0.2, 0.5)),
            translation: DVec3::new(0.1, 0.2, 0.3),
            scale: DVec3::new(1.0, 1.0, 1.0),
        };
        let box_mesh = cube.clone();
        for s in symmetries(&box_mesh) {
            let e = compose_symmetry(&gt, s, box_mesh.bounds().unwrap().centre());
            assert!(crate::metrics::add_s(&box_mesh, &e, &gt) < 1e-9);
        }
        let flipped = compose_symmetry(&gt, symmetries(&box_mesh)[5], DVec3::ZERO);
        assert!(crate::metrics::add(&box_mesh, &flipped, &gt) > 0.1);
        let back = closest_equivalent(&box_mesh, &symmetries(&box_mesh), &flipped, &gt);
        assert!(crate::metrics::add(&box_mesh, &flipped, &back) < 1e-9);
    }
}
