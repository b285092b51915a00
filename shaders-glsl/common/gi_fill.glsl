// What gi leaves to gi_fill at half rate: each untraced pixel it does not trace itself carries,
// in gi.radiance's alpha, -float(bits): which traced neighbours show the same surface (one bit
// per GI_FILL_OFFSETS entry) and which lobes the pixel has. Traced pixels have alpha 1.
#ifndef GI_FILL_GLSL
#define GI_FILL_GLSL

// Left, right, above, below: in a checkerboard every one is traced when the pixel is not.
const ivec2 GI_FILL_OFFSETS[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
#define GI_FILL_DIFFUSE 16u  // the pixel keeps a diffuse signal
#define GI_FILL_SPECULAR 32u // the pixel keeps a specular one (gi.comp's fill_sources says which)

#endif
