//! The pass plan: no more work than the scene needs. Decided once per scene from what is in it,
//! printed by `hybrid-rt plan`, used by default; `--full` runs everything.
//!
//! - Reflection rays only if some surface is at or under the roughness cut-off (rougher ones
//!   get their specular lobe from gi's samples anyway).
//! - Soft-shadow machinery (penumbra detection, tent, filter) only if some light has a radius;
//!   with punctual lights only, one hard-shadow ray per light and no filter.
//! - Lights whose range cannot reach any geometry are culled (static scenes only: in an
//!   animated scene a light or an object could move into range).
//! - Up to four punctual lights each get their own ray-traced visibility (exact and noise-free,
//!   with adaptive soft shadows); with more, the four that bring the most direct light to the
//!   camera's views keep it (render::light_view; small emissive meshes compete for it too) and the
//!   rest are resampled in gi: one light per pixel from candidates drawn from the light grid
//!   (each cell lists the lights whose range reaches it) and the pixel's reservoir of last
//!   frame, with shadow rays, so the cost per pixel does not grow with their number (see
//!   world::lights::shading_order, world::light_grid and shaders-glsl/common/light_reservoir.glsl).
//! - Instances share one bottom-level structure per unique mesh (reported; always so).
//! - GI runs every frame when any surface has a diffuse albedo or is rough enough for its
//!   specular lobe to come from gi, or when lights are resampled (gi shades them); otherwise it
//!   would have nothing to add.

use super::camera::View;
use super::light_view::LightView;
use crate::passes::shadows::MAX_SHADOWED_LIGHTS;
use crate::scene::{Scene, TextureRef};
use glam::Vec3;

/// Candidate lights drawn per pixel and frame for the resampled lights (gi); the shaders'
/// RIS_CANDIDATES (common/light_reservoir.glsl).
pub const RIS_CANDIDATES: u32 = 8;

#[derive(Clone, Debug, serde::Serialize)]
pub struct FramePlan {
    pub reflections: bool,
    /// Some material is transmissive or blended: the reflections pass writes what those
    /// surfaces let through as a signal of its own (`reflections.let_through`, 1x1 and
    /// unwritten otherwise), which its own SVGF chain denoises.
    pub let_through: bool,
    pub soft_shadows: bool,
    /// Some thin glass is tinted: the shadows chain keeps the colour of what it lets through
    /// (`shadows.tint`, 1x1 and unwritten otherwise).
    pub tinted_shadows: bool,
    pub gi: bool,
    /// Indices into the scene's lights that cannot reach any geometry.
    pub culled_lights: Vec<usize>,
    /// The lights the renderer keeps, as indices into the scene's, in the order it shades them
    /// (world::lights::shading_order): the first `chain_punctual` get the shadows chain.
    pub light_order: Vec<usize>,
    /// How many punctual lights have a channel of the shadows chain: of the punctual and mesh
    /// lights, the MAX_SHADOWED_LIGHTS that bring the most to the first view get one
    /// (world::lights::chain_lights).
    pub chain_punctual: usize,
    /// Lights past the per-light-shadowed ones, resampled in gi.
    pub resampled_lights: usize,
    /// Emissive triangles, resampled in gi with those lights (those of the chain's mesh lights
    /// left out).
    pub emitters: u32,
    /// The mesh lights that take the shadows chain's channels after the punctual lights
    /// (world::lights::chain_lights): (instance, first emitter, triangles).
    pub chain_emitters: Vec<(u32, u32, u32)>,
    /// More lights competed for the chain than it has channels, and they were ranked by what
    /// they bring to the camera's views (render::light_view) rather than by power.
    pub chain_by_view: bool,
    /// The diagonal of the scene's bounding box (at time 0): the radiance cache sizes its
    /// cells by it.
    pub scene_diagonal: f32,
    /// One line per decision, saying why.
    pub reasons: Vec<String>,
}

impl FramePlan {
    /// Whether gi keeps a reservoir per pixel: some punctual light or some triangle is
    /// resampled (common/light_reservoir.glsl).
    pub fn reservoirs(&self) -> bool {
        self.resampled_lights > 0 || self.emitters > 0
    }

    /// Whether `other` gives the shadows chain the same lights, in whatever order (another
    /// order would only move them between channels).
    pub fn same_chain(&self, other: &FramePlan) -> bool {
        let chain = |p: &FramePlan| {
            let mut punctual = p.light_order[..p.chain_punctual].to_vec();
            let mut meshes = p.chain_emitters.clone();
            punctual.sort_unstable();
            meshes.sort_unstable();
            (punctual, meshes)
        };
        chain(self) == chain(other)
    }

    /// The names of the shadows chain's lights: the punctual ones from `lights` (the scene's
    /// as loaded, which `light_order` indexes), then the mesh lights' instances.
    pub fn chain_names(&self, lights: &[crate::scene::Light], scene: &Scene) -> String {
        let punctual = self.light_order[..self.chain_punctual].iter().map(|&i| lights[i].name.as_str());
        let meshes = self.chain_emitters.iter().map(|&(i, ..)| instance_name(scene, i));
        let names: Vec<&str> = punctual.chain(meshes).collect();
        if names.is_empty() { "no light".into() } else { names.join(", ") }
    }

    /// Everything on (`--full`); `mesh_lights` and `views` as in [`FramePlan::for_scene`].
    pub fn full(scene: &Scene, mesh_lights: bool, views: &[View]) -> Self {
        let kept: Vec<usize> = (0..scene.lights.len()).collect();
        let (chain, chain_emitters, chain_by_view) = chain_lights(scene, &kept, mesh_lights, views);
        let chain_punctual = chain.len();
        let light_order = crate::world::lights::shading_order(scene, &[], &chain);
        Self {
            reflections: true,
            let_through: true,
            soft_shadows: true,
            tinted_shadows: true,
            gi: true,
            culled_lights: Vec::new(),
            resampled_lights: light_order.len() - chain_punctual,
            emitters: crate::world::lights::emitter_bases(scene).1 - chain_triangles(&chain_emitters),
            chain_emitters,
            chain_by_view,
            light_order,
            chain_punctual,
            scene_diagonal: scene_diagonal(scene),
            reasons: vec!["--full: every pass runs".into()],
        }
    }

    /// `light_grid`: the resampled lights' candidates are drawn from the light grid
    /// (`Settings::light_grid`), which only the reason's text depends on.
    /// `mesh_lights`: small emissive meshes may take the shadows chain's free channels
    /// (`Settings::mesh_lights`). `views`: the camera's (camera::shot_views: at time 0, and
    /// over its animation where it moves); where more lights compete for the shadows chain
    /// than it has channels, they rank by what they bring to them (render::light_view), and by
    /// power without any.
    pub fn for_scene(
        scene: &Scene,
        roughness_cutoff: f32,
        light_grid: bool,
        mesh_lights: bool,
        views: &[View],
    ) -> Self {
        let mut reasons = Vec::new();

        let glossy: Vec<&str> = scene
            .materials
            .iter()
            .filter(|m| min_roughness(scene, m.roughness_factor, m.metallic_roughness_texture) <= roughness_cutoff)
            .map(|m| m.name.as_str())
            .collect();
        // Glass and blended materials of any roughness: the reflections pass traces what they
        // let through.
        let glass: Vec<&str> = scene
            .materials
            .iter()
            .filter(|m| m.is_transmissive() || m.alpha_mode == crate::scene::AlphaMode::Blend)
            .map(|m| m.name.as_str())
            .collect();
        let let_through = !glass.is_empty();
        let reflections = !glossy.is_empty() || let_through;
        reasons.push(if !glass.is_empty() && glossy.is_empty() {
            format!("reflections: traced for what {} transmissive or blended material(s) let through: {}", glass.len(), list(&glass))
        } else if reflections {
            format!("reflections: traced, {} material(s) at or under roughness {roughness_cutoff}: {}", glossy.len(), list(&glossy))
        } else {
            format!("reflections: no rays, no surface is at or under roughness {roughness_cutoff} (gi estimates the specular lobes)")
        });
        if let_through {
            reasons.push(format!(
                "reflections: what {} transmissive or blended material(s) let through is a signal of its own (reflections.let_through), denoised by its own chain",
                glass.len()
            ));
        }

        let culled_lights = if scene.is_animated() { Vec::new() } else { out_of_range(scene) };
        let kept: Vec<usize> = (0..scene.lights.len()).filter(|i| !culled_lights.contains(i)).collect();
        let (chain, chain_emitters, chain_by_view) = chain_lights(scene, &kept, mesh_lights, views);
        let chain_punctual = chain.len();
        let light_order = crate::world::lights::shading_order(scene, &culled_lights, &chain);
        let seen = if views.len() > 1 {
            format!("the camera's {} views over its animation", views.len())
        } else {
            "the first view".into()
        };
        let shadowed = &light_order[..chain_punctual];
        let mut soft: Vec<&str> =
            shadowed.iter().map(|&i| &scene.lights[i]).filter(|l| l.radius > 0.0).map(|l| l.name.as_str()).collect();
        let mesh_lights: Vec<&str> = chain_emitters.iter().map(|&(i, ..)| instance_name(scene, i)).collect();
        soft.extend(&mesh_lights);
        let soft_shadows = !soft.is_empty();
        reasons.push(if soft_shadows {
            format!(
                "shadows: adaptive soft shadows for {} light(s) with a radius or an area: {}",
                soft.len(),
                list(&soft)
            )
        } else {
            "shadows: every light is punctual: one hard-shadow ray per light, no penumbra detection or filter".into()
        });
        // The chain shadows punctual lights and mesh lights (other emitters and the sky go
        // through gi, whose light samples keep the colour).
        let tinted = if shadowed.is_empty() && chain_emitters.is_empty() { Vec::new() } else { tinted_glass(scene) };
        let tinted_shadows = !tinted.is_empty();
        if tinted_shadows {
            reasons.push(format!(
                "shadows: light through tinted thin glass keeps its colour (shadows.tint), {} material(s): {}",
                tinted.len(),
                list(&tinted)
            ));
        }

        if scene.is_animated() {
            reasons.push("lights: none culled, the scene is animated".into());
        } else if culled_lights.is_empty() {
            reasons.push("lights: every light reaches some geometry".into());
        } else {
            let names: Vec<&str> = culled_lights.iter().map(|&i| scene.lights[i].name.as_str()).collect();
            reasons.push(format!("lights: culled {} whose range reaches no geometry: {}", names.len(), list(&names)));
        }

        let resampled_lights = light_order.len() - shadowed.len();
        reasons.push(if resampled_lights > 0 {
            let names: Vec<&str> = shadowed.iter().map(|&i| scene.lights[i].name.as_str()).collect();
            let kept = if shadowed.is_empty() {
                "none keeps a visibility of its own (brighter mesh lights hold the shadows chain)".to_string()
            } else {
                format!(
                    "the {} {} ({}) keep a visibility of their own (exact, noise-free)",
                    shadowed.len(),
                    if chain_by_view {
                        format!("that bring the most direct light to {seen}")
                    } else {
                        "brightest".into()
                    },
                    list(&names)
                )
            };
            let source = if light_grid {
                "drawn from a light grid (a cell lists the lights that reach it, weighed by what they can \
                 bring there and by how often gi's shadow rays from the cell reach their group of lights: \
                 light_grid_update)"
            } else {
                "drawn by power from all of them (--no-light-grid: no grid, nothing learned)"
            };
            format!(
                "many lights: {} punctual lights; {kept}; the other {resampled_lights} are resampled in gi: \
                 per pixel one light from {} candidates {source} and last frame's choice, weighted by its \
                 unshadowed contribution{}, with shadow rays (ReSTIR-style temporal reuse); the cost per pixel \
                 does not grow with the number of lights",
                light_order.len(),
                RIS_CANDIDATES,
                if light_grid { " and that visibility" } else { "" },
            )
        } else {
            format!(
                "lights: {} punctual light(s), each with its own ray-traced visibility (at most \
                 {MAX_SHADOWED_LIGHTS}: exact and noise-free, no resampling needed)",
                light_order.len()
            )
        });

        if !mesh_lights.is_empty() {
            reasons.push(format!(
                "mesh lights: {} emissive mesh(es) of at most {} triangles take shadows chain channel(s), \
                 ranked with the punctual lights by the light they {} (composite integrates their \
                 unshadowed light exactly, the chain's adaptive shadow rays give the share that arrives, \
                 gi's reservoirs leave them out): {}",
                mesh_lights.len(),
                crate::world::lights::MAX_CHAIN_EMITTER_TRIANGLES,
                if chain_by_view { format!("bring to {seen}") } else { "emit".into() },
                list(&mesh_lights)
            ));
        }
        let emitters = crate::world::lights::emitter_bases(scene).1 - chain_triangles(&chain_emitters);
        if emitters > 0 {
            reasons.push(format!(
                "emitters: {emitters} emissive triangle(s), resampled in gi{}: per pixel one point on one of \
                 them from candidates drawn by power{} and last frame's choice, weighted by their unshadowed \
                 contribution{}, with shadow rays",
                if resampled_lights > 0 { " with the resampled punctual lights" } else { "" },
                if light_grid {
                    " x what the light grid's cell has learned to see of the region they lie in (gi's shadow \
                     rays, counted by light_grid_update)"
                } else {
                    ""
                },
                if light_grid { " x that same learned visibility" } else { "" }
            ));
        }

        let unique = scene.meshes.len();
        reasons.push(format!(
            "geometry: {} instance(s) share {unique} bottom-level structure(s), one per unique mesh",
            scene.instances.len()
        ));

        let diffuse = scene.materials.iter().any(|m| m.metallic_factor < 1.0 || m.metallic_roughness_texture.is_some());
        let rough = scene.materials.iter().any(|m| m.roughness_factor > roughness_cutoff);
        let gi = diffuse || rough || resampled_lights > 0;
        reasons.push(if !(diffuse || rough) && gi {
            "gi: every frame, to shade the resampled lights (every surface is a smooth metal)".into()
        } else if gi {
            "gi: every frame (diffuse or rough surfaces need indirect light)".into()
        } else {
            "gi: skipped, every surface is a smooth metal (no diffuse lobe, no rough specular)".into()
        });
        Self {
            reflections,
            let_through,
            soft_shadows,
            tinted_shadows,
            gi,
            culled_lights,
            light_order,
            chain_punctual,
            resampled_lights,
            emitters,
            chain_emitters,
            chain_by_view,
            scene_diagonal: scene_diagonal(scene),
            reasons,
        }
    }
}

/// The mesh lights (world::lights::chain_emitters), none when they are off.
fn chain_triangles(chain: &[(u32, u32, u32)]) -> u32 {
    chain.iter().map(|c| c.2).sum()
}

/// An instance's name in the plan: its node's (instances of one mesh differ by it), else its
/// mesh's.
fn instance_name(scene: &Scene, instance: u32) -> &str {
    let inst = &scene.instances[instance as usize];
    let node = scene.nodes[inst.node as usize].name.as_str();
    if node.is_empty() { scene.meshes[inst.mesh as usize].name.as_str() } else { node }
}

fn scene_diagonal(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds(&scene.evaluate(0.0));
    let d = (hi - lo).length();
    if d.is_finite() { d } else { 1.0 }
}

/// world::lights::chain_lights, its candidates ranked by what they bring to `views` where any
/// are given and more compete than the chain has channels (the CPU BVH is built only then).
/// Also says whether the views ranked them (some of their rays reached a surface).
fn chain_lights(
    scene: &Scene,
    kept: &[usize],
    mesh_lights: bool,
    views: &[View],
) -> (Vec<usize>, Vec<(u32, u32, u32)>, bool) {
    let seen = std::cell::OnceCell::new();
    let brings = |c| if views.is_empty() { 0.0 } else { seen.get_or_init(|| LightView::new(scene, views)).brings(c) };
    let (lights, meshes) = crate::world::lights::chain_lights(scene, kept, mesh_lights, &brings);
    let by_view = seen.get().is_some_and(|v| v.surfaces() > 0);
    (lights, meshes, by_view)
}

/// Thin glass (transmissive without a volume, which shadow rays cross) whose base colour is not
/// grey, by factor or texture: what passes it is coloured. Blended surfaces let 1 - alpha
/// through, grey.
fn tinted_glass(scene: &Scene) -> Vec<&str> {
    let grey = |c: [f32; 3]| c[0] == c[1] && c[1] == c[2];
    let texture_grey = |t: TextureRef| {
        texture_image(scene, t).is_none_or(|img| img.rgba8.chunks_exact(4).all(|p| p[0] == p[1] && p[1] == p[2]))
    };
    scene
        .materials
        .iter()
        .filter(|m| m.is_transmissive() && m.thickness <= 0.0)
        .filter(|m| {
            !grey(m.base_color_factor.truncate().to_array()) || m.base_color_texture.is_some_and(|t| !texture_grey(t))
        })
        .map(|m| m.name.as_str())
        .collect()
}

fn list(names: &[&str]) -> String {
    const SHOWN: usize = 6;
    let mut s =
        names.iter().take(SHOWN).map(|n| if n.is_empty() { "(unnamed)" } else { n }).collect::<Vec<_>>().join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    s
}

/// The decoded image a material's texture reference points at, if any.
fn texture_image(scene: &Scene, t: TextureRef) -> Option<&crate::scene::Image> {
    scene.textures.get(t.texture as usize).and_then(|t| t.image).and_then(|i| scene.images.get(i as usize))
}

/// The lowest roughness a material reaches: its factor times the smallest green value of its
/// metallic-roughness texture (the texture can only lower it).
fn min_roughness(scene: &Scene, factor: f32, texture: Option<TextureRef>) -> f32 {
    let Some(t) = texture else { return factor };
    match texture_image(scene, t) {
        Some(img) => {
            let min_g = img.rgba8.chunks_exact(4).map(|p| p[1]).min().unwrap_or(255);
            factor * min_g as f32 / 255.0
        }
        None => factor,
    }
}

/// Lights with a range whose sphere misses the bounds of every instance (at time 0).
fn out_of_range(scene: &Scene) -> Vec<usize> {
    let pose = scene.evaluate(0.0);
    let boxes: Vec<(Vec3, Vec3)> = scene
        .instances
        .iter()
        .map(|inst| {
            let mesh = &scene.meshes[inst.mesh as usize];
            let m = pose.world[inst.node as usize];
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for i in 0..8 {
                let c = Vec3::new(
                    if i & 1 == 0 { mesh.bounds_min.x } else { mesh.bounds_max.x },
                    if i & 2 == 0 { mesh.bounds_min.y } else { mesh.bounds_max.y },
                    if i & 4 == 0 { mesh.bounds_min.z } else { mesh.bounds_max.z },
                );
                let w = m.transform_point3(c);
                lo = lo.min(w);
                hi = hi.max(w);
            }
            (lo, hi)
        })
        .collect();
    scene
        .lights
        .iter()
        .enumerate()
        .filter(|(_, l)| {
            let Some(range) = l.range else { return false };
            let centre = pose.world[l.node as usize].transform_point3(Vec3::ZERO);
            // Reaching means the range sphere (plus the emitter's own radius) touches a box.
            let reach = range + l.radius;
            !boxes.iter().any(|(lo, hi)| centre.clamp(*lo, *hi).distance_squared(centre) <= reach * reach)
        })
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn punctual_only_scenes_get_hard_shadows_and_matte_ones_no_reflection_rays() {
        let p = FramePlan::for_scene(&builtin::shadow_test(), 0.6, true, true, &[]);
        assert!(!p.soft_shadows && !p.reflections && p.gi, "{:?}", p.reasons);
        let p = FramePlan::for_scene(&builtin::soft_shadow_test(), 0.6, true, true, &[]);
        assert!(p.soft_shadows);
    }

    #[test]
    fn only_tinted_thin_glass_makes_the_shadows_keep_a_colour() {
        let tinted_with = |m: crate::scene::Material| {
            let mut s = builtin::shadow_test();
            s.materials[0] = m;
            FramePlan::for_scene(&s, 0.6, true, true, &[]).tinted_shadows
        };
        let glass = |rgb: Vec3| crate::scene::Material {
            name: "glass".into(),
            base_color_factor: rgb.extend(1.0),
            transmission: 1.0,
            ..Default::default()
        };
        assert!(tinted_with(glass(Vec3::new(1.0, 0.5, 0.25))));
        assert!(!tinted_with(glass(Vec3::splat(0.8))), "grey glass");
        assert!(
            !tinted_with(crate::scene::Material { thickness: 0.1, ..glass(Vec3::new(1.0, 0.5, 0.25)) }),
            "a volume"
        );
        let blend = crate::scene::Material {
            base_color_factor: glam::Vec4::new(1.0, 0.0, 0.0, 0.5),
            alpha_mode: crate::scene::AlphaMode::Blend,
            ..Default::default()
        };
        assert!(!tinted_with(blend), "blended surfaces let 1 - alpha through, grey");
        assert!(!FramePlan::for_scene(&builtin::shadow_test(), 0.6, true, true, &[]).tinted_shadows);
        let mut unlit = builtin::shadow_test();
        unlit.materials[0] = glass(Vec3::new(1.0, 0.5, 0.25));
        unlit.lights.clear();
        assert!(
            !FramePlan::for_scene(&unlit, 0.6, true, true, &[]).tinted_shadows,
            "no punctual light: nothing to shadow"
        );
    }

    #[test]
    fn lights_out_of_range_are_culled_in_static_scenes() {
        let mut s = builtin::shadow_test();
        let mut far = s.lights[0].clone();
        far.kind = crate::scene::LightKind::Point;
        far.range = Some(1.0);
        let node = s.nodes.len() as u32;
        s.nodes.push(crate::scene::Node {
            name: "far".into(),
            parent: None,
            translation: Vec3::new(0.0, 500.0, 0.0),
            rotation: glam::Quat::IDENTITY,
            scale: Vec3::ONE,
        });
        far.node = node;
        s.lights.push(far);
        let p = FramePlan::for_scene(&s, 0.6, true, true, &[]);
        assert_eq!(p.culled_lights, vec![1], "{:?}", p.reasons);
        // The same light in reach stays.
        s.nodes[node as usize].translation = Vec3::new(0.0, 1.5, 0.0);
        assert!(FramePlan::for_scene(&s, 0.6, true, true, &[]).culled_lights.is_empty());
        assert_eq!(FramePlan::for_scene(&s, 0.6, true, true, &[]).light_order, vec![0, 1]);
    }

    #[test]
    fn lights_past_the_shadowed_four_are_resampled_and_the_plan_names_the_four() {
        let s = crate::scene::builtin_many_lights::many_lights();
        let p = FramePlan::for_scene(&s, 0.6, true, true, &[]);
        // (The camera room's highest lights reach no surface with their short range: culled.)
        assert_eq!(p.light_order.len(), s.lights.len() - p.culled_lights.len());
        assert_eq!(p.chain_punctual, MAX_SHADOWED_LIGHTS);
        assert_eq!(p.resampled_lights, p.light_order.len() - MAX_SHADOWED_LIGHTS);
        assert!(p.resampled_lights > 250, "{:?}", p.reasons);
        let line = p.reasons.iter().find(|r| r.starts_with("many lights")).expect("no many-lights line");
        for &i in &p.light_order[..MAX_SHADOWED_LIGHTS] {
            assert!(line.contains(&s.lights[i].name), "{line}");
        }
        assert!(line.contains("light_grid_update"), "{line}");
        // Without the light grid the line says where the candidates come from instead.
        let p = FramePlan::for_scene(&s, 0.6, false, true, &[]);
        let line = p.reasons.iter().find(|r| r.starts_with("many lights")).expect("no many-lights line");
        assert!(line.contains("--no-light-grid") && !line.contains("light_grid_update"), "{line}");
        // Four lights or fewer: none resampled, the scene's order kept.
        let p = FramePlan::for_scene(&builtin::soft_shadow_test(), 0.6, true, true, &[]);
        assert_eq!((p.resampled_lights, p.light_order.clone()), (0, vec![0]));
    }
}
