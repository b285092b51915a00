//! The crate's layering, checked from the source: every `crate::` path (and every `super::`
//! path that climbs to the crate root) in src/ must point down the layer order written in
//! src/lib.rs, and `unsafe` code must stay in src/gpu. No GPU needed: this reads files.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The layers, top first; a module may use modules in later layers only. Must match the order
/// in src/lib.rs's header (and every module lib.rs declares must be here).
const LAYERS: &[&[&str]] = &[
    &["cli"],
    &["app"],
    &["bench"],
    &["capture"],
    &["render"],
    &["passes"],
    &["graph"],
    &["world"],
    &["accel"],
    &["backend"],
    &["scene", "metrics"],
    &["gpu", "image_io", "progress"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// Source with comments, string and char literals blanked out (lifetimes kept), so that only
/// code is searched.
fn strip_comments_and_literals(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r' && matches!(c.get(i + 1), Some('#') | Some('"')) && !ident_char_before(&c, i) {
            // Raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|k| c.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c[i] == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                // Past the backslash and the escaped character ('\'' included).
                let mut j = i + 3;
                while j < c.len() && c[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
                out.push_str("' '");
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
                out.push_str("' '");
            } else {
                out.push(c[i]);
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

fn ident_char_before(c: &[char], i: usize) -> bool {
    i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Open,
    Close,
    Comma,
    Other(char),
}

fn tokens(code: &str) -> Vec<Tok> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(c[start..i].iter().collect()));
            continue;
        }
        match ch {
            ':' if c.get(i + 1) == Some(&':') => {
                out.push(Tok::PathSep);
                i += 2;
                continue;
            }
            '{' => out.push(Tok::Open),
            '}' => out.push(Tok::Close),
            ',' => out.push(Tok::Comma),
            c if c.is_whitespace() => {}
            c => out.push(Tok::Other(c)),
        }
        i += 1;
    }
    out
}

/// Expands the path (or use tree) starting at `toks[i]` into its full paths:
/// `a::{b, c::d}` gives `a::b` and `a::c::d`. Returns the paths and the index after the tree.
fn use_tree(toks: &[Tok], mut i: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix = Vec::new();
    loop {
        match toks.get(i) {
            Some(Tok::Ident(name)) => {
                prefix.push(name.clone());
                i += 1;
                if toks.get(i) == Some(&Tok::PathSep) {
                    i += 1;
                } else {
                    return (vec![prefix], i);
                }
            }
            Some(Tok::Open) => {
                i += 1;
                let mut all = Vec::new();
                while !matches!(toks.get(i), Some(Tok::Close) | None) {
                    let (paths, next) = use_tree(toks, i);
                    all.extend(paths.into_iter().map(|p| [prefix.clone(), p].concat()));
                    // `*` (or anything else that names nothing further) is stepped over.
                    i = if next == i { i + 1 } else { next };
                    if toks.get(i) == Some(&Tok::Comma) {
                        i += 1;
                    }
                }
                return (all, i + 1);
            }
            // `*` (glob) or the end of the path.
            _ => return (vec![prefix], i),
        }
    }
}

/// Every path in `src` that names something from the crate root, as the segments after the
/// root: `crate::a::b` and, from a file `depth` modules deep, `super::...::a::b` with enough
/// `super`s to reach the root (inline `mod x { }` blocks add a level).
fn crate_paths(src: &str, depth: usize) -> Vec<Vec<String>> {
    let toks = tokens(&strip_comments_and_literals(src));
    let mut found = Vec::new();
    // Brace depths at which inline modules were opened.
    let mut inline_mods: Vec<usize> = Vec::new();
    let mut braces = 0usize;
    let mut i = 0;
    while i < toks.len() {
        let starts_path = i == 0 || toks[i - 1] != Tok::PathSep;
        match &toks[i] {
            Tok::Open => braces += 1,
            Tok::Close => {
                braces = braces.saturating_sub(1);
                if inline_mods.last() == Some(&braces) {
                    inline_mods.pop();
                }
            }
            Tok::Ident(k) if k == "mod" => {
                if let (Some(Tok::Ident(_)), Some(Tok::Open)) = (toks.get(i + 1), toks.get(i + 2)) {
                    inline_mods.push(braces);
                }
            }
            Tok::Ident(k) if k == "crate" && starts_path && toks.get(i + 1) == Some(&Tok::PathSep) => {
                let (paths, next) = use_tree(&toks, i + 2);
                found.extend(paths);
                i = next;
                continue;
            }
            Tok::Ident(k) if k == "super" && starts_path => {
                let mut j = i;
                let mut supers = 0;
                while toks.get(j) == Some(&Tok::Ident("super".into())) && toks.get(j + 1) == Some(&Tok::PathSep) {
                    supers += 1;
                    j += 2;
                }
                if supers > 0 && supers >= depth + inline_mods.len() {
                    let (paths, next) = use_tree(&toks, j);
                    found.extend(paths);
                    i = next;
                    continue;
                }
                i = j.max(i + 1);
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    found.retain(|p| !p.is_empty());
    found
}

/// The layering violations of one file of module `from` (a module of the crate root),
/// `depth` modules below the root.
fn violations(from: &str, depth: usize, src: &str) -> Vec<String> {
    let Some(from_layer) = layer_of(from) else {
        return vec![format!("module `{from}` is not in LAYERS (tests/layering.rs) nor in src/lib.rs's order")];
    };
    let mut out = Vec::new();
    for path in crate_paths(src, depth) {
        let to = path[0].as_str();
        if to == from || to == "self" {
            continue;
        }
        let Some(to_layer) = layer_of(to) else {
            out.push(format!("`crate::{}` names `{to}`, which is not a module in LAYERS", path.join("::")));
            continue;
        };
        if to_layer > from_layer {
            continue;
        }
        let shown = path.join("::");
        let how = if to_layer == from_layer { "sits in the same layer as" } else { "sits above" };
        out.push(format!("`{from}` uses `crate::{shown}`: `{to}` {how} `{from}`"));
    }
    out
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The crate-root module a file in src/ belongs to and how deep its own module is, or `None`
/// for the crate roots (lib.rs, main.rs).
fn module_of(rel: &Path) -> Option<(String, usize)> {
    let parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if parts.len() == 1 && (parts[0] == "lib.rs" || parts[0] == "main.rs") {
        return None;
    }
    let top = parts[0].trim_end_matches(".rs").to_string();
    let depth = if parts.last().is_some_and(|f| f == "mod.rs") { parts.len() - 1 } else { parts.len() };
    Some((top, depth))
}

#[test]
fn imports_point_down_the_layers() {
    let src = root().join("src");
    let files = rust_files(&src);
    assert!(files.len() > 50, "found only {} files under {}", files.len(), src.display());
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in &files {
        let rel = file.strip_prefix(&src).expect("under src");
        let Some((module, depth)) = module_of(rel) else { continue };
        let text = std::fs::read_to_string(file).expect("readable source");
        for v in violations(&module, depth, &text) {
            problems.push(format!("{}: {v}", rel.display()));
        }
        checked += 1;
    }
    assert!(problems.is_empty(), "{} layering problem(s) in {checked} files:\n{}", problems.len(), problems.join("\n"));
}

/// Every module src/lib.rs declares has a layer, every layer names a real module, and the
/// order lib.rs's header states is this test's.
#[test]
fn layers_list_every_module() {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).expect("src/lib.rs");
    let declared: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod ").or_else(|| l.trim().strip_prefix("mod ")))
        .map(|l| l.trim_end_matches(';').to_string())
        .collect();
    let listed: BTreeSet<String> = LAYERS.iter().flat_map(|l| l.iter().map(|m| m.to_string())).collect();
    assert_eq!(declared, listed, "src/lib.rs's modules against LAYERS");
    // The order written in lib.rs's header: one layer a line, modules before two spaces.
    let block: Vec<Vec<String>> = lib
        .lines()
        .skip_while(|l| !l.starts_with("//! ```text"))
        .skip(1)
        .take_while(|l| !l.starts_with("//! ```"))
        .map(|l| {
            let l = l.trim_start_matches("//!").trim();
            let names = l.split("  ").next().unwrap_or("");
            names.split(',').map(|m| m.trim().to_string()).collect()
        })
        .collect();
    let layers: Vec<Vec<String>> = LAYERS.iter().map(|l| l.iter().map(|m| m.to_string()).collect()).collect();
    assert_eq!(block, layers, "the order in src/lib.rs's header against LAYERS");
}

/// `unsafe` appears in code only under src/gpu: the compiler denies it in the library and the
/// binary (`#![deny(unsafe_code)]`, allowed on `mod gpu` alone), and this covers the crates
/// the lint does not reach (tests, benches, build script, fuzz targets).
#[test]
fn unsafe_only_in_gpu() {
    let root = root();
    let lib = std::fs::read_to_string(root.join("src/lib.rs")).expect("src/lib.rs");
    let main = std::fs::read_to_string(root.join("src/main.rs")).expect("src/main.rs");
    assert!(lib.contains("#![deny(unsafe_code)]") && main.contains("#![deny(unsafe_code)]"));
    assert!(lib.contains("#[allow(unsafe_code)]\npub mod gpu;"), "unsafe code is allowed on `mod gpu` only");
    let gpu = std::fs::read_to_string(root.join("src/gpu/mod.rs")).expect("src/gpu/mod.rs");
    assert!(
        gpu.contains("#![deny(clippy::undocumented_unsafe_blocks"),
        "src/gpu/mod.rs denies undocumented unsafe blocks"
    );
    let mut files = Vec::new();
    for dir in ["src", "tests", "benches", "fuzz/fuzz_targets"] {
        files.extend(rust_files(&root.join(dir)));
    }
    files.push(root.join("build.rs"));
    let mut found = Vec::new();
    for file in files {
        let rel = file.strip_prefix(&root).expect("under the root").to_path_buf();
        if rel.starts_with("src/gpu") {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&file) else { continue };
        let code = strip_comments_and_literals(&text);
        let allows = code.matches("allow(unsafe_code)").count();
        let unsafe_tokens = tokens(&code).iter().filter(|t| **t == Tok::Ident("unsafe".into())).count();
        if unsafe_tokens > 0 || (allows > 0 && rel != Path::new("src/lib.rs")) || allows > 1 {
            found.push(format!("{}: {unsafe_tokens} unsafe, {allows} allow(unsafe_code)", rel.display()));
        }
    }
    assert!(found.is_empty(), "unsafe code outside src/gpu:\n{}", found.join("\n"));
}

/// The checker itself finds what it must (so the tests above cannot pass by finding nothing).
#[test]
fn checker_finds_upward_paths() {
    let src = r#"
        //! crate::cli in a comment is not a use
        use crate::{gpu::Context, cli::progress};
        use super::super::app::Viewer;
        fn f() { let s = "crate::app"; crate::cli::main(); crate::render::frame(); let c = '{'; }
        mod tests { use super::super::super::cli::x; use super::super::sweep; }
    "#;
    let v = violations("bench", 2, src);
    assert_eq!(v.len(), 4, "{v:#?}");
    assert!(v[0].contains("crate::cli::progress"), "{v:#?}");
    assert!(v[1].contains("crate::app::Viewer"), "{v:#?}");
    assert!(v[2].contains("crate::cli::main"), "{v:#?}");
    assert!(v[3].contains("crate::cli::x"), "{v:#?}");
    // Downward and same-module paths pass.
    assert!(violations("render", 1, "use crate::{passes, gpu::vk, render::x}; use super::scene;").is_empty());
    assert!(violations("graph", 1, "use crate::world::SceneGpu;").is_empty());
    assert_eq!(violations("graph", 1, "use crate::render::Renderer;").len(), 1);
    assert_eq!(violations("scene", 1, "use crate::metrics::flip;").len(), 1, "same layer");
    assert_eq!(violations("newmod", 1, "").len(), 1, "unlisted module");
}
