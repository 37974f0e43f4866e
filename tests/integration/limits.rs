//! Every limit refuses before allocating (issue 23, item 2): files that declare huge
//! sizes or counts in a few bytes are refused with a message naming the limit, and the
//! thread that read them allocated little. The allocator below counts the bytes each
//! thread asks for, so the figure is this test's own, whatever runs beside it.

use glam::DVec3;
use localisebot::io::png::encode_gray;
use localisebot::io::scene::load_scene_with;
use localisebot::{io, CameraJson, Limits, Mesh};
use serde_json::{json, Value};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATED: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATED.try_with(|a| a.set(a.get() + layout.size() as u64));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATED.try_with(|a| a.set(a.get() + new_size as u64));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

/// Runs `f`; returns its result and the bytes this thread allocated meanwhile.
fn allocated<T>(f: impl FnOnce() -> T) -> (T, u64) {
    let before = ALLOCATED.with(Cell::get);
    let out = f();
    (out, ALLOCATED.with(Cell::get) - before)
}

/// `f` fails with every one of `says`, having allocated under 1 MiB.
fn refused_cheaply<T: std::fmt::Debug>(f: impl FnOnce() -> localisebot::Result<T>, says: &[&str]) {
    refused_within(1 << 20, f, says)
}

/// `f` fails with every one of `says`, having allocated under `budget` bytes in all.
fn refused_within<T: std::fmt::Debug>(budget: u64, f: impl FnOnce() -> localisebot::Result<T>, says: &[&str]) {
    let (r, bytes) = allocated(f);
    let e = r.unwrap_err().to_string();
    assert!(says.iter().all(|s| e.contains(s)), "{e}\n  expected {says:?}");
    assert!(bytes < budget, "{bytes} bytes allocated before the refusal: {e}");
}

fn ply_header(vertices: u64, faces: u64) -> Vec<u8> {
    format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes()
}

#[test]
fn a_ply_declaring_billions_of_vertices_is_refused_from_its_header() {
    let mut bytes = ply_header(4_000_000_000, 1);
    bytes.extend([0u8; 64]);
    refused_cheaply(
        || io::load_mesh("scan.ply", &bytes, &io::no_files),
        &[
            "scan.ply",
            "vertex count 4000000000 exceeds the limit of 10000000",
            "--limit vertices=N",
        ],
    );
    // Within the count limit, but more than the bytes that follow can hold.
    let mut bytes = ply_header(9_000_000, 9_000_000);
    bytes.extend([0u8; 64]);
    refused_cheaply(
        || io::load_mesh("scan.ply", &bytes, &io::no_files),
        &[
            "scan.ply",
            "declares 9000000 'vertex' elements",
            "64 bytes follow the header",
        ],
    );
    // A lowered limit refuses a small, honest file.
    let mut l = Limits::DEFAULT;
    l.set("triangles", 11).unwrap();
    let cube = io::gltf_write::glb(&Mesh::cuboid(DVec3::ONE), "cube.glb").unwrap();
    refused_cheaply(
        || io::load_mesh_with("cube.glb", &cube, &io::no_files, &l),
        &["cube.glb", "triangle count 12 exceeds the limit of 11"],
    );
    l.set("triangles", 12).unwrap();
    io::load_mesh_with("cube.glb", &cube, &io::no_files, &l).unwrap();
}

/// A glTF document whose one accessor declares `count` positions, over a tiny buffer,
/// instanced by `nodes` nodes.
fn gltf_declaring(count: u64, nodes: usize) -> Vec<u8> {
    let node_list: Vec<Value> = (0..nodes).map(|_| json!({"mesh": 0})).collect();
    let ids: Vec<usize> = (0..nodes).collect();
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": node_list,
        "scenes": [{"nodes": ids}],
        "scene": 0
    })
    .to_string()
    .into_bytes()
}

#[test]
fn a_gltf_declaring_more_than_the_limits_is_refused_before_its_buffers_are_read() {
    // A valid triangle first: the document is well formed.
    io::load_mesh("t.gltf", &gltf_declaring(3, 1), &io::no_files).unwrap();
    refused_cheaply(
        || io::load_mesh("big.gltf", &gltf_declaring(3_000_000_000, 1), &io::no_files),
        &["big.gltf", "vertex count 3000000000 exceeds the limit"],
    );
    // Instancing multiplies: a small mesh placed by many nodes is counted each time.
    let mut l = Limits::DEFAULT;
    l.set("triangles", 1000).unwrap();
    // (the document of 1001 nodes, 15 kB, costs the JSON parser about 2.4 MB in all).
    refused_within(
        4 << 20,
        || io::load_mesh_with("many.gltf", &gltf_declaring(3, 1001), &io::no_files, &l),
        &["many.gltf", "triangle count 1001 exceeds the limit of 1000"],
    );
    let deep = format!("{{\"asset\": {}}}", "[".repeat(100));
    refused_cheaply(
        || io::load_mesh("deep.gltf", deep.as_bytes(), &io::no_files),
        &["deep.gltf", "nested deeper than 64"],
    );
}

#[test]
fn an_obj_is_counted_before_it_is_parsed() {
    let mut l = Limits::DEFAULT;
    l.set("vertices", 3).unwrap();
    refused_cheaply(
        || {
            io::load_mesh_with(
                "q.obj",
                b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
                &io::no_files,
                &l,
            )
        },
        &["q.obj", "vertex count 4 exceeds the limit of 3"],
    );
}

/// CRC-32 (PNG's), to patch a header.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

/// A valid 2×2 grey PNG whose header then declares `w`×`h` (CRC fixed).
fn png_declaring(w: u32, h: u32) -> Vec<u8> {
    let mut png = encode_gray(2, 2, &[255, 0, 0, 255]);
    png[16..20].copy_from_slice(&w.to_be_bytes());
    png[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    png
}

/// A scene of `views` views whose cameras are `w`×`h`, each mask `m.png`, the mesh `m.obj`.
fn scene_of(views: usize, w: u32, h: u32) -> String {
    let cam = |i: usize| {
        let mut c = json!({"width": w, "height": h, "fx": 500.0, "fy": 500.0, "cx": w as f64 / 2.0, "cy": h as f64 / 2.0,
                           "world_to_camera": [[1,0,0,0],[0,1,0,0],[0,0,1,5],[0,0,0,1]]});
        c["world_to_camera"][0][3] = json!(i as f64 * 0.01);
        serde_json::from_value::<CameraJson>(c).unwrap()
    };
    let v: Vec<Value> = (0..views)
        .map(|i| json!({"name": format!("v{i}"), "mask": "m.png", "camera": serde_json::to_value(cam(i)).unwrap()}))
        .collect();
    json!({"mesh": "m.obj", "views": v}).to_string()
}

#[test]
fn pixels_and_views_are_counted_from_the_cameras_before_any_mask_is_read() {
    let fetched = Cell::new(0);
    let files = |p: &str| -> Option<Vec<u8>> {
        fetched.set(fetched.get() + 1);
        match p {
            "m.obj" => Some(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec()),
            "m.png" => Some(png_declaring(16000, 16000)),
            _ => None,
        }
    };
    let l = Limits::DEFAULT;
    // A 16000×16000 camera: 256 Mpx, over the 64-Mpx limit of a view.
    let text = scene_of(1, 16000, 16000);
    refused_cheaply(
        || load_scene_with("s.json", &text, &files, &l),
        &["view 'v0'", "16000×16000", "view_pixels"],
    );
    // Twenty-two 12-Mpx phone photographs are within the limits; twenty-three are not.
    let text = scene_of(23, 4032, 3024);
    refused_cheaply(
        || load_scene_with("s.json", &text, &files, &l),
        &["view 'v22'", "total_pixels", "--limit total_pixels=N"],
    );
    let text = scene_of(300, 64, 48);
    refused_cheaply(
        || load_scene_with("s.json", &text, &files, &l),
        &["s.json", "number of views 300 exceeds the limit of 256"],
    );
    // The pixel checks came before any mask: only the mesh was fetched, once a scene.
    assert_eq!(fetched.get(), 2, "masks were fetched before the refusals");
    // A mask whose header declares a size not the camera's is refused from its header.
    let text = scene_of(1, 64, 48);
    refused_cheaply(
        || load_scene_with("s.json", &text, &files, &l),
        &["view 'v0'", "m.png", "16000×16000 but the camera is 64×48"],
    );
    // A file over file_bytes.
    let mut small = Limits::DEFAULT;
    small.set("file_bytes", 40).unwrap();
    refused_cheaply(|| load_scene_with("s.json", &text, &files, &small), &["file_bytes"]);
    let deep = format!("{{\"mesh\": \"m.obj\", \"views\": {}", "[".repeat(65));
    refused_cheaply(
        || load_scene_with("s.json", &deep, &files, &l),
        &["s.json", "nested deeper than 64"],
    );
}

#[test]
fn the_command_line_sets_limits_and_names_them() {
    let dir = super::cli::tmp("limits");
    let mesh = dir.join("cube.glb");
    std::fs::write(
        &mesh,
        io::gltf_write::glb(&Mesh::cuboid(DVec3::ONE), "cube.glb").unwrap(),
    )
    .unwrap();
    let ok = super::cli::bin()
        .args(["--limit", "triangles=12", "info"])
        .arg(&mesh)
        .output()
        .unwrap();
    assert!(ok.status.success(), "{}", super::cli::stderr(&ok));
    let o = super::cli::bin()
        .args(["info", "--limit", "triangles=11"])
        .arg(&mesh)
        .output()
        .unwrap();
    let e = super::cli::stderr(&o);
    assert!(
        !o.status.success() && e.contains("cube.glb") && e.contains("triangle count 12 exceeds the limit of 11"),
        "{e}"
    );
    let o = super::cli::bin()
        .args(["info", "--limit", "file_bytes=100"])
        .arg(&mesh)
        .output()
        .unwrap();
    let e = super::cli::stderr(&o);
    assert!(!o.status.success() && e.contains("file_bytes"), "{e}");
    let o = super::cli::bin()
        .args(["info", "--limit", "pixels=5"])
        .arg(&mesh)
        .output()
        .unwrap();
    let e = super::cli::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("unknown limit 'pixels'"), "{e}");
}
