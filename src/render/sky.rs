//! The daylight sky of the default light: a clear sky with a sun, generated on the CPU into an
//! equirectangular environment map, so that every pass and the reference path tracer light a
//! scene from it through the one environment sampler (environment.rs builds its CDFs,
//! shaders-glsl/common/light_sampling.glsl draws from them).
//!
//! - Sky: the analytic model of Preetham, Shirley and Smits, "A Practical Analytic Model for
//!   Daylight" (SIGGRAPH 1999): luminance Y and chromaticity x, y each follow the Perez
//!   distribution F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma),
//!   scaled to the zenith values, with A..E, Y_z, x_z, y_z given by turbidity and sun angle
//!   (the paper's appendix A.2). xyY -> XYZ -> linear sRGB (Rec. 709 primaries, D65).
//! - Sun: a disk of the sun's true angular radius (0.27 degrees, one to four texels of the
//!   1024 x 512 map) whose texels hold the sun radiance times the fraction of the texel the disk
//!   covers, so the map carries exactly the sun's irradiance. Its colour and strength: the
//!   extraterrestrial solar illuminance through Rayleigh and aerosol (Angstrom) extinction along
//!   the air mass (the same paper's appendix, evaluated at one wavelength per sRGB primary).
//! - Ground: below the horizon, a grey Lambertian ground of albedo 0.2 lit by sun and sky.
//! - Scale: the map is scaled so that the horizontal illuminance is pi, i.e. an open white
//!   horizontal diffuse surface reflects radiance 1, as under `--sky 1,1,1`: the tonemapper's
//!   exposure 1 suits it, as it suits the scenes' own emissive values.

use crate::world::environment::{EnvironmentData, direction, luminance, texel_solid_angle, uv};
use glam::{DVec3, Vec2, Vec3};
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Map size; the sun (0.53 degrees across) spans one to four texels of 0.35 degrees.
pub const WIDTH: u32 = 1024;
pub const HEIGHT: u32 = 512;
/// Atmospheric turbidity: 2 is very clear, 2.5 a clear day, 6 hazy.
pub const TURBIDITY: f64 = 2.5;
/// The sun 45 degrees above the horizon, 30 degrees to +X of +Z: behind the framing camera
/// (which sits on +Z looking down -Z, src/render/camera.rs) and over its right shoulder, so
/// what it sees is lit from the front and shadows fall back and to the left.
pub const SUN_ELEVATION_DEG: f64 = 45.0;
pub const SUN_AZIMUTH_DEG: f64 = 30.0;
/// The sun's angular radius (0.2666 degrees).
pub const SUN_ANGULAR_RADIUS: f64 = 4.653e-3;
/// Solar illuminance at normal incidence above the atmosphere, lux.
const SOLAR_ILLUMINANCE: f64 = 128_000.0;
/// Albedo of the grey ground below the horizon.
pub const GROUND_ALBEDO: f64 = 0.2;
/// Wavelengths (micrometres) at which the sun's extinction is evaluated for R, G and B: the
/// dominant wavelengths of the sRGB primaries.
const WAVELENGTHS: [f64; 3] = [0.612, 0.549, 0.465];

/// Unit direction toward the sun (world space, +Y up).
pub fn sun_direction() -> Vec3 {
    let (el, az) = (SUN_ELEVATION_DEG.to_radians(), SUN_AZIMUTH_DEG.to_radians());
    DVec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos()).as_vec3()
}

/// The default light's environment map (generated once per process, then cloned).
pub fn daylight() -> EnvironmentData {
    static MAP: OnceLock<EnvironmentData> = OnceLock::new();
    MAP.get_or_init(|| EnvironmentData::from_texels(WIDTH, HEIGHT, daylight_texels(WIDTH, HEIGHT))).clone()
}

/// Perez coefficients A..E of one quantity.
type Perez = [f64; 5];

/// The Preetham sky for one turbidity and sun zenith angle.
struct Preetham {
    coeffs: [Perez; 3],
    /// Zenith Y (cd/m^2), x, y divided by F(0, theta_sun): value(dir) = zenith * F(dir).
    scale: [f64; 3],
    sun: DVec3,
}

impl Preetham {
    fn new(t: f64, sun: DVec3) -> Self {
        let theta_s = sun.y.clamp(-1.0, 1.0).acos();
        // Appendix A.2: Perez coefficients of Y, x and y, linear in turbidity.
        let coeffs = [
            [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ],
            [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ],
            [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ],
        ];
        // Zenith luminance (kcd/m^2 in the paper) and chromaticity.
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let y_zenith = ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192) * 1000.0;
        let chromaticity = |m: [[f64; 4]; 3]| {
            let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
            let row = |r: [f64; 4]| r.iter().zip(th).map(|(a, b)| a * b).sum::<f64>();
            t * t * row(m[0]) + t * row(m[1]) + row(m[2])
        };
        let x_zenith = chromaticity([
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]);
        let y_chroma_zenith = chromaticity([
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]);
        let zenith = [y_zenith, x_zenith, y_chroma_zenith];
        // F(0, theta_s): the zenith (cos theta = 1) seen at the sun's angle from it.
        let scale = std::array::from_fn(|i| zenith[i] / perez(coeffs[i], 1.0, theta_s));
        Self { coeffs, scale, sun }
    }

    /// Sky radiance toward `dir` (upper hemisphere), linear sRGB in cd/m^2.
    fn radiance(&self, dir: DVec3) -> DVec3 {
        let cos_theta = dir.y.max(1e-4);
        let gamma = dir.dot(self.sun).clamp(-1.0, 1.0).acos();
        let [lum, x, y] = std::array::from_fn(|i| self.scale[i] * perez(self.coeffs[i], cos_theta, gamma));
        xyy_to_srgb(x, y, lum)
    }
}

/// The Perez distribution at zenith angle theta (given as its cosine) and sun angle gamma.
fn perez([a, b, c, d, e]: Perez, cos_theta: f64, gamma: f64) -> f64 {
    (1.0 + a * (b / cos_theta).exp()) * (1.0 + c * (d * gamma).exp() + e * gamma.cos().powi(2))
}

/// CIE xyY to linear sRGB (D65), negative components (out of gamut) dropped.
fn xyy_to_srgb(x: f64, y: f64, lum: f64) -> DVec3 {
    if y <= 0.0 || lum <= 0.0 {
        return DVec3::ZERO;
    }
    let (cx, cz) = (x * lum / y, (1.0 - x - y) * lum / y);
    DVec3::new(
        3.2406 * cx - 1.5372 * lum - 0.4986 * cz,
        -0.9689 * cx + 1.8758 * lum + 0.0415 * cz,
        0.0557 * cx - 0.2040 * lum + 1.0570 * cz,
    )
    .max(DVec3::ZERO)
}

/// Fraction of the sunlight that crosses the atmosphere at zenith angle theta_s, per sRGB
/// primary: Rayleigh exp(-0.008735 l^-4.08 m) and aerosol exp(-beta l^-1.3 m) with
/// beta = 0.04608 T - 0.04586 and the relative optical mass m of Kasten (appendix A.2).
fn sun_transmittance(t: f64, theta_s: f64) -> DVec3 {
    let m = 1.0 / (theta_s.cos() + 0.15 * (93.885 - theta_s.to_degrees()).powf(-1.253));
    let beta = 0.04608 * t - 0.04586;
    let tau = |l: f64| (-m * (0.008735 * l.powf(-4.08) + beta * l.powf(-1.3))).exp();
    DVec3::new(tau(WAVELENGTHS[0]), tau(WAVELENGTHS[1]), tau(WAVELENGTHS[2]))
}

/// Fraction of texel (x, y) that the sun disk covers, by 16 x 16 samples weighted by solid
/// angle (sin theta).
fn sun_coverage(x: u32, y: u32, width: u32, height: u32, sun: Vec3) -> f64 {
    const N: u32 = 16;
    let cos_radius = SUN_ANGULAR_RADIUS.cos();
    let (mut inside, mut total) = (0.0, 0.0);
    for j in 0..N {
        for i in 0..N {
            let s = Vec2::new(
                (x as f32 + (i as f32 + 0.5) / N as f32) / width as f32,
                (y as f32 + (j as f32 + 0.5) / N as f32) / height as f32,
            );
            let d = direction(s);
            let w = (s.y as f64 * PI).sin();
            total += w;
            if (d.dot(sun) as f64) >= cos_radius {
                inside += w;
            }
        }
    }
    if total > 0.0 { inside / total } else { 0.0 }
}

/// The texels of the daylight map, row 0 at the zenith (see the module header).
fn daylight_texels(width: u32, height: u32) -> Vec<[f32; 3]> {
    let sun = sun_direction();
    let sun64 = sun.as_dvec3();
    let sky = Preetham::new(TURBIDITY, sun64);
    let (w, h) = (width as usize, height as usize);
    let centre =
        |x: usize, y: usize| direction(Vec2::new((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32));
    // Rows above the horizon are sky (the horizon is a row boundary: height is even).
    let mut texels = vec![DVec3::ZERO; w * h];
    for y in 0..h / 2 {
        for x in 0..w {
            texels[y * w + x] = sky.radiance(centre(x, y).as_dvec3());
        }
    }
    // The sun: every texel within reach of the disk, by coverage; its radiance then set so
    // that the covered solid angle carries the attenuated solar illuminance exactly.
    let at = uv(sun);
    let reach = SUN_ANGULAR_RADIUS as f32 * 2.0 + std::f32::consts::PI / height as f32 * 2.0;
    let rows = ((at.y - reach / std::f32::consts::PI) * height as f32).floor().max(0.0) as u32
        ..=((at.y + reach / std::f32::consts::PI) * height as f32).ceil().min(height as f32 / 2.0 - 1.0) as u32;
    let mut covered = Vec::new();
    for y in rows {
        let sin_theta = ((y as f32 + 0.5) / height as f32 * std::f32::consts::PI).sin().max(1e-3);
        let half = (reach / sin_theta / std::f32::consts::TAU * width as f32).ceil() as i64 + 1;
        let cx = (at.x * width as f32) as i64;
        for x in (cx - half..=cx + half).map(|x| x.rem_euclid(width as i64) as u32) {
            let c = sun_coverage(x, y, width, height, sun);
            if c > 0.0 {
                covered.push((x, y, c * texel_solid_angle(y, width, height)));
            }
        }
    }
    let sun_omega: f64 = covered.iter().map(|c| c.2).sum();
    let theta_s = sun64.y.acos();
    let sun_radiance = SOLAR_ILLUMINANCE * sun_transmittance(TURBIDITY, theta_s) / sun_omega;
    for &(x, y, omega) in &covered {
        texels[y as usize * w + x as usize] += sun_radiance * (omega / texel_solid_angle(y, width, height));
    }
    // Irradiance of a horizontal surface facing up (per channel, and its luminance).
    let mut irradiance = DVec3::ZERO;
    for y in 0..h / 2 {
        let cos_theta = centre(0, y).y as f64;
        let omega = texel_solid_angle(y as u32, width, height);
        irradiance += texels[y * w..(y + 1) * w].iter().sum::<DVec3>() * cos_theta * omega;
    }
    let ground = irradiance * (GROUND_ALBEDO / PI);
    for t in &mut texels[w * h / 2..] {
        *t = ground;
    }
    let scale = PI / luminance(irradiance.as_vec3()) as f64;
    texels.iter().map(|t| (*t * scale).as_vec3().to_array()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Horizontal irradiance (luminance) of a map: sum of L cos theta d omega over the upper rows.
    fn horizontal_irradiance(env: &EnvironmentData) -> f64 {
        let (w, h) = (env.width as usize, env.height as usize);
        (0..h / 2)
            .map(|y| {
                let cos = direction(Vec2::new(0.5, (y as f32 + 0.5) / h as f32)).y as f64;
                let sum: f64 = env.texels[y * w..(y + 1) * w].iter().map(|t| luminance(Vec3::from(*t)) as f64).sum();
                sum * cos * texel_solid_angle(y as u32, env.width, env.height)
            })
            .sum()
    }

    #[test]
    fn the_map_is_scaled_to_horizontal_irradiance_pi() {
        let env = daylight();
        assert_eq!((env.width, env.height), (WIDTH, HEIGHT));
        assert!(env.texels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
        let e = horizontal_irradiance(&env);
        assert!((e - PI).abs() < 1e-3 * PI, "{e}");
    }

    #[test]
    fn the_sun_carries_the_attenuated_solar_share_at_its_place() {
        let env = daylight();
        let (w, h) = (WIDTH as usize, HEIGHT as usize);
        let sun = sun_direction();
        // Texels within 1 degree of the sun: their irradiance at normal incidence.
        let mut sun_e = 0.0;
        let mut brightest = (0.0f32, Vec3::ZERO);
        for y in 0..h / 2 {
            for x in 0..w {
                let d = direction(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
                let l = luminance(Vec3::from(env.texels[y * w + x]));
                if l > brightest.0 {
                    brightest = (l, d);
                }
                if d.dot(sun) > 1f32.to_radians().cos() {
                    sun_e += l as f64 * texel_solid_angle(y as u32, WIDTH, HEIGHT);
                }
            }
        }
        assert!(brightest.1.dot(sun) > 0.5f32.to_radians().cos(), "brightest texel at {}", brightest.1);
        // Direct sun on a clear day at 45 degrees: about three quarters of the horizontal
        // illuminance (pi), the sky the rest.
        let direct_horizontal = sun_e * sun.y as f64;
        let share = direct_horizontal / PI;
        assert!((0.6..0.9).contains(&share), "sun share of the horizontal illuminance {share}");
        // The sampler draws texels by luminance x solid angle: the sun's few texels get a large
        // share of the samples (it is well importance-sampled), not one in a million.
        let total: f64 = (0..h)
            .map(|y| {
                let row: f64 = env.texels[y * w..(y + 1) * w].iter().map(|t| luminance(Vec3::from(*t)) as f64).sum();
                row * texel_solid_angle(y as u32, WIDTH, HEIGHT)
            })
            .sum();
        let sampled = sun_e / total;
        assert!((0.3..0.9).contains(&sampled), "share of environment samples drawn from the sun {sampled}");
        eprintln!("sun: {share:.3} of the horizontal illuminance, {sampled:.3} of the environment samples");
    }

    #[test]
    fn the_sky_is_blue_brighter_at_the_horizon_than_at_the_zenith_and_the_ground_grey() {
        let sky = Preetham::new(TURBIDITY, sun_direction().as_dvec3());
        // Opposite the sun, at the zenith and 5 degrees above the horizon.
        let away = -sun_direction().as_dvec3().with_y(0.0).normalize();
        let zenith = sky.radiance(DVec3::Y);
        let low = sky.radiance((away + DVec3::Y * 5f64.to_radians().tan()).normalize());
        assert!(zenith.z > zenith.x, "the zenith is blue: {zenith}");
        assert!(luminance(low.as_vec3()) > luminance(zenith.as_vec3()), "horizon {low} zenith {zenith}");
        // Zenith luminance of a clear sky, sun at 45 degrees: a few kcd/m^2 (the paper's Y_z).
        let y = luminance(zenith.as_vec3());
        assert!((2000.0..10000.0).contains(&y), "{y}");
        let env = daylight();
        let g = env.texels[env.texels.len() - 1];
        assert!((luminance(Vec3::from(g)) - GROUND_ALBEDO as f32).abs() < 1e-3, "{g:?}");
    }

    #[test]
    fn sunlight_is_reddened_by_the_atmosphere() {
        let t = sun_transmittance(TURBIDITY, 45f64.to_radians());
        assert!(t.x > t.y && t.y > t.z && t.z > 0.3 && t.x < 1.0, "{t}");
        // Lower sun, longer path, less light.
        let low = sun_transmittance(TURBIDITY, 80f64.to_radians());
        assert!(low.max_element() < t.min_element() + 0.3 && low.z < t.z, "{low} vs {t}");
    }
}
