//! VK_KHR_acceleration_structure: bottom levels (one per mesh) and the top level, their
//! builds, updates (refit) and compaction. The safe types here are all the hardware ray
//! backend (src/accel/hardware.rs) sees.

use super::{Buffer, CommandPool, Context, MemoryLocation, Recorder};
use anyhow::{Context as _, Result, anyhow};
use ash::vk;
use std::sync::Arc;

pub struct AccelStruct {
    ctx: Arc<Context>,
    pub raw: vk::AccelerationStructureKHR,
    _buffer: Buffer,
    pub address: vk::DeviceAddress,
    pub size: u64,
}

impl AccelStruct {
    fn new(ctx: &Arc<Context>, name: &str, ty: vk::AccelerationStructureTypeKHR, size: u64) -> Result<Self> {
        let loader = accel_loader(ctx)?;
        let buffer = Buffer::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::GpuOnly,
        )?;
        let info = vk::AccelerationStructureCreateInfoKHR::default().buffer(buffer.raw).size(size).ty(ty);
        // SAFETY: `buffer` was just made with ACCELERATION_STRUCTURE_STORAGE usage, bound to
        // memory, and holds `size` bytes at offset 0 (offset 0 meets the 256-byte alignment
        // rule); it is kept in `self` for as long as the structure lives.
        let raw = unsafe { loader.create_acceleration_structure(&info, None) }
            .with_context(|| format!("create acceleration structure {name}"))?;
        // SAFETY: `raw` was just made; the loader exists only with ray query enabled, which
        // includes the accelerationStructure feature this query needs.
        let address = unsafe {
            loader.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
            )
        };
        ctx.set_name(raw, name);
        Ok(Self { ctx: ctx.clone(), raw, _buffer: buffer, address, size })
    }
}

impl Drop for AccelStruct {
    fn drop(&mut self) {
        if let Some(loader) = &self.ctx.accel {
            // SAFETY: made by `new`, destroyed once, before its buffer (a field dropped after
            // this). Structures are dropped after the frames tracing them were waited for.
            unsafe { loader.destroy_acceleration_structure(self.raw, None) };
        }
    }
}

fn accel_loader(ctx: &Context) -> Result<&ash::khr::acceleration_structure::Device> {
    ctx.accel.as_ref().ok_or_else(|| anyhow!("the device has no acceleration structures"))
}

/// One mesh's triangles, read from the pooled scene buffers by device address.
#[derive(Clone, Copy, Debug)]
pub struct BlasGeometry {
    pub vertex_address: vk::DeviceAddress,
    pub vertex_stride: u64,
    /// Highest vertex index the mesh's indices address.
    pub max_vertex: u32,
    pub first_vertex: u32,
    pub index_address: vk::DeviceAddress,
    /// Byte offset of the mesh's first index in the index buffer.
    pub index_offset: u32,
    pub triangle_count: u32,
    /// Opaque geometry skips the any-hit path; alpha-masked geometry must not be opaque.
    pub opaque: bool,
}

impl BlasGeometry {
    fn vk(&self) -> vk::AccelerationStructureGeometryKHR<'static> {
        let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: self.vertex_address })
            .vertex_stride(self.vertex_stride)
            .max_vertex(self.max_vertex)
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR { device_address: self.index_address });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
            .flags(if self.opaque {
                vk::GeometryFlagsKHR::OPAQUE
            } else {
                vk::GeometryFlagsKHR::NO_DUPLICATE_ANY_HIT_INVOCATION
            })
    }

    fn range(&self) -> vk::AccelerationStructureBuildRangeInfoKHR {
        vk::AccelerationStructureBuildRangeInfoKHR {
            primitive_count: self.triangle_count,
            primitive_offset: self.index_offset,
            first_vertex: self.first_vertex,
            transform_offset: 0,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct BlasBuildStats {
    /// Bytes of all bottom levels as built.
    pub built_bytes: u64,
    /// Bytes after compaction (equal to `built_bytes` when compaction was not possible).
    pub final_bytes: u64,
    pub compacted: bool,
}

fn scratch_alignment(ctx: &Context) -> u64 {
    let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut as_props);
    // SAFETY: the context's own physical device; the chained struct (an extension the device
    // has: this is called only with the acceleration-structure loader present) lives here.
    unsafe { ctx.instance.get_physical_device_properties2(ctx.physical_device, &mut props) };
    u64::from(as_props.min_acceleration_structure_scratch_offset_alignment).max(1)
}

fn scratch_buffer(ctx: &Arc<Context>, name: &str, size: u64) -> Result<(Buffer, vk::DeviceAddress)> {
    let align = scratch_alignment(ctx);
    let buffer = Buffer::new(
        ctx,
        name,
        size + align,
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
    )?;
    let address = buffer.address.div_ceil(align) * align;
    Ok((buffer, address))
}

fn blas_flags(allow_update: bool, compact: bool) -> vk::BuildAccelerationStructureFlagsKHR {
    let mut f = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE;
    if allow_update {
        f |= vk::BuildAccelerationStructureFlagsKHR::ALLOW_UPDATE;
    }
    if compact {
        f |= vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION;
    }
    f
}

/// Builds one BLAS per geometry in one submission (a single barrier follows all builds), then
/// compacts them when the device can report compacted sizes; `allow_update[i]` marks meshes
/// that deform and will be refit (those are not compacted).
pub fn build_blases(
    ctx: &Arc<Context>,
    pool: &CommandPool,
    geometries: &[BlasGeometry],
    allow_update: &[bool],
) -> Result<(Vec<AccelStruct>, BlasBuildStats)> {
    let loader = accel_loader(ctx)?;
    let mut structs = Vec::with_capacity(geometries.len());
    let mut scratch_offsets = Vec::with_capacity(geometries.len());
    let mut scratch_total = 0u64;
    let align = scratch_alignment(ctx);
    let geoms: Vec<_> = geometries.iter().map(BlasGeometry::vk).collect();
    for (i, g) in geometries.iter().enumerate() {
        let sizes = build_sizes(
            loader,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            blas_flags(allow_update[i], !allow_update[i]),
            &geoms[i],
            g.triangle_count,
        );
        structs.push(AccelStruct::new(
            ctx,
            &format!("blas {i}"),
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            sizes.acceleration_structure_size,
        )?);
        scratch_offsets.push(scratch_total);
        scratch_total += sizes.build_scratch_size.div_ceil(align) * align;
    }
    let (_scratch, scratch_address) = scratch_buffer(ctx, "blas scratch", scratch_total.max(align))?;
    let compactable: Vec<usize> = (0..geometries.len()).filter(|&i| !allow_update[i]).collect();
    let query_pool = if compactable.is_empty() { None } else { compaction_query_pool(ctx, compactable.len() as u32) };
    pool.run(|cmd| {
        let infos: Vec<_> = (0..geometries.len())
            .map(|i| {
                vk::AccelerationStructureBuildGeometryInfoKHR::default()
                    .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                    .flags(blas_flags(allow_update[i], !allow_update[i]))
                    .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                    .dst_acceleration_structure(structs[i].raw)
                    .geometries(std::slice::from_ref(&geoms[i]))
                    .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch_address + scratch_offsets[i] })
            })
            .collect();
        let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> =
            geometries.iter().map(|g| [g.range()]).collect();
        let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> = ranges.iter().map(|r| &r[..]).collect();
        // SAFETY: `cmd` is recording (CommandPool::run). Each info has one geometry and one
        // range (`infos`, `geoms`, `ranges` index alike and outlive the call); each destination
        // was made above with the size this geometry's size query asked for; each build gets
        // its own aligned scratch region of the size queried, so no two builds overlap. The
        // vertex and index addresses are the scene's geometry buffers, which the caller keeps
        // alive (they outlive the structures), and `run` waits for the builds.
        unsafe { loader.cmd_build_acceleration_structures(cmd, &infos, &range_refs) };
        super::memory_barrier(
            ctx,
            cmd,
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR | vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
            ),
        );
        if let Some(qp) = &query_pool {
            let handles: Vec<_> = compactable.iter().map(|&i| structs[i].raw).collect();
            // SAFETY: recording; the pool holds exactly `handles.len()` compacted-size queries,
            // reset here before they are written; the structures were built with
            // ALLOW_COMPACTION and the barrier above orders their builds before the query.
            unsafe {
                ctx.device.cmd_reset_query_pool(cmd, qp.raw, 0, handles.len() as u32);
                loader.cmd_write_acceleration_structures_properties(
                    cmd,
                    &handles,
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    qp.raw,
                    0,
                )
            };
        }
        Ok(())
    })?;
    let built_bytes: u64 = structs.iter().map(|s| s.size).sum();
    let Some(qp) = query_pool else {
        return Ok((structs, BlasBuildStats { built_bytes, final_bytes: built_bytes, compacted: false }));
    };
    let mut sizes = vec![0u64; compactable.len()];
    // SAFETY: the submission that wrote these queries has finished (`run` waited); `sizes`
    // holds one u64 per query (TYPE_64), and WAIT makes every result available.
    unsafe {
        ctx.device.get_query_pool_results(
            qp.raw,
            0,
            &mut sizes,
            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
        )
    }
    .map_err(|e| super::commands::device_error("vkGetQueryPoolResults (compacted BLAS sizes)", e))?;
    let mut compacted = Vec::with_capacity(compactable.len());
    for (k, &i) in compactable.iter().enumerate() {
        let size = if sizes[k] == 0 { structs[i].size } else { sizes[k] };
        compacted.push(AccelStruct::new(
            ctx,
            &format!("blas {i} (compacted)"),
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            size,
        )?);
    }
    pool.run(|cmd| {
        for (k, &i) in compactable.iter().enumerate() {
            let info = vk::CopyAccelerationStructureInfoKHR::default()
                .src(structs[i].raw)
                .dst(compacted[k].raw)
                .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
            // SAFETY: recording; the source was built with ALLOW_COMPACTION and finished (the
            // previous `run` waited), the destination was made with at least the compacted size
            // the device reported (or the full size), and both live until `run` returns.
            unsafe { loader.cmd_copy_acceleration_structure(cmd, &info) };
        }
        super::memory_barrier(
            ctx,
            cmd,
            // Copies run in the build stage unless VK_KHR_ray_tracing_maintenance1 is enabled.
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR | vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
            ),
        );
        Ok(())
    })?;
    let mut compacted = compacted.into_iter();
    let result: Vec<AccelStruct> = structs
        .into_iter()
        .enumerate()
        .map(|(i, s)| if allow_update[i] { s } else { compacted.next().expect("one per compactable") })
        .collect();
    let final_bytes = result.iter().map(|s| s.size).sum();
    Ok((result, BlasBuildStats { built_bytes, final_bytes, compacted: true }))
}

/// Scratch for refitting (UPDATE) or rebuilding in place the bottom levels of deforming
/// meshes, one region per mesh sized for the larger of the two, so any mix of updates and
/// rebuilds records in one call.
pub struct BlasRefitter {
    _scratch: Buffer,
    scratch_address: vk::DeviceAddress,
    offsets: Vec<u64>,
}

/// What to record for one deforming mesh's bottom level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlasRefit {
    /// Mode UPDATE: new vertices, same topology; src = dst, cheap, the tree keeps its shape.
    Update,
    /// Mode BUILD into the same structure: a tree made for the current vertices.
    Rebuild,
}

impl BlasRefitter {
    /// Scratch for `geometries`, whose structures were built by [`build_blases`] with
    /// `allow_update` set.
    pub fn new(ctx: &Arc<Context>, geometries: &[BlasGeometry]) -> Result<Self> {
        let loader = accel_loader(ctx)?;
        let align = scratch_alignment(ctx);
        let mut offsets = Vec::with_capacity(geometries.len());
        let mut total = 0u64;
        for g in geometries {
            let sizes = build_sizes(
                loader,
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                blas_flags(true, false),
                &g.vk(),
                g.triangle_count,
            );
            offsets.push(total);
            total += sizes.build_scratch_size.max(sizes.update_scratch_size).div_ceil(align) * align;
        }
        let (scratch, scratch_address) = scratch_buffer(ctx, "blas refit scratch", total.max(align))?;
        Ok(Self { _scratch: scratch, scratch_address, offsets })
    }

    /// Records the updates and rebuilds of `work` (index into the geometries given to
    /// [`Self::new`], the structure, what to do) in one build call, after a barrier that
    /// orders them after earlier traces and builds. No barrier follows: the caller records
    /// [`Tlas::record_build`] next, whose leading barrier (build writes before build reads)
    /// is the one barrier between all bottom-level work of the frame and the top level.
    pub fn record(
        &self,
        rec: &Recorder,
        geometries: &[BlasGeometry],
        work: &[(usize, &AccelStruct, BlasRefit)],
    ) -> Result<()> {
        if work.is_empty() {
            return Ok(());
        }
        let loader = accel_loader(rec.ctx)?;
        let geoms: Vec<_> = work.iter().map(|&(i, _, _)| [geometries[i].vk()]).collect();
        let infos: Vec<_> = work
            .iter()
            .zip(&geoms)
            .map(|(&(i, blas, what), geom)| {
                let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
                    .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                    .flags(blas_flags(true, false))
                    .dst_acceleration_structure(blas.raw)
                    .geometries(geom)
                    .scratch_data(vk::DeviceOrHostAddressKHR {
                        device_address: self.scratch_address + self.offsets[i],
                    });
                match what {
                    BlasRefit::Update => {
                        info.mode(vk::BuildAccelerationStructureModeKHR::UPDATE).src_acceleration_structure(blas.raw)
                    }
                    BlasRefit::Rebuild => info.mode(vk::BuildAccelerationStructureModeKHR::BUILD),
                }
            })
            .collect();
        let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> =
            work.iter().map(|&(i, _, _)| [geometries[i].range()]).collect();
        let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> = ranges.iter().map(|r| &r[..]).collect();
        // Earlier traces read these structures, and earlier builds wrote them and the scratch.
        rec.memory_barrier(
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER
                    | vk::PipelineStageFlags2::FRAGMENT_SHADER
                    | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
        );
        // SAFETY: recording (`rec`). Each structure was built with ALLOW_UPDATE from the same
        // geometry description (topology and counts unchanged; only vertices move), as UPDATE
        // requires; each uses its own scratch region, sized for the larger of build and update
        // scratch; the barrier above orders this after earlier reads and builds. The caller
        // keeps structures and geometry buffers alive until the frame's fence wait.
        unsafe { loader.cmd_build_acceleration_structures(rec.cmd, &infos, &range_refs) };
        Ok(())
    }
}

struct QueryPool {
    ctx: Arc<Context>,
    raw: vk::QueryPool,
}

impl Drop for QueryPool {
    fn drop(&mut self) {
        // SAFETY: made by compaction_query_pool, destroyed once, after the results were read
        // (the submissions using it were waited for).
        unsafe { self.ctx.device.destroy_query_pool(self.raw, None) };
    }
}

/// A pool for compacted-size queries, or `None` when the device cannot make one (then the
/// structures stay as built).
fn compaction_query_pool(ctx: &Arc<Context>, count: u32) -> Option<QueryPool> {
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
        .query_count(count);
    // SAFETY: creation on a live device from an info on this stack frame.
    match unsafe { ctx.device.create_query_pool(&info, None) } {
        Ok(raw) => Some(QueryPool { ctx: ctx.clone(), raw }),
        Err(e) => {
            log::info!("acceleration-structure compaction unavailable ({e}); keeping structures as built");
            None
        }
    }
}

/// One instance of the top level.
#[derive(Clone, Copy, Debug)]
pub struct TlasInstance {
    /// Row-major 3x4 object-to-world transform (VkTransformMatrixKHR).
    pub transform: [[f32; 4]; 3],
    pub custom_index: u32,
    pub mask: u8,
    pub blas_address: vk::DeviceAddress,
}

/// The top level with its instance buffer and scratch, sized for a fixed instance count and
/// rebuilt in place each time instances move.
pub struct Tlas {
    pub accel: AccelStruct,
    instances: Buffer,
    _scratch: Buffer,
    scratch_address: vk::DeviceAddress,
    count: u32,
    /// Instances were written: a build before that would read uninitialised memory.
    written: bool,
}

impl Tlas {
    pub fn new(ctx: &Arc<Context>, count: u32) -> Result<Self> {
        let loader = accel_loader(ctx)?;
        let instances = Buffer::new(
            ctx,
            "tlas instances",
            (count.max(1) as u64) * size_of::<vk::AccelerationStructureInstanceKHR>() as u64,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::CpuToGpu,
        )?;
        let sizes = build_sizes(
            loader,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE,
            &Self::geometry(instances.address),
            count,
        );
        let accel = AccelStruct::new(
            ctx,
            "tlas",
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            sizes.acceleration_structure_size,
        )?;
        let (scratch, scratch_address) = scratch_buffer(ctx, "tlas scratch", sizes.build_scratch_size)?;
        Ok(Self { accel, instances, _scratch: scratch, scratch_address, count, written: false })
    }

    fn geometry(address: vk::DeviceAddress) -> vk::AccelerationStructureGeometryKHR<'static> {
        let data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR { device_address: address });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances: data })
    }

    /// Writes the instances (host side; call while the GPU is not reading the TLAS).
    pub fn write_instances(&mut self, list: &[TlasInstance]) -> Result<()> {
        if list.len() as u32 != self.count {
            return Err(anyhow!("TLAS made for {} instances, given {}", self.count, list.len()));
        }
        let raw: Vec<vk::AccelerationStructureInstanceKHR> = list
            .iter()
            .map(|i| vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: [i.transform[0], i.transform[1], i.transform[2]].concat().try_into().expect("12 floats"),
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(i.custom_index, i.mask),
                // Rays see both faces; facing is reported, not culled.
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: i.blas_address,
                },
            })
            .collect();
        // SAFETY: VkAccelerationStructureInstanceKHR is a plain C struct of 64 bytes with no
        // padding; viewing the array as bytes to copy it into mapped memory is sound.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                raw.as_ptr() as *const u8,
                raw.len() * size_of::<vk::AccelerationStructureInstanceKHR>(),
            )
        };
        self.instances.write(0, bytes)?;
        self.written = true;
        Ok(())
    }

    /// Records a full rebuild from the written instances, then a barrier that makes the TLAS
    /// visible to ray queries in compute shaders.
    pub fn record_build(&self, rec: &Recorder) -> Result<()> {
        let loader = accel_loader(rec.ctx)?;
        if !self.written {
            return Err(anyhow!("TLAS built before its instances were written"));
        }
        let geom = [Self::geometry(self.instances.address)];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .dst_acceleration_structure(self.accel.raw)
            .geometries(&geom)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: self.scratch_address });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR {
            primitive_count: self.count,
            primitive_offset: 0,
            first_vertex: 0,
            transform_offset: 0,
        }];
        // The previous frame's rays must be done with the TLAS (and scratch) before it is rebuilt.
        rec.memory_barrier(
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR | vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
            ),
        );
        // SAFETY: recording; the destination and scratch were sized for `count` instances
        // (the size query in `new`), and the instance buffer holds exactly `count` written
        // instances (write_instances checks, `written` above). Their BLAS addresses are the
        // caller's (`TlasInstance::blas_address`: the hardware backend passes its own live
        // BLASes, which it keeps for as long as the TLAS). The barrier above orders the
        // rebuild after the last frame's traces and the BLAS builds.
        unsafe { loader.cmd_build_acceleration_structures(rec.cmd, &[info], &[&range]) };
        rec.memory_barrier(
            (
                vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            ),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER,
                vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
            ),
        );
        Ok(())
    }
}

/// Sizes of the structure, build scratch and update scratch for one geometry of `primitives`
/// triangles or instances.
fn build_sizes(
    loader: &ash::khr::acceleration_structure::Device,
    ty: vk::AccelerationStructureTypeKHR,
    flags: vk::BuildAccelerationStructureFlagsKHR,
    geometry: &vk::AccelerationStructureGeometryKHR,
    primitives: u32,
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(flags)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(std::slice::from_ref(geometry));
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: a size query (no device memory is read); `info` has one geometry and one count,
    // and `sizes` is written by the call.
    unsafe {
        loader.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[primitives],
            &mut sizes,
        )
    };
    sizes
}
