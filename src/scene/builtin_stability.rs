//! Scripted scenes of the stability suite (src/bench/stability.rs): each puts one known failure
//! point of a real-time ray tracer in front of a camera, small enough for a CPU Vulkan driver.
//! Reachable as `builtin:NAME` like the other built-in scenes.
//!
//! | scene | failure points |
//! | --- | --- |
//! | `stability-slide` | camera cut, fast pan, ghosting and disocclusion behind a moving cube |
//! | `stability-lights` | lag after a light moves and after one switches off |
//! | `stability-lights-resampled` | the same with both lights resampled (four brighter ones behind the wall) |
//! | `stability-lights-occluded` | lag after a box closes around a light |
//! | `stability-lights-occluded-resampled` | the same around a resampled light |
//! | `stability-leak` | light leaking through a zero-thickness wall into a sealed room |
//! | `stability-cache-leak` | light leaking through a wall thinner than a radiance-cache cell |
//! | `stability-grazing` | shadow acne on a floor lit at a grazing angle, shadow terminator |
//! | `stability-firefly` | fireflies from a tiny, very bright emitter |
//! | `stability-mirror` | a mirror's reflection while the camera moves sideways over it |
//! | `stability-glass` | what a glass pane shows while the camera moves sideways past it |
//! | `stability-blend` | the same past a blended (alpha 0.3) pane |
//! | `stability-slab` | the same past a slab of glass (a volume) |
//! | `stability-rough-glass` | the same past a rough glass pane (roughness 0.3) |
//! | `stability-glass-reflect` | the same past a turned pane that also reflects a brighter wall |
//! | `stability-lens` | the same past a ball of glass, which turns what shows through it |

use super::animation::{Channel, Interpolation, Property};
use super::builtin::{cuboid, node, quad, uv_sphere};
use super::{AlphaMode, Animation, Camera, Instance, Light, LightKind, Material, Node, Scene};
use glam::{Mat4, Quat, Vec3, Vec4};

/// Names accepted after `builtin:` for the scenes of this file.
pub const NAMES: &[&str] = &[
    "stability-slide",
    "stability-slide-morph",
    "stability-lights",
    "stability-lights-resampled",
    "stability-lights-occluded",
    "stability-lights-occluded-resampled",
    "stability-leak",
    "stability-cache-leak",
    "stability-grazing",
    "stability-firefly",
    "stability-mirror",
    "stability-glass",
    "stability-blend",
    "stability-slab",
    "stability-rough-glass",
    "stability-glass-reflect",
    "stability-lens",
];

/// The scene called `name`, if it is one of [`NAMES`].
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "stability-slide" => Some(slide()),
        "stability-slide-morph" => Some(slide_morph()),
        "stability-lights" => Some(lights()),
        "stability-lights-resampled" => Some(lights_resampled()),
        "stability-lights-occluded" => Some(lights_occluded(false)),
        "stability-lights-occluded-resampled" => Some(lights_occluded(true)),
        "stability-leak" => Some(leak()),
        "stability-cache-leak" => Some(cache_leak()),
        "stability-grazing" => Some(grazing()),
        "stability-firefly" => Some(firefly()),
        "stability-mirror" => Some(mirror()),
        "stability-glass" => Some(glass()),
        "stability-blend" => Some(blend()),
        "stability-slab" => Some(slab()),
        "stability-rough-glass" => Some(rough_glass()),
        "stability-glass-reflect" => Some(glass_reflect()),
        "stability-lens" => Some(lens()),
        _ => None,
    }
}

fn diffuse(name: &str, albedo: f32) -> Material {
    Material {
        name: name.into(),
        base_color_factor: Vec4::new(albedo, albedo, albedo, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Default::default()
    }
}

/// A node at `eye` whose -Z axis (a camera's or a light's view direction) points at `target`.
fn looking(name: &str, eye: Vec3, target: Vec3) -> Node {
    let mut n = node(name, eye);
    n.rotation = Quat::from_mat4(&Mat4::look_at_rh(eye, target, Vec3::Y).inverse());
    n
}

fn camera(name: &str, yfov: f32, node: u32) -> Camera {
    Camera { name: name.into(), yfov, aspect_ratio: None, znear: 0.05, zfar: Some(100.0), node }
}

/// Scene animations loop over their longest channel; a last key this late holds every
/// channel's final value for the whole suite.
const HOLD: f32 = 1000.0;

fn light(name: &str, kind: LightKind, intensity: f32, node: u32) -> Light {
    Light { name: name.into(), kind, color: Vec3::ONE, intensity, range: None, radius: 0.0, node }
}

/// Adds `mesh` drawn at a new node `name` at `at`; returns the instance index.
fn add(s: &mut Scene, name: &str, mesh: super::Mesh, at: Vec3) -> u32 {
    s.meshes.push(mesh);
    s.nodes.push(node(name, at));
    s.instances.push(Instance { mesh: s.meshes.len() as u32 - 1, node: s.nodes.len() as u32 - 1 });
    s.instances.len() as u32 - 1
}

/// A wall material whose albedo is a checkerboard of 8x8 squares, sRGB 230 and 110 (linear
/// 0.79 and 0.16), sampled nearest and repeated `repeat` times across the wall's UVs; adds the
/// texture to `s`.
fn checker_wall(s: &mut Scene, repeat: glam::Vec2) -> Material {
    let size = 32u32;
    let cell = size / 8;
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let v = if (x / cell + y / cell).is_multiple_of(2) { 230 } else { 110 };
            rgba.extend_from_slice(&[v, v, v, 255]);
        }
    }
    s.images.push(super::Image { name: "checker".into(), width: size, height: size, rgba8: rgba });
    s.textures.push(super::Texture {
        image: Some(s.images.len() as u32 - 1),
        sampler: super::Sampler {
            mag_filter: super::Filter::Nearest,
            min_filter: super::Filter::Nearest,
            mipmaps: false,
            wrap_s: super::Wrap::Repeat,
            wrap_t: super::Wrap::Repeat,
        },
    });
    let mut wall = diffuse("wall", 1.0);
    wall.base_color_texture = Some(super::TextureRef {
        texture: s.textures.len() as u32 - 1,
        uv_set: 0,
        transform: glam::Mat3::from_scale(repeat),
    });
    wall
}

/// Facts about `slide` that the suite checks against.
pub mod slide_facts {
    /// The sliding cube's instance (after the wall's and the floor's).
    pub const CUBE_INSTANCE: u32 = 2;
    /// The cube slides from x = -CUBE_TRAVEL to +CUBE_TRAVEL between t = 0 and t = SLIDE_END,
    /// from out of view on the left to out of view on the right of the `front` camera, and
    /// stays there.
    pub const CUBE_TRAVEL: f32 = 4.0;
    pub const SLIDE_END: f32 = 0.8;
    /// The `pan` camera turns from PAN_YAW to -PAN_YAW (radians) between PAN_START and
    /// PAN_END: 2.8 degrees a frame at 30 frames a second.
    pub const PAN_YAW: f32 = 0.44;
    pub const PAN_START: f32 = 1.0;
    pub const PAN_END: f32 = 1.6;
    /// Cameras: `front` (static, the wall), `pan`, `aside` (the cut's target: the floor behind
    /// the other two, which they never see).
    pub const FRONT: usize = 0;
    pub const PAN: usize = 1;
    pub const ASIDE: usize = 2;
}

/// A sunlit wall with a checkerboard albedo behind a dark cube that slides across the view;
/// a floor whose bounce light reaches the wall (a noisy signal for the denoiser). Cameras:
/// `front` looks at the wall, `pan` (at the same spot) turns fast across it once the cube has
/// gone, `aside` looks down at the floor behind them.
pub fn slide() -> Scene {
    use slide_facts::*;
    let mut s = Scene { name: "builtin:stability-slide".into(), ..Default::default() };
    let wall = checker_wall(&mut s, glam::Vec2::new(4.0, 1.5));
    s.materials.push(wall);
    s.materials.push(diffuse("floor", 0.6));
    s.materials.push(diffuse("cube", 0.03));
    add(&mut s, "wall", quad(Vec3::new(0.0, 1.0, -4.0), Vec3::X * 16.0, Vec3::Y * 6.0, 0), Vec3::ZERO);
    add(&mut s, "floor", quad(Vec3::new(0.0, -1.0, 0.0), Vec3::Z * 12.0, Vec3::X * 16.0, 1), Vec3::ZERO);
    let cube = add(&mut s, "cube", cuboid(Vec3::splat(0.5), 2), Vec3::new(-CUBE_TRAVEL, 0.0, -2.0));
    let eye = Vec3::new(0.0, 0.0, 2.0);
    let front = s.nodes.len() as u32;
    s.nodes.push(node("front", eye));
    s.nodes.push(node("pan", eye));
    s.nodes.push(looking("aside", Vec3::new(0.0, 0.5, 5.0), Vec3::new(0.0, -1.0, 3.0)));
    for (i, name) in ["front", "pan", "aside"].into_iter().enumerate() {
        s.cameras.push(camera(name, 0.9, front + i as u32));
    }
    let sun = s.nodes.len() as u32;
    s.nodes.push(looking("sun", Vec3::ZERO, Vec3::new(0.3, -0.5, -1.0)));
    s.lights.push(light("sun", LightKind::Directional, 3.0, sun));
    let yaw = |a: f32| Vec4::from(Quat::from_rotation_y(a));
    s.animations.push(Animation {
        name: "slide".into(),
        channels: vec![
            Channel {
                node: s.instances[cube as usize].node,
                property: Property::Translation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, SLIDE_END, HOLD],
                values: vec![
                    Vec4::new(-CUBE_TRAVEL, 0.0, -2.0, 0.0),
                    Vec4::new(CUBE_TRAVEL, 0.0, -2.0, 0.0),
                    Vec4::new(CUBE_TRAVEL, 0.0, -2.0, 0.0),
                ],
            },
            Channel {
                node: front + PAN as u32,
                property: Property::Rotation,
                interpolation: Interpolation::Linear,
                times: vec![PAN_START, PAN_END, HOLD],
                values: vec![yaw(PAN_YAW), yaw(-PAN_YAW), yaw(-PAN_YAW)],
            },
        ],
    });
    s
}

/// `slide` with the cube moved by a morph target instead of its node: the node stays at the
/// start and the target shifts every vertex by the whole travel, its weight going from 0 to 1
/// over the same time. The pixels see the same cube in the same places; only how it moves
/// differs (its vertices within the mesh, which the G-buffer's motion vectors must carry).
pub fn slide_morph() -> Scene {
    use slide_facts::*;
    let mut s = slide();
    s.name = "builtin:stability-slide-morph".into();
    let (node, mesh) = (s.instances[CUBE_INSTANCE as usize].node, s.instances[CUBE_INSTANCE as usize].mesh);
    s.animations[0].channels.retain(|c| c.node != node);
    let count = s.meshes[mesh as usize].vertices.len();
    s.morphs.push(super::Morph {
        mesh,
        targets: vec![super::MorphTarget { positions: vec![Vec3::X * 2.0 * CUBE_TRAVEL; count], normals: Vec::new() }],
        weights: vec![0.0],
        channels: vec![super::WeightChannel {
            interpolation: Interpolation::Linear,
            times: vec![0.0, SLIDE_END, HOLD],
            values: vec![0.0, 1.0, 1.0],
            period: HOLD,
        }],
    });
    s
}

/// Facts about `lights`.
pub mod lights_facts {
    use glam::Vec3;
    /// The point light `mover` jumps from MOVER_FROM to MOVER_TO at MOVE_TIME (seconds).
    pub const MOVER: &str = "mover";
    pub const MOVER_FROM: Vec3 = Vec3::new(-1.8, 2.0, -1.0);
    pub const MOVER_TO: Vec3 = Vec3::new(1.8, 2.0, -1.0);
    pub const MOVE_TIME: f32 = 0.5;
    /// In `lights_sweep`, `mover` glides from MOVER_FROM to MOVER_TO over these seconds
    /// (3.6 m in 60 frames of 1/30 s: 6 cm a frame).
    pub const SWEEP_START: f32 = 0.5;
    pub const SWEEP_END: f32 = 2.5;
    /// The point light the suite switches off (by setting its intensity to 0 between frames).
    pub const SWITCHED: &str = "switched";
    /// `lights_resampled` adds this many point lights behind the back wall, each BEHIND_POWER
    /// times as intense as `mover` and `switched`: the renderer gives the shadows chain to the
    /// brightest lights, so those two are resampled in gi (common/light_reservoir.glsl).
    pub const BEHIND: usize = 4;
    pub const BEHIND_POWER: f32 = 4.0;
    /// In `lights_occluded`, a closed box (half-extent BOX_HALF) jumps at MOVE_TIME from under
    /// the floor to around `mover`, hiding it from the whole room.
    pub const BOX_HALF: f32 = 0.25;
}

/// A white room open toward the camera, lit by two point lights: `mover` jumps from the left
/// to the right half of the room at `MOVE_TIME`, `switched` stays where it is (the suite
/// switches it off). White walls make a large part of the light indirect, the part that
/// temporal accumulation can hold on to.
pub fn lights() -> Scene {
    use lights_facts::*;
    let mut s = Scene { name: "builtin:stability-lights".into(), ..Default::default() };
    s.materials.push(diffuse("white", 0.8));
    room(&mut s, 0);
    let eye = s.nodes.len() as u32;
    s.nodes.push(looking("eye", Vec3::new(0.0, 1.5, 4.5), Vec3::new(0.0, 1.2, 0.0)));
    s.cameras.push(camera("eye", 0.9, eye));
    s.nodes.push(node(MOVER, MOVER_FROM));
    s.lights.push(light(MOVER, LightKind::Point, 12.0, eye + 1));
    s.nodes.push(node(SWITCHED, Vec3::new(0.0, 2.6, -2.0)));
    s.lights.push(light(SWITCHED, LightKind::Point, 12.0, eye + 2));
    s.animations.push(Animation {
        name: "move".into(),
        channels: vec![Channel {
            node: eye + 1,
            property: Property::Translation,
            interpolation: Interpolation::Step,
            times: vec![0.0, MOVE_TIME, HOLD],
            values: vec![MOVER_FROM.extend(0.0), MOVER_TO.extend(0.0), MOVER_TO.extend(0.0)],
        }],
    });
    s
}

/// `lights` with BEHIND brighter point lights behind the back wall (z = -3.5), which light
/// nothing the camera sees: `mover` and `switched` are then among the resampled lights, whose
/// light comes from per-pixel reservoirs kept across frames, and the suite measures how soon
/// those follow a light that moves or goes off.
pub fn lights_resampled() -> Scene {
    use lights_facts::*;
    let mut s = lights();
    s.name = "builtin:stability-lights-resampled".into();
    for k in 0..BEHIND {
        let at = Vec3::new(-2.25 + 1.5 * k as f32, 1.5, -3.5);
        s.nodes.push(node(&format!("behind {k}"), at));
        let node = s.nodes.len() as u32 - 1;
        s.lights.push(light(&format!("behind {k}"), LightKind::Point, 12.0 * BEHIND_POWER, node));
    }
    s
}

/// `lights` (`lights_resampled` where `resampled`) with `mover` staying where it starts and a
/// box that jumps at MOVE_TIME from under the floor to around `mover`, hiding it from every
/// point of the room; `switched` still lights it. Unlike a light switched off, nothing about
/// the lights changes, so nothing that restarts on such a change (the reservoirs, the
/// radiance cache's means, the denoiser's history) restarts: the suite measures how soon the
/// frame lets go of the hidden light, the reservoirs' part where the light is resampled.
pub fn lights_occluded(resampled: bool) -> Scene {
    use lights_facts::*;
    let mut s = if resampled { lights_resampled() } else { lights() };
    s.name =
        if resampled { "builtin:stability-lights-occluded-resampled" } else { "builtin:stability-lights-occluded" }
            .into();
    s.animations.clear();
    let hidden = Vec3::new(MOVER_FROM.x, -2.0 * BOX_HALF, MOVER_FROM.z);
    let around = MOVER_FROM;
    let cage = add(&mut s, "box", cuboid(Vec3::splat(BOX_HALF), 0), hidden);
    s.animations.push(Animation {
        name: "occlude".into(),
        channels: vec![Channel {
            node: s.instances[cage as usize].node,
            property: Property::Translation,
            interpolation: Interpolation::Step,
            times: vec![0.0, MOVE_TIME, HOLD],
            values: vec![hidden.extend(0.0), around.extend(0.0), around.extend(0.0)],
        }],
    });
    s
}

/// `lights` with `mover` gliding instead: from MOVER_FROM at SWEEP_START to MOVER_TO at
/// SWEEP_END (lights_facts), a light that changes every frame.
pub fn lights_sweep() -> Scene {
    use lights_facts::*;
    let mut s = lights();
    s.name = "builtin:stability-lights-sweep".into();
    let channel = &mut s.animations[0].channels[0];
    channel.interpolation = Interpolation::Linear;
    channel.times = vec![0.0, SWEEP_START, SWEEP_END, HOLD];
    channel.values = vec![MOVER_FROM.extend(0.0), MOVER_FROM.extend(0.0), MOVER_TO.extend(0.0), MOVER_TO.extend(0.0)];
    s
}

/// Floor (y = 0), ceiling (y = 3), back (z = -3) and side walls (x = +-3) of a room open
/// toward +Z, facing in, in `material`.
fn room(s: &mut Scene, material: u32) {
    let (x, y, z) = (Vec3::X * 6.0, Vec3::Y * 3.0, Vec3::Z * 6.0);
    add(s, "floor", quad(Vec3::ZERO, z, x, material), Vec3::ZERO);
    add(s, "ceiling", quad(Vec3::new(0.0, 3.0, 0.0), x, z, material), Vec3::ZERO);
    add(s, "back", quad(Vec3::new(0.0, 1.5, -3.0), x, y, material), Vec3::ZERO);
    add(s, "left", quad(Vec3::new(-3.0, 1.5, 0.0), y, z, material), Vec3::ZERO);
    add(s, "right", quad(Vec3::new(3.0, 1.5, 0.0), z, y, material), Vec3::ZERO);
}

/// Facts about `leak`.
pub mod leak_facts {
    use glam::Vec3;
    /// The sealed room is the box [-1, 1] x [0, 2] x [-1, 1]; its six walls are zero-thickness
    /// quads, instances 0..6 in the order -X, +X, floor, ceiling, -Z, +Z.
    pub const HALF: f32 = 1.0;
    pub const PLUS_X_INSTANCE: u32 = 1;
    pub const MINUS_Z_INSTANCE: u32 = 4;
    /// The point light, outside the room, 2 cm from the +X wall.
    pub const LIGHT: Vec3 = Vec3::new(HALF + 0.02, 1.0, 0.0);
    /// Cameras: `inside` the room, looking at the +X wall and the floor along it; `corner`
    /// outside, seeing the lit outer face of the +X wall beside the unlit outer face of the -Z
    /// wall across the room's edge.
    pub const INSIDE: usize = 0;
    pub const CORNER: usize = 1;
}

/// A sealed room with zero-thickness walls and a bright point light just outside one of them.
/// Nothing outside the room reflects light and the environment is black, so inside the room
/// and on the outer faces the light cannot see, the true radiance is exactly 0.
pub fn leak() -> Scene {
    use leak_facts::*;
    let mut s = Scene { name: "builtin:stability-leak".into(), ..Default::default() };
    // Double-sided: each wall is seen from inside by one camera and from outside by the other.
    s.materials.push(Material { double_sided: true, ..diffuse("wall", 0.8) });
    let h = HALF;
    let c = Vec3::new(0.0, h, 0.0);
    let (x, y, z) = (Vec3::X * 2.0 * h, Vec3::Y * 2.0 * h, Vec3::Z * 2.0 * h);
    // Quads facing out of the room.
    add(&mut s, "-x", quad(c - Vec3::X * h, z, y, 0), Vec3::ZERO);
    add(&mut s, "+x", quad(c + Vec3::X * h, y, z, 0), Vec3::ZERO);
    add(&mut s, "floor", quad(c - Vec3::Y * h, x, z, 0), Vec3::ZERO);
    add(&mut s, "ceiling", quad(c + Vec3::Y * h, z, x, 0), Vec3::ZERO);
    add(&mut s, "-z", quad(c - Vec3::Z * h, y, x, 0), Vec3::ZERO);
    add(&mut s, "+z", quad(c + Vec3::Z * h, x, y, 0), Vec3::ZERO);
    let cams = s.nodes.len() as u32;
    s.nodes.push(looking("inside", Vec3::new(-0.8, 1.4, 0.8), Vec3::new(1.0, 0.5, -0.3)));
    s.nodes.push(looking("corner", Vec3::new(3.0, 1.3, -3.0), Vec3::new(1.0, 1.0, -1.0)));
    s.cameras.push(camera("inside", 1.2, cams));
    s.cameras.push(camera("corner", 0.8, cams + 1));
    s.nodes.push(node("lamp", LIGHT));
    s.lights.push(light("lamp", LightKind::Point, 4.0, cams + 2));
    s
}

/// Facts about `cache_leak`.
pub mod cache_leak_facts {
    use glam::Vec3;
    /// The floor runs under the dividing wall at x = WALL_X, which is off the radiance cache's
    /// cell grid (multiples of the cell size from the origin), so floor cells straddle it.
    pub const WALL_X: f32 = 0.05;
    /// Instances: the lit room's floor, the dark room's floor, then the walls.
    pub const LIT_FLOOR_INSTANCE: u32 = 0;
    pub const DARK_FLOOR_INSTANCE: u32 = 1;
    /// The point light in the lit room (x < WALL_X), below the outer walls' tops (y = 1).
    pub const LIGHT: Vec3 = Vec3::new(-1.0, 0.4, 0.0);
}

/// Two rooms without a ceiling, [-2, 2] x [0, 1] x [-1, 1], on one floor, split by a
/// zero-thickness wall 1.5 high at x = WALL_X (higher than the outer walls, so no straight
/// path joins a surface of one room to a surface of the other); a point light in the -X room,
/// a camera above both. The environment is black and nothing outside reflects: the true
/// radiance of the +X room is exactly 0, while floor cells of the radiance cache (cells of
/// about 0.12 here) straddle the wall.
pub fn cache_leak() -> Scene {
    use cache_leak_facts::*;
    let mut s = Scene { name: "builtin:stability-cache-leak".into(), ..Default::default() };
    s.materials.push(Material { double_sided: true, ..diffuse("wall", 0.8) });
    let (y, z2) = (Vec3::Y, Vec3::Z * 2.0);
    let lit_width = WALL_X + 2.0;
    let dark_width = 2.0 - WALL_X;
    add(
        &mut s,
        "lit floor",
        quad(Vec3::new(WALL_X - lit_width / 2.0, 0.0, 0.0), z2, Vec3::X * lit_width, 0),
        Vec3::ZERO,
    );
    add(
        &mut s,
        "dark floor",
        quad(Vec3::new(WALL_X + dark_width / 2.0, 0.0, 0.0), z2, Vec3::X * dark_width, 0),
        Vec3::ZERO,
    );
    add(&mut s, "-x wall", quad(Vec3::new(-2.0, 0.5, 0.0), z2, y, 0), Vec3::ZERO);
    add(&mut s, "+x wall", quad(Vec3::new(2.0, 0.5, 0.0), y, z2, 0), Vec3::ZERO);
    add(&mut s, "-z wall", quad(Vec3::new(0.0, 0.5, -1.0), Vec3::X * 4.0, y, 0), Vec3::ZERO);
    add(&mut s, "+z wall", quad(Vec3::new(0.0, 0.5, 1.0), y, Vec3::X * 4.0, 0), Vec3::ZERO);
    add(&mut s, "divider", quad(Vec3::new(WALL_X, 0.75, 0.0), z2, y * 1.5, 0), Vec3::ZERO);
    let cam = s.nodes.len() as u32;
    s.nodes.push(looking("above", Vec3::new(WALL_X, 4.5, 0.6), Vec3::new(WALL_X, 0.0, 0.0)));
    s.cameras.push(camera("above", 0.9, cam));
    s.nodes.push(node("lamp", LIGHT));
    s.lights.push(light("lamp", LightKind::Point, 4.0, cam + 1));
    s
}

/// Facts about `grazing`.
pub mod grazing_facts {
    use glam::Vec3;
    pub const FLOOR_INSTANCE: u32 = 0;
    pub const SPHERE_INSTANCE: u32 = 1;
    /// The low-poly sphere (12 segments, 6 rings) of radius SPHERE_RADIUS rests on the floor.
    pub const SPHERE_CENTRE: Vec3 = Vec3::new(0.0, 0.5, -1.0);
    pub const SPHERE_RADIUS: f32 = 0.5;
    /// Direction the sunlight travels: 5 degrees above the horizon.
    pub fn light_dir() -> Vec3 {
        let e = 5f32.to_radians();
        Vec3::new(-e.cos() * 0.8, -e.sin(), -e.cos() * 0.6).normalize()
    }
}

/// A large floor under a sun 5 degrees above the horizon, with nothing on it but a coarse
/// smooth-shaded sphere: every floor point outside the sphere's shadow is lit (speckle there is
/// shadow acne), and the sphere's lit side ends at a terminator that the faceted geometry makes
/// hard to shade.
pub fn grazing() -> Scene {
    use grazing_facts::*;
    let mut s = Scene { name: "builtin:stability-grazing".into(), ..Default::default() };
    s.materials.push(diffuse("white", 0.8));
    add(&mut s, "floor", quad(Vec3::ZERO, Vec3::Z * 40.0, Vec3::X * 40.0, 0), Vec3::ZERO);
    add(&mut s, "sphere", uv_sphere(SPHERE_RADIUS, 12, 6, 0), SPHERE_CENTRE);
    let eye = s.nodes.len() as u32;
    s.nodes.push(looking("eye", Vec3::new(0.3, 1.2, 2.0), Vec3::new(0.0, 0.2, -1.5)));
    s.cameras.push(camera("eye", 1.0, eye));
    s.nodes.push(looking("sun", Vec3::ZERO, light_dir()));
    s.lights.push(light("sun", LightKind::Directional, 3.0, eye + 1));
    s
}

/// Facts about `firefly`.
pub mod firefly_facts {
    /// The emitter: a 3 cm square of radiance EMISSION 5 cm under the ceiling, facing it, out of
    /// the camera's view. It is the only light: the room sees only the small, very bright spot
    /// it makes on the ceiling (also out of view), through one bounce.
    pub const EMISSION: f32 = 20000.0;
    pub const SIDE: f32 = 0.03;
}

/// The white room of `lights` with a glossy floor, lit only by a tiny emitter of very high
/// radiance facing the ceiling: light sampling finds the emitter, but the hot spot it makes is
/// found only by bounce rays that happen to hit it, each a firefly.
pub fn firefly() -> Scene {
    use firefly_facts::*;
    let mut s = Scene { name: "builtin:stability-firefly".into(), ..Default::default() };
    s.materials.push(diffuse("white", 0.8));
    s.materials.push(Material { roughness_factor: 0.3, ..diffuse("glossy", 0.5) });
    s.materials.push(Material { emissive_factor: Vec3::splat(EMISSION), ..diffuse("emitter", 0.0) });
    room(&mut s, 0);
    s.meshes[0].material = 1;
    add(&mut s, "emitter", quad(Vec3::new(0.0, 2.95, 2.5), Vec3::Z * SIDE, Vec3::X * SIDE, 2), Vec3::ZERO);
    let eye = s.nodes.len() as u32;
    s.nodes.push(looking("eye", Vec3::new(0.0, 1.2, 4.0), Vec3::new(0.0, 0.8, -1.0)));
    s.cameras.push(camera("eye", 0.8, eye));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_with_its_cameras_and_is_small() {
        for name in NAMES {
            let s = by_name(name).unwrap();
            assert!(!s.cameras.is_empty(), "{name}: no camera");
            let triangles: usize = s.meshes.iter().map(|m| m.triangle_count()).sum();
            assert!(triangles < 5000, "{name}: {triangles} triangles");
            assert!(s.lights.iter().all(|l| (l.node as usize) < s.nodes.len()), "{name}: light without node");
        }
        assert!(by_name("no-such-scene").is_none());
    }

    #[test]
    fn the_cube_leaves_the_front_view_and_the_pan_turns() {
        use slide_facts::*;
        let s = slide();
        let cube = &s.instances[CUBE_INSTANCE as usize];
        assert_eq!(s.meshes[cube.mesh as usize].name, "cuboid");
        let cube = cube.node as usize;
        let at = |t: f32| s.evaluate(t).world[cube].w_axis.x;
        assert_eq!(at(0.0), -CUBE_TRAVEL);
        assert_eq!(at(SLIDE_END + 1.0), CUBE_TRAVEL);
        let pan = s.cameras[PAN].node as usize;
        let forward = |t: f32| s.evaluate(t).world[pan].transform_vector3(Vec3::NEG_Z);
        assert!(forward(PAN_START).x < -0.4 && forward(PAN_END).x > 0.4);
    }

    /// The room's walls face out of it (the light outside sees the +X wall's front).
    #[test]
    fn leak_room_walls_face_out() {
        let s = leak();
        for inst in &s.instances {
            let m = &s.meshes[inst.mesh as usize];
            let v = m.vertices[0];
            let (p, n) = (Vec3::from(v.position), Vec3::from(v.normal));
            assert!((p - Vec3::new(0.0, 1.0, 0.0)).dot(n) > 0.99, "{}: normal {n} at {p}", m.name);
        }
    }
}

/// Facts about `mirror`.
pub mod mirror_facts {
    /// The mirror floor's instance (after the wall's).
    pub const FLOOR_INSTANCE: u32 = 1;
    /// The `truck` camera moves from x = -TRUCK to +TRUCK between TRUCK_START and TRUCK_END
    /// (0.056 a frame at 30 frames a second), always looking the same way.
    pub const TRUCK: f32 = 0.5;
    pub const TRUCK_START: f32 = 1.0;
    pub const TRUCK_END: f32 = 1.6;
}

/// A near-mirror floor (metal, roughness 0.05) reflecting a sunlit checkerboard wall; the
/// `truck` camera looks down at the floor and moves sideways, so the reflection (about 6 away,
/// behind the mirror) and the floor (about 2.5 away) move across the screen at different speeds.
pub fn mirror() -> Scene {
    use mirror_facts::*;
    let mut s = Scene { name: "builtin:stability-mirror".into(), ..Default::default() };
    let wall = checker_wall(&mut s, glam::Vec2::new(2.0, 0.75));
    s.materials.push(wall);
    s.materials.push(Material {
        name: "mirror".into(),
        base_color_factor: Vec4::new(0.9, 0.9, 0.9, 1.0),
        metallic_factor: 1.0,
        roughness_factor: 0.05,
        ..Default::default()
    });
    add(&mut s, "wall", quad(Vec3::new(0.0, 2.0, -4.0), Vec3::X * 16.0, Vec3::Y * 6.0, 0), Vec3::ZERO);
    add(&mut s, "floor", quad(Vec3::new(0.0, -1.0, 0.0), Vec3::Z * 12.0, Vec3::X * 16.0, 1), Vec3::ZERO);
    sunlit_truck(&mut s, Vec3::new(-TRUCK, 0.5, 2.0), Vec3::new(0.0, -1.2, -2.5));
    s
}

/// The sun of the truck scenes and their `truck` camera, which starts at `from` looking along
/// `towards` and moves to x = +TRUCK between TRUCK_START and TRUCK_END (mirror_facts).
fn sunlit_truck(s: &mut Scene, from: Vec3, towards: Vec3) {
    use mirror_facts::*;
    let truck = s.nodes.len() as u32;
    s.nodes.push(looking("truck", from, from + towards));
    s.cameras.push(camera("truck", 0.9, truck));
    let sun = s.nodes.len() as u32;
    s.nodes.push(looking("sun", Vec3::ZERO, Vec3::new(0.2, -0.4, -1.0)));
    s.lights.push(light("sun", LightKind::Directional, 3.0, sun));
    let to = Vec3::new(TRUCK, from.y, from.z);
    s.animations.push(Animation {
        name: "truck".into(),
        channels: vec![Channel {
            node: truck,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, TRUCK_START, TRUCK_END, HOLD],
            values: vec![from.extend(0.0), from.extend(0.0), to.extend(0.0), to.extend(0.0)],
        }],
    });
}

/// Names and numbers of `stability-glass`, `stability-blend`, `stability-slab`,
/// `stability-rough-glass`, `stability-glass-reflect` and `stability-lens` the scenarios use.
pub mod glass_facts {
    /// The pane's instance (after the wall's).
    pub const PANE_INSTANCE: u32 = 1;
    /// The `truck` camera moves as `stability-mirror`'s does.
    pub use super::mirror_facts::{TRUCK, TRUCK_END, TRUCK_START};
}

/// A thin-walled glass pane (KHR_materials_transmission, roughness 0) 2 in front of the `truck`
/// camera, and behind it, 6.5 away, a sunlit checkerboard wall: as the camera moves sideways,
/// what the pane shows (the wall, seen through it) crosses the screen at the wall's speed, not
/// the pane's.
pub fn glass() -> Scene {
    let pane = clear_glass("glass", 0.0, 1.5, 0.0);
    pane_before_wall("builtin:stability-glass", pane, thin_pane())
}

/// As `stability-glass`, the pane rough (0.3): what it lets through is a blurred, noisy image
/// of the wall, which the denoiser must average without smearing it as the camera moves.
pub fn rough_glass() -> Scene {
    let pane = clear_glass("frosted", 0.3, 1.5, 0.0);
    pane_before_wall("builtin:stability-rough-glass", pane, thin_pane())
}

/// As `stability-glass`, the pane (IOR 2, 3 x 1.5) turned 60 degrees about the vertical, so
/// that it reflects a side wall which a second sun lights four times as brightly: a third to
/// a half of what its pixels show is that reflection, the rest the wall behind. The two move
/// differently as the camera moves: one history cannot follow both.
pub fn glass_reflect() -> Scene {
    let pane = clear_glass("glass", 0.0, 2.0, 0.0);
    let turned = Vec3::new(0.5, 0.0, -0.75f32.sqrt()) * 3.0;
    let mut s = pane_before_wall("builtin:stability-glass-reflect", pane, quad(Vec3::ZERO, turned, Vec3::Y * 1.5, 1));
    add(&mut s, "side wall", quad(Vec3::new(3.0, 2.0, -1.0), Vec3::Z * 10.0, Vec3::Y * 6.0, 0), Vec3::ZERO);
    let side_sun = s.nodes.len() as u32;
    s.nodes.push(looking("side sun", Vec3::ZERO, Vec3::new(1.0, -0.3, -0.2)));
    s.lights.push(light("side sun", LightKind::Directional, 12.0, side_sun));
    s
}

/// As `stability-glass`, with a ball of glass (radius 0.6, IOR 1.5, a volume) in the pane's
/// place: a lens, which shows the wall behind it turned upside down and moving against the
/// camera's motion, where no distance along the view ray says where it was last frame.
pub fn lens() -> Scene {
    let ball = clear_glass("lens", 0.0, 1.5, 1.2);
    pane_before_wall("builtin:stability-lens", ball, uv_sphere(0.6, 48, 24, 1))
}

/// As `stability-glass`, with a rough blended pane (alpha 0.3) in the glass's place: 70% of
/// what it shows lies behind it.
pub fn blend() -> Scene {
    let pane = Material {
        name: "veil".into(),
        base_color_factor: Vec4::new(0.9, 0.9, 0.9, 0.3),
        metallic_factor: 0.0,
        roughness_factor: 0.6,
        alpha_mode: AlphaMode::Blend,
        ..Default::default()
    };
    pane_before_wall("builtin:stability-blend", pane, thin_pane())
}

/// As `stability-glass`, with a slab of glass 0.2 thick (a volume, IOR 1.5) in the pane's
/// place: the wall seen through it is refracted twice, shifted sideways but not turned.
pub fn slab() -> Scene {
    let pane = clear_glass("slab", 0.0, 1.5, 0.2);
    pane_before_wall("builtin:stability-slab", pane, cuboid(Vec3::new(1.0, 0.75, 0.1), 1))
}

/// The glass scenes' material: clear (transmission 1, white), `roughness`, `ior`, `thickness`
/// (0: thin-walled, else a volume).
fn clear_glass(name: &str, roughness: f32, ior: f32, thickness: f32) -> Material {
    Material {
        name: name.into(),
        base_color_factor: Vec4::ONE,
        metallic_factor: 0.0,
        roughness_factor: roughness,
        transmission: 1.0,
        ior,
        thickness,
        ..Default::default()
    }
}

/// The glass and blend scenes' pane: 2 x 1.5, facing the camera.
fn thin_pane() -> super::Mesh {
    quad(Vec3::ZERO, Vec3::X * 2.0, Vec3::Y * 1.5, 1)
}

/// The glass, blend and slab scenes: a checkerboard wall, the `pane` (`mesh` of `material`)
/// in front of it, the truck camera.
fn pane_before_wall(name: &str, material: Material, mesh: super::Mesh) -> Scene {
    use glass_facts::*;
    let mut s = Scene { name: name.into(), ..Default::default() };
    let wall = checker_wall(&mut s, glam::Vec2::new(2.0, 0.75));
    s.materials.push(wall);
    s.materials.push(material);
    add(&mut s, "wall", quad(Vec3::new(0.0, 2.0, -4.0), Vec3::X * 16.0, Vec3::Y * 6.0, 0), Vec3::ZERO);
    add(&mut s, "pane", mesh, Vec3::new(0.0, 0.5, 0.5));
    sunlit_truck(&mut s, Vec3::new(-TRUCK, 0.5, 2.5), Vec3::NEG_Z);
    s
}
