//! The scene on the GPU: geometry pooled into one vertex and one index buffer, mesh, instance,
//! material and light tables, textures with CPU-built mip chains, and the scene descriptor set
//! (set 0) every pass binds. Geometry and textures are uploaded once; the instance table and
//! the lights are rewritten each frame from the animated pose, and deforming meshes' vertices
//! when their morph weights change (src/world/deform.rs) or their joints move
//! (src/world/skinning.rs).

use super::environment::EnvironmentData;
use super::lights::{self, LightTables};
use crate::accel::{self, RayAccel};
use crate::backend::Backend;
use crate::gpu::{
    self, Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSet, DescriptorSetLayout, Image,
    MemoryLocation, Recorder, Sampler, SamplerDesc, ShaderLibrary,
    staged::{self, StagedBuffer},
    vk,
};
use crate::scene::{self, LightKind, Pose, Scene};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

/// Set 0 binding numbers (shaders-glsl/common/scene.glsl).
pub mod binding {
    pub const FRAME: u32 = 0;
    pub const VERTICES: u32 = 1;
    pub const INDICES: u32 = 2;
    pub const MESHES: u32 = 3;
    pub const INSTANCES: u32 = 4;
    pub const MATERIALS: u32 = 5;
    pub const LIGHTS: u32 = 6;
    pub const TEXTURES: u32 = 7;
    // 8..11: the ray backend (src/accel).
    // 12..16: light sampling (src/world/lights.rs, shaders-glsl/common/light_sampling.glsl).
    pub const LIGHT_TABLE: u32 = 12;
    pub const EMITTERS: u32 = 13;
    pub const EMITTER_BASE: u32 = 14;
    pub const ENV_TEXELS: u32 = 15;
    pub const ENV_CDF: u32 = 16;
    /// The material model and the specular directional-albedo table (src/world/brdf.rs).
    pub const BRDF_DATA: u32 = 17;
    /// Last frame's positions of deforming vertices (src/world/skinning.rs, deform.rs).
    pub const PREV_POSITIONS: u32 = 18;
    /// The light grid over the resampled lights (src/world/light_grid.rs): header and cells,
    /// then the cells' entries.
    pub const LIGHT_GRID: u32 = 19;
    pub const LIGHT_GRID_ENTRIES: u32 = 20;
    /// What the hybrid frame learned each cell to see of each group of lights.
    pub const LIGHT_GRID_VISIBILITY: u32 = 21;
    /// The emissive triangles sorted into the light grid's groups.
    pub const EMITTER_GROUPS: u32 = 22;
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMesh {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub material: u32,
}

pub const INSTANCE_ALPHA_MASKED: u32 = 1;
/// The instance's mesh deforms (skinned or morphed): the G-buffer reads last frame's positions
/// from `prev_positions`. Mirrors INSTANCE_DEFORMS in common/scene.glsl.
pub const INSTANCE_DEFORMS: u32 = 2;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuInstance {
    pub object_to_world: [[f32; 4]; 4],
    pub prev_object_to_world: [[f32; 4]; 4],
    pub normal_to_world: [[f32; 4]; 4],
    pub mesh: u32,
    pub material: u32,
    pub flags: u32,
    pub pad: u32,
}

pub const MATERIAL_DOUBLE_SIDED: u32 = 1;
/// alphaMode BLEND (common/scene.glsl MATERIAL_BLEND): coverage by alpha.
pub const MATERIAL_BLEND: u32 = 2;
/// The least alpha a blended surface is drawn with: texels below it are holes.
pub const BLEND_VISIBLE_ALPHA: f32 = 1.0 / 256.0;

/// Texture slots per material (common/scene.glsl TEX_*).
pub const TEXTURE_SLOTS: usize = 6;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub base_color_factor: [f32; 4],
    pub emissive_factor: [f32; 3],
    pub alpha_cutoff: f32,
    pub metallic: f32,
    pub roughness: f32,
    pub normal_scale: f32,
    pub occlusion_strength: f32,
    pub tex: [i32; TEXTURE_SLOTS],
    pub uv_sets: u32,
    pub flags: u32,
    pub transmission: f32,
    pub ior: f32,
    pub thickness: f32,
    pub attenuation_distance: f32,
    pub attenuation_color: [f32; 3],
    pub uv_xform: [[f32; 4]; 2 * TEXTURE_SLOTS],
}

pub const LIGHT_DIRECTIONAL: u32 = 0;
pub const LIGHT_POINT: u32 = 1;
pub const LIGHT_SPOT: u32 = 2;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub range: f32,
    pub intensity: [f32; 3],
    pub radius: f32,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub pad: [u32; 2],
}

/// Per-frame constants (the `frame` uniform block).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub inv_view: [[f32; 4]; 4],
    pub prev_view_proj: [[f32; 4]; 4],
    pub jittered_view_proj: [[f32; 4]; 4],
    pub camera_pos: [f32; 3],
    pub znear: f32,
    pub prev_camera_pos: [f32; 3],
    pub zfar: f32,
    pub size: [u32; 2],
    pub frame_index: u32,
    pub light_count: u32,
    pub jitter: [f32; 2],
    pub time: f32,
    pub exposure: f32,
    pub sky_color: [f32; 3],
    pub instance_count: u32,
    pub flags: u32,
    /// Last frame's `jitter`: what a reprojection onto last frame's texels corrects for.
    pub prev_jitter: [f32; 2],
    /// The punctual lights with a channel of the shadows chain, lights 0.. (the frame plan's
    /// `chain_punctual`); the others are resampled.
    pub chain_punctual: u32,
}

/// `FrameUniforms::flags`: the first frame, or a camera cut: no temporal history is valid.
pub const FRAME_RESET_HISTORY: u32 = 1;
/// Set when the light differs from last frame's (a punctual light moved, dimmed or went off,
/// an emitter moved): what remembers light rather than geometry (the radiance cache) starts
/// anew. Mirrors FRAME_LIGHTS_CHANGED in common/scene.glsl.
pub const FRAME_LIGHTS_CHANGED: u32 = 2;

pub struct SceneGpu {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub meshes: Buffer,
    pub materials: Buffer,
    /// Rewritten every frame (device-local, staged: gpu::staged).
    pub instances: StagedBuffer,
    pub lights: StagedBuffer,
    pub frame: Buffer,
    /// Mesh table as uploaded (first index, count, base vertex) for draws.
    pub mesh_table: Vec<GpuMesh>,
    pub instance_meshes: Vec<u32>,
    _images: Vec<Image>,
    _samplers: Vec<Sampler>,
    pub set_layout: DescriptorSetLayout,
    pub set: DescriptorSet,
    pub accel: Box<dyn RayAccel>,
    pub light_tables: LightTables,
    _brdf_data: Buffer,
    prev_world: Option<Vec<Mat4>>,
    /// The punctual lights as last written, to tell whether this frame's differ.
    prev_lights: Option<Vec<GpuLight>>,
    /// Whether the lights written by the last `update_pose` differ from the frame's before.
    pub lights_changed: bool,
    deformer: Option<super::deform::Deformer>,
    /// One vec3 per vertex: where deforming vertices were last frame.
    prev_positions: Buffer,
    skinner: Option<super::skinning::Skinner>,
}

fn mat(m: Mat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d()
}

impl SceneGpu {
    #[allow(clippy::too_many_arguments)]
    pub fn upload(
        ctx: &Arc<Context>,
        pool: &CommandPool,
        shaders: &ShaderLibrary,
        scene: &Scene,
        pose: &Pose,
        backend: Backend,
        environment: &EnvironmentData,
        brdf: super::brdf::BrdfModel,
        light_grid: bool,
        chain: super::lights::ChainLights,
    ) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        // Acceleration-structure builds read the geometry by device address.
        let geometry_usage = match backend {
            Backend::RayQuery => {
                storage
                    | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                    | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
            }
            Backend::Compute => storage,
        };
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut mesh_table = Vec::with_capacity(scene.meshes.len());
        for m in &scene.meshes {
            mesh_table.push(GpuMesh {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: vertices.len() as i32,
                material: m.material,
            });
            vertices.extend_from_slice(&m.vertices);
            indices.extend_from_slice(&m.indices);
        }
        let vertices =
            gpu::upload::device_buffer(ctx, pool, "scene.vertices", bytemuck::cast_slice(&vertices), geometry_usage)?;
        let indices = gpu::upload::device_buffer(
            ctx,
            pool,
            "scene.indices",
            bytemuck::cast_slice(&indices),
            geometry_usage | vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        let meshes = gpu::upload::device_buffer(ctx, pool, "scene.meshes", bytemuck::cast_slice(&mesh_table), storage)?;
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();
        let materials =
            gpu::upload::device_buffer(ctx, pool, "scene.materials", bytemuck::cast_slice(&materials), storage)?;
        let instances = StagedBuffer::new(
            ctx,
            "scene.instances",
            (scene.instances.len().max(1) * size_of::<GpuInstance>()) as u64,
            storage,
        )?;
        let lights = StagedBuffer::new(
            ctx,
            "scene.lights",
            (scene.lights.len().max(1) * size_of::<GpuLight>()) as u64,
            storage,
        )?;
        let frame = Buffer::new(
            ctx,
            "frame",
            size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let (images, samplers, mut texture_bindings) = upload_textures(ctx, pool, scene)?;
        // Unused slots repeat slot 0 (white): every slot is a valid descriptor.
        texture_bindings.resize(texture_slots(texture_bindings.len()), texture_bindings[0]);

        let geometry = accel::Geometry {
            vertices: &vertices,
            indices: &indices,
            ranges: mesh_table.iter().map(|m| (m.first_index, m.base_vertex)).collect(),
        };
        let accel = accel::create(backend, ctx, pool, scene, pose, &geometry)?;
        let base_vertex: Vec<i32> = mesh_table.iter().map(|m| m.base_vertex).collect();
        let deformer = super::deform::Deformer::new(ctx, scene, &base_vertex, backend == Backend::RayQuery)?;
        // Only deforming vertices are ever read from it; where none deforms it is one element.
        let deforming = !scene.skinned.is_empty() || !scene.morphs.is_empty();
        let indexed_vertices = if deforming { scene.meshes.iter().map(|m| m.vertices.len()).sum() } else { 1 };
        let prev_positions = Buffer::new(
            ctx,
            "scene.prev_positions",
            (indexed_vertices * size_of::<[f32; 3]>()) as u64,
            // The skinning pass writes its meshes' range, the deformer copies the morphs' in.
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let skinner = super::skinning::Skinner::new(
            ctx,
            pool,
            shaders,
            scene,
            &base_vertex,
            (&vertices, &prev_positions),
            backend == Backend::RayQuery,
        )?;
        let mut bindings = scene_bindings(texture_bindings.len() as u32);
        bindings.extend(accel.bindings());
        bindings.extend(lights::bindings());
        let light_tables = LightTables::new(ctx, pool, scene, pose, environment, light_grid, chain)?;
        let brdf_data = gpu::upload::device_buffer(ctx, pool, "brdf_data", &super::brdf::gpu_data(brdf), storage)?;
        let set_layout = DescriptorSetLayout::new(ctx, &bindings, false)?;
        let set = DescriptorSet::new(ctx, &set_layout)?;
        set.write_buffer(binding::FRAME, BindingKind::UniformBuffer, &frame);
        set.write_buffer(binding::VERTICES, BindingKind::StorageBuffer, &vertices);
        set.write_buffer(binding::INDICES, BindingKind::StorageBuffer, &indices);
        set.write_buffer(binding::MESHES, BindingKind::StorageBuffer, &meshes);
        set.write_buffer(binding::INSTANCES, BindingKind::StorageBuffer, instances.buffer());
        set.write_buffer(binding::MATERIALS, BindingKind::StorageBuffer, &materials);
        set.write_buffer(binding::LIGHTS, BindingKind::StorageBuffer, lights.buffer());
        set.write_sampled_images(binding::TEXTURES, &texture_bindings);
        accel.write_set(&set);
        light_tables.write_set(&set);
        set.write_buffer(binding::BRDF_DATA, BindingKind::StorageBuffer, &brdf_data);
        set.write_buffer(binding::PREV_POSITIONS, BindingKind::StorageBuffer, &prev_positions);

        let mut gpu = Self {
            vertices,
            indices,
            meshes,
            materials,
            instances,
            lights,
            frame,
            instance_meshes: scene.instances.iter().map(|i| i.mesh).collect(),
            mesh_table,
            _images: images,
            _samplers: samplers,
            set_layout,
            set,
            accel,
            light_tables,
            _brdf_data: brdf_data,
            prev_world: None,
            prev_lights: None,
            lights_changed: true,
            deformer,
            prev_positions,
            skinner,
        };
        gpu.update_pose(scene, pose)?;
        Ok(gpu)
    }

    /// Rewrites instances (with last frame's transforms for motion vectors) and lights.
    pub fn update_pose(&mut self, scene: &Scene, pose: &Pose) -> Result<()> {
        let prev = self.prev_world.as_ref().unwrap_or(&pose.world);
        let instances: Vec<GpuInstance> = scene
            .instances
            .iter()
            .map(|inst| {
                let m = pose.world[inst.node as usize];
                let mesh = &scene.meshes[inst.mesh as usize];
                let masked = scene.materials[mesh.material as usize].alpha_mode.cutoff().is_some();
                let deforms = scene.deforms(inst.mesh);
                GpuInstance {
                    object_to_world: mat(m),
                    prev_object_to_world: mat(prev[inst.node as usize]),
                    normal_to_world: mat(m.inverse().transpose()),
                    mesh: inst.mesh,
                    material: mesh.material,
                    flags: if masked { INSTANCE_ALPHA_MASKED } else { 0 } | if deforms { INSTANCE_DEFORMS } else { 0 },
                    pad: 0,
                }
            })
            .collect();
        self.instances.write(0, bytemuck::cast_slice(&instances))?;
        let lights = gpu_lights(scene, pose);
        self.lights.write(0, bytemuck::cast_slice(&lights))?;
        let punctual_changed = self.prev_lights.as_ref().is_none_or(|prev| {
            bytemuck::cast_slice::<GpuLight, u8>(prev) != bytemuck::cast_slice::<GpuLight, u8>(&lights)
        });
        if punctual_changed {
            self.light_tables.update_grid(&lights, scene.bounds(pose))?;
        }
        self.prev_lights = Some(lights);
        let mut changed = Vec::new();
        if let Some(deformer) = &mut self.deformer {
            changed.extend(deformer.update(scene, pose)?);
        }
        if let Some(skinner) = &mut self.skinner {
            changed.extend(skinner.update(scene, pose)?);
        }
        if !changed.is_empty() {
            let meshes: Vec<(u32, &[Vec3])> = changed.iter().map(|(m, p)| (*m, p.as_slice())).collect();
            self.accel.update_geometry(scene, pose, &meshes)?;
        }
        self.accel.update_instances(scene, pose)?;
        let emitters_moved = self.light_tables.update(scene, pose, &changed)?;
        self.lights_changed = punctual_changed || emitters_moved;
        self.prev_world = Some(pose.world.clone());
        Ok(())
    }

    /// Puts `tables` (made for another shadows chain, with the scene's lights in its new
    /// shading order: `Renderer::rank_chain_for`) in place of the light tables, in the scene's
    /// descriptor set too. Everything else stays; the next `update_pose` writes the lights in
    /// their new order and rebuilds the light grid. Call between frames: the set must not be in
    /// use.
    pub fn set_light_tables(&mut self, tables: LightTables) {
        tables.write_set(&self.set);
        let old = std::mem::replace(&mut self.light_tables, tables);
        self.light_tables.inherit_shapes(old);
        self.prev_lights = None;
    }

    /// Records what makes the GPU scene current before the frame's passes: a rebuilt light grid
    /// copied in, deformed vertices copied into the vertex buffer, then the ray backend's
    /// structures refit or rebuilt over them.
    pub fn record_update(&mut self, rec: &Recorder) -> Result<()> {
        staged::record_copies(rec, &mut [&mut self.instances, &mut self.lights]);
        self.light_tables.record(rec);
        if let Some(deformer) = &mut self.deformer {
            deformer.record(rec, &self.vertices, &self.prev_positions);
        }
        if let Some(skinner) = &mut self.skinner {
            skinner.record(rec);
        }
        self.accel.record_update(rec)
    }

    pub fn write_frame(&mut self, u: &FrameUniforms) -> Result<()> {
        self.frame.write(0, bytemuck::bytes_of(u))
    }
}

/// The size of the texture array for `count` textures: a power of two, at least 64. The layout
/// is part of what a driver compiles a pipeline against (lavapipe compiles again, for minutes,
/// for every new layout), so scenes with different texture counts should share one.
fn texture_slots(count: usize) -> usize {
    count.next_power_of_two().max(64)
}

fn scene_bindings(texture_count: u32) -> Vec<Binding> {
    let b = |binding, kind| Binding { binding, kind, count: 1 };
    vec![
        b(binding::FRAME, BindingKind::UniformBuffer),
        b(binding::VERTICES, BindingKind::StorageBuffer),
        b(binding::INDICES, BindingKind::StorageBuffer),
        b(binding::MESHES, BindingKind::StorageBuffer),
        b(binding::INSTANCES, BindingKind::StorageBuffer),
        b(binding::MATERIALS, BindingKind::StorageBuffer),
        b(binding::LIGHTS, BindingKind::StorageBuffer),
        Binding { binding: binding::TEXTURES, kind: BindingKind::SampledImage, count: texture_count },
        b(binding::BRDF_DATA, BindingKind::StorageBuffer),
        b(binding::PREV_POSITIONS, BindingKind::StorageBuffer),
    ]
}

fn gpu_material(m: &scene::Material) -> GpuMaterial {
    // In the order of common/scene.glsl's TEX_* slots.
    let slots: [Option<scene::TextureRef>; TEXTURE_SLOTS] = [
        m.base_color_texture,
        m.metallic_roughness_texture,
        m.normal_texture,
        m.occlusion_texture,
        m.emissive_texture,
        m.transmission_texture,
    ];
    let mut tex = [-1i32; TEXTURE_SLOTS];
    let mut uv_sets = 0u32;
    let mut uv_xform = [[0.0f32; 4]; 2 * TEXTURE_SLOTS];
    for (i, slot) in slots.iter().enumerate() {
        let xf = slot.map(|s| s.transform).unwrap_or(glam::Mat3::IDENTITY);
        // Rows of the 2x3 affine part: uv' = (row0 . (u, v, 1), row1 . (u, v, 1)).
        uv_xform[2 * i] = [xf.x_axis.x, xf.y_axis.x, xf.z_axis.x, 0.0];
        uv_xform[2 * i + 1] = [xf.x_axis.y, xf.y_axis.y, xf.z_axis.y, 0.0];
        if let Some(s) = slot {
            // Texture 0 of the GPU table is the white fallback; scene textures follow.
            tex[i] = s.texture as i32 + 1;
            if s.uv_set == 1 {
                uv_sets |= 1 << i;
            }
        }
    }
    GpuMaterial {
        base_color_factor: m.base_color_factor.to_array(),
        emissive_factor: m.emissive_factor.to_array(),
        alpha_cutoff: match m.alpha_mode {
            scene::AlphaMode::Blend => BLEND_VISIBLE_ALPHA,
            mode => mode.cutoff().unwrap_or(-1.0),
        },
        metallic: m.metallic_factor,
        roughness: m.roughness_factor,
        normal_scale: m.normal_scale,
        occlusion_strength: m.occlusion_strength,
        tex,
        uv_sets,
        flags: if m.double_sided { MATERIAL_DOUBLE_SIDED } else { 0 }
            | if m.alpha_mode == scene::AlphaMode::Blend { MATERIAL_BLEND } else { 0 },
        transmission: m.transmission,
        ior: m.ior,
        thickness: m.thickness,
        attenuation_distance: m.attenuation_distance,
        attenuation_color: m.attenuation_color.to_array(),
        uv_xform,
    }
}

/// The scene's punctual lights in world space at a pose.
pub fn gpu_lights(scene: &Scene, pose: &Pose) -> Vec<GpuLight> {
    scene.lights.iter().map(|l| gpu_light(l, &pose.world[l.node as usize])).collect()
}

fn gpu_light(l: &scene::Light, world: &Mat4) -> GpuLight {
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
    let (kind, cos_inner, cos_outer) = match l.kind {
        LightKind::Directional => (LIGHT_DIRECTIONAL, 1.0, 1.0),
        LightKind::Point => (LIGHT_POINT, -1.0, -1.0),
        LightKind::Spot { inner_cone, outer_cone } => (LIGHT_SPOT, inner_cone.cos(), outer_cone.cos()),
    };
    GpuLight {
        position: position.to_array(),
        kind,
        direction: direction.to_array(),
        range: l.range.unwrap_or(0.0),
        intensity: (l.color * l.intensity).to_array(),
        radius: l.radius,
        cos_inner,
        cos_outer,
        pad: [0; 2],
    }
}

type TextureUpload = (Vec<Image>, Vec<Sampler>, Vec<(vk::ImageView, vk::Sampler)>);

/// Uploads every image once and pairs images with samplers into the bindless table. Entry 0
/// is a 1x1 white texture, the stand-in for missing images.
fn upload_textures(ctx: &Arc<Context>, pool: &CommandPool, scene: &Scene) -> Result<TextureUpload> {
    let mut images = vec![gpu::upload::texture(ctx, pool, "white", &[(1, 1, vec![255; 4])])?];
    for img in &scene.images {
        let levels = super::mips::chain(img.width, img.height, &img.rgba8);
        images.push(gpu::upload::texture(ctx, pool, &img.name, &levels)?);
    }
    let mut samplers = Vec::new();
    let mut sampler_index: HashMap<SamplerDesc, usize> = HashMap::new();
    let mut get_sampler = |d: SamplerDesc, samplers: &mut Vec<Sampler>| -> Result<vk::Sampler> {
        if let Some(&i) = sampler_index.get(&d) {
            return Ok(samplers[i].raw);
        }
        samplers.push(Sampler::new(ctx, d)?);
        sampler_index.insert(d, samplers.len() - 1);
        Ok(samplers[samplers.len() - 1].raw)
    };
    let mut table = vec![(images[0].view, get_sampler(SamplerDesc::LINEAR_CLAMP, &mut samplers)?)];
    for t in &scene.textures {
        let view = t.image.map(|i| images[i as usize + 1].view).unwrap_or(images[0].view);
        table.push((view, get_sampler(sampler_desc(&t.sampler), &mut samplers)?));
    }
    Ok((images, samplers, table))
}

fn sampler_desc(s: &scene::Sampler) -> SamplerDesc {
    let wrap = |w| match w {
        scene::Wrap::Repeat => vk::SamplerAddressMode::REPEAT,
        scene::Wrap::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        scene::Wrap::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
    SamplerDesc {
        mag_linear: s.mag_filter == scene::Filter::Linear,
        min_linear: s.min_filter == scene::Filter::Linear,
        mipmaps: s.mipmaps,
        wrap_u: wrap(s.wrap_s),
        wrap_v: wrap(s.wrap_t),
    }
}
