//! The scene: everything the renderer draws, in a form independent of the file it came from.
//!
//! Data flows one way: a loader (glTF, or a built-in scene) fills a [`Scene`]; the GPU layer
//! uploads it; passes read it. Geometry is shared: a [`Mesh`] is stored once and drawn by any
//! number of [`Instance`]s. The node hierarchy is kept (flattened, parents before children) so
//! that node animations can be played back: [`Scene::evaluate`] turns a time into world
//! transforms for every node, from which instance, light and camera poses follow.

pub mod animation;
pub mod builtin;
pub mod builtin_many_lights;
pub mod builtin_skin;
pub mod builtin_stability;
pub mod gltf;
pub mod limits;
pub mod morph;
pub mod skin;
pub mod tangents;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use std::path::PathBuf;

pub use self::gltf::{LoadOptions, load_gltf, load_gltf_bytes};
pub use limits::Limits;
pub use morph::{Morph, MorphTarget, WeightChannel};
pub use skin::{Influence, Skin, SkinnedMesh};

/// A scene-loading failure. The message always names the file and the problem.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct SceneError {
    pub path: PathBuf,
    pub problem: String,
}

impl SceneError {
    pub fn new(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        Self { path: path.into(), problem: problem.into() }
    }
}

/// One vertex as the rasteriser and the ray tracers both read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// xyz = tangent, w = bitangent sign (glTF convention: B = cross(N, T) * w).
    pub tangent: [f32; 4],
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
}

/// Triangle geometry in the mesh's local space; one glTF primitive becomes one `Mesh`.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub vertices: Vec<Vertex>,
    /// Triangle list, three indices per triangle (non-indexed primitives get 0..n).
    pub indices: Vec<u32>,
    pub material: u32,
    /// Local-space bounds.
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Texels with alpha below the cutoff are discarded (raster) or ignored (rays).
    Mask {
        cutoff: f32,
    },
    /// glTF BLEND, as coverage: the surface covers the share alpha of each point and the rest
    /// of the light passes straight through (the reference decides per path; the hybrid frame
    /// traces what lies behind in the reflections pass). Shadow rays see it masked at 0.5
    /// ([`AlphaMode::cutoff`]).
    Blend,
}

impl AlphaMode {
    /// The alpha cutoff the renderer applies, or `None` for opaque geometry.
    pub fn cutoff(self) -> Option<f32> {
        match self {
            AlphaMode::Opaque => None,
            AlphaMode::Mask { cutoff } => Some(cutoff),
            AlphaMode::Blend => Some(0.5),
        }
    }
}

/// A reference from a material slot to a texture, with KHR_texture_transform folded in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: u32,
    /// Which UV set (0 or 1) the slot reads.
    pub uv_set: u32,
    /// uv' = transform * vec3(uv, 1): offset, rotation and scale of KHR_texture_transform,
    /// identity when the extension is absent.
    pub transform: Mat3,
}

/// glTF metallic-roughness material.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color_factor: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    /// Roughness in G, metallic in B (glTF layout).
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    pub occlusion_texture: Option<TextureRef>,
    pub occlusion_strength: f32,
    /// Linear emitted radiance scale: emissive_factor * KHR_materials_emissive_strength.
    pub emissive_factor: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// KHR_materials_transmission: the share of the dielectric's diffuse light that passes
    /// through the surface instead (0 = opaque).
    pub transmission: f32,
    /// Its texture: transmission scales by the red channel.
    pub transmission_texture: Option<TextureRef>,
    /// KHR_materials_ior: index of refraction of the dielectric (1.5 gives glTF's F0 of 0.04).
    pub ior: f32,
    /// KHR_materials_volume: 0 means thin-walled (light passes straight through the surface);
    /// above 0 the mesh bounds a volume that refracts and absorbs.
    pub thickness: f32,
    /// Beer-Lambert absorption in the volume: light keeps `attenuation_color` after
    /// `attenuation_distance` (infinite: no absorption).
    pub attenuation_color: Vec3,
    pub attenuation_distance: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_factor: Vec3::ZERO,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            thickness: 0.0,
            attenuation_color: Vec3::ONE,
            attenuation_distance: f32::INFINITY,
        }
    }
}

impl Material {
    /// True when the material emits light (a candidate area light).
    pub fn is_emissive(&self) -> bool {
        self.emissive_factor.max_element() > 0.0
    }

    /// True when light may pass through the surface (KHR_materials_transmission; where the
    /// metallic texture makes the surface a metal, none does).
    pub fn is_transmissive(&self) -> bool {
        self.transmission > 0.0
    }

    /// True when rays must look at each triangle they cross before counting it as a hit (a
    /// non-opaque instance, in both ray backends): the alpha test, and shadow rays' passage
    /// through blended and thin-walled transmissive surfaces (common/hit.glsl).
    pub fn rays_test_candidates(&self) -> bool {
        self.alpha_mode.cutoff().is_some() || (self.is_transmissive() && self.thickness <= 0.0)
    }
}

/// Decoded image pixels, always RGBA8. Colour-space decoding (sRGB for base colour and
/// emissive) happens in the shader, so one image can serve slots of either kind.
#[derive(Clone, Debug)]
pub struct Image {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    Linear,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    pub mag_filter: Filter,
    pub min_filter: Filter,
    /// Whether minification uses mipmaps (glTF *_MIPMAP_* filters, or no filter given).
    pub mipmaps: bool,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

impl Default for Sampler {
    fn default() -> Self {
        Self {
            mag_filter: Filter::Linear,
            min_filter: Filter::Linear,
            mipmaps: true,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
        }
    }
}

/// A texture = an image and how to sample it. `image` is `None` for glTF textures whose
/// source is missing or failed to decode; they sample as white (the loader warns).
#[derive(Clone, Debug)]
pub struct Texture {
    pub image: Option<u32>,
    pub sampler: Sampler,
}

/// A node of the flattened hierarchy. Nodes are ordered so that a parent precedes its children.
#[derive(Clone, Debug)]
pub struct Node {
    pub name: String,
    pub parent: Option<u32>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Node {
    pub fn local_matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// A mesh drawn at a node's world transform.
#[derive(Clone, Debug)]
pub struct Instance {
    pub mesh: u32,
    pub node: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Shines along the node's -Z axis.
    Directional,
    Point,
    /// Cone along the node's -Z axis, angles in radians.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
}

/// KHR_lights_punctual light attached to a node.
#[derive(Clone, Debug)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Candela (point, spot) or lux (directional), as in KHR_lights_punctual.
    pub intensity: f32,
    /// Distance beyond which the light has no effect; `None` = infinite.
    pub range: Option<f32>,
    /// Emitter radius for soft shadows (0 = hard); read from the light's `extras.radius`.
    pub radius: f32,
    pub node: u32,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub name: String,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Aspect ratio from the file, if any; the renderer uses the output's aspect.
    pub aspect_ratio: Option<f32>,
    pub znear: f32,
    pub zfar: Option<f32>,
    /// The camera looks along the node's -Z axis, +Y up.
    pub node: u32,
}

/// A node animation: channels that drive translation, rotation or scale over time.
#[derive(Clone, Debug)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<animation::Channel>,
}

impl Animation {
    /// Time of the last keyframe of any channel.
    pub fn duration(&self) -> f32 {
        self.channels.iter().map(|c| c.duration()).fold(0.0, f32::max)
    }
}

/// A complete scene.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    /// The file the scene came from (`None` for built-in scenes).
    pub source: Option<PathBuf>,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub images: Vec<Image>,
    pub textures: Vec<Texture>,
    pub nodes: Vec<Node>,
    pub instances: Vec<Instance>,
    pub lights: Vec<Light>,
    pub cameras: Vec<Camera>,
    pub animations: Vec<Animation>,
    /// Morph targets of the deforming meshes, at most one per mesh.
    pub morphs: Vec<Morph>,
    /// Skeletons of the skinned meshes.
    pub skins: Vec<Skin>,
    /// Meshes deformed by a skin, at most one entry per mesh; none of them also morphs.
    pub skinned: Vec<SkinnedMesh>,
    /// Recoverable defects found while loading, each naming the defect.
    pub warnings: Vec<String>,
}

/// World-space pose of every node at one time.
#[derive(Clone, Debug)]
pub struct Pose {
    pub time: f32,
    pub world: Vec<Mat4>,
}

impl Scene {
    /// Evaluates all animations at `time` (seconds; each animation loops over its duration)
    /// and returns the world matrix of every node.
    pub fn evaluate(&self, time: f32) -> Pose {
        let mut locals: Vec<(Vec3, Quat, Vec3)> =
            self.nodes.iter().map(|n| (n.translation, n.rotation, n.scale)).collect();
        for anim in &self.animations {
            let d = anim.duration();
            let t = if d > 0.0 { time.rem_euclid(d) } else { 0.0 };
            for ch in &anim.channels {
                ch.apply(t, &mut locals);
            }
        }
        let mut world = Vec::with_capacity(self.nodes.len());
        for (i, node) in self.nodes.iter().enumerate() {
            let (t, r, s) = locals[i];
            let local = Mat4::from_scale_rotation_translation(s, r, t);
            let m = match node.parent {
                Some(p) => world[p as usize] * local,
                None => local,
            };
            world.push(m);
        }
        Pose { time, world }
    }

    /// True when any animation moves any node.
    pub fn is_animated(&self) -> bool {
        self.animations.iter().any(|a| !a.channels.is_empty()) || self.morphs.iter().any(Morph::is_animated)
    }

    /// The morph targets of `mesh`, if it deforms.
    pub fn morph_of(&self, mesh: u32) -> Option<&Morph> {
        self.morphs.iter().find(|m| m.mesh == mesh)
    }

    /// The skin deforming `mesh`, if any.
    pub fn skinned_of(&self, mesh: u32) -> Option<&SkinnedMesh> {
        self.skinned.iter().find(|s| s.mesh == mesh)
    }

    /// Whether `mesh`'s vertices change from frame to frame (morph targets or a skin): its
    /// bottom-level structure is built for updates.
    pub fn deforms(&self, mesh: u32) -> bool {
        self.morph_of(mesh).is_some() || self.skinned_of(mesh).is_some()
    }

    /// World-space bounds of all instances at a pose.
    pub fn bounds(&self, pose: &Pose) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for inst in &self.instances {
            let m = pose.world[inst.node as usize];
            let mesh = &self.meshes[inst.mesh as usize];
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
        }
        if lo.x > hi.x { (Vec3::ZERO, Vec3::ZERO) } else { (lo, hi) }
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }
}

/// Texture-transform matrix of KHR_texture_transform: T * R * S, applied to vec3(uv, 1).
pub fn uv_transform(offset: Vec2, rotation: f32, scale: Vec2) -> Mat3 {
    let t = Mat3::from_cols(Vec3::X, Vec3::Y, offset.extend(1.0));
    let (s, c) = rotation.sin_cos();
    // glTF rotates UVs counter-clockwise in UV space, which with V pointing down is this matrix.
    let r = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
    let sc = Mat3::from_diagonal(scale.extend(1.0));
    t * r * sc
}
