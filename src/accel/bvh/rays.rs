//! The benchmark ray sets, defined exactly so that every backend traces the same rays.
//!
//! Let the scene's triangles in world space have the bounding box `[min, max]`, centre
//! `C = (min + max) / 2` and diagonal length `diag = |max - min|` ([`triangle_bounds`]).
//!
//! - **Primary** ([`BenchView::primary`]): camera at `eye = C + 1.5 * diag * normalize(1, 0.7,
//!   1.2)` looking at `C`, world up (0, 1, 0), 60 degree vertical field of view, `W x H`
//!   (default 1024 x 1024) rays through pixel centres, row 0 at the top, row-major;
//!   directions normalised, `tmin = 0`, `tmax = f32::MAX`; traced for the closest hit.
//! - **Shadow** ([`BenchView::shadow`]): one per primary ray that hit, in primary order, from
//!   the hit point `P = origin + t * dir` toward a point light at `eye + (0, 0.5 * diag, 0)`:
//!   direction normalised, `tmin = 1e-4 * diag`, `tmax = |light - P| - 1e-4 * diag`; traced
//!   for any hit.
//! - **Incoherent** ([`BenchView::incoherent`]): `N` (default 1,048,576) rays from splitmix64
//!   seeded with 2. Per ray five draws `ox, oy, oz, u, v`, each `(next >> 40) * 2^-24` (exact
//!   in f32); `origin = min + (ox, oy, oz) * (max - min)` in f32; `z = 1 - 2u`, `r = sqrt(1 -
//!   z*z)`, `phi = 2 pi v`, `dir = (r cos phi, r sin phi, z)` evaluated in f64 and rounded to
//!   f32; `tmin = 0`, `tmax = f32::MAX` (finite, so GPU code needs no infinity); traced for
//!   the closest hit.
//!
//! splitmix64: `state += 0x9E3779B97F4A7C15; z = state; z = (z ^ (z >> 30)) *
//! 0xBF58476D1CE4E5B9; z = (z ^ (z >> 27)) * 0x94D049BB133111EB; return z ^ (z >> 31)`, all
//! wrapping.

use super::SceneBvh;
use super::layout::{rows, transform_point};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

pub const DEFAULT_WIDTH: u32 = 1024;
pub const DEFAULT_HEIGHT: u32 = 1024;
pub const DEFAULT_INCOHERENT: usize = 1 << 20;

/// One ray as uploaded to the GPU, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

/// The splitmix64 generator (Steele, Lea, Flood 2014).
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 bits: `(next >> 40) * 2^-24`.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

/// World-space bounds of every triangle of every instance in the top level, from the exact
/// transformed vertices (not the instance boxes). An empty scene gives a zero box.
pub fn triangle_bounds(bvh: &SceneBvh) -> (Vec3, Vec3) {
    let mut lo = Vec3::INFINITY;
    let mut hi = Vec3::NEG_INFINITY;
    for inst in &bvh.tlas.instances {
        let object_to_world = rows(&inst.object_to_world);
        for (_, vertices) in bvh.blas.triangles(inst.mesh) {
            for v in vertices {
                let w = transform_point(&object_to_world, v);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
    }
    if lo.x > hi.x { (Vec3::ZERO, Vec3::ZERO) } else { (lo, hi) }
}

/// The benchmark camera, light and bounds.
#[derive(Clone, Copy, Debug)]
pub struct BenchView {
    pub min: Vec3,
    pub max: Vec3,
    pub diag: f32,
    pub eye: Vec3,
    pub light: Vec3,
}

impl BenchView {
    pub fn new(min: Vec3, max: Vec3) -> Self {
        let centre = (min + max) * 0.5;
        let diag = (max - min).length();
        let eye = centre + 1.5 * diag * Vec3::new(1.0, 0.7, 1.2).normalize();
        Self { min, max, diag, eye, light: eye + Vec3::new(0.0, 0.5 * diag, 0.0) }
    }

    /// `width * height` primary rays, row 0 at the top.
    pub fn primary(&self, width: u32, height: u32) -> Vec<Ray> {
        let forward = ((self.min + self.max) * 0.5 - self.eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let tan_half = 30f32.to_radians().tan();
        let aspect = width as f32 / height as f32;
        let mut rays = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                let sx = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * tan_half * aspect;
                let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * tan_half;
                let dir = (forward + sx * right + sy * up).normalize();
                rays.push(Ray { origin: self.eye.into(), tmin: 0.0, dir: dir.into(), tmax: f32::MAX });
            }
        }
        rays
    }

    /// Shadow rays for the primary rays' hit distances (`None` = missed, no shadow ray).
    pub fn shadow(&self, primary: &[Ray], hit_t: &[Option<f32>]) -> Vec<Ray> {
        let offset = 1e-4 * self.diag;
        primary
            .iter()
            .zip(hit_t)
            .filter_map(|(ray, t)| {
                let p = Vec3::from(ray.origin) + (*t)? * Vec3::from(ray.dir);
                let to_light = self.light - p;
                let distance = to_light.length();
                let dir = to_light / distance;
                Some(Ray { origin: p.into(), tmin: offset, dir: dir.into(), tmax: distance - offset })
            })
            .collect()
    }

    /// `n` incoherent rays.
    pub fn incoherent(&self, n: usize) -> Vec<Ray> {
        let mut rng = SplitMix64::new(2);
        let extent = self.max - self.min;
        (0..n)
            .map(|_| {
                let o = Vec3::new(rng.unit(), rng.unit(), rng.unit());
                let (u, v) = (f64::from(rng.unit()), f64::from(rng.unit()));
                let z = 1.0 - 2.0 * u;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * std::f64::consts::PI * v;
                let dir = DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3();
                Ray { origin: (self.min + o * extent).into(), tmin: 0.0, dir: dir.into(), tmax: f32::MAX }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_reference_values() {
        // First outputs for seed 0 from the reference implementation.
        let mut rng = SplitMix64::new(0);
        assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(rng.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        assert!(SplitMix64::new(2).unit() < 1.0);
    }

    #[test]
    fn primary_rays_frame_the_box() {
        let view = BenchView::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let rays = view.primary(2, 2);
        assert_eq!(rays.len(), 4);
        // The four rays are symmetric about the view direction; top row points up.
        let mean: Vec3 = rays.iter().map(|r| Vec3::from(r.dir)).sum::<Vec3>() / 4.0;
        assert!(mean.normalize().dot(-view.eye.normalize()) > 0.9999);
        assert!(rays[0].dir[1] > rays[2].dir[1]);
        for r in &rays {
            assert_eq!(Vec3::from(r.origin), view.eye);
            assert!((Vec3::from(r.dir).length() - 1.0).abs() < 1e-6);
        }
        // Centre-column ray of an odd-width image hits the centre line exactly.
        let centre = view.primary(3, 3)[4];
        assert!(Vec3::from(centre.dir).dot(-view.eye.normalize()) > 0.999_999);
    }

    #[test]
    fn shadow_rays_end_short_of_the_light() {
        let view = BenchView::new(Vec3::ZERO, Vec3::ONE);
        let primary = view.primary(4, 4);
        let hits: Vec<Option<f32>> = (0..16).map(|i| (i % 2 == 0).then_some(2.0)).collect();
        let shadow = view.shadow(&primary, &hits);
        assert_eq!(shadow.len(), 8);
        let s = shadow[0];
        let end = Vec3::from(s.origin) + s.tmax * Vec3::from(s.dir);
        assert!((end.distance(view.light) - 1e-4 * view.diag).abs() < 1e-4);
    }

    #[test]
    fn incoherent_rays_are_in_the_box_and_unit_length() {
        let view = BenchView::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 2.5));
        let rays = view.incoherent(10_000);
        let mut mean = Vec3::ZERO;
        for r in &rays {
            let o = Vec3::from(r.origin);
            assert!(o.cmpge(view.min).all() && o.cmple(view.max).all());
            assert!((Vec3::from(r.dir).length() - 1.0).abs() < 1e-6);
            mean += Vec3::from(r.dir);
        }
        assert!((mean / 10_000.0).length() < 0.03);
        // Reproducible: the first ray follows from the first five draws of seed 2.
        let mut rng = SplitMix64::new(2);
        let ox = rng.unit();
        assert_eq!(rays[0].origin[0], -1.0 + ox * 4.0);
    }
}
