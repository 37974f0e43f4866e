//! Edge topology of a mesh, built once: vertices welded by position, the unique
//! undirected edges between welded vertices, and each edge's adjacent faces.
//!
//! Welding: positions are quantised to a grid of step `WELD_TOLERANCE × d` (d the
//! diagonal of the finite positions' bounding box, 1 when that is zero) measured from
//! the box's minimum corner, and vertices whose three rounded grid coordinates agree
//! are one welded vertex. Exact copies (the glTF seam case: one position repeated for
//! each UV or normal) always weld; two positions closer than a step may still straddle
//! a cell boundary and stay apart. Vertices with a non-finite coordinate are never
//! welded. A welded vertex is represented by its smallest original index, and that
//! index is what an edge stores for each end (all copies project to the same pixel, so
//! any copy serves for gradients).
//!
//! Closed components: faces connected through edges form components; a component in
//! which every edge has exactly two faces running through it in opposite directions is
//! a closed, consistently oriented surface. Its projection is covered by its
//! front-facing faces alone (every ray through it meets a front face first), so the
//! hard coverage may skip its back faces: [`EdgeTopology::front_signs`] gives, per face,
//! the sign of the projected (image-space) area of a front-facing face of its component
//! — −1 when the component's signed volume is positive (outward winding; in OpenCV
//! image coordinates, y down, a face turned to the camera projects clockwise) and +1
//! when negative — or 0 for faces of open or inconsistent components (never skipped).

use glam::DVec3;

/// Grid step of the weld, relative to the bounding-box diagonal.
pub const WELD_TOLERANCE: f64 = 1e-7;

/// An absent second face in [`EdgeTopology`]'s `pairs`.
pub(crate) const NO_FACE: u32 = u32::MAX;
/// An edge with more than two faces in [`EdgeTopology`]'s `pairs`.
pub(crate) const MANY_FACES: u32 = u32::MAX - 1;

/// One face adjacent to an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Incidence {
    /// Index of the face in the triangle list.
    pub face: u32,
    /// Whether the face's cyclic vertex order runs from the edge's end 0 to its end 1
    /// (then its third vertex c satisfies `sign((b − a) × (c − a)) = sign(area)`).
    pub forward: bool,
}

/// The welded edges of a mesh and their adjacent faces (see the module doc).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EdgeTopology {
    /// Number of vertices and triangles it was built from.
    pub(crate) vertex_count: usize,
    pub(crate) face_count: usize,
    /// Number of distinct welded vertices.
    pub(crate) welded: usize,
    /// Per edge, its faces packed for the per-render pass: `face << 1 | forward` of its
    /// first two incidences ([`NO_FACE`] when it has one), or `[MANY_FACES, _]` when it
    /// has more than two (then read `incidences`).
    pub(crate) pairs: Vec<[u32; 2]>,
    /// Per face, its vertices' welded representatives (all 0 for a face referring to
    /// a vertex beyond the positions).
    pub(crate) welded_faces: Vec<[u32; 3]>,
    /// Per edge, its ends as representative (smallest original) vertex indices,
    /// `ends[e][0] < ends[e][1]`; edges sorted by `(ends[0], ends[1])`.
    pub(crate) ends: Vec<[u32; 2]>,
    /// `incidences[start[e]..start[e + 1]]` are edge e's faces, by increasing face index.
    pub(crate) start: Vec<u32>,
    pub(crate) incidences: Vec<Incidence>,
    /// Per face, the projected-area sign of a front-facing face of its closed,
    /// consistently oriented component, or 0 (module doc).
    pub(crate) front: Vec<i8>,
}

impl EdgeTopology {
    /// Builds the topology of `triangles` over `positions`. Triangles referring to a
    /// vertex beyond `positions` are left out (a render with them is refused anyway),
    /// as are the edges of a triangle whose two ends weld into one vertex.
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> EdgeTopology {
        let rep = weld(positions);
        let n = positions.len();
        let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
        for (f, t) in triangles.iter().enumerate() {
            if t.iter().any(|&i| i as usize >= n) {
                continue;
            }
            let w = t.map(|i| rep[i as usize]);
            for k in 0..3 {
                let (u, v) = (w[k], w[(k + 1) % 3]);
                if u != v {
                    half.push((u.min(v), u.max(v), f as u32, u < v));
                }
            }
        }
        half.sort_unstable();
        let mut topo = EdgeTopology {
            vertex_count: n,
            face_count: triangles.len(),
            welded: rep.iter().enumerate().filter(|&(i, &r)| r as usize == i).count(),
            welded_faces: triangles
                .iter()
                .map(|t| {
                    if t.iter().all(|&i| (i as usize) < n) {
                        t.map(|i| rep[i as usize])
                    } else {
                        [0; 3]
                    }
                })
                .collect(),
            ends: Vec::new(),
            start: vec![0],
            incidences: Vec::with_capacity(half.len()),
            pairs: Vec::new(),
            front: Vec::new(),
        };
        for (i, &(a, b, face, forward)) in half.iter().enumerate() {
            if i > 0 && (half[i - 1].0, half[i - 1].1) != (a, b) {
                topo.start.push(topo.incidences.len() as u32);
            }
            if i == 0 || (half[i - 1].0, half[i - 1].1) != (a, b) {
                topo.ends.push([a, b]);
            }
            topo.incidences.push(Incidence { face, forward });
        }
        if !half.is_empty() {
            topo.start.push(topo.incidences.len() as u32);
        }
        let pack = |i: &Incidence| i.face << 1 | u32::from(i.forward);
        topo.pairs = (0..topo.ends.len())
            .map(|e| match topo.incidences(e) {
                [a] => [pack(a), NO_FACE],
                [a, b] => [pack(a), pack(b)],
                _ => [MANY_FACES, 0],
            })
            .collect();
        topo.front = front_signs(&topo, positions, triangles);
        topo
    }

    /// Per face, the projected-area sign meaning "front-facing" for faces of closed,
    /// consistently oriented components, 0 for the others (module doc).
    pub fn front_signs(&self) -> &[i8] {
        &self.front
    }

    /// The topology of a [`Mesh`](crate::Mesh).
    pub fn from_mesh(mesh: &crate::Mesh) -> EdgeTopology {
        EdgeTopology::new(&mesh.positions, &mesh.triangles)
    }

    /// Number of unique undirected edges between welded vertices.
    pub fn edge_count(&self) -> usize {
        self.ends.len()
    }

    /// Number of welded vertices (distinct positions up to the weld tolerance).
    pub fn welded_vertex_count(&self) -> usize {
        self.welded
    }

    /// Edge `e`'s ends (smallest original vertex index of each welded end, ascending).
    ///
    /// # Panics
    /// If `e >= edge_count()`.
    pub fn ends(&self, e: usize) -> [u32; 2] {
        self.ends[e]
    }

    /// Edge `e`'s adjacent faces (triangle indices, ascending).
    ///
    /// # Panics
    /// If `e >= edge_count()`.
    pub fn faces(&self, e: usize) -> impl Iterator<Item = u32> + '_ {
        self.incidences(e).iter().map(|i| i.face)
    }

    #[inline]
    pub(crate) fn incidences(&self, e: usize) -> &[Incidence] {
        &self.incidences[self.start[e] as usize..self.start[e + 1] as usize]
    }
}

/// The front sign of every face (see [`EdgeTopology::front_signs`]): components by
/// union-find over shared edges; a component is closed and oriented when each of its
/// edges has exactly two faces, one running forward and one backward.
fn front_signs(topo: &EdgeTopology, positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<i8> {
    let nf = triangles.len();
    let mut parent: Vec<u32> = (0..nf as u32).collect();
    fn root(parent: &mut [u32], mut f: u32) -> u32 {
        while parent[f as usize] != f {
            let p = parent[f as usize];
            parent[f as usize] = parent[p as usize];
            f = p;
        }
        f
    }
    let mut bad = vec![false; nf];
    for e in 0..topo.ends.len() {
        let inc = topo.incidences(e);
        let ok = inc.len() == 2 && inc[0].forward != inc[1].forward && inc[0].face != inc[1].face;
        if let [first, rest @ ..] = inc {
            for i in rest {
                let (a, b) = (root(&mut parent, first.face), root(&mut parent, i.face));
                if a != b {
                    parent[a as usize] = b;
                }
            }
        }
        if !ok {
            for i in inc {
                bad[i.face as usize] = true;
            }
        }
    }
    // A face none of whose edges is listed (degenerate, or beyond the vertices) is bad.
    let mut seen = vec![false; nf];
    for i in &topo.incidences {
        seen[i.face as usize] = true;
    }
    let n = positions.len();
    let mut comp_bad = vec![false; nf];
    let mut volume = vec![0.0f64; nf];
    for f in 0..nf {
        let r = root(&mut parent, f as u32) as usize;
        let t = triangles[f];
        if bad[f] || !seen[f] || t.iter().any(|&i| i as usize >= n) {
            comp_bad[r] = true;
            continue;
        }
        let [a, b, c] = t.map(|i| positions[i as usize]);
        volume[r] += a.dot(b.cross(c));
    }
    (0..nf)
        .map(|f| {
            let r = root(&mut parent, f as u32) as usize;
            let v = volume[r];
            if comp_bad[r] || !v.is_finite() || v == 0.0 {
                0
            } else if v > 0.0 {
                -1
            } else {
                1
            }
        })
        .collect()
}

/// Per vertex, the smallest original index of the vertices welded with it.
fn weld(positions: &[DVec3]) -> Vec<u32> {
    let finite = || positions.iter().filter(|p| p.is_finite());
    let lo = finite().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let hi = finite().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
    let diag = (hi - lo).length();
    let step = if diag.is_finite() && diag > 0.0 {
        diag * WELD_TOLERANCE
    } else {
        1.0
    };
    // Grid coordinates are in [0, 1e7]; non-finite vertices get a key of their own.
    let mut keyed: Vec<([i64; 3], u32)> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let key = if p.is_finite() {
                ((*p - lo) / step).round().to_array().map(|c| c as i64)
            } else {
                [-1, i as i64, 0]
            };
            (key, i as u32)
        })
        .collect();
    keyed.sort_unstable();
    let mut rep = vec![0u32; positions.len()];
    let mut first = 0;
    for k in 0..keyed.len() {
        if keyed[k].0 != keyed[first].0 {
            first = k;
        }
        rep[keyed[k].1 as usize] = keyed[first].1;
    }
    rep
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube with 24 vertices (4 per face, as glTF's Box stores it).
    fn seam_cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut pos = Vec::new();
        let mut tris = Vec::new();
        for axis in 0..3 {
            for side in [0.0, 1.0] {
                let base = pos.len() as u32;
                for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    pos.push(DVec3::from_array(p));
                }
                // Counter-clockwise seen from outside: (u, v) turn about +axis.
                if side == 1.0 {
                    tris.push([base, base + 1, base + 2]);
                    tris.push([base, base + 2, base + 3]);
                } else {
                    tris.push([base, base + 2, base + 1]);
                    tris.push([base, base + 3, base + 2]);
                }
            }
        }
        (pos, tris)
    }

    #[test]
    fn a_seamed_cube_welds_into_a_closed_mesh() {
        let (pos, tris) = seam_cube();
        let t = EdgeTopology::new(&pos, &tris);
        assert_eq!(t.welded_vertex_count(), 8);
        // 12 cube edges + 6 face diagonals, each shared by exactly two faces.
        assert_eq!(t.edge_count(), 18);
        for e in 0..t.edge_count() {
            assert_eq!(t.faces(e).count(), 2, "edge {e}");
            let [a, b] = t.ends(e);
            assert!(a < b);
            // Representatives are the smallest index holding that position.
            for v in [a, b] {
                assert!(pos[..v as usize].iter().all(|p| *p != pos[v as usize]));
            }
            // The two faces run through the edge in opposite directions (consistent winding).
            let inc = t.incidences(e);
            assert_ne!(inc[0].forward, inc[1].forward);
        }
        // Closed and wound outwards: a front face projects with negative area.
        assert!(t.front_signs().iter().all(|&s| s == -1));
        // Inwards: positive; with one face flipped: not oriented, nothing is culled.
        let inward: Vec<[u32; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert!(EdgeTopology::new(&pos, &inward).front_signs().iter().all(|&s| s == 1));
        let mut flipped = tris.clone();
        flipped[3] = [flipped[3][0], flipped[3][2], flipped[3][1]];
        assert!(EdgeTopology::new(&pos, &flipped).front_signs().iter().all(|&s| s == 0));
        // An open mesh (a face removed) is never culled either.
        assert!(EdgeTopology::new(&pos, &tris[1..])
            .front_signs()
            .iter()
            .all(|&s| s == 0));
    }

    #[test]
    fn weld_tolerance_is_relative_to_the_box() {
        let (mut pos, tris) = seam_cube();
        // A copy moved by 1e-9 of the diagonal still welds; one moved by 1e-5 does not.
        pos[4] += DVec3::splat(1e-9);
        assert_eq!(EdgeTopology::new(&pos, &tris).welded_vertex_count(), 8);
        pos[4] += DVec3::splat(1e-5);
        assert_eq!(EdgeTopology::new(&pos, &tris).welded_vertex_count(), 9);
    }

    #[test]
    fn non_manifold_edges_keep_every_face_and_bad_input_does_not_panic() {
        let pos = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::Y,
            DVec3::splat(f64::NAN),
        ];
        let tris = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [0, 1, 9], [0, 0, 1], [5, 0, 1]];
        let t = EdgeTopology::new(&pos, &tris);
        let e = (0..t.edge_count()).find(|&e| t.ends(e) == [0, 1]).unwrap();
        // Faces 0, 1, 2, 5 and the degenerate face 4 (whose edge 0–1 appears twice).
        assert_eq!(t.faces(e).collect::<Vec<_>>(), vec![0, 1, 2, 4, 4, 5]);
        assert_eq!(t.welded_vertex_count(), 6);
        assert!(EdgeTopology::new(&[], &[[0, 1, 2]]).edge_count() == 0);
    }
}
