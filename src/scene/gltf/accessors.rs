//! Buffers, buffer views and accessors: every byte range, stride, component type and sparse
//! substitution is checked before anything is read or allocated from it.

use super::container::load_uri;
use super::{ACCESSORS, BUFFER_VIEWS, BUFFERS, Ctx, lookup, to_usize};
use crate::scene::SceneError;
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use serde_json::Value;
use std::borrow::Cow;

// ---------------------------------------------------------------------------------------------
// Buffers and accessors.

/// The parsed file: typed JSON, untyped JSON where needed, and the bytes of every buffer.
pub(super) struct Data<'a> {
    pub(super) root: &'a json::Root,
    pub(super) buffers: &'a [Cow<'a, [u8]>],
    pub(super) untyped: Option<&'a Value>,
}

pub(super) fn load_buffers<'f>(
    ctx: &Ctx,
    root: &json::Root,
    bin: Option<&'f [u8]>,
) -> Result<Vec<Cow<'f, [u8]>>, SceneError> {
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
pub(super) fn view_bytes<'d>(ctx: &Ctx, data: &Data<'d>, index: usize, path: &str) -> Result<&'d [u8], SceneError> {
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
pub(super) struct Format {
    pub(super) component: ComponentType,
    pub(super) components: usize,
    pub(super) normalized: bool,
}

impl Format {
    pub(super) fn element_size(self) -> usize {
        self.component.size() * self.components
    }
}

/// Accessor elements in a buffer view: element `i` starts at `i * stride` in `bytes`.
pub(super) struct Strided<'d> {
    pub(super) bytes: &'d [u8],
    pub(super) stride: usize,
    pub(super) count: usize,
    pub(super) format: Format,
}

impl<'d> Strided<'d> {
    pub(super) fn element(&self, i: usize) -> Option<&'d [u8]> {
        let start = i.checked_mul(self.stride)?;
        self.bytes.get(start..start.checked_add(self.format.element_size())?)
    }
}

/// Where an accessor's (or sparse part's) elements lie.
pub(super) struct Placement {
    pub(super) view: usize,
    pub(super) byte_offset: u64,
    pub(super) count: u64,
    /// The view's byteStride applies to accessors, never to sparse indices and values.
    pub(super) use_view_stride: bool,
}

pub(super) fn strided<'d>(
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

pub(super) fn type_name(ty: Type) -> &'static str {
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

pub(super) fn accessor_format(
    ctx: &Ctx,
    acc: &json::Accessor,
    expected: Type,
    path: &str,
) -> Result<Format, SceneError> {
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
pub(super) fn read_accessor<T: Copy>(
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

pub(super) fn decode_all<T>(
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

pub(super) fn apply_sparse<T>(
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

pub(super) fn le_bytes<const K: usize>(bytes: &[u8]) -> [u8; K] {
    bytes.try_into().unwrap_or([0; K])
}

/// Component `c` of an element as a float, normalised integers mapped to [0, 1] or [-1, 1].
pub(super) fn component_f32(format: Format, bytes: &[u8], c: usize) -> f32 {
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

pub(super) fn decode_f32<const N: usize>(format: Format, bytes: &[u8]) -> [f32; N] {
    std::array::from_fn(|c| component_f32(format, bytes, c))
}

/// An unsigned integer element (indices); other component types read as 0, and callers
/// check the type first.
pub(super) fn decode_u32(format: Format, bytes: &[u8]) -> u32 {
    match format.component {
        ComponentType::U8 => u32::from(u8::from_le_bytes(le_bytes(bytes))),
        ComponentType::U16 => u32::from(u16::from_le_bytes(le_bytes(bytes))),
        ComponentType::U32 => u32::from_le_bytes(le_bytes(bytes)),
        _ => 0,
    }
}

pub(super) fn expected_type<const N: usize>() -> Type {
    match N {
        1 => Type::Scalar,
        2 => Type::Vec2,
        3 => Type::Vec3,
        _ => Type::Vec4,
    }
}

/// Reads an accessor of N-component vectors (N = 1 to 4) as floats. `max_vertices` caps
/// every such accessor, vertex attribute or not: it is the scene's largest per-element count.
pub(super) fn read_floats<const N: usize>(
    ctx: &Ctx,
    data: &Data,
    index: usize,
    path: &str,
) -> Result<Vec<[f32; N]>, SceneError> {
    let limit = ("max_vertices", ctx.limits().max_vertices);
    let accessor = (index, expected_type::<N>());
    read_accessor(ctx, data, accessor, path, limit, decode_f32::<N>)
}

pub(super) fn read_indices(ctx: &Ctx, data: &Data, index: usize, path: &str) -> Result<Vec<u32>, SceneError> {
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
