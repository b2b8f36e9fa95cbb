//! The shadow casters, main world: every entity with a `Mesh3d` whose mesh is loaded (and
//! a triangle list) and no [`NotShadowCaster`] becomes one instance of a penumbra
//! [`Scene`]. When that set changes (entities added or removed, a mesh swapped or edited)
//! the scene is made anew; when instances only move, their new transforms are passed on
//! and the render world refits the BVH ([`penumbra::gpu::GpuScene::set_transforms`]).

use std::path::PathBuf;
use std::sync::Arc;

use bevy::light::NotShadowCaster;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy::transform::TransformSystems;
use penumbra::scene::{Instance, LoadWarnings, Material, Scene, SceneTriangle};

/// The casters as penumbra sees them, updated in `PostUpdate` after transforms propagate.
#[derive(Resource, Default, Debug)]
pub struct Casters {
    /// Each instance's entity and mesh, in instance order (sorted by entity).
    pub members: Vec<(Entity, AssetId<Mesh>)>,
    /// Each instance's world transform as the scene or the last move has it.
    transforms: Vec<Mat4>,
    /// Bumped whenever [`Casters::scene`] is made anew.
    pub version: u64,
    /// The scene of the current members (`None`: no caster with triangles).
    pub scene: Option<Arc<Scene>>,
    /// Instances moved this frame and their new transforms (penumbra's glam).
    pub moves: Vec<(u32, glam::Mat4)>,
}

pub(crate) fn build(app: &mut App) {
    app.init_resource::<Casters>()
        .add_systems(PostUpdate, update_casters.after(TransformSystems::Propagate));
}

/// Bevy's matrix as penumbra's (Bevy 0.20 is on glam 0.33, penumbra on 0.34).
pub fn to_penumbra(m: Mat4) -> glam::Mat4 {
    glam::Mat4::from_cols_array(&m.to_cols_array())
}

fn update_casters(
    mut casters: ResMut<Casters>,
    meshes: Res<Assets<Mesh>>,
    mut mesh_events: MessageReader<AssetEvent<Mesh>>,
    query: Query<(Entity, &Mesh3d, &GlobalTransform), Without<NotShadowCaster>>,
) {
    casters.moves.clear();
    let edited: Vec<AssetId<Mesh>> = mesh_events
        .read()
        .filter_map(|e| match e {
            AssetEvent::Modified { id } => Some(*id),
            _ => None,
        })
        .collect();
    let mut members: Vec<(Entity, AssetId<Mesh>, Mat4)> = query
        .iter()
        .filter(|(_, mesh, _)| {
            meshes
                .get(&mesh.0)
                .is_some_and(|m| m.primitive_topology() == PrimitiveTopology::TriangleList)
        })
        .map(|(e, mesh, t)| (e, mesh.id(), t.to_matrix()))
        .collect();
    members.sort_by_key(|(e, _, _)| *e);
    let same_set = members.len() == casters.members.len()
        && members
            .iter()
            .zip(&casters.members)
            .all(|(a, b)| (a.0, a.1) == *b)
        && !casters.members.iter().any(|(_, m)| edited.contains(m));
    if same_set {
        let moves: Vec<(u32, glam::Mat4)> = members
            .iter()
            .zip(&casters.transforms)
            .enumerate()
            .filter(|(_, (m, old))| m.2 != **old)
            .map(|(i, (m, _))| (i as u32, to_penumbra(m.2)))
            .collect();
        for &(i, _) in &moves {
            casters.transforms[i as usize] = members[i as usize].2;
        }
        casters.moves = moves;
        return;
    }
    let scene = scene_of(&members, &meshes);
    casters.members = members.iter().map(|m| (m.0, m.1)).collect();
    casters.transforms = members.iter().map(|m| m.2).collect();
    casters.scene = scene.map(Arc::new);
    casters.version += 1;
}

/// One instance per member, its triangles in world space, one white opaque material.
fn scene_of(members: &[(Entity, AssetId<Mesh>, Mat4)], meshes: &Assets<Mesh>) -> Option<Scene> {
    let mut triangles = Vec::new();
    let mut instances = Vec::with_capacity(members.len());
    for (i, (entity, mesh, world)) in members.iter().enumerate() {
        instances.push(Instance {
            node: i as u32,
            name: Some(format!("{entity}")),
            world_from_object: to_penumbra(*world),
        });
        let Some(mesh) = meshes.get(*mesh) else { continue };
        let Some(positions) = mesh
            .try_attribute(Mesh::ATTRIBUTE_POSITION)
            .ok()
            .and_then(|v| v.as_float3())
        else {
            continue;
        };
        let corner = |k: usize| world.transform_point3(Vec3::from_array(positions[k]));
        let indices: Vec<usize> = match mesh.try_indices() {
            Ok(Indices::U16(v)) => v.iter().map(|&k| usize::from(k)).collect(),
            Ok(Indices::U32(v)) => v.iter().map(|&k| k as usize).collect(),
            Err(_) => (0..positions.len()).collect(),
        };
        for t in indices.chunks_exact(3) {
            if t.iter().any(|&k| k >= positions.len()) {
                continue;
            }
            let p = [corner(t[0]), corner(t[1]), corner(t[2])];
            let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            if normal == Vec3::ZERO || !normal.is_finite() {
                continue;
            }
            let v = |p: Vec3| glam::Vec3::from_array(p.to_array());
            triangles.push(SceneTriangle {
                positions: p.map(v),
                normals: [v(normal); 3],
                uvs: [glam::Vec2::ZERO; 3],
                material: 0,
                instance: i as u32,
            });
        }
    }
    if triangles.is_empty() {
        return None;
    }
    Some(Scene {
        source: PathBuf::from("bevy world"),
        triangles,
        materials: vec![Material::default()],
        images: Vec::new(),
        instances,
        camera: None,
        warnings: LoadWarnings::default(),
    })
}
