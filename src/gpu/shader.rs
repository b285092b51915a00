//! Shader modules: SPIR-V compiled at build time and embedded, or compiled at run time from a
//! shaders-glsl folder (the viewer's hot reload and `--shader-dir`), with the same conventions
//! (see shader_compile.rs).

use anyhow::{Result, anyhow};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

#[path = "shader_compile.rs"]
mod compile;

pub use compile::RAY_VARIANTS;

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

    /// Compiles every module in `dir` now (errors name file and line) and uses those.
    pub fn from_dir(dir: &Path) -> Result<Self> {
        let mut lib = Self { overrides: HashMap::new(), source_dir: Some(dir.to_path_buf()) };
        lib.recompile()?;
        Ok(lib)
    }

    /// Recompiles all modules from the source folder. On error the previous SPIR-V is kept
    /// and the error (with file and line) returned.
    pub fn recompile(&mut self) -> Result<()> {
        let dir = self.source_dir.clone().ok_or_else(|| anyhow!("no shader source folder"))?;
        let compiler = shaderc::Compiler::new().map_err(|e| anyhow!("shaderc: {e}"))?;
        let mut fresh = HashMap::new();
        let modules = compile::list_modules(&dir).map_err(|e| anyhow!("{}: {e}", dir.display()))?;
        for module in modules {
            let variants: Vec<(Option<&str>, Option<&str>)> = if compile::is_traced(&dir, &module) {
                RAY_VARIANTS.iter().map(|(k, d)| (Some(*k), Some(*d))).collect()
            } else {
                vec![(None, None)]
            };
            for (variant, define) in variants {
                let words = compile::compile(&compiler, &dir, &module, define).map_err(|e| anyhow!(e))?;
                fresh.insert(compile::module_key(&module, variant), words);
            }
        }
        self.overrides = fresh;
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
