//! The mesh of the big-input benchmark: a closed, bumpy, asymmetric ellipsoid about
//! 12 cm long with exactly 1,000,000 triangles (a stand-in for a dense scan), written
//! as `OUT_DIR/big.glb`. `scripts/bench-big.sh` then makes eight 4032×3024 views of it
//! with `localisebot synth` and fits them on the command line and on the page.
//!
//! ```text
//! cargo run --release --example big_scene -- OUT_DIR
//! ```

use glam::DVec3;
use localisebot::io::gltf_write;
use localisebot::Mesh;
use std::f64::consts::{PI, TAU};

/// Rings of latitude (poles included) and meridians: 2·LON·(LAT − 2) = 1,000,000 triangles.
const LAT: usize = 502;
const LON: usize = 1000;

/// The surface along unit direction `d`: an ellipsoid (semi-axes 6, 4 and 3 cm) with
/// bumps of a few millimetres, none of them symmetric about an axis or a plane.
fn surface(d: DVec3) -> DVec3 {
    let bump = 1.0
        + 0.08 * (3.0 * d.x + 1.0).sin() * (2.0 * d.y - 0.5).cos()
        + 0.05 * (5.0 * d.z + 2.0 * d.x).sin()
        + 0.12 * d.x.max(0.0) * d.y.max(0.0)
        + 0.01 * (40.0 * d.y).sin() * (37.0 * d.z).cos(); // fine detail: a scan's texture
    d * DVec3::new(0.06, 0.04, 0.03) * bump
}

fn big_mesh() -> Mesh {
    let dir = |theta: f64, phi: f64| DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
    let mut positions = vec![surface(DVec3::Y)];
    for i in 1..LAT - 1 {
        let theta = PI * i as f64 / (LAT - 1) as f64;
        positions.extend((0..LON).map(|j| surface(dir(theta, TAU * j as f64 / LON as f64))));
    }
    positions.push(surface(-DVec3::Y));
    let south = (positions.len() - 1) as u32;
    let at = |i: usize, j: usize| (1 + (i - 1) * LON + j % LON) as u32; // ring i ≥ 1, meridian j
    let mut triangles = Vec::with_capacity(2 * LON * (LAT - 2));
    for j in 0..LON {
        triangles.push([0, at(1, j + 1), at(1, j)]); // north cap
        triangles.push([south, at(LAT - 2, j), at(LAT - 2, j + 1)]); // south cap
        for i in 1..LAT - 2 {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    Mesh { positions, triangles }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::path::PathBuf::from(std::env::args().nth(1).ok_or("usage: big_scene OUT_DIR")?);
    let mesh = big_mesh();
    mesh.validate("big.glb")?;
    std::fs::create_dir_all(&out)?;
    let path = out.join("big.glb");
    std::fs::write(&path, gltf_write::glb(&mesh, "big.glb")?)?;
    println!(
        "{}: {} vertices, {} triangles, diameter {:.3} m",
        path.display(),
        mesh.positions.len(),
        mesh.triangle_count(),
        mesh.diameter()
    );
    Ok(())
}
