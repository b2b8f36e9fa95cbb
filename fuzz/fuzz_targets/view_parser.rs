//! Bytes in, `Result` out: the view parser and its validation must never
//! panic, and a view they accept must give the renderer only finite numbers
//! (camera frame, light samples, shading and shadow parameters).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use penumbra::pass_inputs::camera_params;
use penumbra::reference::shade::shade_params;
use penumbra::reference::shadow_per_ray::shadow_params;
use penumbra::sampling::light_points;
use penumbra::scene::view::View;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(view) = View::from_json(text, Path::new("fuzz.json")) else {
        return;
    };
    for (w, h) in [(1, 1), (7, 1), (1024, 768)] {
        let cam = camera_params(&view.camera, w, h, 1e-3);
        for v in [cam.eye, cam.forward, cam.right, cam.up] {
            assert!(v.is_finite(), "{view:?} gives camera {cam:?}");
        }
        assert!(cam.forward.length() > 0.5 && cam.right.length() > 0.0 && cam.up.length() > 0.0);
        let shade = shade_params(&view.light, w, h);
        assert!(
            shade.light_center.is_finite()
                && shade.light_normal.is_finite()
                && shade.light_area.is_finite()
                && shade.light_area > 0.0
                && shade.radiance.is_finite(),
            "{view:?} gives shade params {shade:?}"
        );
        let shadow = shadow_params(&view.light, w, h);
        assert!(
            shadow.light_normal.is_finite()
                && shadow.light_corners.iter().flatten().all(|c| c.is_finite()),
            "{view:?} gives shadow params {shadow:?}"
        );
    }
    assert!(light_points(&view.light).iter().all(|p| p.is_finite()), "{view:?}");
    // What the parser accepts, it writes back and reads again unchanged.
    let again = View::from_json(&view.to_json(), Path::new("again.json")).expect("round trip");
    assert_eq!(again, view);
});
