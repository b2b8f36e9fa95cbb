//! Bad views are refused with an exact message naming the field at fault;
//! legal but suspicious ones (a light facing away from the scene, a camera
//! inside a closed object) pass validation and get a warning instead.

use std::path::Path;

use glam::{Vec2, Vec3};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::pass_inputs::camera_params;
use penumbra::reference::shade::shade_params;
use penumbra::scene::view::{Camera, QuadLight, View, ViewFile};
use penumbra::scene::view_checks::{ViewWarning, view_warnings};
use penumbra::scene::{Instance, LoadWarnings, Material, Scene, SceneTriangle};
use penumbra::{Error, sampling};

/// An ordinary view: looking at the origin from +z, a 1×1 light above facing down.
fn good() -> View {
    View {
        camera: Camera {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_degrees: 60.0,
        },
        light: QuadLight {
            corner: Vec3::new(-0.5, 4.0, -0.5),
            edge_u: Vec3::X,
            edge_v: Vec3::Z,
            color: Vec3::ONE,
            intensity: 2.0,
        },
        ground_y: None,
    }
}

/// `good()` changed by `edit` must fail validation with exactly `expected`.
fn refused(edit: impl FnOnce(&mut View), expected: &str) {
    let mut view = good();
    edit(&mut view);
    assert_eq!(view.validate(), Err(expected.to_owned()), "{view:?}");
    // The JSON route gives the same message, prefixed with the file.
    let path = Path::new("views/bad.json");
    if let Ok(text) = serde_json::to_string(&view) {
        // JSON has no NaN or infinity: serde writes them as null, which is a parse error instead.
        if view.validate().is_err() && !text.contains("null") {
            let err = View::from_json(&text, path).unwrap_err();
            assert_eq!(err.to_string(), format!("views/bad.json: {expected}"));
        }
    }
}

#[test]
fn the_good_view_passes_and_light_points_are_finite() {
    let view = good();
    assert_eq!(view.validate(), Ok(()));
    let light = view.light;
    assert!(sampling::light_points(&light).iter().all(|p| p.is_finite()));
    assert_eq!(shade_params(&light, 1, 1).light_area, 1.0);
}

#[test]
fn zero_area_lights() {
    refused(
        |v| v.light.edge_v = Vec3::new(2.0, 0.0, 0.0),
        "light has zero area: |edge_u × edge_v| = 0 (edge_u [1, 0, 0] and edge_v [2, 0, 0] are zero, \
         parallel or too short)",
    );
    refused(
        |v| v.light.edge_u = Vec3::ZERO,
        "light has zero area: |edge_u × edge_v| = 0 (edge_u [0, 0, 0] and edge_v [0, 0, 1] are zero, \
         parallel or too short)",
    );
    // Not exactly zero, but below what f32 can normalise.
    refused(
        |v| {
            v.light.edge_u = Vec3::new(1e-30, 0.0, 0.0);
            v.light.edge_v = Vec3::new(0.0, 0.0, 1e-30);
        },
        "light has zero area: |edge_u × edge_v| = 0 (edge_u [0.000000000000000000000000000001, 0, 0] \
         and edge_v [0, 0, 0.000000000000000000000000000001] are zero, parallel or too short)",
    );
}

#[test]
fn non_finite_numbers_anywhere() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    refused(|v| v.camera.eye.x = nan, "camera.eye [NaN, 1, 5] is not finite");
    refused(
        |v| v.camera.target.y = inf,
        "camera.target [0, inf, 0] is not finite",
    );
    refused(|v| v.camera.up.z = -inf, "camera.up [0, 1, -inf] is not finite");
    refused(
        |v| v.camera.fov_y_degrees = nan,
        "camera.fov_y_degrees NaN is not finite",
    );
    refused(
        |v| v.light.corner.x = nan,
        "light.corner [NaN, 4, -0.5] is not finite",
    );
    refused(
        |v| v.light.edge_u.x = inf,
        "light.edge_u [inf, 0, 0] is not finite",
    );
    refused(
        |v| v.light.edge_v.z = nan,
        "light.edge_v [0, 0, NaN] is not finite",
    );
    refused(|v| v.light.color.y = inf, "light.color [1, inf, 1] is not finite");
    refused(|v| v.light.intensity = nan, "light.intensity NaN is not finite");
    refused(|v| v.ground_y = Some(-inf), "ground_y -inf is not finite");
    // JSON cannot spell NaN, but a number beyond f32's range reads as infinity.
    let text = r#"{"camera": {"eye": [1e39, 0, 0], "target": [0, 0, 0], "fov_y_degrees": 45},
                   "light": {"corner": [0, 5, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1]}}"#;
    assert_eq!(
        View::from_json(text, Path::new("far.json"))
            .unwrap_err()
            .to_string(),
        "far.json: camera.eye [inf, 0, 0] is not finite"
    );
}

#[test]
fn degenerate_cameras() {
    refused(
        |v| v.camera.target = v.camera.eye,
        "camera.eye and camera.target are the same point [0, 1, 5]",
    );
    refused(
        |v| v.camera.up = Vec3::new(0.0, -2.0, -10.0),
        "camera.up [0, -2, -10] is zero or parallel to the view direction [0, -0.19611613, -0.9805807]",
    );
    refused(
        |v| v.camera.up = Vec3::ZERO,
        "camera.up [0, 0, 0] is zero or parallel to the view direction [0, -0.19611613, -0.9805807]",
    );
    // Finite ends whose difference is not.
    refused(
        |v| {
            v.camera.eye = Vec3::new(-3e38, 0.0, 0.0);
            v.camera.target = Vec3::new(3e38, 0.0, 0.0);
        },
        "camera.target - camera.eye = [inf, 0, 0] overflows f32",
    );
    for fov in [0.0, -10.0, 180.0, 181.0, 0.0009] {
        refused(
            |v| v.camera.fov_y_degrees = fov,
            &format!("camera.fov_y_degrees is {fov}, must be in [0.001, 180)"),
        );
    }
    // Found by fuzzing: tan(fov / 2) underflows to 0, so every pixel's ray is the same.
    refused(
        |v| v.camera.fov_y_degrees = 41e-45,
        "camera.fov_y_degrees is 0.00000000000000000000000000000000000000000004, must be in [0.001, 180)",
    );
}

#[test]
fn negative_or_overflowing_lights() {
    refused(
        |v| v.light.intensity = -1.0,
        "light.intensity is -1, must not be negative",
    );
    refused(
        |v| v.light.color = Vec3::new(1.0, -0.5, 1.0),
        "light.color [1, -0.5, 1] has a negative component",
    );
    refused(
        |v| {
            v.light.color = Vec3::splat(1e30);
            v.light.intensity = 1e30;
        },
        "light radiance color × intensity = [1000000000000000000000000000000, 1000000000000000000000000000000, \
         1000000000000000000000000000000] × 1000000000000000000000000000000 overflows f32",
    );
    refused(
        |v| {
            v.light.edge_u = Vec3::new(1e20, 0.0, 0.0);
            v.light.edge_v = Vec3::new(0.0, 0.0, 1e20);
        },
        "light is too large: |edge_u × edge_v|² overflows f32 (edge_u [100000000000000000000, 0, 0], \
         edge_v [0, 0, 100000000000000000000])",
    );
    refused(
        |v| {
            v.light.corner = Vec3::new(3e38, 0.0, 0.0);
            v.light.edge_u = Vec3::new(1e38, 0.0, 0.0);
            v.light.edge_v = Vec3::new(0.0, 0.0, 1e-20);
        },
        "light reaches past the f32 range (a corner or its centre is [inf, 0, 0])",
    );
}

#[test]
fn json_problems_name_the_file() {
    let cases = [
        ("{", "EOF while parsing an object at line 1 column 1"),
        (
            r#"{"camera": {"eye": [0, 0, 1], "target": [0, 0, 0], "fov_y_degrees": 45}}"#,
            r#"has no light: give "light": {…} or "lights": [{…}, …]"#,
        ),
        (
            r#"{"camera": {"eye": [0, 0, 1], "target": [0, 0, 0], "fov": 45}}"#,
            "unknown field `fov`, expected one of `eye`, `target`, `up`, `fov_y_degrees` at line 1 column 56",
        ),
    ];
    for (text, expected) in cases {
        let err = View::from_json(text, Path::new("v.json")).unwrap_err();
        assert!(matches!(err, Error::View { .. }), "{err:?}");
        assert_eq!(err.to_string(), format!("v.json: {expected}"));
    }
    let missing = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-such-view.json");
    let io = std::fs::read(&missing).unwrap_err();
    assert_eq!(
        View::load(&missing).unwrap_err().to_string(),
        format!("{}: {io}", missing.display())
    );
}

/// A view file may list several lights: each becomes a view with the same camera, in the
/// file's order; a one-light reader (View::from_json) refuses such a file by name.
#[test]
fn several_lights_give_one_view_each_and_one_light_readers_refuse_them() {
    let text = r#"{"camera": {"eye": [0, 0, 5], "target": [0, 0, 0], "fov_y_degrees": 45},
        "lights": [{"corner": [0, 3, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]},
                   {"corner": [2, 3, 0], "edge_u": [0.5, 0, 0], "edge_v": [0, 0, -0.5], "intensity": 4}],
        "ground_y": -1}"#;
    let file = ViewFile::from_json(text, Path::new("two.json")).unwrap();
    let views = file.views();
    assert_eq!(views.len(), 2);
    assert_eq!(views[0].light.corner, Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(views[1].light.intensity, 4.0);
    assert!(
        views
            .iter()
            .all(|v| v.camera == file.camera && v.ground_y == Some(-1.0))
    );
    assert_eq!(
        View::from_json(text, Path::new("two.json"))
            .unwrap_err()
            .to_string(),
        "two.json: has 2 lights; this traces one (penumbra render takes several)"
    );
    // One light, in either form, is the same view.
    let single = r#"{"camera": {"eye": [0, 0, 5], "target": [0, 0, 0], "fov_y_degrees": 45},
        "light": {"corner": [0, 3, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}}"#;
    let listed = r#"{"camera": {"eye": [0, 0, 5], "target": [0, 0, 0], "fov_y_degrees": 45},
        "lights": [{"corner": [0, 3, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1]}]}"#;
    assert_eq!(
        View::from_json(single, Path::new("a")).unwrap(),
        View::from_json(listed, Path::new("b")).unwrap()
    );
}

#[test]
fn validated_views_give_finite_camera_and_light_data() {
    // What validation promises the renderer, on a few edge-of-range views.
    let mut views = vec![good()];
    let mut v = good();
    v.camera.fov_y_degrees = 179.999;
    views.push(v);
    let mut v = good();
    v.camera.fov_y_degrees = penumbra::scene::view::MIN_FOV_Y_DEGREES;
    v.camera.up = Vec3::new(1e30, 1e30, 0.0);
    views.push(v);
    let mut v = good();
    v.camera.eye = Vec3::new(0.0, 1e-30, 5e-30);
    v.camera.target = Vec3::new(0.0, 0.0, 1e-44);
    views.push(v);
    let mut v = good();
    v.camera.eye = Vec3::new(-1e38, 0.0, 0.0);
    v.camera.target = Vec3::new(1e38, 0.0, 0.0);
    views.push(v);
    let mut v = good();
    v.light.edge_u = Vec3::new(1e9, 0.0, 0.0);
    v.light.edge_v = Vec3::new(0.0, 0.0, 1e9);
    views.push(v);
    for view in views {
        view.validate().unwrap();
        let cam = camera_params(&view.camera, 7, 1, 1e-3);
        for v in [cam.eye, cam.forward, cam.right, cam.up] {
            assert!(v.is_finite(), "{view:?}: {cam:?}");
        }
        let shade = shade_params(&view.light, 7, 1);
        assert!(shade.light_normal.is_finite() && shade.light_area.is_finite() && shade.light_area > 0.0);
        assert!(shade.radiance.is_finite());
        assert!(sampling::light_points(&view.light).iter().all(|p| p.is_finite()));
    }
}

/// A closed unit cube centred at `c` (outward-facing) over a ground square at y = 0.
fn cube_scene(c: Vec3) -> Scene {
    let mut triangles = Vec::new();
    let corner = |x: f32, y: f32, z: f32| c + 0.5 * Vec3::new(x, y, z);
    // Each face as (normal axis, sign): two triangles counter-clockwise seen from outside.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let p = |a: f32, b: f32| {
                let q = n + a * u + b * v;
                corner(q.x, q.y, q.z)
            };
            let quad = [p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)];
            for tri in [[0, 1, 2], [0, 2, 3]] {
                let mut positions = tri.map(|i| quad[i]);
                let face = (positions[1] - positions[0]).cross(positions[2] - positions[0]);
                if face.dot(n) < 0.0 {
                    positions.swap(1, 2);
                }
                triangles.push(positions);
            }
        }
    }
    for positions in [
        [
            Vec3::new(-9.0, 0.0, -9.0),
            Vec3::new(-9.0, 0.0, 9.0),
            Vec3::new(9.0, 0.0, 9.0),
        ],
        [
            Vec3::new(-9.0, 0.0, -9.0),
            Vec3::new(9.0, 0.0, 9.0),
            Vec3::new(9.0, 0.0, -9.0),
        ],
    ] {
        triangles.push(positions);
    }
    Scene {
        source: "cube".into(),
        triangles: triangles
            .into_iter()
            .map(|positions| {
                let n = (positions[1] - positions[0])
                    .cross(positions[2] - positions[0])
                    .normalize();
                SceneTriangle {
                    positions,
                    normals: [n; 3],
                    uvs: [Vec2::ZERO; 3],
                    material: 0,
                    instance: 0,
                }
            })
            .collect(),
        materials: vec![Material::default()],
        images: Vec::new(),
        instances: vec![Instance {
            node: 0,
            name: None,
            world_from_object: glam::Mat4::IDENTITY,
        }],
        camera: None,
        warnings: LoadWarnings::default(),
    }
}

#[test]
fn suspicious_views_pass_with_warnings() {
    let scene = cube_scene(Vec3::new(0.0, 1.0, 0.0));
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    assert_eq!(view_warnings(&good(), &scene, &bvh), []);

    // The light turned upward: everything is below its plane.
    let mut up = good();
    std::mem::swap(&mut up.light.edge_u, &mut up.light.edge_v);
    assert_eq!(up.validate(), Ok(()), "legal");
    let warnings = view_warnings(&up, &scene, &bvh);
    assert_eq!(warnings, [ViewWarning::LightFacesAway { normal: Vec3::Y }]);
    assert_eq!(
        warnings[0].to_string(),
        "the light faces away from the whole scene (every vertex is behind its plane; it emits \
         toward [0, 1, 0]): every surface is unlit"
    );
    // A light below the ground facing down sees nothing either.
    let mut below = good();
    below.light.corner.y = -1.0;
    assert!(matches!(
        view_warnings(&below, &scene, &bvh)[..],
        [ViewWarning::LightFacesAway { .. }]
    ));

    // The eye inside the cube.
    let mut inside = good();
    inside.camera.eye = Vec3::new(0.1, 1.1, 0.2);
    assert_eq!(inside.validate(), Ok(()), "legal");
    let warnings = view_warnings(&inside, &scene, &bvh);
    assert_eq!(
        warnings,
        [ViewWarning::CameraInsideGeometry {
            eye: inside.camera.eye
        }]
    );
    assert_eq!(
        warnings[0].to_string(),
        "the camera eye [0.1, 1.1, 0.2] seems to be inside closed geometry (all 26 probe rays hit \
         back faces): the image shows the inside of an object"
    );
    // Below the ground (an open surface) is not inside anything.
    let mut under = good();
    under.camera.eye = Vec3::new(3.0, -1.0, 3.0);
    assert_eq!(view_warnings(&under, &scene, &bvh), []);
}

#[test]
fn inputs_that_crashed_the_fuzzer_are_refused() {
    // Each file under tests/fuzz_regressions/view_parser/ once passed validation
    // with a view the renderer cannot use (see README, "Fuzzing").
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/view_parser");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for file in files {
        let err = View::load(&file).expect_err("refused");
        eprintln!("{err}");
    }
}
