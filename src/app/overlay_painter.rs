//! The egui side of the overlay: a frame of egui output (tessellated meshes, texture changes,
//! scale) turned into the plain textured triangles the presenter draws (`gpu::Overlay`). The
//! meshes go into one vertex and one index list, each keeping its clip rectangle and texture;
//! egui's own callbacks (custom painting) are not used by the viewer and are left out.

use crate::gpu::{Overlay, OverlayDraw, OverlayTextureId, OverlayTextureUpdate, OverlayVertex};

/// One frame of the overlay, owning what `gpu::Overlay` borrows (texels stay in egui's delta).
pub struct OverlayFrame<'a> {
    vertices: Vec<OverlayVertex>,
    indices: Vec<u32>,
    draws: Vec<OverlayDraw>,
    textures: Vec<OverlayTextureUpdate<'a>>,
    freed: Vec<OverlayTextureId>,
    pixels_per_point: f32,
}

impl<'a> OverlayFrame<'a> {
    pub fn new(primitives: &[egui::ClippedPrimitive], delta: &'a egui::TexturesDelta, pixels_per_point: f32) -> Self {
        let mut frame = Self {
            vertices: Vec::new(),
            indices: Vec::new(),
            draws: Vec::new(),
            textures: delta.set.iter().map(|(id, d)| texture_update(*id, d)).collect(),
            freed: delta.free.iter().map(|&id| texture_id(id)).collect(),
            pixels_per_point,
        };
        for p in primitives {
            let egui::epaint::Primitive::Mesh(mesh) = &p.primitive else { continue };
            if mesh.indices.is_empty() {
                continue;
            }
            let r = p.clip_rect;
            frame.draws.push(OverlayDraw {
                clip: [r.min.x, r.min.y, r.max.x, r.max.y],
                texture: texture_id(mesh.texture_id),
                first_index: frame.indices.len() as u32,
                index_count: mesh.indices.len() as u32,
                vertex_offset: frame.vertices.len() as u32,
            });
            frame.indices.extend_from_slice(&mesh.indices);
            frame.vertices.extend(mesh.vertices.iter().map(|v| OverlayVertex {
                pos: [v.pos.x, v.pos.y],
                uv: [v.uv.x, v.uv.y],
                color: v.color.to_array(),
            }));
        }
        frame
    }

    /// What the presenter draws; egui's points are the overlay's units.
    pub fn overlay(&self) -> Overlay<'_> {
        Overlay {
            vertices: &self.vertices,
            indices: &self.indices,
            draws: &self.draws,
            textures: &self.textures,
            freed: &self.freed,
            pixels_per_unit: self.pixels_per_point,
        }
    }
}

/// egui's two id spaces (its own textures and the application's) kept apart in one number.
fn texture_id(id: egui::TextureId) -> OverlayTextureId {
    match id {
        egui::TextureId::Managed(n) => OverlayTextureId(n << 1),
        egui::TextureId::User(n) => OverlayTextureId((n << 1) | 1),
    }
}

fn texture_update(id: egui::TextureId, d: &egui::epaint::ImageDelta) -> OverlayTextureUpdate<'_> {
    let egui::ImageData::Color(img) = &d.image;
    OverlayTextureUpdate {
        id: texture_id(id),
        at: d.pos.map(|[x, y]| [x as u32, y as u32]),
        width: img.width() as u32,
        height: img.height() as u32,
        // Color32 is premultiplied RGBA8, four bytes in that order.
        texels: bytemuck::cast_slice(&img.pixels),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::epaint::{ClippedPrimitive, ImageDelta, Mesh, Primitive, Vertex};
    use egui::{Color32, Rect, TextureId, TextureOptions, pos2};
    use std::sync::Arc;

    fn mesh(texture: TextureId, vertices: usize, indices: &[u32]) -> Mesh {
        let vertices = (0..vertices)
            .map(|i| Vertex {
                pos: pos2(i as f32, 2.0 * i as f32),
                uv: pos2(0.5, 0.25),
                color: Color32::from_rgba_premultiplied(10, 20, 30, 40),
            })
            .collect();
        Mesh { indices: indices.to_vec(), vertices, texture_id: texture }
    }

    fn clipped(clip: Rect, m: Mesh) -> ClippedPrimitive {
        ClippedPrimitive { clip_rect: clip, primitive: Primitive::Mesh(m) }
    }

    #[test]
    fn meshes_become_one_list_with_a_draw_each() {
        let a = Rect::from_min_max(pos2(1.0, 2.0), pos2(30.0, 40.0));
        let b = Rect::from_min_max(pos2(0.0, 0.0), pos2(8.0, 9.0));
        let primitives = vec![
            clipped(a, mesh(TextureId::Managed(0), 3, &[0, 1, 2])),
            clipped(a, mesh(TextureId::Managed(0), 2, &[])), // nothing to draw: left out
            clipped(b, mesh(TextureId::User(7), 4, &[0, 1, 2, 2, 3, 0])),
        ];
        let delta = egui::TexturesDelta::default();
        let frame = OverlayFrame::new(&primitives, &delta, 1.5);
        let o = frame.overlay();
        o.check().expect("a consistent overlay");
        assert_eq!(o.vertices.len(), 7);
        assert_eq!(o.indices, &[0, 1, 2, 0, 1, 2, 2, 3, 0]);
        assert_eq!(o.pixels_per_unit, 1.5);
        assert_eq!(
            o.draws,
            &[
                OverlayDraw {
                    clip: [1.0, 2.0, 30.0, 40.0],
                    texture: OverlayTextureId(0),
                    first_index: 0,
                    index_count: 3,
                    vertex_offset: 0
                },
                OverlayDraw {
                    clip: [0.0, 0.0, 8.0, 9.0],
                    texture: OverlayTextureId(15),
                    first_index: 3,
                    index_count: 6,
                    vertex_offset: 3
                },
            ]
        );
        assert_eq!(o.vertices[4], OverlayVertex { pos: [1.0, 2.0], uv: [0.5, 0.25], color: [10, 20, 30, 40] });
    }

    #[test]
    fn texture_changes_pass_through() {
        let image = |w, h, c| egui::ImageData::Color(Arc::new(egui::ColorImage::filled([w, h], c)));
        let mut delta = egui::TexturesDelta::default();
        let red = Color32::from_rgb(255, 0, 0);
        delta.set.push((TextureId::Managed(0), ImageDelta::full(image(4, 2, red), TextureOptions::LINEAR)));
        delta.set.push((TextureId::Managed(0), ImageDelta::partial([1, 1], image(2, 1, red), TextureOptions::LINEAR)));
        delta.free.push(TextureId::Managed(3));
        let frame = OverlayFrame::new(&[], &delta, 1.0);
        let o = frame.overlay();
        o.check().expect("sizes match texels");
        assert_eq!(o.textures.len(), 2);
        let (full, patch) = (&o.textures[0], &o.textures[1]);
        assert_eq!((full.id, full.at, full.width, full.height), (OverlayTextureId(0), None, 4, 2));
        assert_eq!(&full.texels[..4], &[255, 0, 0, 255]);
        assert_eq!(full.texels.len(), 4 * 2 * 4);
        assert_eq!((patch.at, patch.width, patch.height, patch.texels.len()), (Some([1, 1]), 2, 1, 8));
        assert_eq!(o.freed, &[OverlayTextureId(6)]);
    }
}
