//! Skins: a primitive's JOINTS_0 and WEIGHTS_0, a skin's joints and inverse bind matrices,
//! and the node that binds them to a mesh. Hostile values get an error naming the field
//! (joints past the skin's count, joints outside the scene, too many joints, bad matrices) or
//! a stated fallback with a warning (unusable weights, a second skin on a shared mesh).

use super::accessors::{accessor_format, read_accessor, read_floats};
use super::{Builder, NODES, SKINS, lookup};
use crate::scene::{Influence, SceneError, Skin, SkinnedMesh};
use glam::Mat4;
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

/// A primitive's joint influences as read, before a skin says how many joints there are.
pub(super) struct PrimitiveInfluences {
    /// JSON path of the primitive, for errors found when a node binds a skin to it.
    pub path: String,
    pub influences: Vec<Influence>,
}

impl Builder<'_> {
    /// JOINTS_0 and WEIGHTS_0 of a primitive (`None` when it has neither). Weights are made
    /// usable here: non-finite or negative ones count as 0, the rest are scaled to sum to 1; a
    /// vertex left with no weight keeps its bind-pose place (a warning says how many).
    pub(super) fn influences(
        &mut self,
        prim: &json::mesh::Primitive,
        path: &str,
        vertex_count: usize,
    ) -> Result<Option<PrimitiveInfluences>, SceneError> {
        use json::mesh::Semantic;
        let joints = prim.attributes.get(&Checked::Valid(Semantic::Joints(0)));
        let weights = prim.attributes.get(&Checked::Valid(Semantic::Weights(0)));
        if prim.attributes.contains_key(&Checked::Valid(Semantic::Joints(1))) {
            self.ctx.warn_once(
                "joints-1",
                "only four joint influences per vertex are used (JOINTS_0/WEIGHTS_0); JOINTS_1 and later are ignored",
            );
        }
        let (joints, weights) = match (joints, weights) {
            (None, None) => return Ok(None),
            (Some(j), Some(w)) => (j.value(), w.value()),
            _ => {
                self.ctx
                    .warn(format!("{path}: JOINTS_0 without WEIGHTS_0 or the reverse; the primitive is not skinned"));
                return Ok(None);
            }
        };
        let jpath = format!("{path}.attributes.JOINTS_0");
        let acc = lookup(&self.ctx, &self.data.root.accessors, joints, super::ACCESSORS, &jpath)?;
        let format = accessor_format(&self.ctx, acc, Type::Vec4, &format!("{jpath} -> accessors[{joints}]"))?;
        if format.normalized || !matches!(format.component, ComponentType::U8 | ComponentType::U16 | ComponentType::U32)
        {
            return Err(self
                .ctx
                .err(format!("{jpath}: joint indices must be unsigned bytes or shorts, not normalised")));
        }
        let limit = ("max_vertices", self.ctx.limits().max_vertices);
        let joints = read_accessor(&self.ctx, &self.data, (joints, Type::Vec4), &jpath, limit, |f, b| {
            std::array::from_fn(|c| super::accessors::component_f32(f, b, c) as u32)
        })?;
        let wpath = format!("{path}.attributes.WEIGHTS_0");
        let weights = read_floats::<4>(&self.ctx, &self.data, weights, &wpath)?;
        for (what, n) in [(&jpath, joints.len()), (&wpath, weights.len())] {
            if n != vertex_count {
                return Err(self.ctx.err(format!("{what}: {n} elements, but POSITION has {vertex_count}")));
            }
        }
        let mut unweighted = 0;
        let mut repaired = false;
        let influences = joints
            .into_iter()
            .zip(weights)
            .map(|(joints, mut weights)| {
                for w in &mut weights {
                    if !w.is_finite() || *w < 0.0 {
                        repaired = true;
                        *w = 0.0;
                    }
                }
                let sum: f32 = weights.iter().sum();
                if sum > 0.0 {
                    weights.iter_mut().for_each(|w| *w /= sum);
                } else {
                    unweighted += 1;
                }
                Influence { joints, weights }
            })
            .collect();
        if repaired {
            self.ctx.warn(format!("{wpath}: non-finite or negative weights count as 0"));
        }
        if unweighted > 0 {
            self.ctx.warn(format!(
                "{wpath}: {unweighted} vertices have no weight; they keep their bind-pose place on the skinned node"
            ));
        }
        Ok(Some(PrimitiveInfluences { path: path.to_string(), influences }))
    }

    /// Binds glTF skin `skin` to the primitives of the mesh that node `i` draws: each
    /// primitive with joint influences becomes a [`SkinnedMesh`] on the node's scene node.
    pub(super) fn attach_skin(
        &mut self,
        i: usize,
        skin: usize,
        primitives: &[Option<u32>],
        scene_index: u32,
    ) -> Result<(), SceneError> {
        let path = format!("nodes[{i}].skin");
        if primitives.is_empty() {
            self.ctx.warn(format!("{path}: the node draws no mesh; the skin is not used"));
            return Ok(());
        }
        let skin_id = self.skin(skin, &path)?;
        let joint_count = self.scene.skins[skin_id as usize].joints.len();
        for &mesh in primitives.iter().flatten() {
            let Some((prim_path, mut influences)) =
                self.skin_influences.get(&mesh).map(|r| (r.path.clone(), r.influences.clone()))
            else {
                self.ctx.warn(format!(
                    "{path}: {} has no JOINTS_0/WEIGHTS_0; it is drawn rigidly with the node",
                    self.scene.meshes[mesh as usize].name
                ));
                continue;
            };
            if self.scene.skinned_of(mesh).is_some() {
                self.ctx.warn_once(
                    "skin-shared",
                    "a skinned mesh drawn by several nodes takes the first node's skinned shape in all",
                );
                continue;
            }
            for (v, inf) in influences.iter_mut().enumerate() {
                for k in 0..4 {
                    let j = inf.joints[k] as usize;
                    if j < joint_count {
                        continue;
                    }
                    if inf.weights[k] > 0.0 {
                        return Err(self.ctx.err(format!(
                            "{}.attributes.JOINTS_0: vertex {v} names joint {j}, but skins[{skin}] has {joint_count} joints",
                            prim_path
                        )));
                    }
                    inf.joints[k] = 0; // weightless: any valid index does
                }
            }
            if self.scene.morph_of(mesh).is_some() {
                self.ctx.warn(format!(
                    "{}: morph targets on a skinned primitive are not supported; it is skinned from its base shape",
                    prim_path
                ));
                let k = self.scene.morphs.iter().position(|m| m.mesh == mesh).expect("morph_of found it");
                self.scene.morphs.remove(k);
                self.morph_driver.remove(k);
            }
            self.scene.skinned.push(SkinnedMesh { mesh, skin: skin_id, node: scene_index, influences });
        }
        Ok(())
    }

    /// `Scene::skins` index of glTF skin `index`, built on first use.
    fn skin(&mut self, index: usize, path: &str) -> Result<u32, SceneError> {
        let root = self.data.root;
        let skin = lookup(&self.ctx, &root.skins, index, SKINS, path)?;
        if let Some(&id) = self.skin_cache.get(&index) {
            return Ok(id);
        }
        let path = format!("skins[{index}]");
        let total = self.scene.skins.iter().map(|s| s.joints.len() as u64).sum::<u64>() + skin.joints.len() as u64;
        let limit = self.ctx.limits().max_joints;
        self.ctx.check(&format!("{path}.joints: joints in the scene so far"), "max_joints", total, limit)?;
        if skin.joints.is_empty() {
            return Err(self.ctx.err(format!("{path}.joints: a skin needs at least one joint")));
        }
        let mut joints = Vec::with_capacity(skin.joints.len());
        for (k, j) in skin.joints.iter().enumerate() {
            let jpath = format!("{path}.joints[{k}]");
            lookup(&self.ctx, &root.nodes, j.value(), NODES, &jpath)?;
            let Some(node) = self.scene_node.get(j.value()).copied().flatten() else {
                return Err(self.ctx.err(format!("{jpath}: node {} is not in the loaded scene", j.value())));
            };
            joints.push(node);
        }
        let inverse_bind = match skin.inverse_bind_matrices {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(acc) => {
                let ipath = format!("{path}.inverseBindMatrices");
                let limit = ("max_joints", limit);
                let m: Vec<Mat4> =
                    read_accessor(&self.ctx, &self.data, (acc.value(), Type::Mat4), &ipath, limit, |f, b| {
                        Mat4::from_cols_array(&std::array::from_fn(|c| super::accessors::component_f32(f, b, c)))
                    })?;
                if m.len() < joints.len() {
                    return Err(self.ctx.err(format!("{ipath}: {} matrices for {} joints", m.len(), joints.len())));
                }
                if let Some(bad) = m.iter().position(|m| !m.is_finite()) {
                    return Err(self.ctx.err(format!("{ipath}: matrix {bad} is not finite")));
                }
                m[..joints.len()].to_vec()
            }
        };
        let name = skin.name.clone().unwrap_or_else(|| path.clone());
        self.scene.skins.push(Skin { name, joints, inverse_bind });
        let id = (self.scene.skins.len() - 1) as u32;
        self.skin_cache.insert(index, id);
        Ok(id)
    }
}
