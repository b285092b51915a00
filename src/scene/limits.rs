//! Resource limits for scene loading.
//!
//! Scene files are untrusted input: a few bytes of JSON can claim gigabytes of geometry or
//! textures. The loader checks every size it is about to act on against these limits before
//! allocating, so a hostile or broken file fails with a clear error instead of exhausting
//! memory. The defaults are generous enough for any scene this renderer can reasonably draw.

use super::SceneError;
use std::path::Path;

/// Upper bounds on what one scene may contain. All limits apply per scene unless noted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Triangles over all meshes; an index accessor may hold at most 3 × this + 2 indices
    /// (default 20 M).
    pub max_triangles: u64,
    /// Vertices over all meshes, after un-welding for flat normals; also the most elements
    /// any one non-index accessor may have (default 64 M).
    pub max_vertices: u64,
    /// Width or height of any one image (default 16384, the common Vulkan maximum).
    pub max_texture_dimension: u32,
    /// Texels over all images (default 512 Mi, i.e. 2 GiB of RGBA8 before mipmaps).
    pub max_texture_pixels_total: u64,
    /// Bytes of any one buffer, image file, or the scene file itself (default 512 MiB).
    pub max_buffer_bytes: u64,
    /// Bytes of all buffers and images loaded from URIs together, a file counting as often
    /// as it is referred to (default 4 GiB): without it, a file listing one big neighbour
    /// as a buffer a thousand times would need a thousand copies of it.
    pub max_total_bytes: u64,
    /// Depth of the node hierarchy, roots at depth 1 (default 64).
    pub max_node_depth: u32,
    /// Nodes, including those created for GPU-instanced copies (default 1 M).
    pub max_nodes: u32,
    /// Encoded length of any one `data:` URI (default 256 MiB).
    pub max_data_uri_bytes: u64,
    /// Mesh instances, one per primitive of every node that draws a mesh, GPU-instanced
    /// copies included (default 4 M). Nodes times primitives: a small file could ask for
    /// billions.
    pub max_instances: u64,
    /// Keyframe times and values over all animation channels (default 16 M). Channels may
    /// share accessors, so their total is not bounded by the size of any one of them.
    pub max_animation_keys: u64,
    /// Joints over all skins (default 65 536). Each joint's matrices are rewritten for the GPU
    /// every animated frame, and a skin must fit one storage buffer.
    pub max_joints: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_triangles: 20_000_000,
            max_vertices: 64_000_000,
            max_texture_dimension: 16384,
            max_texture_pixels_total: 512 << 20,
            max_buffer_bytes: 512 << 20,
            max_total_bytes: 4 << 30,
            max_node_depth: 64,
            max_nodes: 1_000_000,
            max_data_uri_bytes: 256 << 20,
            max_instances: 4_000_000,
            max_animation_keys: 16_000_000,
            max_joints: 65_536,
        }
    }
}

/// The command-line flag that sets each limit (`hybrid-rt render --help` lists them): an
/// exceeded limit names its flag, so the user learns what to raise without reading the source.
pub const FLAGS: [(&str, &str); 12] = [
    ("max_triangles", "--max-triangles"),
    ("max_vertices", "--max-vertices"),
    ("max_texture_dimension", "--max-texture-size"),
    ("max_texture_pixels_total", "--max-texture-pixels"),
    ("max_buffer_bytes", "--max-buffer-mib"),
    ("max_total_bytes", "--max-total-mib"),
    ("max_node_depth", "--max-node-depth"),
    ("max_nodes", "--max-nodes"),
    ("max_data_uri_bytes", "--max-data-uri-mib"),
    ("max_instances", "--max-instances"),
    ("max_animation_keys", "--max-animation-keys"),
    ("max_joints", "--max-joints"),
];

/// Fails with an error naming the file, what was measured, the limit, both values and the
/// flag that raises the limit when `value` exceeds `limit`. `limit_name` is a field of
/// [`Limits`], or an expression in one (`3 * max_triangles + 2`).
pub fn check_limit(file: &Path, what: &str, limit_name: &str, value: u64, limit: u64) -> Result<(), SceneError> {
    if value > limit {
        let mut problem = format!("{what}: {value} exceeds the limit {limit_name} = {limit}");
        if let Some((_, flag)) = FLAGS.iter().find(|(field, _)| limit_name.contains(field)) {
            problem.push_str(&format!(" (raise it with {flag})"));
        }
        return Err(SceneError::new(file, problem));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_generous() {
        let l = Limits::default();
        assert_eq!(l.max_triangles, 20_000_000);
        assert_eq!(l.max_texture_dimension, 16384);
        assert_eq!(l.max_buffer_bytes, 512 * 1024 * 1024);
        assert_eq!(l.max_total_bytes, 4 * 1024 * 1024 * 1024);
        assert_eq!(l.max_node_depth, 64);
        assert_eq!(l.max_nodes, 1_000_000);
        assert_eq!(l.max_data_uri_bytes, 256 * 1024 * 1024);
        assert_eq!(l.max_instances, 4_000_000);
        assert_eq!(l.max_animation_keys, 16_000_000);
    }

    #[test]
    fn check_limit_names_everything() {
        let file = Path::new("/tmp/scene.gltf");
        assert!(check_limit(file, "triangles", "max_triangles", 10, 10).is_ok());
        let err = check_limit(file, "triangles", "max_triangles", 11, 10).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("/tmp/scene.gltf"), "{msg}");
        assert!(msg.contains("max_triangles"), "{msg}");
        assert!(msg.contains("11"), "{msg}");
        assert!(msg.contains("= 10"), "{msg}");
        assert!(msg.contains("(raise it with --max-triangles)"), "{msg}");
        let indices = check_limit(file, "indices", "3 * max_triangles + 2", 6, 5).unwrap_err().to_string();
        assert!(indices.contains("--max-triangles"), "{indices}");
    }
}
