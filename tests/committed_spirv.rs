//! shaders-spv/ (the SPIR-V a default build embeds) is exactly what shaders-glsl/ compiles to:
//! every module is compiled now, at run time, from the relative path `shaders-glsl` (as
//! `--shader-dir shaders-glsl` would), and its bytes must equal the committed file; the manifest
//! must record the GLSL hashes, the compiler and its options. The SPIR-V the build script
//! embedded (compiled by build.rs with this feature) must be the same bytes too.
//!
//! With `HYBRID_RT_BLESS_SPIRV=1` that test writes shaders-spv/ instead of checking it: that is
//! tools/compile-shaders.sh, the one command to run after editing a shader. It needs the
//! `shader-compiler` feature (tools/test.sh enables it). The other tests check what a build
//! without the feature checks (build.rs): that an edited, added or removed GLSL file or SPIR-V
//! file is named as stale. No GPU.

mod common;

use hybrid_rt::gpu::shader_sources::{MANIFEST, Manifest, stale_spirv};
use std::path::Path;

#[cfg(feature = "shader-compiler")]
fn bytes_of(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

#[cfg(feature = "shader-compiler")]
#[test]
fn committed_spirv_is_what_the_glsl_compiles_to() {
    // Tests run in the package root; the relative path is part of what is tested.
    let glsl = Path::new("shaders-glsl");
    let spv = Path::new("shaders-spv");
    use hybrid_rt::gpu::ShaderLibrary;
    use hybrid_rt::gpu::shader::COMPILER;
    use hybrid_rt::gpu::shader_sources::{REGENERATE, fnv1a64, scan_sources, spirv_file_name};
    let bless = std::env::var_os("HYBRID_RT_BLESS_SPIRV").is_some_and(|v| v == "1");
    let lib = ShaderLibrary::from_dir(glsl).unwrap_or_else(|e| panic!("shaders-glsl does not compile: {e:#}"));
    let (sources, keys) = scan_sources(glsl).expect("scan shaders-glsl");
    let mut manifest =
        Manifest { compiler: COMPILER.0.into(), options: COMPILER.1.into(), sources, ..Default::default() };
    let mut stale = Vec::new();
    for (_, key, _) in &keys {
        let fresh = bytes_of(&lib.get(key).unwrap());
        manifest.modules.insert(key.clone(), fnv1a64(&fresh));
        let file = spv.join(spirv_file_name(key));
        if bless {
            std::fs::write(&file, &fresh).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        } else if std::fs::read(&file).ok().as_ref() != Some(&fresh) {
            stale.push(format!("{} is not what {key} compiles to", file.display()));
        }
        let embedded = bytes_of(&ShaderLibrary::embedded().get(key).unwrap());
        assert_eq!(embedded, fresh, "{key}: build.rs embedded other SPIR-V than the runtime compiler made");
    }
    let embedded_keys: Vec<&str> = ShaderLibrary::embedded_keys().collect();
    let keys: Vec<&str> = keys.iter().map(|(_, k, _)| k.as_str()).collect();
    assert_eq!(embedded_keys, keys, "the embedded modules are not the modules in shaders-glsl");

    // SPIR-V files of modules that no longer exist.
    for entry in std::fs::read_dir(spv).expect("read shaders-spv") {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".spv") && !keys.iter().any(|k| spirv_file_name(k) == name) {
            if bless {
                std::fs::remove_file(&path).unwrap();
            } else {
                stale.push(format!("{} belongs to no module in shaders-glsl", path.display()));
            }
        }
    }
    let text = manifest.render();
    let manifest_path = spv.join(MANIFEST);
    if bless {
        std::fs::write(&manifest_path, &text).unwrap();
        println!("wrote {} modules and {} to {}", keys.len(), MANIFEST, spv.display());
        return;
    }
    if std::fs::read_to_string(&manifest_path).ok().as_deref() != Some(text.as_str()) {
        stale.push(format!("{} does not record these GLSL files, compiler and SPIR-V", manifest_path.display()));
    }
    assert!(stale.is_empty(), "shaders-spv/ is stale; regenerate it with {REGENERATE}:\n  {}", stale.join("\n  "));
}

#[test]
fn the_manifest_reads_back_what_it_wrote() {
    let mut m = Manifest { compiler: "shaderc-sys 1.2.3".into(), options: "a, b".into(), ..Default::default() };
    m.sources.insert("common/trace.glsl".into(), 0x0123_4567_89ab_cdef);
    m.modules.insert("shadows.comp:rayquery".into(), u64::MAX);
    assert_eq!(Manifest::parse(&m.render()), Ok(m));
    assert!(Manifest::parse("glsl zz common/x.glsl").unwrap_err().contains("line 1"));
}

#[test]
fn edited_added_and_removed_files_are_named_as_stale() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = common::temp_dir("stale-spirv");
    let (glsl, spv) = (dir.join("shaders-glsl"), dir.join("shaders-spv"));
    common::copy_dir(&root.join("shaders-glsl"), &glsl);
    common::copy_dir(&root.join("shaders-spv"), &spv);
    let stale = || stale_spirv(&glsl, &spv).unwrap();
    assert_eq!(stale(), Vec::<String>::new(), "the committed SPIR-V is stale: run tools/compile-shaders.sh");

    // An include edited (one byte): named, once, as changed.
    let brdf = glsl.join("common/brdf.glsl");
    let mut text = std::fs::read_to_string(&brdf).unwrap();
    text.push('\n');
    std::fs::write(&brdf, &text).unwrap();
    let s = stale();
    assert!(s.len() == 1 && s[0].contains("common/brdf.glsl: changed"), "{s:?}");
    text.pop();
    std::fs::write(&brdf, &text).unwrap();
    assert!(stale().is_empty());

    // A new traced module: its file and both variants' missing SPIR-V.
    std::fs::write(
        glsl.join("example_new_pass.comp"),
        "#version 460\n#include \"common/trace.glsl\"\nvoid main() {}\n",
    )
    .unwrap();
    let s = stale();
    assert!(s.iter().any(|l| l.contains("example_new_pass.comp: new")), "{s:?}");
    assert!(s.iter().any(|l| l.contains("example_new_pass.comp:rayquery has no SPIR-V")), "{s:?}");
    assert!(s.iter().any(|l| l.contains("example_new_pass.comp:compute has no SPIR-V")), "{s:?}");
    std::fs::remove_file(glsl.join("example_new_pass.comp")).unwrap();

    // A removed module, and a SPIR-V file that differs from the manifest.
    std::fs::rename(glsl.join("taa.comp"), dir.join("taa.comp")).unwrap();
    let s = stale();
    assert!(s.iter().any(|l| l.contains("taa.comp: removed")), "{s:?}");
    assert!(s.iter().any(|l| l.contains("module taa.comp no longer exists")), "{s:?}");
    std::fs::rename(dir.join("taa.comp"), glsl.join("taa.comp")).unwrap();
    std::fs::write(spv.join("tonemap.comp.spv"), b"\x03\x02\x23\x07").unwrap();
    let s = stale();
    assert!(s.len() == 1 && s[0].contains("tonemap.comp.spv: differs"), "{s:?}");
    std::fs::remove_file(spv.join(MANIFEST)).unwrap();
    assert!(stale()[0].contains(MANIFEST));
    let _ = std::fs::remove_dir_all(&dir);
}
