//! Shader modules: the SPIR-V embedded at build time (from shaders-spv/, or compiled from
//! shaders-glsl/ with the `shader-compiler` feature), or compiled at run time from a
//! shaders-glsl folder (the viewer's hot reload and `--shader-dir`, which need that feature).

use anyhow::{Result, anyhow};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

#[cfg(feature = "shader-compiler")]
use super::shader_compile as compile;
pub use super::shader_sources::RAY_VARIANTS;

/// The compiler and options the runtime compiler uses, for shaders-spv/manifest.txt.
#[cfg(feature = "shader-compiler")]
pub const COMPILER: (&str, &str) = (
    concat!("shaderc-sys ", env!("HYBRID_RT_SHADERC_VERSION"), " (libshaderc built from its bundled sources)"),
    compile::OPTIONS,
);

/// What a build without the runtime compiler says when asked to compile.
pub const NO_COMPILER: &str = "this hybrid-rt was built without the runtime shader compiler \
     (it runs the SPIR-V committed in shaders-spv/); rebuild it with \
     `cargo build --features shader-compiler` to compile shaders-glsl at run time";

/// Where SPIR-V comes from.
pub struct ShaderLibrary {
    /// Runtime-compiled modules override the embedded ones.
    overrides: HashMap<String, Vec<u32>>,
    source_dir: Option<PathBuf>,
}

impl ShaderLibrary {
    /// Only the SPIR-V embedded at build time.
    pub fn embedded() -> Self {
        Self { overrides: HashMap::new(), source_dir: None }
    }

    /// Ok when this build can compile GLSL at run time; else the error saying how to get a
    /// build that can (checked up front by options that would compile later, like hot reload).
    pub fn runtime_compiler() -> Result<()> {
        if cfg!(feature = "shader-compiler") { Ok(()) } else { Err(anyhow!(NO_COMPILER)) }
    }

    /// Compiles every module in `dir` (relative or absolute) now and uses those. Errors name
    /// file and line; without the `shader-compiler` feature, the error says how to rebuild.
    pub fn from_dir(dir: &Path) -> Result<Self> {
        let mut lib = Self { overrides: HashMap::new(), source_dir: Some(dir.to_path_buf()) };
        lib.recompile()?;
        Ok(lib)
    }

    /// The modules of `dir` where a command was given `--shader-dir`, else the embedded ones.
    pub fn from_dir_or_embedded(dir: Option<&Path>) -> Result<Self> {
        dir.map_or_else(|| Ok(Self::embedded()), Self::from_dir)
    }

    /// Recompiles all modules from the source folder. On error the previous SPIR-V is kept
    /// and the error (with file and line) returned.
    pub fn recompile(&mut self) -> Result<()> {
        let dir = self.source_dir.as_deref().ok_or_else(|| anyhow!("no shader source folder"))?;
        self.overrides = compile_dir(dir)?;
        Ok(())
    }

    /// SPIR-V for a module key (`gbuffer.vert`, `shadows.comp:rayquery`, ...).
    pub fn get(&self, key: &str) -> Result<Vec<u32>> {
        if let Some(words) = self.overrides.get(key) {
            return Ok(words.clone());
        }
        let bytes = embedded::EMBEDDED
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, b)| *b)
            .ok_or_else(|| anyhow!("no shader module named {key}"))?;
        ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| anyhow!("{key}: bad SPIR-V: {e}"))
    }

    /// Names of all embedded modules.
    pub fn embedded_keys() -> impl Iterator<Item = &'static str> {
        embedded::EMBEDDED.iter().map(|(k, _)| *k)
    }
}

/// Every module key in `dir` compiled to SPIR-V words.
#[cfg(feature = "shader-compiler")]
fn compile_dir(dir: &Path) -> Result<HashMap<String, Vec<u32>>> {
    let compiler = shaderc::Compiler::new().map_err(|e| anyhow!("shaderc: {e}"))?;
    let mut out = HashMap::new();
    let modules = super::shader_sources::list_modules(dir).map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    for module in modules {
        for (key, define) in super::shader_sources::variants(dir, &module) {
            let words = compile::compile(&compiler, dir, &module, define).map_err(|e| anyhow!(e))?;
            out.insert(key, words);
        }
    }
    Ok(out)
}

#[cfg(not(feature = "shader-compiler"))]
fn compile_dir(dir: &Path) -> Result<HashMap<String, Vec<u32>>> {
    Err(anyhow!("{}: cannot compile: {NO_COMPILER}", dir.display()))
}
