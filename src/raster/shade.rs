//! A plain shaded render (z-buffer, flat Lambert shading, soft background) of a
//! posed mesh: the "photographs" of synthetic scenes and of the bundled example.
//! Display only — the fit never looks at images.

use crate::camera::Camera;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::project::project_mesh;
use crate::view::Rgba;
use glam::DVec3;

/// Renders `mesh` at `pose` into `camera` with a headlight-style light, RGBA8.
pub fn render_shaded(mesh: &Mesh, pose: &Pose, camera: &Camera, colour: [u8; 3]) -> Rgba {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut depth = vec![f64::INFINITY; w * h];
    let mut data = vec![0u8; w * h * 4];
    for y in 0..h {
        for x in 0..w {
            let g = (200.0 - 60.0 * y as f64 / h as f64) as u8;
            data[(y * w + x) * 4..(y * w + x) * 4 + 4].copy_from_slice(&[g, g, g.saturating_add(12), 255]);
        }
    }
    let proj = project_mesh(mesh, pose, camera);
    let light = DVec3::new(-0.4, -0.6, -1.0).normalize();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if !(proj.in_front(a) && proj.in_front(b) && proj.in_front(c)) {
            continue;
        }
        let (pa, pb, pc) = (proj.uv[a], proj.uv[b], proj.uv[c]);
        let area = (pb - pa).perp_dot(pc - pa);
        if area.abs() < 1e-12 {
            continue;
        }
        let n = (proj.cam[b] - proj.cam[a])
            .cross(proj.cam[c] - proj.cam[a])
            .normalize_or_zero();
        let shade = 0.25 + 0.75 * n.dot(light).abs();
        let rgb = colour.map(|c| (c as f64 * shade).min(255.0) as u8);
        let (iz_a, iz_b, iz_c) = (1.0 / proj.cam[a].z, 1.0 / proj.cam[b].z, 1.0 / proj.cam[c].z);
        let x0 = pa.x.min(pb.x).min(pc.x).ceil().max(0.0) as usize;
        let x1 = pa.x.max(pb.x).max(pc.x).floor().min(w as f64 - 1.0);
        let y0 = pa.y.min(pb.y).min(pc.y).ceil().max(0.0) as usize;
        let y1 = pa.y.max(pb.y).max(pc.y).floor().min(h as f64 - 1.0);
        if x1 < 0.0 || y1 < 0.0 {
            continue;
        }
        for y in y0..=y1 as usize {
            for x in x0..=x1 as usize {
                let p = glam::DVec2::new(x as f64, y as f64);
                let wa = (pb - p).perp_dot(pc - p) / area;
                let wb = (pc - p).perp_dot(pa - p) / area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                // 1/z is affine in screen space: nearest surface wins.
                let z = 1.0 / (wa * iz_a + wb * iz_b + wc * iz_c);
                let i = y * w + x;
                if z < depth[i] {
                    depth[i] = z;
                    data[i * 4..i * 4 + 4].copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
                }
            }
        }
    }
    Rgba {
        width: camera.width,
        height: camera.height,
        data,
    }
}
