//! Pass-level capture: every named output of the frame graph written as EXR (exact values)
//! and PNG (a preview made for eyes: normals, depth, ids and motion made visible), plus a
//! manifest.json saying which pass wrote what, in which format and size, at which frame, and
//! how long the pass took on the GPU.

use crate::graph::Preview;
use crate::image_io::{self, CpuImage};
use crate::render::Renderer;
use anyhow::{Result, bail};
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Serialize)]
pub struct ManifestEntry {
    pub pass: String,
    pub output: String,
    pub format: String,
    pub width: u32,
    pub height: u32,
    /// 1-based number of the frame.
    pub frame: u32,
    pub gpu_ms: Option<f64>,
    pub exr: String,
    pub png: String,
    pub preview: Preview,
}

#[derive(Serialize)]
pub struct Manifest {
    pub scene: String,
    pub device: String,
    pub entries: Vec<ManifestEntry>,
}

/// Where a capture goes, created on the first dump.
pub struct Capture {
    pub dir: PathBuf,
    /// Write each frame into its own `frame_NNNN` folder (several frames were asked for).
    per_frame_folders: bool,
    /// Replace files that are in the way.
    force: bool,
    manifest: Manifest,
}

impl Capture {
    /// Refuses a folder that already holds a capture unless `force`.
    pub fn new(dir: &Path, per_frame_folders: bool, force: bool, scene: &str, device: &str) -> Result<Self> {
        let manifest_path = dir.join("manifest.json");
        if manifest_path.exists() && !force {
            bail!("{}: already holds a capture; pass --force to overwrite it", dir.display());
        }
        if dir.exists() && !dir.is_dir() {
            bail!("{}: exists and is not a folder", dir.display());
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            per_frame_folders,
            force,
            manifest: Manifest { scene: scene.to_string(), device: device.to_string(), entries: Vec::new() },
        })
    }

    /// Dumps every output of the frame the renderer rendered last.
    pub fn dump(&mut self, r: &mut Renderer) -> Result<()> {
        // Frames are numbered from 1, as on the command line (--dump-frames).
        let frame = r.frame_index;
        let folder = if self.per_frame_folders { self.dir.join(format!("frame_{frame:04}")) } else { self.dir.clone() };
        let names = r.graph.output_order.clone();
        // A folder without a manifest may still hold files of the same names (a capture whose
        // manifest was removed, or the user's own): none is replaced without --force.
        for name in &names {
            for ext in ["exr", "png"] {
                image_io::check_overwrite(&folder.join(format!("{name}.{ext}")), self.force)?;
            }
        }
        let images = r.read_outputs(&names)?;
        for (name, img) in names.iter().zip(&images) {
            let desc = r.graph.images.desc(*name).expect("graph output").clone();
            let pass = r.graph.producer(*name).unwrap_or("?").to_string();
            let exr = folder.join(format!("{name}.exr"));
            let png = folder.join(format!("{name}.png"));
            image_io::write_exr(&exr, img, image_io::channel_names(img.channels))?;
            let rgba = preview(img, desc.preview);
            image_io::write_png_rgba8(&png, img.width, img.height, &rgba)?;
            let gpu_ms = r.last_pass_times.iter().find(|t| t.pass == pass).map(|t| t.gpu_ms);
            self.manifest.entries.push(ManifestEntry {
                output: name.to_string(),
                pass,
                format: format!("{:?}", desc.format),
                width: img.width,
                height: img.height,
                frame,
                gpu_ms,
                exr: relative(&self.dir, &exr),
                png: relative(&self.dir, &png),
                preview: desc.preview,
            });
        }
        self.write_manifest()
    }

    fn write_manifest(&self) -> Result<()> {
        let json = serde_json::to_vec_pretty(&self.manifest)?;
        image_io::write_atomic(&self.dir.join("manifest.json"), |tmp| Ok(std::fs::write(tmp, &json)?))
    }
}

fn relative(base: &Path, p: &Path) -> String {
    p.strip_prefix(base).unwrap_or(p).to_string_lossy().into_owned()
}

/// An 8-bit RGBA picture of an output, made for looking at.
pub fn preview(img: &CpuImage, kind: Preview) -> Vec<u8> {
    let n = img.pixel_count();
    let mut out = vec![0u8; n * 4];
    let ch = |i: usize, c: usize| {
        if c < img.channels {
            img.get((i % img.width as usize) as u32, (i / img.width as usize) as u32, c)
        } else {
            0.0
        }
    };
    let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    let srgb = |v: f32| {
        let v = v.clamp(0.0, 1.0);
        if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
    };
    let (lo, hi) = range(img);
    let motion_scale = (0..n).map(|i| ch(i, 0).abs().max(ch(i, 1).abs())).fold(0.0f32, f32::max).max(1e-6);
    for i in 0..n {
        let px: [u8; 4] = match kind {
            Preview::Color => {
                let g = |c| if img.channels == 1 { ch(i, 0) } else { ch(i, c) };
                [to8(srgb(g(0))), to8(srgb(g(1))), to8(srgb(g(2))), 255]
            }
            Preview::Display => [to8(ch(i, 0)), to8(ch(i, 1)), to8(ch(i, 2)), 255],
            Preview::Normal => [to8(ch(i, 0) * 0.5 + 0.5), to8(ch(i, 1) * 0.5 + 0.5), to8(ch(i, 2) * 0.5 + 0.5), 255],
            Preview::Depth => {
                let d = ch(i, 0);
                let v = if d > 0.0 && hi > lo {
                    1.0 - 0.85 * (d - lo) / (hi - lo)
                } else if d > 0.0 {
                    1.0
                } else {
                    0.0
                };
                [to8(v), to8(v), to8(v), 255]
            }
            Preview::Ids => id_colour(img.get_u32((i % img.width as usize) as u32, (i / img.width as usize) as u32, 0)),
            Preview::Motion => {
                [to8(0.5 + 0.5 * ch(i, 0) / motion_scale), to8(0.5 + 0.5 * ch(i, 1) / motion_scale), 128, 255]
            }
            Preview::Tint => match img.get_u32((i % img.width as usize) as u32, (i / img.width as usize) as u32, 0) {
                0 => [255; 4],
                packed => [packed as u8, (packed >> 8) as u8, (packed >> 16) as u8, 255],
            },
            Preview::Scalar => {
                let v = if hi > lo { (ch(i, 0) - lo) / (hi - lo) } else { 0.0 };
                [to8(v), to8(v), to8(v), 255]
            }
        };
        out[i * 4..i * 4 + 4].copy_from_slice(&px);
    }
    out
}

/// Min and max of channel 0 over pixels with a positive value (depth: 0 means no surface).
fn range(img: &CpuImage) -> (f32, f32) {
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for y in 0..img.height {
        for x in 0..img.width {
            let v = img.get(x, y, 0);
            if v.is_finite() && v > 0.0 {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if lo > hi { (0.0, 0.0) } else { (lo, hi) }
}

/// A stable, well-spread colour per id; "no id" is black.
fn id_colour(id: u32) -> [u8; 4] {
    if id == u32::MAX {
        return [0, 0, 0, 255];
    }
    let mut h = id.wrapping_mul(0x9E37_79B9) ^ 0x5bd1_e995;
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    [64 + (h & 0xbf) as u8, 64 + ((h >> 8) & 0xbf) as u8, 64 + ((h >> 16) & 0xbf) as u8, 255]
}
