//! The loader's unit tests: hostile and defective files, each must give a clear error or a
//! stated fallback.

use super::container::{BASE64, GLB_CHUNK_BIN, GLB_CHUNK_JSON, has_scheme, percent_decode};
use super::*;
use crate::scene::animation::Interpolation;
use crate::scene::{AlphaMode, Filter, LightKind, Sampler, Wrap, tangents, uv_transform};
use base64::Engine;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use serde_json::Value;
use serde_json::json;
use std::io::Cursor;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
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
        ("node", |g| g.json["scenes"][0]["nodes"] = json!([4]), "scenes[0].nodes[0]: node 4 out of range (1 nodes)"),
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
        ("instances", |l| l.max_instances = 1, "instances in the scene so far: 2 exceeds the limit max_instances = 1"),
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

// ---- Skins ---------------------------------------------------------------------------------

/// A triangle skinned to two joints (nodes 1 and 2, the second a child of the first one unit
/// up), its vertices weighted (2, 2) to both, (1, 0) and (0, 1): weights are normalised on
/// load. Joint 2 turns 90 degrees about Z over the first second and holds for one more.
fn skinned_triangle() -> Gltf {
    let mut g = Gltf::triangle();
    let normals = g.float_accessor(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3", 3);
    let view = g.view(&u16s(&[0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0]));
    let joints = g.accessor(view, USHORT, 3, "VEC4");
    let weights = g.float_accessor(&[2.0, 2.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0], "VEC4", 3);
    g.primitive()["attributes"]["NORMAL"] = json!(normals);
    g.primitive()["attributes"]["JOINTS_0"] = json!(joints);
    g.primitive()["attributes"]["WEIGHTS_0"] = json!(weights);
    let up = Mat4::from_translation(Vec3::Y).inverse();
    let ibm = g.float_accessor(&[Mat4::IDENTITY.to_cols_array(), up.to_cols_array()].concat(), "MAT4", 2);
    g.push("nodes", json!({"children": [2]}));
    g.push("nodes", json!({"translation": [0.0, 1.0, 0.0]}));
    g.json["nodes"][0]["skin"] = json!(0);
    g.json["nodes"][0]["translation"] = json!([5.0, 0.0, 0.0]);
    g.json["scenes"][0]["nodes"] = json!([0, 1]);
    g.json["skins"] = json!([{"joints": [1, 2], "inverseBindMatrices": ibm}]);
    let times = g.float_accessor(&[0.0, 1.0, 2.0], "SCALAR", 3);
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let turns = g.float_accessor(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, s, s, 0.0, 0.0, s, s], "VEC4", 3);
    g.json["animations"] = json!([{"samplers": [{"input": times, "output": turns}],
        "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}]);
    g
}

#[test]
fn loads_skins_and_skins_on_the_cpu() {
    let dir = TempDir::new("skin");
    let scene = load(&skinned_triangle().write_gltf(&dir, "skin")).unwrap();
    assert_consistent(&scene);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!((scene.skins.len(), scene.skinned.len()), (1, 1));
    let skinned = &scene.skinned[0];
    let skin = &scene.skins[skinned.skin as usize];
    assert_eq!(
        skin.joints.iter().map(|&j| scene.nodes[j as usize].translation).collect::<Vec<_>>(),
        [Vec3::ZERO, Vec3::Y]
    );
    assert_eq!(skinned.influences[0].weights, [0.5, 0.5, 0.0, 0.0]);
    // At t = 1 joint 2 has turned (0, 0) about (0, 1) to (1, 1), and (0, 1) stays.
    let pose = scene.evaluate(1.0);
    let joints = skin.joint_matrices(&pose, skinned.node);
    let v = skinned.skin(&scene.meshes[skinned.mesh as usize].vertices, &joints);
    let world = |i: usize| pose.world[skinned.node as usize].transform_point3(Vec3::from(v[i].position));
    for (i, expected) in [(0, Vec3::new(0.5, 0.5, 0.0)), (1, Vec3::X), (2, Vec3::new(0.0, 1.0, 0.0))] {
        assert!((world(i) - expected).length() < 1e-5, "vertex {i}: {} vs {expected}", world(i));
    }
    // The skinned node's own translation (x = 5) is not applied: glTF ignores it.
    let bind = skinned
        .skin(&scene.meshes[skinned.mesh as usize].vertices, &skin.joint_matrices(&scene.evaluate(0.0), skinned.node));
    assert!(
        (pose.world[skinned.node as usize].transform_point3(Vec3::from(bind[1].position)) - Vec3::X).length() < 1e-5
    );
}

#[test]
fn hostile_skins_fail_with_the_field_named() {
    let cases: &[Case<Gltf>] = &[
        (
            "joint past the count",
            |g| {
                let view = g.view(&u16s(&[7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]));
                let joints = g.accessor(view, USHORT, 3, "VEC4");
                g.primitive()["attributes"]["JOINTS_0"] = json!(joints);
            },
            "attributes.JOINTS_0: vertex 0 names joint 7, but skins[0] has 2 joints",
        ),
        (
            "float joints",
            |g| {
                let joints = g.float_accessor(&[0.0; 12], "VEC4", 3);
                g.primitive()["attributes"]["JOINTS_0"] = json!(joints);
            },
            "joint indices must be unsigned",
        ),
        ("skin out of range", |g| g.json["nodes"][0]["skin"] = json!(4), "nodes[0].skin: skin 4 out of range"),
        (
            "joint not in the scene",
            |g| {
                g.push("nodes", json!({}));
                g.json["skins"][0]["joints"] = json!([1, 3]);
            },
            "skins[0].joints[1]: node 3 is not in the loaded scene",
        ),
        (
            "joint out of range",
            |g| g.json["skins"][0]["joints"] = json!([1, 9]),
            "skins[0].joints[1]: node 9 out of range",
        ),
        (
            "too few inverse bind matrices",
            |g| {
                let one = g.float_accessor(&Mat4::IDENTITY.to_cols_array(), "MAT4", 1);
                g.json["skins"][0]["inverseBindMatrices"] = json!(one);
            },
            "inverseBindMatrices: 1 matrices for 2 joints",
        ),
        (
            "NaN inverse bind matrix",
            |g| {
                let bad = g.float_accessor(&[[f32::NAN; 16], Mat4::IDENTITY.to_cols_array()].concat(), "MAT4", 2);
                g.json["skins"][0]["inverseBindMatrices"] = json!(bad);
            },
            "inverseBindMatrices: matrix 0 is not finite",
        ),
        ("skeleton cycle", |g| g.json["nodes"][2]["children"] = json!([1]), "node cycle"),
        ("no joints", |g| g.json["skins"][0]["joints"] = json!([]), "skins[0].joints: a skin needs at least one joint"),
    ];
    let dir = TempDir::new("hostile-skins");
    for (name, change, needle) in cases {
        let mut g = skinned_triangle();
        change(&mut g);
        let path = g.write_gltf(&dir, &name.replace(' ', "-"));
        assert_error(load(&path), &path, &[needle]);
    }
    // More joints than the limit allows.
    let path = skinned_triangle().write_gltf(&dir, "joints-limit");
    assert_error(load_with(&path, |o| o.limits.max_joints = 1), &path, &["max_joints", "--max-joints"]);
}

#[test]
fn unusable_weights_fall_back_with_a_warning() {
    let mut g = skinned_triangle();
    let weights = g.float_accessor(&[f32::NAN, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0], "VEC4", 3);
    g.primitive()["attributes"]["WEIGHTS_0"] = json!(weights);
    let dir = TempDir::new("weights");
    let scene = load(&g.write_gltf(&dir, "weights")).unwrap();
    assert_warning(&scene, "WEIGHTS_0: non-finite or negative weights count as 0");
    assert_warning(&scene, "WEIGHTS_0: 2 vertices have no weight; they keep their bind-pose place");
    let skinned = &scene.skinned[0];
    assert_eq!(skinned.influences[0].weights, [0.0, 1.0, 0.0, 0.0]);
    // A weightless vertex stays where the skinned node puts it, whatever the joints do.
    let pose = scene.evaluate(1.0);
    let joints = scene.skins[0].joint_matrices(&pose, skinned.node);
    let base = &scene.meshes[skinned.mesh as usize].vertices;
    assert_eq!(skinned.skin(base, &joints)[1].position, base[1].position);
}

#[test]
fn unsupported_extensions_in_use_are_named_once() {
    let mut g = Gltf::triangle();
    g.json["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_materials_clearcoat", "KHR_materials_sheen"]);
    g.json["materials"] = json!([{"extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0}}}]);
    g.primitive()["material"] = json!(0);
    let dir = TempDir::new("extensions");
    let scene = load(&g.write_gltf(&dir, "extensions")).unwrap();
    assert_warning(&scene, "extensionsUsed[1]: KHR_materials_clearcoat is not supported");
    assert_warning(&scene, "extensionsUsed[2]: KHR_materials_sheen is not supported");
    assert!(scene.warnings.iter().all(|w| !w.contains("KHR_lights_punctual")), "{:?}", scene.warnings);
}

#[test]
fn transmission_ior_and_volume_load_and_bad_values_fall_back() {
    let mut g = Gltf::triangle();
    g.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]);
    let png = g.view(&png_2x2([255, 0, 0, 255]));
    g.json["images"] = json!([{"bufferView": png, "mimeType": "image/png"}]);
    g.json["textures"] = json!([{"source": 0}]);
    g.json["materials"] = json!([
        {"extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 0.75, "transmissionTexture": {"index": 0, "texCoord": 1}},
            "KHR_materials_ior": {"ior": 1.33},
            "KHR_materials_volume": {"thicknessFactor": 0.2, "attenuationDistance": 2.0, "attenuationColor": [1.0, 0.5, 0.25]},
        }},
        {"extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 3.0, "transmissionTexture": {"index": 7}},
            "KHR_materials_ior": {"ior": 0.5},
            "KHR_materials_volume": {"thicknessFactor": -1.0, "attenuationDistance": 0.0},
        }},
    ]);
    g.primitive()["material"] = json!(0);
    let dir = TempDir::new("transmission");
    let scene = load(&g.write_gltf(&dir, "transmission")).unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.transmission, m.ior, m.thickness, m.attenuation_distance), (0.75, 1.33, 0.2, 2.0));
    assert_eq!(m.attenuation_color, Vec3::new(1.0, 0.5, 0.25));
    assert!(m.is_transmissive());
    let texture = m.transmission_texture.expect("transmissionTexture is read");
    assert_eq!((texture.texture, texture.uv_set), (0, 1));
    let bad = &scene.materials[1];
    assert_eq!((bad.transmission, bad.ior, bad.thickness, bad.attenuation_distance), (0.0, 1.5, 0.0, f32::INFINITY));
    assert_warning(
        &scene,
        "materials[1].extensions.KHR_materials_transmission.transmissionFactor: 3 is outside [0, 1]",
    );
    assert_eq!(bad.transmission_texture, None);
    assert_warning(&scene, "materials[1].extensions.KHR_materials_transmission.transmissionTexture.index");
    assert_warning(&scene, "materials[1].extensions.KHR_materials_ior.ior: 0.5 is below 1");
    assert_warning(&scene, "KHR_materials_volume.thicknessFactor: -1 is negative");
    assert_warning(&scene, "KHR_materials_volume.attenuationDistance: 0 is not positive");
}
