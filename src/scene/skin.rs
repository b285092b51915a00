//! Skins (glTF skeletal animation): a skinned mesh's vertices follow up to four joints each,
//! weighted; the joints are nodes of the scene, so node animations move them.
//!
//! Skinning runs on the GPU (src/world/skinning.rs, shaders-glsl/skinning.comp). The CPU
//! evaluation here ([`SkinnedMesh::skin`]) is the same formula: the compute backend refits its
//! BVH from it (that refit runs on the CPU, as for morph targets), and tests hold the GPU's
//! vertices against it.

use super::{Pose, Vertex};
use glam::{Mat3, Mat4, Vec3, Vec4};

/// A skeleton: the joints (scene nodes) and the matrices that take the mesh from its bind
/// pose into each joint's space.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    pub name: String,
    /// `Scene::nodes` index of each joint.
    pub joints: Vec<u32>,
    /// One per joint (glTF `inverseBindMatrices`, identity when the file has none).
    pub inverse_bind: Vec<Mat4>,
}

/// A vertex's joints (indices into its skin's `joints`) and their weights, which sum to 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Influence {
    pub joints: [u32; 4],
    pub weights: [f32; 4],
}

/// A mesh deformed by a skin, as drawn by one node.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinnedMesh {
    /// Index into `Scene::meshes`.
    pub mesh: u32,
    /// Index into `Scene::skins`.
    pub skin: u32,
    /// The node whose instance draws the mesh. glTF ignores a skinned mesh's own node
    /// transform; the skinned vertices are written in that node's space, so that its instance
    /// transform (which every pass applies) takes them back to where the joints put them.
    pub node: u32,
    /// One per vertex of the mesh.
    pub influences: Vec<Influence>,
}

impl Skin {
    /// Per joint, the matrix that takes a bind-pose vertex to the space of `node` at `pose`:
    /// inverse(world[node]) * world[joint] * inverse_bind[joint].
    pub fn joint_matrices(&self, pose: &Pose, node: u32) -> Vec<Mat4> {
        let to_node = pose.world[node as usize].inverse();
        self.joints.iter().zip(&self.inverse_bind).map(|(&j, ib)| to_node * pose.world[j as usize] * *ib).collect()
    }
}

/// Normals transform by the inverse transpose; the cofactor matrix is that times the
/// determinant, so it gives the same direction once normalised (its sign flipped for mirroring
/// joints), without a division that a degenerate joint matrix would turn into NaN.
pub fn cofactor(m: Mat3) -> Mat3 {
    let c = Mat3::from_cols(m.y_axis.cross(m.z_axis), m.z_axis.cross(m.x_axis), m.x_axis.cross(m.y_axis));
    if m.determinant() < 0.0 { -c } else { c }
}

impl SkinnedMesh {
    /// The blended joint matrix of vertex `i`; identity for a vertex without weight (the
    /// loader's fallback for one: it keeps its bind-pose place on the skinned node).
    pub fn matrix(&self, i: usize, joints: &[Mat4]) -> Mat4 {
        let inf = &self.influences[i];
        if inf.weights == [0.0; 4] {
            return Mat4::IDENTITY;
        }
        let mut m = Mat4::ZERO;
        for k in 0..4 {
            if inf.weights[k] != 0.0 {
                m += joints[inf.joints[k] as usize] * inf.weights[k];
            }
        }
        m
    }

    /// The bind-pose vertices `base` skinned with `joints` ([`Skin::joint_matrices`]):
    /// positions, normals and tangents move; texture coordinates stay. A normal or tangent
    /// that a degenerate matrix collapses keeps its bind-pose direction.
    pub fn skin(&self, base: &[Vertex], joints: &[Mat4]) -> Vec<Vertex> {
        base.iter()
            .enumerate()
            .map(|(i, v)| {
                let m = self.matrix(i, joints);
                let linear = Mat3::from_mat4(m);
                let normal = (cofactor(linear) * Vec3::from(v.normal)).try_normalize().unwrap_or(v.normal.into());
                let t = Vec4::from(v.tangent);
                let tangent = (linear * t.truncate()).try_normalize().unwrap_or(t.truncate());
                Vertex {
                    position: m.transform_point3(v.position.into()).to_array(),
                    normal: normal.to_array(),
                    tangent: tangent.extend(t.w).to_array(),
                    ..*v
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn two_joints_blend_and_normals_follow() {
        // Joint 0 stays; joint 1 turns 90 degrees about +Z. Inverse bind matrices are identity,
        // so a joint's world matrix moves bind-pose vertices directly.
        let skin = Skin { name: "s".into(), joints: vec![1, 2], inverse_bind: vec![Mat4::IDENTITY; 2] };
        let turn = Mat4::from_quat(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2));
        let pose = Pose { time: 0.0, world: vec![Mat4::from_translation(Vec3::X), Mat4::IDENTITY, turn] };
        let joints = skin.joint_matrices(&pose, 0);
        let v = Vertex {
            position: [1.0, 0.0, 0.0],
            normal: [0.0, 1.0, 0.0],
            tangent: [1.0, 0.0, 0.0, -1.0],
            ..Default::default()
        };
        let mesh = SkinnedMesh {
            mesh: 0,
            skin: 0,
            node: 0,
            influences: vec![
                Influence { joints: [1, 0, 0, 0], weights: [1.0, 0.0, 0.0, 0.0] },
                Influence { joints: [0, 1, 0, 0], weights: [0.5, 0.5, 0.0, 0.0] },
            ],
        };
        let out = mesh.skin(&[v, v], &joints);
        // Fully on joint 1: (1,0,0) turns to (0,1,0), then into node 0's space (x - 1).
        let p = Vec3::from(out[0].position);
        assert!((p - Vec3::new(-1.0, 1.0, 0.0)).length() < 1e-6, "{p}");
        assert!((Vec3::from(out[0].normal) - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
        assert!((Vec4::from(out[0].tangent).truncate() - Vec3::Y).length() < 1e-6);
        assert_eq!(out[0].tangent[3], -1.0);
        // Half and half: the linear blend of both positions.
        let p = Vec3::from(out[1].position);
        assert!((p - Vec3::new(-0.5, 0.5, 0.0)).length() < 1e-6, "{p}");
    }

    #[test]
    fn cofactor_is_the_inverse_transpose_up_to_scale_and_mirrors_keep_orientation() {
        let m = Mat3::from_cols(Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 3.0));
        let n = Vec3::new(0.3, -0.4, 0.5);
        let a = (cofactor(m) * n).normalize();
        let b = (m.inverse().transpose() * n).normalize();
        assert!((a - b).length() < 1e-6);
        let mirror = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        let a = (cofactor(mirror) * Vec3::X).normalize();
        assert!((a - (mirror.inverse().transpose() * Vec3::X)).length() < 1e-6);
    }
}
