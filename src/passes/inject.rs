//! inject: puts an image made on the CPU into the frame under a name, in place of the pass
//! that would compute it. Tests use it to feed the denoisers known signals (an impulse, a
//! checkerboard, noise with a known mean).

use crate::gpu::{Buffer, Context, MemoryLocation, vk};
use crate::graph::{Output, OutputDesc, Pass, PassContext, PassDesc, PassKind, Preview, Usage};
use anyhow::{Result, bail};
use std::sync::{Arc, Mutex};

pub const NAME: &str = "inject";

/// The RGBA f32 texels the next frame will see; shared with whoever fills it.
pub type Texels = Arc<Mutex<Vec<[f32; 4]>>>;

pub struct InjectPass {
    output: Output,
    staging: Buffer,
    texels: Texels,
}

/// An injected RGBA32F image, `extent` texels, named `output` (declared by the caller with
/// [`NAME`] as its pass: `Output::new(inject::NAME, "signal")`).
pub fn new(ctx: &Arc<Context>, output: Output, extent: vk::Extent2D) -> Result<(InjectPass, Texels)> {
    let n = (extent.width * extent.height) as usize;
    let staging = Buffer::new(
        ctx,
        "inject staging",
        (n * 16) as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
    )?;
    let texels: Texels = Arc::new(Mutex::new(vec![[0.0; 4]; n]));
    Ok((InjectPass { output, staging, texels: texels.clone() }, texels))
}

impl Pass for InjectPass {
    fn desc(&self) -> PassDesc {
        PassDesc {
            name: NAME.into(),
            kind: PassKind::Transfer,
            inputs: Vec::new(),
            outputs: vec![OutputDesc {
                name: self.output.into(),
                format: vk::Format::R32G32B32A32_SFLOAT,
                usage: Usage::Transfer,
                preview: Preview::Color,
                extent: None,
            }],
        }
    }

    fn record(&mut self, ctx: &PassContext) -> Result<()> {
        let texels = self.texels.lock().map_err(|_| anyhow::anyhow!("inject texels poisoned"))?;
        if texels.len() * 16 != self.staging.size as usize {
            bail!("inject: {} texels given for a {}-byte image", texels.len(), self.staging.size);
        }
        // Written while recording, before the frame's submission: the host write is visible.
        self.staging.write(0, bytemuck::cast_slice(&texels))?;
        ctx.rec.copy_buffer_to_image(&self.staging, ctx.images.get(self.output));
        Ok(())
    }
}
