//! The light tables behind Monte Carlo light sampling (shaders-glsl/common/light_sampling.glsl):
//! the emissive triangles, one CDF over every light by power, and the environment's texels and
//! CDFs, bound in set 0 at bindings 12..16; and the light grid over the resampled lights
//! (`light_grid`), at bindings 19 to 21, with the emissive triangles sorted into its groups at
//! binding 22.
//!
//! The light grid lives in device-local memory: gi reads its entries for every candidate and
//! counts into its visibility with atomics, and light_grid_update rewrites the entries' CDFs,
//! every frame. A rebuild (the punctual lights changed) is staged in host-visible memory and
//! copied in by `record`, with the frame's commands.
//!
//! Emissive triangles are stored in world space, rebuilt on the CPU when an emissive instance
//! moves. The alternative, storing (instance, triangle) and transforming in the shader, would
//! save that rebuild but not the CDF's: a triangle's power is its area, which an instance's
//! scale changes, so the table must follow the pose either way. Emitters are few (lamps, not
//! scenery), the rebuild is linear in them and skipped for poses where none moved, and the
//! shader then samples a triangle with no matrix work.
//!
//! Power, the selection weight, is the luminance flux each light sends into the scene's
//! bounding sphere (radius r): 4 pi I for a point light, 2 pi (1 - cos outer) I for a spot
//! (its cone), E pi r^2 for a directional light, pi L A per emitting side of a triangle, and
//! 4 pi^2 r^2 L_mean for the environment. It only steers variance; any positive weight for a
//! light that can contribute keeps the estimate unbiased.

use super::environment::{EnvironmentData, luminance};
use super::light_grid::{
    self, GpuEmitterGroup, GpuEmitterGroupEntry, GpuLightGridEntry, GpuLightGridHeader, GpuLightGridVisibility,
    LightGrid,
};
use super::scene_gpu::{GpuLight, binding};
use crate::gpu::{
    self, Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSet, MemoryLocation, Recorder,
    staged::{self, StagedBuffer},
    vk,
};
use crate::scene::{LightKind, Pose, Scene};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// The shadows chain's channels: the punctual and mesh lights that bring the most light to the
/// first view take one each (`chain_lights`), the punctual ones first in `shading_order`; the
/// other punctual lights are resampled. Mirrors SHADOW_LIGHTS in common/shadows_common.glsl.
pub const SHADOWED_LIGHTS: usize = 4;

pub const LIGHT_KIND_PUNCTUAL: u32 = 0;
pub const LIGHT_KIND_EMITTER: u32 = 1;
pub const LIGHT_KIND_ENVIRONMENT: u32 = 2;
pub const EMITTER_DOUBLE_SIDED: u32 = 1;
/// The emitter belongs to a mesh light of the shadows chain (`chain_lights`): composite
/// shades it, so gi's reservoirs leave it out. Mirrors EMITTER_IN_CHAIN in
/// common/light_sampling.glsl.
pub const EMITTER_IN_CHAIN: u32 = 2;
/// The most triangles a mesh light of the shadows chain may have: composite integrates each
/// one's unshadowed light in closed form, per pixel, and the shadows pass keeps each one's share
/// of it. Mirrors MESH_LIGHT_MAX_TRIANGLES in common/mesh_lights.glsl.
pub const MAX_CHAIN_EMITTER_TRIANGLES: usize = 8;
/// Bytes before the emitters' groups at binding 22: their count, padded.
const EMITTER_GROUPS_HEADER: usize = 16;
/// `emitter_base` of an instance that emits nothing.
pub const NO_EMITTER: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLightTableHeader {
    pub entry_count: u32,
    pub first_emitter_entry: u32,
    pub env_entry: u32,
    pub env_width: u32,
    pub env_height: u32,
    pub env_constant: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLightEntry {
    pub kind: u32,
    pub index: u32,
    pub cdf: f32,
    pub pmf: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEmitter {
    pub p0: [f32; 3],
    pub instance: u32,
    pub e1: [f32; 3],
    pub primitive: u32,
    pub e2: [f32; 3],
    pub area: f32,
    pub normal: [f32; 3],
    pub flags: u32,
}

/// The set-0 bindings this module fills.
pub fn bindings() -> Vec<Binding> {
    [
        binding::LIGHT_TABLE,
        binding::EMITTERS,
        binding::EMITTER_BASE,
        binding::ENV_TEXELS,
        binding::ENV_CDF,
        binding::LIGHT_GRID,
        binding::LIGHT_GRID_ENTRIES,
        binding::LIGHT_GRID_VISIBILITY,
        binding::EMITTER_GROUPS,
    ]
    .into_iter()
    .map(|b| Binding { binding: b, kind: BindingKind::StorageBuffer, count: 1 })
    .collect()
}

pub struct LightTables {
    /// Header and CDF entries; rewritten when emitters move.
    table: StagedBuffer,
    emitters: StagedBuffer,
    emitter_base: Buffer,
    env_texels: Buffer,
    env_cdf: Buffer,
    /// The light grid's header and cells, and its entries (at most `grid_capacity`); rebuilt
    /// when the punctual lights change.
    grid: StagedBuffer,
    grid_entries: StagedBuffer,
    /// Per cell and light group, the visibility the hybrid frame learns
    /// (src/passes/light_grid_update.rs); reset when a rebuild moves the grid's cells.
    /// Device-local.
    grid_visibility: Buffer,
    grid_capacity: usize,
    /// The emissive triangles by the grid's groups (`light_grid::emitter_groups`); rewritten
    /// when emitters move or the grid's cells do.
    emitter_groups: StagedBuffer,
    /// What the grid's emitter groups are built from: each emissive triangle's centroid and
    /// power as last built, a mesh light of the shadows chain's with power 0 (see `update`).
    group_points: Vec<(Vec3, f32)>,
    /// Whether the next `record` resets the visibility.
    visibility_reset_pending: bool,
    /// The header of the grid last written (where its cells are).
    grid_header: GpuLightGridHeader,
    /// The grid built at load to size `grid_entries`, with the lights and bounds it was built
    /// for: the first `update_grid` (SceneGpu::upload's, for the same pose) writes it instead of
    /// building it again (4000 lights without a range: 2M entries, about 70 ms on 2 cores).
    grid_at_load: Option<(Vec<GpuLight>, (Vec3, Vec3), LightGrid)>,
    /// Off (`Settings::light_grid`): the grid stays empty and every point draws the resampled
    /// lights by power from all of them.
    grid_enabled: bool,
    /// Instances whose material emits, and their transforms when the table was last built.
    emissive: Vec<u32>,
    /// Emissive meshes that deform (morph targets, skins): their vertices' object-space
    /// positions as last deformed, which the emitters are built from in place of the mesh's.
    shapes: Shapes,
    /// The instances that are mesh lights of the shadows chain (the frame plan's).
    chain: Vec<u32>,
    /// The punctual lights with a channel of the chain, which the grid leaves out.
    chain_punctual: usize,
    built_for: Option<Vec<Mat4>>,
    /// Powers of the punctual lights and of the environment (fixed for the scene).
    punctual_powers: Vec<f32>,
    env_power: f32,
    env_header: (u32, u32, [f32; 3]),
    /// Mean environment radiance: the hybrid frame's sky colour.
    pub sky: Vec3,
}

impl LightTables {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &CommandPool,
        scene: &Scene,
        pose: &Pose,
        env: &EnvironmentData,
        grid_enabled: bool,
        chain: ChainLights,
    ) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let (bases, emitter_count) = emitter_bases(scene);
        let entry_count = scene.lights.len() + emitter_count as usize + 1;
        let table = StagedBuffer::new(
            ctx,
            "lights.table",
            (size_of::<GpuLightTableHeader>() + entry_count * size_of::<GpuLightEntry>()) as u64,
            storage,
        )?;
        let emitters = StagedBuffer::new(
            ctx,
            "lights.emitters",
            (emitter_count.max(1) as usize * size_of::<GpuEmitter>()) as u64,
            storage,
        )?;
        let emitter_base =
            gpu::upload::device_buffer(ctx, pool, "lights.emitter_base", bytemuck::cast_slice(&bases), storage)?;
        let env_texels =
            gpu::upload::device_buffer(ctx, pool, "lights.env_texels", bytemuck::cast_slice(&env.texels), storage)?;
        let env_cdf = gpu::upload::device_buffer(ctx, pool, "lights.env_cdf", bytemuck::cast_slice(&env.cdf), storage)?;
        let radius = scene_radius(scene, pose);
        let punctual_powers: Vec<f32> = scene.lights.iter().map(|l| punctual_power(l, radius)).collect();
        let grid_cells = (light_grid::RESOLUTION as usize).pow(3);
        let device_storage = storage | vk::BufferUsageFlags::TRANSFER_DST;
        let grid_bytes = size_of::<GpuLightGridHeader>() + grid_cells * size_of::<[u32; 2]>();
        let grid = StagedBuffer::new(ctx, "lights.grid", grid_bytes as u64, storage)?;
        // Room for the grid of the lights as they are now, twice over, so that lights that move
        // rarely need a coarser grid, up to MAX_ENTRIES; and at least for every resampled light
        // once (one cell).
        // (None with the grid off: it stays empty.)
        let grid_at_load = grid_enabled.then(|| {
            let (lights, bounds) = (super::scene_gpu::gpu_lights(scene, pose), scene.bounds(pose));
            let grid = build_grid(
                &lights,
                &punctual_powers,
                chain.punctual,
                bounds,
                light_grid::MAX_ENTRIES,
                emitter_count > 0,
            );
            (lights, bounds, grid)
        });
        let at_load_entries = grid_at_load.as_ref().map_or(0, |(_, _, grid)| grid.entries.len());
        let grid_capacity = (2 * at_load_entries).min(light_grid::MAX_ENTRIES).max(scene.lights.len()).max(1);
        let entries_bytes = grid_capacity * size_of::<GpuLightGridEntry>();
        let grid_entries = StagedBuffer::new(ctx, "lights.grid_entries", entries_bytes as u64, storage)?;
        let emitter_groups = StagedBuffer::new(
            ctx,
            "lights.emitter_groups",
            (EMITTER_GROUPS_HEADER
                + light_grid::EMITTER_GROUPS as usize * size_of::<GpuEmitterGroup>()
                + emitter_count.max(1) as usize * size_of::<GpuEmitterGroupEntry>()) as u64,
            storage,
        )?;
        let visibility_count =
            if grid_enabled { light_grid::RESOLUTION.pow(3) * light_grid::GROUP_COUNT } else { 1 } as usize;
        let grid_visibility = Buffer::new(
            ctx,
            "lights.grid_visibility",
            (visibility_count * size_of::<GpuLightGridVisibility>()) as u64,
            device_storage,
            MemoryLocation::GpuOnly,
        )?;
        let mut tables = Self {
            table,
            emitters,
            emitter_base,
            env_texels,
            env_cdf,
            grid,
            grid_entries,
            grid_visibility,
            grid_capacity,
            emitter_groups,
            group_points: Vec::new(),
            // The device-local buffer starts undefined.
            visibility_reset_pending: true,
            grid_header: GpuLightGridHeader::default(),
            grid_at_load,
            grid_enabled,
            emissive: emissive_instances(scene),
            chain: chain.meshes.to_vec(),
            chain_punctual: chain.punctual,
            built_for: None,
            shapes: Shapes::new(),
            punctual_powers,
            env_power: 4.0 * PI * PI * radius * radius * luminance(env.mean),
            env_header: (env.width, env.height, env.constant.to_array()),
            sky: env.mean,
        };
        tables.update(scene, pose, &[])?;
        Ok(tables)
    }

    /// Takes over what `old` knew of the deformed emissive meshes' shapes (the deformer and
    /// the skinning report a shape only when it changes), and builds the emitters from them at
    /// the next `update`: tables made again for another shadows chain
    /// (`SceneGpu::set_light_tables`).
    pub fn inherit_shapes(&mut self, old: LightTables) {
        self.shapes = old.shapes;
        self.built_for = None;
    }

    pub fn write_set(&self, set: &DescriptorSet) {
        set.write_buffer(binding::LIGHT_TABLE, BindingKind::StorageBuffer, self.table.buffer());
        set.write_buffer(binding::EMITTERS, BindingKind::StorageBuffer, self.emitters.buffer());
        set.write_buffer(binding::EMITTER_BASE, BindingKind::StorageBuffer, &self.emitter_base);
        set.write_buffer(binding::ENV_TEXELS, BindingKind::StorageBuffer, &self.env_texels);
        set.write_buffer(binding::ENV_CDF, BindingKind::StorageBuffer, &self.env_cdf);
        set.write_buffer(binding::LIGHT_GRID, BindingKind::StorageBuffer, self.grid.buffer());
        set.write_buffer(binding::LIGHT_GRID_ENTRIES, BindingKind::StorageBuffer, self.grid_entries.buffer());
        set.write_buffer(binding::LIGHT_GRID_VISIBILITY, BindingKind::StorageBuffer, &self.grid_visibility);
        set.write_buffer(binding::EMITTER_GROUPS, BindingKind::StorageBuffer, self.emitter_groups.buffer());
    }

    /// Where the light grid's cells are (no cells: no grid), as last written.
    pub fn grid_header(&self) -> GpuLightGridHeader {
        self.grid_header
    }

    /// Rebuilds the light grid for the punctual lights as written this frame, over the scene's
    /// bounds at this pose; at a coarser resolution when the finest would not fit. Staged:
    /// `record` copies it in.
    pub fn update_grid(&mut self, lights: &[GpuLight], bounds: (Vec3, Vec3)) -> Result<()> {
        if !self.grid_enabled {
            return self.stage_grid(&GpuLightGridHeader::default(), &[], &[]);
        }
        let grid = match self.grid_at_load.take() {
            // It fits: the capacity is at least its size.
            Some((built_for, built_bounds, grid))
                if built_bounds == bounds
                    && bytemuck::cast_slice::<GpuLight, u8>(&built_for)
                        == bytemuck::cast_slice::<GpuLight, u8>(lights) =>
            {
                grid
            }
            _ => build_grid(
                lights,
                &self.punctual_powers,
                self.chain_punctual,
                bounds,
                self.grid_capacity,
                !self.emissive.is_empty(),
            ),
        };
        log::debug!(
            "light grid: {:?} cells, {} entries for {} resampled lights",
            grid.header.dims,
            grid.entries.len(),
            lights.len().saturating_sub(self.chain_punctual)
        );
        // What was learned is kept where the new grid has the same cells and groups (the same
        // header: the bounds did not change): an estimate is what a cell sees of a region of the
        // scene, which lights that moved, dimmed or went off within it do not change much, and
        // one frame's rays correct it (light_grid_update's memory is 4 rays). Otherwise it
        // belonged to the old cells. An animated light rebuilds the grid every frame, and would
        // never learn anything if each rebuild forgot.
        let moved = bytemuck::bytes_of(&grid.header) != bytemuck::bytes_of(&self.grid_header);
        if moved {
            self.visibility_reset_pending = true;
        }
        self.stage_grid(&grid.header, &grid.cells, &grid.entries)?;
        if moved { self.stage_emitter_groups() } else { Ok(()) }
    }

    /// Sorts the emissive triangles as last built into the groups of the grid as last written,
    /// for the next `record` to copy in.
    fn stage_emitter_groups(&mut self) -> Result<()> {
        let (groups, entries) = light_grid::emitter_groups(&self.grid_header, &self.group_points);
        let listed = EMITTER_GROUPS_HEADER + light_grid::EMITTER_GROUPS as usize * size_of::<GpuEmitterGroup>();
        self.emitter_groups.write(0, bytemuck::bytes_of(&[groups.len() as u32, 0, 0, 0]))?;
        self.emitter_groups.write(EMITTER_GROUPS_HEADER, bytemuck::cast_slice(&groups))?;
        self.emitter_groups.write(listed, bytemuck::cast_slice(&entries))
    }

    /// Writes a grid for the next `record` to copy in.
    fn stage_grid(
        &mut self,
        header: &GpuLightGridHeader,
        cells: &[[u32; 2]],
        entries: &[GpuLightGridEntry],
    ) -> Result<()> {
        self.grid.write(0, bytemuck::bytes_of(header))?;
        self.grid.write(size_of::<GpuLightGridHeader>(), bytemuck::cast_slice(cells))?;
        self.grid_entries.write(0, bytemuck::cast_slice(entries))?;
        self.grid_header = *header;
        Ok(())
    }

    /// Records the copies of what was rewritten (light table, emitters, grid) into the
    /// device-local buffers, and the reset of the learned visibility where the grid's cells
    /// moved, between barriers against the shaders that read and write them. Nothing is
    /// recorded when nothing is pending.
    pub fn record(&mut self, rec: &Recorder) {
        staged::record_copies(
            rec,
            &mut [
                &mut self.table,
                &mut self.emitters,
                &mut self.grid,
                &mut self.grid_entries,
                &mut self.emitter_groups,
            ],
        );
        if std::mem::take(&mut self.visibility_reset_pending) {
            let shaders = (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            );
            let transfer = (vk::PipelineStageFlags2::TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
            rec.memory_barrier(shaders, transfer);
            rec.zero_buffer(&self.grid_visibility);
            rec.memory_barrier(transfer, shaders);
        }
    }

    /// Rebuilds the emitters and the CDF when an emissive instance moved since the last build,
    /// or an emissive mesh deformed (`deformed`: this frame's (mesh, object-space positions)
    /// of the deforming meshes, from the morph deformer and the skinning); true when it did
    /// (the first call always does).
    pub fn update(&mut self, scene: &Scene, pose: &Pose, deformed: &[(u32, Vec<Vec3>)]) -> Result<bool> {
        let now: Vec<Mat4> =
            self.emissive.iter().map(|&i| pose.world[scene.instances[i as usize].node as usize]).collect();
        let mut reshaped = false;
        for (mesh, positions) in deformed {
            // (The skinning leaves a mesh's positions out where only the GPU needs them: never
            // for an emissive one.)
            if !positions.is_empty() && scene.materials[scene.meshes[*mesh as usize].material as usize].is_emissive() {
                self.shapes.insert(*mesh, positions.clone());
                reshaped = true;
            }
        }
        if self.built_for.as_ref() == Some(&now) && !reshaped {
            return Ok(false);
        }
        let emitters = emitters_shaped(scene, pose, &self.chain, &self.shapes);
        let mut powers: Vec<(u32, u32, f32)> = Vec::with_capacity(self.punctual_powers.len() + emitters.len() + 1);
        powers.extend(self.punctual_powers.iter().enumerate().map(|(i, &p)| (LIGHT_KIND_PUNCTUAL, i as u32, p)));
        powers
            .extend(emitters.iter().enumerate().map(|(i, e)| (LIGHT_KIND_EMITTER, i as u32, emitter_power(scene, e))));
        self.group_points = group_points(scene, &emitters);
        powers.push((LIGHT_KIND_ENVIRONMENT, 0, self.env_power));
        let entries = light_cdf(&powers);
        let (env_width, env_height, env_constant) = self.env_header;
        let header = GpuLightTableHeader {
            entry_count: entries.len() as u32,
            first_emitter_entry: self.punctual_powers.len() as u32,
            env_entry: (powers.len() - 1) as u32,
            env_width,
            env_height,
            env_constant,
        };
        self.table.write(0, bytemuck::bytes_of(&header))?;
        self.table.write(size_of::<GpuLightTableHeader>(), bytemuck::cast_slice(&entries))?;
        self.emitters.write(0, bytemuck::cast_slice(&emitters))?;
        self.stage_emitter_groups()?;
        self.built_for = Some(now);
        Ok(true)
    }
}

fn instance_emits(scene: &Scene, instance: u32) -> bool {
    let mesh = &scene.meshes[scene.instances[instance as usize].mesh as usize];
    scene.materials[mesh.material as usize].is_emissive()
}

/// Instances whose material emits, in instance order.
pub fn emissive_instances(scene: &Scene) -> Vec<u32> {
    (0..scene.instances.len() as u32).filter(|&i| instance_emits(scene, i)).collect()
}

/// Per instance, the index of its first emitter (its triangle t is emitter base + t), or
/// NO_EMITTER; and the total number of emitters.
pub fn emitter_bases(scene: &Scene) -> (Vec<u32>, u32) {
    let mut next = 0u32;
    let bases = (0..scene.instances.len() as u32)
        .map(|i| {
            if !instance_emits(scene, i) {
                return NO_EMITTER;
            }
            let base = next;
            next += scene.meshes[scene.instances[i as usize].mesh as usize].triangle_count() as u32;
            base
        })
        .collect();
    (bases, next)
}

/// The shadows chain's lights (`chain_lights`): how many punctual lights lead the shading order
/// with a channel each, and the mesh lights' instances after them.
#[derive(Clone, Copy, Debug)]
pub struct ChainLights<'a> {
    pub punctual: usize,
    pub meshes: &'a [u32],
}

/// A light that can take a channel of the shadows chain (`chain_lights`): a punctual light
/// (index into the scene's lights) or a mesh light (its instance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChainCandidate {
    Punctual(usize),
    Mesh(u32),
}

/// The shadows chain's lights, punctual and mesh lights ranked together: of the kept punctual
/// lights (`punctual`, indices into the scene's lights) and the emissive instances that can be
/// mesh lights, the SHADOWED_LIGHTS that bring the most light. Where more compete than that,
/// `seen` says what each brings to what the camera sees (render::light_view), and they rank by
/// it; candidates it finds equal (none reaching the view, or `seen` 0 for all) rank by the
/// power they emit over the whole scene, and a tie goes to the punctual light. Returns the
/// punctual lights among them, in rank order (they lead `shading_order`), and the mesh lights
/// that take the channels after them, each as (instance, first emitter, triangles). Until
/// 2026-12-06 the ranking was by power alone, so a bright light behind a wall held a channel
/// that a light in the camera's room would use (`builtin:many-lights`: two of the four).
///
/// A mesh light must emit its material's factor alone (no emissive texture), be opaque and
/// rigid, and have at most MAX_CHAIN_EMITTER_TRIANGLES triangles: composite then integrates its
/// unshadowed light exactly (the polygons' form factors), and the chain's adaptive shadow rays
/// give the share that arrives. `mesh_lights` false: none is (`--no-mesh-lights`).
pub fn chain_lights(
    scene: &Scene,
    punctual: &[usize],
    mesh_lights: bool,
    seen: &dyn Fn(ChainCandidate) -> f32,
) -> (Vec<usize>, Vec<(u32, u32, u32)>) {
    let radius = scene_radius(scene, &scene.evaluate(0.0));
    let meshes = if mesh_lights { mesh_light_candidates(scene) } else { Vec::new() };
    let candidates: Vec<(ChainCandidate, f32)> = punctual
        .iter()
        .map(|&i| (ChainCandidate::Punctual(i), punctual_power(&scene.lights[i], radius)))
        .chain(meshes.iter().map(|&((instance, ..), power)| (ChainCandidate::Mesh(instance), power)))
        .collect();
    let view: Vec<f32> = if candidates.len() > SHADOWED_LIGHTS {
        candidates.iter().map(|&(c, _)| seen(c)).collect()
    } else {
        vec![0.0; candidates.len()]
    };
    // What a candidate brings to the view, then its power, then the punctual light first; the
    // sort is stable, so equal candidates keep the scene's order.
    let mut rank: Vec<usize> = (0..candidates.len()).collect();
    let mesh = |k: usize| matches!(candidates[k].0, ChainCandidate::Mesh(_));
    rank.sort_by(|&a, &b| {
        view[b].total_cmp(&view[a]).then(candidates[b].1.total_cmp(&candidates[a].1)).then(mesh(a).cmp(&mesh(b)))
    });
    let chosen: Vec<ChainCandidate> = rank.iter().take(SHADOWED_LIGHTS).map(|&k| candidates[k].0).collect();
    let lights = chosen
        .iter()
        .filter_map(|c| match c {
            ChainCandidate::Punctual(i) => Some(*i),
            ChainCandidate::Mesh(_) => None,
        })
        .collect();
    let chain = chosen
        .iter()
        .filter_map(|c| match c {
            ChainCandidate::Mesh(i) => meshes.iter().find(|m| m.0.0 == *i).map(|m| m.0),
            ChainCandidate::Punctual(_) => None,
        })
        .collect();
    (lights, chain)
}

/// The emissive instances that can be mesh lights (see `chain_lights`), brightest first, each
/// with its power at time 0 summed over its triangles as the light table weighs them.
fn mesh_light_candidates(scene: &Scene) -> Vec<((u32, u32, u32), f32)> {
    let (bases, _) = emitter_bases(scene);
    let mut power = vec![0.0f32; scene.instances.len()];
    for e in emitters(scene, &scene.evaluate(0.0), &[]) {
        power[e.instance as usize] += emitter_power(scene, &e);
    }
    let mut candidates: Vec<((u32, u32, u32), f32)> = (0..scene.instances.len() as u32)
        .filter(|&i| power[i as usize] > 0.0)
        .filter_map(|i| {
            let inst = &scene.instances[i as usize];
            let mesh = &scene.meshes[inst.mesh as usize];
            let material = &scene.materials[mesh.material as usize];
            let fits = material.emissive_texture.is_none()
                && material.alpha_mode == crate::scene::AlphaMode::Opaque
                && !material.is_transmissive()
                && !scene.deforms(inst.mesh)
                && mesh.triangle_count() <= MAX_CHAIN_EMITTER_TRIANGLES;
            fits.then_some(((i, bases[i as usize], mesh.triangle_count() as u32), power[i as usize]))
        })
        .collect();
    candidates.sort_by(|a, b| b.1.total_cmp(&a.1));
    candidates
}

/// Object-space vertex positions of deformed meshes, by mesh, in place of their vertices'.
type Shapes = std::collections::HashMap<u32, Vec<Vec3>>;

/// Every triangle of every emissive instance in world space, in emitter order, each mesh in
/// its undeformed shape; those of the instances in `chain` (the shadows chain's mesh lights)
/// flagged EMITTER_IN_CHAIN.
pub fn emitters(scene: &Scene, pose: &Pose, chain: &[u32]) -> Vec<GpuEmitter> {
    emitters_shaped(scene, pose, chain, &Shapes::new())
}

/// `emitters`, with the deformed meshes in `shapes` in their deformed shape.
fn emitters_shaped(scene: &Scene, pose: &Pose, chain: &[u32], shapes: &Shapes) -> Vec<GpuEmitter> {
    let mut out = Vec::new();
    for i in emissive_instances(scene) {
        let inst = &scene.instances[i as usize];
        let mesh = &scene.meshes[inst.mesh as usize];
        let shape = shapes.get(&inst.mesh);
        let position = |v: u32| shape.map_or(Vec3::from(mesh.vertices[v as usize].position), |s| s[v as usize]);
        let world = pose.world[inst.node as usize];
        // A mirroring transform flips the winding; the front side stays where the object-space
        // winding puts it, which is the side the ray backends call front.
        let side = world.determinant().signum();
        let sides = if scene.materials[mesh.material as usize].double_sided { EMITTER_DOUBLE_SIDED } else { 0 };
        let flags = sides | if chain.contains(&i) { EMITTER_IN_CHAIN } else { 0 };
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let p = |k: usize| world.transform_point3(position(tri[k]));
            let (p0, p1, p2) = (p(0), p(1), p(2));
            let (e1, e2) = (p1 - p0, p2 - p0);
            let cross = e1.cross(e2);
            out.push(GpuEmitter {
                p0: p0.to_array(),
                instance: i,
                e1: e1.to_array(),
                primitive: t as u32,
                e2: e2.to_array(),
                area: 0.5 * cross.length(),
                normal: (cross.normalize_or_zero() * side).to_array(),
                flags,
            });
        }
    }
    out
}

/// The light grid for the punctual lights past the `shadowed` ones, within `capacity` entries;
/// with none of them resampled, cells without lights where `emitters`: gi learns in them what
/// each cell sees of the emissive triangles.
fn build_grid(
    lights: &[GpuLight],
    powers: &[f32],
    shadowed: usize,
    bounds: (Vec3, Vec3),
    capacity: usize,
    emitters: bool,
) -> LightGrid {
    let grid = LightGrid::build_within(lights, powers, shadowed, bounds, light_grid::RESOLUTION, capacity);
    if grid.header.cell_count == 0 && emitters { LightGrid::cells_only(bounds, light_grid::RESOLUTION) } else { grid }
}

/// What the grid's emitter groups are built from: each emitter's centroid and power, the
/// shadows chain's mesh lights' power 0. gi draws its reservoirs' emitter candidates from the
/// groups, and such a candidate weighs nothing there (composite shades those lights): every
/// draw of one was wasted, most of them where the chain holds the brightest lights
/// (builtin:many-panels' camera room). The light table keeps them: path vertices' light
/// samples need them.
fn group_points(scene: &Scene, emitters: &[GpuEmitter]) -> Vec<(Vec3, f32)> {
    emitters
        .iter()
        .map(|e| (centroid(e), if e.flags & EMITTER_IN_CHAIN != 0 { 0.0 } else { emitter_power(scene, e) }))
        .collect()
}

/// An emitter triangle's centroid.
pub(crate) fn centroid(e: &GpuEmitter) -> Vec3 {
    Vec3::from(e.p0) + (Vec3::from(e.e1) + Vec3::from(e.e2)) / 3.0
}

fn emitter_power(scene: &Scene, e: &GpuEmitter) -> f32 {
    let mesh = scene.instances[e.instance as usize].mesh;
    let material = &scene.materials[scene.meshes[mesh as usize].material as usize];
    let sides = if e.flags & EMITTER_DOUBLE_SIDED != 0 { 2.0 } else { 1.0 };
    PI * luminance(material.emissive_factor) * e.area * sides
}

/// The order in which the renderer keeps the scene's lights, `excluded` (culled) left out. The
/// shadows chain's punctual lights (`chain`, from `chain_lights`) come first and get its
/// per-light visibility (exact, with adaptive soft shadows), the rest are resampled in gi
/// (shaders-glsl/common/light_reservoir.glsl), brightest (by power, ties in scene order) first.
/// Where the chain holds every kept light, the scene's order is kept.
pub fn shading_order(scene: &Scene, excluded: &[usize], chain: &[usize]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..scene.lights.len()).filter(|i| !excluded.contains(i)).collect();
    if order.len() > chain.len() {
        let radius = scene_radius(scene, &scene.evaluate(0.0));
        let power: Vec<f32> = scene.lights.iter().map(|l| punctual_power(l, radius)).collect();
        order.retain(|i| !chain.contains(i));
        order.sort_by(|&a, &b| power[b].total_cmp(&power[a]));
        order.splice(0..0, chain.iter().copied());
    }
    order
}

fn punctual_power(light: &crate::scene::Light, radius: f32) -> f32 {
    let i = luminance(light.color * light.intensity).max(0.0);
    match light.kind {
        LightKind::Point => 4.0 * PI * i,
        LightKind::Spot { outer_cone, .. } => 2.0 * PI * (1.0 - outer_cone.cos()) * i,
        LightKind::Directional => PI * radius * radius * i,
    }
}

/// Radius of the scene's bounding sphere at a pose (1 for an empty scene).
fn scene_radius(scene: &Scene, pose: &Pose) -> f32 {
    let (lo, hi) = scene.bounds(pose);
    let r = 0.5 * (hi - lo).length();
    if r > 0.0 && r.is_finite() { r } else { 1.0 }
}

/// Selection CDF over (kind, index, power): empty when nothing has power. Every entry from the
/// last one with power on has cdf exactly 1, so the shader's search for the first cdf > u
/// (u < 1) never picks an entry of probability 0.
pub fn light_cdf(powers: &[(u32, u32, f32)]) -> Vec<GpuLightEntry> {
    let clean = |p: f32| if p.is_finite() && p > 0.0 { p as f64 } else { 0.0 };
    let total: f64 = powers.iter().map(|e| clean(e.2)).sum();
    if total <= 0.0 {
        return Vec::new();
    }
    let last = powers.iter().rposition(|e| clean(e.2) > 0.0).unwrap_or(0);
    let mut acc = 0.0f64;
    powers
        .iter()
        .enumerate()
        .map(|(i, &(kind, index, power))| {
            acc += clean(power);
            let cdf = if i >= last { 1.0 } else { (acc / total) as f32 };
            GpuLightEntry { kind, index, cdf, pmf: (clean(power) / total) as f32 }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Instance, Material, Node, builtin};
    use glam::Quat;

    fn emissive_scene(scale: Vec3, double_sided: bool) -> Scene {
        let mut s = Scene::default();
        s.materials.push(Material { name: "plain".into(), ..Default::default() });
        s.materials.push(Material {
            name: "lamp".into(),
            emissive_factor: Vec3::new(2.0, 2.0, 2.0),
            double_sided,
            ..Default::default()
        });
        // Unit square at the origin facing +Z (two triangles), and a plain quad.
        s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X, Vec3::Y, 1));
        s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X, Vec3::Y, 0));
        for (name, t, sc) in [("plain", Vec3::ZERO, Vec3::ONE), ("lamp", Vec3::new(0.0, 3.0, 0.0), scale)] {
            s.nodes.push(Node { name: name.into(), parent: None, translation: t, rotation: Quat::IDENTITY, scale: sc });
        }
        s.instances.push(Instance { mesh: 1, node: 0 });
        s.instances.push(Instance { mesh: 0, node: 1 });
        s
    }

    #[test]
    fn emitters_are_world_space_triangles_of_emissive_instances() {
        let s = emissive_scene(Vec3::new(2.0, 3.0, 1.0), false);
        let pose = s.evaluate(0.0);
        assert_eq!(emitter_bases(&s), (vec![NO_EMITTER, 0], 2));
        let e = emitters(&s, &pose, &[1]);
        assert_eq!(e.len(), 2);
        let area: f32 = e.iter().map(|e| e.area).sum();
        assert!((area - 6.0).abs() < 1e-5, "scaled square has area 2 x 3, got {area}");
        // A mesh light of the shadows chain.
        for (t, em) in e.iter().enumerate() {
            assert_eq!((em.instance, em.primitive, em.flags), (1, t as u32, EMITTER_IN_CHAIN));
            assert!(Vec3::from(em.normal).abs_diff_eq(Vec3::Z, 1e-6), "{:?}", em.normal);
            assert!((em.p0[1] - 3.0).abs() < 1.5 + 1e-5, "translated to y = 3: {:?}", em.p0);
        }
        let power: f32 = e.iter().map(|em| emitter_power(&s, em)).sum();
        assert!((power - PI * 2.0 * 6.0).abs() < 1e-3, "{power}");
    }

    #[test]
    fn a_mirroring_transform_keeps_the_front_side() {
        let s = emissive_scene(Vec3::new(-1.0, 1.0, 1.0), true);
        let e = emitters(&s, &s.evaluate(0.0), &[1]);
        // Mirrored in x, the winding turns over, but the quad still faces +Z.
        assert!(Vec3::from(e[0].normal).abs_diff_eq(Vec3::Z, 1e-6), "{:?}", e[0].normal);
        assert_eq!(e[0].flags, EMITTER_DOUBLE_SIDED | EMITTER_IN_CHAIN);
    }

    #[test]
    fn the_shaders_hold_as_many_mesh_light_triangles_as_the_selection_allows() {
        let glsl = include_str!("../../shaders-glsl/common/mesh_lights.glsl");
        let define = format!("#define MESH_LIGHT_MAX_TRIANGLES {MAX_CHAIN_EMITTER_TRIANGLES}u");
        assert!(glsl.contains(&define), "common/mesh_lights.glsl must say {define}");
    }

    /// `count` point lights of `intensity` candela at the lamp's node.
    fn with_point_lights(s: &Scene, count: usize, intensity: f32) -> (Scene, Vec<usize>) {
        let mut s = s.clone();
        for k in 0..count {
            s.lights.push(crate::scene::Light {
                name: format!("point {k}"),
                kind: LightKind::Point,
                color: Vec3::ONE,
                intensity,
                range: None,
                radius: 0.0,
                node: 1,
            });
        }
        (s, (0..count).collect())
    }

    /// `chain_lights` ranking by power alone (nothing reaches a view): how many punctual lights
    /// the chain takes, and its mesh lights.
    fn by_power(s: &Scene, kept: &[usize], mesh_lights: bool) -> (usize, Vec<(u32, u32, u32)>) {
        let (lights, meshes) = chain_lights(s, kept, mesh_lights, &|_| 0.0);
        (lights.len(), meshes)
    }

    #[test]
    fn the_chain_goes_to_the_lights_that_bring_the_most_to_the_view() {
        let s = emissive_scene(Vec3::ONE, false);
        let (bases, _) = emitter_bases(&s);
        // Six point lights of 4 pi 100 outshine the lamp (2 pi); the view sees only lights 4
        // and 5 and the lamp, the lamp most.
        let (s, kept) = with_point_lights(&s, 6, 100.0);
        let seen = |c: ChainCandidate| match c {
            ChainCandidate::Punctual(4) => 1.0,
            ChainCandidate::Punctual(5) => 2.0,
            ChainCandidate::Mesh(1) => 3.0,
            _ => 0.0,
        };
        let (lights, meshes) = chain_lights(&s, &kept, true, &seen);
        // Then the brightest of those the view does not reach, in the scene's order.
        assert_eq!((lights.clone(), meshes), (vec![5, 4, 0], vec![(1, bases[1], 2)]));
        // They lead the shading order; the rest follow by power.
        assert_eq!(shading_order(&s, &[], &lights), vec![5, 4, 0, 1, 2, 3]);
        // With no more candidates than channels, the view is not asked.
        let (lights, _) = chain_lights(&s, &kept[..3], true, &|_| panic!("asked"));
        assert_eq!(lights, vec![0, 1, 2]);
        assert_eq!(shading_order(&s, &[3, 4, 5], &lights), vec![0, 1, 2], "all in the chain: the scene's order");
    }

    #[test]
    fn small_plain_emitters_rank_with_the_punctual_lights_for_the_chain() {
        let mut s = emissive_scene(Vec3::ONE, false);
        // A brighter lamp, a textured one and one of too many triangles beside the first.
        let bright = s.materials.len() as u32;
        s.materials.push(Material { emissive_factor: Vec3::splat(5.0), ..s.materials[1].clone() });
        let textured = s.materials.len() as u32;
        s.materials.push(Material {
            emissive_texture: Some(crate::scene::TextureRef { texture: 0, uv_set: 0, transform: glam::Mat3::IDENTITY }),
            ..s.materials[1].clone()
        });
        s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X, Vec3::Y, bright));
        s.meshes.push(builtin::quad(Vec3::ZERO, Vec3::X, Vec3::Y, textured));
        s.meshes.push(builtin::uv_sphere(1.0, 8, 4, bright));
        for mesh in 2..5 {
            s.instances.push(Instance { mesh, node: 1 });
        }
        let (bases, _) = emitter_bases(&s);
        // The bright quad first, then the first lamp; the textured quad and the sphere never.
        let (punctual, chain) = by_power(&s, &[], true);
        assert_eq!((punctual, chain.clone()), (0, vec![(2, bases[2], 2), (1, bases[1], 2)]));
        assert_eq!(by_power(&s, &[], false), (0, vec![]), "--no-mesh-lights");
        // Brighter point lights (4 pi 100 against the quads' 5 pi and 2 pi) come first.
        let (bright3, kept) = with_point_lights(&s, 3, 100.0);
        assert_eq!(by_power(&bright3, &kept, true), (3, vec![(2, bases[2], 2)]), "one channel left by 3 lights");
        let (bright4, kept) = with_point_lights(&s, 4, 100.0);
        assert_eq!(by_power(&bright4, &kept, true), (4, vec![]), "4 brighter lights leave none");
        // Dimmer ones (4 pi 0.5 = 2 pi, the lamp's: a tie goes to the light) give the bright quad a
        // channel, and the lamp one only where fewer lights are kept.
        let (dim6, kept) = with_point_lights(&s, 6, 0.5);
        assert_eq!(by_power(&dim6, &kept, true), (3, vec![(2, bases[2], 2)]));
        assert_eq!(by_power(&dim6, &kept[..2], true), (2, vec![(2, bases[2], 2), (1, bases[1], 2)]));
        let chain: Vec<u32> = chain.iter().map(|c| c.0).collect();
        let flagged: Vec<u32> = emitters(&s, &s.evaluate(0.0), &chain)
            .iter()
            .filter(|e| e.flags & EMITTER_IN_CHAIN != 0)
            .map(|e| e.instance)
            .collect();
        assert_eq!(flagged, vec![1, 1, 2, 2]);
        // The grid's groups draw only the others: the chain's triangles have no power there,
        // the textured quad and the sphere theirs as in the light table.
        let e = emitters(&s, &s.evaluate(0.0), &chain);
        for (em, (_, power)) in e.iter().zip(group_points(&s, &e)) {
            let expected = if em.flags & EMITTER_IN_CHAIN != 0 { 0.0 } else { emitter_power(&s, em) };
            assert_eq!(power, expected, "instance {}", em.instance);
            assert!(emitter_power(&s, em) > 0.0);
        }
    }

    /// The structs match light_sampling.glsl's scalar layout: 4-byte members, vec3 unpadded.
    #[test]
    fn gpu_structs_match_the_shader_layout() {
        assert_eq!(size_of::<GpuLightTableHeader>(), 5 * 4 + 12);
        assert_eq!(size_of::<GpuLightEntry>(), 16);
        assert_eq!(size_of::<GpuEmitter>(), 4 * (12 + 4));
        assert_eq!(std::mem::offset_of!(GpuEmitter, normal), 48);
    }

    /// light_reservoir.glsl takes entry i of the table for punctual light i.
    #[test]
    fn punctual_lights_lead_the_cdf_in_light_order() {
        let powers: Vec<(u32, u32, f32)> = (0..6)
            .map(|i| (LIGHT_KIND_PUNCTUAL, i, 1.0 + i as f32))
            .chain([(LIGHT_KIND_EMITTER, 0, 2.0), (LIGHT_KIND_ENVIRONMENT, 0, 1.0)])
            .collect();
        let entries = light_cdf(&powers);
        for (i, e) in entries.iter().take(6).enumerate() {
            assert_eq!((e.kind, e.index), (LIGHT_KIND_PUNCTUAL, i as u32));
        }
    }

    #[test]
    fn more_lights_than_the_shadowed_ones_are_ordered_brightest_first() {
        let s = crate::scene::builtin_many_lights::many_lights();
        let all: Vec<usize> = (0..s.lights.len()).collect();
        let (chain, _) = chain_lights(&s, &all, true, &|_| 0.0);
        let order = shading_order(&s, &[], &chain);
        assert_eq!(order.len(), s.lights.len());
        let radius = scene_radius(&s, &s.evaluate(0.0));
        let p = |i: usize| punctual_power(&s.lights[i], radius);
        assert!(order.windows(2).all(|w| p(w[0]) >= p(w[1])));
        // A few lights keep the scene's order; excluded ones are left out.
        let s = builtin::soft_shadow_test();
        assert_eq!(shading_order(&s, &[], &[0]), vec![0]);
        assert!(shading_order(&s, &[0], &[]).is_empty());
    }

    #[test]
    fn cdf_is_normalised_and_never_picks_powerless_lights() {
        let entries = light_cdf(&[(0, 0, 1.0), (1, 0, 0.0), (1, 1, 3.0), (2, 0, 0.0)]);
        let pmf: Vec<f32> = entries.iter().map(|e| e.pmf).collect();
        assert_eq!(pmf, vec![0.25, 0.0, 0.75, 0.0]);
        let cdf: Vec<f32> = entries.iter().map(|e| e.cdf).collect();
        assert_eq!(cdf, vec![0.25, 0.25, 1.0, 1.0]);
        // The shader picks the first entry whose cdf exceeds u.
        let pick = |u: f32| entries.iter().position(|e| e.cdf > u).unwrap();
        assert_eq!((pick(0.0), pick(0.2499), pick(0.25), pick(0.9999999)), (0, 0, 2, 2));
        assert!(light_cdf(&[(0, 0, 0.0), (2, 0, f32::NAN)]).is_empty());
    }
}
