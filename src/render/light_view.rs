//! What each light brings to what the camera sees first: the shadows chain's ranking
//! (world::lights::chain_lights) where more lights compete for its four channels than it has.
//! Ranked by the power a light emits over the whole scene, a bright light behind a wall took a
//! channel, with its exact, noise-free visibility, that a light in the camera's room would use:
//! `builtin:many-lights` gave two of the four to its sealed room.
//!
//! So each candidate is ranked by its direct light on the view at time 0: a grid of primary rays
//! through the starting camera on the CPU BVH, and at each opaque surface they reach, the
//! luminance of the light's unshadowed irradiance there (a mesh light's from each triangle's
//! centroid) times whether one shadow ray toward it arrives, summed. See-through surfaces
//! (render::sky_reach::Surface) are crossed as if open, since light passes them.

use super::camera::View;
use super::sky_reach::Surface;
use crate::accel::bvh::{SceneBvh, closest_hit};
use crate::scene::{Pose, Scene};
use crate::world::environment::luminance;
use crate::world::lights::{ChainCandidate, EMITTER_DOUBLE_SIDED, GpuEmitter, centroid, emitters};
use crate::world::scene_gpu::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_SPOT, gpu_lights};
use glam::{Vec2, Vec3};

/// The grid of primary rays, columns by rows: enough that a spot's pool of light a tenth of the
/// view wide holds a few of them.
pub const GRID: [u32; 2] = [32, 24];
/// See-through surfaces a ray crosses before it counts as stopped.
const CROSSINGS: usize = 8;

/// The surfaces the starting view sees, and what their rays are traced against.
pub struct LightView<'a> {
    scene: &'a Scene,
    bvh: SceneBvh,
    pose: Pose,
    /// Each surface's point and its normal on the camera's side.
    surfaces: Vec<(Vec3, Vec3)>,
    lights: Vec<GpuLight>,
    emitters: Vec<GpuEmitter>,
    /// Offsets off a surface, relative to the scene's size (as sky_reach's).
    eps: f32,
}

impl<'a> LightView<'a> {
    /// The surfaces of the scene at time 0 that `GRID` rays through each of `views` reach.
    pub fn new(scene: &'a Scene, views: &[View]) -> Self {
        let pose = scene.evaluate(0.0);
        let bvh = SceneBvh::build(scene, &pose);
        let (lo, hi) = scene.bounds(&pose);
        let eps = 1e-4 * (hi - lo).max_element().max(1e-3);
        let size = Vec2::new(GRID[0] as f32, GRID[1] as f32);
        let mut surfaces = Vec::new();
        for (view, k) in views.iter().flat_map(|v| (0..GRID[0] * GRID[1]).map(move |k| (v, k))) {
            let pixel = Vec2::new((k % GRID[0]) as f32 + 0.5, (k / GRID[0]) as f32 + 0.5);
            let dir = view.ray_dir(pixel, size);
            let mut origin = view.position;
            for _ in 0..CROSSINGS {
                let Some(hit) = closest_hit(&bvh, origin, dir, 0.0, f32::INFINITY, 0xFF, |_, _, _, _| false) else {
                    break;
                };
                let s = Surface::at(scene, &pose, &hit, origin, dir);
                if !s.see_through {
                    surfaces.push((s.position + s.facing * eps, s.facing));
                    break;
                }
                origin = s.position - s.facing * eps;
            }
        }
        let lights = gpu_lights(scene, &pose);
        let emitters = emitters(scene, &pose, &[]);
        Self { scene, bvh, pose, surfaces, lights, emitters, eps }
    }

    /// How many of the grid's rays reached a surface.
    pub fn surfaces(&self) -> usize {
        self.surfaces.len()
    }

    /// What `candidate` brings to the view: its direct irradiance's luminance summed over the
    /// view's surfaces, where a shadow ray toward it arrives. (Never NaN, which would rank
    /// first: `max` takes 0 for it.)
    pub fn brings(&self, candidate: ChainCandidate) -> f32 {
        let sum: f32 = match candidate {
            ChainCandidate::Punctual(i) => {
                self.surfaces.iter().map(|&(p, n)| self.punctual(&self.lights[i], p, n)).sum()
            }
            ChainCandidate::Mesh(instance) => {
                let mesh = &self.scene.meshes[self.scene.instances[instance as usize].mesh as usize];
                let emission = luminance(self.scene.materials[mesh.material as usize].emissive_factor);
                let triangles: Vec<&GpuEmitter> = self.emitters.iter().filter(|e| e.instance == instance).collect();
                let sum: f32 = self
                    .surfaces
                    .iter()
                    .map(|&(p, n)| triangles.iter().map(|e| self.triangle(e, p, n)).sum::<f32>())
                    .sum();
                emission * sum
            }
        };
        sum.max(0.0)
    }

    /// A punctual light's irradiance at `p` (normal `n`), where it arrives: glTF's inverse
    /// square with the range window and a spot's cone (common/lights.glsl).
    fn punctual(&self, light: &GpuLight, p: Vec3, n: Vec3) -> f32 {
        let intensity = luminance(Vec3::from(light.intensity));
        if light.kind == LIGHT_DIRECTIONAL {
            let l = -Vec3::from(light.direction);
            let cos = n.dot(l);
            return if cos > 0.0 && self.arrives(p, l, f32::INFINITY) { intensity * cos } else { 0.0 };
        }
        let to = Vec3::from(light.position) - p;
        let d = to.length();
        let l = to / d.max(1e-12);
        let cos = n.dot(l);
        if cos <= 0.0 {
            return 0.0;
        }
        let window = crate::world::light_grid::range_window(d, light.range);
        let cone = if light.kind == LIGHT_SPOT {
            let cd = Vec3::from(light.direction).dot(-l);
            ((cd - light.cos_outer) / (light.cos_inner - light.cos_outer).max(1e-4)).clamp(0.0, 1.0).powi(2)
        } else {
            1.0
        };
        let e = intensity * cos * window * cone / (d * d).max(self.eps * self.eps);
        if e > 0.0 && self.arrives(p, l, d) { e } else { 0.0 }
    }

    /// An emissive triangle's irradiance at `p` (normal `n`) per unit of its radiance, seen as
    /// a point at its centroid (Le A cos cos / d^2, the distance kept above the triangle's
    /// size), where it arrives.
    fn triangle(&self, e: &GpuEmitter, p: Vec3, n: Vec3) -> f32 {
        let to = centroid(e) - p;
        let d = to.length();
        let l = to / d.max(1e-12);
        let facing = -Vec3::from(e.normal).dot(l);
        let cos_e = if e.flags & EMITTER_DOUBLE_SIDED != 0 { facing.abs() } else { facing };
        let cos = n.dot(l);
        if cos_e <= 0.0 || cos <= 0.0 {
            return 0.0;
        }
        let f = e.area * cos_e * cos / (d * d).max(e.area);
        // Short of the centroid: the triangle itself must not count as in the way.
        if self.arrives(p, l, d * (1.0 - 1e-3)) { f } else { 0.0 }
    }

    /// Whether a ray from `p` toward `l` passes `dist` without an opaque surface in the way.
    /// Thin glass and masked or blended surfaces are alpha-tested instances whose candidates the
    /// closure turns down, so the ray passes them as sky_reach's walks do; a volume's surface
    /// is hit and crossed in the loop.
    fn arrives(&self, p: Vec3, l: Vec3, dist: f32) -> bool {
        let mut origin = p;
        let mut left = dist;
        for _ in 0..CROSSINGS {
            let Some(hit) = closest_hit(&self.bvh, origin, l, 0.0, left, 0xFF, |_, _, _, _| false) else {
                return true;
            };
            let s = Surface::at(self.scene, &self.pose, &hit, origin, l);
            if !s.see_through {
                return false;
            }
            origin = s.position - s.facing * self.eps;
            left -= hit.t + self.eps;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::{CameraChoice, first_view};
    use crate::render::plan::FramePlan;
    use crate::scene::builtin_many_lights::{facts, many_lights, many_panels};

    fn seen_from_the_camera(s: &Scene) -> LightView<'_> {
        LightView::new(s, &[first_view(s, &CameraChoice::Default, 64, 64).unwrap()])
    }

    /// `builtin:many-lights`: the sealed room's lights bring nothing to the camera's room, and
    /// the camera room's lights whose range reaches what it sees bring something.
    #[test]
    fn lights_behind_the_wall_bring_nothing_to_the_view() {
        let s = many_lights();
        let view = seen_from_the_camera(&s);
        assert_eq!(view.surfaces(), (GRID[0] * GRID[1]) as usize, "the camera is inside a closed room");
        let brings = |i| view.brings(ChainCandidate::Punctual(i));
        let (hidden, own): (Vec<usize>, Vec<usize>) =
            (0..s.lights.len()).partition(|&i| s.lights[i].name.starts_with(facts::HIDDEN_PREFIX));
        assert!(hidden.iter().all(|&i| brings(i) == 0.0));
        // (Their range is 1.25: those in the room's far corners light little of what it sees;
        // measured 24 of 48.)
        let lit = own.iter().filter(|&&i| brings(i) > 0.0).count();
        assert!(lit >= own.len() / 3, "{lit} of {} camera-room lights reach the view", own.len());
        // The same of the panels: instances named like the lights.
        let s = many_panels();
        let view = seen_from_the_camera(&s);
        for (i, inst) in s.instances.iter().enumerate() {
            let name = &s.nodes[inst.node as usize].name;
            let b = view.brings(ChainCandidate::Mesh(i as u32));
            if name.starts_with(facts::HIDDEN_PREFIX) {
                assert_eq!(b, 0.0, "{name}");
            } else if name.starts_with("visible.") {
                assert!(b > 0.0, "{name}");
            }
        }
    }

    /// A floor seen from above between two walls, an opaque one and a glass one, with a light
    /// behind each, two spots over it (one turned away) and a sun.
    #[test]
    fn what_a_light_brings_follows_its_kind_and_what_stands_in_the_way() {
        use crate::scene::builtin::{node, quad};
        use crate::scene::{Instance, Light, LightKind, Material};
        let mut s = Scene::default();
        s.materials.push(Material { name: "white".into(), ..Default::default() });
        // A volume's surface: thin glass is not even a candidate for these rays (its instance is
        // alpha-tested, and the closure turns its candidates down), a volume's is crossed here.
        s.materials.push(Material { name: "glass".into(), transmission: 1.0, thickness: 0.1, ..Default::default() });
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        // The floor faces up (Z x X); the walls stand at x = 2.5 (opaque) and x = -2.5 (glass).
        let meshes = [
            quad(Vec3::ZERO, z * 4.0, x * 4.0, 0),
            quad(Vec3::new(2.5, 2.5, 0.0), y * 5.0, z * 10.0, 0),
            quad(Vec3::new(-2.5, 2.5, 0.0), y * 5.0, z * 10.0, 1),
        ];
        for (k, mesh) in meshes.into_iter().enumerate() {
            s.meshes.push(mesh);
            s.nodes.push(node(&format!("mesh {k}"), Vec3::ZERO));
            s.instances.push(Instance { mesh: k as u32, node: k as u32 });
        }
        let down = glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        let spot = LightKind::Spot { inner_cone: 0.3, outer_cone: 0.6 };
        let lights = [
            ("behind the wall", LightKind::Point, Vec3::new(3.0, 1.0, 0.0), glam::Quat::IDENTITY),
            ("behind the glass", LightKind::Point, Vec3::new(-3.0, 1.0, 0.0), glam::Quat::IDENTITY),
            ("spot down", spot, Vec3::new(0.0, 2.0, 0.0), down),
            ("spot up", spot, Vec3::new(0.0, 2.0, 0.0), down.inverse()),
            ("sun", LightKind::Directional, Vec3::new(0.0, 5.0, 0.0), down),
        ];
        for (name, kind, at, rotation) in lights {
            let mut n = node(name, at);
            n.rotation = rotation;
            s.nodes.push(n);
            let node = s.nodes.len() as u32 - 1;
            s.lights.push(Light {
                name: name.into(),
                kind,
                color: Vec3::ONE,
                intensity: 1.0,
                range: None,
                radius: 0.0,
                node,
            });
        }
        let eye = Vec3::new(0.0, 4.0, 3.0);
        let view = crate::render::camera::perspective(
            glam::Mat4::look_at_rh(eye, Vec3::ZERO, Vec3::Y),
            eye,
            0.8,
            1.0,
            0.05,
            100.0,
        );
        let seen = LightView::new(&s, &[view]);
        assert!(seen.surfaces() > 0);
        let brings: Vec<f32> = (0..s.lights.len()).map(|i| seen.brings(ChainCandidate::Punctual(i))).collect();
        assert_eq!(brings[0], 0.0, "through the opaque wall: {brings:?}");
        assert!(brings[1] > 0.0, "glass lets it through: {brings:?}");
        assert!(brings[2] > 0.0 && brings[3] == 0.0, "the spots: {brings:?}");
        assert!(brings[4] > 0.0, "the sun: {brings:?}");
    }

    /// Ranked by power, two of the four channels went to the sealed room's sphere lights (and
    /// with them the soft-shadow passes); ranked by the view, all four go to the camera's room.
    #[test]
    fn the_chain_goes_to_the_camera_room() {
        let s = many_lights();
        let names = |p: &FramePlan| -> Vec<String> {
            p.light_order[..p.chain_punctual].iter().map(|&i| s.lights[i].name.clone()).collect()
        };
        let by_power = FramePlan::for_scene(&s, 0.6, true, true, &[]);
        assert!(!by_power.chain_by_view);
        assert_eq!(names(&by_power).iter().filter(|n| n.starts_with(facts::HIDDEN_PREFIX)).count(), 2);
        assert!(by_power.soft_shadows);
        let view = first_view(&s, &CameraChoice::Default, 64, 64).unwrap();
        let by_view = FramePlan::for_scene(&s, 0.6, true, true, &[view]);
        assert!(by_view.chain_by_view);
        let chain = names(&by_view);
        assert!(chain.len() == 4 && chain.iter().all(|n| n.starts_with("visible.")), "{chain:?}");
        assert!(!by_view.soft_shadows, "the camera room's lights are points: {:?}", by_view.reasons);
        assert_eq!(by_view.resampled_lights, by_power.resampled_lights);
    }

    /// A camera that walks into the sealed room halfway through its animation ranks the lights
    /// of both rooms by what it sees of them over the whole shot (camera::shot_views): the
    /// sealed room's take channels that the first view alone gives to the camera's room.
    #[test]
    fn an_animated_camera_ranks_the_lights_of_the_rooms_it_walks_into() {
        use crate::render::camera::shot_views;
        use crate::scene::animation::{Channel, Interpolation, Property};
        let mut s = many_lights();
        let camera = s.cameras[0].node;
        let look = |eye: Vec3, at: Vec3| {
            glam::Vec4::from(glam::Quat::from_mat4(&glam::Mat4::look_at_rh(eye, at, Vec3::Y).inverse()).to_array())
        };
        let (camera_room, sealed_room) = (Vec3::new(-3.9, 2.2, 0.0), Vec3::new(3.9, 2.2, 0.0));
        let step = |property, values: [glam::Vec4; 2]| Channel {
            node: camera,
            property,
            interpolation: Interpolation::Step,
            times: vec![0.0, 1.0, 2.0],
            values: vec![values[0], values[1], values[1]],
        };
        s.animations.push(crate::scene::Animation {
            name: "walk".into(),
            channels: vec![
                step(Property::Translation, [camera_room.extend(0.0), sealed_room.extend(0.0)]),
                step(
                    Property::Rotation,
                    [look(camera_room, Vec3::new(0.0, 0.6, 0.0)), look(sealed_room, Vec3::new(0.5, 0.6, 0.0))],
                ),
            ],
        });
        let names = |p: &FramePlan| -> Vec<String> {
            p.light_order[..p.chain_punctual].iter().map(|&i| s.lights[i].name.clone()).collect()
        };
        let first =
            FramePlan::for_scene(&s, 0.6, true, true, &[first_view(&s, &CameraChoice::Default, 64, 64).unwrap()]);
        assert!(names(&first).iter().all(|n| n.starts_with("visible.")), "{:?}", names(&first));
        let views = shot_views(&s, &CameraChoice::Default, 64, 64).unwrap();
        assert_eq!(views.len(), 8);
        let shot = FramePlan::for_scene(&s, 0.6, true, true, &views);
        let chain = names(&shot);
        eprintln!("the shot's chain: {chain:?}; the first view's: {:?}", names(&first));
        assert!(chain.iter().any(|n| n.starts_with(facts::HIDDEN_PREFIX)), "{chain:?}");
        assert!(
            shot.reasons.iter().any(|r| r.contains("the camera's 8 views over its animation")),
            "{:?}",
            shot.reasons
        );
        // A camera that does not move is one view, however the rest of the scene moves.
        s.animations[0].channels.iter_mut().for_each(|c| c.node = s.nodes.len() as u32 - 1);
        assert_eq!(shot_views(&s, &CameraChoice::Default, 64, 64).unwrap().len(), 1);
    }
}
