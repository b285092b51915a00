//! `builtin:many-lights`: hundreds of punctual lights, most of them behind a wall. Two sealed
//! rooms side by side share a thick wall; the camera is in the visible room, lit by its own
//! short-range lights, and every light of the hidden room can reach the visible one only through
//! that wall. It checks that the many-light path shadows every light (no leak) and that its
//! image keeps the reference's energy (tests/many_lights.rs), and it is the scene for timing
//! the frame against the light count.

use super::builtin::{cuboid, node, quad};
use super::{Camera, Instance, Light, LightKind, Material, Scene};
use glam::{Mat4, Quat, Vec3};

/// Facts about `many_lights` that tests check against.
pub mod facts {
    use glam::Vec3;
    /// The whole block is [-4, 4] x [0, 3] x [-3, 3]; the wall x in [-WALL, WALL] splits it
    /// into the visible room (x < 0, the camera's) and the hidden room (x > 0).
    pub const HALF_X: f32 = 4.0;
    pub const HEIGHT: f32 = 3.0;
    pub const HALF_Z: f32 = 3.0;
    pub const WALL: f32 = 0.05;
    /// The visible room's floor strip x in [STRIP_X, -WALL] next to the wall: no visible-room
    /// light reaches it (their range ends short of it), so light arrives there directly only
    /// from the hidden room's lights, if they leak, and otherwise only as indirect light.
    pub const STRIP_X: f32 = -1.2;
    pub const STRIP_INSTANCE: u32 = 1;
    /// Visible-room lights: VISIBLE_LIGHTS point lights at x <= VISIBLE_MAX_X, heights
    /// VISIBLE_Y.., with range VISIBLE_RANGE.
    pub const VISIBLE_LIGHTS: usize = 48;
    pub const VISIBLE_MAX_X: f32 = -2.4;
    pub const VISIBLE_RANGE: f32 = 1.25;
    /// Hidden-room lights: a 16 x 16 grid, named `hidden.N`.
    pub const HIDDEN_LIGHTS: usize = 256;
    pub const HIDDEN_PREFIX: &str = "hidden.";
    /// Where the strip's centre is.
    pub const STRIP_CENTRE: Vec3 = Vec3::new(0.5 * (STRIP_X - WALL), 0.0, 0.0);
    /// `many_panels`: square emissive panels (two triangles each) of this side just under the
    /// ceiling, facing down; VISIBLE_PANELS in the camera's room at x <= VISIBLE_MAX_X, and a
    /// HIDDEN_PANELS_SIDE^2 grid in the hidden room (their nodes named `hidden.N`).
    pub const PANEL_SIDE: f32 = 0.4;
    pub const PANEL_EMISSION: f32 = 8.0;
    pub const VISIBLE_PANELS: usize = 8;
    pub const HIDDEN_PANELS_SIDE: usize = 8;
}

/// Deterministic value in [0, 1) for light `i` and stream `k` (splitmix64).
fn hash01(i: usize, k: u64) -> f32 {
    let mut z = (i as u64).wrapping_add(k.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

fn diffuse(name: &str, albedo: Vec3, roughness: f32) -> Material {
    Material {
        name: name.into(),
        base_color_factor: albedo.extend(1.0),
        metallic_factor: 0.0,
        roughness_factor: roughness,
        ..Default::default()
    }
}

fn add(s: &mut Scene, name: &str, mesh: super::Mesh, at: Vec3) {
    s.meshes.push(mesh);
    s.nodes.push(node(name, at));
    s.instances.push(Instance { mesh: s.meshes.len() as u32 - 1, node: s.nodes.len() as u32 - 1 });
}

fn point(s: &mut Scene, name: String, at: Vec3, color: Vec3, intensity: f32, range: Option<f32>, radius: f32) {
    s.nodes.push(node(&name, at));
    let node = s.nodes.len() as u32 - 1;
    s.lights.push(Light { name, kind: LightKind::Point, color, intensity, range, radius, node });
}

/// The two rooms and their 304 lights (see [`facts`]).
pub fn many_lights() -> Scene {
    use facts::*;
    let mut s = Scene { name: "builtin:many-lights".into(), ..Default::default() };
    s.materials.push(diffuse("white", Vec3::splat(0.7), 1.0));
    s.materials.push(diffuse("floor", Vec3::new(0.6, 0.55, 0.5), 1.0));
    // A glossy dielectric side wall: the resampled lights' specular lobe shows on it.
    s.materials.push(diffuse("satin", Vec3::new(0.3, 0.4, 0.6), 0.35));
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let (hx, h, hz) = (HALF_X, HEIGHT, HALF_Z);
    // Inward-facing shell. The visible room's floor is two quads: the far part and the strip.
    let far = 0.5 * (-hx + STRIP_X);
    add(&mut s, "floor_far", quad(Vec3::new(far, 0.0, 0.0), z * 2.0 * hz, x * (STRIP_X + hx), 1), Vec3::ZERO);
    add(&mut s, "floor_strip", quad(STRIP_CENTRE, z * 2.0 * hz, x * (-WALL - STRIP_X), 1), Vec3::ZERO);
    add(&mut s, "floor_hidden", quad(Vec3::new(0.5 * hx, 0.0, 0.0), z * 2.0 * hz, x * hx, 1), Vec3::ZERO);
    add(&mut s, "ceiling", quad(Vec3::new(0.0, h, 0.0), x * 2.0 * hx, z * 2.0 * hz, 0), Vec3::ZERO);
    add(&mut s, "-x", quad(Vec3::new(-hx, 0.5 * h, 0.0), y * h, z * 2.0 * hz, 0), Vec3::ZERO);
    add(&mut s, "+x", quad(Vec3::new(hx, 0.5 * h, 0.0), z * 2.0 * hz, y * h, 0), Vec3::ZERO);
    add(&mut s, "-z", quad(Vec3::new(0.0, 0.5 * h, -hz), x * 2.0 * hx, y * h, 2), Vec3::ZERO);
    add(&mut s, "+z", quad(Vec3::new(0.0, 0.5 * h, hz), y * h, x * 2.0 * hx, 0), Vec3::ZERO);
    // The wall is a solid box that pokes through floor, ceiling and side walls, so no ray can
    // pass along a seam.
    add(&mut s, "wall", cuboid(Vec3::new(WALL, 0.5 * h + 0.1, hz + 0.1), 0), Vec3::new(0.0, 0.5 * h, 0.0));

    let eye = Vec3::new(-3.9, 2.2, 0.0);
    let mut cam = node("camera", eye);
    cam.rotation = look(eye, Vec3::new(0.0, 0.6, 0.0));
    s.nodes.push(cam);
    s.cameras.push(Camera {
        name: "visible".into(),
        yfov: 1.3,
        aspect_ratio: None,
        znear: 0.05,
        zfar: Some(100.0),
        node: s.nodes.len() as u32 - 1,
    });

    // Visible room: 4 x 12 short-range lights, warm and cool, near the camera's end, at least
    // 0.6 from every wall (a light close to a wall makes a hot spot there that a one-sample GI
    // bounce finds rarely: a test of the denoiser's firefly clamp, not of the light sampling).
    for i in 0..VISIBLE_LIGHTS {
        let (ix, iz) = (i % 4, i / 4);
        let at = Vec3::new(VISIBLE_MAX_X - 0.3 * (3 - ix) as f32, 0.9 + 0.2 * (i % 3) as f32, -2.4 + 0.44 * iz as f32);
        let color = if i % 2 == 0 { Vec3::new(1.0, 0.8, 0.6) } else { Vec3::new(0.6, 0.8, 1.0) };
        point(&mut s, format!("visible.{i}"), at, color, 2.0 + 2.0 * hash01(i, 1), Some(VISIBLE_RANGE), 0.0);
    }
    // Hidden room: 16 x 16 lights at random heights and strengths, no range. The two strongest
    // (so among the per-light-shadowed ones) and every 16th are sphere lights.
    let n = (HIDDEN_LIGHTS as f32).sqrt() as usize;
    for i in 0..HIDDEN_LIGHTS {
        let (ix, iz) = (i % n, i / n);
        let at = Vec3::new(
            WALL + 0.25 + (hx - WALL - 0.5) * ix as f32 / (n - 1) as f32,
            0.3 + 2.4 * hash01(i, 2),
            -hz + 0.3 + (2.0 * hz - 0.6) * iz as f32 / (n - 1) as f32,
        );
        let strong = i == 37 || i == 150;
        let intensity = if strong { 20.0 } else { 0.5 + 3.0 * hash01(i, 3) };
        let radius = if strong || i % 16 == 5 { 0.1 } else { 0.0 };
        let color = Vec3::new(0.6 + 0.4 * hash01(i, 4), 0.6 + 0.4 * hash01(i, 5), 0.6 + 0.4 * hash01(i, 6));
        point(&mut s, format!("{HIDDEN_PREFIX}{i}"), at, color, intensity, None, radius);
    }
    s
}

/// `builtin:many-panels`: the same two rooms lit by emissive panels instead of punctual lights
/// (see [`facts`]): 144 emissive triangles, 128 of them behind the wall, for the emitters'
/// resampling what `many_lights` is for the punctual lights'.
pub fn many_panels() -> Scene {
    use facts::*;
    let mut s = many_lights();
    s.name = "builtin:many-panels".into();
    // (The lights' nodes stay, unused.)
    s.lights.clear();
    let panel = s.materials.len() as u32;
    s.materials.push(Material {
        name: "panel".into(),
        metallic_factor: 0.0,
        emissive_factor: Vec3::splat(PANEL_EMISSION),
        ..Default::default()
    });
    let (y, side) = (HEIGHT - 0.02, PANEL_SIDE);
    // Facing down: X x Z = -Y.
    let add_panel = |s: &mut Scene, name: String, x: f32, z: f32| {
        add(s, &name, quad(Vec3::new(x, y, z), Vec3::X * side, Vec3::Z * side, panel), Vec3::ZERO);
    };
    for i in 0..VISIBLE_PANELS {
        let (ix, iz) = (i % 2, i / 2);
        add_panel(&mut s, format!("visible.{i}"), VISIBLE_MAX_X - 0.8 * ix as f32, -2.1 + 1.4 * iz as f32);
    }
    let n = HIDDEN_PANELS_SIDE;
    for i in 0..n * n {
        let (ix, iz) = (i % n, i / n);
        let x = WALL + 0.4 + (HALF_X - WALL - 0.8) * ix as f32 / (n - 1) as f32;
        let z = -HALF_Z + 0.4 + (2.0 * HALF_Z - 0.8) * iz as f32 / (n - 1) as f32;
        add_panel(&mut s, format!("{HIDDEN_PREFIX}{i}"), x, z);
    }
    s
}

fn look(eye: Vec3, target: Vec3) -> Quat {
    Quat::from_mat4(&Mat4::look_at_rh(eye, target, Vec3::Y).inverse())
}
