//! glTF 2.0 loader: `.gltf` (external or `data:` URI buffers and images) and `.glb` files.
//!
//! Scene files are untrusted. The gltf crate's validation rejects files this renderer must
//! still load (the nvpro Cornell box has a texture whose image does not exist), so the JSON is
//! parsed without it and every index, byte range and count is checked here, before it is used
//! and before anything is allocated from it. Defects the scene can do without (a missing
//! texture, an orthographic camera) load with a warning; everything else is a [`SceneError`]
//! naming the file and the JSON path of the problem.

use super::animation::{Channel, Interpolation, Property};
use super::limits::{Limits, check_limit};
use super::{
    AlphaMode, Animation, Camera, Filter, Image, Instance, Light, LightKind, Material, Mesh, Morph, MorphTarget, Node,
    Sampler, Scene, SceneError, Texture, TextureRef, Vertex, WeightChannel, Wrap, tangents, uv_transform,
};
use base64::Engine;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use serde_json::Value;
use std::borrow::Cow;
use std::cell::Cell;
use std::collections::HashSet;
use std::io::Cursor;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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
// Container: GLB or JSON.

const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_CHUNK_JSON: u32 = 0x4E4F_534A;
const GLB_CHUNK_BIN: u32 = 0x004E_4942;
const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// The JSON text and, for a GLB, its BIN chunk.
fn split_container<'f>(ctx: &Ctx, file: &'f [u8]) -> Result<(&'f [u8], Option<&'f [u8]>), SceneError> {
    if file.starts_with(GLB_MAGIC) {
        return parse_glb(ctx, file);
    }
    let text = file.strip_prefix(UTF8_BOM).unwrap_or(file);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok((text, None)),
        _ => Err(ctx.err("not a glTF file: it starts with neither '{' (glTF JSON) nor the GLB magic 'glTF'")),
    }
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let word = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(word.try_into().ok()?))
}

fn parse_glb<'f>(ctx: &Ctx, file: &'f [u8]) -> Result<(&'f [u8], Option<&'f [u8]>), SceneError> {
    let truncated = |detail: String| ctx.err(format!("truncated GLB file: {detail}"));
    let (Some(version), Some(length)) = (le_u32(file, 4), le_u32(file, 8)) else {
        return Err(truncated(format!("{} bytes, the GLB header needs 12", file.len())));
    };
    if version != 2 {
        return Err(ctx.err(format!("GLB version {version} is not supported (expected 2)")));
    }
    let length = length as usize;
    let Some(body) = file.get(12..length) else {
        return Err(truncated(format!("the header says {length} bytes, the file has {}", file.len())));
    };
    let mut json = None;
    let mut bin = None;
    let mut rest = body;
    while !rest.is_empty() {
        let (Some(chunk_len), Some(chunk_type)) = (le_u32(rest, 0), le_u32(rest, 4)) else {
            return Err(truncated(format!("a chunk header needs 8 bytes, {} remain", rest.len())));
        };
        let chunk_len = chunk_len as usize;
        let Some(chunk) = rest.get(8..8 + chunk_len) else {
            return Err(truncated(format!("a chunk of {chunk_len} bytes, {} remain", rest.len() - 8)));
        };
        match chunk_type {
            GLB_CHUNK_JSON if json.is_none() => json = Some(chunk),
            GLB_CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(chunk),
            // Unknown chunk types are to be ignored, per the GLB specification.
            _ => {}
        }
        rest = &rest[8 + chunk_len..];
    }
    let json = json.ok_or_else(|| ctx.err("GLB file without a JSON chunk"))?;
    Ok((json, bin))
}

fn parse_json(ctx: &Ctx, json_bytes: &[u8]) -> Result<json::Root, SceneError> {
    json::Root::from_slice(json_bytes).map_err(|e| ctx.err(format!("malformed glTF JSON: {e}")))
}

fn check_asset(ctx: &Ctx, root: &json::Root) -> Result<(), SceneError> {
    let version = &root.asset.version;
    if !version.starts_with("2.") {
        return Err(ctx.err(format!("asset.version: glTF {version} is not supported (expected 2.x)")));
    }
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(ctx.err(format!("extensionsRequired[{i}]: required extension {ext} is not supported")));
        }
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            log::debug!("{}: ignoring extension {ext}", ctx.file.display());
        }
    }
    Ok(())
}

fn untyped_json(ctx: &Ctx, root: &json::Root, json_bytes: &[u8]) -> Result<Option<Value>, SceneError> {
    if !root.extensions_used.iter().any(|e| UNTYPED_EXTENSIONS.contains(&e.as_str())) {
        return Ok(None);
    }
    serde_json::from_slice(json_bytes).map(Some).map_err(|e| ctx.err(format!("malformed glTF JSON: {e}")))
}

// ---------------------------------------------------------------------------------------------
// URIs and files.

/// Reads a file, refusing it if it is larger than `max_buffer_bytes`.
fn read_file(ctx: &Ctx, file: &Path, what: &str) -> Result<Vec<u8>, SceneError> {
    let cannot = |e: std::io::Error| ctx.err(format!("{what}: cannot read {}: {e}", file.display()));
    let len = std::fs::metadata(file).map_err(cannot)?.len();
    ctx.check(&format!("{what}: size of {}", file.display()), "max_buffer_bytes", len, ctx.limits().max_buffer_bytes)?;
    std::fs::read(file).map_err(cannot)
}

/// The bytes a buffer or image URI refers to.
fn load_uri(ctx: &Ctx, uri: &str, path: &str) -> Result<Vec<u8>, SceneError> {
    let bytes = match uri.strip_prefix("data:") {
        Some(data) => decode_data_uri(ctx, data, path)?,
        None => read_file(ctx, &resolve_uri(ctx, uri, path)?, path)?,
    };
    ctx.uri_bytes.set(ctx.uri_bytes.get() + bytes.len() as u64);
    let what = format!("{path}: bytes loaded from URIs so far");
    ctx.check(&what, "max_total_bytes", ctx.uri_bytes.get(), ctx.limits().max_total_bytes)?;
    Ok(bytes)
}

/// Accepts padded and unpadded base64: exporters differ.
const BASE64: base64::engine::GeneralPurpose = base64::engine::GeneralPurpose::new(
    &base64::alphabet::STANDARD,
    base64::engine::GeneralPurposeConfig::new()
        .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
);

/// Decodes the part of a `data:` URI after the scheme: `[<media type>];base64,<data>`.
fn decode_data_uri(ctx: &Ctx, data: &str, path: &str) -> Result<Vec<u8>, SceneError> {
    ctx.check(
        &format!("{path}: data URI length"),
        "max_data_uri_bytes",
        data.len() as u64,
        ctx.limits().max_data_uri_bytes,
    )?;
    let (header, payload) =
        data.split_once(',').ok_or_else(|| ctx.err(format!("{path}: malformed data URI (no ',')")))?;
    if !header.ends_with(";base64") {
        return Err(ctx.err(format!("{path}: only base64 data URIs are supported")));
    }
    BASE64.decode(payload).map_err(|e| ctx.err(format!("{path}: malformed base64 in data URI: {e}")))
}

/// The file a relative URI names, refused if it lies outside the scene's folder (after
/// resolving `..` and symbolic links) unless the options allow that.
fn resolve_uri(ctx: &Ctx, uri: &str, path: &str) -> Result<PathBuf, SceneError> {
    if has_scheme(uri) {
        return Err(
            ctx.err(format!("{path}: URI '{uri}' has a scheme; only relative file paths and data URIs are supported"))
        );
    }
    let decoded =
        percent_decode(uri).ok_or_else(|| ctx.err(format!("{path}: malformed percent-encoding in URI '{uri}'")))?;
    let relative = Path::new(&decoded);
    let dir = ctx.file.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let escapes =
        relative.is_absolute() || relative.components().any(|c| matches!(c, Component::Prefix(_) | Component::RootDir));
    if escapes && !ctx.opts.allow_outside_uris {
        return Err(outside_error(ctx, uri, path, dir));
    }
    let joined = dir.join(relative);
    let resolved =
        joined.canonicalize().map_err(|e| ctx.err(format!("{path}: cannot open '{}': {e}", joined.display())))?;
    if !ctx.opts.allow_outside_uris {
        let dir = dir
            .canonicalize()
            .map_err(|e| ctx.err(format!("cannot resolve the scene folder {}: {e}", dir.display())))?;
        if !resolved.starts_with(&dir) {
            return Err(outside_error(ctx, uri, path, &dir));
        }
    }
    Ok(resolved)
}

fn outside_error(ctx: &Ctx, uri: &str, path: &str, dir: &Path) -> SceneError {
    ctx.err(format!(
        "{path}: URI '{uri}' refers to a file outside the scene folder {}; \
         pass --allow-outside-uris to allow it",
        dir.display()
    ))
}

/// True for `scheme:...` URIs (RFC 3986: a letter, then letters, digits, '+', '-' or '.').
fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else {
        return false;
    };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
}

/// Decodes `%XX` escapes; `None` for a malformed escape or a result that is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        if b == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

// ---------------------------------------------------------------------------------------------
// Buffers and accessors.

/// The parsed file: typed JSON, untyped JSON where needed, and the bytes of every buffer.
struct Data<'a> {
    root: &'a json::Root,
    buffers: &'a [Cow<'a, [u8]>],
    untyped: Option<&'a Value>,
}

fn load_buffers<'f>(ctx: &Ctx, root: &json::Root, bin: Option<&'f [u8]>) -> Result<Vec<Cow<'f, [u8]>>, SceneError> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let path = format!("buffers[{i}]");
        let byte_length = buffer.byte_length.0;
        ctx.check(&format!("{path}.byteLength"), "max_buffer_bytes", byte_length, ctx.limits().max_buffer_bytes)?;
        let bytes: Cow<[u8]> = match (&buffer.uri, bin) {
            (Some(uri), _) => Cow::Owned(load_uri(ctx, uri, &format!("{path}.uri"))?),
            // Only the first buffer may refer to the GLB BIN chunk.
            (None, Some(bin)) if i == 0 => Cow::Borrowed(bin),
            (None, _) => {
                return Err(ctx.err(format!("{path}: no uri and no GLB BIN chunk to refer to")));
            }
        };
        if (bytes.len() as u64) < byte_length {
            return Err(
                ctx.err(format!("{path}: has {} bytes of data, less than its byteLength {byte_length}", bytes.len()))
            );
        }
        let byte_length = byte_length as usize;
        buffers.push(match bytes {
            Cow::Borrowed(b) => Cow::Borrowed(&b[..byte_length]),
            Cow::Owned(mut b) => {
                b.truncate(byte_length);
                Cow::Owned(b)
            }
        });
    }
    Ok(buffers)
}

/// The bytes of buffer view `index`, checked against its buffer.
fn view_bytes<'d>(ctx: &Ctx, data: &Data<'d>, index: usize, path: &str) -> Result<&'d [u8], SceneError> {
    let view = lookup(ctx, &data.root.buffer_views, index, BUFFER_VIEWS, path)?;
    let vpath = format!("bufferViews[{index}]");
    let buffer = lookup(ctx, data.buffers, view.buffer.value(), BUFFERS, &format!("{vpath}.buffer"))?;
    let start = view.byte_offset.map_or(0, |o| o.0);
    let len = view.byte_length.0;
    let range = start
        .checked_add(len)
        .filter(|&end| end <= buffer.len() as u64)
        .and_then(|end| Some(usize::try_from(start).ok()?..usize::try_from(end).ok()?));
    range.and_then(|r| buffer.get(r)).ok_or_else(|| {
        ctx.err(format!(
            "{vpath}: byteOffset {start} + byteLength {len} lies beyond the end of \
             buffer {} ({} bytes)",
            view.buffer.value(),
            buffer.len()
        ))
    })
}

/// How one accessor element is stored.
#[derive(Clone, Copy)]
struct Format {
    component: ComponentType,
    components: usize,
    normalized: bool,
}

impl Format {
    fn element_size(self) -> usize {
        self.component.size() * self.components
    }
}

/// Accessor elements in a buffer view: element `i` starts at `i * stride` in `bytes`.
struct Strided<'d> {
    bytes: &'d [u8],
    stride: usize,
    count: usize,
    format: Format,
}

impl<'d> Strided<'d> {
    fn element(&self, i: usize) -> Option<&'d [u8]> {
        let start = i.checked_mul(self.stride)?;
        self.bytes.get(start..start.checked_add(self.format.element_size())?)
    }
}

/// Where an accessor's (or sparse part's) elements lie.
struct Placement {
    view: usize,
    byte_offset: u64,
    count: u64,
    /// The view's byteStride applies to accessors, never to sparse indices and values.
    use_view_stride: bool,
}

fn strided<'d>(
    ctx: &Ctx,
    data: &Data<'d>,
    at: &Placement,
    format: Format,
    path: &str,
) -> Result<Strided<'d>, SceneError> {
    let bytes = view_bytes(ctx, data, at.view, &format!("{path}.bufferView"))?;
    let element = format.element_size() as u64;
    let view_stride = data.root.buffer_views.get(at.view).and_then(|v| v.byte_stride).map(|s| s.0 as u64);
    let stride = view_stride.filter(|_| at.use_view_stride).unwrap_or(element);
    if stride < element {
        return Err(ctx.err(format!(
            "{path}: bufferViews[{}].byteStride {stride} is less than the element size {element}",
            at.view
        )));
    }
    let needed = match at.count {
        0 => Some(at.byte_offset),
        n => stride.checked_mul(n - 1).and_then(|b| b.checked_add(element)).and_then(|b| b.checked_add(at.byte_offset)),
    };
    let fits = needed.filter(|&n| n <= bytes.len() as u64);
    let (Some(_), Ok(offset), Ok(count)) = (fits, usize::try_from(at.byte_offset), usize::try_from(at.count)) else {
        return Err(ctx.err(format!(
            "{path}: {} elements of {element} bytes (stride {stride}) from byteOffset {} \
             overrun bufferViews[{}] ({} bytes)",
            at.count,
            at.byte_offset,
            at.view,
            bytes.len()
        )));
    };
    Ok(Strided { bytes: &bytes[offset..], stride: stride as usize, count, format })
}

fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

fn accessor_format(ctx: &Ctx, acc: &json::Accessor, expected: Type, path: &str) -> Result<Format, SceneError> {
    let Checked::Valid(ty) = acc.type_ else {
        return Err(ctx.err(format!("{path}.type: invalid accessor type")));
    };
    if ty != expected {
        return Err(ctx.err(format!(
            "{path}: accessor type {} where {} is required",
            type_name(ty),
            type_name(expected)
        )));
    }
    let Checked::Valid(component) = acc.component_type else {
        return Err(ctx.err(format!("{path}.componentType: invalid component type")));
    };
    Ok(Format { component: component.0, components: ty.multiplicity(), normalized: acc.normalized })
}

/// The most elements one accessor may have: the name of the limit, and its value.
type ElementLimit = (&'static str, u64);

/// Reads accessor `index` (referenced from JSON path `path`), which must have type
/// `expected` and at most `limit` elements, decoding each element with `decode`; applies
/// sparse substitution.
fn read_accessor<T: Copy>(
    ctx: &Ctx,
    data: &Data,
    (index, expected): (usize, Type),
    path: &str,
    (limit_name, limit): ElementLimit,
    decode: impl Fn(Format, &[u8]) -> T,
) -> Result<Vec<T>, SceneError> {
    let acc = lookup(ctx, &data.root.accessors, index, ACCESSORS, path)?;
    let path = format!("{path} -> accessors[{index}]");
    let format = accessor_format(ctx, acc, expected, &path)?;
    ctx.check(&format!("{path}: element count"), limit_name, acc.count.0, limit)?;
    let mut out = match acc.buffer_view {
        Some(view) => {
            let at = Placement {
                view: view.value(),
                byte_offset: acc.byte_offset.map_or(0, |o| o.0),
                count: acc.count.0,
                use_view_stride: true,
            };
            let elements = strided(ctx, data, &at, format, &path)?;
            decode_all(ctx, &elements, &decode, &path)?
        }
        // All zeros (before sparse substitution); only the limit bounds the count.
        None => {
            let zeros = [0u8; 16];
            let zero = decode(format, zeros.get(..format.element_size()).unwrap_or(&zeros));
            vec![zero; to_usize(ctx, acc.count.0, &path)?]
        }
    };
    if let Some(sparse) = &acc.sparse {
        apply_sparse(ctx, data, sparse, format, &mut out, &decode, &path)?;
    }
    Ok(out)
}

fn decode_all<T>(
    ctx: &Ctx,
    elements: &Strided,
    decode: &impl Fn(Format, &[u8]) -> T,
    path: &str,
) -> Result<Vec<T>, SceneError> {
    let mut out = Vec::with_capacity(elements.count);
    for i in 0..elements.count {
        let bytes = elements.element(i).ok_or_else(|| ctx.err(format!("{path}: element {i} out of range")))?;
        out.push(decode(elements.format, bytes));
    }
    Ok(out)
}

fn apply_sparse<T>(
    ctx: &Ctx,
    data: &Data,
    sparse: &json::accessor::sparse::Sparse,
    format: Format,
    out: &mut [T],
    decode: &impl Fn(Format, &[u8]) -> T,
    path: &str,
) -> Result<(), SceneError> {
    let count = sparse.count.0;
    if count > out.len() as u64 {
        return Err(ctx.err(format!("{path}.sparse.count: {count} exceeds the accessor's count {}", out.len())));
    }
    let Checked::Valid(index_type) = sparse.indices.component_type else {
        return Err(ctx.err(format!("{path}.sparse.indices.componentType: invalid component type")));
    };
    let index_format = Format { component: index_type.0, components: 1, normalized: false };
    let indices_at = Placement {
        view: sparse.indices.buffer_view.value(),
        byte_offset: sparse.indices.byte_offset.0,
        count,
        use_view_stride: false,
    };
    let values_at = Placement {
        view: sparse.values.buffer_view.value(),
        byte_offset: sparse.values.byte_offset.0,
        count,
        use_view_stride: false,
    };
    let indices = strided(ctx, data, &indices_at, index_format, &format!("{path}.sparse.indices"))?;
    let values = strided(ctx, data, &values_at, format, &format!("{path}.sparse.values"))?;
    let len = out.len();
    for k in 0..indices.count {
        let (Some(i), Some(v)) = (indices.element(k), values.element(k)) else {
            return Err(ctx.err(format!("{path}.sparse: element {k} out of range")));
        };
        let target = decode_u32(index_format, i) as usize;
        let slot = out.get_mut(target).ok_or_else(|| {
            ctx.err(format!("{path}.sparse.indices[{k}]: index {target} out of range ({len} elements)"))
        })?;
        *slot = decode(format, v);
    }
    Ok(())
}

fn le_bytes<const K: usize>(bytes: &[u8]) -> [u8; K] {
    bytes.try_into().unwrap_or([0; K])
}

/// Component `c` of an element as a float, normalised integers mapped to [0, 1] or [-1, 1].
fn component_f32(format: Format, bytes: &[u8], c: usize) -> f32 {
    let size = format.component.size();
    let b = bytes.get(c * size..(c + 1) * size).unwrap_or(&[]);
    let n = format.normalized;
    match format.component {
        ComponentType::F32 => f32::from_le_bytes(le_bytes(b)),
        ComponentType::I8 => {
            let v = f32::from(i8::from_le_bytes(le_bytes(b)));
            if n { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U8 => {
            let v = f32::from(u8::from_le_bytes(le_bytes(b)));
            if n { v / 255.0 } else { v }
        }
        ComponentType::I16 => {
            let v = f32::from(i16::from_le_bytes(le_bytes(b)));
            if n { (v / 32767.0).max(-1.0) } else { v }
        }
        ComponentType::U16 => {
            let v = f32::from(u16::from_le_bytes(le_bytes(b)));
            if n { v / 65535.0 } else { v }
        }
        ComponentType::U32 => {
            let v = u32::from_le_bytes(le_bytes(b)) as f32;
            if n { v / u32::MAX as f32 } else { v }
        }
    }
}

fn decode_f32<const N: usize>(format: Format, bytes: &[u8]) -> [f32; N] {
    std::array::from_fn(|c| component_f32(format, bytes, c))
}

/// An unsigned integer element (indices); other component types read as 0, and callers
/// check the type first.
fn decode_u32(format: Format, bytes: &[u8]) -> u32 {
    match format.component {
        ComponentType::U8 => u32::from(u8::from_le_bytes(le_bytes(bytes))),
        ComponentType::U16 => u32::from(u16::from_le_bytes(le_bytes(bytes))),
        ComponentType::U32 => u32::from_le_bytes(le_bytes(bytes)),
        _ => 0,
    }
}

fn expected_type<const N: usize>() -> Type {
    match N {
        1 => Type::Scalar,
        2 => Type::Vec2,
        3 => Type::Vec3,
        _ => Type::Vec4,
    }
}

/// Reads an accessor of N-component vectors (N = 1 to 4) as floats. `max_vertices` caps
/// every such accessor, vertex attribute or not: it is the scene's largest per-element count.
fn read_floats<const N: usize>(ctx: &Ctx, data: &Data, index: usize, path: &str) -> Result<Vec<[f32; N]>, SceneError> {
    let limit = ("max_vertices", ctx.limits().max_vertices);
    let accessor = (index, expected_type::<N>());
    read_accessor(ctx, data, accessor, path, limit, decode_f32::<N>)
}

fn read_indices(ctx: &Ctx, data: &Data, index: usize, path: &str) -> Result<Vec<u32>, SceneError> {
    let acc = lookup(ctx, &data.root.accessors, index, ACCESSORS, path)?;
    let unsigned = matches!(
        acc.component_type,
        Checked::Valid(json::accessor::GenericComponentType(
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        ))
    );
    if !unsigned {
        return Err(ctx.err(format!(
            "{path} -> accessors[{index}].componentType: \
             indices must be unsigned bytes, shorts or ints"
        )));
    }
    // A strip of n + 2 indices makes n triangles.
    let max_indices = ctx.limits().max_triangles.saturating_mul(3).saturating_add(2);
    let limit = ("3 * max_triangles + 2", max_indices);
    read_accessor(ctx, data, (index, Type::Scalar), path, limit, decode_u32)
}

// ---------------------------------------------------------------------------------------------
// Images.

/// An image's encoded bytes, ready to decode.
struct Encoded<'d> {
    name: String,
    bytes: Cow<'d, [u8]>,
    mime: Option<&'d str>,
}

fn load_images(ctx: &Ctx, data: &Data) -> Result<Vec<Image>, SceneError> {
    let mut encoded = Vec::with_capacity(data.root.images.len());
    let mut total_texels = 0u64;
    for (i, image) in data.root.images.iter().enumerate() {
        let item = encoded_image(ctx, data, i, image)?;
        total_texels += check_image_size(ctx, &item, i)?;
        ctx.check(
            "texels over all images",
            "max_texture_pixels_total",
            total_texels,
            ctx.limits().max_texture_pixels_total,
        )?;
        encoded.push(item);
    }
    let decoded = decode_in_parallel(&encoded, ctx.limits());
    encoded
        .into_iter()
        .zip(decoded)
        .enumerate()
        .map(|(i, (item, result))| {
            let (width, height, rgba8) =
                result.map_err(|e| ctx.err(format!("images[{i}] ('{}'): cannot decode: {e}", item.name)))?;
            Ok(Image { name: item.name, width, height, rgba8 })
        })
        .collect()
}

fn encoded_image<'d>(ctx: &Ctx, data: &Data<'d>, i: usize, image: &'d json::Image) -> Result<Encoded<'d>, SceneError> {
    let path = format!("images[{i}]");
    let bytes = match (&image.uri, image.buffer_view) {
        (Some(uri), _) => Cow::Owned(load_uri(ctx, uri, &format!("{path}.uri"))?),
        (None, Some(view)) => Cow::Borrowed(view_bytes(ctx, data, view.value(), &format!("{path}.bufferView"))?),
        (None, None) => return Err(ctx.err(format!("{path}: neither uri nor bufferView"))),
    };
    let uri_name = image.uri.as_deref().filter(|u| !u.starts_with("data:"));
    let name = image.name.as_deref().or(uri_name).map_or_else(|| path.clone(), str::to_owned);
    Ok(Encoded { name, bytes, mime: image.mime_type.as_ref().map(|m| m.0.as_str()) })
}

/// A reader for a PNG or JPEG image, identified by its content and, failing that, its MIME type.
fn image_reader<'b>(item: &'b Encoded) -> Result<image::ImageReader<Cursor<&'b [u8]>>, String> {
    let mut reader =
        image::ImageReader::new(Cursor::new(&item.bytes[..])).with_guessed_format().map_err(|e| e.to_string())?;
    let from_mime = item.mime.and_then(image::ImageFormat::from_mime_type);
    if let (None, Some(format)) = (reader.format(), from_mime) {
        reader.set_format(format);
    }
    match reader.format() {
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => Ok(reader),
        Some(other) => Err(format!("{other:?} images are not supported (only PNG and JPEG)")),
        None => Err("not a PNG or JPEG image".into()),
    }
}

/// Checks an image's dimensions (read from its header) against the limits; returns its texels.
fn check_image_size(ctx: &Ctx, item: &Encoded, i: usize) -> Result<u64, SceneError> {
    let cannot = |e: String| ctx.err(format!("images[{i}] ('{}'): cannot decode: {e}", item.name));
    let (w, h) = image_reader(item).and_then(|r| r.into_dimensions().map_err(|e| e.to_string())).map_err(cannot)?;
    let max = u64::from(ctx.limits().max_texture_dimension);
    let what = format!("images[{i}] ('{}'): size {w}x{h}", item.name);
    ctx.check(&what, "max_texture_dimension", u64::from(w.max(h)), max)?;
    Ok(u64::from(w) * u64::from(h))
}

type Decoded = Result<(u32, u32, Vec<u8>), String>;

fn decode_rgba8(item: &Encoded, limits: &Limits) -> Decoded {
    let mut reader = image_reader(item)?;
    let mut decoder_limits = image::Limits::default();
    decoder_limits.max_image_width = Some(limits.max_texture_dimension);
    decoder_limits.max_image_height = Some(limits.max_texture_dimension);
    // 16-bit RGBA is the largest decoded layout: 8 bytes per texel.
    let max_dim = u64::from(limits.max_texture_dimension);
    decoder_limits.max_alloc = Some(max_dim * max_dim * 8);
    reader.limits(decoder_limits);
    let rgba = reader.decode().map_err(|e| e.to_string())?.into_rgba8();
    Ok((rgba.width(), rgba.height(), rgba.into_raw()))
}

/// Decodes all images on all cores (decoding dominates load time for textured scenes).
/// A panicking decoder is reported as that image's error rather than taking the process down.
fn decode_in_parallel(items: &[Encoded], limits: &Limits) -> Vec<Decoded> {
    let next = AtomicUsize::new(0);
    let worker = || {
        let mut done = Vec::new();
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(item) = items.get(i) else {
                break;
            };
            let decode = std::panic::AssertUnwindSafe(|| decode_rgba8(item, limits));
            let result = std::panic::catch_unwind(decode).unwrap_or_else(|_| Err("the image decoder panicked".into()));
            done.push((i, result));
        }
        done
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(items.len());
    let mut results: Vec<Option<Decoded>> = (0..items.len()).map(|_| None).collect();
    std::thread::scope(|s| {
        let helpers: Vec<_> =
            (1..threads).filter_map(|_| std::thread::Builder::new().spawn_scoped(s, worker).ok()).collect();
        // This thread decodes too, so failing to spawn helpers only costs speed.
        let mut done = worker();
        for helper in helpers {
            done.extend(helper.join().unwrap_or_default());
        }
        for (i, result) in done {
            if let Some(slot) = results.get_mut(i) {
                *slot = Some(result);
            }
        }
    });
    results.into_iter().map(|r| r.unwrap_or_else(|| Err("the image was not decoded".into()))).collect()
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
        }
    }

    fn build(mut self) -> Result<Scene, SceneError> {
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

// ---------------------------------------------------------------------------------------------
// Node hierarchy.

/// The glTF nodes of the scene to load, parents before children, each with its glTF parent.
fn scene_nodes(ctx: &mut Ctx, root: &json::Root) -> Result<Vec<(usize, Option<usize>)>, SceneError> {
    ctx.check("node count", "max_nodes", root.nodes.len() as u64, u64::from(ctx.limits().max_nodes))?;
    let parents = node_parents(ctx, root)?;
    check_acyclic(ctx, root, &parents)?;
    let roots = scene_roots(ctx, root, &parents)?;
    walk_depth_first(ctx, root, &roots, &parents)
}

fn children(root: &json::Root, node: usize) -> impl DoubleEndedIterator<Item = usize> + '_ {
    let children = root.nodes.get(node).and_then(|n| n.children.as_deref()).unwrap_or_default();
    children.iter().map(|c| c.value())
}

/// Each node's parent; a node listed as the child of two nodes (or twice) is an error, since
/// the hierarchy must be a forest.
fn node_parents(ctx: &Ctx, root: &json::Root) -> Result<Vec<Option<usize>>, SceneError> {
    let mut parents = vec![None; root.nodes.len()];
    for p in 0..root.nodes.len() {
        for (k, c) in children(root, p).enumerate() {
            let path = format!("nodes[{p}].children[{k}]");
            let parent = lookup(ctx, &parents, c, NODES, &path)?;
            if c == p {
                return Err(ctx.err(format!("{path}: node {p} is its own child (a node cycle)")));
            }
            if let Some(q) = parent {
                return Err(ctx.err(format!("{path}: nodes[{c}] has two parents, nodes[{q}] and nodes[{p}]")));
            }
            if let Some(slot) = parents.get_mut(c) {
                *slot = Some(p);
            }
        }
    }
    Ok(parents)
}

/// With at most one parent per node, every node not reachable from a parentless node lies on
/// a cycle or below one.
fn check_acyclic(ctx: &Ctx, root: &json::Root, parents: &[Option<usize>]) -> Result<(), SceneError> {
    let mut reached = vec![false; parents.len()];
    let mut stack: Vec<usize> = parentless(parents).collect();
    while let Some(i) = stack.pop() {
        if let Some(r) = reached.get_mut(i) {
            *r = true;
        }
        stack.extend(children(root, i));
    }
    let Some(start) = reached.iter().position(|r| !r) else {
        return Ok(());
    };
    // Walking up as many steps as there are nodes is sure to end on the cycle itself.
    let mut node = start;
    for _ in 0..parents.len() {
        node = parents.get(node).copied().flatten().unwrap_or(node);
    }
    Err(ctx.err(format!("nodes[{node}]: node cycle (the node is its own ancestor)")))
}

fn parentless(parents: &[Option<usize>]) -> impl Iterator<Item = usize> + '_ {
    parents.iter().enumerate().filter(|(_, p)| p.is_none()).map(|(i, _)| i)
}

/// The root nodes of the default scene, else of scene 0, else every parentless node.
fn scene_roots(ctx: &mut Ctx, root: &json::Root, parents: &[Option<usize>]) -> Result<Vec<usize>, SceneError> {
    let scene = match root.scene {
        Some(s) => Some((s.value(), lookup(ctx, &root.scenes, s.value(), SCENES, "scene")?)),
        None => root.scenes.first().map(|s| (0, s)),
    };
    let Some((s, scene)) = scene else {
        return Ok(parentless(parents).collect());
    };
    let mut listed = vec![false; parents.len()];
    let mut roots = Vec::with_capacity(scene.nodes.len());
    for (k, node) in scene.nodes.iter().enumerate() {
        let (i, path) = (node.value(), format!("scenes[{s}].nodes[{k}]"));
        if let Some(p) = lookup(ctx, parents, i, NODES, &path)? {
            return Err(ctx.err(format!("{path}: node {i} is not a root node (it is a child of nodes[{p}])")));
        }
        if listed.get_mut(i).is_some_and(|seen| std::mem::replace(seen, true)) {
            ctx.warn(format!("{path}: node {i} is listed twice; it is loaded once"));
            continue;
        }
        roots.push(i);
    }
    Ok(roots)
}

/// Pre-order traversal, so that parents precede their children.
fn walk_depth_first(
    ctx: &Ctx,
    root: &json::Root,
    roots: &[usize],
    parents: &[Option<usize>],
) -> Result<Vec<(usize, Option<usize>)>, SceneError> {
    let max_depth = u64::from(ctx.limits().max_node_depth);
    let mut order = Vec::new();
    let mut stack: Vec<(usize, u64)> = roots.iter().rev().map(|&r| (r, 1)).collect();
    while let Some((i, depth)) = stack.pop() {
        ctx.check(&format!("nodes[{i}]: hierarchy depth"), "max_node_depth", depth, max_depth)?;
        order.push((i, parents.get(i).copied().flatten()));
        stack.extend(children(root, i).rev().map(|c| (c, depth + 1)));
    }
    Ok(order)
}

/// Translation, rotation and scale of a node matrix. A matrix that scales an axis to zero has
/// no defined rotation; identity stands in.
fn decompose(m: Mat4) -> (Vec3, Quat, Vec3) {
    let (scale, rotation, translation) = m.to_scale_rotation_translation();
    (translation, if rotation.is_finite() { rotation } else { Quat::IDENTITY }, scale)
}

/// The unit quaternion of an xyzw array; `None` for a zero quaternion.
fn unit_quat(q: [f32; 4]) -> Option<Quat> {
    let q = Quat::from_array(q);
    (q.length_squared() > 0.0).then(|| q.normalize())
}

// ---------------------------------------------------------------------------------------------
// Textures and materials.

impl Builder<'_> {
    fn textures(&mut self) -> Vec<Texture> {
        let root = self.data.root;
        let mut textures = Vec::with_capacity(root.textures.len());
        for (i, texture) in root.textures.iter().enumerate() {
            let image = self.texture_image(i, texture);
            let sampler = self.texture_sampler(i, texture);
            textures.push(Texture { image, sampler });
        }
        textures
    }

    fn texture_image(&mut self, i: usize, texture: &json::Texture) -> Option<u32> {
        let source = texture.source.value();
        // With allow_empty_texture, the gltf crate marks an absent source with u32::MAX.
        if source == u32::MAX as usize {
            self.ctx.warn(format!("textures[{i}]: no source image; the texture samples as white"));
            return None;
        }
        let path = format!("textures[{i}].source");
        let consequence = "the texture samples as white";
        lookup_or_warn(&mut self.ctx, &self.scene.images, source, IMAGES, &path, consequence)?;
        Some(source as u32)
    }

    fn texture_sampler(&mut self, i: usize, texture: &json::Texture) -> Sampler {
        let root = self.data.root;
        let Some(index) = texture.sampler else {
            return Sampler::default();
        };
        let path = format!("textures[{i}].sampler");
        let consequence = "using the default sampler";
        match lookup_or_warn(&mut self.ctx, &root.samplers, index.value(), SAMPLERS, &path, consequence) {
            Some(sampler) => convert_sampler(sampler),
            None => Sampler::default(),
        }
    }

    fn materials(&mut self) -> Vec<Material> {
        let root = self.data.root;
        let materials: Vec<Material> = root.materials.iter().enumerate().map(|(i, m)| self.material(i, m)).collect();
        self.warn_blend(&materials);
        materials
    }

    fn material(&mut self, i: usize, m: &json::Material) -> Material {
        let pbr = &m.pbr_metallic_roughness;
        let info = |t: &json::texture::Info| (t.index.value(), t.tex_coord);
        let strength = m.extensions.as_ref().and_then(|e| e.emissive_strength.as_ref());
        let strength = strength.map_or(1.0, |s| s.emissive_strength.0);
        Material {
            name: m.name.clone().unwrap_or_else(|| format!("material{i}")),
            base_color_factor: Vec4::from(pbr.base_color_factor.0),
            base_color_texture: self.texture_ref(
                i,
                "pbrMetallicRoughness/baseColorTexture",
                pbr.base_color_texture.as_ref().map(info),
            ),
            metallic_factor: pbr.metallic_factor.0,
            roughness_factor: pbr.roughness_factor.0,
            metallic_roughness_texture: self.texture_ref(
                i,
                "pbrMetallicRoughness/metallicRoughnessTexture",
                pbr.metallic_roughness_texture.as_ref().map(info),
            ),
            normal_texture: self.texture_ref(
                i,
                "normalTexture",
                m.normal_texture.as_ref().map(|t| (t.index.value(), t.tex_coord)),
            ),
            normal_scale: m.normal_texture.as_ref().map_or(1.0, |t| t.scale),
            occlusion_texture: self.texture_ref(
                i,
                "occlusionTexture",
                m.occlusion_texture.as_ref().map(|t| (t.index.value(), t.tex_coord)),
            ),
            occlusion_strength: m.occlusion_texture.as_ref().map_or(1.0, |t| t.strength.0),
            emissive_factor: Vec3::from(m.emissive_factor.0) * strength,
            emissive_texture: self.texture_ref(i, "emissiveTexture", m.emissive_texture.as_ref().map(info)),
            alpha_mode: self.alpha_mode(i, m),
            double_sided: m.double_sided,
        }
    }

    /// The texture slot at JSON pointer `slot` (relative to the material), given its texture
    /// index and texCoord, with KHR_texture_transform applied.
    fn texture_ref(&mut self, material: usize, slot: &str, info: Option<(usize, u32)>) -> Option<TextureRef> {
        let (index, tex_coord) = info?;
        let path = format!("materials[{material}].{}", slot.replace('/', "."));
        let consequence = "the slot is left empty";
        lookup_or_warn(&mut self.ctx, &self.scene.textures, index, TEXTURES, &format!("{path}.index"), consequence)?;
        let pointer = format!("/materials/{material}/{slot}/extensions/KHR_texture_transform");
        let transform = self.data.untyped.and_then(|json| json.pointer(&pointer));
        let (matrix, tex_coord_override) = transform.map_or((Mat3::IDENTITY, None), texture_transform);
        let mut uv_set = tex_coord_override.unwrap_or(tex_coord);
        if uv_set > 1 {
            self.ctx.warn(format!("{path}: TEXCOORD_{uv_set} is not loaded (only sets 0 and 1); using TEXCOORD_0"));
            uv_set = 0;
        }
        Some(TextureRef { texture: index as u32, uv_set, transform: matrix })
    }

    fn alpha_mode(&mut self, i: usize, m: &json::Material) -> AlphaMode {
        match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Opaque) => AlphaMode::Opaque,
            Checked::Valid(json::material::AlphaMode::Mask) => {
                AlphaMode::Mask { cutoff: m.alpha_cutoff.map_or(0.5, |c| c.0) }
            }
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            Checked::Invalid => {
                self.ctx.warn(format!("materials[{i}].alphaMode: invalid value; using OPAQUE"));
                AlphaMode::Opaque
            }
        }
    }

    /// One warning per scene: the renderer has no sorted transparency.
    fn warn_blend(&mut self, materials: &[Material]) {
        let mut blended = materials.iter().enumerate().filter(|(_, m)| m.alpha_mode == AlphaMode::Blend);
        if let Some((first, m)) = blended.next() {
            let count = 1 + blended.count();
            self.ctx.warn(format!(
                "{count} material(s) use alphaMode BLEND (first: materials[{first}] '{}'); \
                 blending is drawn as alpha-masked at cutoff 0.5",
                m.name
            ));
        }
    }
}

/// KHR_texture_transform as a matrix, and its texCoord override.
fn texture_transform(t: &Value) -> (Mat3, Option<u32>) {
    let offset = json_vec2(t.get("offset")).unwrap_or(Vec2::ZERO);
    let rotation = t.get("rotation").and_then(Value::as_f64).unwrap_or(0.0) as f32;
    let scale = json_vec2(t.get("scale")).unwrap_or(Vec2::ONE);
    let tex_coord = t.get("texCoord").and_then(Value::as_u64).map(|c| u32::try_from(c).unwrap_or(u32::MAX));
    (uv_transform(offset, rotation, scale), tex_coord)
}

fn json_vec2(value: Option<&Value>) -> Option<Vec2> {
    match value?.as_array()?.as_slice() {
        [x, y] => Some(Vec2::new(x.as_f64()? as f32, y.as_f64()? as f32)),
        _ => None,
    }
}

fn convert_sampler(s: &json::texture::Sampler) -> Sampler {
    use json::texture::{MagFilter, MinFilter};
    let mag_filter = match s.mag_filter {
        Some(Checked::Valid(MagFilter::Nearest)) => Filter::Nearest,
        _ => Filter::Linear,
    };
    let (min_filter, mipmaps) = match s.min_filter {
        Some(Checked::Valid(MinFilter::Nearest)) => (Filter::Nearest, false),
        Some(Checked::Valid(MinFilter::Linear)) => (Filter::Linear, false),
        Some(Checked::Valid(MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear)) => {
            (Filter::Nearest, true)
        }
        _ => (Filter::Linear, true),
    };
    Sampler { mag_filter, min_filter, mipmaps, wrap_s: convert_wrap(s.wrap_s), wrap_t: convert_wrap(s.wrap_t) }
}

fn convert_wrap(wrap: Checked<json::texture::WrappingMode>) -> Wrap {
    use json::texture::WrappingMode;
    match wrap {
        Checked::Valid(WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
        Checked::Valid(WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    }
}

// ---------------------------------------------------------------------------------------------
// Nodes, instances, cameras and lights.

impl Builder<'_> {
    fn add_nodes(&mut self, order: &[(usize, Option<usize>)]) -> Result<(), SceneError> {
        let root = self.data.root;
        for &(i, parent) in order {
            let node = lookup(&self.ctx, &root.nodes, i, NODES, "scene")?;
            let (translation, rotation, scale) = self.node_transform(i, node)?;
            let parent = parent.and_then(|p| self.scene_node.get(p).copied().flatten());
            if let Some(slot) = self.scene_node.get_mut(i) {
                *slot = Some(self.scene.nodes.len() as u32);
            }
            let name = node.name.clone().unwrap_or_default();
            self.scene.nodes.push(Node { name, parent, translation, rotation, scale });
        }
        Ok(())
    }

    fn node_transform(&mut self, i: usize, node: &json::Node) -> Result<(Vec3, Quat, Vec3), SceneError> {
        let (translation, rotation, scale) = match node.matrix {
            Some(m) => decompose(Mat4::from_cols_array(&m)),
            None => (
                node.translation.map_or(Vec3::ZERO, Vec3::from),
                node.rotation.map_or(Quat::IDENTITY, |q| Quat::from_array(q.0)),
                node.scale.map_or(Vec3::ONE, Vec3::from),
            ),
        };
        if !(translation.is_finite() && rotation.is_finite() && scale.is_finite()) {
            return Err(self.ctx.err(format!("nodes[{i}]: transform is not finite")));
        }
        let rotation = unit_quat(rotation.to_array()).unwrap_or_else(|| {
            self.ctx.warn(format!("nodes[{i}].rotation: zero quaternion; using identity"));
            Quat::IDENTITY
        });
        Ok((translation, rotation, scale))
    }

    /// Attaches a node's mesh instances, camera and light.
    fn attach(&mut self, i: usize) -> Result<(), SceneError> {
        let root = self.data.root;
        let (Some(node), Some(scene_index)) = (root.nodes.get(i), self.scene_node.get(i).copied().flatten()) else {
            return Ok(());
        };
        let path = format!("nodes[{i}]");
        if let Some(skin) = node.skin {
            lookup(&self.ctx, &root.skins, skin.value(), SKINS, &format!("{path}.skin"))?;
            self.ctx.warn_once("skin", "skins are not supported: skinned meshes are drawn in their bind pose");
        }
        if let Some(mesh) = node.mesh {
            self.attach_mesh(i, node, mesh.value(), scene_index)?;
        }
        if let Some(camera) = node.camera {
            self.attach_camera(&path, camera.value(), scene_index);
        }
        if let Some(light) = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()) {
            self.attach_light(&path, light.light.value(), scene_index);
        }
        Ok(())
    }

    fn attach_mesh(&mut self, i: usize, node: &json::Node, mesh: usize, scene_index: u32) -> Result<(), SceneError> {
        let primitives = self.mesh(mesh, &format!("nodes[{i}].mesh"))?;
        let targets = self.gpu_instances(i, node, scene_index)?.unwrap_or_else(|| vec![scene_index]);
        let drawn = primitives.iter().flatten().count() as u64;
        let instances = (self.scene.instances.len() as u64).saturating_add(drawn.saturating_mul(targets.len() as u64));
        let limit = self.ctx.limits().max_instances;
        self.ctx.check(
            &format!("nodes[{i}]: mesh instances in the scene so far"),
            "max_instances",
            instances,
            limit,
        )?;
        for &node in &targets {
            for &mesh in primitives.iter().flatten() {
                self.scene.instances.push(Instance { mesh, node });
            }
        }
        self.drive_morphs(i, node, &primitives);
        Ok(())
    }

    /// Makes glTF node `i` the driver of its meshes' morphs that have none yet: its `weights`
    /// replace the mesh's, and weight animations of the node play on them. A deforming mesh
    /// has one shape per frame, so other nodes drawing it show the driver's shape.
    fn drive_morphs(&mut self, i: usize, node: &json::Node, primitives: &[Option<u32>]) {
        for &mesh in primitives.iter().flatten() {
            let Some(k) = self.scene.morphs.iter().position(|m| m.mesh == mesh) else {
                continue;
            };
            match self.morph_driver[k] {
                None => {
                    self.morph_driver[k] = Some(i);
                    if let Some(weights) = &node.weights {
                        let count = self.scene.morphs[k].targets.len();
                        let path = format!("nodes[{i}].weights");
                        self.scene.morphs[k].weights = self.fit_weights(weights, count, &path);
                    }
                }
                Some(driver) if driver != i => self.ctx.warn_once(
                    "morph-shared",
                    "a morphing mesh drawn by several nodes takes the shape of the first node's weights in all",
                ),
                Some(_) => {}
            }
        }
    }

    /// `weights` for `count` targets: a list of another length is replaced by zeros (with a
    /// warning), non-finite weights by 0.
    fn fit_weights(&mut self, weights: &[f32], count: usize, path: &str) -> Vec<f32> {
        if weights.len() != count {
            self.ctx.warn(format!("{path}: {} weights for {count} morph targets; using 0", weights.len()));
            return vec![0.0; count];
        }
        weights.iter().map(|w| if w.is_finite() { *w } else { 0.0 }).collect()
    }

    /// EXT_mesh_gpu_instancing: one child node per instance, so the instances share the
    /// node's meshes and follow its animation. `None` when the node is not instanced.
    fn gpu_instances(&mut self, i: usize, node: &json::Node, parent: u32) -> Result<Option<Vec<u32>>, SceneError> {
        let pointer = format!("/nodes/{i}/extensions/EXT_mesh_gpu_instancing/attributes");
        let Some(attributes) = self.data.untyped.and_then(|json| json.pointer(&pointer)) else {
            return Ok(None);
        };
        let path = format!("nodes[{i}].extensions.EXT_mesh_gpu_instancing.attributes");
        let translations = self.instance_attribute::<3>(attributes, "TRANSLATION", &path)?;
        let rotations = self.instance_attribute::<4>(attributes, "ROTATION", &path)?;
        let scales = self.instance_attribute::<3>(attributes, "SCALE", &path)?;
        let counts =
            [translations.as_ref().map(Vec::len), rotations.as_ref().map(Vec::len), scales.as_ref().map(Vec::len)];
        let Some(count) = counts.iter().flatten().copied().max() else {
            self.ctx.warn(format!("{path}: no TRANSLATION, ROTATION or SCALE; the mesh is drawn once"));
            return Ok(None);
        };
        if counts.iter().flatten().any(|&c| c != count) {
            return Err(self.ctx.err(format!("{path}: the attribute accessors differ in count")));
        }
        let nodes = (self.scene.nodes.len() + count) as u64;
        self.ctx.check(
            &format!("{path}: node count with instances"),
            "max_nodes",
            nodes,
            u64::from(self.ctx.limits().max_nodes),
        )?;
        let name = node.name.clone().unwrap_or_default();
        let mut ids = Vec::with_capacity(count);
        for k in 0..count {
            let t = translations.as_ref().and_then(|v| v.get(k)).map_or(Vec3::ZERO, |&t| Vec3::from(t));
            let r = rotations.as_ref().and_then(|v| v.get(k)).map_or(Some(Quat::IDENTITY), |&r| unit_quat(r));
            let s = scales.as_ref().and_then(|v| v.get(k)).map_or(Vec3::ONE, |&s| Vec3::from(s));
            let Some(r) = r.filter(|r| r.is_finite() && t.is_finite() && s.is_finite()) else {
                return Err(self.ctx.err(format!("{path}: instance {k} has a non-finite or zero-rotation transform")));
            };
            ids.push(self.scene.nodes.len() as u32);
            let node =
                Node { name: format!("{name}#{k}"), parent: Some(parent), translation: t, rotation: r, scale: s };
            self.scene.nodes.push(node);
        }
        Ok(Some(ids))
    }

    fn instance_attribute<const N: usize>(
        &self,
        attributes: &Value,
        name: &str,
        path: &str,
    ) -> Result<Option<Vec<[f32; N]>>, SceneError> {
        let Some(value) = attributes.get(name) else {
            return Ok(None);
        };
        let path = format!("{path}.{name}");
        let index = value.as_u64().and_then(|i| usize::try_from(i).ok());
        let index = index.ok_or_else(|| self.ctx.err(format!("{path}: not an accessor index")))?;
        read_floats::<N>(&self.ctx, &self.data, index, &path).map(Some)
    }

    fn attach_camera(&mut self, path: &str, index: usize, node: u32) {
        let root = self.data.root;
        let path = format!("{path}.camera");
        let Some(camera) = lookup_or_warn(&mut self.ctx, &root.cameras, index, CAMERAS, &path, "the camera is skipped")
        else {
            return;
        };
        let perspective =
            camera.perspective.as_ref().filter(|p| p.yfov > 0.0 && p.yfov < std::f32::consts::PI && p.znear > 0.0);
        match (camera.type_, perspective) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p)) => self.scene.cameras.push(Camera {
                name: camera.name.clone().unwrap_or_default(),
                yfov: p.yfov,
                aspect_ratio: p.aspect_ratio,
                znear: p.znear,
                zfar: p.zfar,
                node,
            }),
            (Checked::Valid(json::camera::Type::Orthographic), _) => {
                self.ctx.warn(format!(
                    "cameras[{index}]: orthographic cameras are not supported; \
                     the camera is skipped"
                ));
            }
            _ => self.ctx.warn(format!("cameras[{index}]: not a valid perspective camera; the camera is skipped")),
        }
    }

    fn attach_light(&mut self, path: &str, index: usize, node: u32) {
        use json::extensions::scene::khr_lights_punctual::Type;
        let root = self.data.root;
        let lights = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let lights = lights.map_or(&[][..], |l| &l.lights[..]);
        let path = format!("{path}.extensions.KHR_lights_punctual.light");
        let Some(light) = lookup_or_warn(&mut self.ctx, lights, index, LIGHTS, &path, "the light is skipped") else {
            return;
        };
        let kind = match light.type_ {
            Checked::Valid(Type::Directional) => LightKind::Directional,
            Checked::Valid(Type::Point) => LightKind::Point,
            Checked::Valid(Type::Spot) => LightKind::Spot {
                inner_cone: light.spot.as_ref().map_or(0.0, |s| s.inner_cone_angle),
                outer_cone: light.spot.as_ref().map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle),
            },
            Checked::Invalid => {
                self.ctx.warn(format!("lights[{index}].type: invalid light type; the light is skipped"));
                return;
            }
        };
        self.scene.lights.push(Light {
            name: light.name.clone().unwrap_or_default(),
            kind,
            color: Vec3::from(light.color),
            intensity: light.intensity,
            range: light.range,
            radius: light_radius(light.extras.as_deref()),
            node,
        });
    }
}

/// `extras.radius` of a light, 0 when absent or not a finite non-negative number.
fn light_radius(extras: Option<&serde_json::value::RawValue>) -> f32 {
    let extras: Option<Value> = extras.and_then(|raw| serde_json::from_str(raw.get()).ok());
    let radius = extras.and_then(|e| e.get("radius")?.as_f64()).map_or(0.0, |r| r as f32);
    if radius.is_finite() { radius.max(0.0) } else { 0.0 }
}

// ---------------------------------------------------------------------------------------------
// Meshes.

impl Builder<'_> {
    /// The `Scene::meshes` indices of a glTF mesh's primitives, built on first use so that
    /// every node referring to the mesh shares them.
    fn mesh(&mut self, index: usize, path: &str) -> Result<Vec<Option<u32>>, SceneError> {
        let root = self.data.root;
        let mesh = lookup(&self.ctx, &root.meshes, index, MESHES, path)?;
        if let Some(Some(built)) = self.mesh_cache.get(index) {
            return Ok(built.clone());
        }
        let mut built = Vec::with_capacity(mesh.primitives.len());
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let path = format!("meshes[{index}].primitives[{p}]");
            let name = match &mesh.name {
                Some(name) if mesh.primitives.len() > 1 => format!("{name}#{p}"),
                Some(name) => name.clone(),
                None => path.clone(),
            };
            let id = match self.primitive(primitive, &path, name)? {
                Some((m, targets)) => {
                    self.scene.meshes.push(m);
                    let id = (self.scene.meshes.len() - 1) as u32;
                    if !targets.is_empty() {
                        let weights = match &mesh.weights {
                            Some(w) => self.fit_weights(w, targets.len(), &format!("meshes[{index}].weights")),
                            None => vec![0.0; targets.len()],
                        };
                        self.scene.morphs.push(Morph { mesh: id, targets, weights, channels: Vec::new() });
                        self.morph_driver.push(None);
                    }
                    Some(id)
                }
                None => None,
            };
            built.push(id);
        }
        if let Some(slot) = self.mesh_cache.get_mut(index) {
            *slot = Some(built.clone());
        }
        Ok(built)
    }

    /// One primitive as a mesh, with its morph targets (empty when it has none); `None` (with
    /// a warning) for primitives that draw no triangles.
    fn primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        path: &str,
        name: String,
    ) -> Result<Option<(Mesh, Vec<MorphTarget>)>, SceneError> {
        use json::mesh::Semantic;
        let Some(mode) = self.triangle_mode(prim, path) else {
            return Ok(None);
        };
        let Some(position) = prim.attributes.get(&Checked::Valid(Semantic::Positions)) else {
            self.ctx.warn(format!("{path}: no POSITION attribute; the primitive is skipped"));
            return Ok(None);
        };
        let mut vertices = self.positions(position.value(), path)?;
        let present = self.vertex_attributes(prim, path, &mut vertices)?;
        let Some(mut indices) = self.triangles(prim, mode, vertices.len(), path)? else {
            return Ok(None);
        };
        let mut targets = self.morph_targets(prim, path, vertices.len())?;
        let material = self.primitive_material(prim, path);
        let file_vertices = vertices.len();
        self.shading_frame(&mut vertices, &mut indices, present, material, path)?;
        if !targets.is_empty() && vertices.len() != file_vertices {
            // Generated flat normals or tangent seams split vertices; the deltas no longer
            // line up with them.
            self.ctx.warn(format!(
                "{path}: morph targets on a primitive without NORMAL, or whose tangents are generated \
                 with seams, are not supported; the mesh is drawn in its base shape"
            ));
            targets.clear();
        }
        let (mut bounds_min, mut bounds_max) = bounds(&vertices);
        // The bounds cover the targets at any weights in [0, 1] (framing and culling use
        // them); weights outside that range can leave them.
        for t in &targets {
            let (lo, hi) = t.positions.iter().fold((Vec3::ZERO, Vec3::ZERO), |(lo, hi), d| (lo.min(*d), hi.max(*d)));
            (bounds_min, bounds_max) = (bounds_min + lo, bounds_max + hi);
        }
        Ok(Some((Mesh { name, vertices, indices, material, bounds_min, bounds_max }, targets)))
    }

    /// The primitive's morph targets: POSITION and NORMAL deltas, one per vertex. TANGENT
    /// deltas are ignored (with a warning): tangents keep their base direction.
    fn morph_targets(
        &mut self,
        prim: &json::mesh::Primitive,
        path: &str,
        vertex_count: usize,
    ) -> Result<Vec<MorphTarget>, SceneError> {
        let Some(targets) = prim.targets.as_ref() else {
            return Ok(Vec::new());
        };
        let mut out = Vec::with_capacity(targets.len().min(64));
        for (k, target) in targets.iter().enumerate() {
            let path = format!("{path}.targets[{k}]");
            if target.tangents.is_some() {
                self.ctx.warn_once("morph-tangents", "morph target TANGENT deltas are ignored");
            }
            let positions = self.morph_deltas(target.positions.map(|a| a.value()), &path, "POSITION", vertex_count)?;
            let normals = self.morph_deltas(target.normals.map(|a| a.value()), &path, "NORMAL", vertex_count)?;
            out.push(MorphTarget { positions, normals });
        }
        Ok(out)
    }

    /// One attribute's deltas (empty when absent); they count towards `max_vertices`, which
    /// bounds their memory like the vertices'. Non-finite deltas become 0 with a warning.
    fn morph_deltas(
        &mut self,
        accessor: Option<usize>,
        path: &str,
        name: &str,
        vertex_count: usize,
    ) -> Result<Vec<Vec3>, SceneError> {
        let Some(accessor) = accessor else {
            return Ok(Vec::new());
        };
        let path = format!("{path}.{name}");
        let deltas = read_floats::<3>(&self.ctx, &self.data, accessor, &path)?;
        if deltas.len() != vertex_count {
            return Err(self.ctx.err(format!("{path}: {} deltas, but POSITION has {vertex_count}", deltas.len())));
        }
        self.count_vertices(vertex_count as u64, 0, &path)?;
        let mut repaired = false;
        let deltas = deltas
            .into_iter()
            .map(|d| {
                let d = Vec3::from(d);
                repaired |= !d.is_finite();
                if d.is_finite() { d } else { Vec3::ZERO }
            })
            .collect();
        if repaired {
            self.ctx.warn(format!("{path}: non-finite deltas replaced by 0"));
        }
        Ok(deltas)
    }

    /// Fills in NORMAL, TANGENT, TEXCOORD_0 and TEXCOORD_1 where the primitive has them.
    fn vertex_attributes(
        &mut self,
        prim: &json::mesh::Primitive,
        path: &str,
        vertices: &mut [Vertex],
    ) -> Result<Present, SceneError> {
        use json::mesh::Semantic;
        let n = vertices.len();
        let normals = self.attribute::<3>(prim, Semantic::Normals, path, n)?;
        let tangents = self.attribute::<4>(prim, Semantic::Tangents, path, n)?;
        let uv0 = self.attribute::<2>(prim, Semantic::TexCoords(0), path, n)?;
        let uv1 = self.attribute::<2>(prim, Semantic::TexCoords(1), path, n)?;
        let present =
            Present { normals: normals.is_some(), tangents: tangents.is_some(), uv: [uv0.is_some(), uv1.is_some()] };
        for (v, normal) in vertices.iter_mut().zip(normals.into_iter().flatten()) {
            v.normal = normal;
        }
        for (v, tangent) in vertices.iter_mut().zip(tangents.into_iter().flatten()) {
            v.tangent = tangent;
        }
        for (v, uv) in vertices.iter_mut().zip(uv0.into_iter().flatten()) {
            v.uv0 = uv;
        }
        for (v, uv) in vertices.iter_mut().zip(uv1.into_iter().flatten()) {
            v.uv1 = uv;
        }
        Ok(present)
    }

    /// Unit normals and tangents for every vertex: the file's, else generated (flat normals
    /// as glTF prescribes, tangents as `generate_tangents` decides). May add vertices.
    fn shading_frame(
        &mut self,
        vertices: &mut Vec<Vertex>,
        indices: &mut Vec<u32>,
        present: Present,
        material: u32,
        path: &str,
    ) -> Result<(), SceneError> {
        if present.normals {
            tangents::normalize_normals(vertices);
        } else {
            self.count_vertices(indices.len() as u64, vertices.len() as u64, path)?;
            tangents::flat_normals(vertices, indices);
        }
        let before = vertices.len();
        if present.tangents {
            tangents::normalize_tangents(vertices);
        } else {
            self.generate_tangents(vertices, indices, material, present.uv, path);
        }
        self.count_vertices(vertices.len() as u64, before as u64, path)
    }

    fn triangle_mode(&mut self, prim: &json::mesh::Primitive, path: &str) -> Option<json::mesh::Mode> {
        use json::mesh::Mode;
        match prim.mode {
            Checked::Valid(mode @ (Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)) => Some(mode),
            Checked::Valid(mode) => {
                self.ctx
                    .warn(format!("{path}: mode {mode:?} (points or lines) is not drawn; the primitive is skipped"));
                None
            }
            Checked::Invalid => {
                self.ctx.warn(format!("{path}.mode: invalid primitive mode; the primitive is skipped"));
                None
            }
        }
    }

    /// Vertices with positions set; positions must be finite.
    fn positions(&mut self, accessor: usize, path: &str) -> Result<Vec<Vertex>, SceneError> {
        let apath = format!("{path}.attributes.POSITION");
        let positions = read_floats::<3>(&self.ctx, &self.data, accessor, &apath)?;
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(self.ctx.err(format!("{apath}: vertex {i} is not finite (NaN or Inf)")));
        }
        if u32::try_from(positions.len()).is_err() {
            return Err(self.ctx.err(format!("{apath}: too many vertices")));
        }
        self.count_vertices(positions.len() as u64, 0, path)?;
        Ok(positions.into_iter().map(|position| Vertex { position, ..Vertex::default() }).collect())
    }

    /// Adds `added - removed` vertices to the scene total and checks the limit.
    fn count_vertices(&mut self, added: u64, removed: u64, path: &str) -> Result<(), SceneError> {
        self.total_vertices = (self.total_vertices + added).saturating_sub(removed);
        let limit = self.ctx.limits().max_vertices;
        self.ctx.check(&format!("{path}: vertices in the scene so far"), "max_vertices", self.total_vertices, limit)
    }

    /// A vertex attribute other than POSITION, if present; it must have one element per
    /// vertex. Non-finite values become 0 with a warning: they would poison shading.
    fn attribute<const N: usize>(
        &mut self,
        prim: &json::mesh::Primitive,
        semantic: json::mesh::Semantic,
        path: &str,
        vertex_count: usize,
    ) -> Result<Option<Vec<[f32; N]>>, SceneError> {
        let Some(index) = prim.attributes.get(&Checked::Valid(semantic.clone())) else {
            return Ok(None);
        };
        let path = format!("{path}.attributes.{}", semantic.to_string());
        let mut values = read_floats::<N>(&self.ctx, &self.data, index.value(), &path)?;
        if values.len() != vertex_count {
            return Err(self.ctx.err(format!("{path}: {} elements, but POSITION has {vertex_count}", values.len())));
        }
        let mut repaired = false;
        for c in values.iter_mut().flatten().filter(|c| !c.is_finite()) {
            *c = 0.0;
            repaired = true;
        }
        if repaired {
            self.ctx.warn(format!("{path}: non-finite values replaced by 0"));
        }
        Ok(Some(values))
    }

    /// The primitive's triangle list; `None` (with a warning) when it has no triangles.
    fn triangles(
        &mut self,
        prim: &json::mesh::Primitive,
        mode: json::mesh::Mode,
        vertex_count: usize,
        path: &str,
    ) -> Result<Option<Vec<u32>>, SceneError> {
        use json::mesh::Mode;
        let indices = match prim.indices {
            Some(index) => read_indices(&self.ctx, &self.data, index.value(), &format!("{path}.indices"))?,
            // `positions` checked that the vertex count fits in u32.
            None => (0..vertex_count as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(self
                .ctx
                .err(format!("{path}.indices: index value {bad} out of range ({vertex_count} vertices)")));
        }
        let len = indices.len();
        let count = if mode == Mode::Triangles { len / 3 } else { len.saturating_sub(2) };
        self.total_triangles += count as u64;
        let limit = self.ctx.limits().max_triangles;
        self.ctx.check(
            &format!("{path}: triangles in the scene so far"),
            "max_triangles",
            self.total_triangles,
            limit,
        )?;
        if mode == Mode::Triangles && len % 3 != 0 {
            self.ctx.warn(format!("{path}: {len} indices is not a multiple of 3; the last {} are ignored", len % 3));
        }
        if count == 0 {
            self.ctx.warn(format!("{path}: no triangles; the primitive is skipped"));
            return Ok(None);
        }
        Ok(Some(triangle_list(mode, indices)))
    }

    fn primitive_material(&mut self, prim: &json::mesh::Primitive, path: &str) -> u32 {
        if let Some(material) = prim.material {
            let path = format!("{path}.material");
            let consequence = "using the default material";
            if lookup_or_warn(&mut self.ctx, &self.scene.materials, material.value(), MATERIALS, &path, consequence)
                .is_some()
            {
                return material.value() as u32;
            }
        }
        self.default_material()
    }

    /// The material appended for primitives without one, added on first use.
    fn default_material(&mut self) -> u32 {
        *self.default_material.get_or_insert_with(|| {
            self.scene.materials.push(Material::default());
            (self.scene.materials.len() - 1) as u32
        })
    }

    /// MikkTSpace tangents where the material has a normal texture (and the UVs it reads);
    /// otherwise an arbitrary frame, since nothing reads the tangent's direction.
    fn generate_tangents(
        &mut self,
        vertices: &mut Vec<Vertex>,
        indices: &mut [u32],
        material: u32,
        has_uv: [bool; 2],
        path: &str,
    ) {
        let normal_map = self.scene.materials.get(material as usize).and_then(|m| m.normal_texture);
        let Some(uv_set) = normal_map.map(|t| t.uv_set) else {
            tangents::orthonormal_tangents(vertices);
            return;
        };
        if !has_uv.get(uv_set as usize).copied().unwrap_or(false) {
            self.ctx.warn(format!(
                "{path}: the normal texture reads TEXCOORD_{uv_set}, which the primitive \
                 lacks; using an arbitrary tangent frame"
            ));
            tangents::orthonormal_tangents(vertices);
        } else if !tangents::mikktspace_is_tractable(vertices, indices) {
            self.ctx.warn(format!(
                "{path}: too many triangle corners share a position for MikkTSpace to finish in \
                 reasonable time; using an arbitrary tangent frame"
            ));
            tangents::orthonormal_tangents(vertices);
        } else if !tangents::mikktspace_tangents(vertices, indices, uv_set) {
            self.ctx.warn(format!("{path}: MikkTSpace tangent generation failed; using an arbitrary tangent frame"));
            tangents::orthonormal_tangents(vertices);
        }
    }
}

/// Which optional vertex attributes a primitive has.
#[derive(Clone, Copy)]
struct Present {
    normals: bool,
    tangents: bool,
    uv: [bool; 2],
}

/// Strips and fans as triangle lists, winding preserved (glTF spec, section 3.7.2.1).
fn triangle_list(mode: json::mesh::Mode, mut indices: Vec<u32>) -> Vec<u32> {
    use json::mesh::Mode;
    match mode {
        Mode::TriangleStrip => indices
            .windows(3)
            .enumerate()
            .flat_map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[0], w[2], w[1]] })
            .collect(),
        Mode::TriangleFan => match indices.split_first() {
            Some((&first, rest)) => rest.windows(2).flat_map(|w| [w[0], w[1], first]).collect(),
            None => Vec::new(),
        },
        _ => {
            indices.truncate(indices.len() - indices.len() % 3);
            indices
        }
    }
}

fn bounds(vertices: &[Vertex]) -> (Vec3, Vec3) {
    let init = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    vertices.iter().fold(init, |(lo, hi), v| {
        let p = Vec3::from(v.position);
        (lo.min(p), hi.max(p))
    })
}

// ---------------------------------------------------------------------------------------------
// Animations.

impl Builder<'_> {
    fn animations(&mut self) -> Result<(), SceneError> {
        let root = self.data.root;
        for (a, animation) in root.animations.iter().enumerate() {
            let mut channels = Vec::with_capacity(animation.channels.len());
            let mut weights = Vec::new();
            for (c, channel) in animation.channels.iter().enumerate() {
                let path = format!("animations[{a}].channels[{c}]");
                if channel.target.path == Checked::Valid(json::animation::Property::MorphTargetWeights) {
                    weights.extend(self.weight_channel(a, animation, channel, &path)?);
                } else if let Some(channel) = self.channel(a, animation, channel, &path)? {
                    channels.push(channel);
                }
            }
            // Weights loop with the whole animation, as its node channels do.
            let period = weights
                .iter()
                .map(|(_, w): &(Vec<usize>, WeightChannel)| w.times.last().copied().unwrap_or(0.0))
                .fold(channels.iter().map(Channel::duration).fold(0.0, f32::max), f32::max);
            for (morphs, mut channel) in weights {
                channel.period = period;
                for k in morphs {
                    self.scene.morphs[k].channels.push(channel.clone());
                }
            }
            if !channels.is_empty() {
                let name = animation.name.clone().unwrap_or_else(|| format!("animation{a}"));
                self.scene.animations.push(Animation { name, channels });
            }
        }
        Ok(())
    }

    /// One channel; `None` for channels this renderer cannot play (with a warning) or that
    /// target nodes outside the loaded scene.
    fn channel(
        &mut self,
        a: usize,
        animation: &json::Animation,
        channel: &json::animation::Channel,
        path: &str,
    ) -> Result<Option<Channel>, SceneError> {
        use json::animation::Property as P;
        let root = self.data.root;
        let s = channel.sampler.value();
        let sampler = lookup(&self.ctx, &animation.samplers, s, ANIMATION_SAMPLERS, &format!("{path}.sampler"))?;
        let target = channel.target.node.value();
        lookup(&self.ctx, &root.nodes, target, NODES, &format!("{path}.target.node"))?;
        let property = match channel.target.path {
            Checked::Valid(P::Translation) => Property::Translation,
            Checked::Valid(P::Rotation) => Property::Rotation,
            Checked::Valid(P::Scale) => Property::Scale,
            // Played by `weight_channel`.
            Checked::Valid(P::MorphTargetWeights) => return Ok(None),
            Checked::Invalid => {
                self.ctx.warn(format!("{path}.target.path: invalid; the channel is skipped"));
                return Ok(None);
            }
        };
        let Some(node) = self.scene_node.get(target).copied().flatten() else {
            log::debug!("{}: {path} animates a node outside the scene", self.ctx.file.display());
            return Ok(None);
        };
        let Some(interpolation) = self.interpolation(a, s, sampler) else {
            return Ok(None);
        };
        let spath = format!("animations[{a}].samplers[{s}]");
        let times = self.key_times(sampler, &spath)?;
        let output = sampler.output.value();
        let opath = format!("{spath}.output");
        let values: Vec<Vec4> = match property {
            Property::Rotation => {
                read_floats::<4>(&self.ctx, &self.data, output, &opath)?.into_iter().map(Vec4::from).collect()
            }
            Property::Translation | Property::Scale => read_floats::<3>(&self.ctx, &self.data, output, &opath)?
                .into_iter()
                .map(|v| Vec3::from(v).extend(0.0))
                .collect(),
        };
        self.count_animation_keys(values.len(), &spath)?;
        let channel = Channel { node, property, interpolation, times, values };
        match channel_defect(&channel) {
            Some(defect) => {
                self.ctx.warn(format!("{spath}: {defect}; the channel is skipped"));
                Ok(None)
            }
            None => Ok(Some(channel)),
        }
    }
}

impl Builder<'_> {
    /// A sampler's interpolation; `None` (with a warning) when invalid.
    fn interpolation(&mut self, a: usize, s: usize, sampler: &json::animation::Sampler) -> Option<Interpolation> {
        match sampler.interpolation {
            Checked::Valid(json::animation::Interpolation::Step) => Some(Interpolation::Step),
            Checked::Valid(json::animation::Interpolation::Linear) => Some(Interpolation::Linear),
            Checked::Valid(json::animation::Interpolation::CubicSpline) => Some(Interpolation::CubicSpline),
            Checked::Invalid => {
                self.ctx.warn(format!("animations[{a}].samplers[{s}].interpolation: invalid; the channel is skipped"));
                None
            }
        }
    }

    fn key_times(&mut self, sampler: &json::animation::Sampler, spath: &str) -> Result<Vec<f32>, SceneError> {
        let times = read_floats::<1>(&self.ctx, &self.data, sampler.input.value(), &format!("{spath}.input"))?;
        let times: Vec<f32> = times.into_iter().map(|[t]| t).collect();
        self.count_animation_keys(times.len(), spath)?;
        Ok(times)
    }

    /// A channel that animates morph target weights: the morphs it drives (those whose
    /// driver is the target node) and their weights; `None` when there are none or the
    /// channel cannot be played (with a warning).
    fn weight_channel(
        &mut self,
        a: usize,
        animation: &json::Animation,
        channel: &json::animation::Channel,
        path: &str,
    ) -> Result<Option<(Vec<usize>, WeightChannel)>, SceneError> {
        let root = self.data.root;
        let s = channel.sampler.value();
        let sampler = lookup(&self.ctx, &animation.samplers, s, ANIMATION_SAMPLERS, &format!("{path}.sampler"))?;
        let target = channel.target.node.value();
        lookup(&self.ctx, &root.nodes, target, NODES, &format!("{path}.target.node"))?;
        let morphs: Vec<usize> =
            (0..self.morph_driver.len()).filter(|&k| self.morph_driver[k] == Some(target)).collect();
        let Some(&first) = morphs.first() else {
            if self.scene_node.get(target).copied().flatten().is_some() {
                self.ctx
                    .warn(format!("{path}: node {target} draws no morph targets of its own; the channel is skipped"));
            }
            return Ok(None);
        };
        let Some(interpolation) = self.interpolation(a, s, sampler) else {
            return Ok(None);
        };
        let spath = format!("animations[{a}].samplers[{s}]");
        let times = self.key_times(sampler, &spath)?;
        let values = read_floats::<1>(&self.ctx, &self.data, sampler.output.value(), &format!("{spath}.output"))?;
        let values: Vec<f32> = values.into_iter().map(|[v]| v).collect();
        self.count_animation_keys(values.len(), &spath)?;
        let per_key =
            self.scene.morphs[first].targets.len() * if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let defect = key_times_defect(&times).or_else(|| {
            if values.len() != times.len() * per_key {
                Some(format!("{} output values for {} keys of {per_key} weights", values.len(), times.len()))
            } else if !values.iter().all(|v| v.is_finite()) {
                Some("output values are not finite".into())
            } else {
                None
            }
        });
        if let Some(defect) = defect {
            self.ctx.warn(format!("{spath}: {defect}; the channel is skipped"));
            return Ok(None);
        }
        Ok(Some((morphs, WeightChannel { interpolation, times, values, period: 0.0 })))
    }

    /// Adds keyframe times or values to the scene total and checks the limit.
    fn count_animation_keys(&mut self, added: usize, path: &str) -> Result<(), SceneError> {
        self.total_animation_keys += added as u64;
        let limit = self.ctx.limits().max_animation_keys;
        let what = format!("{path}: animation keys in the scene so far");
        self.ctx.check(&what, "max_animation_keys", self.total_animation_keys, limit)
    }
}

/// Why key times cannot be played, if they cannot.
fn key_times_defect(times: &[f32]) -> Option<String> {
    if times.is_empty() {
        return Some("no keyframes".into());
    }
    if !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[0] > w[1]) {
        return Some("key times are not finite and ascending".into());
    }
    None
}

/// Why a channel cannot be played, if it cannot.
fn channel_defect(channel: &Channel) -> Option<String> {
    let keys = channel.times.len();
    let per_key = if channel.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    if let Some(defect) = key_times_defect(&channel.times) {
        return Some(defect);
    }
    if channel.values.len() != keys * per_key {
        return Some(format!("{} output values for {keys} keys (expected {})", channel.values.len(), keys * per_key));
    }
    if !channel.values.iter().all(|v| v.is_finite()) {
        return Some("output values are not finite".into());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use std::time::Instant;

    // ---- Fixtures --------------------------------------------------------------------------

    /// A fresh folder under the system temp dir, removed when dropped.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(tag: &str) -> Self {
            static COUNTER: AtomicUsize = AtomicUsize::new(0);
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let dir = std::env::temp_dir().join(format!("hybrid-rt-{tag}-{}-{n}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Self(dir)
        }

        fn join(&self, name: &str) -> PathBuf {
            self.0.join(name)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn f32s(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    fn u16s(values: &[u16]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    fn u32s(values: &[u32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    const FLOAT: u32 = 5126;
    const UBYTE: u32 = 5121;
    const BYTE: u32 = 5120;
    const USHORT: u32 = 5123;
    const UINT: u32 = 5125;

    /// A glTF file under construction: JSON plus the bytes of its one buffer.
    struct Gltf {
        json: Value,
        bin: Vec<u8>,
    }

    impl Gltf {
        fn empty() -> Self {
            let json = json!({
                "asset": {"version": "2.0"},
                "buffers": [{"byteLength": 0}],
                "scene": 0,
                "scenes": [{"nodes": []}],
            });
            Self { json, bin: Vec::new() }
        }

        /// One mesh of one indexed primitive (u16 indices) on one root node.
        fn mesh(positions: &[[f32; 3]], indices: &[u16]) -> Self {
            let mut g = Self::empty();
            let pos = g.vec3_accessor(positions);
            let view = g.view(&u16s(indices));
            let idx = g.accessor(view, USHORT, indices.len(), "SCALAR");
            g.push("meshes", json!({"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}));
            let node = g.push("nodes", json!({"mesh": 0}));
            g.json["scenes"][0]["nodes"] = json!([node]);
            g
        }

        fn triangle() -> Self {
            Self::mesh(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[0, 1, 2])
        }

        fn push(&mut self, key: &str, value: Value) -> usize {
            if self.json.get(key).is_none() {
                self.json[key] = json!([]);
            }
            let array = self.json[key].as_array_mut().unwrap();
            array.push(value);
            array.len() - 1
        }

        /// Appends bytes at a 4-byte aligned offset as a new buffer view.
        fn view(&mut self, bytes: &[u8]) -> usize {
            while !self.bin.len().is_multiple_of(4) {
                self.bin.push(0);
            }
            let offset = self.bin.len();
            self.bin.extend_from_slice(bytes);
            self.json["buffers"][0]["byteLength"] = json!(self.bin.len());
            self.push("bufferViews", json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}))
        }

        fn accessor(&mut self, view: usize, component: u32, count: usize, ty: &str) -> usize {
            self.push("accessors", json!({"bufferView": view, "componentType": component, "count": count, "type": ty}))
        }

        fn vec3_accessor(&mut self, values: &[[f32; 3]]) -> usize {
            let view = self.view(&f32s(values.as_flattened()));
            self.accessor(view, FLOAT, values.len(), "VEC3")
        }

        fn float_accessor(&mut self, values: &[f32], ty: &str, count: usize) -> usize {
            let view = self.view(&f32s(values));
            self.accessor(view, FLOAT, count, ty)
        }

        fn primitive(&mut self) -> &mut Value {
            &mut self.json["meshes"][0]["primitives"][0]
        }

        fn json_text(&self) -> Vec<u8> {
            serde_json::to_vec_pretty(&self.json).unwrap()
        }

        /// Writes `NAME.gltf` with the buffer in the file `bin_name`.
        fn write_with_bin(&mut self, dir: &TempDir, name: &str, bin_name: &str, uri: &str) -> PathBuf {
            self.json["buffers"][0]["uri"] = json!(uri);
            std::fs::write(dir.join(bin_name), &self.bin).unwrap();
            let path = dir.join(&format!("{name}.gltf"));
            std::fs::write(&path, self.json_text()).unwrap();
            path
        }

        fn write_gltf(&mut self, dir: &TempDir, name: &str) -> PathBuf {
            let bin = format!("{name}.bin");
            self.write_with_bin(dir, name, &bin, &bin)
        }

        fn write_embedded(&mut self, dir: &TempDir, name: &str) -> PathBuf {
            let uri = format!("data:application/octet-stream;base64,{}", BASE64.encode(&self.bin));
            self.json["buffers"][0]["uri"] = json!(uri);
            let path = dir.join(&format!("{name}.gltf"));
            std::fs::write(&path, self.json_text()).unwrap();
            path
        }

        fn glb_bytes(&self) -> Vec<u8> {
            let mut json = serde_json::to_vec(&self.json).unwrap();
            while !json.len().is_multiple_of(4) {
                json.push(b' ');
            }
            let mut bin = self.bin.clone();
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            let total = 12 + 8 + json.len() + 8 + bin.len();
            let mut out = b"glTF".to_vec();
            out.extend(u32s(&[2, total as u32, json.len() as u32, GLB_CHUNK_JSON]));
            out.extend(&json);
            out.extend(u32s(&[bin.len() as u32, GLB_CHUNK_BIN]));
            out.extend(&bin);
            out
        }

        fn write_glb(&self, dir: &TempDir, name: &str) -> PathBuf {
            let path = dir.join(&format!("{name}.glb"));
            std::fs::write(&path, self.glb_bytes()).unwrap();
            path
        }
    }

    fn png_2x2(rgba: [u8; 4]) -> Vec<u8> {
        let mut out = Vec::new();
        image::RgbaImage::from_pixel(2, 2, image::Rgba(rgba))
            .write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
            .unwrap();
        out
    }

    fn load(path: &Path) -> Result<Scene, SceneError> {
        load_gltf(path, &LoadOptions::default())
    }

    fn load_with(path: &Path, change: impl FnOnce(&mut LoadOptions)) -> Result<Scene, SceneError> {
        let mut opts = LoadOptions::default();
        change(&mut opts);
        load_gltf(path, &opts)
    }

    /// Asserts that loading failed with a message naming the file and containing each needle.
    #[track_caller]
    fn assert_error(result: Result<Scene, SceneError>, file: &Path, needles: &[&str]) {
        let msg = match result {
            Ok(_) => panic!("{} loaded; expected an error mentioning {needles:?}", file.display()),
            Err(e) => e.to_string(),
        };
        assert!(msg.contains(&file.display().to_string()), "file not named in: {msg}");
        for needle in needles {
            assert!(msg.contains(needle), "expected {needle:?} in: {msg}");
        }
    }

    /// A named way to break a fixture, and what the resulting error must say.
    type Case<T> = (&'static str, fn(&mut T), &'static str);

    #[track_caller]
    fn assert_warning(scene: &Scene, needle: &str) {
        let found = scene.warnings.iter().filter(|w| w.contains(needle)).count();
        assert_eq!(found, 1, "expected one warning containing {needle:?} in {:?}", scene.warnings);
    }

    /// What every loaded scene must satisfy for the renderer to use it without checks.
    fn assert_consistent(scene: &Scene) {
        assert!(scene.triangle_count() > 0);
        for (i, node) in scene.nodes.iter().enumerate() {
            assert!(node.parent.is_none_or(|p| (p as usize) < i), "node {i} precedes its parent");
            assert!(node.rotation.is_normalized());
        }
        for inst in &scene.instances {
            assert!((inst.mesh as usize) < scene.meshes.len() && (inst.node as usize) < scene.nodes.len());
        }
        for mesh in &scene.meshes {
            assert!((mesh.material as usize) < scene.materials.len());
            assert_eq!(mesh.indices.len() % 3, 0);
            assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.vertices.len()));
            assert!(mesh.bounds_min.cmple(mesh.bounds_max).all());
            for v in &mesh.vertices {
                assert!(Vec3::from(v.normal).is_normalized(), "{v:?}");
                assert!(Vec3::from(v.tangent[..3].try_into().unwrap_or([0.0; 3])).is_normalized(), "{v:?}");
                assert_eq!(v.tangent[3].abs(), 1.0);
            }
        }
        for texture in &scene.textures {
            assert!(texture.image.is_none_or(|i| (i as usize) < scene.images.len()));
        }
        for image in &scene.images {
            assert_eq!(image.rgba8.len(), (image.width * image.height * 4) as usize);
        }
        for m in &scene.materials {
            let slots = [
                m.base_color_texture,
                m.metallic_roughness_texture,
                m.normal_texture,
                m.occlusion_texture,
                m.emissive_texture,
            ];
            assert!(slots.iter().flatten().all(|t| (t.texture as usize) < scene.textures.len() && t.uv_set < 2));
        }
    }

    // ---- Valid files -----------------------------------------------------------------------

    #[test]
    fn embedded_triangle_gets_flat_normals_and_a_default_material() {
        let dir = TempDir::new("embedded");
        let path = Gltf::triangle().write_embedded(&dir, "tri");
        let scene = load(&path).unwrap();
        assert_consistent(&scene);
        assert_eq!(scene.name, "tri");
        assert_eq!(scene.source.as_deref(), Some(path.as_path()));
        assert_eq!(scene.triangle_count(), 1);
        assert_eq!(scene.materials.len(), 1);
        assert_eq!(scene.materials[0].name, "default");
        let mesh = &scene.meshes[0];
        assert!(mesh.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
        assert_eq!((mesh.bounds_min, mesh.bounds_max), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }

    #[test]
    fn glb_and_percent_encoded_external_buffers_load() {
        let dir = TempDir::new("containers");
        let glb = Gltf::triangle().write_glb(&dir, "tri");
        assert_eq!(load(&glb).unwrap().triangle_count(), 1);
        let gltf = Gltf::triangle().write_with_bin(&dir, "ext", "my mesh.bin", "my%20mesh.bin");
        assert_eq!(load(&gltf).unwrap().triangle_count(), 1);
    }

    #[test]
    fn strips_fans_index_types_and_skipped_primitives() {
        let mut g = Gltf::empty();
        let positions =
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]];
        let pos = g.vec3_accessor(&positions);
        let nrm = g.vec3_accessor(&[[0.0, 0.0, 1.0]; 6]);
        let v = g.view(&[0, 1, 2, 3]);
        let strip = g.accessor(v, UBYTE, 4, "SCALAR");
        let v = g.view(&u32s(&[0, 1, 2, 3]));
        let fan = g.accessor(v, UINT, 4, "SCALAR");
        let v = g.view(&u16s(&[0, 1, 2, 3]));
        let four = g.accessor(v, USHORT, 4, "SCALAR");
        let attributes = json!({"POSITION": pos, "NORMAL": nrm});
        g.push(
            "meshes",
            json!({"name": "m", "primitives": [
                {"attributes": attributes, "indices": strip, "mode": 5},
                {"attributes": attributes, "indices": fan, "mode": 6},
                {"attributes": attributes},
                {"attributes": attributes, "mode": 0},
                {"attributes": attributes, "indices": four},
            ]}),
        );
        g.push("nodes", json!({"mesh": 0}));
        g.json["scenes"][0]["nodes"] = json!([0]);
        let dir = TempDir::new("modes");
        let scene = load(&g.write_gltf(&dir, "modes")).unwrap();
        assert_consistent(&scene);
        let indices: Vec<&[u32]> = scene.meshes.iter().map(|m| m.indices.as_slice()).collect();
        assert_eq!(indices, [&[0, 1, 2, 1, 3, 2][..], &[1, 2, 0, 2, 3, 0], &[0, 1, 2, 3, 4, 5], &[0, 1, 2]]);
        assert_eq!(scene.meshes[0].name, "m#0");
        assert_eq!(scene.instances.len(), 4);
        assert_warning(&scene, "meshes[0].primitives[3]: mode Points");
        assert_warning(&scene, "meshes[0].primitives[4]: 4 indices is not a multiple of 3");
    }

    #[test]
    fn normalized_strided_and_sparse_accessors() {
        let mut g = Gltf::empty();
        // Interleaved: position (3 x f32) then uv (2 x normalised u16), stride 16.
        let mut interleaved = Vec::new();
        for (p, uv) in [([0.0f32, 0.0, 0.0], [0u16, 0]), ([1.0, 0.0, 0.0], [65535, 0]), ([0.0, 1.0, 0.0], [0, 32768])] {
            interleaved.extend(f32s(&p));
            interleaved.extend(u16s(&uv));
        }
        let view = g.view(&interleaved);
        g.json["bufferViews"][view]["byteStride"] = json!(16);
        let pos = g.accessor(view, FLOAT, 3, "VEC3");
        let uv = g.accessor(view, USHORT, 3, "VEC2");
        g.json["accessors"][uv]["byteOffset"] = json!(12);
        g.json["accessors"][uv]["normalized"] = json!(true);
        // Sparse over data: vertex 2 moves to y = 2.
        let sparse_index = g.view(&[2]);
        let sparse_value = g.view(&f32s(&[0.0, 2.0, 0.0]));
        g.json["accessors"][pos]["sparse"] = json!({
            "count": 1,
            "indices": {"bufferView": sparse_index, "componentType": UBYTE},
            "values": {"bufferView": sparse_value},
        });
        // Sparse without data: zeros except vertex 1's normal.
        let normal_value = g.view(&f32s(&[1.0, 0.0, 0.0]));
        let idx16 = g.view(&u16s(&[1, 0]));
        let nrm = g.push(
            "accessors",
            json!({"componentType": FLOAT, "count": 3, "type": "VEC3",
                "sparse": {
                    "count": 1,
                    "indices": {"bufferView": idx16, "componentType": USHORT},
                    "values": {"bufferView": normal_value},
                },
            }),
        );
        // Normalised signed bytes: 127 -> 1, -128 -> -1.
        let tangent_view = g.view(&[0, 127, 0, 0x80, 0, 127, 0, 0x80, 0, 127, 0, 0x80]);
        let tan = g.accessor(tangent_view, BYTE, 3, "VEC4");
        g.json["accessors"][tan]["normalized"] = json!(true);
        let attributes = json!({"POSITION": pos, "TEXCOORD_0": uv, "NORMAL": nrm, "TANGENT": tan});
        g.push("meshes", json!({"primitives": [{"attributes": attributes}]}));
        g.push("nodes", json!({"mesh": 0}));
        g.json["scenes"][0]["nodes"] = json!([0]);
        let dir = TempDir::new("accessors");
        let scene = load(&g.write_gltf(&dir, "acc")).unwrap();
        assert_consistent(&scene);
        let v = &scene.meshes[0].vertices;
        assert_eq!(v[2].position, [0.0, 2.0, 0.0]);
        assert_eq!(v[1].uv0, [1.0, 0.0]);
        assert!((v[2].uv0[1] - 32768.0 / 65535.0).abs() < 1e-6);
        assert_eq!(v[1].normal, [1.0, 0.0, 0.0]);
        assert_eq!(v[0].normal, [0.0, 0.0, 1.0], "zero normals are repaired");
        assert_eq!(v[0].tangent, [0.0, 1.0, 0.0, -1.0]);
    }

    #[test]
    fn materials_textures_and_samplers() {
        let mut g = Gltf::triangle();
        let uv0 = g.float_accessor(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2", 3);
        let uv1 = g.float_accessor(&[0.0, 0.0, 0.0, 1.0, 1.0, 0.0], "VEC2", 3);
        *g.primitive() = json!({
            "attributes": {"POSITION": 0, "TEXCOORD_0": uv0, "TEXCOORD_1": uv1},
            "indices": 1,
            "material": 0,
        });
        let png = g.view(&png_2x2([255, 0, 0, 255]));
        let dir = TempDir::new("materials");
        std::fs::write(dir.join("tex 1.png"), png_2x2([0, 255, 0, 128])).unwrap();
        g.json["images"] = json!([{"bufferView": png, "mimeType": "image/png"}, {"uri": "tex%201.png"}]);
        g.json["samplers"] = json!([
            {"magFilter": 9728, "minFilter": 9986, "wrapS": 33071, "wrapT": 33648},
            {"minFilter": 9729},
        ]);
        g.json["textures"] = json!([
            {"source": 0, "sampler": 0},
            {"source": 1, "sampler": 1},
            {"source": 5},
            {"source": 0, "sampler": 9},
        ]);
        g.json["extensionsUsed"] = json!(["KHR_texture_transform", "KHR_materials_emissive_strength"]);
        let transform = json!({
            "KHR_texture_transform": {"offset": [0.5, 0.0], "scale": [2.0, 2.0], "texCoord": 1},
        });
        g.json["materials"] = json!([
            {"name": "full",
             "pbrMetallicRoughness": {
                 "baseColorFactor": [0.5, 0.5, 0.5, 1.0],
                 "baseColorTexture": {"index": 0, "extensions": transform},
                 "metallicFactor": 0.25,
                 "roughnessFactor": 0.75,
                 "metallicRoughnessTexture": {"index": 1},
             },
             "normalTexture": {"index": 0, "scale": 0.5, "texCoord": 1},
             "occlusionTexture": {"index": 1, "strength": 0.3},
             "emissiveTexture": {"index": 1}, "emissiveFactor": [1.0, 0.5, 0.0],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
             "alphaMode": "MASK", "doubleSided": true},
            {"name": "blend1", "alphaMode": "BLEND"},
            {"name": "blend2", "alphaMode": "BLEND"},
            {"name": "badtex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 42}}},
            {"name": "cutoff", "alphaMode": "MASK", "alphaCutoff": 0.25},
        ]);
        let scene = load(&g.write_gltf(&dir, "mat")).unwrap();
        assert_consistent(&scene);
        assert_eq!(scene.images.len(), 2);
        assert_eq!(&scene.images[0].rgba8[..4], &[255, 0, 0, 255]);
        assert_eq!(&scene.images[1].rgba8[..4], &[0, 255, 0, 128]);
        assert_eq!(scene.images[1].name, "tex%201.png");
        let s0 = scene.textures[0].sampler;
        assert_eq!((s0.mag_filter, s0.min_filter, s0.mipmaps), (Filter::Nearest, Filter::Nearest, true));
        assert_eq!((s0.wrap_s, s0.wrap_t), (Wrap::ClampToEdge, Wrap::MirroredRepeat));
        assert!(!scene.textures[1].sampler.mipmaps);
        assert_eq!(scene.textures[2].image, None);
        assert_warning(&scene, "textures[2].source: image 5 out of range (2 images)");
        assert_eq!(scene.textures[3].sampler, Sampler::default());
        assert_warning(&scene, "textures[3].sampler: sampler 9 out of range (2 samplers)");

        let m = &scene.materials[0];
        let base = m.base_color_texture.unwrap();
        assert_eq!((base.texture, base.uv_set), (0, 1));
        assert_eq!(base.transform, uv_transform(Vec2::new(0.5, 0.0), 0.0, Vec2::splat(2.0)));
        assert_eq!(m.metallic_roughness_texture.map(|t| (t.texture, t.transform)), Some((1, Mat3::IDENTITY)));
        assert_eq!((m.metallic_factor, m.roughness_factor), (0.25, 0.75));
        assert_eq!((m.normal_texture.unwrap().uv_set, m.normal_scale), (1, 0.5));
        assert_eq!(m.occlusion_strength, 0.3);
        assert_eq!(m.emissive_factor, Vec3::new(4.0, 2.0, 0.0));
        assert_eq!(m.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
        assert!(m.double_sided);
        assert_eq!(scene.materials[1].alpha_mode, AlphaMode::Blend);
        assert_warning(&scene, "2 material(s) use alphaMode BLEND");
        assert_eq!(scene.materials[3].base_color_texture, None);
        assert_warning(&scene, "materials[3].pbrMetallicRoughness.baseColorTexture.index: texture 42 out of range");
        assert_eq!(scene.materials[4].alpha_mode, AlphaMode::Mask { cutoff: 0.25 });
        // The normal texture reads TEXCOORD_1 = (y, x) here: MikkTSpace puts the tangent along +Y.
        let t = Vec4::from(scene.meshes[0].vertices[0].tangent);
        assert!(t.truncate().abs_diff_eq(Vec3::Y, 1e-5), "{t}");
    }

    #[test]
    fn lights_and_cameras_attach_to_nodes() {
        let mut g = Gltf::triangle();
        g.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        g.json["extensions"] = json!({"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.0, 0.0], "intensity": 5.0, "range": 10.0,
             "extras": {"radius": 0.25}},
            {"type": "spot", "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
            {"type": "directional", "name": "sun"},
        ]}});
        g.json["cameras"] = json!([
            {"type": "perspective",
             "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100.0, "aspectRatio": 1.5}},
            {"type": "orthographic",
             "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}},
        ]);
        let light = |i: usize| json!({"KHR_lights_punctual": {"light": i}});
        for node in [
            json!({"extensions": light(0)}),
            json!({"extensions": light(1)}),
            json!({"extensions": light(2), "camera": 0}),
            json!({"camera": 1}),
            json!({"extensions": light(7)}),
        ] {
            g.push("nodes", node);
        }
        g.json["scenes"][0]["nodes"] = json!([0, 1, 2, 3, 4, 5]);
        let dir = TempDir::new("lights");
        let scene = load(&g.write_gltf(&dir, "lights")).unwrap();
        assert_consistent(&scene);
        assert_eq!(scene.lights.len(), 3);
        let point = &scene.lights[0];
        assert_eq!((point.kind, point.color, point.intensity), (LightKind::Point, Vec3::X, 5.0));
        assert_eq!((point.range, point.radius, point.node), (Some(10.0), 0.25, 1));
        let spot = &scene.lights[1];
        assert_eq!(spot.kind, LightKind::Spot { inner_cone: 0.1, outer_cone: 0.5 });
        assert_eq!((spot.color, spot.intensity, spot.range, spot.radius), (Vec3::ONE, 1.0, None, 0.0));
        assert_eq!((scene.lights[2].kind, scene.lights[2].name.as_str()), (LightKind::Directional, "sun"));
        assert_eq!(scene.cameras.len(), 1);
        let camera = &scene.cameras[0];
        assert_eq!(
            (camera.yfov, camera.aspect_ratio, camera.znear, camera.zfar, camera.node),
            (0.8, Some(1.5), 0.1, Some(100.0), 3)
        );
        assert_warning(&scene, "cameras[1]: orthographic cameras are not supported");
        assert_warning(&scene, "nodes[5].extensions.KHR_lights_punctual.light: light 7 out of range (3 lights)");
    }

    #[test]
    fn loads_morph_targets_weights_and_weight_animations() {
        let mut g = Gltf::triangle();
        let lift = g.float_accessor(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3", 3);
        let shift = g.float_accessor(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0], "VEC3", 3);
        let normals = g.float_accessor(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3", 3);
        let normal_deltas = g.float_accessor(&[1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, -1.0], "VEC3", 3);
        g.primitive()["attributes"]["NORMAL"] = json!(normals);
        g.primitive()["targets"] = json!([{"POSITION": lift, "NORMAL": normal_deltas}, {"POSITION": shift}]);
        g.json["meshes"][0]["weights"] = json!([0.25, 0.0]);
        // A second node draws the mesh again with weights of its own: it takes the first's.
        g.json["nodes"][0]["weights"] = json!([0.5, 0.5]);
        g.push("nodes", json!({"mesh": 0, "weights": [1.0, 1.0]}));
        g.json["scenes"][0]["nodes"] = json!([0, 1]);
        let times = g.float_accessor(&[0.0, 1.0, 4.0], "SCALAR", 3);
        let weights = g.float_accessor(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0], "SCALAR", 6);
        let steps = g.float_accessor(&[0.0, 1.0, 0.0], "SCALAR", 3);
        g.json["animations"] = json!([{"samplers": [
            {"input": times, "output": weights},
            {"input": times, "output": steps, "interpolation": "STEP"},
        ], "channels": [
            {"sampler": 0, "target": {"node": 0, "path": "weights"}},
            {"sampler": 1, "target": {"node": 0, "path": "weights"}},
            {"sampler": 0, "target": {"node": 1, "path": "weights"}},
        ]}]);
        let dir = TempDir::new("morph");
        let scene = load(&g.write_gltf(&dir, "morph")).unwrap();
        assert_consistent(&scene);
        assert!(scene.is_animated());
        assert_eq!(scene.morphs.len(), 1);
        let morph = &scene.morphs[0];
        assert_eq!((morph.mesh, morph.targets.len(), morph.weights.as_slice()), (0, 2, &[0.5, 0.5][..]));
        assert_eq!(morph.targets[0].positions, vec![Vec3::Z; 3]);
        assert_eq!((morph.targets[0].normals.len(), morph.targets[1].normals.len()), (3, 0));
        // Six values for three keys of two weights: the first channel; the second has three
        // values for two targets and is skipped.
        assert_eq!(morph.channels.len(), 1);
        assert_eq!(morph.channels[0].period, 4.0);
        assert_eq!(morph.weights_at(0.5), vec![0.5, 0.0]);
        assert_eq!(morph.weights_at(2.5), vec![1.0, 0.5]);
        assert_eq!(morph.weights_at(4.5), vec![0.5, 0.0], "loops over the animation");
        let v = morph.deform(&scene.meshes[0].vertices, &morph.weights_at(2.5));
        assert_eq!(v[0].position, [0.5, 0.0, 1.0]);
        let n = Vec3::from(v[0].normal);
        assert!((n - Vec3::X).length() < 1e-6, "normal {n}");
        // Bounds cover the targets at full weight.
        assert_eq!((scene.meshes[0].bounds_min, scene.meshes[0].bounds_max), (Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)));
        assert_warning(&scene, "animations[0].samplers[1]: 3 output values for 3 keys of 2 weights");
        assert_warning(&scene, "a morphing mesh drawn by several nodes");
        assert_warning(&scene, "node 1 draws no morph targets of its own");
    }

    #[test]
    fn hierarchy_is_flattened_parents_first_with_shared_meshes() {
        let mut g = Gltf::triangle();
        // 90 degrees about Z, scale 2, translation (1, 2, 3), column-major.
        let matrix = [0.0, 2.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0, 2.0, 3.0, 1.0];
        g.json["nodes"] = json!([
            {"name": "a", "children": [2], "translation": [5.0, 0.0, 0.0]},
            {"name": "b", "matrix": matrix},
            {"name": "c", "children": [3], "mesh": 0},
            {"name": "d", "mesh": 0},
            {"name": "unlisted", "mesh": 0},
        ]);
        g.json["scenes"][0]["nodes"] = json!([1, 0]);
        let dir = TempDir::new("hierarchy");
        let scene = load(&g.write_gltf(&dir, "h")).unwrap();
        assert_consistent(&scene);
        let names: Vec<&str> = scene.nodes.iter().map(|n| n.name.as_str()).collect();
        assert_eq!(names, ["b", "a", "c", "d"]);
        assert_eq!(scene.nodes.iter().map(|n| n.parent).collect::<Vec<_>>(), [None, None, Some(1), Some(2)]);
        let b = &scene.nodes[0];
        assert!(b.translation.abs_diff_eq(Vec3::new(1.0, 2.0, 3.0), 1e-6));
        assert!(b.scale.abs_diff_eq(Vec3::splat(2.0), 1e-6));
        assert!(b.rotation.abs_diff_eq(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), 1e-6));
        assert_eq!(scene.meshes.len(), 1, "instances share the mesh");
        assert_eq!(scene.instances.iter().map(|i| (i.mesh, i.node)).collect::<Vec<_>>(), [(0, 2), (0, 3)]);
        let pose = scene.evaluate(0.0);
        assert!(pose.world[3].transform_point3(Vec3::ZERO).abs_diff_eq(Vec3::new(5.0, 0.0, 0.0), 1e-6));

        // Without scenes, every root node is loaded.
        g.json.as_object_mut().unwrap().remove("scenes");
        g.json.as_object_mut().unwrap().remove("scene");
        let scene = load(&g.write_gltf(&dir, "noscenes")).unwrap();
        assert_eq!(scene.nodes.len(), 5);
        assert_eq!(scene.instances.len(), 3);
    }

    #[test]
    fn animations_load_and_unsupported_channels_are_skipped() {
        let mut g = Gltf::triangle();
        let times = g.float_accessor(&[0.0, 1.0, 2.0], "SCALAR", 3);
        let translations = g.float_accessor(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 2.0, 0.0], "VEC3", 3);
        let q = Quat::from_rotation_y(1.0).to_array();
        let rotations: Vec<f32> = [[0.0; 4], [0.0, 0.0, 0.0, 1.0], [0.0; 4]]
            .iter()
            .cycle()
            .take(9)
            .enumerate()
            .flat_map(|(k, v)| if k == 4 { q } else { *v })
            .collect();
        let rotations = g.float_accessor(&rotations, "VEC4", 9);
        let scales = g.float_accessor(&[1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 3.0, 3.0, 3.0], "VEC3", 3);
        let short = g.float_accessor(&[0.0; 6], "VEC3", 2);
        g.json["animations"] = json!([{"name": "spin", "samplers": [
            {"input": times, "output": translations},
            {"input": times, "output": rotations, "interpolation": "CUBICSPLINE"},
            {"input": times, "output": scales, "interpolation": "STEP"},
            {"input": times, "output": short},
        ], "channels": [
            {"sampler": 0, "target": {"node": 0, "path": "translation"}},
            {"sampler": 1, "target": {"node": 0, "path": "rotation"}},
            {"sampler": 2, "target": {"node": 0, "path": "scale"}},
            {"sampler": 0, "target": {"node": 0, "path": "weights"}},
            {"sampler": 3, "target": {"node": 0, "path": "translation"}},
        ]}]);
        let dir = TempDir::new("animation");
        let scene = load(&g.write_gltf(&dir, "anim")).unwrap();
        assert_consistent(&scene);
        assert!(scene.is_animated());
        let animation = &scene.animations[0];
        assert_eq!((animation.name.as_str(), animation.channels.len(), animation.duration()), ("spin", 3, 2.0));
        assert_eq!(animation.channels[1].interpolation, Interpolation::CubicSpline);
        assert_warning(&scene, "node 0 draws no morph targets of its own; the channel is skipped");
        assert_warning(&scene, "animations[0].samplers[3]: 2 output values for 3 keys (expected 3)");
        let (scale, _, translation) = scene.evaluate(0.5).world[0].to_scale_rotation_translation();
        assert!(scale.abs_diff_eq(Vec3::ONE, 1e-5), "step holds the first key: {scale}");
        assert!(translation.abs_diff_eq(Vec3::X, 1e-5), "{translation}");
        let world = scene.evaluate(1.5).world[0];
        assert!(world.transform_point3(Vec3::ZERO).abs_diff_eq(Vec3::new(2.0, 1.0, 0.0), 1e-5));
        let world = scene.evaluate(1.0).world[0];
        let (_, rotation, _) = world.to_scale_rotation_translation();
        assert!(rotation.abs_diff_eq(Quat::from_rotation_y(1.0), 1e-5));
    }

    #[test]
    fn gpu_instancing_makes_child_nodes_sharing_the_mesh() {
        let mut g = Gltf::triangle();
        let translations = g.float_accessor(&[0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 6.0, 0.0, 0.0], "VEC3", 3);
        g.json["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
        g.json["nodes"][0]["name"] = json!("crowd");
        g.json["nodes"][0]["extensions"] =
            json!({"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": translations}}});
        let dir = TempDir::new("instancing");
        let scene = load(&g.write_glb(&dir, "inst")).unwrap();
        assert_consistent(&scene);
        assert_eq!(scene.meshes.len(), 1);
        assert_eq!(scene.nodes.len(), 4);
        assert_eq!(scene.instances.iter().map(|i| (i.mesh, i.node)).collect::<Vec<_>>(), [(0, 1), (0, 2), (0, 3)]);
        assert_eq!((scene.nodes[3].name.as_str(), scene.nodes[3].parent), ("crowd#2", Some(0)));
        assert_eq!(scene.nodes[3].translation, Vec3::new(6.0, 0.0, 0.0));
    }

    // ---- Bad files -------------------------------------------------------------------------

    #[test]
    fn missing_file() {
        let path = std::env::temp_dir().join("hybrid-rt-no-such-scene.gltf");
        assert_error(load(&path), &path, &["cannot read", "No such file"]);
    }

    #[test]
    fn truncated_glb() {
        let dir = TempDir::new("truncated");
        let path = dir.join("cut.glb");
        let bytes = Gltf::triangle().glb_bytes();
        std::fs::write(&path, &bytes[..bytes.len() - 10]).unwrap();
        assert_error(load(&path), &path, &["truncated GLB file"]);
        std::fs::write(&path, &bytes[..7]).unwrap();
        assert_error(load(&path), &path, &["truncated GLB file", "7 bytes"]);
    }

    #[test]
    fn wrong_magic() {
        let dir = TempDir::new("magic");
        let path = dir.join("zip.glb");
        std::fs::write(&path, b"PK\x03\x04 not a scene").unwrap();
        assert_error(load(&path), &path, &["not a glTF file"]);
    }

    #[test]
    fn malformed_json() {
        let dir = TempDir::new("json");
        let path = dir.join("bad.gltf");
        std::fs::write(&path, b"{\"asset\": {\"version\": \"2.0\"},").unwrap();
        assert_error(load(&path), &path, &["malformed glTF JSON"]);
        std::fs::write(&path, b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": -1}]}").unwrap();
        assert_error(load(&path), &path, &["malformed glTF JSON"]);
    }

    #[test]
    fn buffer_shorter_than_its_byte_length() {
        let mut g = Gltf::triangle();
        let dir = TempDir::new("short");
        let path = g.write_gltf(&dir, "short");
        g.json["buffers"][0]["byteLength"] = json!(1000);
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["buffers[0]", "less than its byteLength 1000"]);
    }

    #[test]
    fn missing_external_buffer() {
        let mut g = Gltf::triangle();
        let dir = TempDir::new("nobin");
        let path = g.write_with_bin(&dir, "nobin", "other.bin", "nothere.bin");
        assert_error(load(&path), &path, &["buffers[0].uri", "nothere.bin"]);
    }

    #[test]
    fn buffer_view_beyond_its_buffer() {
        let mut g = Gltf::triangle();
        g.json["bufferViews"][0]["byteLength"] = json!(400);
        let dir = TempDir::new("view");
        let path = g.write_gltf(&dir, "view");
        assert_error(load(&path), &path, &["bufferViews[0]", "beyond the end of buffer 0"]);
    }

    #[test]
    fn accessor_beyond_its_buffer_view() {
        let mut g = Gltf::triangle();
        g.json["accessors"][0]["count"] = json!(10);
        let dir = TempDir::new("accessor");
        let path = g.write_gltf(&dir, "acc");
        assert_error(
            load(&path),
            &path,
            &["meshes[0].primitives[0].attributes.POSITION -> accessors[0]", "overrun bufferViews[0]"],
        );
        g.json["accessors"][0]["count"] = json!(u64::MAX);
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["accessors[0]", "max_vertices"]);
        let big = Limits { max_vertices: u64::MAX, ..Limits::default() };
        let result = load_with(&path, |o| o.limits = big);
        assert_error(result, &path, &["accessors[0]", "overrun"]);
    }

    #[test]
    fn indices_out_of_range() {
        let mut g = Gltf::triangle();
        g.primitive()["indices"] = json!(7);
        let dir = TempDir::new("indices");
        let path = g.write_gltf(&dir, "idx");
        assert_error(load(&path), &path, &["meshes[0].primitives[0].indices: accessor 7 out of range (2 accessors)"]);
        let path = Gltf::mesh(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[0, 1, 5]).write_gltf(&dir, "value");
        assert_error(load(&path), &path, &["meshes[0].primitives[0].indices: index value 5 out of range (3 vertices)"]);
    }

    #[test]
    fn other_indices_out_of_range() {
        let dir = TempDir::new("refs");
        let cases: [Case<Gltf>; 4] = [
            ("mesh", |g| g.json["nodes"][0]["mesh"] = json!(3), "nodes[0].mesh: mesh 3 out of range (1 meshes)"),
            (
                "node",
                |g| g.json["scenes"][0]["nodes"] = json!([4]),
                "scenes[0].nodes[0]: node 4 out of range (1 nodes)",
            ),
            (
                "view",
                |g| g.json["accessors"][0]["bufferView"] = json!(9),
                "accessors[0].bufferView: bufferView 9 out of range (2 bufferViews)",
            ),
            (
                "buffer",
                |g| g.json["bufferViews"][0]["buffer"] = json!(2),
                "bufferViews[0].buffer: buffer 2 out of range (1 buffers)",
            ),
        ];
        for (name, change, needle) in cases {
            let mut g = Gltf::triangle();
            change(&mut g);
            let path = g.write_gltf(&dir, name);
            assert_error(load(&path), &path, &[needle]);
        }
    }

    #[test]
    fn nan_and_infinite_positions() {
        let dir = TempDir::new("nan");
        let path = Gltf::mesh(&[[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]], &[0, 1, 2]).write_gltf(&dir, "nan");
        assert_error(load(&path), &path, &["attributes.POSITION", "vertex 1 is not finite"]);
        let path = Gltf::mesh(&[[0.0; 3], [0.0; 3], [0.0, f32::INFINITY, 0.0]], &[0, 1, 2]).write_gltf(&dir, "inf");
        assert_error(load(&path), &path, &["vertex 2 is not finite"]);
    }

    #[test]
    fn scene_without_triangles() {
        let mut g = Gltf::triangle();
        g.primitive()["mode"] = json!(0);
        let dir = TempDir::new("empty");
        let path = g.write_gltf(&dir, "points");
        assert_error(load(&path), &path, &["no triangles"]);
    }

    #[test]
    fn unsupported_required_extension() {
        let mut g = Gltf::triangle();
        g.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression", "NV_unknown"]);
        g.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
        let dir = TempDir::new("ext");
        let path = g.write_gltf(&dir, "ext");
        assert_error(load(&path), &path, &["extensionsRequired[0]", "KHR_draco_mesh_compression", "not supported"]);
        g.json.as_object_mut().unwrap().remove("extensionsRequired");
        std::fs::write(&path, g.json_text()).unwrap();
        assert!(load(&path).is_ok(), "unknown optional extensions are ignored");
    }

    #[test]
    fn uris_outside_the_scene_folder() {
        let dir = TempDir::new("outside");
        std::fs::create_dir(dir.join("scene")).unwrap();
        let mut g = Gltf::triangle();
        std::fs::write(dir.join("outside.bin"), &g.bin).unwrap();
        g.json["buffers"][0]["uri"] = json!("../outside.bin");
        let path = dir.join("scene/up.gltf");
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["buffers[0].uri", "outside the scene folder", "--allow-outside-uris"]);
        assert!(load_with(&path, |o| o.allow_outside_uris = true).is_ok());

        let absolute = dir.join("outside.bin").display().to_string();
        g.json["buffers"][0]["uri"] = json!(absolute);
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["outside the scene folder", "--allow-outside-uris"]);
        assert!(load_with(&path, |o| o.allow_outside_uris = true).is_ok());

        g.json["buffers"][0]["uri"] = json!("http://example.com/x.bin");
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["has a scheme"]);
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_out_of_the_scene_folder() {
        let dir = TempDir::new("symlink");
        std::fs::create_dir(dir.join("scene")).unwrap();
        let mut g = Gltf::triangle();
        std::fs::write(dir.join("outside.bin"), &g.bin).unwrap();
        std::os::unix::fs::symlink(dir.join("outside.bin"), dir.join("scene/link.bin")).unwrap();
        g.json["buffers"][0]["uri"] = json!("link.bin");
        let path = dir.join("scene/link.gltf");
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["outside the scene folder"]);
    }

    #[test]
    fn undecodable_image() {
        let mut g = Gltf::triangle();
        let bad = BASE64.encode(b"\x89PNG\r\n\x1a\nthis is not a PNG body");
        g.json["images"] = json!([{"uri": format!("data:image/png;base64,{bad}")}]);
        let dir = TempDir::new("image");
        let path = g.write_gltf(&dir, "img");
        assert_error(load(&path), &path, &["images[0]", "cannot decode"]);
        g.json["images"] = json!([{"uri": "data:image/png;base64,AAAA"}]);
        std::fs::write(&path, g.json_text()).unwrap();
        assert_error(load(&path), &path, &["images[0]", "cannot decode"]);
    }

    #[test]
    fn node_cycles_and_shared_children() {
        let dir = TempDir::new("cycles");
        let cases = [
            ("cycle", json!([{"mesh": 0}, {"children": [2]}, {"children": [1]}]), "node cycle"),
            ("self", json!([{"mesh": 0, "children": [0]}]), "nodes[0].children[0]: node 0 is its own child"),
            (
                "twoparents",
                json!([{"mesh": 0}, {"children": [3]}, {"children": [3]}, {}]),
                "nodes[3] has two parents, nodes[1] and nodes[2]",
            ),
            ("child", json!([{"mesh": 0, "children": [5]}]), "nodes[0].children[0]: node 5 out of range (1 nodes)"),
        ];
        for (name, nodes, needle) in cases {
            let mut g = Gltf::triangle();
            g.json["nodes"] = nodes;
            let path = g.write_gltf(&dir, name);
            assert_error(load(&path), &path, &[needle]);
        }
        let mut g = Gltf::triangle();
        g.json["nodes"] = json!([{"children": [1]}, {"mesh": 0}]);
        g.json["scenes"][0]["nodes"] = json!([1]);
        let path = g.write_gltf(&dir, "notroot");
        assert_error(load(&path), &path, &["scenes[0].nodes[0]: node 1 is not a root node"]);
    }

    #[test]
    fn limits_are_enforced() {
        let dir = TempDir::new("limits");
        let mut g = Gltf::triangle();
        let primitive = g.primitive().clone();
        g.json["meshes"][0]["primitives"] = json!([primitive, primitive]);
        g.json["nodes"] = json!([{"children": [1]}, {"mesh": 0}]);
        g.json["images"] = json!([{"uri": "t.png"}]);
        std::fs::write(dir.join("t.png"), png_2x2([0; 4])).unwrap();
        let path = g.write_gltf(&dir, "lim");
        let embedded = g.write_embedded(&dir, "emb");
        let cases: [Case<Limits>; 11] = [
            ("indices", |l| l.max_triangles = 0, "3 exceeds the limit 3 * max_triangles + 2 = 2"),
            ("triangles", |l| l.max_triangles = 1, "so far: 2 exceeds the limit max_triangles = 1"),
            ("elements", |l| l.max_vertices = 2, "count: 3 exceeds the limit max_vertices = 2"),
            ("vertices", |l| l.max_vertices = 5, "so far: 6 exceeds the limit max_vertices = 5"),
            ("nodes", |l| l.max_nodes = 1, "node count: 2 exceeds the limit max_nodes = 1"),
            ("depth", |l| l.max_node_depth = 1, "depth: 2 exceeds the limit max_node_depth = 1"),
            ("buffer", |l| l.max_buffer_bytes = 10, "exceeds the limit max_buffer_bytes = 10"),
            (
                "instances",
                |l| l.max_instances = 1,
                "instances in the scene so far: 2 exceeds the limit max_instances = 1",
            ),
            // The 42-byte buffer fits; with the 86-byte image the total does not.
            ("total", |l| l.max_total_bytes = 50, "images[0].uri: bytes loaded from URIs so far: 128 exceeds"),
            ("texture", |l| l.max_texture_dimension = 1, "2 exceeds the limit max_texture_dimension = 1"),
            ("texels", |l| l.max_texture_pixels_total = 3, "4 exceeds the limit max_texture_pixels_total = 3"),
        ];
        for (_, change, needle) in cases {
            assert_error(load_with(&path, |o| change(&mut o.limits)), &path, &[needle]);
        }
        let data_uri = load_with(&embedded, |o| o.limits.max_data_uri_bytes = 10);
        assert_error(data_uri, &embedded, &["data URI length: 88 exceeds the limit max_data_uri_bytes = 10"]);
        assert!(load(&path).is_ok());
    }

    #[test]
    fn uri_helpers() {
        assert_eq!(percent_decode("a%20b%2Fc.png").as_deref(), Some("a b/c.png"));
        assert_eq!(percent_decode("bad%2"), None);
        assert_eq!(percent_decode("bad%zz"), None);
        assert!(has_scheme("https://x") && has_scheme("file:a") && !has_scheme("a/b:c") && !has_scheme("plain.bin"));
    }

    // ---- Sample scenes ---------------------------------------------------------------------

    /// The shared sample scenes, from `HYBRID_RT_SCENES` (default `../shared/scenes`). Missing
    /// scenes fail the test on CI and skip it elsewhere.
    fn scenes_dir() -> Option<PathBuf> {
        let dir = PathBuf::from(std::env::var("HYBRID_RT_SCENES").unwrap_or_else(|_| "../shared/scenes".into()));
        if dir.is_dir() {
            return Some(dir);
        }
        let reason = format!("sample scenes not found at {} (set HYBRID_RT_SCENES)", dir.display());
        assert!(std::env::var("CI").as_deref() != Ok("true"), "{reason}");
        eprintln!("skipping: {reason}");
        None
    }

    fn load_sample(relative: &str) -> Option<Scene> {
        let path = scenes_dir()?.join(relative);
        let start = Instant::now();
        let scene = load(&path).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("{relative}: {} triangles in {:?}", scene.triangle_count(), start.elapsed());
        assert_consistent(&scene);
        Some(scene)
    }

    #[test]
    fn every_sample_scene_loads() {
        let Some(dir) = scenes_dir() else {
            return;
        };
        let mut files = vec!["nvpro-cornell-box/cornellBox.gltf".to_string()];
        for (folder, ext) in [("khronos", "glb"), ("vinc3r-cornell-box", "gltf")] {
            for entry in walk(&dir.join(folder)) {
                if entry.extension().is_some_and(|e| e == ext) {
                    files.push(entry.strip_prefix(&dir).unwrap().display().to_string());
                }
            }
        }
        assert!(files.len() >= 8, "{files:?}");
        for file in files {
            load_sample(&file);
        }
    }

    fn walk(dir: &Path) -> Vec<PathBuf> {
        let mut out = Vec::new();
        for entry in std::fs::read_dir(dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() { out.extend(walk(&path)) } else { out.push(path) }
        }
        out
    }

    #[test]
    fn damaged_helmet() {
        let Some(scene) = load_sample("khronos/DamagedHelmet/DamagedHelmet.glb") else {
            return;
        };
        // The file's one primitive has 46356 indices, i.e. 15452 triangles.
        assert_eq!(scene.triangle_count(), 15452);
        assert_eq!(scene.images.len(), 5);
        assert!(scene.materials[0].normal_texture.is_some());
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }

    #[test]
    fn simple_instancing_shares_one_mesh() {
        let Some(scene) = load_sample("khronos/SimpleInstancing/SimpleInstancing.glb") else {
            return;
        };
        assert_eq!(scene.meshes.len(), 1);
        assert_eq!(scene.instances.len(), 125);
        assert!(scene.instances.iter().all(|i| i.mesh == 0));
    }

    #[test]
    fn emissive_strength_is_applied() {
        let Some(scene) = load_sample("khronos/EmissiveStrengthTest/EmissiveStrengthTest.glb") else {
            return;
        };
        let emit = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap().emissive_factor;
        let base = Vec3::new(0.1, 0.5, 0.9);
        assert!(emit("Emit1").abs_diff_eq(base, 1e-6));
        assert!(emit("Emit16").abs_diff_eq(base * 16.0, 1e-5));
    }

    #[test]
    fn nvpro_cornell_box_warns_about_the_missing_image() {
        let Some(scene) = load_sample("nvpro-cornell-box/cornellBox.gltf") else {
            return;
        };
        assert_eq!(scene.textures[0].image, None);
        assert_warning(&scene, "textures[0].source: image 0 out of range (0 images)");
        assert_eq!(scene.cameras.len(), 1);
    }

    #[test]
    fn big_scene_loads_quickly() {
        let start = Instant::now();
        let Some(scene) = load_sample("khronos/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb") else {
            return;
        };
        assert!(scene.triangle_count() > 1_000_000);
        if !cfg!(debug_assertions) {
            assert!(start.elapsed().as_secs_f32() < 2.0, "{:?}", start.elapsed());
        }
    }

    /// Generated tangents must follow glTF's convention: the test model ships tangents, and
    /// MikkTSpace run on the same geometry has to reproduce them, bitangent sign included.
    #[test]
    fn mikktspace_reproduces_shipped_tangents() {
        let Some(scene) = load_sample("khronos/NormalTangentMirrorTest/NormalTangentMirrorTest.glb") else {
            return;
        };
        let mesh = &scene.meshes[0];
        let mut vertices = mesh.vertices.clone();
        let mut indices = mesh.indices.clone();
        assert!(tangents::mikktspace_tangents(&mut vertices, &mut indices, 0));
        for (&generated, &shipped) in indices.iter().zip(&mesh.indices) {
            let g = Vec4::from(vertices[generated as usize].tangent);
            let s = Vec4::from(mesh.vertices[shipped as usize].tangent);
            assert!(g.truncate().dot(s.truncate()) > 0.95 && g.w == s.w, "{g} vs {s}");
        }
    }
}
