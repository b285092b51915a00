//! Building both levels straight from a loaded [`Scene`] at a [`Pose`].

use super::{BlasPool, BuildOptions, InstanceDesc, MeshBvh, SceneBvh, reserved_rows};
use crate::scene::{Pose, Scene};
use glam::{Affine3A, Vec3};

impl SceneBvh {
    /// Builds every mesh's bottom level (meshes in parallel) and the top level for `pose`.
    /// Deforming meshes' trees are built over their base vertices, in [`reserved_rows`] rows.
    /// Instance custom indices are positions in `scene.instances`; every instance gets mask
    /// 0xFF and is alpha-tested when its mesh's material is not opaque.
    pub fn build(scene: &Scene, pose: &Pose) -> Self {
        let blas = BlasPool::build(scene.meshes.len(), |i| {
            let mesh = &scene.meshes[i];
            let positions: Vec<Vec3> = mesh.vertices.iter().map(|v| v.position.into()).collect();
            let mut tree = MeshBvh::build(&positions, &mesh.indices, &BuildOptions::MESH);
            if scene.deforms(i as u32) {
                // Room for whatever shape a rebuild for deformed vertices gives.
                tree.rows.resize(reserved_rows(tree.triangle_count), [0; 4]);
            }
            tree
        });
        Self::new(blas, &instance_descs(scene, pose))
    }

    /// Rebuilds only the top level, for a new pose of the same scene.
    pub fn update_instances(&mut self, scene: &Scene, pose: &Pose) {
        self.set_instances(&instance_descs(scene, pose));
    }
}

/// One [`InstanceDesc`] per scene instance, in scene order.
pub fn instance_descs(scene: &Scene, pose: &Pose) -> Vec<InstanceDesc> {
    scene
        .instances
        .iter()
        .enumerate()
        .map(|(i, inst)| {
            let material = scene.meshes[inst.mesh as usize].material;
            let alpha_tested = scene.materials.get(material as usize).is_some_and(|m| m.rays_test_candidates());
            InstanceDesc {
                object_to_world: Affine3A::from_mat4(pose.world[inst.node as usize]),
                mesh: inst.mesh,
                custom_index: i as u32,
                mask: 0xFF,
                alpha_tested,
                material,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::{accept_all, closest_hit};
    use crate::scene::{AlphaMode, Instance, Material, Mesh, Vertex};
    use glam::Mat4;

    /// A unit right triangle in the xy plane, facing +z.
    fn triangle_mesh(material: u32) -> Mesh {
        let vertex = |x, y| Vertex { position: [x, y, 0.0], ..Default::default() };
        Mesh {
            name: "tri".into(),
            vertices: vec![vertex(0.0, 0.0), vertex(1.0, 0.0), vertex(0.0, 1.0)],
            indices: vec![0, 1, 2],
            material,
            bounds_min: Vec3::ZERO,
            bounds_max: Vec3::new(1.0, 1.0, 0.0),
        }
    }

    #[test]
    fn builds_from_scene_and_moves_instances() {
        let scene = Scene {
            meshes: vec![triangle_mesh(0), triangle_mesh(1)],
            materials: vec![
                Material::default(),
                Material { alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..Default::default() },
            ],
            instances: vec![Instance { mesh: 0, node: 0 }, Instance { mesh: 1, node: 1 }],
            ..Default::default()
        };
        let pose =
            |z: f32| Pose { time: 0.0, world: vec![Mat4::from_translation(Vec3::new(5.0, 0.0, z)), Mat4::IDENTITY] };
        let mut bvh = SceneBvh::build(&scene, &pose(0.0));
        assert_eq!(bvh.blas.meshes.len(), 2);
        let masked = bvh.tlas.instances.iter().find(|i| i.custom_index == 1).expect("instance 1");
        assert!(masked.alpha_tested && masked.material == 1);
        let ray = |bvh: &SceneBvh| closest_hit(bvh, Vec3::new(5.2, 0.2, 1.0), -Vec3::Z, 0.0, 100.0, 0xFF, accept_all);
        assert_eq!(ray(&bvh).map(|h| (h.instance, h.t)), Some((0, 1.0)));
        let blas_rows = bvh.blas.rows.clone();
        bvh.update_instances(&scene, &pose(-2.0));
        assert_eq!(ray(&bvh).map(|h| (h.instance, h.t)), Some((0, 3.0)));
        assert_eq!(bvh.blas.rows, blas_rows);
    }
}
