//! The settings the viewer can change while it runs, in one table: the overlay draws a widget
//! per entry and scripts set them by name (`taa=off`, `s_max=8`), so both stay in step with
//! `render::Settings` and with each other.

use crate::passes::gi::GiRate;
use crate::render::Settings;

#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Bool,
    Int {
        min: u32,
        max: u32,
    },
    /// `log`: a logarithmic slider (values spanning decades).
    Float {
        min: f32,
        max: f32,
        log: bool,
    },
}

pub struct Tunable {
    /// The script key.
    pub name: &'static str,
    /// The overlay's heading it sits under.
    pub group: &'static str,
    pub help: &'static str,
    pub kind: Kind,
    /// Changing it rebuilds the frame's passes (their parameters are fixed at creation);
    /// otherwise it takes effect on the next frame as it is.
    pub rebuild: bool,
    pub get: fn(&Settings) -> f64,
    pub set: fn(&mut Settings, f64),
}

// A bool field or a number field with its type; the bool arm comes first so that `bool` is
// never tried as the number arm's kind expression.
macro_rules! tunable {
    ($name:literal, $group:literal, $help:literal, bool, |$s:ident| $field:expr) => {
        Tunable {
            name: $name,
            group: $group,
            help: $help,
            kind: Kind::Bool,
            rebuild: true,
            get: |$s: &Settings| if $field { 1.0 } else { 0.0 },
            set: |$s: &mut Settings, v: f64| $field = v != 0.0,
        }
    };
    ($name:literal, $group:literal, $help:literal, $kind:expr, $rebuild:expr, |$s:ident| $field:expr, $ty:ty) => {
        Tunable {
            name: $name,
            group: $group,
            help: $help,
            kind: $kind,
            rebuild: $rebuild,
            get: |$s: &Settings| $field as f64,
            set: |$s: &mut Settings, v: f64| $field = v as $ty,
        }
    };
}

const fn int(min: u32, max: u32) -> Kind {
    Kind::Int { min, max }
}

const fn float(min: f32, max: f32, log: bool) -> Kind {
    Kind::Float { min, max, log }
}

pub static ALL: &[Tunable] = &[
    tunable!("taa", "Frame", "temporal anti-aliasing", bool, |s| s.taa),
    tunable!("denoiser", "Frame", "SVGF on the diffuse and specular signals", bool, |s| s.denoiser),
    tunable!("exposure", "Frame", "multiplier before tonemapping", float(0.05, 20.0, true), false, |s| s.exposure, f32),
    tunable!("seed", "Frame", "mixed into every random stream", int(0, 1000), true, |s| s.seed, u32),
    tunable!("s_max", "Shadows", "most rays per pixel and area light", int(1, 16), true, |s| s.shadows.s_max, u32),
    tunable!(
        "shadow_delta",
        "Shadows",
        "penumbra threshold on dv_bar",
        float(0.001, 0.5, true),
        true,
        |s| s.shadows.delta,
        f32
    ),
    tunable!(
        "shadow_eta",
        "Shadows",
        "dv_bar of the widest filter",
        float(0.01, 1.0, false),
        true,
        |s| s.shadows.eta,
        f32
    ),
    tunable!(
        "shadow_budget",
        "Shadows",
        "dv_bar sum, as a fraction of the pixels, that lowers s_max",
        float(0.01, 1.0, false),
        true,
        |s| s.shadows.budget_fraction,
        f32
    ),
    tunable!("forced_blocks", "Shadows", "refresh rotating 8x8 blocks", bool, |s| s.shadows.forced_blocks),
    tunable!(
        "reflection_rays",
        "Reflections",
        "specular samples per pixel",
        int(1, 8),
        true,
        |s| s.reflections.rays,
        u32
    ),
    tunable!(
        "roughness_cutoff",
        "Reflections",
        "rougher surfaces take the environment instead of a ray",
        float(0.0, 1.0, false),
        true,
        |s| s.reflections.roughness_cutoff,
        f32
    ),
    tunable!(
        "gi_bounces",
        "GI",
        "path vertices traced before the radiance cache",
        int(1, 4),
        true,
        |s| s.gi.bounces,
        u32
    ),
    Tunable {
        name: "gi_rate",
        group: "GI",
        help: "gi traces 1 of this many pixels a frame (1, 2 or 4), fills the rest",
        kind: int(1, 4),
        rebuild: true,
        get: |s: &Settings| s.gi.rate.pixels() as f64,
        // 3 is between the rates: the coarser one.
        set: |s: &mut Settings, v: f64| {
            s.gi.rate = GiRate::from_pixels((v as u32).next_power_of_two()).unwrap_or(s.gi.rate)
        },
    },
    tunable!("radiance_cache", "GI", "world-space cache of indirect light where rays end", bool, |s| s
        .radiance_cache
        .enabled),
    tunable!(
        "cache_budget",
        "GI",
        "radiance-cache cells updated per frame",
        int(256, 65536),
        true,
        |s| s.radiance_cache.budget,
        u32
    ),
    tunable!(
        "cache_cells",
        "GI",
        "radiance-cache cells along the scene's diagonal",
        float(8.0, 256.0, true),
        true,
        |s| s.radiance_cache.cells_per_diagonal,
        f32
    ),
    tunable!("atrous", "Denoiser", "a-trous iterations", int(1, 6), true, |s| s.denoise.iterations, u32),
    tunable!("sigma_z", "Denoiser", "depth edge-stopping", float(0.01, 10.0, true), true, |s| s.denoise.sigma_z, f32),
    tunable!(
        "sigma_n",
        "Denoiser",
        "normal edge-stopping exponent",
        float(1.0, 512.0, true),
        true,
        |s| s.denoise.sigma_n,
        f32
    ),
    tunable!(
        "sigma_l",
        "Denoiser",
        "luminance edge-stopping",
        float(0.1, 100.0, true),
        true,
        |s| s.denoise.sigma_l,
        f32
    ),
    tunable!(
        "alpha",
        "Denoiser",
        "least weight of a new colour",
        float(0.01, 1.0, true),
        true,
        |s| s.denoise.alpha,
        f32
    ),
    tunable!(
        "moments_alpha",
        "Denoiser",
        "least weight of new moments",
        float(0.01, 1.0, true),
        true,
        |s| s.denoise.moments_alpha,
        f32
    ),
    tunable!(
        "history_cap",
        "Denoiser",
        "longest history, frames",
        float(1.0, 256.0, true),
        true,
        |s| s.denoise.history_cap,
        f32
    ),
    tunable!(
        "clamp_sigma",
        "Denoiser",
        "outlier clamp, standard deviations",
        float(0.5, 16.0, false),
        true,
        |s| s.denoise.clamp_sigma,
        f32
    ),
    tunable!(
        "converged",
        "Denoiser",
        "later a-trous iterations skip noise under this fraction",
        float(0.0, 0.5, false),
        true,
        |s| s.denoise.converged,
        f32
    ),
];

pub fn find(name: &str) -> Option<&'static Tunable> {
    ALL.iter().find(|t| t.name == name)
}

pub fn parse_bool(v: &str) -> Option<bool> {
    match v {
        "on" | "true" | "1" | "yes" => Some(true),
        "off" | "false" | "0" | "no" => Some(false),
        _ => None,
    }
}

/// Sets a tunable from script text; says whether the frame must be rebuilt.
pub fn set(settings: &mut Settings, name: &str, value: &str) -> anyhow::Result<bool> {
    let t = find(name).ok_or_else(|| anyhow::anyhow!("no tunable named {name}"))?;
    let v = match t.kind {
        Kind::Bool => parse_bool(value).map(|b| if b { 1.0 } else { 0.0 }),
        Kind::Int { min, max } => value.parse::<u32>().ok().filter(|v| (min..=max).contains(v)).map(f64::from),
        Kind::Float { min, max, .. } => value.parse::<f32>().ok().filter(|v| (min..=max).contains(v)).map(f64::from),
    };
    let v = v.ok_or_else(|| {
        let range = match t.kind {
            Kind::Bool => "on or off".to_string(),
            Kind::Int { min, max } => format!("a whole number in {min}..={max}"),
            Kind::Float { min, max, .. } => format!("a number in {min}..={max}"),
        };
        anyhow::anyhow!("{name}={value}: expected {range}")
    })?;
    (t.set)(settings, v);
    Ok(t.rebuild)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_tunable_reads_back_what_was_set() {
        for t in ALL {
            let mut s = Settings::default();
            let v = match t.kind {
                Kind::Bool => 1.0 - (t.get)(&s),
                Kind::Int { max, .. } => max as f64,
                Kind::Float { min, max, .. } => ((min + max) * 0.5) as f64,
            };
            (t.set)(&mut s, v);
            assert!(((t.get)(&s) - v).abs() < 1e-6, "{}", t.name);
        }
        let names: std::collections::HashSet<_> = ALL.iter().map(|t| t.name).collect();
        assert_eq!(names.len(), ALL.len(), "names are unique");
    }

    #[test]
    fn script_values_are_checked() {
        let mut s = Settings::default();
        assert!(set(&mut s, "taa", "off").unwrap());
        assert!(!s.taa);
        assert!(!set(&mut s, "exposure", "2").unwrap());
        assert_eq!(s.exposure, 2.0);
        assert!(set(&mut s, "s_max", "99").is_err());
        assert!(set(&mut s, "taa", "maybe").is_err());
        assert!(set(&mut s, "nope", "1").is_err());
    }
}
