// shade_colors.glsl — the colour ramps of the heatmap mode and the traversal counters (heat), of
// the difference of a counter between two trees (diverging) and of the overlay's depth colouring.
// Shared code (see geometry.glsl); also used by overlay.vert.

/// Blue → cyan → green → yellow → red for x in [0, 1].
vec3 heat_color(float x) {
    float t = clamp(x, 0.0f, 1.0f);
    return clamp(vec3(1.5f - abs(4.0f * t - 3.0f), 1.5f - abs(4.0f * t - 2.0f), 1.5f - abs(4.0f * t - 1.0f)), 0.0f, 1.0f);
}

/// Line colour of a tree depth (overlay): hues a golden angle apart, so neighbours differ.
vec3 depth_color(uint depth) {
    float h = fract(float(depth) * 0.6180339f) * 6.0f;
    vec3 rgb = clamp(vec3(abs(h - 3.0f) - 1.0f, 2.0f - abs(h - 2.0f), 2.0f - abs(h - 4.0f)), 0.0f, 1.0f);
    return mix(vec3(1.0f), rgb, 0.85f);
}

/// White at x = 0, to blue at x = -1 and red at x = 1: signed differences (a counter of one tree
/// minus another's, issue 35); the ends are ColorBrewer's RdBu ends.
vec3 diverging_color(float x) {
    float t = clamp(x, -1.0f, 1.0f);
    vec3 end = t < 0.0f ? vec3(0.0191f, 0.0908f, 0.3185f) : vec3(0.3185f, 0.0f, 0.0194f);
    return mix(vec3(1.0f), end, abs(t));
}
