//! The native side of the wasm parity check: fits `tests/fixtures/scenes/avocado-3view`
//! natively and checks that the result matches `native_fit.json` there, the file the
//! WebAssembly suites (`tests/wasm_common`) compare their own fit with. After a change
//! to the estimator, rewrite it with `LOCALISEBOT_BLESS=1 cargo test --test wasm_parity`.
#![cfg(not(target_arch = "wasm32"))]

use localisebot::estimator::{Estimator, FitSettings};
use localisebot::load_scene;
use serde_json::Value;
use std::path::PathBuf;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/scenes/avocado-3view")
}

/// Equal structure and strings; numbers equal to 1e-9 relative.
fn close(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-9 * (1.0 + y.abs())
        }
        (Value::Array(x), Value::Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y)),
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
        }
        _ => a == b,
    }
}

#[test]
fn the_recorded_native_fit_is_current() {
    let dir = dir();
    let text = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    let scene = load_scene("scene.json", &text, &|p| std::fs::read(dir.join(p)).ok()).unwrap();
    let mut est = Estimator::new(scene.mesh, scene.views, scene.initial_pose, FitSettings::default()).unwrap();
    while !est.is_done() {
        est.step().unwrap();
    }
    let result = est.result(0.0, scene.ground_truth_pose.as_ref());
    let now = serde_json::to_value(&result).unwrap();
    let path = dir.join("native_fit.json");
    if std::env::var_os("LOCALISEBOT_BLESS").is_some() {
        std::fs::write(&path, serde_json::to_string_pretty(&now).unwrap() + "\n").unwrap();
    }
    let recorded: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let stale = "native_fit.json is stale: rewrite it with `LOCALISEBOT_BLESS=1 cargo test --test wasm_parity`";
    assert!(
        close(&now["pose"], &recorded["pose"]),
        "{stale}: pose {} vs {}",
        now["pose"],
        recorded["pose"]
    );
    assert!(
        close(&now["views"], &recorded["views"]),
        "{stale}: views {} vs {}",
        now["views"],
        recorded["views"]
    );
    assert_eq!(now["iterations"], recorded["iterations"], "{stale}");
    // The recorded fit is a good one, so the wasm suites compare with a sound reference.
    assert!(now["mean_iou"].as_f64().unwrap() >= 0.95);
    assert!(now["errors"]["rotation_deg"].as_f64().unwrap() < 2.0);
}
