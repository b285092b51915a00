//! How a glTF file's bytes reach the loader: the GLB container or plain JSON, the asset
//! header, and the files and `data:` URIs it refers to (kept inside the scene's folder unless
//! the user allows otherwise).

use super::{Ctx, SUPPORTED_EXTENSIONS, UNTYPED_EXTENSIONS};
use crate::scene::SceneError;
use base64::Engine;
use gltf::json;
use serde_json::Value;
use std::path::{Component, Path, PathBuf};

// ---------------------------------------------------------------------------------------------
// Container: GLB or JSON.

pub(super) const GLB_MAGIC: &[u8; 4] = b"glTF";
pub(super) const GLB_CHUNK_JSON: u32 = 0x4E4F_534A;
pub(super) const GLB_CHUNK_BIN: u32 = 0x004E_4942;
pub(super) const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// The JSON text and, for a GLB, its BIN chunk.
pub(super) fn split_container<'f>(ctx: &Ctx, file: &'f [u8]) -> Result<(&'f [u8], Option<&'f [u8]>), SceneError> {
    if file.starts_with(GLB_MAGIC) {
        return parse_glb(ctx, file);
    }
    let text = file.strip_prefix(UTF8_BOM).unwrap_or(file);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok((text, None)),
        _ => Err(ctx.err("not a glTF file: it starts with neither '{' (glTF JSON) nor the GLB magic 'glTF'")),
    }
}

pub(super) fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let word = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(word.try_into().ok()?))
}

pub(super) fn parse_glb<'f>(ctx: &Ctx, file: &'f [u8]) -> Result<(&'f [u8], Option<&'f [u8]>), SceneError> {
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

pub(super) fn parse_json(ctx: &Ctx, json_bytes: &[u8]) -> Result<json::Root, SceneError> {
    json::Root::from_slice(json_bytes).map_err(|e| ctx.err(format!("malformed glTF JSON: {e}")))
}

pub(super) fn check_asset(ctx: &Ctx, root: &json::Root) -> Result<(), SceneError> {
    let version = &root.asset.version;
    if !version.starts_with("2.") {
        return Err(ctx.err(format!("asset.version: glTF {version} is not supported (expected 2.x)")));
    }
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(ctx.err(format!("extensionsRequired[{i}]: required extension {ext} is not supported")));
        }
    }
    Ok(())
}

pub(super) fn untyped_json(ctx: &Ctx, root: &json::Root, json_bytes: &[u8]) -> Result<Option<Value>, SceneError> {
    if !root.extensions_used.iter().any(|e| UNTYPED_EXTENSIONS.contains(&e.as_str())) {
        return Ok(None);
    }
    serde_json::from_slice(json_bytes).map(Some).map_err(|e| ctx.err(format!("malformed glTF JSON: {e}")))
}

// ---------------------------------------------------------------------------------------------
// URIs and files.

/// Reads a file, refusing it if it is larger than `max_buffer_bytes`.
pub(super) fn read_file(ctx: &Ctx, file: &Path, what: &str) -> Result<Vec<u8>, SceneError> {
    let cannot = |e: std::io::Error| ctx.err(format!("{what}: cannot read {}: {e}", file.display()));
    let len = std::fs::metadata(file).map_err(cannot)?.len();
    ctx.check(&format!("{what}: size of {}", file.display()), "max_buffer_bytes", len, ctx.limits().max_buffer_bytes)?;
    std::fs::read(file).map_err(cannot)
}

/// The bytes a buffer or image URI refers to.
pub(super) fn load_uri(ctx: &Ctx, uri: &str, path: &str) -> Result<Vec<u8>, SceneError> {
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
pub(super) const BASE64: base64::engine::GeneralPurpose = base64::engine::GeneralPurpose::new(
    &base64::alphabet::STANDARD,
    base64::engine::GeneralPurposeConfig::new()
        .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
);

/// Decodes the part of a `data:` URI after the scheme: `[<media type>];base64,<data>`.
pub(super) fn decode_data_uri(ctx: &Ctx, data: &str, path: &str) -> Result<Vec<u8>, SceneError> {
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
pub(super) fn resolve_uri(ctx: &Ctx, uri: &str, path: &str) -> Result<PathBuf, SceneError> {
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

pub(super) fn outside_error(ctx: &Ctx, uri: &str, path: &str, dir: &Path) -> SceneError {
    ctx.err(format!(
        "{path}: URI '{uri}' refers to a file outside the scene folder {}; \
         pass --allow-outside-uris to allow it",
        dir.display()
    ))
}

/// True for `scheme:...` URIs (RFC 3986: a letter, then letters, digits, '+', '-' or '.').
pub(super) fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else {
        return false;
    };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
}

/// Decodes `%XX` escapes; `None` for a malformed escape or a result that is not UTF-8.
pub(super) fn percent_decode(s: &str) -> Option<String> {
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
