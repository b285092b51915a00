//! GLSL -> SPIR-V compilation with shaderc (the `shader-compiler` feature), shared by
//! `build.rs` (which includes this file to compile every shader) and by the runtime compiler
//! (hot reload, `--shader-dir`, the test that checks shaders-spv/). One implementation, so a
//! shader compiles the same way at build time and at run time. The conventions (which files
//! are modules, which are traced) are in shader_sources.rs.
//!
//! Files are named to shaderc relative to the shaders-glsl folder (`gbuffer.vert`,
//! `common/brdf.glsl`): the SPIR-V's debug info carries these names, so the same GLSL gives
//! the same bytes wherever the checkout lives, which is what lets shaders-spv/ be committed.

use super::shader_sources::{Stage, relative_name, resolve_include, stage_of};
use std::path::Path;

/// The compile options below in words, for shaders-spv/manifest.txt.
pub const OPTIONS: &str = "Vulkan 1.2, SPIR-V 1.5, optimised for performance, debug info, \
                           RT_RAY_QUERY=1 or RT_COMPUTE_BVH=1 per ray variant";

/// Compiles one module (optionally for one ray variant) to SPIR-V words. Errors carry
/// shaderc's `file:line: error: ...` text, file names relative to `root`.
pub fn compile(
    compiler: &shaderc::Compiler,
    root: &Path,
    module: &Path,
    variant_define: Option<&str>,
) -> Result<Vec<u32>, String> {
    let kind = match stage_of(module) {
        Some(Stage::Vertex) => shaderc::ShaderKind::Vertex,
        Some(Stage::Fragment) => shaderc::ShaderKind::Fragment,
        Some(Stage::Compute) => shaderc::ShaderKind::Compute,
        None => return Err(format!("{}: not a shader stage", module.display())),
    };
    let source = std::fs::read_to_string(module).map_err(|e| format!("{}: {e}", module.display()))?;
    let name =
        relative_name(root, module).ok_or_else(|| format!("{}: not inside {}", module.display(), root.display()))?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| format!("shaderc: {e}"))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_target_spirv(shaderc::SpirvVersion::V1_5);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_generate_debug_info();
    if let Some(define) = variant_define {
        options.add_macro_definition(define, Some("1"));
    }
    let root_buf = root.to_path_buf();
    options.set_include_callback(move |inc, _ty, includer, _depth| {
        // `includer` is a root-relative name: the module's or an earlier include's.
        let dir = root_buf.join(includer).parent().map(Path::to_path_buf).unwrap_or_else(|| root_buf.clone());
        let path = resolve_include(&root_buf, &dir, inc)
            .ok_or_else(|| format!("{includer}: cannot find include \"{inc}\" inside {}", root_buf.display()))?;
        let content = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let resolved_name = relative_name(&root_buf, &path).unwrap_or_else(|| path.to_string_lossy().into_owned());
        Ok(shaderc::ResolvedInclude { resolved_name, content })
    });
    let artifact = compiler
        .compile_into_spirv(&source, kind, &name, "main", Some(&options))
        .map_err(|e| with_folder(root, &e.to_string()))?;
    Ok(artifact.as_binary().to_vec())
}

/// shaderc's messages name files relative to the root; the user gets `root/file:line: ...`.
fn with_folder(root: &Path, message: &str) -> String {
    let lines = message.lines().map(|line| match line.split_once(':') {
        Some((file, rest)) if !file.is_empty() && root.join(file).is_file() => {
            format!("{}:{rest}", root.join(file).display())
        }
        _ => line.to_string(),
    });
    lines.collect::<Vec<_>>().join("\n")
}
