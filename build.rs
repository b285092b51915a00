//! Compiles every shader module in shaders-glsl/ to SPIR-V and embeds them in the binary
//! (see src/gpu/shader_compile.rs for the conventions). A compile error fails the build with
//! shaderc's `file:line: error` message.

use std::fmt::Write as _;
use std::path::Path;

#[path = "src/gpu/shader_compile.rs"]
mod shader_compile;

use shader_compile::{RAY_VARIANTS, compile, dependencies, is_traced, list_modules, module_key};

fn main() {
    // Read at run time: a build script compiled for one checkout can be reused by another.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest).join("shaders-glsl");
    let out_dir = std::path::PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    println!("cargo:rerun-if-changed={}", root.display());
    println!("cargo:rerun-if-changed={}", root.join("common").display());
    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut table = String::from("pub static EMBEDDED: &[(&str, &[u8])] = &[\n");
    let mut errors = Vec::new();
    for module in list_modules(&root).expect("read shaders-glsl") {
        for dep in dependencies(&root, &module) {
            println!("cargo:rerun-if-changed={}", dep.display());
        }
        let variants: Vec<(Option<&str>, Option<&str>)> = if is_traced(&root, &module) {
            RAY_VARIANTS.iter().map(|(k, d)| (Some(*k), Some(*d))).collect()
        } else {
            vec![(None, None)]
        };
        for (variant, define) in variants {
            let key = module_key(&module, variant);
            match compile(&compiler, &root, &module, define) {
                Ok(words) => {
                    let file = out_dir.join(format!("{}.spv", key.replace(':', ".")));
                    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                    std::fs::write(&file, bytes).expect("write spv");
                    writeln!(table, "    ({key:?}, include_bytes!({:?})),", file.display().to_string()).unwrap();
                }
                Err(e) => errors.push(format!("[{key}] {e}")),
            }
        }
    }
    if !errors.is_empty() {
        panic!("shader compilation failed:\n{}", errors.join("\n"));
    }
    table.push_str("];\n");
    std::fs::write(out_dir.join("shaders.rs"), table).expect("write shaders.rs");
}
