//! The configurations a sweep renders: each one a short name (`d4-s3-b1-r1`) that parses to
//! and prints from the frame settings it changes.

use crate::passes::gi::GiRate;
use crate::render::Settings;
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

/// One configuration of the hybrid frame. Its name lists the settings as letter + number,
/// joined by `-`: `d` SVGF à-trous iterations (0 = denoiser off), `s` shadow rays per pixel
/// and area light at most (s_max), `b` GI bounces, `r` reflection rays per pixel, `t0`
/// when TAA is off, `c0` when the radiance cache is off, `g1`/`g2`/`g4` when gi traces all of
/// the pixels each frame, half or a quarter of them (against the default), and `f1` when every
/// pass runs instead of the scene's frame plan (src/render/plan.rs): a pair differing only in
/// `f` shows what the plan saves and costs. Settings left out of a name take the defaults
/// (`d4-s3-b1-r1`, TAA on: the renderer's defaults, and what `hybrid-rt render` draws).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Config {
    pub denoise_iterations: u32,
    pub shadow_s_max: u32,
    pub gi_bounces: u32,
    pub reflection_rays: u32,
    pub taa: bool,
    /// Every pass (`--full`) instead of the frame plan.
    #[serde(default)]
    pub full: bool,
    /// The radiance cache (sweeps cached before it existed had none).
    #[serde(default)]
    pub cache: bool,
    /// gi traces one of this many pixels per frame: 1, 2 or 4 (GiRate::pixels; `g1`, `g2`,
    /// `g4`). Sweeps cached before it had a bool in its place (`gi_half_rate`), which is
    /// ignored; their points' names say the rate.
    #[serde(default = "default_gi_rate")]
    pub gi_rate: u32,
}

impl Default for Config {
    fn default() -> Self {
        let s = Settings::default();
        Self {
            denoise_iterations: if s.denoiser { s.denoise.iterations } else { 0 },
            shadow_s_max: s.shadows.s_max,
            gi_bounces: s.gi.bounces,
            reflection_rays: s.reflections.rays,
            taa: true,
            full: false,
            cache: s.radiance_cache.enabled,
            gi_rate: s.gi.rate.pixels(),
        }
    }
}

fn default_gi_rate() -> u32 {
    Settings::default().gi.rate.pixels()
}

impl std::fmt::Display for Config {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "d{}-s{}-b{}-r{}",
            self.denoise_iterations, self.shadow_s_max, self.gi_bounces, self.reflection_rays
        )?;
        if !self.taa {
            write!(f, "-t0")?;
        }
        if !self.cache {
            write!(f, "-c0")?;
        }
        if self.gi_rate != default_gi_rate() {
            write!(f, "-g{}", self.gi_rate)?;
        }
        if self.full {
            write!(f, "-f1")?;
        }
        Ok(())
    }
}

impl std::str::FromStr for Config {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        let mut c = Config::default();
        for part in s.split('-') {
            let (key, value) = part.split_at(part.find(|ch: char| ch.is_ascii_digit()).unwrap_or(part.len()));
            let Ok(n) = value.parse::<u32>() else {
                bail!("configuration '{s}': '{part}' is not a letter followed by a number (e.g. d4-s5-b1-r1)");
            };
            let (slot, range) = match key {
                "d" => (&mut c.denoise_iterations, 0..=8),
                "s" => (&mut c.shadow_s_max, 1..=16),
                "b" => (&mut c.gi_bounces, 1..=8),
                "r" => (&mut c.reflection_rays, 1..=8),
                "t" => {
                    if n > 1 {
                        bail!("configuration '{s}': t takes 0 (TAA off) or 1 (on)");
                    }
                    c.taa = n == 1;
                    continue;
                }
                "c" => {
                    if n > 1 {
                        bail!("configuration '{s}': c takes 0 (radiance cache off) or 1 (on)");
                    }
                    c.cache = n == 1;
                    continue;
                }
                "g" => {
                    if GiRate::from_pixels(n).is_none() {
                        bail!(
                            "configuration '{s}': g takes 1 (gi traces every pixel), 2 (half of them a frame) or 4 (a quarter)"
                        );
                    }
                    c.gi_rate = n;
                    continue;
                }
                "f" => {
                    if n > 1 {
                        bail!("configuration '{s}': f takes 0 (frame plan) or 1 (every pass)");
                    }
                    c.full = n == 1;
                    continue;
                }
                _ => bail!(
                    "configuration '{s}': unknown setting '{key}' (d: denoiser iterations, s: shadow s_max, \
                     b: GI bounces, r: reflection rays, t: TAA 0/1, c: radiance cache 0/1, g: gi rate 1/2/4, f: every pass 0/1)"
                ),
            };
            if !range.contains(&n) {
                bail!("configuration '{s}': {key}{n} is outside {}..={}", range.start(), range.end());
            }
            *slot = n;
        }
        Ok(c)
    }
}

impl Config {
    /// Sets what this configuration decides in `s`, leaving the rest.
    pub fn apply(&self, s: &mut Settings) {
        s.denoiser = self.denoise_iterations > 0;
        if self.denoise_iterations > 0 {
            s.denoise.iterations = self.denoise_iterations;
        }
        s.shadows.s_max = self.shadow_s_max;
        s.gi.bounces = self.gi_bounces;
        s.reflections.rays = self.reflection_rays;
        s.taa = self.taa;
        s.full = self.full;
        s.radiance_cache.enabled = self.cache;
        s.gi.rate = GiRate::from_pixels(self.gi_rate).unwrap_or(s.gi.rate);
    }
}

/// The default configurations: each axis moved away from the renderer's defaults (d4-s3-b1-r1)
/// on its own, once with the denoiser on and once with it off, plus the cheapest and the most
/// expensive corners, and the frame without the radiance cache: with one bounce, and as a
/// 1-spp path tracer, and gi at full rate. The first 15 took ~5 minutes at 320x180 on a
/// 2-core lavapipe; the full grid (5 x 3 x 2 x 2 x 2 = 120) would take hours and add few new
/// front points.
pub const DEFAULT_CONFIGS: &[&str] = &[
    "d0-s3-b1-r1-t0", // no temporal filtering at all: the raw one-sample frame
    "d0-s1-b1-r1",
    "d0-s3-b1-r1",
    "d1-s3-b1-r1",
    "d2-s3-b1-r1",
    "d4-s3-b1-r1",    // the renderer's defaults
    "d4-s3-b1-r1-f1", // the same with every pass: what the frame plan saves and costs
    "d4-s3-b1-r1-g1", // the same with gi tracing every pixel every frame
    "d4-s3-b1-r1-g4", // ... and a quarter of them
    "d4-s3-b1-r1-t0",
    "d4-s1-b1-r1",
    "d4-s5-b1-r1", // the chapter's standard tier, the default until 2026-12-06
    "d4-s8-b1-r1",
    "d0-s3-b2-r1",
    "d4-s3-b2-r1",
    "d0-s3-b1-r2",
    "d4-s3-b1-r2",
    "d4-s8-b2-r2",
    "d0-s3-b1-r1-c0", // without the radiance cache: one bounce
    "d4-s3-b1-r1-c0",
    "d4-s3-b8-r1-c0-g1", // a 1-spp path tracer (8 bounces, no cache) + SVGF + TAA
];

pub fn default_configs() -> Vec<Config> {
    DEFAULT_CONFIGS.iter().map(|s| s.parse().expect("the default configurations parse")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_names_round_trip() {
        for s in DEFAULT_CONFIGS {
            assert_eq!(s.parse::<Config>().unwrap().to_string(), *s);
        }
        let c: Config = "d2".parse().unwrap();
        assert_eq!(c, Config { denoise_iterations: 2, ..Default::default() });
        assert_eq!("s8-t0".parse::<Config>().unwrap().to_string(), "d4-s8-b1-r1-t0");
        assert_eq!("b8-c0".parse::<Config>().unwrap().to_string(), "d4-s3-b8-r1-c0");
        assert!(!"c0".parse::<Config>().unwrap().cache && "c1".parse::<Config>().unwrap().cache);
        // Half-rate gi is the default: only full and quarter rate show in a name.
        assert_eq!(["g1", "g2", "g4"].map(|g| g.parse::<Config>().unwrap().gi_rate), [1, 2, 4]);
        assert_eq!("g2".parse::<Config>().unwrap().to_string(), "d4-s3-b1-r1");
        assert_eq!("g4".parse::<Config>().unwrap().to_string(), "d4-s3-b1-r1-g4");
        assert_eq!("c0-g1".parse::<Config>().unwrap().to_string(), "d4-s3-b1-r1-c0-g1");
        for bad in ["x3", "d", "d-1", "s0", "d9", "t2", "c2", "g0", "g3", "", "d4s5"] {
            assert!(bad.parse::<Config>().is_err(), "{bad} should not parse");
        }
    }

    #[test]
    fn config_applies_to_settings() {
        let mut s = Settings::default();
        "d0-s8-b2-r2-t0".parse::<Config>().unwrap().apply(&mut s);
        assert!(!s.denoiser && !s.taa);
        assert_eq!((s.shadows.s_max, s.gi.bounces, s.reflections.rays), (8, 2, 2));
        "d2".parse::<Config>().unwrap().apply(&mut s);
        assert!(s.denoiser && s.taa);
        assert_eq!(s.denoise.iterations, 2);
        "g4".parse::<Config>().unwrap().apply(&mut s);
        assert_eq!(s.gi.rate, GiRate::Quarter);
    }
}
