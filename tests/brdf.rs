//! brdf_sample and brdf_pdf (shaders-glsl/common/brdf.glsl) agree, on the GPU, through the
//! harness shader shaders-glsl/brdf_test.comp. For several (base colour, roughness, metallic,
//! view angle) settings of both material models (glTF Appendix B, the default, and the
//! energy-coupled one):
//!
//! - chi-square goodness of fit: N samples are binned over the upper hemisphere in cells of
//!   equal solid angle (16 bands of cos(theta) x 32 of phi), plus one category for samples that
//!   fell below the horizon. Expected counts are N x the integral of brdf_pdf over each cell
//!   (midpoint rule on a 32 x 32 grid per cell, evaluated by the same shader), and N x (1 -
//!   the integral over the hemisphere) for the lost ones. Cells expecting fewer than 5 are
//!   pooled. The statistic must stay below the chi-square quantile at p = 0.001 for its degrees
//!   of freedom (Wilson-Hilferty). The seed is fixed, so the verdict is reproducible.
//! - the pdf integrates to 1 minus what falls below the horizon: |integral + lost - 1| within
//!   4 binomial standard errors of the lost fraction plus 0.002 for the quadrature;
//! - the sample weights are unbiased: mean(f cos / pdf) equals the quadrature of f cos over the
//!   hemisphere (the directional albedo) within 4 standard errors plus 0.2 %, and stays <= 1
//!   (energy conservation) for white materials where the model conserves energy (every
//!   material of the coupled model, metals of the glTF one: its fresnel_mix dielectric
//!   reflects more than 1 at grazing views, src/world/brdf.rs);
//! - brdf_eval_cos equals the CPU mirror (src/world/brdf.rs) at the quadrature directions.

mod common;

use glam::DVec3;
use hybrid_rt::gpu::{
    Binding, BindingKind, Buffer, CommandPool, Context, DescriptorSet, DescriptorSetLayout, MemoryLocation, Pipeline,
    PushResource, Recorder, ShaderLibrary, vk,
};
use hybrid_rt::world::brdf::{self, Brdf, BrdfModel};
use std::f64::consts::PI;
use std::sync::Arc;

const SAMPLES: u32 = 1 << 19;
const COS_BANDS: usize = 16;
const PHI_BANDS: usize = 32;
const SUB: usize = 32;
const GROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    base_color: [f32; 3],
    metallic: f32,
    roughness: f32,
    cos_view: f32,
    mode: u32,
    count: u32,
    seed: u32,
}

struct Harness {
    ctx: Arc<Context>,
    model: BrdfModel,
    pool: CommandPool,
    pipeline: Pipeline,
    _layouts: [DescriptorSetLayout; 2],
    /// Set 0 holds only the BRDF's data (binding 17: model and table), as in the scene set.
    brdf_set: DescriptorSet,
    _brdf_data: Buffer,
}

impl Harness {
    fn new(ctx: &Arc<Context>, model: BrdfModel) -> Self {
        let b = |binding| Binding { binding, kind: BindingKind::StorageBuffer, count: 1 };
        // The harness reads no scene: set 0 holds only the BRDF's data, set 1 its two buffers.
        let scene = DescriptorSetLayout::new(ctx, &[b(17)], false).unwrap();
        let set = DescriptorSetLayout::new(ctx, &[b(0), b(1)], true).unwrap();
        let spirv = ShaderLibrary::embedded().get("brdf_test.comp").unwrap();
        let pipeline =
            Pipeline::compute(ctx, "brdf_test", &spirv, &[&scene, &set], size_of::<Params>() as u32).unwrap();
        let data =
            Buffer::with_data(ctx, "brdf_data", &brdf::gpu_data(model), vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
        let brdf_set = DescriptorSet::new(ctx, &scene).unwrap();
        brdf_set.write_buffer(17, BindingKind::StorageBuffer, &data);
        Self {
            ctx: ctx.clone(),
            model,
            pool: CommandPool::new(ctx).unwrap(),
            pipeline,
            _layouts: [scene, set],
            brdf_set,
            _brdf_data: data,
        }
    }

    /// Runs `params.count` items; returns two vec4 records per item.
    fn run(&self, params: Params, directions: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let dirs: &[[f32; 4]] = if directions.is_empty() { &[[0.0; 4]] } else { directions };
        let input = Buffer::with_data(&self.ctx, "brdf_test.directions", bytemuck::cast_slice(dirs), storage).unwrap();
        let size = params.count as u64 * 32;
        let output = Buffer::new(&self.ctx, "brdf_test.results", size, storage, MemoryLocation::GpuToCpu).unwrap();
        self.pool
            .run(|cmd| {
                let rec = Recorder::new(&self.ctx, cmd);
                rec.bind_pipeline(&self.pipeline);
                rec.bind_scene_set(&self.pipeline, self.brdf_set.raw);
                rec.push_set(
                    &self.pipeline,
                    &[PushResource::StorageBuffer(input.raw), PushResource::StorageBuffer(output.raw)],
                );
                rec.push_constants(&self.pipeline, bytemuck::bytes_of(&params));
                rec.dispatch(params.count.div_ceil(GROUP), 1, 1);
                rec.memory_barrier(
                    (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
                    (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
                );
                Ok(())
            })
            .unwrap();
        bytemuck::pod_collect_to_vec(&output.mapped().unwrap()[..size as usize])
    }
}

#[derive(Clone, Copy, Debug)]
struct Setting {
    base_color: [f32; 3],
    roughness: f32,
    metallic: f32,
    cos_view: f32,
}

fn cell_of(l: [f32; 4]) -> usize {
    let z = l[2] as f64;
    let phi = (l[1] as f64).atan2(l[0] as f64).rem_euclid(2.0 * PI);
    let c = ((z * COS_BANDS as f64) as usize).min(COS_BANDS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BANDS as f64) as usize).min(PHI_BANDS - 1);
    c * PHI_BANDS + p
}

/// Midpoints of the quadrature grid, cell by cell (SUB x SUB per cell), and the solid angle
/// each stands for.
fn quadrature_directions() -> (Vec<[f32; 4]>, f64) {
    let mut dirs = Vec::with_capacity(COS_BANDS * PHI_BANDS * SUB * SUB);
    for c in 0..COS_BANDS {
        for p in 0..PHI_BANDS {
            for a in 0..SUB {
                for b in 0..SUB {
                    let z = (c as f64 + (a as f64 + 0.5) / SUB as f64) / COS_BANDS as f64;
                    let phi = 2.0 * PI * (p as f64 + (b as f64 + 0.5) / SUB as f64) / PHI_BANDS as f64;
                    let r = (1.0 - z * z).sqrt();
                    dirs.push([(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32, 0.0]);
                }
            }
        }
    }
    let d_omega = 2.0 * PI / (COS_BANDS * PHI_BANDS * SUB * SUB) as f64;
    (dirs, d_omega)
}

/// The chi-square quantile at upper tail probability 0.001 (Wilson-Hilferty).
fn chi2_limit(dof: f64) -> f64 {
    let z = 3.090;
    let k = 2.0 / (9.0 * dof);
    dof * (1.0 - k + z * k.sqrt()).powi(3)
}

fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn check(h: &Harness, s: Setting, seed: u32) {
    let params = |mode, count| Params {
        base_color: s.base_color,
        metallic: s.metallic,
        roughness: s.roughness,
        cos_view: s.cos_view,
        mode,
        count,
        seed,
    };
    let samples = h.run(params(0, SAMPLES), &[]);
    let (dirs, d_omega) = quadrature_directions();
    let evals = h.run(params(1, dirs.len() as u32), &dirs);

    // Expected probability per cell and the hemisphere integrals of pdf and f cos.
    let mut cell_p = vec![0.0f64; COS_BANDS * PHI_BANDS];
    let mut albedo_q = [0.0f64; 3];
    let cpu = Brdf {
        base: DVec3::from_array(s.base_color.map(f64::from)),
        metallic: s.metallic as f64,
        roughness: s.roughness as f64,
    };
    let v = DVec3::new((1.0 - (s.cos_view as f64).powi(2)).sqrt(), 0.0, s.cos_view as f64);
    for (i, rec) in evals.chunks_exact(2).enumerate() {
        let (eval, pdf) = (rec[0], rec[0][3] as f64);
        // The shader evaluates the same model as its CPU mirror (f32 against f64).
        let l = DVec3::new(dirs[i][0] as f64, dirs[i][1] as f64, dirs[i][2] as f64);
        let want = cpu.eval_cos(h.model, DVec3::Z, v, l);
        let got = DVec3::new(eval[0] as f64, eval[1] as f64, eval[2] as f64);
        assert!(
            (got - want).length() <= 1e-3 * want.length() + 1e-5,
            "{s:?} {:?}: brdf_eval_cos {got} at l = {l}, the CPU mirror gives {want}",
            h.model
        );
        cell_p[i / (SUB * SUB)] += pdf * d_omega;
        for c in 0..3 {
            albedo_q[c] += eval[c] as f64 * d_omega;
        }
    }
    let integral: f64 = cell_p.iter().sum();

    let n = SAMPLES as f64;
    let mut observed = vec![0u64; COS_BANDS * PHI_BANDS];
    let mut lost = 0u64;
    let mut weight_sum = [0.0f64; 3];
    let mut weight_sq = [0.0f64; 3];
    for rec in samples.chunks_exact(2) {
        let (l, w) = (rec[0], rec[1]);
        if l[3] <= 0.0 {
            lost += 1;
            continue;
        }
        observed[cell_of(l)] += 1;
        for c in 0..3 {
            weight_sum[c] += w[c] as f64;
            weight_sq[c] += (w[c] as f64).powi(2);
        }
    }

    // Chi-square over cells (small ones pooled) and the lost category.
    let (mut stat, mut dof, mut pool_e, mut pool_o) = (0.0f64, 0usize, 0.0f64, 0.0f64);
    for (p, &o) in cell_p.iter().zip(&observed) {
        let e = p * n;
        if e < 5.0 {
            pool_e += e;
            pool_o += o as f64;
        } else {
            stat += (o as f64 - e).powi(2) / e;
            dof += 1;
        }
    }
    let lost_p = (1.0 - integral).max(0.0);
    for (e, o) in [(pool_e, pool_o), (lost_p * n, lost as f64)] {
        if e >= 5.0 {
            stat += (o - e).powi(2) / e;
            dof += 1;
        } else {
            assert!(o <= 5.0 + 4.0 * e.max(1.0).sqrt(), "{s:?}: {o} samples where {e:.2} were expected");
        }
    }
    let limit = chi2_limit((dof - 1) as f64);
    eprintln!(
        "{s:?} {:?}: chi2 {stat:.1} over {} dof (limit {limit:.1}); pdf integral {integral:.4}, lost {:.4}",
        h.model,
        dof - 1,
        lost as f64 / n
    );
    assert!(stat < limit, "{s:?}: samples do not follow brdf_pdf: chi2 {stat:.1} > {limit:.1} ({} dof)", dof - 1);

    let lost_f = lost as f64 / n;
    let tol = 4.0 * (lost_f * (1.0 - lost_f) / n).sqrt() + 0.002;
    assert!(
        (integral + lost_f - 1.0).abs() <= tol,
        "{s:?}: pdf integrates to {integral:.4} over the hemisphere, {lost_f:.4} of samples lost (tolerance {tol:.4})"
    );
    assert!(integral <= 1.002, "{s:?}: pdf integrates to {integral:.4} > 1");

    for c in 0..3 {
        let mean = weight_sum[c] / n;
        let se = ((weight_sq[c] / n - mean * mean).max(0.0) / n).sqrt();
        let tol = 4.0 * se + 0.002 * albedo_q[c];
        assert!(
            (mean - albedo_q[c]).abs() <= tol,
            "{s:?}: channel {c}: mean weight {mean:.4} but the albedo integral is {:.4} (tolerance {tol:.4})",
            albedo_q[c]
        );
        let conserves = h.model == BrdfModel::Coupled || s.metallic == 1.0;
        if s.base_color[c] >= 1.0 && conserves {
            assert!(mean <= 1.0 + 4.0 * se, "{s:?}: channel {c}: white material reflects {mean:.4} > 1");
        }
    }
    eprintln!(
        "{s:?} {:?}: albedo {:.4} (sampled) vs {:.4} (quadrature), luminance",
        h.model,
        luminance(weight_sum.map(|w| w / n)),
        luminance(albedo_q)
    );
}

#[test]
fn brdf_samples_follow_brdf_pdf() {
    let ctx = common::validated_context();
    {
        let settings = [
            Setting { base_color: [1.0; 3], roughness: 1.0, metallic: 0.0, cos_view: 0.8 },
            Setting { base_color: [0.8, 0.5, 0.2], roughness: 0.5, metallic: 0.0, cos_view: 0.3 },
            Setting { base_color: [1.0, 0.8, 0.4], roughness: 0.3, metallic: 1.0, cos_view: 0.9 },
            Setting { base_color: [1.0; 3], roughness: 0.6, metallic: 0.5, cos_view: 0.1 },
            Setting { base_color: [0.2; 3], roughness: 0.3, metallic: 0.0, cos_view: 0.5 },
            Setting { base_color: [1.0; 3], roughness: 1.0, metallic: 1.0, cos_view: 0.8 },
            Setting { base_color: [1.0; 3], roughness: 1.0, metallic: 1.0, cos_view: 0.4 },
        ];
        let h = Harness::new(&ctx, BrdfModel::Gltf);
        for (i, s) in settings.iter().enumerate() {
            check(&h, *s, 17 + i as u32);
        }
        // The coupled model samples with the same mixture: its white materials, a grazing view
        // and a coloured dielectric.
        let h = Harness::new(&ctx, BrdfModel::Coupled);
        for (i, s) in [settings[0], settings[1], settings[3]].into_iter().enumerate() {
            check(&h, s, 41 + i as u32);
        }
    }
    common::assert_validation_clean(ctx);
}

/// The test can fail: samples drawn for one roughness do not pass against another's pdf.
#[test]
fn chi_square_rejects_a_mismatched_pdf() {
    let ctx = common::validated_context();
    {
        let h = Harness::new(&ctx, BrdfModel::Gltf);
        let params = |mode, count, roughness| Params {
            base_color: [1.0; 3],
            metallic: 1.0,
            roughness,
            cos_view: 0.7,
            mode,
            count,
            seed: 3,
        };
        let samples = h.run(params(0, SAMPLES, 0.5), &[]);
        let (dirs, d_omega) = quadrature_directions();
        let evals = h.run(params(1, dirs.len() as u32, 0.45), &dirs);
        let mut cell_p = vec![0.0f64; COS_BANDS * PHI_BANDS];
        for (i, rec) in evals.chunks_exact(2).enumerate() {
            cell_p[i / (SUB * SUB)] += rec[0][3] as f64 * d_omega;
        }
        let mut observed = vec![0u64; COS_BANDS * PHI_BANDS];
        for rec in samples.chunks_exact(2).filter(|r| r[0][3] > 0.0) {
            observed[cell_of(rec[0])] += 1;
        }
        let n = SAMPLES as f64;
        let (stat, dof) = cell_p
            .iter()
            .zip(&observed)
            .filter(|(p, _)| **p * n >= 5.0)
            .fold((0.0, 0), |(s, d), (p, &o)| (s + (o as f64 - p * n).powi(2) / (p * n), d + 1));
        let limit = chi2_limit((dof - 1) as f64);
        eprintln!("mismatched roughness 0.5 vs 0.45: chi2 {stat:.1}, limit {limit:.1}");
        assert!(stat > limit, "roughness 0.45's pdf should not fit roughness 0.5's samples");
    }
    common::assert_validation_clean(ctx);
}
