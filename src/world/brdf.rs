//! The material model on the CPU: the Lambert + GGX lobes of shaders-glsl/common/brdf.glsl, the
//! choice of how they share light (`BrdfModel`), and the specular directional-albedo table the
//! shader reads for the energy-coupled model.
//!
//! The default is glTF 2.0 Appendix B as written: `fresnel_mix` of Lambert and GGX for the
//! dielectric (the diffuse lobe weighted by 1 - F(v.h), F = 0.04 + 0.96 (1 - v.h)^5), the GGX
//! layer with Schlick Fresnel on baseColor for the metal, mixed by metallic. That is what other
//! glTF renderers compute, so images agree with theirs; it is not energy-conserving: a glossy
//! white dielectric reflects up to 1.2 of the incident light at a view cosine of 0.2.
//!
//! The energy-coupled model (`--brdf coupled`) weights the diffuse lobe instead by
//! (1 - E(v)) (1 - E(l)) / (1 - E_avg), E the specular lobe's directional albedo and E_avg its
//! cosine-weighted average: the lobe stays reciprocal, and the diffuse energy for a view v is
//! exactly albedo (1 - E(v)), so a white dielectric reflects exactly what the specular lobe
//! leaves, and nothing reflects more than it receives.
//!
//! With Schlick's Fresnel, E is linear in F0: E(mu, r; F0) = F0 A(mu, r) + B(mu, r), so one
//! table of (A, B) over view cosine and roughness serves every material.

use glam::DVec3;
use std::f64::consts::PI;

/// How the diffuse and specular lobes share light (`--brdf`; brdf.glsl `brdf_model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BrdfModel {
    /// glTF 2.0 Appendix B: fresnel_mix(Lambert, GGX) for the dielectric, Schlick-Fresnel GGX
    /// for the metal.
    #[default]
    Gltf,
    /// Lambert weighted by the specular lobe's directional albedo at both directions:
    /// reciprocal and energy-conserving.
    Coupled,
}

impl BrdfModel {
    /// The value of brdf.glsl's `brdf_model` (BRDF_MODEL_*).
    fn shader_value(self) -> u32 {
        match self {
            BrdfModel::Gltf => 0,
            BrdfModel::Coupled => 1,
        }
    }
}

/// The contents of the shader's BrdfData buffer (set 0, binding 17): the model, a reserved
/// word, then `energy_table()`.
pub fn gpu_data(model: BrdfModel) -> Vec<u8> {
    let mut data = Vec::with_capacity(8 + std::mem::size_of_val(energy_table()));
    data.extend_from_slice(&model.shader_value().to_le_bytes());
    data.extend_from_slice(&0u32.to_le_bytes());
    data.extend_from_slice(bytemuck::cast_slice(energy_table()));
    data
}

/// Entries per axis: view cosine mu = i / (N - 1) (the shader clamps to >= 1e-4), roughness
/// r = j / (N - 1).
pub const TABLE_SIZE: usize = 32;
/// Smallest GGX alpha (brdf.glsl MIN_ALPHA): a perfect mirror has no finite density.
pub const MIN_ALPHA: f64 = 1e-3;
/// Visible-normal samples per table entry (a stratified 64 x 64 grid).
const STRATA: usize = 64;

/// (A, B) for every (roughness j, mu i) at index j * N + i, followed by their cosine-weighted
/// hemispherical averages per roughness at N * N + j. Computed once per process (~4 M
/// visible-normal samples).
pub fn energy_table() -> &'static [[f32; 2]] {
    static TABLE: std::sync::OnceLock<Vec<[f32; 2]>> = std::sync::OnceLock::new();
    TABLE.get_or_init(compute_energy_table)
}

fn compute_energy_table() -> Vec<[f32; 2]> {
    let n = TABLE_SIZE;
    let mut table = vec![[0.0f32; 2]; n * n + n];
    for j in 0..n {
        let roughness = j as f64 / (n - 1) as f64;
        for i in 0..n {
            let mu = (i as f64 / (n - 1) as f64).max(1e-4);
            let (a, b) = specular_albedo_split(mu, roughness);
            table[j * n + i] = [a as f32, b as f32];
        }
        table[n * n + j] = average(&table[j * n..j * n + n]);
    }
    table
}

/// Cosine-weighted average 2 int_0^1 E(mu) mu dmu of a row, by the trapezoid rule.
fn average(row: &[[f32; 2]]) -> [f32; 2] {
    let n = row.len();
    let mut sum = [0.0f64; 2];
    for i in 0..n - 1 {
        let (m0, m1) = (i as f64 / (n - 1) as f64, (i + 1) as f64 / (n - 1) as f64);
        for c in 0..2 {
            sum[c] += 0.5 * (row[i][c] as f64 * m0 + row[i + 1][c] as f64 * m1) * (m1 - m0);
        }
    }
    [(2.0 * sum[0]) as f32, (2.0 * sum[1]) as f32]
}

fn ggx_alpha(roughness: f64) -> f64 {
    (roughness * roughness).max(MIN_ALPHA)
}

/// Smith's Lambda for GGX at cosine `c`.
fn lambda(c: f64, alpha: f64) -> f64 {
    let t2 = (1.0 - c * c).max(0.0) / (c * c);
    0.5 * (-1.0 + (1.0 + alpha * alpha * t2).sqrt())
}

/// The specular lobe's albedo for F0 = 1 split by Schlick's Fresnel: A multiplies F0, B is the
/// rest. Integrated by visible-normal sampling, for which f cos / pdf = F(v.h) G2 / G1.
fn specular_albedo_split(mu: f64, roughness: f64) -> (f64, f64) {
    let alpha = ggx_alpha(roughness);
    let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let g1 = 1.0 / (1.0 + lambda(mu, alpha));
    let (mut a, mut b) = (0.0, 0.0);
    for s in 0..STRATA * STRATA {
        let u = ((s % STRATA) as f64 + 0.5) / STRATA as f64;
        let w = ((s / STRATA) as f64 + 0.5) / STRATA as f64;
        let h = sample_vndf(v, alpha, u, w);
        let vh = v.dot(h);
        let l = 2.0 * vh * h - v;
        if l.z <= 0.0 {
            continue;
        }
        let g2 = 1.0 / (1.0 + lambda(mu, alpha) + lambda(l.z, alpha));
        let schlick = (1.0 - vh.clamp(0.0, 1.0)).powi(5);
        a += (1.0 - schlick) * g2 / g1;
        b += schlick * g2 / g1;
    }
    let count = (STRATA * STRATA) as f64;
    (a / count, b / count)
}

/// A GGX visible normal for view `v` (Heitz 2018), as brdf sampling draws them.
fn sample_vndf(v: DVec3, alpha: f64, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 { DVec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { DVec3::X };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// A metallic-roughness material, as the shader sees it.
#[derive(Clone, Copy, Debug)]
pub struct Brdf {
    pub base: DVec3,
    pub metallic: f64,
    pub roughness: f64,
}

impl Brdf {
    fn f0(&self) -> DVec3 {
        DVec3::splat(0.04).lerp(self.base, self.metallic)
    }

    /// The specular lobe's directional albedo E(mu) per channel, from the table.
    pub fn specular_albedo(&self, table: &[[f32; 2]], mu: f64) -> DVec3 {
        let [a, b] = lookup(table, mu, self.roughness);
        self.f0() * a + DVec3::splat(b)
    }

    fn specular_albedo_avg(&self, table: &[[f32; 2]]) -> DVec3 {
        let n = TABLE_SIZE;
        let x = self.roughness.clamp(0.0, 1.0) * (n - 1) as f64;
        let j = (x.floor() as usize).min(n - 2);
        let t = x - j as f64;
        let row = |k: usize| table[n * n + k];
        let a = row(j)[0] as f64 * (1.0 - t) + row(j + 1)[0] as f64 * t;
        let b = row(j)[1] as f64 * (1.0 - t) + row(j + 1)[1] as f64 * t;
        self.f0() * a + DVec3::splat(b)
    }

    /// The diffuse lobe divided by albedo / pi for the pair (v, l): the shader's
    /// `brdf_diffuse_weight`.
    pub fn diffuse_weight(&self, model: BrdfModel, n: DVec3, v: DVec3, l: DVec3) -> DVec3 {
        match model {
            BrdfModel::Gltf => DVec3::splat(1.0 - fresnel_dielectric(v.dot((v + l).normalize()))),
            BrdfModel::Coupled => {
                let table = energy_table();
                (DVec3::ONE - self.specular_albedo(table, n.dot(v).max(0.0)))
                    * (DVec3::ONE - self.specular_albedo(table, n.dot(l).max(0.0)))
                    / (DVec3::ONE - self.specular_albedo_avg(table)).max(DVec3::splat(1e-4))
            }
        }
    }

    /// f(v, l) cos(theta_l), the shader's `brdf_eval_cos`.
    pub fn eval_cos(&self, model: BrdfModel, n: DVec3, v: DVec3, l: DVec3) -> DVec3 {
        let (nl, nv) = (n.dot(l), n.dot(v));
        if nl <= 0.0 || nv <= 0.0 {
            return DVec3::ZERO;
        }
        let h = (v + l).normalize();
        let alpha = ggx_alpha(self.roughness);
        let a2 = alpha * alpha;
        let f0 = self.f0();
        let f = f0 + (DVec3::ONE - f0) * (1.0 - v.dot(h).clamp(0.0, 1.0)).powi(5);
        let nh = n.dot(h).max(0.0);
        let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
        let vis = 0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
        let diffuse = self.base * (1.0 - self.metallic) / PI * self.diffuse_weight(model, n, v, l);
        (diffuse + f * d * vis) * nl
    }
}

/// The dielectric's Fresnel (IOR 1.5, F0 = 0.04) at cosine `v_dot_h`.
fn fresnel_dielectric(v_dot_h: f64) -> f64 {
    0.04 + 0.96 * (1.0 - v_dot_h.clamp(0.0, 1.0)).powi(5)
}

/// Bilinear (A, B) at view cosine `mu` and `roughness`, as the shader interpolates.
pub fn lookup(table: &[[f32; 2]], mu: f64, roughness: f64) -> [f64; 2] {
    let n = TABLE_SIZE;
    let (x, y) = (mu.clamp(0.0, 1.0) * (n - 1) as f64, roughness.clamp(0.0, 1.0) * (n - 1) as f64);
    let (i, j) = ((x.floor() as usize).min(n - 2), (y.floor() as usize).min(n - 2));
    let (tx, ty) = (x - i as f64, y - j as f64);
    let at = |i: usize, j: usize, c: usize| table[j * n + i][c] as f64;
    let mut out = [0.0; 2];
    for (c, o) in out.iter_mut().enumerate() {
        let top = at(i, j, c) * (1.0 - tx) + at(i + 1, j, c) * tx;
        let bottom = at(i, j + 1, c) * (1.0 - tx) + at(i + 1, j + 1, c) * tx;
        *o = top * (1.0 - ty) + bottom * ty;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E(mu) = integral of f cos over the hemisphere, by midpoint quadrature in (t, phi) with
    /// z = cos(theta) = t^2, which puts nodes where grazing lobes live.
    fn albedo(b: &Brdf, model: BrdfModel, mu: f64) -> DVec3 {
        let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        // Grazing views have lobes narrow in azimuth: phi needs the finer grid.
        let (nt, nphi) = (500, 1500);
        let mut sum = DVec3::ZERO;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64;
            let z = t * t;
            let r = (1.0 - z * z).sqrt();
            for k in 0..nphi {
                let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                // dz = 2 t dt
                sum += b.eval_cos(model, DVec3::Z, v, DVec3::new(r * phi.cos(), r * phi.sin(), z)) * 2.0 * t;
            }
        }
        sum * 2.0 * PI / (nt * nphi) as f64
    }

    #[test]
    fn coupled_white_materials_never_reflect_more_than_they_receive() {
        for metallic in [0.0, 0.5, 1.0] {
            for roughness in [0.05, 0.3, 0.6, 1.0] {
                let b = Brdf { base: DVec3::ONE, metallic, roughness };
                for mu in [0.05, 0.2, 0.5, 1.0] {
                    let e = albedo(&b, BrdfModel::Coupled, mu).x;
                    // Quadrature of a sharp lobe is noisy at low roughness: 1% slack.
                    assert!(e <= 1.01, "metallic {metallic} roughness {roughness} mu {mu}: albedo {e}");
                    if metallic == 0.0 && roughness >= 0.3 {
                        // A white dielectric reflects everything its specular lobe keeps plus
                        // all the rest diffusely: exactly 1, up to table and quadrature error.
                        assert!((e - 1.0).abs() < 0.02, "roughness {roughness} mu {mu}: albedo {e}");
                    }
                }
            }
        }
    }

    /// glTF 2.0 Appendix B transcribed term by term: specular_brdf = V D (height-correlated
    /// Smith V),
    /// diffuse_brdf = baseColor / pi, metal_brdf = conductor_fresnel(baseColor, specular_brdf),
    /// dielectric_brdf = fresnel_mix(1.5, diffuse_brdf, specular_brdf), material =
    /// mix(dielectric_brdf, metal_brdf, metallic).
    fn appendix_b(b: &Brdf, n: DVec3, v: DVec3, l: DVec3) -> DVec3 {
        let h = (v + l).normalize();
        let alpha = b.roughness * b.roughness;
        let a2 = alpha * alpha;
        let (nl, nv, nh, vh) = (n.dot(l).abs(), n.dot(v).abs(), n.dot(h), v.dot(h).abs());
        let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
        // Height-correlated Smith visibility G2 / (4 |n.l| |n.v|).
        let vis = 0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
        let specular_brdf = vis * d;
        let diffuse_brdf = b.base / PI;
        let metal = specular_brdf * (b.base + (DVec3::ONE - b.base) * (1.0 - vh).powi(5));
        let fr = 0.04 + 0.96 * (1.0 - vh).powi(5);
        let dielectric = diffuse_brdf * (1.0 - fr) + DVec3::splat(specular_brdf * fr);
        (dielectric * (1.0 - b.metallic) + metal * b.metallic) * nl
    }

    #[test]
    fn gltf_model_is_appendix_b() {
        let materials = [
            Brdf { base: DVec3::new(0.8, 0.5, 0.2), metallic: 0.0, roughness: 0.4 },
            Brdf { base: DVec3::new(0.9, 0.6, 0.3), metallic: 1.0, roughness: 0.25 },
            Brdf { base: DVec3::new(0.3, 0.7, 0.9), metallic: 0.4, roughness: 0.8 },
            Brdf { base: DVec3::ONE, metallic: 0.0, roughness: 1.0 },
        ];
        let dirs = [
            DVec3::new(0.3, 0.1, 0.9),
            DVec3::new(-0.7, 0.2, 0.4),
            DVec3::new(0.9, -0.3, 0.15),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(-0.2, -0.9, 0.3),
        ];
        for b in materials {
            for v in dirs {
                for l in dirs {
                    let (v, l) = (v.normalize(), l.normalize());
                    let (got, want) = (b.eval_cos(BrdfModel::Gltf, DVec3::Z, v, l), appendix_b(&b, DVec3::Z, v, l));
                    assert!(
                        (got - want).length() <= 1e-9 * (1.0 + want.length()),
                        "{b:?} v {v} l {l}: {got} != {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_diffuse_lobe_is_reciprocal() {
        let b = Brdf { base: DVec3::new(0.8, 0.5, 0.2), metallic: 0.2, roughness: 0.4 };
        let (v, l) = (DVec3::new(0.3, 0.1, 0.9).normalize(), DVec3::new(-0.7, 0.2, 0.4).normalize());
        for model in [BrdfModel::Gltf, BrdfModel::Coupled] {
            let (fvl, flv) = (b.eval_cos(model, DVec3::Z, v, l) / l.z, b.eval_cos(model, DVec3::Z, l, v) / v.z);
            assert!((fvl - flv).length() < 1e-9, "{model:?}: f(v,l) {fvl} != f(l,v) {flv}");
        }
    }

    #[test]
    fn gltf_white_dielectric_is_not_energy_conserving_at_grazing_views() {
        // What the specification's fresnel_mix does (and why `coupled` exists): a glossy white
        // dielectric seen at grazing angles reflects more than it receives, a rough one a
        // little less than all.
        let glossy = Brdf { base: DVec3::ONE, metallic: 0.0, roughness: 0.3 };
        let rough = Brdf { base: DVec3::ONE, metallic: 0.0, roughness: 1.0 };
        let (g, r) = (albedo(&glossy, BrdfModel::Gltf, 0.2).x, albedo(&rough, BrdfModel::Gltf, 1.0).x);
        assert!(g > 1.1, "glossy white dielectric at mu 0.2: albedo {g}");
        assert!(r < 0.99 && r > 0.95, "rough white dielectric at mu 1: albedo {r}");
    }

    #[test]
    fn table_matches_known_limits() {
        let table = energy_table();
        // A mirror (roughness 0) at normal incidence returns F0 exactly: A = 1, B = 0.
        let [a, b] = lookup(table, 1.0, 0.0);
        assert!((a - 1.0).abs() < 1e-3 && b.abs() < 1e-3, "mirror at normal incidence: A {a}, B {b}");
        // Rough lobes lose energy to single scattering: A + B (F0 = 1) below 1.
        let [a, b] = lookup(table, 0.5, 1.0);
        assert!(a + b < 0.9 && a + b > 0.3, "roughness 1: A + B = {}", a + b);
    }
}
