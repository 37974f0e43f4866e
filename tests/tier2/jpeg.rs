//! Photographs as a phone gives them: JPEG, stored sideways with an EXIF orientation
//! tag. The LM-O ape's three photographs (`../shared/data/real/lmo`, boxes as in
//! `photos.rs`) are turned a quarter anticlockwise as stored and tagged "turn a quarter
//! clockwise to show" (EXIF 6, what a phone held upright writes), JPEG-compressed at
//! quality 90, and fitted from their boxes through the command line, beside the same
//! scene with the PNGs: the pictures as shown are the same, so the poses must be too.

use crate::support::jpeg::sideways_jpeg;

#[test]
fn phone_jpegs_stored_sideways_fit_like_the_pngs() {
    let d = std::env::temp_dir().join(format!("localisebot-jpeg-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let pngs = d.join("pngs");
    crate::import_lmo_boxes(1, "263,310,819", &pngs);
    // The same scene with each photograph a sideways JPEG beside the PNG.
    let text = std::fs::read_to_string(pngs.join("scene.json")).unwrap();
    let mut scene: serde_json::Value = serde_json::from_str(&text).unwrap();
    for v in scene["views"].as_array_mut().unwrap() {
        assert!(v.get("mask").is_none() && v.get("box").is_some(), "{v}");
        let png = v["image"].as_str().unwrap().to_string();
        let shown = image::open(pngs.join(&png)).unwrap().to_rgb8();
        let bytes = sideways_jpeg(&shown, 90);
        let jpg = png.replace(".png", ".jpg");
        std::fs::write(pngs.join(&jpg), bytes).unwrap();
        v["image"] = jpg.into();
    }
    let jpegs = pngs.join("jpegs.json");
    std::fs::write(&jpegs, scene.to_string()).unwrap();
    let fit = |scene: &std::path::Path, out: &str| {
        let out = d.join(out);
        crate::localisebot(&["fit", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(out).unwrap()).unwrap()
    };
    let from_png = fit(&pngs.join("scene.json"), "png.json");
    let from_jpeg = fit(&jpegs, "jpeg.json");
    let add = |r: &serde_json::Value| r["errors"]["add_rel"].as_f64().unwrap();
    let rotation = |r: &serde_json::Value| r["errors"]["rotation_deg"].as_f64().unwrap();
    println!(
        "LM-O ape from boxes: PNGs ADD {:.2} % d, rotation {:.1}°, verdict {}; sideways JPEGs ADD {:.2} % d, \
         rotation {:.1}°, verdict {}",
        100.0 * add(&from_png),
        rotation(&from_png),
        from_png["verdict"],
        100.0 * add(&from_jpeg),
        rotation(&from_jpeg),
        from_jpeg["verdict"]
    );
    // Read sideways (the tag ignored), the photographs would not match their cameras'
    // 640×480 and the load would fail; read turned, the JPEGs fit as the PNGs do.
    assert!(add(&from_jpeg) < 0.1, "{}", from_jpeg["errors"]);
    assert!(
        (add(&from_jpeg) - add(&from_png)).abs() < 0.02,
        "PNG {} against JPEG {}",
        add(&from_png),
        add(&from_jpeg)
    );
    let _ = std::fs::remove_dir_all(&d);
}
