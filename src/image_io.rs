//! Images on the CPU: read-back from the GPU in any of the renderer's formats, and writing
//! PNG and EXR files. Files are written to a temporary name and renamed into place, so a crash
//! never leaves a half-written image, and an existing file is only replaced when asked.

use anyhow::{Context as _, Result, bail};
use ash::vk;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub enum Texels {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

/// A read-back image: `channels` values per pixel, rows top to bottom.
#[derive(Clone, Debug)]
pub struct CpuImage {
    pub width: u32,
    pub height: u32,
    pub channels: usize,
    pub texels: Texels,
    pub format: vk::Format,
}

impl CpuImage {
    /// Decodes raw bytes of a GPU image of `format`.
    pub fn from_raw(format: vk::Format, width: u32, height: u32, bytes: &[u8]) -> Result<Self> {
        let f32s = |b: &[u8]| b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let (channels, texels) = match format {
            vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => (1, Texels::F32(f32s(bytes))),
            vk::Format::R32G32_SFLOAT => (2, Texels::F32(f32s(bytes))),
            vk::Format::R32G32B32A32_SFLOAT => (4, Texels::F32(f32s(bytes))),
            vk::Format::R16G16B16A16_SFLOAT => (
                4,
                Texels::F32(bytes.chunks_exact(2).map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()),
            ),
            vk::Format::R16_SFLOAT => (
                1,
                Texels::F32(bytes.chunks_exact(2).map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()),
            ),
            vk::Format::R8G8B8A8_UNORM => (4, Texels::F32(bytes.iter().map(|&b| b as f32 / 255.0).collect())),
            vk::Format::R8_UNORM => (1, Texels::F32(bytes.iter().map(|&b| b as f32 / 255.0).collect())),
            vk::Format::R32_UINT => (1, Texels::U32(bytemuck::pod_collect_to_vec(bytes))),
            vk::Format::R32G32_UINT => (2, Texels::U32(bytemuck::pod_collect_to_vec(bytes))),
            vk::Format::R32G32B32A32_UINT => (4, Texels::U32(bytemuck::pod_collect_to_vec(bytes))),
            other => bail!("read-back of format {other:?} is not supported"),
        };
        Ok(Self { width, height, channels, texels, format })
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Channel `c` of pixel (x, y) as f32 (ids converted).
    pub fn get(&self, x: u32, y: u32, c: usize) -> f32 {
        let i = (y as usize * self.width as usize + x as usize) * self.channels + c;
        match &self.texels {
            Texels::F32(v) => v[i],
            Texels::U32(v) => v[i] as f32,
        }
    }

    pub fn get_u32(&self, x: u32, y: u32, c: usize) -> u32 {
        let i = (y as usize * self.width as usize + x as usize) * self.channels + c;
        match &self.texels {
            Texels::F32(v) => v[i] as u32,
            Texels::U32(v) => v[i],
        }
    }

    pub fn as_f32(&self) -> Option<&[f32]> {
        match &self.texels {
            Texels::F32(v) => Some(v),
            Texels::U32(_) => None,
        }
    }
}

/// Refuses to replace an existing file unless `force`.
pub fn check_overwrite(path: &Path, force: bool) -> Result<()> {
    if path.exists() && !force {
        bail!("{}: file exists; pass --force to overwrite it", path.display());
    }
    Ok(())
}

/// Writes through `write` to a temporary file beside `path`, then renames it into place.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create folder", dir.display()))?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // Keep the extension last: image encoders choose the format by it.
    let tmp: PathBuf = dir.join(format!(".{}.partial-{}{}", name, std::process::id(), extension_of(path)));
    let result = write(&tmp)
        .and_then(|_| injected_failure(&name, &tmp))
        // On disk before the rename: after a system crash the name holds the old file or the
        // whole new one, never a new one cut short.
        .and_then(|_| {
            std::fs::File::open(&tmp)
                .and_then(|f| f.sync_all())
                .with_context(|| format!("{}: cannot flush to disk", tmp.display()))
        })
        .and_then(|_| {
            std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot move into place", path.display()))
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A test hook (tests/nothing_lost.rs): `HYBRID_RT_FAIL_WRITE=NAME` makes the write of a file
/// named NAME fail after its temporary file was written, cut to half its length, as a write
/// that died part way; `NAME:abort` kills the process at that point instead, as a crash.
fn injected_failure(name: &str, tmp: &Path) -> Result<()> {
    let Ok(spec) = std::env::var("HYBRID_RT_FAIL_WRITE") else {
        return Ok(());
    };
    let (target, abort) = match spec.strip_suffix(":abort") {
        Some(t) => (t, true),
        None => (spec.as_str(), false),
    };
    if target != name {
        return Ok(());
    }
    let half = std::fs::metadata(tmp).map(|m| m.len() / 2).unwrap_or(0);
    std::fs::OpenOptions::new().write(true).open(tmp).and_then(|f| f.set_len(half))?;
    if abort {
        std::process::abort();
    }
    bail!("{name}: write failed part way (injected by HYBRID_RT_FAIL_WRITE)")
}

fn extension_of(path: &Path) -> String {
    path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default()
}

pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    write_atomic(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
            image::ImageFormat::Png,
        )
        .with_context(|| format!("{}: cannot write PNG", path.display()))
    })
}

/// Writes all channels with exact values: f32 as 32-bit float, ids as 32-bit unsigned.
pub fn write_exr(path: &Path, img: &CpuImage, channel_names: &[&str]) -> Result<()> {
    use exr::prelude::*;
    let n = img.pixel_count();
    let mut list = smallvec::SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for c in 0..img.channels {
        let samples = match &img.texels {
            Texels::F32(v) => FlatSamples::F32((0..n).map(|i| v[i * img.channels + c]).collect()),
            Texels::U32(v) => FlatSamples::U32((0..n).map(|i| v[i * img.channels + c]).collect()),
        };
        list.push(AnyChannel::new(channel_names[c], samples));
    }
    let layer = Layer::new(
        (img.width as usize, img.height as usize),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    write_atomic(path, |tmp| {
        Image::from_layer(layer).write().to_file(tmp).with_context(|| format!("{}: cannot write EXR", path.display()))
    })
}

/// Default channel names for an image's channel count.
pub fn channel_names(channels: usize) -> &'static [&'static str] {
    match channels {
        1 => &["Y"],
        2 => &["R", "G"],
        3 => &["R", "G", "B"],
        _ => &["R", "G", "B", "A"],
    }
}

/// Reads every channel of the first layer of an EXR (as written by [`write_exr`]) as f32.
/// EXR stores channels sorted by name; they come back in R, G, B, A (or Y) order, others after.
pub fn read_exr_channels(path: &Path) -> Result<CpuImage> {
    use exr::prelude::*;
    let image =
        read_first_flat_layer_from_file(path).with_context(|| format!("{}: cannot read EXR", path.display()))?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channels = layer.channel_data.list.len();
    let rank = |name: &str| ["Y", "R", "G", "B", "A"].iter().position(|n| *n == name).unwrap_or(5);
    let mut list: Vec<_> = layer.channel_data.list.iter().collect();
    list.sort_by_key(|ch| rank(&ch.name.to_string()));
    let mut px = vec![0f32; w * h * channels];
    for (c, ch) in list.iter().enumerate() {
        for (i, v) in ch.sample_data.values_as_f32().enumerate() {
            px[i * channels + c] = v;
        }
    }
    Ok(CpuImage { width: w as u32, height: h as u32, channels, texels: Texels::F32(px), format: vk::Format::UNDEFINED })
}
/// Reads an RGB(A) float EXR (the first layer) as a 4-channel image.
pub fn read_exr_rgba(path: &Path) -> Result<CpuImage> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![0f32; res.width() * res.height() * 4]),
        |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            let i = (pos.y() * *w + pos.x()) * 4;
            px[i..i + 4].copy_from_slice(&[r, g, b, a]);
        },
    )
    .with_context(|| format!("{}: cannot read EXR", path.display()))?;
    let size = image.layer_data.size;
    let (_, px) = image.layer_data.channel_data.pixels;
    Ok(CpuImage {
        width: size.width() as u32,
        height: size.height() as u32,
        channels: 4,
        texels: Texels::F32(px),
        format: vk::Format::R32G32B32A32_SFLOAT,
    })
}
