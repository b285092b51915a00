//! The default light: which environment lights a scene when nothing was asked for
//! (`Environment::DefaultLight`), and why. A scene that brings no light of its own gets the
//! daylight sky of sky.rs; any other keeps a black environment. Decided once per scene, said by
//! `hybrid-rt plan` and the log; `--env` and `--sky` replace it, `--no-default-light` turns it
//! off.
//!
//! The rule: a scene brings its own light when it has a punctual light (KHR_lights_punctual),
//! or when its emitters are significant: the power they emit, sum of pi L A over emitting sides,
//! is at least `SIGNIFICANT_EMISSION` (10%) of what the default light sends onto the scene's
//! surfaces, pi per unit area (its horizontal irradiance) times their total area. Equivalently,
//! their mean emitted radiance over all surfaces is at least 0.1. The emitted radiance of a
//! triangle is its material's emissive factor times its emissive texture at the triangle's
//! centroid, so an emissive texture that is black almost everywhere (a helmet's indicator
//! lights) counts for the little it emits.
//!
//! A camera in a closed room gets no default light either, whatever its emitters: when no
//! random walk from the camera leaves the scene (sky_reach.rs), a sky would light nothing the
//! camera sees and only draw light samples away from the emitters that do. The camera is the
//! one the frame starts with, at time 0; a viewer that flies out of the room keeps the choice.

use super::{sky, sky_reach};
use crate::scene::{Scene, TextureRef};
use crate::world::environment::{Environment, EnvironmentData, luminance};
use anyhow::Result;
use glam::{Vec2, Vec3};

/// Mean emitted radiance over the scene's surfaces at and above which emitters light the scene.
pub const SIGNIFICANT_EMISSION: f32 = 0.1;

/// How a scene is lit from outside, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Lighting {
    /// The default light (the daylight sky) is used.
    pub default_light: bool,
    /// One line saying which environment and why.
    pub note: String,
}

/// Which environment `env` gives `scene` seen from `camera` (its position at time 0).
pub fn choose(env: &Environment, scene: &Scene, camera: Vec3) -> Lighting {
    let own = own_light(scene).or_else(|why| match env {
        Environment::DefaultLight => enclosed(scene, camera, why),
        _ => Err(why),
    });
    let note = match (env, &own) {
        (Environment::DefaultLight, Err(why)) => {
            format!("default light: a daylight sky with a sun, because {why} (--no-default-light turns it off)")
        }
        (Environment::DefaultLight, Ok(why)) => format!("no default light: {why}; the environment is black"),
        (Environment::Constant(c), Err(why)) if *c == Vec3::ZERO => {
            format!("black environment: the default light is off, although {why}")
        }
        (Environment::Constant(c), _) => format!("constant environment {},{},{} (--sky)", c.x, c.y, c.z),
        (Environment::Map(path, k), _) => format!("environment map {} x {k} (--env)", path.display()),
    };
    Lighting { default_light: *env == Environment::DefaultLight && own.is_err(), note }
}

/// The environment `env` gives `scene` seen from `camera`, ready for upload, and why.
pub fn environment_data(env: &Environment, scene: &Scene, camera: Vec3) -> Result<(EnvironmentData, Lighting)> {
    let lighting = choose(env, scene, camera);
    let data = if lighting.default_light { sky::daylight() } else { EnvironmentData::load(env)? };
    Ok((data, lighting))
}

/// Ok(what lights the scene) when it brings its own light, Err(why not) otherwise.
fn own_light(scene: &Scene) -> Result<String, String> {
    if !scene.lights.is_empty() {
        return Ok(format!("the scene has {} punctual light(s)", scene.lights.len()));
    }
    let emission = mean_emission(scene);
    if emission == 0.0 {
        return Err("the scene has no punctual lights and no emitters".into());
    }
    let what = format!("mean emitted radiance over its surfaces {emission:.3}");
    if emission >= SIGNIFICANT_EMISSION {
        Ok(format!("its emitters light it ({what}, at least {SIGNIFICANT_EMISSION})"))
    } else {
        Err(format!(
            "the scene has no punctual lights and its emitters are too weak to light it ({what}, under {SIGNIFICANT_EMISSION})"
        ))
    }
}

/// For a scene without its own light (`why`): Ok(why no default light) when no light from
/// outside reaches `camera`, Err(why) otherwise.
fn enclosed(scene: &Scene, camera: Vec3, why: String) -> Result<String, String> {
    match sky_reach::from_camera(scene, &scene.evaluate(0.0), camera) {
        sky_reach::Reach::Walks { escaped: 0, paths } => Ok(format!(
            "{why}, but the camera is in a closed room (none of {paths} random walks of up to {} bounces from it leaves the scene)",
            sky_reach::BOUNCES
        )),
        sky_reach::Reach::Walks { escaped, paths } => Err(format!(
            "{why}, and light from outside reaches the camera ({escaped} of {paths} random walks from it leave the scene)"
        )),
        sky_reach::Reach::Outside => Err(why),
    }
}

/// Emitted power over the total surface area, both in world space at time 0: the luminance of
/// the emitted radiance averaged over every surface (emitting sides counted, see the header).
pub fn mean_emission(scene: &Scene) -> f32 {
    let pose = scene.evaluate(0.0);
    let (mut emitted, mut area) = (0.0f64, 0.0f64);
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh as usize];
        let world = pose.world[inst.node as usize];
        let material = scene.materials.get(mesh.material as usize);
        let emissive = material.filter(|m| m.is_emissive());
        let sides = if material.is_some_and(|m| m.double_sided) { 2.0 } else { 1.0 };
        for tri in mesh.indices.chunks_exact(3) {
            let v = |k: usize| &mesh.vertices[tri[k] as usize];
            let p = |k: usize| world.transform_point3(Vec3::from(v(k).position));
            let a = 0.5 * (p(1) - p(0)).cross(p(2) - p(0)).length() as f64;
            area += a;
            if let Some(m) = emissive {
                let texel = m.emissive_texture.map_or(Vec3::ONE, |t| {
                    let uv = |k: usize| Vec2::from(if t.uv_set == 1 { v(k).uv1 } else { v(k).uv0 });
                    emissive_texel(scene, t, (uv(0) + uv(1) + uv(2)) / 3.0)
                });
                emitted += luminance(m.emissive_factor * texel) as f64 * a * sides;
            }
        }
    }
    if area > 0.0 { (emitted / area) as f32 } else { 0.0 }
}

/// The linear colour of an emissive texture (sRGB-encoded) at `uv`, nearest texel, repeating;
/// white when the texture has no image.
fn emissive_texel(scene: &Scene, t: TextureRef, uv: Vec2) -> Vec3 {
    let image = scene.textures.get(t.texture as usize).and_then(|t| t.image).and_then(|i| scene.images.get(i as usize));
    let Some(img) = image.filter(|i| i.width > 0 && i.height > 0) else { return Vec3::ONE };
    let uv = (t.transform * uv.extend(1.0)).truncate();
    let at = |c: f32, n: u32| ((c - c.floor()) * n as f32).min(n as f32 - 1.0).max(0.0) as usize;
    let (x, y) = (at(uv.x, img.width), at(uv.y, img.height));
    let i = (y * img.width as usize + x) * 4;
    let decode = |b: u8| {
        let c = b as f32 / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    match img.rgba8.get(i..i + 3) {
        Some(p) => Vec3::new(decode(p[0]), decode(p[1]), decode(p[2])),
        None => Vec3::ONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Image, Instance, Material, Texture, builtin};
    use glam::Mat3;

    /// A camera far outside every test scene.
    const OUTSIDE: Vec3 = Vec3::splat(100.0);

    /// A 2 x 2 floor (area 4) and a 1 x 1 emissive quad (area 1) of radiance `emission`.
    fn lamp_scene(emission: f32) -> Scene {
        let mut s = Scene::default();
        s.materials.push(Material { name: "floor".into(), ..Default::default() });
        s.materials.push(Material {
            name: "lamp".into(),
            emissive_factor: Vec3::splat(emission),
            ..Default::default()
        });
        s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, 0));
        s.meshes.push(builtin::quad(Vec3::Y, Vec3::X, Vec3::Z, 1));
        s.nodes.push(builtin::node("n", Vec3::ZERO));
        s.instances.push(Instance { mesh: 0, node: 0 });
        s.instances.push(Instance { mesh: 1, node: 0 });
        s
    }

    #[test]
    fn emission_is_averaged_over_all_surfaces() {
        // 1 (area) x 2 (radiance) / 5 (total area).
        assert!((mean_emission(&lamp_scene(2.0)) - 0.4).abs() < 1e-5);
        assert_eq!(mean_emission(&lamp_scene(0.0)), 0.0);
    }

    #[test]
    fn weak_emitters_get_the_default_light_and_strong_ones_do_not() {
        let weak = choose(&Environment::DefaultLight, &lamp_scene(0.2), OUTSIDE);
        assert!(weak.default_light && weak.note.contains("too weak"), "{weak:?}");
        let strong = choose(&Environment::DefaultLight, &lamp_scene(1.0), OUTSIDE);
        assert!(!strong.default_light && strong.note.contains("emitters light it"), "{strong:?}");
        let none = choose(&Environment::DefaultLight, &lamp_scene(0.0), OUTSIDE);
        assert!(none.default_light && none.note.contains("no emitters"), "{none:?}");
        // Asked-for environments replace it; a black one turns it off and says so.
        let off = choose(&Environment::Constant(Vec3::ZERO), &lamp_scene(0.0), OUTSIDE);
        assert!(!off.default_light && off.note.contains("default light is off"), "{off:?}");
        assert!(!choose(&Environment::Constant(Vec3::ONE), &lamp_scene(0.0), OUTSIDE).default_light);
    }

    #[test]
    fn a_mostly_black_emissive_texture_counts_for_what_it_emits() {
        let mut s = lamp_scene(1.0);
        // 4 x 1 texture: one white texel, three black; the lamp's UVs all sit in a black one.
        let mut rgba8 = vec![0u8; 16];
        rgba8[..4].copy_from_slice(&[255; 4]);
        s.images.push(Image { name: "e".into(), width: 4, height: 1, rgba8 });
        s.textures.push(Texture { image: Some(0), sampler: Default::default() });
        let texture = TextureRef { texture: 0, uv_set: 0, transform: Mat3::from_translation(Vec2::new(0.5, 0.0)) };
        s.materials[1].emissive_texture = Some(texture);
        for v in &mut s.meshes[1].vertices {
            v.uv0 = [0.0, 0.0];
        }
        assert_eq!(mean_emission(&s), 0.0, "uv 0.5 after the transform: a black texel");
        s.materials[1].emissive_texture.as_mut().unwrap().transform = Mat3::IDENTITY;
        assert!((mean_emission(&s) - 0.2).abs() < 1e-5, "uv 0: the white texel");
    }

    #[test]
    fn the_builtin_scenes_keep_their_own_lights() {
        for name in [builtin::NAMES, crate::scene::builtin_stability::NAMES].concat() {
            let scene = builtin::by_name(name).unwrap();
            let l = choose(&Environment::DefaultLight, &scene, OUTSIDE);
            assert!(!l.default_light, "{name}: {}", l.note);
        }
    }

    #[test]
    fn a_camera_in_a_closed_room_gets_no_default_light_from_outside_it_does() {
        // The lamp scene's weak lamp inside a closed 4 x 4 x 4 box around it.
        let mut s = lamp_scene(0.2);
        s.meshes.push(builtin::cuboid(Vec3::splat(2.0), 0));
        s.instances.push(Instance { mesh: 2, node: 0 });
        let inside = choose(&Environment::DefaultLight, &s, Vec3::new(0.3, 0.5, -0.2));
        assert!(!inside.default_light && inside.note.contains("closed room"), "{inside:?}");
        let outside = choose(&Environment::DefaultLight, &s, OUTSIDE);
        assert!(outside.default_light && outside.note.contains("too weak"), "{outside:?}");
        // A hole in the box lets the sky in.
        let faces = &mut s.meshes[2].indices;
        faces.truncate(faces.len() - 6);
        let open = choose(&Environment::DefaultLight, &s, Vec3::new(0.3, 0.5, -0.2));
        assert!(open.default_light && open.note.contains("random walks from it leave"), "{open:?}");
    }
}
