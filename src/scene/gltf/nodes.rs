//! The node hierarchy (parents before children, cycles refused) and what nodes carry:
//! instances of meshes (GPU instancing included), morph weights, cameras and lights.

use super::accessors::read_floats;
use super::{Builder, CAMERAS, Ctx, LIGHTS, NODES, SCENES, lookup, lookup_or_warn};
use crate::scene::{Camera, Instance, Light, LightKind, Node, SceneError};
use glam::{Mat4, Quat, Vec3};
use gltf::json;
use gltf::json::validation::Checked;
use serde_json::Value;

// ---------------------------------------------------------------------------------------------
// Node hierarchy.

/// The glTF nodes of the scene to load, parents before children, each with its glTF parent.
pub(super) fn scene_nodes(ctx: &mut Ctx, root: &json::Root) -> Result<Vec<(usize, Option<usize>)>, SceneError> {
    ctx.check("node count", "max_nodes", root.nodes.len() as u64, u64::from(ctx.limits().max_nodes))?;
    let parents = node_parents(ctx, root)?;
    check_acyclic(ctx, root, &parents)?;
    let roots = scene_roots(ctx, root, &parents)?;
    walk_depth_first(ctx, root, &roots, &parents)
}

pub(super) fn children(root: &json::Root, node: usize) -> impl DoubleEndedIterator<Item = usize> + '_ {
    let children = root.nodes.get(node).and_then(|n| n.children.as_deref()).unwrap_or_default();
    children.iter().map(|c| c.value())
}

/// Each node's parent; a node listed as the child of two nodes (or twice) is an error, since
/// the hierarchy must be a forest.
pub(super) fn node_parents(ctx: &Ctx, root: &json::Root) -> Result<Vec<Option<usize>>, SceneError> {
    let mut parents = vec![None; root.nodes.len()];
    for p in 0..root.nodes.len() {
        for (k, c) in children(root, p).enumerate() {
            let path = format!("nodes[{p}].children[{k}]");
            let parent = lookup(ctx, &parents, c, NODES, &path)?;
            if c == p {
                return Err(ctx.err(format!("{path}: node {p} is its own child (a node cycle)")));
            }
            if let Some(q) = parent {
                return Err(ctx.err(format!("{path}: nodes[{c}] has two parents, nodes[{q}] and nodes[{p}]")));
            }
            if let Some(slot) = parents.get_mut(c) {
                *slot = Some(p);
            }
        }
    }
    Ok(parents)
}

/// With at most one parent per node, every node not reachable from a parentless node lies on
/// a cycle or below one.
pub(super) fn check_acyclic(ctx: &Ctx, root: &json::Root, parents: &[Option<usize>]) -> Result<(), SceneError> {
    let mut reached = vec![false; parents.len()];
    let mut stack: Vec<usize> = parentless(parents).collect();
    while let Some(i) = stack.pop() {
        if let Some(r) = reached.get_mut(i) {
            *r = true;
        }
        stack.extend(children(root, i));
    }
    let Some(start) = reached.iter().position(|r| !r) else {
        return Ok(());
    };
    // Walking up as many steps as there are nodes is sure to end on the cycle itself.
    let mut node = start;
    for _ in 0..parents.len() {
        node = parents.get(node).copied().flatten().unwrap_or(node);
    }
    Err(ctx.err(format!("nodes[{node}]: node cycle (the node is its own ancestor)")))
}

pub(super) fn parentless(parents: &[Option<usize>]) -> impl Iterator<Item = usize> + '_ {
    parents.iter().enumerate().filter(|(_, p)| p.is_none()).map(|(i, _)| i)
}

/// The root nodes of the default scene, else of scene 0, else every parentless node.
pub(super) fn scene_roots(
    ctx: &mut Ctx,
    root: &json::Root,
    parents: &[Option<usize>],
) -> Result<Vec<usize>, SceneError> {
    let scene = match root.scene {
        Some(s) => Some((s.value(), lookup(ctx, &root.scenes, s.value(), SCENES, "scene")?)),
        None => root.scenes.first().map(|s| (0, s)),
    };
    let Some((s, scene)) = scene else {
        return Ok(parentless(parents).collect());
    };
    let mut listed = vec![false; parents.len()];
    let mut roots = Vec::with_capacity(scene.nodes.len());
    for (k, node) in scene.nodes.iter().enumerate() {
        let (i, path) = (node.value(), format!("scenes[{s}].nodes[{k}]"));
        if let Some(p) = lookup(ctx, parents, i, NODES, &path)? {
            return Err(ctx.err(format!("{path}: node {i} is not a root node (it is a child of nodes[{p}])")));
        }
        if listed.get_mut(i).is_some_and(|seen| std::mem::replace(seen, true)) {
            ctx.warn(format!("{path}: node {i} is listed twice; it is loaded once"));
            continue;
        }
        roots.push(i);
    }
    Ok(roots)
}

/// Pre-order traversal, so that parents precede their children.
pub(super) fn walk_depth_first(
    ctx: &Ctx,
    root: &json::Root,
    roots: &[usize],
    parents: &[Option<usize>],
) -> Result<Vec<(usize, Option<usize>)>, SceneError> {
    let max_depth = u64::from(ctx.limits().max_node_depth);
    let mut order = Vec::new();
    let mut stack: Vec<(usize, u64)> = roots.iter().rev().map(|&r| (r, 1)).collect();
    while let Some((i, depth)) = stack.pop() {
        ctx.check(&format!("nodes[{i}]: hierarchy depth"), "max_node_depth", depth, max_depth)?;
        order.push((i, parents.get(i).copied().flatten()));
        stack.extend(children(root, i).rev().map(|c| (c, depth + 1)));
    }
    Ok(order)
}

/// Translation, rotation and scale of a node matrix. A matrix that scales an axis to zero has
/// no defined rotation; identity stands in.
pub(super) fn decompose(m: Mat4) -> (Vec3, Quat, Vec3) {
    let (scale, rotation, translation) = m.to_scale_rotation_translation();
    (translation, if rotation.is_finite() { rotation } else { Quat::IDENTITY }, scale)
}

/// The unit quaternion of an xyzw array; `None` for a zero quaternion.
pub(super) fn unit_quat(q: [f32; 4]) -> Option<Quat> {
    let q = Quat::from_array(q);
    (q.length_squared() > 0.0).then(|| q.normalize())
}

// ---------------------------------------------------------------------------------------------
// Nodes, instances, cameras and lights.

impl Builder<'_> {
    pub(super) fn add_nodes(&mut self, order: &[(usize, Option<usize>)]) -> Result<(), SceneError> {
        let root = self.data.root;
        for &(i, parent) in order {
            let node = lookup(&self.ctx, &root.nodes, i, NODES, "scene")?;
            let (translation, rotation, scale) = self.node_transform(i, node)?;
            let parent = parent.and_then(|p| self.scene_node.get(p).copied().flatten());
            if let Some(slot) = self.scene_node.get_mut(i) {
                *slot = Some(self.scene.nodes.len() as u32);
            }
            let name = node.name.clone().unwrap_or_default();
            self.scene.nodes.push(Node { name, parent, translation, rotation, scale });
        }
        Ok(())
    }

    pub(super) fn node_transform(&mut self, i: usize, node: &json::Node) -> Result<(Vec3, Quat, Vec3), SceneError> {
        let (translation, rotation, scale) = match node.matrix {
            Some(m) => decompose(Mat4::from_cols_array(&m)),
            None => (
                node.translation.map_or(Vec3::ZERO, Vec3::from),
                node.rotation.map_or(Quat::IDENTITY, |q| Quat::from_array(q.0)),
                node.scale.map_or(Vec3::ONE, Vec3::from),
            ),
        };
        if !(translation.is_finite() && rotation.is_finite() && scale.is_finite()) {
            return Err(self.ctx.err(format!("nodes[{i}]: transform is not finite")));
        }
        let rotation = unit_quat(rotation.to_array()).unwrap_or_else(|| {
            self.ctx.warn(format!("nodes[{i}].rotation: zero quaternion; using identity"));
            Quat::IDENTITY
        });
        Ok((translation, rotation, scale))
    }

    /// Attaches a node's mesh instances, camera and light.
    pub(super) fn attach(&mut self, i: usize) -> Result<(), SceneError> {
        let root = self.data.root;
        let (Some(node), Some(scene_index)) = (root.nodes.get(i), self.scene_node.get(i).copied().flatten()) else {
            return Ok(());
        };
        let path = format!("nodes[{i}]");
        if let Some(mesh) = node.mesh {
            self.attach_mesh(i, node, mesh.value(), scene_index)?;
        }
        if let Some(skin) = node.skin {
            let primitives = match node.mesh {
                Some(mesh) => self.mesh(mesh.value(), &format!("{path}.mesh"))?,
                None => Vec::new(),
            };
            self.attach_skin(i, skin.value(), &primitives, scene_index)?;
        }
        if let Some(camera) = node.camera {
            self.attach_camera(&path, camera.value(), scene_index);
        }
        if let Some(light) = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()) {
            self.attach_light(&path, light.light.value(), scene_index);
        }
        Ok(())
    }

    pub(super) fn attach_mesh(
        &mut self,
        i: usize,
        node: &json::Node,
        mesh: usize,
        scene_index: u32,
    ) -> Result<(), SceneError> {
        let primitives = self.mesh(mesh, &format!("nodes[{i}].mesh"))?;
        let targets = self.gpu_instances(i, node, scene_index)?.unwrap_or_else(|| vec![scene_index]);
        let drawn = primitives.iter().flatten().count() as u64;
        let instances = (self.scene.instances.len() as u64).saturating_add(drawn.saturating_mul(targets.len() as u64));
        let limit = self.ctx.limits().max_instances;
        self.ctx.check(
            &format!("nodes[{i}]: mesh instances in the scene so far"),
            "max_instances",
            instances,
            limit,
        )?;
        for &node in &targets {
            for &mesh in primitives.iter().flatten() {
                self.scene.instances.push(Instance { mesh, node });
            }
        }
        self.drive_morphs(i, node, &primitives);
        Ok(())
    }

    /// Makes glTF node `i` the driver of its meshes' morphs that have none yet: its `weights`
    /// replace the mesh's, and weight animations of the node play on them. A deforming mesh
    /// has one shape per frame, so other nodes drawing it show the driver's shape.
    pub(super) fn drive_morphs(&mut self, i: usize, node: &json::Node, primitives: &[Option<u32>]) {
        for &mesh in primitives.iter().flatten() {
            let Some(k) = self.scene.morphs.iter().position(|m| m.mesh == mesh) else {
                continue;
            };
            match self.morph_driver[k] {
                None => {
                    self.morph_driver[k] = Some(i);
                    if let Some(weights) = &node.weights {
                        let count = self.scene.morphs[k].targets.len();
                        let path = format!("nodes[{i}].weights");
                        self.scene.morphs[k].weights = self.fit_weights(weights, count, &path);
                    }
                }
                Some(driver) if driver != i => self.ctx.warn_once(
                    "morph-shared",
                    "a morphing mesh drawn by several nodes takes the shape of the first node's weights in all",
                ),
                Some(_) => {}
            }
        }
    }

    /// `weights` for `count` targets: a list of another length is replaced by zeros (with a
    /// warning), non-finite weights by 0.
    pub(super) fn fit_weights(&mut self, weights: &[f32], count: usize, path: &str) -> Vec<f32> {
        if weights.len() != count {
            self.ctx.warn(format!("{path}: {} weights for {count} morph targets; using 0", weights.len()));
            return vec![0.0; count];
        }
        weights.iter().map(|w| if w.is_finite() { *w } else { 0.0 }).collect()
    }

    /// EXT_mesh_gpu_instancing: one child node per instance, so the instances share the
    /// node's meshes and follow its animation. `None` when the node is not instanced.
    pub(super) fn gpu_instances(
        &mut self,
        i: usize,
        node: &json::Node,
        parent: u32,
    ) -> Result<Option<Vec<u32>>, SceneError> {
        let pointer = format!("/nodes/{i}/extensions/EXT_mesh_gpu_instancing/attributes");
        let Some(attributes) = self.data.untyped.and_then(|json| json.pointer(&pointer)) else {
            return Ok(None);
        };
        let path = format!("nodes[{i}].extensions.EXT_mesh_gpu_instancing.attributes");
        let translations = self.instance_attribute::<3>(attributes, "TRANSLATION", &path)?;
        let rotations = self.instance_attribute::<4>(attributes, "ROTATION", &path)?;
        let scales = self.instance_attribute::<3>(attributes, "SCALE", &path)?;
        let counts =
            [translations.as_ref().map(Vec::len), rotations.as_ref().map(Vec::len), scales.as_ref().map(Vec::len)];
        let Some(count) = counts.iter().flatten().copied().max() else {
            self.ctx.warn(format!("{path}: no TRANSLATION, ROTATION or SCALE; the mesh is drawn once"));
            return Ok(None);
        };
        if counts.iter().flatten().any(|&c| c != count) {
            return Err(self.ctx.err(format!("{path}: the attribute accessors differ in count")));
        }
        let nodes = (self.scene.nodes.len() + count) as u64;
        self.ctx.check(
            &format!("{path}: node count with instances"),
            "max_nodes",
            nodes,
            u64::from(self.ctx.limits().max_nodes),
        )?;
        let name = node.name.clone().unwrap_or_default();
        let mut ids = Vec::with_capacity(count);
        for k in 0..count {
            let t = translations.as_ref().and_then(|v| v.get(k)).map_or(Vec3::ZERO, |&t| Vec3::from(t));
            let r = rotations.as_ref().and_then(|v| v.get(k)).map_or(Some(Quat::IDENTITY), |&r| unit_quat(r));
            let s = scales.as_ref().and_then(|v| v.get(k)).map_or(Vec3::ONE, |&s| Vec3::from(s));
            let Some(r) = r.filter(|r| r.is_finite() && t.is_finite() && s.is_finite()) else {
                return Err(self.ctx.err(format!("{path}: instance {k} has a non-finite or zero-rotation transform")));
            };
            ids.push(self.scene.nodes.len() as u32);
            let node =
                Node { name: format!("{name}#{k}"), parent: Some(parent), translation: t, rotation: r, scale: s };
            self.scene.nodes.push(node);
        }
        Ok(Some(ids))
    }

    pub(super) fn instance_attribute<const N: usize>(
        &self,
        attributes: &Value,
        name: &str,
        path: &str,
    ) -> Result<Option<Vec<[f32; N]>>, SceneError> {
        let Some(value) = attributes.get(name) else {
            return Ok(None);
        };
        let path = format!("{path}.{name}");
        let index = value.as_u64().and_then(|i| usize::try_from(i).ok());
        let index = index.ok_or_else(|| self.ctx.err(format!("{path}: not an accessor index")))?;
        read_floats::<N>(&self.ctx, &self.data, index, &path).map(Some)
    }

    pub(super) fn attach_camera(&mut self, path: &str, index: usize, node: u32) {
        let root = self.data.root;
        let path = format!("{path}.camera");
        let Some(camera) = lookup_or_warn(&mut self.ctx, &root.cameras, index, CAMERAS, &path, "the camera is skipped")
        else {
            return;
        };
        let perspective =
            camera.perspective.as_ref().filter(|p| p.yfov > 0.0 && p.yfov < std::f32::consts::PI && p.znear > 0.0);
        match (camera.type_, perspective) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p)) => self.scene.cameras.push(Camera {
                name: camera.name.clone().unwrap_or_default(),
                yfov: p.yfov,
                aspect_ratio: p.aspect_ratio,
                znear: p.znear,
                zfar: p.zfar,
                node,
            }),
            (Checked::Valid(json::camera::Type::Orthographic), _) => {
                self.ctx.warn(format!(
                    "cameras[{index}]: orthographic cameras are not supported; \
                     the camera is skipped"
                ));
            }
            _ => self.ctx.warn(format!("cameras[{index}]: not a valid perspective camera; the camera is skipped")),
        }
    }

    pub(super) fn attach_light(&mut self, path: &str, index: usize, node: u32) {
        use json::extensions::scene::khr_lights_punctual::Type;
        let root = self.data.root;
        let lights = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let lights = lights.map_or(&[][..], |l| &l.lights[..]);
        let path = format!("{path}.extensions.KHR_lights_punctual.light");
        let Some(light) = lookup_or_warn(&mut self.ctx, lights, index, LIGHTS, &path, "the light is skipped") else {
            return;
        };
        let kind = match light.type_ {
            Checked::Valid(Type::Directional) => LightKind::Directional,
            Checked::Valid(Type::Point) => LightKind::Point,
            Checked::Valid(Type::Spot) => LightKind::Spot {
                inner_cone: light.spot.as_ref().map_or(0.0, |s| s.inner_cone_angle),
                outer_cone: light.spot.as_ref().map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle),
            },
            Checked::Invalid => {
                self.ctx.warn(format!("lights[{index}].type: invalid light type; the light is skipped"));
                return;
            }
        };
        self.scene.lights.push(Light {
            name: light.name.clone().unwrap_or_default(),
            kind,
            color: Vec3::from(light.color),
            intensity: light.intensity,
            range: light.range,
            radius: light_radius(light.extras.as_deref()),
            node,
        });
    }
}

/// `extras.radius` of a light, 0 when absent or not a finite non-negative number.
pub(super) fn light_radius(extras: Option<&serde_json::value::RawValue>) -> f32 {
    let extras: Option<Value> = extras.and_then(|raw| serde_json::from_str(raw.get()).ok());
    let radius = extras.and_then(|e| e.get("radius")?.as_f64()).map_or(0.0, |r| r as f32);
    if radius.is_finite() { radius.max(0.0) } else { 0.0 }
}
