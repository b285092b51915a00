//! Meshes: primitives to triangle lists, vertex attributes, morph targets, the shading frame
//! (MikkTSpace tangents where the file has none) and per-scene vertex and triangle budgets.

use super::accessors::{read_floats, read_indices};
use super::skins::PrimitiveInfluences;
use super::{Builder, MATERIALS, MESHES, lookup, lookup_or_warn};
use crate::scene::{Material, Mesh, Morph, MorphTarget, SceneError, Vertex, tangents};
use glam::Vec3;
use gltf::json;
use gltf::json::validation::Checked;

// ---------------------------------------------------------------------------------------------
// Meshes.

/// A primitive as loaded: its mesh, morph targets (empty when it has none) and joint
/// influences (`None` when it has none).
type Primitive = (Mesh, Vec<MorphTarget>, Option<PrimitiveInfluences>);

impl Builder<'_> {
    /// The `Scene::meshes` indices of a glTF mesh's primitives, built on first use so that
    /// every node referring to the mesh shares them.
    pub(super) fn mesh(&mut self, index: usize, path: &str) -> Result<Vec<Option<u32>>, SceneError> {
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
                Some((m, targets, influences)) => {
                    self.scene.meshes.push(m);
                    let id = (self.scene.meshes.len() - 1) as u32;
                    if let Some(influences) = influences {
                        self.skin_influences.insert(id, influences);
                    }
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

    /// One primitive as a mesh, with its morph targets (empty when it has none) and joint
    /// influences; `None` (with a warning) for primitives that draw no triangles.
    pub(super) fn primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        path: &str,
        name: String,
    ) -> Result<Option<Primitive>, SceneError> {
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
        let mut influences = self.influences(prim, path, vertices.len())?;
        let material = self.primitive_material(prim, path);
        let file_vertices = vertices.len();
        // Flat normals give every triangle corner a vertex of its own, a copy of the file's
        // vertex its index named: the joint influences follow that map.
        let corner_sources = (!present.normals && influences.is_some()).then(|| indices.clone());
        self.shading_frame(&mut vertices, &mut indices, present, material, path)?;
        if let (Some(sources), Some(read)) = (&corner_sources, &mut influences)
            && vertices.len() == sources.len()
        {
            let by_file_vertex = std::mem::take(&mut read.influences);
            read.influences =
                sources.iter().map(|&i| by_file_vertex.get(i as usize).copied().unwrap_or_default()).collect();
        }
        if !targets.is_empty() && vertices.len() != file_vertices {
            // Generated flat normals or tangent seams split vertices; the deltas no longer
            // line up with them.
            self.ctx.warn(format!(
                "{path}: morph targets on a primitive without NORMAL, or whose tangents are generated \
                 with seams, are not supported; the mesh is drawn in its base shape"
            ));
            targets.clear();
        }
        if influences.as_ref().is_some_and(|r| r.influences.len() != vertices.len()) {
            self.ctx.warn(format!(
                "{path}: skinning a primitive whose tangents are generated with seams is not supported; \
                 the mesh is drawn in its bind pose"
            ));
            influences = None;
        }
        let (mut bounds_min, mut bounds_max) = bounds(&vertices);
        // The bounds cover the targets at any weights in [0, 1] (framing and culling use
        // them); weights outside that range can leave them.
        for t in &targets {
            let (lo, hi) = t.positions.iter().fold((Vec3::ZERO, Vec3::ZERO), |(lo, hi), d| (lo.min(*d), hi.max(*d)));
            (bounds_min, bounds_max) = (bounds_min + lo, bounds_max + hi);
        }
        Ok(Some((Mesh { name, vertices, indices, material, bounds_min, bounds_max }, targets, influences)))
    }

    /// The primitive's morph targets: POSITION and NORMAL deltas, one per vertex. TANGENT
    /// deltas are ignored (with a warning): tangents keep their base direction.
    pub(super) fn morph_targets(
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
    pub(super) fn morph_deltas(
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
    pub(super) fn vertex_attributes(
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
    pub(super) fn shading_frame(
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

    pub(super) fn triangle_mode(&mut self, prim: &json::mesh::Primitive, path: &str) -> Option<json::mesh::Mode> {
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
    pub(super) fn positions(&mut self, accessor: usize, path: &str) -> Result<Vec<Vertex>, SceneError> {
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
    pub(super) fn count_vertices(&mut self, added: u64, removed: u64, path: &str) -> Result<(), SceneError> {
        self.total_vertices = (self.total_vertices + added).saturating_sub(removed);
        let limit = self.ctx.limits().max_vertices;
        self.ctx.check(&format!("{path}: vertices in the scene so far"), "max_vertices", self.total_vertices, limit)
    }

    /// A vertex attribute other than POSITION, if present; it must have one element per
    /// vertex. Non-finite values become 0 with a warning: they would poison shading.
    pub(super) fn attribute<const N: usize>(
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
    pub(super) fn triangles(
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

    pub(super) fn primitive_material(&mut self, prim: &json::mesh::Primitive, path: &str) -> u32 {
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
    pub(super) fn default_material(&mut self) -> u32 {
        *self.default_material.get_or_insert_with(|| {
            self.scene.materials.push(Material::default());
            (self.scene.materials.len() - 1) as u32
        })
    }

    /// MikkTSpace tangents where the material has a normal texture (and the UVs it reads);
    /// otherwise an arbitrary frame, since nothing reads the tangent's direction.
    pub(super) fn generate_tangents(
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
pub(super) struct Present {
    pub(super) normals: bool,
    pub(super) tangents: bool,
    pub(super) uv: [bool; 2],
}

/// Strips and fans as triangle lists, winding preserved (glTF spec, section 3.7.2.1).
pub(super) fn triangle_list(mode: json::mesh::Mode, mut indices: Vec<u32>) -> Vec<u32> {
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

pub(super) fn bounds(vertices: &[Vertex]) -> (Vec3, Vec3) {
    let init = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    vertices.iter().fold(init, |(lo, hi), v| {
        let p = Vec3::from(v.position);
        (lo.min(p), hi.max(p))
    })
}
