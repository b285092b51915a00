//! The shaders-glsl conventions and the committed SPIR-V's manifest, with no shader compiler:
//! shared by `build.rs` (which includes this file), the runtime compiler (shader_compile.rs)
//! and the test that checks shaders-spv/ against the GLSL.
//!
//! Conventions:
//! - every file directly in `shaders-glsl/` with a stage extension (.vert, .frag, .comp) is a
//!   shader module; `common/` holds includes;
//! - a module that includes `common/trace.glsl` (directly or through another include) is
//!   compiled twice, once per ray backend, with `RT_RAY_QUERY` or `RT_COMPUTE_BVH` defined, and
//!   keyed `name.comp:rayquery` / `name.comp:compute`; other modules are keyed by file name;
//! - shaders-spv/ holds one SPIR-V file per key (`spirv_file_name`) and `manifest.txt`, which
//!   records the FNV-1a 64 hash of every GLSL file the modules read and of every SPIR-V file, so
//!   a build without the shader compiler can tell when the SPIR-V no longer matches the GLSL.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Ray backends a traced shader is compiled for: (key suffix, preprocessor define).
pub const RAY_VARIANTS: [(&str, &str); 2] = [("rayquery", "RT_RAY_QUERY"), ("compute", "RT_COMPUTE_BVH")];

/// The include that marks a shader as ray-traced.
const TRACE_INCLUDE: &str = "common/trace.glsl";

/// The command that recompiles shaders-glsl/ into shaders-spv/ (named in every staleness error).
pub const REGENERATE: &str = "tools/compile-shaders.sh";

/// The manifest's file name inside shaders-spv/.
pub const MANIFEST: &str = "manifest.txt";

/// A module's pipeline stage, from its file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Vertex,
    Fragment,
    Compute,
}

pub fn stage_of(path: &Path) -> Option<Stage> {
    match path.extension()?.to_str()? {
        "vert" => Some(Stage::Vertex),
        "frag" => Some(Stage::Fragment),
        "comp" => Some(Stage::Compute),
        _ => None,
    }
}

/// Shader modules in `root` (not recursive: includes live in subfolders), sorted by name.
pub fn list_modules(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root)? {
        let path = entry?.path();
        if path.is_file() && stage_of(&path).is_some() {
            out.push(path);
        }
    }
    out.sort();
    Ok(out)
}

/// `#include "x"` targets named in a source text.
fn includes_of(source: &str) -> impl Iterator<Item = &str> {
    source.lines().filter_map(|line| {
        let rest = line.trim_start().strip_prefix("#include")?;
        let rest = rest.trim();
        rest.strip_prefix('"')?.split('"').next()
    })
}

/// Every file a module reads (itself and its includes, transitively), as canonical paths, for
/// change tracking. Canonical throughout, so `root` may be relative.
pub fn dependencies(root: &Path, module: &Path) -> Vec<PathBuf> {
    let mut seen = vec![module.canonicalize().unwrap_or_else(|_| module.to_path_buf())];
    let mut i = 0;
    while i < seen.len() {
        if let Ok(src) = std::fs::read_to_string(&seen[i]) {
            let dir = seen[i].parent().unwrap_or(root).to_path_buf();
            for inc in includes_of(&src) {
                if let Some(p) = resolve_include(root, &dir, inc)
                    && !seen.contains(&p)
                {
                    seen.push(p);
                }
            }
        }
        i += 1;
    }
    seen
}

/// True when the module traces rays, i.e. depends on `common/trace.glsl`.
pub fn is_traced(root: &Path, module: &Path) -> bool {
    let Ok(trace) = root.join(TRACE_INCLUDE).canonicalize() else { return false };
    dependencies(root, module).contains(&trace)
}

/// Resolves an include relative to the including file's folder, then to the root, as a
/// canonical path. Refuses anything that resolves outside the root.
pub fn resolve_include(root: &Path, including_dir: &Path, name: &str) -> Option<PathBuf> {
    let root = root.canonicalize().ok()?;
    [including_dir.join(name), root.join(name)]
        .into_iter()
        .filter_map(|p| p.canonicalize().ok())
        .find(|p| p.starts_with(&root) && p.is_file())
}

/// `path` relative to `root`, with `/` separators (how the manifest and the SPIR-V's debug
/// info name a GLSL file, so neither depends on where the checkout lives).
pub fn relative_name(root: &Path, path: &Path) -> Option<String> {
    let root = root.canonicalize().ok()?;
    let path = path.canonicalize().ok()?;
    let rel = path.strip_prefix(&root).ok()?;
    Some(rel.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/"))
}

/// Key under which a compiled module is stored: `file` or `file:variant`.
pub fn module_key(module: &Path, variant: Option<&str>) -> String {
    let name = module.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match variant {
        Some(v) => format!("{name}:{v}"),
        None => name,
    }
}

/// The module's keys with the define each is compiled with: one per ray variant when it traces
/// rays, else one with no define.
pub fn variants(root: &Path, module: &Path) -> Vec<(String, Option<&'static str>)> {
    if is_traced(root, module) {
        RAY_VARIANTS.iter().map(|(v, d)| (module_key(module, Some(v)), Some(*d))).collect()
    } else {
        vec![(module_key(module, None), None)]
    }
}

/// File name of a key's SPIR-V in shaders-spv/ (`shadows.comp:rayquery` ->
/// `shadows.comp.rayquery.spv`).
pub fn spirv_file_name(key: &str) -> String {
    format!("{}.spv", key.replace(':', "."))
}

/// FNV-1a, 64 bits: enough to notice an edit, small enough to write here (no dependency).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// What shaders-spv/manifest.txt records. `sources`: every GLSL file some module reads
/// (root-relative name -> hash); `modules`: key -> hash of its SPIR-V file.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Manifest {
    pub compiler: String,
    pub options: String,
    pub sources: BTreeMap<String, u64>,
    pub modules: BTreeMap<String, u64>,
}

impl Manifest {
    pub fn render(&self) -> String {
        let mut s = String::new();
        s.push_str("# The SPIR-V in this folder, compiled from shaders-glsl/ by ");
        s.push_str(REGENERATE);
        s.push_str(". Generated: do not edit.\n");
        s.push_str("# build.rs checks the GLSL hashes below against shaders-glsl/ (FNV-1a 64).\n");
        let _ = writeln!(s, "compiler {}", self.compiler);
        let _ = writeln!(s, "options {}", self.options);
        for (name, hash) in &self.sources {
            let _ = writeln!(s, "glsl {hash:016x} {name}");
        }
        for (key, hash) in &self.modules {
            let _ = writeln!(s, "spirv {hash:016x} {key}");
        }
        s
    }

    pub fn parse(text: &str) -> Result<Self, String> {
        let mut m = Manifest::default();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let bad = || format!("line {}: expected `compiler`, `options`, `glsl` or `spirv`: {line}", i + 1);
            let (kind, rest) = line.split_once(' ').ok_or_else(bad)?;
            match kind {
                "compiler" => m.compiler = rest.to_string(),
                "options" => m.options = rest.to_string(),
                "glsl" | "spirv" => {
                    let (hash, name) = rest.split_once(' ').ok_or_else(bad)?;
                    let hash = u64::from_str_radix(hash, 16).map_err(|_| bad())?;
                    let map = if kind == "glsl" { &mut m.sources } else { &mut m.modules };
                    map.insert(name.to_string(), hash);
                }
                _ => return Err(bad()),
            }
        }
        Ok(m)
    }
}

/// Hash of every GLSL file the modules in `root` read (root-relative name -> FNV-1a 64), and
/// every module key with its define.
pub type SourceScan = (BTreeMap<String, u64>, Vec<(PathBuf, String, Option<&'static str>)>);

pub fn scan_sources(root: &Path) -> Result<SourceScan, String> {
    let modules = list_modules(root).map_err(|e| format!("{}: {e}", root.display()))?;
    let mut sources = BTreeMap::new();
    let mut keys = Vec::new();
    for module in modules {
        for dep in dependencies(root, &module) {
            let name =
                relative_name(root, &dep).ok_or_else(|| format!("{}: outside {}", dep.display(), root.display()))?;
            if let std::collections::btree_map::Entry::Vacant(slot) = sources.entry(name) {
                let bytes = std::fs::read(&dep).map_err(|e| format!("{}: {e}", dep.display()))?;
                slot.insert(fnv1a64(&bytes));
            }
        }
        for (key, define) in variants(root, &module) {
            keys.push((module.clone(), key, define));
        }
    }
    Ok((sources, keys))
}

/// Every way the SPIR-V in `spv_dir` fails to match the GLSL in `glsl_root`, one line each
/// naming the file (empty: up to date).
pub fn stale_spirv(glsl_root: &Path, spv_dir: &Path) -> Result<Vec<String>, String> {
    let manifest_path = spv_dir.join(MANIFEST);
    let text = match std::fs::read_to_string(&manifest_path) {
        Ok(t) => t,
        Err(e) => return Ok(vec![format!("{}: {e}", manifest_path.display())]),
    };
    let manifest = Manifest::parse(&text).map_err(|e| format!("{}: {e}", manifest_path.display()))?;
    let (sources, keys) = scan_sources(glsl_root)?;
    let mut stale = Vec::new();
    let glsl = |name: &str| glsl_root.join(name).display().to_string();
    for (name, hash) in &sources {
        match manifest.sources.get(name) {
            None => stale.push(format!("{}: new since the SPIR-V was compiled", glsl(name))),
            Some(h) if h != hash => stale.push(format!("{}: changed since the SPIR-V was compiled", glsl(name))),
            Some(_) => {}
        }
    }
    for name in manifest.sources.keys().filter(|n| !sources.contains_key(*n)) {
        stale.push(format!("{}: removed, or no longer read by any module", glsl(name)));
    }
    for (_, key, _) in &keys {
        let file = spv_dir.join(spirv_file_name(key));
        match (manifest.modules.get(key), std::fs::read(&file)) {
            (None, _) => stale.push(format!("{}: module {key} has no SPIR-V in the manifest", file.display())),
            (Some(_), Err(e)) => stale.push(format!("{}: {e}", file.display())),
            (Some(h), Ok(bytes)) if fnv1a64(&bytes) != *h => {
                stale.push(format!("{}: differs from the SPIR-V the manifest records", file.display()))
            }
            _ => {}
        }
    }
    for key in manifest.modules.keys().filter(|k| !keys.iter().any(|(_, key, _)| key == *k)) {
        stale.push(format!(
            "{}: module {key} no longer exists in the GLSL",
            spv_dir.join(spirv_file_name(key)).display()
        ));
    }
    Ok(stale)
}
