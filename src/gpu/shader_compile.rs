//! GLSL -> SPIR-V compilation with shaderc, shared by `build.rs` (which includes this file to
//! embed every shader in the binary) and by the runtime compiler (hot reload). One
//! implementation, so a shader that builds at compile time builds the same way at run time.
//!
//! Conventions:
//! - every file directly in `shaders-glsl/` with a stage extension (.vert, .frag, .comp) is a
//!   shader module; `common/` holds includes;
//! - a module that includes `common/trace.glsl` (directly or through another include) is
//!   compiled twice, once per ray backend, with `RT_RAY_QUERY` or `RT_COMPUTE_BVH` defined, and
//!   keyed `name.comp:rayquery` / `name.comp:compute`; other modules are keyed by file name.

use std::path::{Path, PathBuf};

/// Ray backends a traced shader is compiled for: (key suffix, preprocessor define).
pub const RAY_VARIANTS: [(&str, &str); 2] = [("rayquery", "RT_RAY_QUERY"), ("compute", "RT_COMPUTE_BVH")];

/// The include that marks a shader as ray-traced.
const TRACE_INCLUDE: &str = "common/trace.glsl";

pub fn shader_kind(path: &Path) -> Option<shaderc::ShaderKind> {
    match path.extension()?.to_str()? {
        "vert" => Some(shaderc::ShaderKind::Vertex),
        "frag" => Some(shaderc::ShaderKind::Fragment),
        "comp" => Some(shaderc::ShaderKind::Compute),
        _ => None,
    }
}

/// Shader modules in `root` (not recursive: includes live in subfolders), sorted by name.
pub fn list_modules(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root)? {
        let path = entry?.path();
        if path.is_file() && shader_kind(&path).is_some() {
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

/// Every file a module reads (itself and its includes, transitively), for change tracking.
pub fn dependencies(root: &Path, module: &Path) -> Vec<PathBuf> {
    let mut seen = vec![module.to_path_buf()];
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
    let trace = root.join(TRACE_INCLUDE);
    dependencies(root, module).contains(&trace)
}

/// Resolves an include relative to the including file's folder, then to the root. Refuses
/// anything that resolves outside the root.
fn resolve_include(root: &Path, including_dir: &Path, name: &str) -> Option<PathBuf> {
    let root = root.canonicalize().ok()?;
    [including_dir.join(name), root.join(name)]
        .into_iter()
        .filter_map(|p| p.canonicalize().ok())
        .find(|p| p.starts_with(&root) && p.is_file())
}

/// Key under which a compiled module is stored: `file` or `file:variant`.
pub fn module_key(module: &Path, variant: Option<&str>) -> String {
    let name = module.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match variant {
        Some(v) => format!("{name}:{v}"),
        None => name,
    }
}

/// Compiles one module (optionally for one ray variant) to SPIR-V words. Errors carry
/// shaderc's `file:line: error: ...` text.
pub fn compile(
    compiler: &shaderc::Compiler,
    root: &Path,
    module: &Path,
    variant_define: Option<&str>,
) -> Result<Vec<u32>, String> {
    let kind = shader_kind(module).ok_or_else(|| format!("{}: not a shader stage", module.display()))?;
    let source = std::fs::read_to_string(module).map_err(|e| format!("{}: {e}", module.display()))?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| format!("shaderc: {e}"))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_target_spirv(shaderc::SpirvVersion::V1_5);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_generate_debug_info();
    if let Some(define) = variant_define {
        options.add_macro_definition(define, Some("1"));
    }
    let root_buf = root.to_path_buf();
    options.set_include_callback(move |name, _ty, includer, _depth| {
        let dir = Path::new(includer).parent().map(Path::to_path_buf).unwrap_or_else(|| root_buf.clone());
        let path = resolve_include(&root_buf, &dir, name)
            .ok_or_else(|| format!("{includer}: cannot find include \"{name}\" inside {}", root_buf.display()))?;
        let content = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(shaderc::ResolvedInclude { resolved_name: path.to_string_lossy().into_owned(), content })
    });
    let name = module.to_string_lossy();
    let artifact =
        compiler.compile_into_spirv(&source, kind, &name, "main", Some(&options)).map_err(|e| e.to_string())?;
    Ok(artifact.as_binary().to_vec())
}
