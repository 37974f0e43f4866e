use localisebot::*;
use std::time::Instant;
fn main() {
    let bytes = std::fs::read("tests/fixtures/gltf/Duck/glTF-Binary/Duck.glb").unwrap();
    let mesh = io::load_mesh("Duck.glb", &bytes, &io::no_files).unwrap();
    let c = mesh.clustered(24);
    println!("duck {} tris, clustered {} tris", mesh.triangles.len(), c.triangles.len());
    let s = synth::synthesize(&mesh, &synth::SynthSettings{width:64,height:64,..Default::default()}, None).unwrap();
    let cam = s.cameras[0];
    for (name, m) in [("full", &mesh), ("clustered", &c)] {
        let t = Instant::now();
        let n = 2000;
        let mut acc = 0u64;
        for _ in 0..n {
            let p = raster::project::project_mesh(m, &s.pose, &cam);
            let b = raster::hard::render_bits(&p, &m.triangles, &cam);
            acc += b.count();
        }
        println!("{name}: {:.1} us per project+render_bits (acc {acc})", t.elapsed().as_secs_f64() * 1e6 / n as f64);
    }
}
