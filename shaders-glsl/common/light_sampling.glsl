// Every light in one place, for next-event estimation and for multiple importance sampling:
//   - punctual lights (lights[]): point, spot and directional are delta lights; a point light
//     with radius > 0 is a sphere of uniform radiance, a spot with radius > 0 a disk facing
//     the spot direction. None of them is geometry, so BSDF sampling cannot reach them: their
//     samples carry pdf 0, which means "MIS weight 1";
//   - emissive triangles (every triangle of an instance whose material emits): a triangle by
//     power, a point uniformly on it, converted to solid angle;
//   - the environment: a constant colour, or an equirectangular map sampled by
//     luminance * sin(theta) through a marginal and conditional CDF.
// One light is chosen per sample from a CDF over all of them by power, built on the CPU
// (src/world/lights.rs, src/world/environment.rs), which also fills set-0 bindings 12..16.
#ifndef LIGHT_SAMPLING_GLSL
#define LIGHT_SAMPLING_GLSL

#include "scene.glsl"
#include "lights.glsl"
#include "hit.glsl"
#include "sampling.glsl"
#include "light_grid.glsl"

#define LIGHT_KIND_PUNCTUAL 0u
#define LIGHT_KIND_EMITTER 1u
#define LIGHT_KIND_ENVIRONMENT 2u

// Distance reported for lights at infinity (directional, environment).
#define LIGHT_FAR 1e30

struct LightTableHeader {
    uint entry_count;          // 0 when no light has any power (nothing to sample)
    uint first_emitter_entry;  // emitter i is entry first_emitter_entry + i
    uint env_entry;            // the environment's entry
    uint env_width;            // 0: constant environment env_constant
    uint env_height;
    vec3 env_constant;
};

struct LightEntry {
    uint kind;   // LIGHT_KIND_*
    uint index;  // into lights[] or emitters[]
    float cdf;   // probability of choosing this entry or an earlier one
    float pmf;   // probability of choosing this entry
};

#define EMITTER_DOUBLE_SIDED 1u
// A mesh light of the shadows chain (composite shades it; gi's reservoirs leave it out).
// Rust: world::lights::EMITTER_IN_CHAIN.
#define EMITTER_IN_CHAIN 2u
// emitter_base[] of an instance that emits nothing.
#define NO_EMITTER 0xffffffffu

// One emissive triangle in world space (rebuilt on the CPU when its instance moves).
struct Emitter {
    vec3 p0;
    uint instance;
    vec3 e1;         // p1 - p0
    uint primitive;
    vec3 e2;         // p2 - p0
    float area;
    vec3 normal;     // unit normal of the emitting (front) side
    uint flags;      // EMITTER_DOUBLE_SIDED: both sides emit
};

layout(set = 0, binding = 12, scalar) readonly buffer LightTable {
    LightTableHeader light_table;
    LightEntry light_entries[];
};
layout(set = 0, binding = 13, scalar) readonly buffer Emitters { Emitter emitters[]; };
// First emitter of each instance (emitter of triangle t = emitter_base[instance] + t).
layout(set = 0, binding = 14, scalar) readonly buffer EmitterBase { uint emitter_base[]; };
// Environment map radiance (intensity applied), rows top (+Y) to bottom.
layout(set = 0, binding = 15, scalar) readonly buffer EnvTexels { vec3 env_texels[]; };
// Marginal CDF over rows (height + 1 values), then one conditional CDF per row (width + 1).
layout(set = 0, binding = 16, scalar) readonly buffer EnvCdf { float env_cdf[]; };

// ---- Environment ----------------------------------------------------------------------------
// Equirectangular: u = 0.5 + atan(x, -z) / 2pi (u = 0.5 looks down -Z), v = theta / pi with
// theta measured from +Y (row 0 is the zenith). Lookups are nearest-texel, so radiance is
// piecewise constant per texel, exactly as the CDF assumes: sampling density and radiance
// match texel for texel. Mirrored by src/world/environment.rs.

vec2 env_uv(vec3 dir) {
    return vec2(atan(dir.x, -dir.z) * (0.5 * INV_PI) + 0.5, acos(clamp(dir.y, -1.0, 1.0)) * INV_PI);
}

vec3 env_direction(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * PI;
    float theta = uv.y * PI;
    float s = sin(theta);
    return vec3(s * sin(phi), cos(theta), -s * cos(phi));
}

uvec2 env_texel(vec2 uv) {
    uvec2 size = uvec2(light_table.env_width, light_table.env_height);
    return min(uvec2(uv * vec2(size)), size - 1u);
}

vec3 env_eval(vec3 dir) {
    if (light_table.env_width == 0u) return light_table.env_constant;
    uvec2 t = env_texel(env_uv(dir));
    return env_texels[t.y * light_table.env_width + t.x];
}

// Largest k in [0, n) with cdf[base + k] <= u: the cell of u (cells of zero width are never
// returned, because the cell after them starts at the same value).
uint env_search(uint base, uint n, float u) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        if (env_cdf[base + mid] <= u) lo = mid; else hi = mid - 1u;
    }
    return lo;
}

uint env_row_base(uint row) { return light_table.env_height + 1u + row * (light_table.env_width + 1u); }

// Density in (u, v) of texel (x, y): the product of its marginal and conditional cell widths,
// scaled to densities. Read from the CDFs, so it is exactly what env_sample draws.
float env_pdf_uv(uvec2 t) {
    uint w = light_table.env_width;
    uint h = light_table.env_height;
    uint row = env_row_base(t.y);
    return (env_cdf[t.y + 1u] - env_cdf[t.y]) * float(h) * (env_cdf[row + t.x + 1u] - env_cdf[row + t.x]) * float(w);
}

// Solid-angle density with which env_sample produces `dir` (the map's Jacobian:
// d(omega) = 2 pi^2 sin(theta) du dv).
float env_pdf(vec3 dir) {
    if (light_table.env_width == 0u) return 1.0 / (4.0 * PI);
    vec2 uv = env_uv(dir);
    float sin_theta = sqrt(max(0.0, 1.0 - dir.y * dir.y));
    if (sin_theta <= 0.0) return 0.0;
    return env_pdf_uv(env_texel(uv)) / (2.0 * PI * PI * sin_theta);
}

// A direction toward the environment; false when none can be drawn.
bool env_sample(vec2 u, out vec3 dir, out float pdf) {
    if (light_table.env_width == 0u) {
        dir = sample_uniform_sphere(u);
        pdf = 1.0 / (4.0 * PI);
        return true;
    }
    uint w = light_table.env_width;
    uint h = light_table.env_height;
    uint y = env_search(0u, h, u.y);
    float dv = (u.y - env_cdf[y]) / max(env_cdf[y + 1u] - env_cdf[y], 1e-30);
    uint row = env_row_base(y);
    uint x = env_search(row, w, u.x);
    float du = (u.x - env_cdf[row + x]) / max(env_cdf[row + x + 1u] - env_cdf[row + x], 1e-30);
    vec2 uv = vec2((float(x) + clamp(du, 0.0, 1.0)) / float(w), (float(y) + clamp(dv, 0.0, 1.0)) / float(h));
    dir = env_direction(uv);
    pdf = env_pdf(dir);
    return pdf > 0.0;
}

// ---- Emissive triangles -----------------------------------------------------------------------

// Emitted radiance at a point of an emissive triangle (barycentrics of vertices 1 and 2): the
// material's emission as every pass reads it, and none where the alpha test cuts it away.
vec3 emitter_emission(uint instance, uint primitive, vec2 bary) {
    uvec3 tri = hit_triangle(instance, primitive);
    vec3 w = barycentric_weights(bary);
    vec2 uv0 = w.x * vertices[tri.x].uv0 + w.y * vertices[tri.y].uv0 + w.z * vertices[tri.z].uv0;
    vec2 uv1 = w.x * vertices[tri.x].uv1 + w.y * vertices[tri.y].uv1 + w.z * vertices[tri.z].uv1;
    uint material = instances[instance].material;
    if (!material_alpha_passes(material, uv0, uv1)) return vec3(0.0);
    return read_material(material, uv0, uv1).emissive;
}

// Cosine at the emitter between its emitting side and the direction back toward the receiver
// (`dir` points from the receiver to the emitter); <= 0 when the receiver sees a side that
// does not emit.
float emitter_cosine(Emitter e, vec3 dir) {
    float c = -dot(e.normal, dir);
    return (e.flags & EMITTER_DOUBLE_SIDED) != 0u ? abs(c) : c;
}

// Probability of choosing an entry (0 when nothing can be sampled).
float light_entry_pmf(uint entry) {
    return light_table.entry_count == 0u ? 0.0 : light_entries[entry].pmf;
}

// ---- Sampling and densities -------------------------------------------------------------------

struct NeeSample {
    vec3 dir;       // unit, from the shading point toward the light
    float dist;     // length of the shadow ray (LIGHT_FAR for lights at infinity)
    vec3 weight;    // radiance / (selection probability * pdf): the sample's estimate per unit f*cos
    float pdf;      // solid-angle density including selection, for MIS; 0 when BSDF sampling
                    // cannot produce this light (MIS weight 1)
    uint light;     // the punctual light sampled (index into lights[]); NO_LIGHT for others
    float seen;     // for a resampled light drawn from the light grid, the factor its learned
                    // visibility puts on resampling targets (light_grid_seen); 1 otherwise
};

NeeSample nee_none() {
    NeeSample s;
    s.dir = vec3(0.0, 0.0, 1.0);
    s.dist = 0.0;
    s.weight = vec3(0.0);
    s.pdf = 0.0;
    s.light = NO_LIGHT;
    s.seen = 1.0;
    return s;
}

// Sphere light: uniform radiance intensity / (pi r^2), which gives a distant receiver the
// point light's irradiance; sampled uniformly in the cone it subtends.
NeeSample sample_sphere_light(LightInfo light, vec3 p, vec2 u, float pmf) {
    vec3 d = light.position - p;
    float dist2 = dot(d, d);
    float r2 = light.radius * light.radius;
    if (dist2 <= r2) return nee_none();
    float dc = sqrt(dist2);
    float sin2 = r2 / dist2;
    float one_minus_cos = sin2 / (1.0 + sqrt(1.0 - sin2));
    NeeSample s;
    s.dir = normalize(orthonormal_basis(d / dc) * sample_uniform_cone(u, one_minus_cos));
    // Distance to the near side of the sphere along dir.
    float b = dot(s.dir, d);
    s.dist = b - sqrt(max(r2 - (dist2 - b * b), 0.0));
    vec3 radiance = light.intensity * (range_window(dc, light.range) / (PI * r2));
    s.weight = radiance * (2.0 * PI * one_minus_cos) / pmf;
    s.pdf = 0.0;
    return s;
}

// Disk light for a spot of radius r: a disk facing the spot direction whose radiance toward a
// receiver is intensity * cone * window / (pi r^2 cos_l), so that it shines like the punctual
// spot from afar. Sampled uniformly by area: with the area-to-solid-angle factor
// cos_l pi r^2 / d^2, the estimate is the punctual spot's value from the sampled point.
NeeSample sample_disk_light(LightInfo light, vec3 p, vec2 u, float pmf) {
    mat3 frame = orthonormal_basis(light.direction);
    vec2 d = sample_disk_concentric(u) * light.radius;
    LightInfo moved = light;
    moved.position = light.position + frame[0] * d.x + frame[1] * d.y;
    LightSample ls = sample_punctual(moved, p);
    if (dot(light.direction, -ls.dir) <= 0.0) return nee_none();
    NeeSample s;
    s.dir = ls.dir;
    s.dist = ls.dist;
    s.weight = ls.radiance / pmf;
    s.pdf = 0.0;
    return s;
}

NeeSample sample_punctual_light(uint index, vec3 p, vec2 u, float pmf) {
    LightInfo light = lights[index];
    NeeSample s;
    if (light.radius > 0.0 && light.type == LIGHT_POINT) {
        s = sample_sphere_light(light, p, u, pmf);
    } else if (light.radius > 0.0 && light.type == LIGHT_SPOT) {
        s = sample_disk_light(light, p, u, pmf);
    } else {
        LightSample ls = sample_punctual(light, p);
        s.dir = ls.dir;
        s.dist = ls.dist >= LIGHT_FAR ? LIGHT_FAR : ls.dist;
        s.weight = ls.radiance / pmf;
        s.pdf = 0.0;
    }
    s.light = index;
    s.seen = 1.0;
    return s;
}

// Point u of emitter e seen from p (`bary` its barycentrics): direction and distance, and as
// `weight` (grey) the factor cos_l area / dist^2 that turns its radiance into the sample's
// weight for a density of 1 in u; nee_none() where p sees a side that does not emit.
NeeSample emitter_point(Emitter e, vec3 p, vec2 u, out vec2 bary) {
    bary = sample_triangle(u);
    vec3 q = e.p0 + bary.x * e.e1 + bary.y * e.e2;
    vec3 d = q - p;
    float dist2 = dot(d, d);
    if (dist2 <= 0.0) return nee_none();
    NeeSample s = nee_none();
    s.dist = sqrt(dist2);
    s.dir = d / s.dist;
    float cos_l = emitter_cosine(e, s.dir);
    if (cos_l <= 0.0) return nee_none();
    s.weight = vec3(cos_l * e.area / dist2);
    return s;
}

NeeSample sample_emitter(uint index, vec3 p, vec2 u, float pmf) {
    Emitter e = emitters[index];
    vec2 bary;
    NeeSample s = emitter_point(e, p, u, bary);
    if (!(s.weight.x > 0.0)) return nee_none();
    s.pdf = pmf / s.weight.x;
    s.weight = emitter_emission(e.instance, e.primitive, bary) / s.pdf;
    return s;
}

NeeSample sample_environment(vec2 u, float pmf) {
    NeeSample s;
    float pdf;
    if (!env_sample(u, s.dir, pdf)) return nee_none();
    s.dist = LIGHT_FAR;
    s.pdf = pmf * pdf;
    s.weight = env_eval(s.dir) / s.pdf;
    s.light = NO_LIGHT;
    s.seen = 1.0;
    return s;
}

// The first entry whose cumulative probability exceeds u (the CPU sets every entry after the
// last light with power to exactly 1, so an entry of probability 0 is never chosen). Needs a
// non-empty table.
uint light_entry_search(float u) {
    uint lo = 0u;
    uint hi = light_table.entry_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_entries[mid].cdf > u) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

// Where a shading point draws the resampled punctual lights (those past the shadowed ones;
// the table's entries frame.chain_punctual.. in light order) from: its cell of the light grid, or,
// outside the grid, their sub-range [lo, hi) of the table's CDF. Only where such lights exist.
struct ResampledLights {
    bool in_grid;
    uint cell_index;
    uvec2 cell;
    float lo;
    float hi;
};

ResampledLights resampled_lights_at(vec3 p) {
    ResampledLights r;
    r.in_grid = light_grid_cell_index(p, r.cell_index);
    r.cell = r.in_grid ? light_grid_cells[r.cell_index] : uvec2(0u);
    r.lo = frame.chain_punctual > 0u ? light_entries[frame.chain_punctual - 1u].cdf : 0.0;
    r.hi = light_entries[frame.light_count - 1u].cdf;
    return r;
}

// A resampled light for u in [0, 1) and the probability of choosing it among the resampled
// lights; NO_LIGHT when none can reach the point. `seen` as light_grid_pick's (1 outside the
// grid).
uint resampled_light_pick(ResampledLights r, float u, out float pmf, out float seen) {
    if (r.in_grid) return light_grid_pick(r.cell_index, r.cell, u, pmf, seen);
    pmf = 0.0;
    seen = 1.0;
    if (!(r.hi > r.lo)) return NO_LIGHT;  // the resampled lights have no power
    uint entry = light_entry_search(r.lo + u * (r.hi - r.lo));
    // Rounding can put lo + u (hi - lo) on hi itself; such a draw selects nothing.
    if (entry < frame.chain_punctual || entry >= frame.light_count) return NO_LIGHT;
    pmf = light_entries[entry].pmf / (r.hi - r.lo);
    return entry;
}

// One light sample for shading point p: u.x chooses the light, u.yz the point on it.
NeeSample light_sample(vec3 p, vec3 u) {
    if (light_table.entry_count == 0u) return nee_none();
    LightEntry e = light_entries[light_entry_search(u.x)];
    if (e.kind == LIGHT_KIND_PUNCTUAL && e.index >= frame.chain_punctual) {
        // A resampled light: chosen again among them, from p's cell of the grid, with what is
        // left of u.x (uniform in [lo, hi) on this branch). The probability of the resampled
        // lights as a whole, hi - lo, stays as the table has it, so the other lights' densities
        // (and MIS against them) do not change.
        ResampledLights r = resampled_lights_at(p);
        float pmf, seen;
        uint light = resampled_light_pick(r, clamp((u.x - r.lo) / (r.hi - r.lo), 0.0, 0.99999994), pmf, seen);
        if (light == NO_LIGHT) return nee_none();
        NeeSample s = sample_punctual_light(light, p, u.yz, (r.hi - r.lo) * pmf);
        s.seen = seen;
        return s;
    }
    if (e.kind == LIGHT_KIND_PUNCTUAL) return sample_punctual_light(e.index, p, u.yz, e.pmf);
    if (e.kind == LIGHT_KIND_EMITTER) return sample_emitter(e.index, p, u.yz, e.pmf);
    return sample_environment(u.yz, e.pmf);
}

// Density with which light_sample produces the direction from `from` to point q of triangle
// `primitive` of `instance` (a BSDF-sampled ray hit it): for MIS. 0 for non-emitters.
float light_pdf_emitter(uint instance, uint primitive, vec3 from, vec3 q) {
    uint base = emitter_base[instance];
    if (base == NO_EMITTER) return 0.0;
    uint index = base + primitive;
    Emitter e = emitters[index];
    vec3 d = q - from;
    float dist2 = dot(d, d);
    float cos_l = emitter_cosine(e, d * inversesqrt(dist2));
    if (cos_l <= 0.0 || e.area <= 0.0) return 0.0;
    return light_entry_pmf(light_table.first_emitter_entry + index) * dist2 / (cos_l * e.area);
}

// Density with which light_sample produces direction dir toward the environment.
float light_pdf_environment(vec3 dir) {
    return light_entry_pmf(light_table.env_entry) * env_pdf(dir);
}

// Whether a ray along `dir` that hit triangle `primitive` of `instance` sees an emitting side.
bool emitter_visible_side(uint instance, uint primitive, vec3 dir) {
    uint base = emitter_base[instance];
    return base != NO_EMITTER && emitter_cosine(emitters[base + primitive], dir) > 0.0;
}

#endif
