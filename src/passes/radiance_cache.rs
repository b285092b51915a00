//! radiance_cache: a world-space hash grid of indirect irradiance that persists across frames
//! (shaders-glsl/radiance_cache.comp, common/radiance_cache.glsl). gi and reflections look it
//! up where their rays end, so the frame carries every bounce at about one GI ray per pixel;
//! this pass updates a fixed budget of cells per frame and writes what the cache holds at each
//! visible surface (`radiance_cache.irradiance`) for dumps and the viewer.

use super::PassBuilder;
use super::fullscreen::{FullscreenPass, Input, SHARED_BUFFER_ACCESS};
use super::gbuffer;
use crate::gpu::{Buffer, Context, MemoryLocation, vk};
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, Preview, ShaderInterface};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

pub const NAME: &str = "radiance_cache";
/// What the cache holds at each G-buffer surface: rgb the cached (1/pi) int L_r cos, a the
/// samples in its running mean (0: no cell there yet).
pub const IRRADIANCE: Output = Output::new(NAME, "irradiance");
/// 1 where a cell around a G-buffer surface (its own or one of the four nearest in its plane)
/// restarted its mean this frame on a change that the frame did not announce (an object moved
/// between it and a light): SVGF's temporal pass restarts the diffuse history there.
pub const CHANGED: Output = Output::new(NAME, "changed");
/// The GLSL names of the cache's buffer blocks (common/radiance_cache.glsl), in binding order.
pub const BUFFER_BLOCKS: [&str; 3] = ["RcKeys", "RcCells", "RcStateBuffer"];

/// Slots of the hash table: a power of two. 128 Ki cells of 144 bytes (18 MiB).
pub const CAPACITY: u32 = 1 << 17;
/// The running mean's window: the cache follows a change of the light within about this many
/// updates of a cell.
pub const MAX_SAMPLES: u32 = 16;
/// Size of `RcCell` in common/radiance_cache.glsl (std430: seven vec4, a uvec4, and a uvec2
/// and a uint padded to 16 bytes).
const CELL_BYTES: u64 = 144;
/// Invocations per workgroup of the update (`local_size_x * local_size_y`).
const UPDATE_GROUP: u32 = 64;

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct RadianceCacheSettings {
    /// Off: gi and reflections trace a few vertices further instead of asking the cache.
    pub enabled: bool,
    /// Cells updated per frame at most (one cosine ray and one light sample each).
    pub budget: u32,
    /// The cell size near the camera as a fraction of the scene's bounding-box diagonal.
    pub cells_per_diagonal: f32,
}

impl Default for RadianceCacheSettings {
    fn default() -> Self {
        Self { enabled: true, budget: 8192, cells_per_diagonal: 40.0 }
    }
}

/// One line for the log and `hybrid-rt plan`: whether the cache runs, and its cells and budget.
pub fn describe(s: &RadianceCacheSettings, used: bool, scene_diagonal: f32) -> String {
    if !s.enabled {
        return "radiance cache: off (--no-radiance-cache): gi and reflection rays trace up to 3 bounces".into();
    }
    if !used {
        return "radiance cache: not needed, no gi or reflection rays".into();
    }
    format!(
        "radiance cache: cells of {:.4} at the camera (scene diagonal {scene_diagonal:.3} / {}), doubling every {scene_diagonal:.3} \
         of distance; {} cells updated per frame at most, {CAPACITY} slots, mean over {MAX_SAMPLES} updates",
        scene_diagonal / s.cells_per_diagonal.max(1.0),
        s.cells_per_diagonal,
        s.budget
    )
}

/// Mirrors `RcState` in common/radiance_cache.glsl (std430: 4-byte fields only).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct State {
    cell: f32,
    lod_distance: f32,
    budget: u32,
    max_samples: u32,
    enabled: u32,
    capacity: u32,
    live: [u32; 3],
    updated: [u32; 3],
    restarted: [u32; 3],
}

/// Live and updated cells in one frame, and those whose mean restarted on a change of the scene
/// that the frame did not announce (radiance_cache.comp).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CacheStats {
    pub live: u32,
    pub updated: u32,
    pub restarted: u32,
}

/// The cache's buffers, shared by this pass, gi and reflections, bound in this order after
/// each one's images (`RC_BINDING`).
pub struct Cache {
    keys: Arc<Buffer>,
    cells: Arc<Buffer>,
    state: Arc<Buffer>,
    /// Slots of the table (a token few when the cache is off).
    capacity: u32,
    /// Cell size at the camera, world units.
    pub cell: f32,
    pub settings: RadianceCacheSettings,
}

impl Cache {
    /// A cache for a scene whose bounding box has diagonal `scene_diagonal`. When the settings
    /// turn it off the buffers are token-sized and every query misses.
    pub fn new(ctx: &Arc<Context>, settings: &RadianceCacheSettings, scene_diagonal: f32) -> Result<Self> {
        let capacity = if settings.enabled { CAPACITY } else { UPDATE_GROUP };
        let cell = (scene_diagonal / settings.cells_per_diagonal.max(1.0)).max(1e-4);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let keys = Buffer::new(ctx, "radiance_cache.keys", 4 * capacity as u64, usage, MemoryLocation::GpuOnly)?;
        let cells =
            Buffer::new(ctx, "radiance_cache.cells", CELL_BYTES * capacity as u64, usage, MemoryLocation::GpuOnly)?;
        let state = State {
            cell,
            // Beyond about a scene's size from the camera, cells grow: distant surfaces are
            // seen by few rays and small cells there would never converge.
            lod_distance: scene_diagonal.max(1e-3),
            budget: settings.budget,
            max_samples: MAX_SAMPLES,
            enabled: settings.enabled as u32,
            capacity,
            ..Default::default()
        };
        let state = Buffer::with_data(ctx, "radiance_cache.state", bytemuck::bytes_of(&state), usage)?;
        Ok(Self {
            keys: Arc::new(keys),
            cells: Arc::new(cells),
            state: Arc::new(state),
            capacity,
            cell,
            settings: *settings,
        })
    }

    /// The buffers in binding order (keys, cells, state), with their GLSL block names.
    pub fn buffers(&self) -> Vec<(&'static str, Arc<Buffer>)> {
        BUFFER_BLOCKS.into_iter().zip([self.keys.clone(), self.cells.clone(), self.state.clone()]).collect()
    }

    /// What the update of frame `frame_index` counted; read after that frame finished.
    pub fn stats(&self, frame_index: u32) -> CacheStats {
        let Some(bytes) = self.state.mapped() else { return CacheStats::default() };
        let state: State = bytemuck::pod_read_unaligned(&bytes[..size_of::<State>()]);
        let i = (frame_index % 3) as usize;
        CacheStats { live: state.live[i], updated: state.updated[i], restarted: state.restarted[i] }
    }
}

/// The update and the view, one shader in two modes (push constant `mode`).
pub struct RadianceCachePass {
    pass: FullscreenPass,
    cache: Arc<Cache>,
    seed: u32,
    zeroed: bool,
}

/// radiance_cache.comp's push-constant block.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Params {
    /// 0: the update, 1: the view.
    pub mode: u32,
    pub seed: u32,
}

pub fn new(b: &PassBuilder, cache: &Arc<Cache>, seed: u32) -> Result<RadianceCachePass> {
    let inputs = [gbuffer::DEPTH, gbuffer::NORMAL_GEO, gbuffer::IDS].map(Input::texel).to_vec();
    let outputs = vec![
        OutputDesc::storage(IRRADIANCE, vk::Format::R32G32B32A32_SFLOAT, Preview::Color),
        OutputDesc::storage(CHANGED, vk::Format::R32_SFLOAT, Preview::Scalar),
    ];
    let pass = FullscreenPass::with_buffers(
        b,
        NAME,
        &b.traced_shader("radiance_cache.comp"),
        inputs,
        outputs,
        cache.buffers(),
        &Params { mode: 0, seed },
    )?;
    Ok(RadianceCachePass { pass, cache: cache.clone(), seed, zeroed: false })
}

impl Pass for RadianceCachePass {
    fn desc(&self) -> PassDesc {
        self.pass.desc()
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        if !self.zeroed {
            // New buffers hold whatever the memory held: every key must start empty.
            let rec = ctx.rec;
            rec.memory_barrier(
                SHARED_BUFFER_ACCESS,
                (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
            );
            rec.zero_buffer(&self.cache.keys);
            rec.zero_buffer(&self.cache.cells);
            rec.memory_barrier(
                (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
                SHARED_BUFFER_ACCESS,
            );
            self.zeroed = true;
        }
        self.pass.set_push_constants(&Params { mode: 0, seed: self.seed });
        self.pass.groups = Some([self.cache.capacity.div_ceil(UPDATE_GROUP), 1, 1]);
        self.pass.record(ctx)?;
        self.pass.set_push_constants(&Params { mode: 1, seed: self.seed });
        self.pass.groups = None;
        self.pass.record(ctx)
    }

    fn shader_interface(&self) -> Option<ShaderInterface> {
        self.pass.shader_interface()
    }
}
