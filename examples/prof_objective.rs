use localisebot::app::synth::{synthesize, SynthSettings};
use localisebot::loss::objective::{Objective, ObjectiveSettings};
use localisebot::loss::target::Window;
use localisebot::raster::silhouette::{RasterKind, RenderMesh};
use localisebot::raster::soft::SoftSettings;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = &args[1];
    let size: u32 = args.get(2).map_or(128, |s| s.parse().unwrap());
    let n: usize = args.get(3).map_or(500, |s| s.parse().unwrap());
    let gn = args.get(4).is_some_and(|s| s == "gn");
    let mesh = localisebot::io::load_mesh(path, &std::fs::read(path).unwrap(), &|_| None).unwrap();
    let s = synthesize(
        &mesh,
        &SynthSettings {
            views: 4,
            width: size,
            height: size,
            seed: 11,
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let views = s.views();
    let windows: Vec<Window> = views.iter().map(|v| Window::full(v.camera())).collect();
    let set = ObjectiveSettings {
        soft: SoftSettings { sigma: 1.0, eps: 1e-4 },
        lambda_iou: 1.0,
        lambda_contour: 1.0,
        raster: RasterKind::Edge,
    };
    let mut o = Objective::new(&views, &windows, size, set).unwrap();
    let model = RenderMesh::new(mesh.clone());
    let mut p = s.pose;
    p.translation += glam::DVec3::splat(0.01 * mesh.diameter());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        let t = std::time::Instant::now();
        for _ in 0..n {
            if gn {
                o.normal_equations(&model, &p).unwrap();
            } else {
                o.value_and_gradient(&model, &p).unwrap();
            }
        }
        println!("{:.3} ms per evaluation", t.elapsed().as_secs_f64() * 1e3 / n as f64);
    });
}
