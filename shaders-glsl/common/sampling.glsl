// Random numbers and the warps every Monte Carlo pass shares: a PCG generator seeded by pixel,
// frame and a per-pass salt, an orthonormal basis, and sample warps (cosine hemisphere, cone,
// disk, triangle, sphere, GGX visible normals), each with the density it produces.
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL

#define PI 3.14159265358979
#define INV_PI 0.31830988618379

// ---- Random numbers -------------------------------------------------------------------------

// PCG-RXS-M-XS 32 (O'Neill 2014) as a hash: one LCG step, then the output permutation. Good
// enough to decorrelate neighbouring seeds, which plain LCG seeding is not.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng {
    uint state;
};

// Every input goes through its own hash round, so (pixel, frame, salt) tuples that differ in
// any one component start unrelated streams. Results depend only on these inputs, never on
// thread timing.
Rng rng_init(uvec2 pixel, uint frame, uint salt) {
    return Rng(pcg_hash(pixel.x + pcg_hash(pixel.y + pcg_hash(frame + pcg_hash(salt)))));
}

// Uniform in [0, 1): the top 24 bits, so 1.0 is never returned after rounding.
float rng_next(inout Rng rng) {
    rng.state = rng.state * 747796405u + 2891336453u;
    uint word = ((rng.state >> ((rng.state >> 28u) + 4u)) ^ rng.state) * 277803737u;
    word = (word >> 22u) ^ word;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_next2(inout Rng rng) { return vec2(rng_next(rng), rng_next(rng)); }
vec3 rng_next3(inout Rng rng) { return vec3(rng_next(rng), rng_next(rng), rng_next(rng)); }

// ---- Frames -----------------------------------------------------------------------------------

// Tangent and bitangent completing unit `n` to a right-handed orthonormal basis (Duff et al.
// 2017, "Building an Orthonormal Basis, Revisited"): no normalisation, no singularity.
mat3 orthonormal_basis(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    return mat3(t, bt, n);
}

// ---- Warps ------------------------------------------------------------------------------------

// Square to unit disk, concentric (Shirley and Chiu 1997): keeps strata compact.
vec2 sample_disk_concentric(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    float r, phi;
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        phi = (PI / 4.0) * (o.y / o.x);
    } else {
        r = o.y;
        phi = (PI / 2.0) - (PI / 4.0) * (o.x / o.y);
    }
    return r * vec2(cos(phi), sin(phi));
}

// Cosine-weighted direction about +Z; pdf = cos(theta) / pi.
vec3 sample_cosine_hemisphere(vec2 u) {
    vec2 d = sample_disk_concentric(u);
    return vec3(d, sqrt(max(0.0, 1.0 - dot(d, d))));
}

float cosine_hemisphere_pdf(float cos_theta) { return max(cos_theta, 0.0) * INV_PI; }

// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
vec3 sample_uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Uniform direction in the cone about +Z whose half-angle has cosine cos_max, given
// one_minus_cos_max = 1 - cos_max computed without cancellation by the caller;
// pdf = 1 / (2 pi (1 - cos_max)).
vec3 sample_uniform_cone(vec2 u, float one_minus_cos_max) {
    float one_minus_cos = u.x * one_minus_cos_max;
    float cos_theta = 1.0 - one_minus_cos;
    // sin^2 = (1 - cos)(1 + cos), accurate for narrow cones.
    float sin_theta = sqrt(max(0.0, one_minus_cos * (2.0 - one_minus_cos)));
    float phi = 2.0 * PI * u.y;
    return vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

// Uniform point on a triangle as barycentric weights of vertices 1 and 2 (the convention of
// Hit.bary); pdf = 1 / area.
vec2 sample_triangle(vec2 u) {
    float su = sqrt(u.x);
    return vec2(su * (1.0 - u.y), su * u.y);
}

// GGX distribution of visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible
// Normals"), isotropic roughness `alpha`. `v` is the view direction in the tangent frame
// (z = normal, v.z > 0). Returns a microfacet normal m with density
// D_v(m) = G1(v) max(0, v.m) D(m) / v.z  (see ggx_vndf_pdf in brdf.glsl).
vec3 sample_ggx_vndf(vec3 v, float alpha, vec2 u) {
    // Stretch the view into the configuration where the distribution is a hemisphere.
    vec3 vh = normalize(vec3(alpha * v.x, alpha * v.y, v.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    // A point on the disk, then squashed onto the part of it the view sees.
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    // Lift onto the hemisphere and unstretch.
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// Power heuristic with beta = 2 (Veach 1997) for one sample from each of two strategies.
float mis_power(float pdf_this, float pdf_other) {
    float a = pdf_this * pdf_this;
    float b = pdf_other * pdf_other;
    return a + b > 0.0 ? a / (a + b) : 0.0;
}

#endif
