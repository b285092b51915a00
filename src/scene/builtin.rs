//! Built-in scenes made in code, for tests with analytic answers and for quick looks. Each is
//! reachable from the command line as `builtin:NAME`.

use super::animation::{Channel, Interpolation, Property};
use super::{Animation, Camera, Instance, Material, Mesh, Node, Scene, Vertex};
use anyhow::Result;
use glam::{Quat, Vec3, Vec4};

/// Names accepted after `builtin:` (with the stability suite's, `super::builtin_stability::NAMES`).
pub const NAMES: &[&str] = &[
    "gbuffer-test",
    "alpha-shadow",
    "shadow-test",
    "soft-shadow-test",
    "checker-test",
    "facet-test",
    "morph-test",
    "many-lights",
    "many-panels",
    "skin-test",
];

pub fn by_name(name: &str) -> Result<Scene> {
    match name {
        "gbuffer-test" => Ok(gbuffer_test()),
        "alpha-shadow" => Ok(alpha_shadow()),
        "shadow-test" => Ok(shadow_test()),
        "soft-shadow-test" => Ok(soft_shadow_test()),
        "checker-test" => Ok(checker_test()),
        "facet-test" => Ok(facet_test()),
        "morph-test" => Ok(morph_test()),
        "many-lights" => Ok(super::builtin_many_lights::many_lights()),
        "many-panels" => Ok(super::builtin_many_lights::many_panels()),
        "skin-test" => Ok(super::builtin_skin::skin_test()),
        _ => super::builtin_stability::by_name(name).ok_or_else(|| {
            let known = [NAMES, super::builtin_stability::NAMES].concat().join(", ");
            anyhow::anyhow!("builtin:{name}: no such built-in scene (known: {known})")
        }),
    }
}

/// Facts about `gbuffer_test` that tests check against.
pub mod gbuffer_test_facts {
    use glam::Vec3;
    /// The camera sits at the origin looking down -Z with this vertical field of view.
    pub const YFOV: f32 = std::f32::consts::FRAC_PI_3;
    /// The back plane z = -PLANE_DISTANCE faces the camera.
    pub const PLANE_DISTANCE: f32 = 10.0;
    pub const SPHERE_CENTRE: Vec3 = Vec3::new(-1.2, 0.0, -5.0);
    pub const SPHERE_RADIUS: f32 = 1.0;
    /// The cube moves along +X at this speed (units per second), centred at x = 0 at t = 0.5.
    pub const CUBE_SPEED: f32 = 2.0;
    pub const CUBE_Y: f32 = 1.0;
    pub const CUBE_Z: f32 = -4.0;
    pub const CUBE_HALF: f32 = 0.25;
    pub const PLANE_INSTANCE: u32 = 0;
    pub const SPHERE_INSTANCE: u32 = 1;
    pub const CUBE_INSTANCE: u32 = 2;
}

/// A back plane, a finely tessellated sphere and a cube that moves along +X: plane depth,
/// sphere normals and motion vectors have closed-form answers.
pub fn gbuffer_test() -> Scene {
    use gbuffer_test_facts::*;
    let mut s = Scene { name: "builtin:gbuffer-test".into(), ..Default::default() };
    s.materials.push(Material {
        name: "grey".into(),
        metallic_factor: 0.0,
        roughness_factor: 0.8,
        ..Default::default()
    });
    s.meshes.push(quad(Vec3::new(0.0, 0.0, -PLANE_DISTANCE), Vec3::X * 40.0, Vec3::Y * 40.0, 0));
    s.meshes.push(uv_sphere(SPHERE_RADIUS, 128, 64, 0));
    s.meshes.push(cuboid(Vec3::splat(CUBE_HALF), 0));
    s.nodes.push(node("plane", Vec3::ZERO));
    s.nodes.push(node("sphere", SPHERE_CENTRE));
    s.nodes.push(node("cube", Vec3::new(-CUBE_SPEED * 0.5, CUBE_Y, CUBE_Z)));
    s.nodes.push(node("camera", Vec3::ZERO));
    for i in 0..3 {
        s.instances.push(Instance { mesh: i, node: i });
    }
    s.cameras.push(Camera {
        name: "origin".into(),
        yfov: YFOV,
        aspect_ratio: None,
        znear: 0.1,
        zfar: Some(100.0),
        node: 3,
    });
    s.lights.push(super::Light {
        name: "sun".into(),
        kind: super::LightKind::Directional,
        color: Vec3::ONE,
        intensity: 3.0,
        range: None,
        radius: 0.0,
        node: 3,
    });
    s.animations.push(Animation {
        name: "cube_slide".into(),
        channels: vec![Channel {
            node: 2,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![
                Vec4::new(-CUBE_SPEED * 0.5, CUBE_Y, CUBE_Z, 0.0),
                Vec4::new(CUBE_SPEED * 0.5, CUBE_Y, CUBE_Z, 0.0),
            ],
        }],
    });
    s
}

/// Facts about `alpha_shadow` that tests check against.
pub mod alpha_shadow_facts {
    /// The masked square spans x, z in [-HALF, HALF] at height MASK_Y.
    pub const HALF: f32 = 1.0;
    pub const MASK_Y: f32 = 1.0;
    /// Checker cells per side of the mask texture; cell (i, j) is opaque when i + j is even.
    pub const CELLS: u32 = 8;
    pub const FLOOR_INSTANCE: u32 = 0;
    pub const MASK_INSTANCE: u32 = 1;

    /// Whether the mask is opaque above floor point (x, z) (the texture's checker, u along
    /// +x and v along +z).
    pub fn opaque_at(x: f32, z: f32) -> Option<bool> {
        let (u, v) = ((x + HALF) / (2.0 * HALF), (z + HALF) / (2.0 * HALF));
        if !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v) {
            return None;
        }
        let (i, j) = ((u * CELLS as f32) as u32, (v * CELLS as f32) as u32);
        Some((i + j) % 2 == 0)
    }
}

/// A floor lit straight from above by a directional light through an alpha-masked square
/// whose texture is a checkerboard of opaque and fully transparent cells: the shadow on the
/// floor must be the same checkerboard.
pub fn alpha_shadow() -> Scene {
    use alpha_shadow_facts::*;
    let mut s = Scene { name: "builtin:alpha-shadow".into(), ..Default::default() };
    let size = 64u32;
    let cell = size / CELLS;
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let opaque = (x / cell + y / cell).is_multiple_of(2);
            rgba.extend_from_slice(&[200, 60, 40, if opaque { 255 } else { 0 }]);
        }
    }
    s.images.push(super::Image { name: "checker_alpha".into(), width: size, height: size, rgba8: rgba });
    s.textures.push(super::Texture {
        image: Some(0),
        sampler: super::Sampler {
            mag_filter: super::Filter::Nearest,
            min_filter: super::Filter::Nearest,
            mipmaps: false,
            wrap_s: super::Wrap::ClampToEdge,
            wrap_t: super::Wrap::ClampToEdge,
        },
    });
    s.materials.push(Material {
        name: "floor".into(),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Default::default()
    });
    s.materials.push(Material {
        name: "mask".into(),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        base_color_texture: Some(super::TextureRef { texture: 0, uv_set: 0, transform: glam::Mat3::IDENTITY }),
        alpha_mode: super::AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        ..Default::default()
    });
    // Floor facing +Y; the mask facing +Y with u along +x and v along +z.
    s.meshes.push(quad(Vec3::ZERO, Vec3::Z * 8.0, Vec3::X * 8.0, 0));
    let mut mask = quad(Vec3::new(0.0, MASK_Y, 0.0), Vec3::Z * (2.0 * HALF), Vec3::X * (2.0 * HALF), 1);
    for v in &mut mask.vertices {
        v.uv0 = [(v.position[0] + HALF) / (2.0 * HALF), (v.position[2] + HALF) / (2.0 * HALF)];
        v.uv1 = v.uv0;
    }
    s.meshes.push(mask);
    s.nodes.push(node("floor", Vec3::ZERO));
    s.nodes.push(node("mask", Vec3::ZERO));
    let mut eye = node("camera", Vec3::new(0.0, 6.0, 0.0));
    eye.rotation = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    s.nodes.push(eye);
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.instances.push(Instance { mesh: 1, node: 1 });
    s.cameras.push(Camera {
        name: "above".into(),
        yfov: 0.9,
        aspect_ratio: None,
        znear: 0.1,
        zfar: Some(50.0),
        node: 2,
    });
    s.lights.push(super::Light {
        name: "sun".into(),
        kind: super::LightKind::Directional,
        color: Vec3::ONE,
        intensity: 2.0,
        range: None,
        radius: 0.0,
        node: 2,
    });
    s
}

/// Facts about `shadow_test` that tests check against.
pub mod shadow_test_facts {
    use glam::Vec3;
    /// The box stands on the floor (y = 0): centre (0, HALF, 0), half extent HALF.
    pub const HALF: f32 = 0.5;
    /// Direction the sunlight travels.
    pub fn light_dir() -> Vec3 {
        Vec3::new(1.0, -0.6, 1.0).normalize()
    }
    pub const FLOOR_INSTANCE: u32 = 0;
    /// Whether floor point `p` (y = 0) is in the box's shadow: the ray toward the light hits
    /// the box.
    pub fn shadowed(p: Vec3) -> bool {
        ray_hits_box(p, -light_dir(), f32::INFINITY)
    }

    /// Whether the ray `o + t d`, 0 <= t <= tmax, meets the box.
    pub fn ray_hits_box(o: Vec3, d: Vec3, tmax: f32) -> bool {
        let (lo, hi) = (Vec3::new(-HALF, 0.0, -HALF), Vec3::new(HALF, 2.0 * HALF, HALF));
        let (mut t0, mut t1) = (0.0f32, tmax);
        for a in 0..3 {
            let (n, f) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t0 = t0.max(n.min(f));
            t1 = t1.min(n.max(f));
        }
        t0 <= t1
    }

    /// The sphere light of `soft_shadow_test`: centre and radius.
    pub const SPHERE_LIGHT: Vec3 = Vec3::new(-1.5, 3.0, -1.5);
    pub const SPHERE_RADIUS: f32 = 0.4;
}

/// A box on a large floor under a low sun, seen from a camera just above the floor: the
/// floor is at a grazing angle (shadow acne would show as speckle) and the shadow must touch
/// the box (peter-panning would detach it).
pub fn shadow_test() -> Scene {
    use shadow_test_facts::*;
    let mut s = Scene { name: "builtin:shadow-test".into(), ..Default::default() };
    s.materials.push(Material {
        name: "white".into(),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        ..Default::default()
    });
    s.meshes.push(quad(Vec3::ZERO, Vec3::Z * 40.0, Vec3::X * 40.0, 0));
    s.meshes.push(cuboid(Vec3::splat(HALF), 0));
    s.nodes.push(node("floor", Vec3::ZERO));
    s.nodes.push(node("box", Vec3::new(0.0, HALF, 0.0)));
    // Low enough that the far floor is seen at a few degrees, high enough to see the contact.
    let eye = Vec3::new(2.5, 1.0, 6.5);
    let mut cam = node("camera", eye);
    cam.rotation = Quat::from_mat4(&glam::Mat4::look_at_rh(eye, Vec3::new(0.6, 0.0, 0.4), Vec3::Y).inverse());
    s.nodes.push(cam);
    let mut sun = node("sun", Vec3::ZERO);
    sun.rotation = Quat::from_rotation_arc(Vec3::NEG_Z, light_dir());
    s.nodes.push(sun);
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.instances.push(Instance { mesh: 1, node: 1 });
    s.cameras.push(Camera {
        name: "grazing".into(),
        yfov: 0.7,
        aspect_ratio: None,
        znear: 0.05,
        zfar: Some(100.0),
        node: 2,
    });
    s.lights.push(super::Light {
        name: "sun".into(),
        kind: super::LightKind::Directional,
        color: Vec3::ONE,
        intensity: 3.0,
        range: None,
        radius: 0.0,
        node: 3,
    });
    s
}

/// `shadow_test` lit by a sphere light instead of the sun: the box casts a soft shadow whose
/// true visibility `shadow_test_facts::ray_hits_box` can integrate.
pub fn soft_shadow_test() -> Scene {
    use shadow_test_facts::*;
    let mut s = shadow_test();
    s.name = "builtin:soft-shadow-test".into();
    let lamp = s.nodes.len() as u32;
    s.nodes.push(node("lamp", SPHERE_LIGHT));
    s.lights[0] = super::Light {
        name: "lamp".into(),
        kind: super::LightKind::Point,
        color: Vec3::ONE,
        intensity: 30.0,
        range: None,
        radius: SPHERE_RADIUS,
        node: lamp,
    };
    s
}

/// Facts about `checker_test`.
pub mod checker_test_facts {
    /// Checker cells across the wall; the camera sees the wall's central 2 x 2 units.
    pub const CELLS: u32 = 8;
    /// Base colours of the two kinds of cell (linear).
    pub const LIGHT: f32 = 0.8;
    pub const DARK: f32 = 0.1;
    pub const WALL_INSTANCE: u32 = 0;
}

/// A wall with a sharp black-and-white checkerboard albedo, lit only by an emissive panel
/// (area light, so its light is a noisy ray-traced signal): after denoising, the checkerboard
/// must still be sharp, because the denoiser filters light with the albedo divided out.
pub fn checker_test() -> Scene {
    use checker_test_facts::*;
    let mut s = Scene { name: "builtin:checker-test".into(), ..Default::default() };
    let size = 64u32;
    let cell = size / CELLS;
    let to8 =
        |v: f32| (255.0 * if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }).round() as u8;
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let v = if (x / cell + y / cell).is_multiple_of(2) { to8(LIGHT) } else { to8(DARK) };
            rgba.extend_from_slice(&[v, v, v, 255]);
        }
    }
    s.images.push(super::Image { name: "checker".into(), width: size, height: size, rgba8: rgba });
    s.textures.push(super::Texture {
        image: Some(0),
        sampler: super::Sampler {
            mag_filter: super::Filter::Nearest,
            min_filter: super::Filter::Nearest,
            mipmaps: false,
            wrap_s: super::Wrap::ClampToEdge,
            wrap_t: super::Wrap::ClampToEdge,
        },
    });
    s.materials.push(Material {
        name: "checker".into(),
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        base_color_texture: Some(super::TextureRef { texture: 0, uv_set: 0, transform: glam::Mat3::IDENTITY }),
        ..Default::default()
    });
    s.materials.push(Material {
        name: "panel".into(),
        metallic_factor: 0.0,
        emissive_factor: Vec3::splat(4.0),
        ..Default::default()
    });
    // The wall at z = 0 facing +Z; the panel in front of it, facing it, off to the side and
    // above the camera's view.
    s.meshes.push(quad(Vec3::ZERO, Vec3::X * 2.0, Vec3::Y * 2.0, 0));
    s.meshes.push(quad(Vec3::new(0.0, 1.6, 1.2), Vec3::X * 1.6, Vec3::new(0.0, -0.8, 0.6), 1));
    s.nodes.push(node("wall", Vec3::ZERO));
    s.nodes.push(node("panel", Vec3::ZERO));
    s.nodes.push(node("camera", Vec3::new(0.0, 0.0, 2.0)));
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.instances.push(Instance { mesh: 1, node: 1 });
    s.cameras.push(Camera {
        name: "front".into(),
        yfov: 0.9,
        aspect_ratio: None,
        znear: 0.05,
        zfar: Some(20.0),
        node: 2,
    });
    s
}

/// A root node at `t`, unrotated and unscaled.
pub(crate) fn node(name: &str, t: Vec3) -> Node {
    Node { name: name.into(), parent: None, translation: t, rotation: Quat::IDENTITY, scale: Vec3::ONE }
}

pub(super) fn vertex(p: Vec3, n: Vec3, t: Vec3, uv: [f32; 2]) -> Vertex {
    Vertex { position: p.to_array(), normal: n.to_array(), tangent: t.extend(1.0).to_array(), uv0: uv, uv1: uv }
}

/// Facts about `facet_test`.
pub mod facet_test_facts {
    /// Both spheres are UV spheres of this many segments and rings (the default scene's gold
    /// sphere has the same tessellation): neighbouring faces differ by 11.25 degrees.
    pub const SEGMENTS: u32 = 32;
    pub const RINGS: u32 = 16;
    pub const DIFFUSE_SPHERE_INSTANCE: u32 = 2;
    pub const GLOSSY_SPHERE_INSTANCE: u32 = 3;
}

/// Two smooth-shaded, coarsely tessellated spheres on a floor in front of a wall, lit only by
/// an emissive panel above them (an area light, so their light is a noisy ray-traced signal):
/// a white diffuse one and a gold one as glossy as the default scene's. Their true shading is
/// smooth; after denoising it must not step at the triangle edges.
pub fn facet_test() -> Scene {
    use facet_test_facts::*;
    let mut s = Scene { name: "builtin:facet-test".into(), ..Default::default() };
    let plain = |name: &str, color: Vec4, metallic: f32, roughness: f32| Material {
        name: name.into(),
        base_color_factor: color,
        metallic_factor: metallic,
        roughness_factor: roughness,
        ..Default::default()
    };
    s.materials.push(plain("white", Vec4::new(0.8, 0.8, 0.8, 1.0), 0.0, 1.0));
    s.materials.push(plain("gold", Vec4::new(1.0, 0.78, 0.34, 1.0), 1.0, 0.25));
    s.materials.push(Material { emissive_factor: Vec3::splat(6.0), ..plain("panel", Vec4::ZERO, 0.0, 1.0) });
    s.meshes.push(quad(Vec3::ZERO, Vec3::Z * 8.0, Vec3::X * 8.0, 0));
    s.meshes.push(quad(Vec3::new(0.0, 2.0, -2.5), Vec3::X * 8.0, Vec3::Y * 4.0, 0));
    s.meshes.push(uv_sphere(1.0, SEGMENTS, RINGS, 0));
    s.meshes.push(uv_sphere(1.0, SEGMENTS, RINGS, 1));
    // Above the spheres, facing down, a little toward the camera.
    s.meshes.push(quad(Vec3::new(0.0, 3.5, 1.0), Vec3::X * 2.0, Vec3::Z * 1.5, 2));
    let at = [Vec3::ZERO, Vec3::ZERO, Vec3::new(-1.15, 1.0, 0.0), Vec3::new(1.15, 1.0, 0.0), Vec3::ZERO];
    for (i, p) in at.into_iter().enumerate() {
        s.nodes.push(node(&s.meshes[i].name, p));
        s.instances.push(Instance { mesh: i as u32, node: i as u32 });
    }
    let eye = Vec3::new(0.0, 1.3, 4.5);
    let mut cam = node("camera", eye);
    cam.rotation = Quat::from_mat4(&glam::Mat4::look_at_rh(eye, Vec3::new(0.0, 1.0, 0.0), Vec3::Y).inverse());
    s.nodes.push(cam);
    s.cameras.push(Camera {
        name: "front".into(),
        yfov: 0.65,
        aspect_ratio: None,
        znear: 0.05,
        zfar: Some(50.0),
        node: s.nodes.len() as u32 - 1,
    });
    s
}

/// Facts about `morph_test` that tests check against.
pub mod morph_test_facts {
    /// The camera sits at the origin looking down -Z with this vertical field of view.
    pub const YFOV: f32 = std::f32::consts::FRAC_PI_3;
    /// The morphing sheet: CELLS x CELLS quads spanning x, y in [-HALF, HALF] at z = SHEET_Z.
    pub const SHEET_Z: f32 = -4.0;
    pub const HALF: f32 = 1.5;
    pub const CELLS: u32 = 48;
    /// The weights run through their keys in this many seconds, then loop.
    pub const PERIOD: f32 = 2.0;
    pub const BACK_INSTANCE: u32 = 0;
    pub const SHEET_INSTANCE: u32 = 1;
    pub const SHEET_MESH: u32 = 1;
}

/// A back wall and a finely tessellated sheet facing the camera with two morph targets, a
/// bump towards the camera and a ripple along x, whose weights are animated (linear keys):
/// the deforming mesh of the BLAS refit and BVH refit tests.
pub fn morph_test() -> Scene {
    use morph_test_facts::*;
    let mut s = Scene { name: "builtin:morph-test".into(), ..Default::default() };
    s.materials.push(Material {
        name: "grey".into(),
        metallic_factor: 0.0,
        roughness_factor: 0.7,
        ..Default::default()
    });
    s.meshes.push(quad(Vec3::new(0.0, 0.0, -8.0), Vec3::X * 20.0, Vec3::Y * 20.0, 0));
    let mut vertices = Vec::new();
    let mut bump = Vec::new();
    let mut ripple = Vec::new();
    for j in 0..=CELLS {
        for i in 0..=CELLS {
            let (a, b) = (i as f32 / CELLS as f32, j as f32 / CELLS as f32);
            let (x, y) = ((a * 2.0 - 1.0) * HALF, (b * 2.0 - 1.0) * HALF);
            vertices.push(vertex(Vec3::new(x, y, 0.0), Vec3::Z, Vec3::X, [a, 1.0 - b]));
            bump.push(Vec3::Z * 0.8 * (-(x * x + y * y) * 1.5).exp());
            ripple.push(Vec3::new(0.0, 0.1 * (x * 4.0).cos(), 0.3 * (x * 4.0).sin()));
        }
    }
    let mut indices = Vec::new();
    let row = CELLS + 1;
    for j in 0..CELLS {
        for i in 0..CELLS {
            let (a, b) = (j * row + i, (j + 1) * row + i);
            indices.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    s.meshes.push(finish("sheet", vertices, indices, 0));
    s.morphs.push(super::Morph {
        mesh: SHEET_MESH,
        targets: vec![
            super::MorphTarget { positions: bump, normals: Vec::new() },
            super::MorphTarget { positions: ripple, normals: Vec::new() },
        ],
        weights: vec![0.0, 0.0],
        channels: vec![super::WeightChannel {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 0.5, 1.0, 1.5, PERIOD],
            values: vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0],
            period: PERIOD,
        }],
    });
    s.nodes.push(node("back", Vec3::ZERO));
    s.nodes.push(node("sheet", Vec3::new(0.0, 0.0, SHEET_Z)));
    s.nodes.push(node("camera", Vec3::ZERO));
    s.instances.push(Instance { mesh: 0, node: 0 });
    s.instances.push(Instance { mesh: SHEET_MESH, node: 1 });
    s.cameras.push(Camera {
        name: "origin".into(),
        yfov: YFOV,
        aspect_ratio: None,
        znear: 0.1,
        zfar: Some(100.0),
        node: 2,
    });
    s.lights.push(super::Light {
        name: "sun".into(),
        kind: super::LightKind::Directional,
        color: Vec3::ONE,
        intensity: 3.0,
        range: None,
        radius: 0.0,
        node: 2,
    });
    // The bounds cover every pose the weights reach (both in [0, 1]), for framing and culling.
    let (lo, hi) = (Vec3::new(-HALF, -HALF - 0.1, -0.3), Vec3::new(HALF, HALF + 0.1, 1.1));
    s.meshes[SHEET_MESH as usize].bounds_min = lo;
    s.meshes[SHEET_MESH as usize].bounds_max = hi;
    s
}

pub(super) fn finish(name: &str, vertices: Vec<Vertex>, indices: Vec<u32>, material: u32) -> Mesh {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for v in &vertices {
        lo = lo.min(Vec3::from(v.position));
        hi = hi.max(Vec3::from(v.position));
    }
    Mesh { name: name.into(), vertices, indices, material, bounds_min: lo, bounds_max: hi }
}

/// A parallelogram centred at `c` spanned by `u` and `v`, facing `u x v`.
pub fn quad(c: Vec3, u: Vec3, v: Vec3, material: u32) -> Mesh {
    let n = u.cross(v).normalize();
    let t = u.normalize();
    let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
    let vertices = corners.iter().map(|&(a, b)| vertex(c + u * a + v * b, n, t, [a + 0.5, 0.5 - b])).collect();
    finish("quad", vertices, vec![0, 1, 2, 0, 2, 3], material)
}

/// A closed UV sphere centred at the origin, counter-clockwise seen from outside.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32, material: u32) -> Mesh {
    let mut vertices = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            let t = Vec3::new(-phi.sin(), 0.0, -phi.cos());
            vertices.push(vertex(n * radius, n, t, [s as f32 / segments as f32, r as f32 / rings as f32]));
        }
    }
    let mut indices = Vec::new();
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            if r > 0 {
                indices.extend_from_slice(&[a, b, a + 1]);
            }
            if r + 1 < rings {
                indices.extend_from_slice(&[a + 1, b, b + 1]);
            }
        }
    }
    finish("uv_sphere", vertices, indices, material)
}

/// An axis-aligned box centred at the origin with half extents `h`, faces pointing out.
pub fn cuboid(h: Vec3, material: u32) -> Mesh {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let mut v = Vec3::ZERO;
            v[(axis + 2) % 3] = 1.0;
            if sign < 0.0 {
                std::mem::swap(&mut u, &mut v);
            }
            let base = vertices.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = (n + u * a + v * b) * h;
                vertices.push(vertex(p, n, u, [(a + 1.0) * 0.5, (1.0 - b) * 0.5]));
            }
            indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    finish("cuboid", vertices, indices, material)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's winding agrees with its vertex normals (front faces point outward).
    fn check_winding(m: &Mesh) {
        for t in m.indices.chunks(3) {
            let p = |i: u32| Vec3::from(m.vertices[i as usize].position);
            let ng = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            let n = Vec3::from(m.vertices[t[0] as usize].normal);
            assert!(ng.dot(n) > 0.0, "{}: triangle {t:?} winds against its normal", m.name);
        }
    }

    #[test]
    fn generated_meshes_wind_outward() {
        check_winding(&quad(Vec3::ZERO, Vec3::X, Vec3::Y, 0));
        check_winding(&uv_sphere(1.0, 16, 8, 0));
        check_winding(&cuboid(Vec3::ONE, 0));
    }
}
