//! Textures, samplers and metallic-roughness materials, with the texture transforms and
//! alpha modes they use.

use super::{Builder, IMAGES, SAMPLERS, TEXTURES, lookup_or_warn};
use crate::scene::{AlphaMode, Filter, Material, Sampler, Texture, TextureRef, Wrap, uv_transform};
use glam::{Mat3, Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::validation::Checked;
use serde_json::Value;

// ---------------------------------------------------------------------------------------------
// Textures and materials.

impl Builder<'_> {
    pub(super) fn textures(&mut self) -> Vec<Texture> {
        let root = self.data.root;
        let mut textures = Vec::with_capacity(root.textures.len());
        for (i, texture) in root.textures.iter().enumerate() {
            let image = self.texture_image(i, texture);
            let sampler = self.texture_sampler(i, texture);
            textures.push(Texture { image, sampler });
        }
        textures
    }

    pub(super) fn texture_image(&mut self, i: usize, texture: &json::Texture) -> Option<u32> {
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

    pub(super) fn texture_sampler(&mut self, i: usize, texture: &json::Texture) -> Sampler {
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

    pub(super) fn materials(&mut self) -> Vec<Material> {
        let root = self.data.root;
        root.materials.iter().enumerate().map(|(i, m)| self.material(i, m)).collect()
    }

    pub(super) fn material(&mut self, i: usize, m: &json::Material) -> Material {
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
            ..self.transmission(i, m)
        }
    }

    /// KHR_materials_transmission (factor and texture), _ior and _volume, on an otherwise default
    /// material. The volume's thicknessTexture is not read (with a warning): it stands in
    /// for the distance a ray travels through the volume, and every pass here traces that
    /// distance instead (the extension's own advice to ray tracers).
    pub(super) fn transmission(&mut self, i: usize, m: &json::Material) -> Material {
        let mut out = Material::default();
        let Some(ext) = m.extensions.as_ref() else {
            return out;
        };
        let path = format!("materials[{i}].extensions");
        let finite_in = |x: f32, lo: f32, hi: f32| x.is_finite() && (lo..=hi).contains(&x);
        if let Some(t) = &ext.transmission {
            let factor = t.transmission_factor.0;
            if finite_in(factor, 0.0, 1.0) {
                out.transmission = factor;
            } else {
                self.ctx.warn(format!(
                    "{path}.KHR_materials_transmission.transmissionFactor: {factor} is outside [0, 1]; using 0"
                ));
            }
            let info = t.transmission_texture.as_ref().map(|t| (t.index.value(), t.tex_coord));
            out.transmission_texture =
                self.texture_ref(i, "extensions/KHR_materials_transmission/transmissionTexture", info);
        }
        if let Some(ior) = &ext.ior {
            let value = ior.ior.0;
            if value.is_finite() && value >= 1.0 {
                out.ior = value;
            } else {
                self.ctx.warn(format!("{path}.KHR_materials_ior.ior: {value} is below 1; using 1.5"));
            }
        }
        if let Some(v) = &ext.volume {
            let (thickness, distance, color) =
                (v.thickness_factor.0, v.attenuation_distance.0, Vec3::from(v.attenuation_color.0));
            if thickness.is_finite() && thickness >= 0.0 {
                out.thickness = thickness;
            } else {
                self.ctx
                    .warn(format!("{path}.KHR_materials_volume.thicknessFactor: {thickness} is negative; thin-walled"));
            }
            if distance > 0.0 && !distance.is_nan() {
                out.attenuation_distance = distance;
            } else {
                self.ctx.warn(format!(
                    "{path}.KHR_materials_volume.attenuationDistance: {distance} is not positive; no absorption"
                ));
            }
            if color.is_finite() && color.cmpge(Vec3::ZERO).all() && color.cmple(Vec3::ONE).all() {
                out.attenuation_color = color;
            } else {
                self.ctx.warn(format!("{path}.KHR_materials_volume.attenuationColor: outside [0, 1]; white"));
            }
            if v.thickness_texture.is_some() {
                self.ctx.warn_once(
                    "thickness-texture",
                    "thicknessTexture is not read: the rays measure the volume's thickness themselves",
                );
            }
        }
        out
    }

    /// The texture slot at JSON pointer `slot` (relative to the material), given its texture
    /// index and texCoord, with KHR_texture_transform applied.
    pub(super) fn texture_ref(
        &mut self,
        material: usize,
        slot: &str,
        info: Option<(usize, u32)>,
    ) -> Option<TextureRef> {
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

    pub(super) fn alpha_mode(&mut self, i: usize, m: &json::Material) -> AlphaMode {
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
}

/// KHR_texture_transform as a matrix, and its texCoord override.
pub(super) fn texture_transform(t: &Value) -> (Mat3, Option<u32>) {
    let offset = json_vec2(t.get("offset")).unwrap_or(Vec2::ZERO);
    let rotation = t.get("rotation").and_then(Value::as_f64).unwrap_or(0.0) as f32;
    let scale = json_vec2(t.get("scale")).unwrap_or(Vec2::ONE);
    let tex_coord = t.get("texCoord").and_then(Value::as_u64).map(|c| u32::try_from(c).unwrap_or(u32::MAX));
    (uv_transform(offset, rotation, scale), tex_coord)
}

pub(super) fn json_vec2(value: Option<&Value>) -> Option<Vec2> {
    match value?.as_array()?.as_slice() {
        [x, y] => Some(Vec2::new(x.as_f64()? as f32, y.as_f64()? as f32)),
        _ => None,
    }
}

pub(super) fn convert_sampler(s: &json::texture::Sampler) -> Sampler {
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

pub(super) fn convert_wrap(wrap: Checked<json::texture::WrappingMode>) -> Wrap {
    use json::texture::WrappingMode;
    match wrap {
        Checked::Valid(WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
        Checked::Valid(WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    }
}
