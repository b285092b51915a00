//! `builtin:skin-test`: an arm of three joints in front of a wall, bending in the picture's
//! plane at its middle joint and towards the camera at its last one, with a smooth blend of
//! weights between them. The skinned mesh's own node sits away from the origin, as glTF
//! allows (its transform must not move the skinned vertices). It is the skinned mesh of the
//! skinning tests (tests/skinning.rs): G-buffer against CPU skinning, backends against each
//! other through refits and rebuilds, motion vectors.

use super::animation::{Channel, Interpolation, Property};
use super::builtin::{finish, node, quad, vertex};
use super::{Animation, Camera, Influence, Instance, Light, LightKind, Material, Scene, Skin, SkinnedMesh};
use glam::{Mat4, Quat, Vec3, Vec4};

/// Facts about `skin_test` that tests check against.
pub mod facts {
    /// The camera sits at the origin looking down -Z with this vertical field of view.
    pub const YFOV: f32 = std::f32::consts::FRAC_PI_3;
    /// The arm's bind pose: a box along x in [-LENGTH / 2, LENGTH / 2], HALF_THICKNESS around
    /// y = 0 and z = ARM_Z.
    pub const ARM_Z: f32 = -4.0;
    pub const LENGTH: f32 = 3.0;
    pub const HALF_THICKNESS: f32 = 0.25;
    /// Rings of vertices along the arm.
    pub const SEGMENTS: u32 = 48;
    /// The joints' rotations run through their keys in this many seconds, then loop.
    pub const PERIOD: f32 = 2.0;
    pub const WALL_INSTANCE: u32 = 0;
    pub const ARM_INSTANCE: u32 = 1;
    pub const ARM_MESH: u32 = 1;
    /// The node drawing the arm (its transform is not applied to the skinned vertices).
    pub const ARM_NODE: u32 = 1;
}

/// The joints' x in the bind pose: the root at the arm's start, then one every LENGTH / 3.
fn joint_x() -> [f32; 3] {
    let l = facts::LENGTH;
    [-l / 2.0, -l / 6.0, l / 6.0]
}

/// Weights of the three joints at x: tents one joint-spacing wide around each joint, the
/// first and last flat beyond their joint.
fn weights(x: f32) -> [f32; 4] {
    let j = joint_x();
    let spacing = j[1] - j[0];
    let tent = |c: f32| (1.0 - (x - c).abs() / spacing).max(0.0);
    let w = [if x <= j[0] { 1.0 } else { tent(j[0]) }, tent(j[1]), if x >= j[2] { 1.0 } else { tent(j[2]) }];
    let sum: f32 = w.iter().sum();
    [w[0] / sum, w[1] / sum, w[2] / sum, 0.0]
}

/// A skinned arm, lit by a sun, before a wall; see the module doc.
pub fn skin_test() -> Scene {
    use facts::*;
    let mut s = Scene { name: "builtin:skin-test".into(), ..Default::default() };
    s.materials.push(Material {
        name: "grey".into(),
        metallic_factor: 0.0,
        roughness_factor: 0.7,
        ..Default::default()
    });
    s.materials.push(Material {
        name: "orange".into(),
        base_color_factor: Vec4::new(0.9, 0.4, 0.1, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.5,
        ..Default::default()
    });
    s.meshes.push(quad(Vec3::new(0.0, 0.0, -8.0), Vec3::X * 20.0, Vec3::Y * 20.0, 0));
    // Four sides, each its own strip of vertices (flat across, smooth along the arm).
    let h = HALF_THICKNESS;
    let sides = [(Vec3::Z, Vec3::Y), (Vec3::Y, -Vec3::Z), (-Vec3::Z, -Vec3::Y), (-Vec3::Y, Vec3::Z)];
    let (mut vertices, mut indices, mut influences) = (Vec::new(), Vec::new(), Vec::new());
    for (normal, across) in sides {
        let first = vertices.len() as u32;
        for i in 0..=SEGMENTS {
            let a = i as f32 / SEGMENTS as f32;
            let x = (a - 0.5) * LENGTH;
            for side in [-1.0, 1.0] {
                let p = Vec3::new(x, 0.0, ARM_Z) + (normal + across * side) * h;
                vertices.push(vertex(p, normal, Vec3::X, [a, 0.5 + 0.5 * side]));
                influences.push(Influence { joints: [0, 1, 2, 0], weights: weights(x) });
            }
        }
        for i in 0..SEGMENTS {
            let (a, b) = (first + 2 * i, first + 2 * i + 2);
            // Counter-clockwise seen from outside: across x along (the normal's side).
            indices.extend_from_slice(&[a, b, b + 1, a, b + 1, a + 1]);
        }
    }
    let mut arm = finish("arm", vertices, indices, 1);
    // Every pose the animation reaches stays within the arm's length of its root.
    arm.bounds_min = Vec3::new(-LENGTH / 2.0, -LENGTH, ARM_Z - LENGTH) - h;
    arm.bounds_max = Vec3::new(LENGTH * 1.5, LENGTH, ARM_Z + LENGTH) + h;
    s.meshes.push(arm);

    s.nodes.push(node("wall", Vec3::ZERO));
    s.nodes.push(node("arm", Vec3::new(0.4, -0.3, 0.6)));
    s.nodes.push(node("camera", Vec3::ZERO));
    let j = joint_x();
    let joint_nodes = [3u32, 4, 5];
    s.nodes.push(node("shoulder", Vec3::new(j[0], 0.0, ARM_Z)));
    for (k, name) in [(1, "elbow"), (2, "wrist")] {
        let mut n = node(name, Vec3::new(j[k] - j[k - 1], 0.0, 0.0));
        n.parent = Some(joint_nodes[k - 1]);
        s.nodes.push(n);
    }
    let inverse_bind = j.iter().map(|&x| Mat4::from_translation(Vec3::new(x, 0.0, ARM_Z)).inverse()).collect();
    s.skins.push(Skin { name: "arm".into(), joints: joint_nodes.to_vec(), inverse_bind });
    s.skinned.push(SkinnedMesh { mesh: ARM_MESH, skin: 0, node: ARM_NODE, influences });
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.instances.push(Instance { mesh: ARM_MESH, node: ARM_NODE });

    let turn = |axis: Vec3, degrees: f32| Vec4::from(Quat::from_axis_angle(axis, degrees.to_radians()).to_array());
    let keys = vec![0.0, PERIOD / 2.0, PERIOD];
    let rotation = |node: u32, axis: Vec3, degrees: f32| Channel {
        node,
        property: Property::Rotation,
        interpolation: Interpolation::Linear,
        times: keys.clone(),
        values: vec![turn(axis, 0.0), turn(axis, degrees), turn(axis, 0.0)],
    };
    s.animations.push(Animation {
        name: "bend".into(),
        channels: vec![rotation(joint_nodes[1], Vec3::Z, 50.0), rotation(joint_nodes[2], Vec3::Y, -40.0)],
    });
    s.cameras.push(Camera {
        name: "origin".into(),
        yfov: YFOV,
        aspect_ratio: None,
        znear: 0.1,
        zfar: Some(100.0),
        node: 2,
    });
    s.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        color: Vec3::ONE,
        intensity: 3.0,
        range: None,
        radius: 0.0,
        node: 2,
    });
    s
}
