//! Prints (does not assert) the silhouette-edge soft rasteriser's timings: 4 views of
//! a mesh, forward + gradient records, next to the hard raster alone and the SoftRas
//! forward, single-threaded.
//!
//! `cargo run --release --example edge_timing [mesh.glb …]` (default: the shared Duck,
//! a 2000-triangle blob and the shared 2CylinderEngine).

use glam::DVec3;
use localisebot::raster::edge::{EdgeSilhouette, EdgeTopology};
use localisebot::raster::hard;
use localisebot::raster::project::project_mesh;
use localisebot::raster::soft::{SoftRasterizer, SoftSettings};
use localisebot::{Camera, Mask, Mesh, Pose};
use std::time::Instant;

fn cameras(mesh: &Mesh, size: u32) -> Vec<Camera> {
    let b = mesh.bounds().expect("empty mesh");
    let (c, r) = (b.centre(), b.size().length() * 0.5);
    [
        DVec3::new(1.0, 0.5, 1.0),
        DVec3::new(-1.0, 0.6, 0.8),
        DVec3::new(0.2, 1.0, -1.0),
        DVec3::new(-0.7, -0.4, -1.0),
    ]
    .iter()
    .map(|d| {
        Camera::look_at(
            c + d.normalize() * r * 3.5,
            c,
            DVec3::Y,
            size,
            size,
            150.0 * size as f64 / 128.0,
        )
    })
    .collect()
}

/// Best and median of `reps` runs of `f`, in milliseconds.
fn time(reps: usize, mut f: impl FnMut()) -> (f64, f64) {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(|a, b| a.partial_cmp(b).unwrap());
    (t[0], t[reps / 2])
}

fn run(label: &str, mesh: &Mesh, size: u32) {
    let cams = cameras(mesh, size);
    let s = SoftSettings::from_ndc(1e-4, size, size);
    let t0 = Instant::now();
    let topo = EdgeTopology::from_mesh(mesh);
    let t_topo = t0.elapsed().as_secs_f64() * 1e3;
    let projs: Vec<_> = cams.iter().map(|c| project_mesh(mesh, &Pose::IDENTITY, c)).collect();
    let mut sils: Vec<EdgeSilhouette> = cams.iter().map(|_| EdgeSilhouette::new()).collect();
    let reps = if mesh.triangles.len() > 50_000 { 15 } else { 60 };
    let edge = time(reps, || {
        for ((sil, p), c) in sils.iter_mut().zip(&projs).zip(&cams) {
            sil.render(&topo, p, &mesh.triangles, c, &s).unwrap();
        }
    });
    let project = time(reps, || {
        for c in &cams {
            std::hint::black_box(project_mesh(mesh, &Pose::IDENTITY, c));
        }
    });
    let mut masks: Vec<Mask> = cams.iter().map(|_| Mask::empty(0, 0)).collect();
    let hard_only = time(reps, || {
        for ((m, p), c) in masks.iter_mut().zip(&projs).zip(&cams) {
            hard::render_projected_into(p, &mesh.triangles, c, m);
        }
    });
    let mut softs: Vec<SoftRasterizer> = cams.iter().map(|_| SoftRasterizer::new()).collect();
    let soft = time(reps.min(15), || {
        for (r, c) in softs.iter_mut().zip(&cams) {
            r.render(mesh, &Pose::IDENTITY, c, &s).unwrap();
        }
    });
    let outline: usize = sils.iter().map(|s| s.outline_edges()).sum();
    let records: usize = sils.iter().map(|s| s.records().len()).sum();
    println!(
        "{label}: {} tris, {} edges (topology {t_topo:.2} ms), {} views {size}²: edge forward+records \
         {:.3} ms best / {:.3} median ({:.0} outline edges, {:.0} records per view); hard alone {:.3} ms; \
         projection {:.3} ms; SoftRas forward {:.2} ms",
        mesh.triangles.len(),
        topo.edge_count(),
        cams.len(),
        edge.0,
        edge.1,
        outline as f64 / cams.len() as f64,
        records as f64 / cams.len() as f64,
        hard_only.0,
        project.0,
        soft.0,
    );
}

fn load(path: &str) -> Option<Mesh> {
    let bytes = std::fs::read(path).ok()?;
    match localisebot::io::load_mesh(path, &bytes, &|_| None) {
        Ok(m) => Some(m),
        Err(e) => {
            println!("{path}: {e}");
            None
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let shared = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/gltf");
    let paths = if args.is_empty() {
        vec![
            format!("{shared}/Duck/glTF-Binary/Duck.glb"),
            "blob2k".into(),
            format!("{shared}/2CylinderEngine/glTF-Binary/2CylinderEngine.glb"),
        ]
    } else {
        args
    };
    for p in &paths {
        let mesh = if p == "blob2k" {
            Some(localisebot::app::synth::blob_mesh(22, 50))
        } else {
            load(p)
        };
        let Some(mesh) = mesh else {
            println!("{p}: skipped (not found)");
            continue;
        };
        let name = std::path::Path::new(p)
            .file_stem()
            .map_or(p.clone(), |s| s.to_string_lossy().into());
        for size in [128, 256] {
            run(&name, &mesh, size);
        }
    }
}
