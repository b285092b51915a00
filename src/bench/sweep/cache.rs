//! What a sweep keeps on disk and reads back: a stable hash of the scene's bytes for cache
//! keys, the cache paths, and the pick of a configuration for `render --target-ms /
//! --target-error` from a cached sweep.

use super::{Config, Point, SceneSweep};
use crate::backend::Backend;
use crate::bench::slug;
use crate::bench::target::{self, Measured, Target};
use crate::render::{CameraChoice, Environment, default_light};
use crate::scene::Scene;
use anyhow::{Context as _, Result, bail};
use std::path::{Path, PathBuf};

/// 64-bit FNV-1a: a stable hash (unlike std's) for cache keys; collisions are not a concern.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The URIs of buffers and images that a glTF (JSON, or the JSON chunk of a GLB) names outside
/// itself (not `data:`).
fn external_uris(bytes: &[u8]) -> Vec<String> {
    let json = if bytes.starts_with(b"glTF") && bytes.len() >= 20 {
        let len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
        bytes.get(20..20 + len).unwrap_or(&[])
    } else {
        bytes
    };
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(json) else { return Vec::new() };
    ["buffers", "images"]
        .iter()
        .filter_map(|k| doc.get(k).and_then(|v| v.as_array()))
        .flatten()
        .filter_map(|item| item.get("uri").and_then(|u| u.as_str()))
        .filter(|u| !u.starts_with("data:"))
        .map(str::to_string)
        .collect()
}

/// A hash of the scene's content: the bytes of the file and of the buffers and images it
/// names (a built-in scene: its name). Renaming or moving a scene keeps its cached results;
/// editing any of its files drops them.
pub fn scene_hash(spec: &str) -> Result<String> {
    let mut h = Fnv::new();
    if let Some(name) = spec.strip_prefix("builtin:") {
        h.write(b"builtin:");
        h.write(name.as_bytes());
    } else {
        let path = Path::new(spec);
        let bytes = std::fs::read(path).with_context(|| format!("{spec}: cannot read the scene file"))?;
        h.write(&bytes);
        let dir = path.parent().unwrap_or(Path::new("."));
        for uri in external_uris(&bytes) {
            // A file the loader could not read has already failed the load; skip it here.
            if let Ok(b) = std::fs::read(dir.join(&uri)) {
                h.write(uri.as_bytes());
                h.write(&b);
            }
        }
    }
    Ok(format!("{:016x}", h.0))
}

/// The scene as it appears in cache keys: its content hash, marked when the default light
/// lights it.
pub fn lit_scene_key(hash: String, default_light: bool) -> String {
    if default_light { format!("{hash}-daylight") } else { hash }
}

/// The camera as it appears in cache keys.
pub fn camera_key(c: &CameraChoice) -> String {
    match c {
        CameraChoice::Default => "default".into(),
        CameraChoice::Index(i) => format!("camera{i}"),
        CameraChoice::Name(n) => format!("camera-{}", slug(n)),
    }
}

/// The file `render --target-*` reads for a scene, camera, size, backend and device.
pub fn sweep_cache_path(
    cache_dir: &Path,
    scene_hash: &str,
    camera: &str,
    (width, height): (u32, u32),
    backend: Backend,
    device: &str,
) -> PathBuf {
    cache_dir.join("sweep").join(format!(
        "{scene_hash}-{camera}-{width}x{height}-{}-{}.json",
        backend.variant(),
        slug(device)
    ))
}

/// For `render --target-ms / --target-error`: the configuration picked from the cached sweep
/// of this scene (as named on the command line, loaded, and lit by `environment`), camera,
/// size, backend and device, and why.
pub fn pick_for_render(
    cache_dir: &Path,
    (spec, scene, environment): (&str, &Scene, &Environment),
    camera: &CameraChoice,
    size: (u32, u32),
    backend: Backend,
    device: &str,
    goal: Target,
) -> Result<(Config, String)> {
    let start = crate::render::camera::start_position(scene, camera)?;
    let lit = default_light::choose(environment, scene, start).default_light;
    let hash = lit_scene_key(scene_hash(spec)?, lit);
    let cam = camera_key(camera);
    let path = sweep_cache_path(cache_dir, &hash, &cam, size, backend, device);
    if !path.is_file() {
        let (w, h) = size;
        let mut camera_arg =
            if matches!(camera, CameraChoice::Default) { String::new() } else { format!(" --camera {cam}") };
        if !lit && default_light::choose(&Environment::DefaultLight, scene, start).default_light {
            camera_arg += " --no-default-light";
        }
        let mut msg = format!(
            "no speed/accuracy sweep of {spec} at {w}x{h} ({} backend, {cam} camera) on {device} in {}; \
             make one with: hybrid-rt bench sweep {spec} --size {w}x{h}{camera_arg} --backend {}",
            backend.variant(),
            cache_dir.join("sweep").display(),
            backend.variant()
        );
        let other = other_sizes(cache_dir, &hash, &cam, backend, device);
        if !other.is_empty() {
            msg += &format!(" (sweeps exist at {}: pass one as --size)", other.join(", "));
        }
        bail!(msg);
    }
    let sweep: SceneSweep = serde_json::from_slice(&std::fs::read(&path)?)
        .with_context(|| format!("{}: not a sweep result; delete it and run the sweep again", path.display()))?;
    let measured: Vec<Measured> = sweep.points.iter().map(Point::measured).collect();
    let pick = target::select(&measured, goal)?;
    let p = &sweep.points[pick.index];
    let why = format!(
        "{}: {} (sweep of {} configurations, error after {} frames, {})",
        p.name,
        pick.why,
        sweep.points.len(),
        sweep.frames,
        path.display()
    );
    // The name, not the stored settings: it says the gi rate in sweeps cached before the rate
    // had three values.
    let config = p.name.parse().unwrap_or(p.config);
    Ok((config, why))
}

/// Sizes at which a sweep of this scene, camera, backend and device is cached.
fn other_sizes(cache_dir: &Path, hash: &str, camera: &str, backend: Backend, device: &str) -> Vec<String> {
    let prefix = format!("{hash}-{camera}-");
    let suffix = format!("-{}-{}.json", backend.variant(), slug(device));
    let Ok(entries) = std::fs::read_dir(cache_dir.join("sweep")) else { return Vec::new() };
    let mut sizes: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| Some(n.strip_prefix(&prefix)?.strip_suffix(&suffix)?.to_string()))
        .collect();
    sizes.sort();
    sizes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_and_gltf_uris() {
        let json = br#"{"buffers":[{"uri":"a.bin"},{"uri":"data:x"}],"images":[{"uri":"t.png"}]}"#;
        assert_eq!(external_uris(json), vec!["a.bin", "t.png"]);
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&0u32.to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(json);
        assert_eq!(external_uris(&glb), vec!["a.bin", "t.png"]);
        assert!(external_uris(b"\x00\x01").is_empty());
        assert_ne!(scene_hash("builtin:a").unwrap(), scene_hash("builtin:b").unwrap());
    }
}
