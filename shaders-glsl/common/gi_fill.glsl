// What gi leaves to gi_fill at a reduced rate: each untraced pixel it does not trace itself
// carries, in gi.radiance's alpha, -float(bits): which traced neighbours show the same surface
// (one bit per GI_FILL_OFFSETS entry) and which lobes the pixel has. Traced pixels have alpha 1.
#ifndef GI_FILL_GLSL
#define GI_FILL_GLSL

// Left, right, above, below, then the diagonals. At half rate (a checkerboard) the first four
// are traced when the pixel is not; at quarter rate (one pixel of each 2x2 block) a pixel in a
// traced row or column has two of the first four traced, and the others the four diagonals.
#define GI_FILL_NEIGHBOURS 8
const ivec2 GI_FILL_OFFSETS[GI_FILL_NEIGHBOURS] = ivec2[GI_FILL_NEIGHBOURS](
    ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1), ivec2(-1, -1), ivec2(1, -1), ivec2(-1, 1), ivec2(1, 1));
#define GI_FILL_DIFFUSE 256u  // the pixel keeps a diffuse signal
#define GI_FILL_SPECULAR 512u // the pixel keeps a specular one (gi.comp's fill_sources says which)

// Whether gi traces pixel q this frame on its lattice (`rate` pixels per traced one: 2 or 4;
// a pixel off it that no neighbour can fill is traced as well). Half rate: a checkerboard that
// alternates every frame. Quarter rate: one pixel of each 2x2 block, the four in turn, the
// diagonal one second so that two frames in a row cover the block's both diagonals.
bool gi_fill_on_lattice(ivec2 q, uint rate, uint frame_index) {
    if (rate == 2u) return ((q.x + q.y + int(frame_index)) & 1) == 0;
    const ivec2 PHASES[4] = ivec2[4](ivec2(0, 0), ivec2(1, 1), ivec2(1, 0), ivec2(0, 1));
    ivec2 o = PHASES[frame_index & 3u];
    return (q.x & 1) == o.x && (q.y & 1) == o.y;
}

#endif
