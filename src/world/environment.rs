//! The environment: the radiance rays see when they leave the scene. A constant colour, or an
//! equirectangular HDR map (.exr or .hdr) that light sampling draws directions from in
//! proportion to luminance x solid angle, through a marginal CDF over rows and one conditional
//! CDF per row (shaders-glsl/common/light_sampling.glsl reads them).
//!
//! Map convention (mirrored in the shader): u = 0.5 + atan2(x, -z) / 2pi, so u = 0.5 looks down
//! -Z and u grows toward +X; v = theta / pi with theta measured from +Y, so row 0 is the zenith.
//! Texels are looked up nearest, so radiance is constant over a texel, as the CDF assumes.

use anyhow::{Context as _, Result, bail};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// What surrounds the scene (`Settings::environment`).
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The default light: the daylight sky of sky.rs when the scene brings no light of its
    /// own, black otherwise (the rule is in default_light.rs). `Settings::default()`'s choice.
    DefaultLight,
    /// The same radiance from every direction.
    Constant(Vec3),
    /// An equirectangular map file and a multiplier applied to its radiance.
    Map(PathBuf, f32),
}

/// Black: no light from outside.
impl Default for Environment {
    fn default() -> Self {
        Environment::Constant(Vec3::ZERO)
    }
}

/// An environment ready for upload.
#[derive(Clone, Debug)]
pub struct EnvironmentData {
    /// Map size in texels; 0 x 0 for a constant environment.
    pub width: u32,
    pub height: u32,
    /// Radiance of a constant environment (zero for a map).
    pub constant: Vec3,
    /// Map radiance with the multiplier applied, row 0 first.
    pub texels: Vec<[f32; 3]>,
    /// Marginal CDF over rows (height + 1 values from 0 to 1), then one conditional CDF per row
    /// (width + 1 values each).
    pub cdf: Vec<f32>,
    /// Radiance averaged over the sphere of directions.
    pub mean: Vec3,
}

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Unit direction of map coordinates `uv` in [0, 1]^2.
pub fn direction(uv: Vec2) -> Vec3 {
    let phi = (uv.x - 0.5) * std::f32::consts::TAU;
    let theta = uv.y * std::f32::consts::PI;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// Map coordinates of unit direction `dir`.
pub fn uv(dir: Vec3) -> Vec2 {
    Vec2::new(dir.x.atan2(-dir.z) / std::f32::consts::TAU + 0.5, dir.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
}

/// Solid angle of one texel of row `row` in a `width` x `height` map.
pub fn texel_solid_angle(row: u32, width: u32, height: u32) -> f64 {
    let theta = |r: u32| PI * r as f64 / height as f64;
    2.0 * PI / width as f64 * (theta(row).cos() - theta(row + 1).cos())
}

impl EnvironmentData {
    /// Loads and prepares `env`. A missing or undecodable map file is an error naming it.
    /// `DefaultLight` gives black here: whether a scene gets the sky instead is
    /// default_light.rs's decision.
    pub fn load(env: &Environment) -> Result<Self> {
        match env {
            Environment::DefaultLight => Ok(Self::constant(Vec3::ZERO)),
            Environment::Constant(c) => Ok(Self::constant(*c)),
            Environment::Map(path, intensity) => {
                if !intensity.is_finite() || *intensity < 0.0 {
                    bail!("environment map {}: intensity {intensity} must be finite and >= 0", path.display());
                }
                let (w, h, texels) = read_map(path)?;
                let scaled = texels.iter().map(|t| (Vec3::from(*t) * *intensity).to_array()).collect();
                Ok(Self::from_texels(w, h, scaled))
            }
        }
    }

    pub fn constant(c: Vec3) -> Self {
        Self { width: 0, height: 0, constant: c, texels: Vec::new(), cdf: Vec::new(), mean: c }
    }

    /// A map from radiance texels (row 0 = zenith). Negative and non-finite texels count as 0.
    pub fn from_texels(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Self {
        assert_eq!(texels.len(), (width * height) as usize, "texel count of a {width}x{height} map");
        let texels: Vec<[f32; 3]> =
            texels.into_iter().map(|t| t.map(|c| if c.is_finite() && c > 0.0 { c } else { 0.0 })).collect();
        let (w, h) = (width as usize, height as usize);
        // Weight of a texel: luminance x its solid angle (the integral of sin(theta) over it).
        let weights: Vec<f64> = (0..h)
            .flat_map(|y| {
                let omega = texel_solid_angle(y as u32, width, height);
                texels[y * w..(y + 1) * w].iter().map(move |t| luminance(Vec3::from(*t)) as f64 * omega)
            })
            .collect();
        let row_sums: Vec<f64> = weights.chunks(w).map(|r| r.iter().sum()).collect();
        let mut cdf = cumulative(&row_sums);
        for row in weights.chunks(w) {
            cdf.extend(cumulative(row));
        }
        let mut mean = Vec3::ZERO;
        for (y, row) in texels.chunks(w).enumerate() {
            let omega = texel_solid_angle(y as u32, width, height) as f32;
            mean += row.iter().map(|t| Vec3::from(*t)).sum::<Vec3>() * omega;
        }
        mean /= 4.0 * std::f32::consts::PI;
        Self { width, height, constant: Vec3::ZERO, texels, cdf, mean }
    }
}

/// CDF of `weights`: n + 1 values from exactly 0 to exactly 1; uniform when all are zero.
fn cumulative(weights: &[f64]) -> Vec<f32> {
    let total: f64 = weights.iter().sum();
    let n = weights.len();
    let mut out = Vec::with_capacity(n + 1);
    let mut acc = 0.0f64;
    out.push(0.0);
    for (i, w) in weights.iter().enumerate() {
        acc += w;
        out.push(if total > 0.0 { (acc / total) as f32 } else { (i + 1) as f32 / n as f32 });
    }
    out[n] = 1.0;
    out
}

fn read_map(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    if !path.is_file() {
        bail!("environment map {}: no such file", path.display());
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let map = match ext.as_deref() {
        Some("exr") => read_exr_rgb(path)?,
        Some("hdr") => {
            let img = image::open(path)
                .with_context(|| format!("environment map {}: cannot decode", path.display()))?
                .into_rgb32f();
            (img.width(), img.height(), img.pixels().map(|p| p.0).collect())
        }
        _ => bail!("environment map {}: unsupported format (expected .exr or .hdr)", path.display()),
    };
    if map.0 == 0 || map.1 == 0 {
        bail!("environment map {}: the image is empty", path.display());
    }
    Ok(map)
}

/// The first RGB(A) layer of an EXR as RGB (alpha, if any, is ignored).
fn read_exr_rgb(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * *w + pos.x()] = [r, g, b],
    )
    .with_context(|| format!("environment map {}: cannot decode", path.display()))?;
    let size = image.layer_data.size;
    Ok((size.width() as u32, size.height() as u32, image.layer_data.channel_data.pixels.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_and_direction_are_inverse() {
        for &(u, v) in &[(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.26, 0.95)] {
            let back = uv(direction(Vec2::new(u, v)));
            assert!((back - Vec2::new(u, v)).abs().max_element() < 1e-5, "({u}, {v}) -> {back}");
        }
        // The documented landmarks: row 0 is +Y, u = 0.5 looks down -Z, u = 0.75 toward +X.
        assert!(direction(Vec2::new(0.3, 0.0)).abs_diff_eq(Vec3::Y, 1e-6));
        assert!(direction(Vec2::new(0.5, 0.5)).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(direction(Vec2::new(0.75, 0.5)).abs_diff_eq(Vec3::X, 1e-6));
    }

    #[test]
    fn texel_solid_angles_cover_the_sphere() {
        let total: f64 = (0..16).map(|y| 32.0 * texel_solid_angle(y, 32, 16)).sum();
        assert!((total - 4.0 * PI).abs() < 1e-9, "{total}");
    }

    #[test]
    fn cdfs_follow_luminance_times_solid_angle() {
        // 4 x 2 map: one bright texel in the top row, the rest dim, one black texel.
        let mut texels = vec![[1.0f32; 3]; 8];
        texels[1] = [7.0; 3];
        texels[6] = [0.0; 3];
        let env = EnvironmentData::from_texels(4, 2, texels);
        assert_eq!(env.cdf.len(), 3 + 2 * 5);
        // Both rows span the same solid angle: the top row weighs 10, the bottom row 3.
        assert!((env.cdf[1] - 10.0 / 13.0).abs() < 1e-6, "{:?}", &env.cdf[..3]);
        assert_eq!(env.cdf[2], 1.0);
        let top = &env.cdf[3..8];
        assert!((top[2] - top[1] - 0.7).abs() < 1e-6, "{top:?}");
        let bottom = &env.cdf[8..13];
        assert_eq!(bottom[3], bottom[2], "the black texel has zero width");
        // The mean over the sphere: the average texel value, rows weighing equally here.
        assert!((env.mean.x - 13.0 / 8.0).abs() < 1e-5, "{}", env.mean);
    }

    #[test]
    fn a_black_map_gets_uniform_cdfs() {
        let env = EnvironmentData::from_texels(2, 2, vec![[0.0; 3]; 4]);
        assert_eq!(&env.cdf[..3], &[0.0, 0.5, 1.0]);
        assert_eq!(env.mean, Vec3::ZERO);
    }

    #[test]
    fn bad_maps_are_errors_naming_the_file() {
        let missing = Environment::Map(PathBuf::from("/nonexistent/sky.exr"), 1.0);
        let e = format!("{:#}", EnvironmentData::load(&missing).unwrap_err());
        assert!(e.contains("/nonexistent/sky.exr") && e.contains("no such file"), "{e}");

        let dir = std::env::temp_dir().join(format!("hybrid-rt-env-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let garbage = dir.join("garbage.hdr");
        std::fs::write(&garbage, b"not an image").unwrap();
        let e = format!("{:#}", EnvironmentData::load(&Environment::Map(garbage.clone(), 1.0)).unwrap_err());
        assert!(e.contains("garbage.hdr") && e.contains("cannot decode"), "{e}");
        let png = dir.join("sky.png");
        std::fs::write(&png, b"").unwrap();
        let e = format!("{:#}", EnvironmentData::load(&Environment::Map(png, 1.0)).unwrap_err());
        assert!(e.contains("sky.png") && e.contains("unsupported"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
