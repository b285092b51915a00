//! Images: encoded bytes located, their size checked against the limits before decoding, and
//! decoded in parallel; an undecodable image loads as missing with a warning.

use super::Ctx;
use super::accessors::{Data, view_bytes};
use super::container::load_uri;
use crate::scene::limits::Limits;
use crate::scene::{Image, SceneError};
use gltf::json;
use std::borrow::Cow;
use std::io::Cursor;
use std::sync::atomic::{AtomicUsize, Ordering};

// ---------------------------------------------------------------------------------------------
// Images.

/// An image's encoded bytes, ready to decode.
pub(super) struct Encoded<'d> {
    pub(super) name: String,
    pub(super) bytes: Cow<'d, [u8]>,
    pub(super) mime: Option<&'d str>,
}

pub(super) fn load_images(ctx: &Ctx, data: &Data) -> Result<Vec<Image>, SceneError> {
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

pub(super) fn encoded_image<'d>(
    ctx: &Ctx,
    data: &Data<'d>,
    i: usize,
    image: &'d json::Image,
) -> Result<Encoded<'d>, SceneError> {
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
pub(super) fn image_reader<'b>(item: &'b Encoded) -> Result<image::ImageReader<Cursor<&'b [u8]>>, String> {
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
pub(super) fn check_image_size(ctx: &Ctx, item: &Encoded, i: usize) -> Result<u64, SceneError> {
    let cannot = |e: String| ctx.err(format!("images[{i}] ('{}'): cannot decode: {e}", item.name));
    let (w, h) = image_reader(item).and_then(|r| r.into_dimensions().map_err(|e| e.to_string())).map_err(cannot)?;
    let max = u64::from(ctx.limits().max_texture_dimension);
    let what = format!("images[{i}] ('{}'): size {w}x{h}", item.name);
    ctx.check(&what, "max_texture_dimension", u64::from(w.max(h)), max)?;
    Ok(u64::from(w) * u64::from(h))
}

type Decoded = Result<(u32, u32, Vec<u8>), String>;

pub(super) fn decode_rgba8(item: &Encoded, limits: &Limits) -> Decoded {
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
pub(super) fn decode_in_parallel(items: &[Encoded], limits: &Limits) -> Vec<Decoded> {
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
