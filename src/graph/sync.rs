//! Barrier placement. Each image remembers its last write and the reads since; before a pass
//! runs, one global memory barrier covers every hazard its declared reads and writes have
//! (read-after-write, write-after-write, write-after-read). Images stay in GENERAL layout, so
//! no layout transitions are needed after their first use.

use super::{PassKind, Resource, Usage};
use crate::gpu::{Recorder, vk};
use std::collections::HashMap;

type Stage = vk::PipelineStageFlags2;
type Acc = vk::AccessFlags2;

#[derive(Clone, Copy, Debug)]
pub struct Access {
    stage: Stage,
    access: Acc,
}

impl Access {
    pub fn read(kind: PassKind) -> Self {
        match kind {
            PassKind::Compute => {
                Self { stage: Stage::COMPUTE_SHADER, access: Acc::SHADER_STORAGE_READ | Acc::SHADER_SAMPLED_READ }
            }
            PassKind::Raster => {
                Self { stage: Stage::FRAGMENT_SHADER, access: Acc::SHADER_STORAGE_READ | Acc::SHADER_SAMPLED_READ }
            }
            // (A history pass reads nothing on the GPU; the graph places no barrier for it.)
            PassKind::Transfer | PassKind::History => Self::transfer_read(),
        }
    }

    pub fn write(usage: Usage) -> Self {
        match usage {
            // Read too: atomics (the SVGF rejection counter) read what they write.
            Usage::Storage => {
                Self { stage: Stage::COMPUTE_SHADER, access: Acc::SHADER_STORAGE_WRITE | Acc::SHADER_STORAGE_READ }
            }
            Usage::Transfer => Self { stage: Stage::COPY, access: Acc::TRANSFER_WRITE },
            Usage::ColorAttachment => Self {
                stage: Stage::COLOR_ATTACHMENT_OUTPUT,
                access: Acc::COLOR_ATTACHMENT_WRITE | Acc::COLOR_ATTACHMENT_READ,
            },
            Usage::DepthAttachment => Self {
                stage: Stage::EARLY_FRAGMENT_TESTS | Stage::LATE_FRAGMENT_TESTS,
                access: Acc::DEPTH_STENCIL_ATTACHMENT_WRITE | Acc::DEPTH_STENCIL_ATTACHMENT_READ,
            },
        }
    }

    pub fn transfer_read() -> Self {
        Self { stage: Stage::COPY, access: Acc::TRANSFER_READ }
    }
}

#[derive(Default)]
pub struct SyncState {
    write: Option<Access>,
    /// Stages that already see the last write.
    visible_to: Stage,
    /// Stages that read since the last write (a later write must wait for them).
    reads: Stage,
}

pub fn barrier(
    rec: &Recorder,
    state: &mut HashMap<Resource, SyncState>,
    reads: &[(Resource, Access)],
    writes: &[(Resource, Access)],
) {
    let (mut src_s, mut src_a, mut dst_s, mut dst_a) = (Stage::NONE, Acc::NONE, Stage::NONE, Acc::NONE);
    for (name, r) in reads {
        let st = state.entry(*name).or_default();
        if let Some(w) = st.write
            && !st.visible_to.contains(r.stage)
        {
            src_s |= w.stage;
            src_a |= w.access;
            dst_s |= r.stage;
            dst_a |= r.access;
            st.visible_to |= r.stage;
        }
        st.reads |= r.stage;
    }
    for (name, w) in writes {
        let st = state.entry(*name).or_default();
        if let Some(prev) = st.write {
            src_s |= prev.stage;
            src_a |= prev.access;
            dst_s |= w.stage;
            dst_a |= w.access;
        }
        if st.reads != Stage::NONE {
            // Write-after-read needs only an execution dependency.
            src_s |= st.reads;
            dst_s |= w.stage;
        }
        st.write = Some(*w);
        st.visible_to = Stage::NONE;
        st.reads = Stage::NONE;
    }
    if src_s != Stage::NONE {
        rec.memory_barrier((src_s, src_a), (dst_s, dst_a));
    }
}
