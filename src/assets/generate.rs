//! The project's own scenes, generated from code: a `.glb` file and a view
//! (camera + quad light) each.
//!
//! Both scenes are y-up, in metres, with everything resting on (or floating
//! over) a ground plane at y = 0, and are built to show contact shadows and
//! intricate penumbrae under a quad light:
//!
//! - `playground` (the default): boxes, a pillar, a sphere touching the
//!   ground in one point, a thin fence, a small table, a rotated box and a
//!   post.
//! - `lattice`: a dense two-layer lattice of thin bars floating at 1 m over a
//!   few small cubes.
//! - `screen`: a perforated screen floating at 1 m, one quad whose holes are an
//!   alpha-masked texture (`alphaMode: MASK`), over a small box.
//!
//! Lights are square, face down (`cross(edge_u, edge_v)` is -y), are about a
//! sixth of the scene's width and sit off-centre. Their intensity is chosen so
//! that the ground at the origin gets an irradiance of about 1 (see
//! [`unit_irradiance_intensity`]).
//!
//! Run `cargo run --release --example generate_assets` to write the committed
//! copies under `assets/`.

use glam::{Mat4, Quat, Vec3, Vec4};

use super::glb_writer::{GlbCamera, GlbScene, MaskTexture, Material, Object, Placement, write_glb};
use super::shapes::{self, TriangleMesh};
use crate::scene::view::{Camera, QuadLight, View};

/// A generated scene: the bytes of its `.glb` file and its view.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedScene {
    /// Scene name; also the file stem under `assets/`.
    pub name: &'static str,
    /// The binary glTF file.
    pub glb: Vec<u8>,
    /// Camera and light to render it with.
    pub view: View,
}

impl GeneratedScene {
    /// Number of triangles in the `.glb` file (read back from its index
    /// accessors).
    pub fn triangle_count(&self) -> usize {
        let gltf = gltf::Gltf::from_slice(&self.glb).expect("generated GLB files are valid");
        gltf.meshes()
            .flat_map(|mesh| mesh.primitives())
            .filter_map(|primitive| primitive.indices())
            .map(|indices| indices.count() / 3)
            .sum()
    }
}

/// Names of the generated scenes, the default first.
pub const SCENE_NAMES: [&str; 3] = ["playground", "lattice", "screen"];

/// Generates the scene called `name`, or `None` if there is no such scene.
pub fn generate(name: &str) -> Option<GeneratedScene> {
    let (name, (scene, view)) = match name {
        "playground" => ("playground", playground()),
        "lattice" => ("lattice", lattice()),
        "screen" => ("screen", screen()),
        _ => return None,
    };
    Some(GeneratedScene {
        name,
        glb: write_glb(&scene),
        view,
    })
}

/// Generates every scene, in [`SCENE_NAMES`] order.
pub fn generate_all() -> Vec<GeneratedScene> {
    SCENE_NAMES
        .iter()
        .map(|name| generate(name).expect("every listed scene generates"))
        .collect()
}

/// Radiance scale that gives irradiance ≈ 1 at `point` on an upward-facing
/// surface, for a light small compared with its distance.
///
/// With the light's centre at distance `d` and height `h` above the point,
/// both cosines are `h / d`, so `E ≈ L · A · (h/d)² / d²`; solving `E = 1`
/// gives `L = d⁴ / (A · h²)`. Only `+ - * /`, so the result is the same on
/// every platform.
pub fn unit_irradiance_intensity(light: &QuadLight, point: Vec3) -> f32 {
    let to_light = light.center() - point;
    let d2 = to_light.length_squared();
    let area = light.area_normal().length_squared().sqrt();
    d2 * d2 / (area * to_light.y * to_light.y)
}

/// A square light of `size`, centred at `center`, facing -y, with
/// [`unit_irradiance_intensity`] at the origin.
fn downward_square_light(center: Vec3, size: f32) -> QuadLight {
    // cross(+x, +z) = -y: the light emits down.
    let mut light = QuadLight::from_center(center, Vec3::X * size, Vec3::Z * size);
    light.intensity = unit_irradiance_intensity(&light, Vec3::ZERO);
    light
}

/// The file of `objects` in `materials` (with `camera` on a node of its own) and its view.
fn scene_and_view(
    materials: Vec<Material>,
    objects: Vec<Object>,
    camera: Camera,
    light: QuadLight,
) -> (GlbScene, View) {
    let scene = GlbScene {
        materials,
        objects,
        camera: Some(glb_camera(&camera)),
    };
    (
        scene,
        View {
            camera,
            light,
            ground_y: None,
        },
    )
}

fn glb_camera(camera: &Camera) -> GlbCamera {
    GlbCamera {
        eye: camera.eye,
        target: camera.target,
        up: camera.up,
        yfov_radians: camera.fov_y_degrees.to_radians(),
    }
}

/// A rotation about +y by `degrees`, from the deterministic [`shapes::sin_cos`].
fn rotation_y(degrees: f64) -> Quat {
    let (sin, cos) = shapes::sin_cos(degrees.to_radians() / 2.0);
    Quat::from_xyzw(0.0, sin as f32, 0.0, cos as f32)
}

/// `translation · rotation_y(degrees) · scale` written out entry by entry, so
/// the bytes do not depend on how glam multiplies matrices on this platform.
fn matrix_y_rotation(translation: Vec3, degrees: f64, scale: Vec3) -> Mat4 {
    let (sin, cos) = shapes::sin_cos(degrees.to_radians());
    let (sin, cos) = (sin as f32, cos as f32);
    Mat4::from_cols(
        Vec4::new(cos * scale.x, 0.0, -sin * scale.x, 0.0),
        Vec4::new(0.0, scale.y, 0.0, 0.0),
        Vec4::new(sin * scale.z, 0.0, cos * scale.z, 0.0),
        translation.extend(1.0),
    )
}

fn material(name: &str, rgb: [f32; 3]) -> Material {
    Material {
        name: name.into(),
        base_color: [rgb[0], rgb[1], rgb[2], 1.0],
        mask: None,
    }
}

fn object(name: &str, mesh: TriangleMesh, material: usize, placement: Placement) -> Object {
    Object {
        name: name.into(),
        mesh,
        uvs: Vec::new(),
        material,
        placement,
    }
}

// Material indices shared by both scenes.
const GROUND: usize = 0;
const RED: usize = 1;
const BLUE: usize = 2;
const WOOD: usize = 3;
const METAL: usize = 4;
const GREEN: usize = 5;

fn materials() -> Vec<Material> {
    vec![
        material("ground", [0.75, 0.75, 0.75]),
        material("red", [0.8, 0.2, 0.15]),
        material("blue", [0.2, 0.35, 0.8]),
        material("wood", [0.7, 0.5, 0.3]),
        material("metal", [0.3, 0.3, 0.32]),
        material("green", [0.25, 0.65, 0.3]),
    ]
}

/// A fence in the xy plane, standing on y = 0 and centred on x = 0: nine
/// vertical bars and three horizontal rails just behind them (so no faces
/// coincide), all with a square cross-section of `bar`.
fn fence_mesh(width: f32, height: f32, bar: f32) -> TriangleMesh {
    let mut mesh = TriangleMesh::default();
    let posts = 9;
    for i in 0..posts {
        let x = width * (i as f32 / (posts - 1) as f32 - 0.5);
        let post = shapes::box_on_ground(Vec3::new(bar, height, bar));
        mesh.append(&post, Vec3::new(x, 0.0, 0.0));
    }
    let rail = shapes::box_centered(Vec3::new(width + bar, bar, bar));
    for y in [0.25, 0.55, 0.85] {
        mesh.append(&rail, Vec3::new(0.0, y * height, bar));
    }
    mesh
}

/// A table standing on y = 0: a thin top plate of `top` size (x, z) at
/// `height`, on four thin legs inset from its corners.
fn table_mesh(top: [f32; 2], height: f32) -> TriangleMesh {
    let plate = 0.04;
    let leg = 0.05;
    let mut mesh = shapes::box_min_max(
        Vec3::new(-0.5 * top[0], height - plate, -0.5 * top[1]),
        Vec3::new(0.5 * top[0], height, 0.5 * top[1]),
    );
    let leg_mesh = shapes::box_on_ground(Vec3::new(leg, height - plate, leg));
    let (x, z) = (0.5 * top[0] - leg, 0.5 * top[1] - leg);
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        mesh.append(&leg_mesh, Vec3::new(sx * x, 0.0, sz * z));
    }
    mesh
}

/// The default scene: a 12 m × 12 m ground with assorted occluders.
fn playground() -> (GlbScene, View) {
    let sphere_radius = 0.7;
    let objects = vec![
        object(
            "ground",
            shapes::ground_plane(12.0, 12.0, 12, 12),
            GROUND,
            Placement::translation(Vec3::ZERO),
        ),
        object(
            "box",
            shapes::box_on_ground(Vec3::ONE),
            RED,
            Placement::translation(Vec3::new(-2.2, 0.0, 1.6)),
        ),
        object(
            "pillar",
            shapes::box_on_ground(Vec3::new(0.3, 2.5, 0.3)),
            BLUE,
            Placement::translation(Vec3::new(2.0, 0.0, -2.0)),
        ),
        // Its bottom pole touches the ground in exactly one point.
        object(
            "sphere",
            shapes::uv_sphere(sphere_radius, 16, 32),
            GREEN,
            Placement::translation(Vec3::new(0.6, sphere_radius, 1.9)),
        ),
        object(
            "fence",
            fence_mesh(2.4, 1.5, 0.04),
            METAL,
            Placement::Matrix(matrix_y_rotation(Vec3::new(-0.6, 0.0, -1.6), 20.0, Vec3::ONE)),
        ),
        object(
            "table",
            table_mesh([1.2, 0.8], 0.75),
            WOOD,
            Placement::translation(Vec3::new(2.3, 0.0, 1.0)),
        ),
        object(
            "rotated_box",
            shapes::box_on_ground(Vec3::new(0.8, 0.6, 0.5)),
            BLUE,
            Placement::Trs {
                translation: Vec3::new(-2.8, 0.0, -1.2),
                rotation: rotation_y(35.0),
                scale: Vec3::ONE,
            },
        ),
        // A unit cylinder stretched into a post by a non-uniform scale.
        object(
            "post",
            shapes::cylinder(1.0, 1.0, 24),
            RED,
            Placement::Matrix(matrix_y_rotation(
                Vec3::new(3.4, 0.0, -0.4),
                0.0,
                Vec3::new(0.12, 1.8, 0.12),
            )),
        ),
    ];
    let camera = Camera {
        eye: Vec3::new(6.0, 4.5, 7.0),
        target: Vec3::new(0.0, 0.6, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 45.0,
    };
    // 2 m: a sixth of the 12 m ground. Off-centre towards -x, +z so shadows
    // fall towards +x, -z, across the camera's view.
    let light = downward_square_light(Vec3::new(-2.0, 6.0, 1.0), 2.0);
    scene_and_view(materials(), objects, camera, light)
}

/// Two layers of `count` parallel bars each (along x below, along z above),
/// `spacing` apart, with a square cross-section of `bar`, the lower layer's
/// underside at `height`; centred on the y axis.
fn lattice_mesh(count: u32, spacing: f32, bar: f32, height: f32) -> TriangleMesh {
    let span = spacing * (count - 1) as f32;
    let length = span + 2.0 * bar;
    let along_x = shapes::box_centered(Vec3::new(length, bar, bar));
    let along_z = shapes::box_centered(Vec3::new(bar, bar, length));
    let mut mesh = TriangleMesh::default();
    for i in 0..count {
        let offset = spacing * i as f32 - 0.5 * span;
        mesh.append(&along_x, Vec3::new(0.0, height + 0.5 * bar, offset));
        mesh.append(&along_z, Vec3::new(offset, height + 1.5 * bar, 0.0));
    }
    mesh
}

/// A floating two-layer lattice over a few small cubes on a 10 m × 10 m ground.
fn lattice() -> (GlbScene, View) {
    let mut objects = vec![
        object(
            "ground",
            shapes::ground_plane(10.0, 10.0, 10, 10),
            GROUND,
            Placement::translation(Vec3::ZERO),
        ),
        // Turned against the light's edges so the penumbrae of the two bar
        // directions do not line up with the light's own.
        object(
            "lattice",
            lattice_mesh(20, 0.3, 0.05, 1.0),
            METAL,
            Placement::Matrix(matrix_y_rotation(Vec3::ZERO, 30.0, Vec3::ONE)),
        ),
    ];
    let cubes = [
        (Vec3::new(-1.2, 0.0, -0.8), 0.3, 0.0, RED),
        (Vec3::new(0.4, 0.0, -1.5), 0.25, 20.0, BLUE),
        (Vec3::new(1.3, 0.0, 0.5), 0.35, 45.0, GREEN),
        (Vec3::new(-0.3, 0.0, 1.2), 0.2, 10.0, WOOD),
        (Vec3::new(0.0, 0.0, 0.0), 0.3, 60.0, RED),
    ];
    for (i, (position, size, degrees, material)) in cubes.into_iter().enumerate() {
        objects.push(object(
            &format!("cube_{i}"),
            shapes::box_on_ground(Vec3::splat(size)),
            material,
            Placement::Trs {
                translation: position,
                rotation: rotation_y(degrees),
                scale: Vec3::ONE,
            },
        ));
    }
    let camera = Camera {
        eye: Vec3::new(5.0, 2.2, 6.0),
        target: Vec3::new(0.0, 0.4, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 45.0,
    };
    // 1.6 m: about a sixth of the 10 m ground; 7 m up so the penumbra of the
    // lattice on the ground (≈ 1.6 · 1 / 6 ≈ 0.27 m) is about one bar spacing.
    let light = downward_square_light(Vec3::new(-1.2, 7.0, 0.8), 1.6);
    scene_and_view(materials(), objects, camera, light)
}

/// Texels per side of the screen's texture, and the period and radius (in texels) of
/// its round holes: 4 × 4 holes, each a disc of alpha 0 in an opaque texture.
pub const SCREEN_TEXELS: u32 = 32;
const SCREEN_HOLE_PERIOD: u32 = 8;
const SCREEN_HOLE_RADIUS: f32 = 2.6;
/// The screen's side (m).
pub const SCREEN_SIZE: f32 = 3.0;
/// Height of the screen's plane over the ground (m).
pub const SCREEN_HEIGHT: f32 = 1.0;

/// Whether texel `(x, y)` of the screen's texture is in a hole (alpha 0).
pub fn screen_texel_is_hole(x: u32, y: u32) -> bool {
    let centre = 0.5 * SCREEN_HOLE_PERIOD as f32;
    let dx = (x % SCREEN_HOLE_PERIOD) as f32 + 0.5 - centre;
    let dy = (y % SCREEN_HOLE_PERIOD) as f32 + 0.5 - centre;
    dx * dx + dy * dy <= SCREEN_HOLE_RADIUS * SCREEN_HOLE_RADIUS
}

/// The screen's texture as PNG: orange where the screen is, alpha 0 in the holes.
fn screen_png() -> Vec<u8> {
    use image::ImageEncoder;
    let image = image::RgbaImage::from_fn(SCREEN_TEXELS, SCREEN_TEXELS, |x, y| {
        if screen_texel_is_hole(x, y) {
            image::Rgba([0, 0, 0, 0])
        } else {
            image::Rgba([230, 140, 50, 255])
        }
    });
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            image.as_raw(),
            SCREEN_TEXELS,
            SCREEN_TEXELS,
            image::ExtendedColorType::Rgba8,
        )
        .expect("encoding a small RGBA image to memory cannot fail");
    png
}

/// A quad in the plane y = 0 facing +y, `size` on a side and centred on the origin,
/// with texture coordinates 0..1 over it (u along +x, v along +z).
fn textured_square(size: f32) -> (TriangleMesh, Vec<[f32; 2]>) {
    let h = 0.5 * size;
    let mesh = TriangleMesh {
        positions: vec![[-h, 0.0, -h], [h, 0.0, -h], [h, 0.0, h], [-h, 0.0, h]],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        // Counter-clockwise seen from +y.
        indices: vec![0, 2, 1, 0, 3, 2],
    };
    (mesh, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
}

/// A perforated screen (one alpha-masked quad) floating over a small box on an 8 m × 8 m
/// ground: the holes' shadows are where the light comes through the texture.
fn screen() -> (GlbScene, View) {
    let mut materials = materials();
    let screen_material = materials.len();
    materials.push(Material {
        name: "perforated".into(),
        base_color: [1.0; 4],
        mask: Some(MaskTexture {
            png: screen_png(),
            cutoff: 0.5,
        }),
    });
    let (quad, uvs) = textured_square(SCREEN_SIZE);
    let objects = vec![
        object(
            "ground",
            shapes::ground_plane(8.0, 8.0, 16, 16),
            GROUND,
            Placement::translation(Vec3::ZERO),
        ),
        Object {
            name: "screen".into(),
            mesh: quad,
            uvs,
            material: screen_material,
            placement: Placement::translation(Vec3::Y * SCREEN_HEIGHT),
        },
        object(
            "box",
            shapes::box_on_ground(Vec3::new(0.4, 0.5, 0.4)),
            RED,
            Placement::Matrix(matrix_y_rotation(Vec3::new(0.75, 0.0, 0.75), 25.0, Vec3::ONE)),
        ),
    ];
    let camera = Camera {
        eye: Vec3::new(3.5, 3.2, 4.5),
        target: Vec3::new(0.0, 0.3, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 45.0,
    };
    // 0.6 m, 3 m over the screen: penumbrae of 0.6 · 1 / 3 = 0.2 m on the ground, less
    // than the holes' 0.49 m, so each hole casts a fully lit spot with a soft rim.
    let light = downward_square_light(Vec3::new(-0.3, 4.0, 0.2), 0.6);
    scene_and_view(materials, objects, camera, light)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_scene_generates_and_unknown_names_do_not() {
        for scene in generate_all() {
            assert!(scene.view.validate().is_ok(), "{}", scene.name);
            assert!(scene.triangle_count() > 0, "{}", scene.name);
        }
        assert!(generate("no such scene").is_none());
    }

    #[test]
    fn generation_is_deterministic() {
        assert_eq!(generate_all(), generate_all());
    }

    #[test]
    fn rotation_helpers_agree_with_glam() {
        let q = rotation_y(35.0);
        assert!(q.abs_diff_eq(Quat::from_rotation_y(35f32.to_radians()), 1e-6));
        let m = matrix_y_rotation(Vec3::new(1.0, 2.0, 3.0), 30.0, Vec3::new(2.0, 3.0, 4.0));
        let expected = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 3.0, 4.0),
            Quat::from_rotation_y(30f32.to_radians()),
            Vec3::new(1.0, 2.0, 3.0),
        );
        assert!(m.abs_diff_eq(expected, 1e-6));
    }
}
