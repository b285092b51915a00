//! glTF 2.0 loader: `.gltf` (external or `data:` URI buffers and images) and `.glb` files.
//!
//! Scene files are untrusted. The gltf crate's validation rejects files this renderer must
//! still load (the nvpro Cornell box has a texture whose image does not exist), so the JSON is
//! parsed without it and every index, byte range and count is checked here, before it is used
//! and before anything is allocated from it. Defects the scene can do without (a missing
//! texture, an orthographic camera) load with a warning; everything else is a [`SceneError`]
//! naming the file and the JSON path of the problem.
//!
//! This module holds what every stage shares: the entry points, the loading context (file,
//! options, warnings, limits) and the [`Builder`] that assembles the [`Scene`]. One module per
//! stage of a load, in the order they run: `container` (GLB or JSON, URIs and files),
//! `accessors` (buffers, views, typed reads), `images`, `materials` (textures, samplers),
//! `nodes` (hierarchy, instances, cameras, lights), `meshes` (primitives, attributes, morph
//! targets, tangents), `animation`.

mod accessors;
mod animation;
mod container;
mod images;
mod materials;
mod meshes;
mod nodes;
mod skins;
#[cfg(test)]
mod tests;

use super::limits::{Limits, check_limit};
use super::{Image, Scene, SceneError};
use accessors::{Data, load_buffers};
use container::{check_asset, parse_json, read_file, split_container, untyped_json};
use images::load_images;
use nodes::scene_nodes;
use std::cell::Cell;
use std::collections::HashSet;
use std::path::Path;

/// How to load a glTF file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Let URIs resolve to files outside the scene file's folder. Off by default so that a
    /// downloaded scene cannot make the renderer read arbitrary files.
    pub allow_outside_uris: bool,
    pub limits: Limits,
}

/// Extensions this loader implements. A file that requires any other is refused, because
/// drawing it without the extension would be wrong rather than merely less pretty.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "EXT_mesh_gpu_instancing",
];

/// Extensions the typed glTF JSON model drops; when a file uses one, the JSON is also kept
/// untyped to read them.
const UNTYPED_EXTENSIONS: &[&str] = &["KHR_texture_transform", "EXT_mesh_gpu_instancing"];

/// Loads a glTF 2.0 scene: the default scene (or scene 0, or every root node when the file
/// has no scenes), with its meshes, materials, textures, lights, cameras and animations.
pub fn load_gltf(path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let file = read_file(&Ctx::new(path, opts), path, "the scene file")?;
    load_gltf_bytes(&file, path, opts)
}

/// Loads a glTF or GLB file already in memory, as [`load_gltf`] would load it from `path`:
/// `path` names the file in messages and its folder is where relative URIs resolve. The
/// fuzzers feed mutated files through here without writing them to disk.
pub fn load_gltf_bytes(file: &[u8], path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let ctx = Ctx::new(path, opts);
    ctx.check("size of the scene file", "max_buffer_bytes", file.len() as u64, ctx.limits().max_buffer_bytes)?;
    let (json_bytes, bin) = split_container(&ctx, file)?;
    let root = parse_json(&ctx, json_bytes)?;
    check_asset(&ctx, &root)?;
    let untyped = untyped_json(&ctx, &root, json_bytes)?;
    let buffers = load_buffers(&ctx, &root, bin)?;
    let data = Data { root: &root, buffers: &buffers, untyped: untyped.as_ref() };
    let images = load_images(&ctx, &data)?;
    Builder::new(ctx, data, images).build()
}

// ---------------------------------------------------------------------------------------------
// Context: the file being loaded, options, warnings.

struct Ctx<'a> {
    file: &'a Path,
    opts: &'a LoadOptions,
    warnings: Vec<String>,
    /// Keys of warnings that are given once per scene rather than once per occurrence.
    warned: HashSet<&'static str>,
    /// Bytes loaded from URIs so far, for `max_total_bytes`.
    uri_bytes: Cell<u64>,
}

impl<'a> Ctx<'a> {
    fn new(file: &'a Path, opts: &'a LoadOptions) -> Self {
        Self { file, opts, warnings: Vec::new(), warned: HashSet::new(), uri_bytes: Cell::new(0) }
    }

    fn limits(&self) -> &Limits {
        &self.opts.limits
    }

    fn err(&self, problem: impl Into<String>) -> SceneError {
        SceneError::new(self.file, problem)
    }

    fn warn(&mut self, problem: impl Into<String>) {
        let problem = problem.into();
        log::warn!("{}: {problem}", self.file.display());
        self.warnings.push(problem);
    }

    fn warn_once(&mut self, key: &'static str, problem: impl Into<String>) {
        if self.warned.insert(key) {
            self.warn(problem);
        }
    }

    fn check(&self, what: &str, limit_name: &str, value: u64, limit: u64) -> Result<(), SceneError> {
        check_limit(self.file, what, limit_name, value, limit)
    }
}

/// A JSON array's name for messages, singular and plural.
#[derive(Clone, Copy)]
struct Kind {
    one: &'static str,
    many: &'static str,
}

const ACCESSORS: Kind = Kind::new("accessor", "accessors");
const BUFFER_VIEWS: Kind = Kind::new("bufferView", "bufferViews");
const BUFFERS: Kind = Kind::new("buffer", "buffers");
const MESHES: Kind = Kind::new("mesh", "meshes");
const MATERIALS: Kind = Kind::new("material", "materials");
const TEXTURES: Kind = Kind::new("texture", "textures");
const IMAGES: Kind = Kind::new("image", "images");
const SAMPLERS: Kind = Kind::new("sampler", "samplers");
const NODES: Kind = Kind::new("node", "nodes");
const SCENES: Kind = Kind::new("scene", "scenes");
const CAMERAS: Kind = Kind::new("camera", "cameras");
const LIGHTS: Kind = Kind::new("light", "lights");
const SKINS: Kind = Kind::new("skin", "skins");
const ANIMATION_SAMPLERS: Kind = Kind::new("sampler", "samplers in the animation");

impl Kind {
    const fn new(one: &'static str, many: &'static str) -> Self {
        Self { one, many }
    }
}

fn out_of_range(path: &str, index: usize, len: usize, kind: Kind) -> String {
    format!("{path}: {} {index} out of range ({len} {})", kind.one, kind.many)
}

/// `items[index]`, or an error naming the JSON path that held the bad index.
fn lookup<'r, T>(ctx: &Ctx, items: &'r [T], index: usize, kind: Kind, path: &str) -> Result<&'r T, SceneError> {
    items.get(index).ok_or_else(|| ctx.err(out_of_range(path, index, items.len(), kind)))
}

/// `items[index]`, or a warning (ending in `consequence`) and `None`.
fn lookup_or_warn<'r, T>(
    ctx: &mut Ctx,
    items: &'r [T],
    index: usize,
    kind: Kind,
    path: &str,
    consequence: &str,
) -> Option<&'r T> {
    let item = items.get(index);
    if item.is_none() {
        ctx.warn(format!("{}; {consequence}", out_of_range(path, index, items.len(), kind)));
    }
    item
}

fn to_usize(ctx: &Ctx, value: u64, what: &str) -> Result<usize, SceneError> {
    usize::try_from(value).map_err(|_| ctx.err(format!("{what}: {value} is too large")))
}

// ---------------------------------------------------------------------------------------------
// Scene assembly.

struct Builder<'a> {
    ctx: Ctx<'a>,
    data: Data<'a>,
    scene: Scene,
    /// `Scene::meshes` index of each glTF mesh's primitives, built on first use; `None` for
    /// primitives that are skipped.
    mesh_cache: Vec<Option<Vec<Option<u32>>>>,
    /// `Scene::nodes` index of each glTF node in the loaded scene.
    scene_node: Vec<Option<u32>>,
    default_material: Option<u32>,
    /// Per `Scene::morphs` entry: the glTF node whose `weights` (and weight animations) drive
    /// it, the first node that draws its mesh.
    morph_driver: Vec<Option<usize>>,
    total_vertices: u64,
    total_triangles: u64,
    total_animation_keys: u64,
    /// Joint influences of the primitives that have them, by `Scene::meshes` index.
    skin_influences: std::collections::HashMap<u32, skins::PrimitiveInfluences>,
    /// `Scene::skins` index of each glTF skin built so far.
    skin_cache: std::collections::HashMap<usize, u32>,
}

impl<'a> Builder<'a> {
    fn new(ctx: Ctx<'a>, data: Data<'a>, images: Vec<Image>) -> Self {
        let name = ctx.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let scene = Scene { name, source: Some(ctx.file.to_path_buf()), images, ..Scene::default() };
        Self {
            mesh_cache: vec![None; data.root.meshes.len()],
            scene_node: vec![None; data.root.nodes.len()],
            ctx,
            data,
            scene,
            default_material: None,
            morph_driver: Vec::new(),
            total_vertices: 0,
            total_triangles: 0,
            total_animation_keys: 0,
            skin_influences: Default::default(),
            skin_cache: Default::default(),
        }
    }

    fn build(mut self) -> Result<Scene, SceneError> {
        // Once per file, whatever uses them: the picture differs from what the author saw.
        for (i, ext) in self.data.root.extensions_used.iter().enumerate() {
            if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
                self.ctx.warn(format!("extensionsUsed[{i}]: {ext} is not supported; what it adds is ignored"));
            }
        }
        self.scene.textures = self.textures();
        self.scene.materials = self.materials();
        let order = scene_nodes(&mut self.ctx, self.data.root)?;
        self.add_nodes(&order)?;
        for &(gltf_node, _) in &order {
            self.attach(gltf_node)?;
        }
        self.animations()?;
        if self.scene.triangle_count() == 0 {
            return Err(self.ctx.err("the scene has no triangles to draw"));
        }
        self.scene.warnings = std::mem::take(&mut self.ctx.warnings);
        Ok(self.scene)
    }
}
