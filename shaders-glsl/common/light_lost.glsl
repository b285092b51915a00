// What a history holds that is gone without the frame announcing it (an occluder), as the
// histories of SVGF's signals and TAA's colour test it: gi.light_lost, the luminance of what a
// pixel's resampled light brought last frame and no longer brings, in shadow now.
#ifndef LIGHT_LOST_GLSL
#define LIGHT_LOST_GLSL

// A history lets go where the light lost brought more than this share of its luminance: less
// is noise the history should average, more is a change it would lag behind for its window.
const float LOST_SHARE = 0.25;

bool lost_share_of(float lost, float history_luminance) { return lost > LOST_SHARE * history_luminance; }

#endif
