//! A world-space grid over the resampled punctual lights (those past the shadowed ones; see
//! `lights::shading_order`), read by shaders-glsl/common/light_grid.glsl at set-0 bindings 19
//! and 20. Each cell lists the lights whose range (and, for a spot, outer cone) reaches it,
//! with a CDF over a bound of what each can deliver there; a shading point draws its
//! candidates for those lights from its cell's list instead of from all of them by power.
//!
//! Why: with many short-range lights, a point sees few of them. Drawn by power from all, most
//! candidates land on lights that are out of range, and a GI bounce's hit, which gets few
//! draws, finds a light it can use only rarely: the rare lucky samples are bright, and SVGF's
//! outlier clamp takes them for fireflies (the denoised `builtin:many-lights` was 11% dark).
//!
//! It stays unbiased: a light that is not listed in a cell is out of range or outside the cone
//! of every point of it (its range window or cone factor is exactly zero there), and a listed
//! one has a positive probability. Points outside the grid (geometry that moved past the
//! bounds it was built for) draw from all the resampled lights by power, as before. Lights
//! without a range and directional lights are listed in every cell (spots: where their cone
//! reaches).
//!
//! The grid knows distances, not walls: a room full of lights without a range is listed, and
//! drawn, in every cell of the room next door. So the hybrid frame learns what each cell sees.
//! The lights are sorted into groups by position (a [`GROUPS_PER_SIDE`]^3 grid over the same
//! bounds, and one group for directional lights); gi counts its shadow rays per cell and group
//! and how many something blocked (set-0 binding 21, [`GpuLightGridVisibility`]), and the
//! `light_grid_update` pass (src/passes/light_grid_update.rs) reweighs each entry by its
//! group's visibility from the cell before the next frame draws from it. A group pools the rays
//! of its lights, since one light among hundreds is drawn too rarely to be learned alone. A
//! listed light keeps at least a hundredth of its bound, so the choice stays unbiased. The
//! emissive triangles are not listed, but a shadow ray toward one counts in the group of the
//! region its sampled point lies in ([`group_at`]), and their resampling targets take that
//! group's factor. They are sorted into the groups by their centroids ([`emitter_groups`],
//! set-0 binding 22), and `light_grid_update` builds per cell a CDF over the groups by power x
//! visibility, from which gi draws an emitter candidate's group (then a triangle of it by
//! power): candidates go to the emitters a cell sees. A scene whose only resampled lights are
//! emitters gets a grid of empty cells for it ([`LightGrid::cells_only`]).

use super::scene_gpu::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_SPOT};
use bytemuck::{Pod, Zeroable};
use glam::{UVec3, Vec3};
use std::f32::consts::PI;

/// Cells along the longest side of the scene's bounds; the other sides get as many cells of
/// the same size as they need. Mirrors nothing in GLSL (the header carries the sizes).
pub const RESOLUTION: u32 = 16;

/// Light groups along each side of the bounds: a group's lights share one visibility estimate
/// per cell. Coarse, so that each group's estimate gets rays enough to learn from.
pub const GROUPS_PER_SIDE: u32 = 4;
/// The groups by position, then the directional lights' own.
pub const GROUP_COUNT: u32 = GROUPS_PER_SIDE * GROUPS_PER_SIDE * GROUPS_PER_SIDE + 1;

/// The most entries a grid may hold (40 MB): past it, a coarser grid. A scene of a few thousand
/// lights without a range would otherwise list every one of them in each of 4096 cells.
pub const MAX_ENTRIES: usize = 1 << 21;

/// Mirrors `LightGridHeader` in common/light_grid.glsl (scalar layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLightGridHeader {
    pub lo: [f32; 3],
    /// 0: no grid; every point draws from all the resampled lights.
    pub cell_count: u32,
    pub inv_cell: [f32; 3],
    /// Light groups (the visibility buffer holds `cell_count x group_count` estimates).
    pub group_count: u32,
    pub dims: [u32; 3],
    pub pad1: u32,
}

/// Mirrors `LightGridEntry`: one light of a cell, with the cell's CDF.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLightGridEntry {
    pub light: u32,
    /// Probability of choosing this entry or an earlier one of the cell (the cell's last is 1).
    pub cdf: f32,
    pub pmf: f32,
    /// The weight the CDF is built from before visibility: a bound on what the light delivers.
    pub bound: f32,
    /// The light's group (see the module's documentation).
    pub group: u32,
}

/// Mirrors `LightGridVisibility`: per cell and light group, the share of the shadow rays from
/// the cell toward the group's lights that something blocked (learned on the GPU), and the
/// frame's counts behind the next estimate. All zeros, as a fill leaves it: nothing learned,
/// every group taken as seen, which leaves the bound's CDF as it is.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLightGridVisibility {
    pub hidden: f32,
    pub rays: u32,
    pub blocked: u32,
    /// In slot j of a cell: the cell's CDF over the emitters' listed groups (power x
    /// visibility) up to the j-th ([`emitter_groups`]), written by light_grid_update; all zeros
    /// until it runs.
    pub emitters_cdf: f32,
}

/// The groups by position, those the emissive triangles are sorted into.
pub const EMITTER_GROUPS: u32 = GROUPS_PER_SIDE * GROUPS_PER_SIDE * GROUPS_PER_SIDE;

/// Mirrors `EmitterGroup` in common/light_grid.glsl: a group that holds emitters, its stretch
/// of the emitters sorted by group, and its share of their power.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEmitterGroup {
    pub first: u32,
    pub count: u32,
    pub share: f32,
    pub group: u32,
}

/// Mirrors `EmitterGroupEntry`: an emissive triangle (index into the emitters) with its
/// group's CDF by power.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEmitterGroupEntry {
    pub emitter: u32,
    pub cdf: f32,
    pub pmf: f32,
}

/// The emissive triangles (`emitters[i]`: its centroid and power) sorted into the groups of the
/// grid of `header` by their centroids: the groups that hold any, each with a CDF by power over
/// its triangles and its share of the total. gi draws an emitter candidate's group by the
/// cell's learned CDF over these groups and a triangle of it by power (common/light_grid.glsl,
/// light_grid_emitter_pick); only the groups that hold emitters are listed, so that a scene
/// with one lamp pays for one. Where a triangle spans two groups its centroid decides; the
/// probability of drawing it is the same whatever its group, so this only steers variance.
/// Nothing when nothing has power or there is no grid.
pub fn emitter_groups(
    header: &GpuLightGridHeader,
    emitters: &[(Vec3, f32)],
) -> (Vec<GpuEmitterGroup>, Vec<GpuEmitterGroupEntry>) {
    let clean = |p: f32| if p.is_finite() && p > 0.0 { p as f64 } else { 0.0 };
    let total: f64 = emitters.iter().map(|e| clean(e.1)).sum();
    if total <= 0.0 || header.cell_count == 0 {
        return (Vec::new(), Vec::new());
    }
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); EMITTER_GROUPS as usize];
    for (i, &(centroid, power)) in emitters.iter().enumerate() {
        if clean(power) > 0.0 {
            members[group_at(header, centroid) as usize].push(i as u32);
        }
    }
    let (mut groups, mut entries) = (Vec::new(), Vec::new());
    for (group, list) in members.iter().enumerate().filter(|(_, list)| !list.is_empty()) {
        let power: f64 = list.iter().map(|&i| clean(emitters[i as usize].1)).sum();
        groups.push(GpuEmitterGroup {
            first: entries.len() as u32,
            count: list.len() as u32,
            share: (power / total) as f32,
            group: group as u32,
        });
        let mut acc = 0.0f64;
        for (k, &i) in list.iter().enumerate() {
            let p = clean(emitters[i as usize].1);
            acc += p;
            let cdf = if k + 1 == list.len() { 1.0 } else { (acc / power) as f32 };
            entries.push(GpuEmitterGroupEntry { emitter: i, cdf, pmf: (p / power) as f32 });
        }
    }
    (groups, entries)
}

/// A built grid: the header, per cell (first entry, entry count), and the entries.
#[derive(Clone, Debug, Default)]
pub struct LightGrid {
    pub header: GpuLightGridHeader,
    pub cells: Vec<[u32; 2]>,
    pub entries: Vec<GpuLightGridEntry>,
}

impl LightGrid {
    /// The grid over lights `first..` of `lights` (`powers[i]`: light i's selection power, as
    /// in the light table) within `bounds`, `resolution` cells along its longest side; None
    /// when it would hold more than `capacity` entries (found out before they are all made).
    /// Empty (no cells) when no light is resampled or the bounds are degenerate.
    fn build(
        lights: &[GpuLight],
        powers: &[f32],
        first: usize,
        bounds: (Vec3, Vec3),
        resolution: u32,
        capacity: usize,
    ) -> Option<Self> {
        if lights.len() <= first {
            return Some(Self::default());
        }
        let Some(layout) = Layout::over(bounds, resolution) else {
            return Some(Self::default());
        };
        let header = layout.header();
        let Layout { lo, size, dims } = layout;
        let extent = size * dims.as_vec3();
        let cell_count = (dims.x * dims.y * dims.z) as usize;
        let scene_radius = 0.5 * extent.length();
        let half_diagonal_sq = (0.5 * size).length_squared();

        // Per cell, the listed lights and their weights: each light visits only the cells its
        // range reaches.
        let mut lists: Vec<Vec<(u32, f32)>> = vec![Vec::new(); cell_count];
        let mut listed = 0usize;
        for (i, light) in lights.iter().enumerate().skip(first) {
            let power = powers.get(i).copied().unwrap_or(0.0);
            if !(power.is_finite() && power > 0.0) {
                continue;
            }
            let reach = light_reach(light);
            let (c0, c1) = if reach.is_finite() {
                let p = Vec3::from(light.position);
                let cell_of = |q: Vec3| ((q - lo) / size).floor().clamp(Vec3::ZERO, (dims - 1).as_vec3()).as_uvec3();
                (cell_of(p - reach), cell_of(p + reach))
            } else {
                (UVec3::ZERO, dims - 1)
            };
            for z in c0.z..=c1.z {
                for y in c0.y..=c1.y {
                    for x in c0.x..=c1.x {
                        let cell_lo = lo + UVec3::new(x, y, z).as_vec3() * size;
                        if let Some(w) =
                            cell_weight(light, power, (cell_lo, cell_lo + size), half_diagonal_sq, scene_radius)
                        {
                            lists[((z * dims.y + y) * dims.x + x) as usize].push((i as u32, w));
                            listed += 1;
                            if listed > capacity {
                                return None;
                            }
                        }
                    }
                }
            }
        }

        let group_of = |light: &GpuLight| {
            if light.kind == LIGHT_DIRECTIONAL {
                GROUP_COUNT - 1
            } else {
                group_at(&header, Vec3::from(light.position))
            }
        };
        let mut cells = Vec::with_capacity(cell_count);
        let mut entries = Vec::new();
        for list in &lists {
            let total: f64 = list.iter().map(|&(_, w)| w as f64).sum();
            cells.push([entries.len() as u32, list.len() as u32]);
            let mut acc = 0.0f64;
            for (k, &(light, w)) in list.iter().enumerate() {
                acc += w as f64;
                let cdf = if k + 1 == list.len() { 1.0 } else { (acc / total) as f32 };
                let group = group_of(&lights[light as usize]);
                entries.push(GpuLightGridEntry { light, cdf, pmf: (w as f64 / total) as f32, bound: w, group });
            }
        }
        Some(Self { header, cells, entries })
    }

    /// A grid whose cells list no light, at `resolution` over `bounds`: where no punctual light
    /// is resampled but emissive triangles are, the cells and groups are still where gi learns
    /// what each cell sees of them (common/light_grid.glsl, light_grid_learn_point). Empty when
    /// the bounds are degenerate.
    pub fn cells_only(bounds: (Vec3, Vec3), resolution: u32) -> Self {
        let Some(layout) = Layout::over(bounds, resolution) else {
            return Self::default();
        };
        let header = layout.header();
        let cells = vec![[0, 0]; header.cell_count as usize];
        Self { header, cells, entries: Vec::new() }
    }

    /// The grid at the finest resolution (from `resolution` down by halves) whose entries fit
    /// in `capacity`: one cell lists each light at most once, so a single cell always fits
    /// when `capacity` holds every resampled light.
    pub fn build_within(
        lights: &[GpuLight],
        powers: &[f32],
        first: usize,
        bounds: (Vec3, Vec3),
        resolution: u32,
        capacity: usize,
    ) -> Self {
        let mut res = resolution.max(1);
        loop {
            let limit = if res == 1 { usize::MAX } else { capacity };
            if let Some(grid) = Self::build(lights, powers, first, bounds, res, limit) {
                return grid;
            }
            res /= 2;
        }
    }
}

/// The group of a light at `q` in the grid of `header`: the region of the bounds it lies in,
/// GROUPS_PER_SIDE to a side (directional lights have a group of their own). Computed from the
/// header alone, as light_grid_group_at in common/light_grid.glsl does for an emissive
/// triangle's point.
pub fn group_at(header: &GpuLightGridHeader, q: Vec3) -> u32 {
    let group_size = UVec3::from(header.dims).as_vec3() / (Vec3::from(header.inv_cell) * GROUPS_PER_SIDE as f32);
    let max = (GROUPS_PER_SIDE - 1) as f32;
    let g = ((q - Vec3::from(header.lo)) / group_size).floor().clamp(Vec3::ZERO, Vec3::splat(max)).as_uvec3();
    (g.z * GROUPS_PER_SIDE + g.y) * GROUPS_PER_SIDE + g.x
}

/// Where a grid's cells are: its padded lower corner, a cell's size and the cells per side.
struct Layout {
    lo: Vec3,
    size: Vec3,
    dims: UVec3,
}

impl Layout {
    /// `resolution` cells along the longest side of `bounds`, as many of the same size as the
    /// other sides need; None for degenerate bounds.
    fn over(bounds: (Vec3, Vec3), resolution: u32) -> Option<Self> {
        let (lo, hi) = bounds;
        let extent = hi - lo;
        if !extent.is_finite() || extent.max_element() <= 0.0 {
            return None;
        }
        // Padded so that points on the bounds, and the shadow rays' offset origins just off
        // them, fall inside.
        let pad = Vec3::splat(1e-3 * extent.max_element() + 1e-4);
        let (lo, hi) = (lo - pad, hi + pad);
        let extent = hi - lo;
        let cell = extent.max_element() / resolution.max(1) as f32;
        let dims = (extent / cell).ceil().as_uvec3().clamp(UVec3::ONE, UVec3::splat(resolution.max(1)));
        Some(Self { lo, size: extent / dims.as_vec3(), dims })
    }

    fn header(&self) -> GpuLightGridHeader {
        GpuLightGridHeader {
            lo: self.lo.to_array(),
            cell_count: self.dims.x * self.dims.y * self.dims.z,
            inv_cell: (1.0 / self.size).to_array(),
            group_count: GROUP_COUNT,
            dims: self.dims.to_array(),
            pad1: 0,
        }
    }
}

/// How far from its position a light can deliver anything: its range (plus its radius, which
/// moves a disk light's sample points off the centre); infinite without a range.
fn light_reach(light: &GpuLight) -> f32 {
    if light.kind == LIGHT_DIRECTIONAL || light.range <= 0.0 {
        f32::INFINITY
    } else {
        light.range + light.radius.max(0.0)
    }
}

/// The light's weight in a cell: a bound on the irradiance it can bring to the cell's nearest
/// point (intensity / d^2 for lights at a position, with d no less than the cell's half
/// diagonal; the irradiance E for a directional light), or None when its range does not reach
/// the cell. Any positive weight keeps the estimate unbiased; this one steers candidates toward
/// near and bright lights. A floor keeps a light whose window rounds to 0 at the edge drawable.
fn cell_weight(
    light: &GpuLight,
    power: f32,
    cell: (Vec3, Vec3),
    half_diagonal_sq: f32,
    scene_radius: f32,
) -> Option<f32> {
    if light.kind == LIGHT_DIRECTIONAL {
        return Some(power / (PI * scene_radius * scene_radius));
    }
    let p = Vec3::from(light.position);
    let d = (p.clamp(cell.0, cell.1) - p).length();
    let reach = light_reach(light);
    if d >= reach || (light.kind == LIGHT_SPOT && !cone_reaches(light, cell)) {
        return None;
    }
    // power / 4 pi: the point light's intensity (a spot's averaged over the sphere).
    let window = if reach.is_finite() { range_window(d - light.radius.max(0.0), light.range) } else { 1.0 };
    Some(power / (4.0 * PI) * window.max(1e-4) / (d * d).max(half_diagonal_sq))
}

/// Whether a spot's outer cone can reach a cell. A spot delivers nothing at an angle of its
/// outer cone or more from its axis (common/lights.glsl), so a cell is out of reach when its
/// centre lies further from the axis than the outer cone plus the angle the cell's bounding
/// sphere subtends from the light. That sphere is grown by the light's radius, because a disk
/// light's sample points leave its centre.
fn cone_reaches(light: &GpuLight, cell: (Vec3, Vec3)) -> bool {
    let to_cell = 0.5 * (cell.0 + cell.1) - Vec3::from(light.position);
    let spread = 0.5 * (cell.1 - cell.0).length() + light.radius.max(0.0);
    let d = to_cell.length();
    let axis = Vec3::from(light.direction).normalize_or_zero();
    if d <= spread || axis == Vec3::ZERO {
        return true;
    }
    let from_axis = (axis.dot(to_cell) / d).clamp(-1.0, 1.0).acos();
    let outer = light.cos_outer.clamp(-1.0, 1.0).acos();
    // The margin absorbs rounding in the shader's own cone test.
    from_axis - (spread / d).asin() < outer + 1e-3
}

/// common/lights.glsl's `range_window`.
pub(crate) fn range_window(dist: f32, range: f32) -> f32 {
    if range <= 0.0 {
        return 1.0;
    }
    let r = dist.max(0.0) / range;
    let w = (1.0 - r * r * r * r).clamp(0.0, 1.0);
    w * w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::scene_gpu::{LIGHT_DIRECTIONAL, LIGHT_POINT};

    fn point(position: Vec3, range: f32) -> GpuLight {
        GpuLight {
            position: position.to_array(),
            kind: LIGHT_POINT,
            direction: [0.0, 0.0, -1.0],
            range,
            intensity: [1.0; 3],
            radius: 0.0,
            cos_inner: -1.0,
            cos_outer: -1.0,
            pad: [0; 2],
        }
    }

    fn cell_of(grid: &LightGrid, p: Vec3) -> usize {
        let h = &grid.header;
        let c = ((p - Vec3::from(h.lo)) * Vec3::from(h.inv_cell)).as_uvec3();
        ((c.z * h.dims[1] + c.y) * h.dims[0] + c.x) as usize
    }

    fn listed(grid: &LightGrid, cell: usize) -> Vec<u32> {
        let [first, count] = grid.cells[cell];
        grid.entries[first as usize..(first + count) as usize].iter().map(|e| e.light).collect()
    }

    #[test]
    fn a_cell_lists_exactly_the_lights_that_reach_it() {
        let bounds = (Vec3::ZERO, Vec3::splat(16.0));
        // Lights 0 and 1 are shadowed (not in the grid); 2 reaches 1 unit, 3 has no range, 4
        // is directional, 5 has no power.
        let lights = vec![
            point(Vec3::splat(8.0), 0.0),
            point(Vec3::splat(8.0), 0.0),
            point(Vec3::new(2.5, 2.5, 2.5), 1.0),
            point(Vec3::new(12.0, 12.0, 12.0), 0.0),
            GpuLight { kind: LIGHT_DIRECTIONAL, ..point(Vec3::ZERO, 0.0) },
            point(Vec3::new(2.5, 2.5, 2.5), 5.0),
        ];
        let powers = [1.0, 1.0, 1.0, 1.0, 1.0, 0.0];
        let grid = LightGrid::build(&lights, &powers, 2, bounds, RESOLUTION, usize::MAX).unwrap();
        assert_eq!(grid.header.dims, [16, 16, 16]);
        assert_eq!(listed(&grid, cell_of(&grid, Vec3::new(2.5, 2.5, 2.5))), vec![2, 3, 4]);
        assert_eq!(listed(&grid, cell_of(&grid, Vec3::new(10.5, 2.5, 2.5))), vec![3, 4]);
        // Every point within range of light 2 is in a cell that lists it.
        for k in 0..1000 {
            let t = k as f32 * 0.618;
            let dir = Vec3::new(t.sin() * (3.0 * t).cos(), t.cos(), t.sin() * (3.0 * t).sin());
            let q = Vec3::splat(2.5) + dir * 0.999 * (k % 10) as f32 / 10.0;
            assert!(listed(&grid, cell_of(&grid, q)).contains(&2), "{q}");
        }
        for (cell, &[first, count]) in grid.cells.iter().enumerate() {
            let e = &grid.entries[first as usize..(first + count) as usize];
            assert!(e.windows(2).all(|w| w[0].cdf <= w[1].cdf), "cell {cell}");
            assert_eq!(e.last().map(|e| e.cdf), Some(1.0), "cell {cell}");
            let sum: f32 = e.iter().map(|e| e.pmf).sum();
            assert!((sum - 1.0).abs() < 1e-5 && e.iter().all(|e| e.pmf > 0.0), "cell {cell}");
        }
    }

    #[test]
    fn lights_are_grouped_by_where_they_are() {
        let bounds = (Vec3::ZERO, Vec3::splat(16.0));
        // Light 0 is shadowed; 1 and 2 share a corner of the bounds, 3 is at the far corner,
        // 4 is directional.
        let lights = vec![
            point(Vec3::splat(8.0), 0.0),
            point(Vec3::splat(1.0), 0.0),
            point(Vec3::splat(2.0), 0.0),
            point(Vec3::splat(15.0), 0.0),
            GpuLight { kind: LIGHT_DIRECTIONAL, ..point(Vec3::ZERO, 0.0) },
        ];
        let grid = LightGrid::build(&lights, &[1.0; 5], 1, bounds, RESOLUTION, usize::MAX).unwrap();
        assert_eq!(grid.header.group_count, GROUP_COUNT);
        let group = |light: u32| grid.entries.iter().find(|e| e.light == light).map(|e| e.group).unwrap();
        assert_eq!(group(1), 0);
        assert_eq!(group(1), group(2));
        assert_eq!(group(3), GROUP_COUNT - 2);
        assert_eq!(group(4), GROUP_COUNT - 1);
        // A light keeps its group in every cell that lists it, and every entry starts with the
        // CDF of its bound.
        for e in &grid.entries {
            assert_eq!(e.group, group(e.light));
            assert!(e.bound > 0.0);
        }
    }

    /// With no resampled punctual light the grid still has its cells (emitters learn in
    /// them), listing nothing, where a grid of lights would have them; and group_at, which the
    /// shaders mirror for emitters' points, agrees with the groups the lights were given.
    #[test]
    fn a_grid_without_lights_keeps_the_cells_and_groups() {
        let bounds = (Vec3::ZERO, Vec3::new(16.0, 4.0, 8.0));
        let lights = vec![point(Vec3::splat(1.0), 0.0), point(Vec3::new(15.0, 3.0, 1.0), 0.0)];
        let with = LightGrid::build(&lights, &[1.0; 2], 0, bounds, RESOLUTION, usize::MAX).unwrap();
        let without = LightGrid::cells_only(bounds, RESOLUTION);
        assert_eq!(bytemuck::bytes_of(&with.header), bytemuck::bytes_of(&without.header));
        assert_eq!(without.cells.len(), without.header.cell_count as usize);
        assert!(without.cells.iter().all(|c| c[1] == 0) && without.entries.is_empty());
        for (i, light) in lights.iter().enumerate() {
            let e = with.entries.iter().find(|e| e.light == i as u32).unwrap();
            assert_eq!(e.group, group_at(&without.header, Vec3::from(light.position)));
        }
        assert_ne!(group_at(&without.header, Vec3::splat(1.0)), group_at(&without.header, Vec3::new(15.0, 3.0, 1.0)));
        assert_eq!(LightGrid::cells_only((Vec3::ONE, Vec3::ONE), RESOLUTION).header.cell_count, 0);
    }

    /// Each group lists its emitters with a CDF by power; the shares sum to 1 and a triangle's
    /// probability, its group's share times its part of the group, is its part of the total.
    #[test]
    fn emitters_are_sorted_into_their_groups_by_power() {
        let grid = LightGrid::cells_only((Vec3::ZERO, Vec3::new(16.0, 4.0, 8.0)), RESOLUTION);
        let emitters =
            [(Vec3::splat(1.0), 1.0), (Vec3::new(15.0, 3.0, 1.0), 2.0), (Vec3::splat(1.2), 3.0), (Vec3::ONE, 0.0)];
        let (groups, entries) = emitter_groups(&grid.header, &emitters);
        assert_eq!(groups.len(), 2, "only the groups that hold emitters are listed");
        assert!((groups.iter().map(|g| g.share).sum::<f32>() - 1.0).abs() < 1e-6);
        assert_eq!(entries.len(), 3, "the powerless triangle is left out");
        let group_of = |q: Vec3| groups.iter().find(|g| g.group == group_at(&grid.header, q)).unwrap();
        for (i, &(centroid, power)) in emitters.iter().enumerate().take(3) {
            let g = group_of(centroid);
            let stretch = &entries[g.first as usize..(g.first + g.count) as usize];
            let e = stretch.iter().find(|e| e.emitter == i as u32).expect("listed in its group");
            assert!((g.share * e.pmf - power / 6.0).abs() < 1e-6, "emitter {i}");
            assert_eq!(stretch.last().unwrap().cdf, 1.0);
        }
        assert_eq!(group_of(Vec3::splat(1.0)).count, 2, "the two triangles near the corner share a group");
        // Without a grid, or without power, nothing to draw from.
        assert!(emitter_groups(&GpuLightGridHeader::default(), &emitters).1.is_empty());
        assert!(emitter_groups(&grid.header, &[(Vec3::ONE, 0.0)]).1.is_empty());
    }

    #[test]
    fn a_spot_is_listed_only_where_its_cone_reaches() {
        let bounds = (Vec3::ZERO, Vec3::splat(16.0));
        let at = Vec3::new(8.0, 15.0, 8.0);
        let outer = 30f32.to_radians();
        let mut lights = vec![point(Vec3::ZERO, 0.0); 4];
        lights.push(GpuLight {
            kind: LIGHT_SPOT,
            direction: [0.0, -1.0, 0.0],
            cos_inner: 20f32.to_radians().cos(),
            cos_outer: outer.cos(),
            ..point(at, 0.0)
        });
        let powers = vec![1.0; lights.len()];
        let grid = LightGrid::build(&lights, &powers, 4, bounds, RESOLUTION, usize::MAX).unwrap();
        let lists = |q: Vec3| listed(&grid, cell_of(&grid, q)).contains(&4);
        assert!(lists(Vec3::new(8.0, 1.0, 8.0)));
        // Beside and above the light, and on the floor well outside the cone's footprint
        // (radius 14 tan 30 = 8.1 around (8, 8)).
        assert!(!lists(Vec3::new(1.0, 15.5, 1.0)));
        assert!(!lists(Vec3::new(8.0, 15.9, 12.0)));
        assert!(!lists(Vec3::new(0.5, 0.5, 0.5)));
        let culled = grid.cells.iter().filter(|c| c[1] == 0).count();
        assert!(culled > grid.cells.len() / 2, "{culled} of {} cells culled", grid.cells.len());
        // Every point strictly inside the cone is in a cell that lists the spot.
        for k in 0..2000 {
            let t = k as f32 * 0.618;
            let angle = (k % 97) as f32 / 97.0 * 0.999 * outer;
            let dir = Vec3::new(angle.sin() * t.cos(), -angle.cos(), angle.sin() * t.sin());
            let q = at + dir * (0.05 + 14.0 * (k % 13) as f32 / 13.0);
            if q.cmpge(Vec3::ZERO).all() && q.cmplt(Vec3::splat(16.0)).all() {
                assert!(lists(q), "{q} at {} degrees from the axis", angle.to_degrees());
            }
        }
    }

    #[test]
    fn nearer_lights_weigh_more_and_the_grid_fits_its_capacity() {
        let bounds = (Vec3::ZERO, Vec3::new(16.0, 4.0, 2.0));
        let lights: Vec<GpuLight> = (0..40).map(|i| point(Vec3::new(0.4 * i as f32, 1.0, 1.0), 0.0)).collect();
        let powers = vec![1.0; lights.len()];
        let grid = LightGrid::build(&lights, &powers, 4, bounds, RESOLUTION, usize::MAX).unwrap();
        assert_eq!(grid.header.dims[0], 16);
        let cell = cell_of(&grid, Vec3::new(0.5, 1.0, 1.0));
        let [first, count] = grid.cells[cell];
        let e = &grid.entries[first as usize..(first + count) as usize];
        assert_eq!(count, 36);
        assert!(e[0].pmf > 10.0 * e[35].pmf, "{} vs {}", e[0].pmf, e[35].pmf);
        let fit = LightGrid::build_within(&lights, &powers, 4, bounds, RESOLUTION, 36 * 20);
        assert!(fit.entries.len() <= 36 * 20 && fit.header.dims[0] < 16, "{:?}", fit.header.dims);
        let one = LightGrid::build_within(&lights, &powers, 4, bounds, RESOLUTION, 36);
        assert_eq!((one.header.cell_count, one.entries.len()), (1, 36));
        assert!(LightGrid::build(&lights, &powers, 4, bounds, RESOLUTION, 36 * 20).is_none());
        assert_eq!(LightGrid::build_within(&lights, &powers, 40, bounds, RESOLUTION, 1).header.cell_count, 0);
    }
}
