//! Embeds one SPIR-V module per shader key in the binary (src/gpu/shader.rs's `EMBEDDED`).
//!
//! By default the SPIR-V is the one committed in shaders-spv/, so a build needs no shader
//! compiler (a cold libshaderc build alone takes ~20 minutes on 2 cores); the build fails, naming
//! the files and `tools/compile-shaders.sh`, when shaders-glsl/ changed since that SPIR-V was
//! compiled (shaders-spv/manifest.txt). With the `shader-compiler` feature it compiles
//! shaders-glsl/ with shaderc instead (a compile error fails the build with shaderc's
//! `file:line: error` message), and tests/committed_spirv.rs checks that the result is
//! byte-for-byte the committed SPIR-V.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

// Shared with the crate; this script uses part of it.
#[allow(dead_code)]
#[path = "src/gpu/shader_sources.rs"]
mod shader_sources;

#[cfg(feature = "shader-compiler")]
#[allow(dead_code)]
#[path = "src/gpu/shader_compile.rs"]
mod shader_compile;

fn main() {
    // Read at run time: a build script compiled for one checkout can be reused by another.
    let manifest_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let glsl = manifest_dir.join("shaders-glsl");
    let spv = manifest_dir.join("shaders-spv");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    // A folder here is scanned recursively: any added, removed or edited file reruns this.
    println!("cargo:rerun-if-changed={}", glsl.display());
    let files = embedded_files(&glsl, &spv, &out_dir, &manifest_dir);
    let mut table = String::from("pub static EMBEDDED: &[(&str, &[u8])] = &[\n");
    for (key, file) in files {
        writeln!(table, "    ({key:?}, include_bytes!({:?})),", file.display().to_string()).unwrap();
    }
    table.push_str("];\n");
    std::fs::write(out_dir.join("shaders.rs"), table).expect("write shaders.rs");
}

/// The committed SPIR-V, after checking that it matches shaders-glsl/.
#[cfg(not(feature = "shader-compiler"))]
fn embedded_files(glsl: &Path, spv: &Path, _out_dir: &Path, _manifest_dir: &Path) -> Vec<(String, PathBuf)> {
    println!("cargo:rerun-if-changed={}", spv.display());
    let stale = match shader_sources::stale_spirv(glsl, spv) {
        Ok(stale) => stale,
        Err(e) => fail(&format!("cannot check the committed SPIR-V: {e}")),
    };
    if !stale.is_empty() {
        fail(&format!(
            "the SPIR-V in {} does not match the GLSL in {}:\n  {}\nRegenerate it with `{}` (it needs the \
             `shader-compiler` feature: libshaderc, ~20 minutes to build the first time) and commit shaders-spv/.",
            spv.display(),
            glsl.display(),
            stale.join("\n  "),
            shader_sources::REGENERATE
        ));
    }
    let (_, keys) = shader_sources::scan_sources(glsl).unwrap_or_else(|e| fail(&e));
    keys.into_iter().map(|(_, key, _)| (key.clone(), spv.join(shader_sources::spirv_file_name(&key)))).collect()
}

/// Every module compiled now from shaders-glsl/. shaders-spv/ is not read: the regenerate
/// command needs this build while it is stale, and tests/committed_spirv.rs compares the two.
#[cfg(feature = "shader-compiler")]
fn embedded_files(glsl: &Path, _spv: &Path, out_dir: &Path, manifest_dir: &Path) -> Vec<(String, PathBuf)> {
    println!("cargo:rustc-env=HYBRID_RT_SHADERC_VERSION={}", locked_version(manifest_dir, "shaderc-sys"));
    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let (_, keys) = shader_sources::scan_sources(glsl).unwrap_or_else(|e| fail(&e));
    let mut files = Vec::new();
    let mut errors = Vec::new();
    for (module, key, define) in keys {
        match shader_compile::compile(&compiler, glsl, &module, define) {
            Ok(words) => {
                let file = out_dir.join(shader_sources::spirv_file_name(&key));
                let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                std::fs::write(&file, bytes).expect("write spv");
                files.push((key, file));
            }
            Err(e) => errors.push(format!("[{key}] {e}")),
        }
    }
    if !errors.is_empty() {
        fail(&format!("shader compilation failed:\n{}", errors.join("\n")));
    }
    files
}

/// A package's version in Cargo.lock (the shaderc sources libshaderc is built from), for the
/// manifest's `compiler` line.
#[cfg(feature = "shader-compiler")]
fn locked_version(manifest_dir: &Path, package: &str) -> String {
    let lock = std::fs::read_to_string(manifest_dir.join("Cargo.lock")).unwrap_or_default();
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line == format!("name = \"{package}\"")
            && let Some(v) = lines.next().and_then(|l| l.strip_prefix("version = \""))
        {
            return v.trim_end_matches('"').to_string();
        }
    }
    "unknown".into()
}

/// Stops the build with a message cargo shows in full.
fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}
