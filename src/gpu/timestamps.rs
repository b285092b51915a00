//! GPU timestamps: one pair per pass, read back after the frame's fence, so each pass's GPU
//! time lands in the capture manifest and the bench.

use super::Context;
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

pub struct TimestampPool {
    ctx: Arc<Context>,
    pool: vk::QueryPool,
    pub capacity: u32,
}

impl TimestampPool {
    pub fn new(ctx: &Arc<Context>, capacity: u32) -> Result<Self> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: creation on a live device from an info on this stack frame.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }.context("create timestamp pool")?;
        // SAFETY: host reset of the whole new pool; hostQueryReset is enabled by create_device.
        unsafe { ctx.device.reset_query_pool(pool, 0, capacity) };
        Ok(Self { ctx: ctx.clone(), pool, capacity })
    }

    pub fn supported(&self) -> bool {
        self.ctx.caps.timestamp_period_ns > 0.0
    }

    /// Resets all queries; recorded at the start of a frame.
    pub fn reset(&self, cmd: vk::CommandBuffer) {
        // SAFETY: `cmd` is a recording command buffer of this device outside a render pass
        // instance (callers pass their `Recorder::cmd` at the start of a frame); the range is
        // the whole pool, which is live.
        unsafe { self.ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
    }

    pub(super) fn write(&self, cmd: vk::CommandBuffer, index: u32) {
        // A query past the pool is a bug in the caller's pass count, never data-dependent.
        assert!(index < self.capacity, "timestamp {index} of a pool of {}", self.capacity);
        self.ctx.cmd_write_timestamp2(cmd, self.pool, index);
    }

    /// Reads `count` timestamps (after the frame's fence) as milliseconds from the first; `None`
    /// when the device has no timestamps.
    pub fn read_ms(&self, count: u32) -> Option<Vec<f64>> {
        if !self.supported() || count == 0 || count > self.capacity {
            return None;
        }
        let mut raw = vec![0u64; count as usize];
        // SAFETY: queries 0..count of the live pool (count <= capacity, checked above) into
        // `raw`, which holds `count` u64s (TYPE_64). Without WAIT, queries not yet available
        // make the call return NOT_READY, mapped to None.
        let r =
            unsafe { self.ctx.device.get_query_pool_results(self.pool, 0, &mut raw, vk::QueryResultFlags::TYPE_64) };
        r.ok()?;
        let period = self.ctx.caps.timestamp_period_ns as f64;
        Some(raw.iter().map(|t| (t.wrapping_sub(raw[0])) as f64 * period * 1e-6).collect())
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        // SAFETY: made by `new`, destroyed once; the frame graph that owns it is dropped only
        // after its last frame was waited for.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
