// shade.glsl — the Whitted tracer of the report (§2.1): reflection and refraction kept on an
// explicit ray stack (GLSL has no recursion, §3.1), one shadow ray to the point light attenuated by
// the transparencies it crosses, the atmosphere colour for rays that hit nothing, n×n
// supersampling and the BVH overlay lookup (§3.3).
//
// Written as a state machine over a TraceState so that no dispatch holds unbounded work (issue 8):
// trace_steps() runs a budget of steps (every loop iteration of the shader counts against it), and
// a trace suspended after any step continues from its saved state (state.glsl) in the next dispatch
// with the same result.
// Shared code: see geometry.glsl.

struct RayTask {
    vec3 origin;
    vec3 dir;
    vec3 weight;  ///< how much this ray contributes to the pixel
    uint depth;   ///< bounces so far (0: the primary ray)
    uint kind;    ///< RAY_CAMERA, RAY_REFLECTION or RAY_REFRACTION: which surfaces it sees (traverse.glsl sees)
};

RayTask ray_task(vec3 origin, vec3 dir, vec3 weight, uint depth, uint kind) {
    RayTask t;
    t.origin = origin;
    t.dir = dir;
    t.weight = weight;
    t.depth = depth;
    t.kind = kind;
    return t;
}

// What a trace does next (TraceState::phase).
LOCAL_CONST uint PHASE_SAMPLE = 0u;    ///< start the pixel's next sample, or finish the pass
LOCAL_CONST uint PHASE_START = 1u;     ///< start the closest-hit query of `task`
LOCAL_CONST uint PHASE_CLOSEST = 2u;   ///< walking the closest-hit query of `task`
LOCAL_CONST uint PHASE_SHADOW = 3u;    ///< walking the shadow ray of the hit in `closest`
LOCAL_CONST uint PHASE_NEXT_RAY = 4u;  ///< take the next ray off the ray stack, or end the sample
LOCAL_CONST uint PHASE_DONE = 5u;      ///< every sample of the pass is accumulated (the phases from
                                       ///< here on are final)
LOCAL_CONST uint PHASE_FAILED = 6u;    ///< stopped: more work than frame.max_work_per_pixel

/// One pixel's trace in progress. The ray stack (`rays` entries) and the traversal stack live in
/// the slot's storage (ray_word_load/store, node_stack_load/store).
struct TraceState {
    uvec2 pixel;
    uint phase;       ///< PHASE_*
    uint sample_index;  ///< the sample being traced: sx + n·sy on the n×n grid
    uint target;      ///< the pass ends before this sample
    uint rays;        ///< entries on the ray stack
    uint work;        ///< steps of work in this pass so far (checked against max_work_per_pixel)
    Walk walk;        ///< the query in progress (traverse.glsl)
    TraceRay ray;     ///< the ray it follows
    Hit hit;          ///< its result so far
    Hit closest;      ///< the closest hit of `task`, kept while its shadow ray is walked
    RayTask task;     ///< the ray being traced
    vec4 overlay;     ///< the overlay pass's line at this pixel: its point from the camera, box depth + 1 (w = 0: none)
    vec3 color;       ///< of this sample so far
    TraversalCounts counts;  ///< of this sample's primary ray's closest-hit walk (issue 35: secondary and
                             ///< shadow rays are not counted, so a pixel's counters describe the tree
                             ///< seen from the camera, as Bvh.trace_pixel records it)
    float depth;      ///< view-axis depth of what this sample's primary ray shows (inf: sky or a holdout)
    bool holdout;     ///< this sample's primary ray met a holdout: no colour and no alpha (Cycles' holdout);
                      ///< set and read in one step (shade_or_shadow, next_ray): never saved
};

float infinity() { return uintBitsToFloat(0x7f800000u); }

#include "camera.glsl"

#include "ray_offset.glsl"

#include "surface.glsl"

/// Ambient, plus diffuse and a Blinn-Phong highlight from the point light scaled by the shadow
/// ray's transmission (only traced where the light is in front: lambert > 0). `n` faces the viewer.
vec3 direct_light(vec3 p, vec3 n, vec3 view_dir, vec3 albedo, float transmission) {
    vec3 to_light = frame.light_position - p;
    vec3 l = to_light / length(to_light);
    float lambert = dot(n, l);
    vec3 color = albedo * AMBIENT;
    if (!(lambert > 0.0f)) return color;
    if (transmission <= 0.0f) return color;
    float highlight = pow(max(dot(n, normalize(l - view_dir)), 0.0f), SHININESS) * SPECULAR;
    return color + frame.light_color * (transmission * (1.0f - AMBIENT)) * (albedo * lambert + vec3(highlight));
}

void push_ray(INOUT(TraceState) s, RayTask t) {
    uint k = 3u * s.rays;
    ray_word_store(k, uvec4(floatBitsToUint(t.origin.x), floatBitsToUint(t.origin.y), floatBitsToUint(t.origin.z), t.depth));
    ray_word_store(k + 1u, uvec4(floatBitsToUint(t.dir.x), floatBitsToUint(t.dir.y), floatBitsToUint(t.dir.z), t.kind));
    ray_word_store(k + 2u, uvec4(floatBitsToUint(t.weight.x), floatBitsToUint(t.weight.y), floatBitsToUint(t.weight.z), 0u));
    s.rays += 1u;
}

RayTask pop_ray(INOUT(TraceState) s) {
    s.rays -= 1u;
    uint k = 3u * s.rays;
    uvec4 a = ray_word_load(k);
    uvec4 b = ray_word_load(k + 1u);
    uvec4 c = ray_word_load(k + 2u);
    return ray_task(vec3(uintBitsToFloat(a.x), uintBitsToFloat(a.y), uintBitsToFloat(a.z)),
                    vec3(uintBitsToFloat(b.x), uintBitsToFloat(b.y), uintBitsToFloat(b.z)),
                    vec3(uintBitsToFloat(c.x), uintBitsToFloat(c.y), uintBitsToFloat(c.z)), a.w, b.w);
}

/// The distance along the primary ray of the overlay's line at a pixel (`overlay`: the line's point
/// relative to the camera in xyz, its box's depth + 1 in w; 0 where no line): overlay_distance of
/// that point, as the overlay pass depth-tests it (overlay.frag, overlay_cpu.cpp).
float line_distance(vec4 overlay) { return overlay.w > 0.0f ? overlay_distance(xyz(overlay)) : 0.0f; }

/// The colour of the overlay's line at a pixel: its box's depth colour, or the one colour.
vec3 line_color(vec4 overlay) {
    return frame.overlay_color_by_depth != 0u ? depth_color(uint(overlay.w) - 1u) : xyz(frame.overlay_color);
}

/// A line lying on a surface (a box's face on a floor or a wall) is not lost to rounding: the
/// primary ray's query stops 2^-12 of the line's distance short of it (a hit from there on counts
/// as behind it), far above the rounding of the two rasterizers and of the tracer (compared
/// exactly, whichever last bits each had hid some of its pixels, differently on the GPU and the
/// CPU reference). Where the pixel's centre meets
/// the surface farther in front of the line (a surface at a grazing angle, the centre up to half
/// the line's width off it), line_on_surface decides by the line's own point.
LOCAL_CONST float LINE_ON_SURFACE = 1.0f - 1.0f / 4096.0f;

/// Whether a primary ray's query at a line pixel stops at the line (LINE_ON_SURFACE): only where
/// lines are a pixel wide. A pixel of a wider line lies up to half its width off the line, and the
/// surface its ray meets beyond the line may still hide it (a box's edge under a floor, the pixel
/// on the far side of the edge: the floor there is farther than the edge): the query walks on to
/// the surface, and line_on_surface decides by the line's point.
bool query_stops_at_line() { return frame.overlay_line_width <= 1.0f; }

/// The tmin and tmax of the closest-hit query of `task` (start_closest), `overlay` the pixel's
/// overlay (line_distance).
vec2 query_span(RayTask task, vec4 overlay) {
    bool primary = task.depth == 0u;
    bool measured = frame.mode == MODE_HEATMAP || frame.count_traversal != 0u;
    bool line = primary && overlay.w > 0.0f && !measured && query_stops_at_line();
    float k = primary ? clip_scale(task.dir) : 0.0f;  // camera rays see between the clipping planes
    return vec2(primary ? frame.clip_start * k : 0.0f,
                min(line ? line_distance(overlay) * LINE_ON_SURFACE : FAR_AWAY, primary ? frame.clip_end * k : FAR_AWAY));
}

/// Starts the closest-hit query of `task`. Where the overlay drew a line in front of the primary
/// ray's surface, the line wins: the query of a one-pixel line's pixel only looks up to the line's
/// distance (report §3.3; a wider line's walks on: query_stops_at_line) —
/// unless the render measures the walks (the heatmap mode, the traversal counters): then it walks
/// to the surface and after_closest puts the line in front of a surface behind it, the same
/// picture, but box tests that do not change with the boxes drawn (cut at the line, a pixel's 21
/// box tests were 13; Bvh.trace_pixel records 21). A primary ray looks only between the camera's
/// clipping planes (Cycles' camera_sample_*).
void start_closest(INOUT(TraceState) s) {
    vec2 span = query_span(s.task, s.overlay);
    s.ray = make_ray(s.task.origin, s.task.dir, span.x);
    s.hit = empty_hit(span.y);
    s.walk = start_walk();
    s.phase = PHASE_CLOSEST;
}

/// The pixel's next sample: its primary ray becomes the task; or the pass is done.
void start_sample(INOUT(TraceState) s) {
    if (s.sample_index >= s.target) {
        s.phase = PHASE_DONE;
        return;
    }
#ifdef __cplusplus
    s.task = camera_task(s.pixel, s.sample_index);  // cpu_tracer.h: camera_ray, or the one traced ahead
#else
    s.task = camera_ray(s.pixel, s.sample_index);
#endif
    s.color = vec3(0.0f);
    s.counts = no_counts();
    s.depth = infinity();
    s.holdout = false;
    // no ray (outside the fisheye's ellipse): a black sample that hit nothing, as in Cycles
    s.phase = has_ray(s.task) ? PHASE_START : PHASE_NEXT_RAY;
}

/// The next ray off the stack becomes the task, or the sample is complete: its colour, counters,
/// depth and whether it covers the pixel (its alpha: its camera ray met no holdout, and with
/// Film ▸ Transparent showed something, a finite depth: a surface or the overlay's line) go into
/// the pixel's sums (whole samples only, so a stopped render leaves consistent sums).
void next_ray(INOUT(TraceState) s) {
    if (s.rays == 0u) {
        // a sample with no camera ray (outside the fisheye's ellipse) is opaque black, as Cycles
        // writes it with Film ▸ Transparent (it was alpha 0); its task is that zero ray
        bool no_ray = dot(s.task.dir, s.task.dir) == 0.0f;
        bool shows = frame.film_transparent == 0u || s.depth < infinity() || no_ray;
        accumulate_sample(s.pixel, s.color, s.counts, s.depth, shows && !s.holdout);
        s.sample_index += 1u;
        s.phase = PHASE_SAMPLE;
        return;
    }
    s.task = pop_ray(s);
    s.phase = PHASE_START;
}

/// Direct light at the surface `f` of `closest` (the shadow ray's transmission in `hit`), then its
/// refraction (Snell; total internal reflection turns it into reflection) and reflection rays.
void finish_shading(INOUT(TraceState) s, Surface f) {
    if (f.opaque > 0.0f)
        s.color += s.task.weight * f.opaque * direct_light(f.p, f.facing, s.task.dir, xyz(f.m.color_reflective), s.hit.transmission);
    s.phase = PHASE_NEXT_RAY;
    if (s.task.depth >= frame.max_ray_depth) return;
    float transparent = f.m.transparent_ior.x;
    float reflect_weight = f.m.color_reflective.w;
    if (transparent > 0.0f) {
        float eta = f.entering ? 1.0f / f.m.transparent_ior.y : f.m.transparent_ior.y;
        vec3 refracted = refract(s.task.dir, f.facing, eta);
        if (dot(refracted, refracted) > 0.0f) {
            vec3 dir = normalize(refracted);
            push_ray(s, ray_task(ray_origin(f, dir, false), dir, s.task.weight * transparent, s.task.depth + 1u,
                                 RAY_REFRACTION));
        }
        else
            reflect_weight += transparent;
    }
    if (reflect_weight > 0.0f) {
        vec3 dir = reflect(s.task.dir, f.facing);
        push_ray(s, ray_task(ray_origin(f, dir, true), dir, s.task.weight * reflect_weight, s.task.depth + 1u,
                             RAY_REFLECTION));
    }
}

/// Whether the overlay's line at a pixel (`overlay`) lies on the surface `hit` that the pixel's
/// primary ray `task` met in front of it. The overlay pass stores, per line pixel, the point P of
/// the line segment that the fragment was drawn for (the rasterizer's interpolation at the
/// fragment: where the fragment's centre projects onto the segment on the GPU, where the segment
/// crosses the pixel's column (row) on the CPU reference), so a pixel of a wide line knows where
/// the line's centre is, up to half the width away. The line shows where P lies in front of the
/// plane of the surface at the pixel (its point S = origin + t·dir, its normal) or behind it by at
/// most a slope bias of a pixel's worth, as polygon offset's (the pixel's footprint at S times the
/// tangent of the angle between the ray and the normal, the depth the surface spans across one
/// pixel; measured along the normal, times its cosine), for the rounding of the rasterizers and
/// of the tracer. For a planar surface that is exact at every width: a box's edge on a floor keeps
/// its whole width, one under it stays hidden (a bias that grew with the width let the edges of a
/// box 0.3 under a floor seen 8.5° from above show through at widths 3-16).
bool line_on_surface(RayTask task, Hit hit, vec4 overlay) {
    Surface f = surface_at(task, hit);
    float c = abs(dot(f.facing, task.dir));
    // at most 64 (a surface within 0.9° of edge-on), as polygon offset's slope is bounded: a
    // sphere's rim or a silhouette seen edge-on let lines far behind it show
    float slope = min(sqrt(max(1.0f - c * c, 0.0f)) / c, 64.0f);
    float slack = pixel_footprint(task.dir, hit.t) * slope * c;
    // P − S, both relative to the camera (the ray's origin is on the lens or the orthographic
    // camera's plane): no rounding at the scene's magnitude
    vec3 s_from_camera = (task.origin - frame.camera_position) + task.dir * hit.t;
    vec3 to_line = xyz(overlay) - s_from_camera;
    return -dot(to_line, f.facing) <= slack;  // facing: the normal on the ray's side
}

/// The closest-hit query of `task` is answered: the primary ray's traversal counters and depth; the sky
/// (or the overlay's line, report §3.3) for a miss, or for a hit behind the line (a measured walk's:
/// start_closest) or that the line lies on: the line wins. Returns true for a hit that is shaded.
bool after_closest(INOUT(TraceState) s) {
    bool line = s.task.depth == 0u && s.overlay.w > 0.0f;
    if (line && s.hit.ref != NO_HIT &&
        ((query_stops_at_line() && s.hit.t >= line_distance(s.overlay) * LINE_ON_SURFACE) ||
         line_on_surface(s.task, s.hit, s.overlay)))
        s.hit.ref = NO_HIT;
    if (s.task.depth == 0u) {
        s.counts = s.hit.counts;
        s.depth = s.hit.ref != NO_HIT ? camera_depth(s.task, s.hit.t) : (line ? camera_depth(s.task, line_distance(s.overlay)) : infinity());
    }
    if (s.hit.ref != NO_HIT) return true;
    bool transparent = s.task.depth == 0u && frame.film_transparent != 0u;  // Film ▸ Transparent: no colour
    s.color += s.task.weight * (line ? line_color(s.overlay) : (transparent ? vec3(0.0f) : frame.sky));
    s.phase = PHASE_NEXT_RAY;
    return false;
}

/// Starts a shadow ray toward the light where it lights an opaque part of the surface `f` of the
/// closest hit (report §2.1); returns false where there is none to trace. It starts off the
/// surface (ray_origin) and stops short of the light by a bound on where the ray's arithmetic
/// puts the light (the rounding of its length and direction, relative to the distance, and of
/// the light's coordinates).
bool start_shadow(INOUT(TraceState) s, Surface f) {
    vec3 to_light = frame.light_position - f.p;
    vec3 l = to_light / length(to_light);  // as direct_light's
    if (!(f.opaque > 0.0f && dot(f.facing, l) > 0.0f)) return false;
    vec3 origin = ray_origin(f, l, true);
    vec3 to_end = frame.light_position - origin;
    float dist = length(to_end);
    vec3 light = abs(frame.light_position);
    float short_of_light = gamma_bound(8.0f) * dist + gamma_bound(2.0f) * max(max(light.x, light.y), light.z);
    s.ray = make_ray(origin, to_end / dist, 0.0f);
    s.hit = empty_hit(dist - short_of_light);
    s.walk = start_walk();
    s.phase = PHASE_SHADOW;
    return true;
}

/// The closest hit is known: a shadow ray starts where the light may reach the surface, else the
/// hit is shaded (returns true: finish_shading now, with no light but the ambient). A holdout
/// (Cycles' Holdout: Object ▸ Visibility, a view layer's collection, the Holdout shader) ends the
/// ray with no colour, and where a camera ray meets it the sample is a hole: uncovered (alpha 0),
/// with the sky's depth, as Cycles writes both passes there (returns false: the next ray).
bool shade_or_shadow(INOUT(TraceState) s) {
    s.closest = s.hit;
    Surface f = surface_at(s.task, s.closest);
    if (f.m.transparent_ior.z != 0.0f) {
        if (s.task.depth == 0u) {
            s.holdout = true;
            s.depth = infinity();
        }
        s.phase = PHASE_NEXT_RAY;
        return false;
    }
    if (start_shadow(s, f)) return false;
    s.hit.transmission = 0.0f;  // no shadow ray: direct_light adds ambient only
    return true;
}

/// Loops of walk() that may run once even where no lane of the SIMD vector walks (lavapipe runs
/// both sides of a branch under a mask, loops included).
LOCAL_CONST uint WALK_LOOPS = 4u;

/// Traces for about `budget` steps (each loop iteration of walk() and of this loop is one), or
/// until the pass is done for this pixel. One iteration follows a ray as the report's recursion
/// does (§2.1): its closest-hit walk, then its shadow walk, then the shading and the next ray;
/// a walk cut short by the budget goes on in the next iteration (or dispatch). Each piece of the
/// shading appears once: lavapipe runs every branch of a SIMD vector under a mask, whichever lanes
/// take it. The count stays an upper bound of the loop iterations the SIMD vector ran (see walk);
/// it ends at most a few steps past `budget`. A trace whose work passes max_work_per_pixel fails
/// (the same steps on both backends: the work count is not the synchronised one).
void trace_steps(INOUT(TraceState) s, uint budget) {
    uint steps = 0u;
    while (s.phase < PHASE_DONE && steps < budget) {
        steps += 1u;
        s.work += 1u;
        bool finish = false;
        if (s.phase == PHASE_CLOSEST) walk(s.walk, s.ray, s.task.kind, s.hit, s.work, steps, budget);
        steps = sync_steps(steps) + WALK_LOOPS;
        if (s.work > frame.max_work_per_pixel) s.phase = PHASE_FAILED;
        if (s.phase == PHASE_CLOSEST && s.walk.state == WALK_FINISHED && after_closest(s)) finish = shade_or_shadow(s);
        if (s.phase == PHASE_SHADOW) walk(s.walk, s.ray, RAY_SHADOW, s.hit, s.work, steps, budget);
        steps = sync_steps(steps) + WALK_LOOPS;
        if (s.work > frame.max_work_per_pixel) s.phase = PHASE_FAILED;
        if (s.phase == PHASE_SHADOW && s.walk.state == WALK_FINISHED) finish = true;
        if (finish) finish_shading(s, surface_at(s.task, s.closest));
        if (s.phase == PHASE_NEXT_RAY) next_ray(s);
        if (s.phase == PHASE_SAMPLE) start_sample(s);
        if (s.phase == PHASE_START) start_closest(s);
    }
}

/// A pixel's trace at the start of a pass: its samples `first` .. `target` - 1 are to be traced.
TraceState begin_pixel(uvec2 p, uint first, uint target) {
    TraceState s;
    s.pixel = p;
    s.phase = PHASE_SAMPLE;
    s.sample_index = first;
    s.target = target;
    s.rays = 0u;
    s.work = 0u;
    s.walk = start_walk();
    s.ray = make_ray(vec3(0.0f), vec3(0.0f, 0.0f, 1.0f), 0.0f);
    s.hit = empty_hit(0.0f);
    s.closest = s.hit;
    s.task = ray_task(vec3(0.0f), vec3(0.0f), vec3(0.0f), 0u, RAY_CAMERA);
    s.overlay = overlay_at(p);
    s.color = vec3(0.0f);
    s.counts = no_counts();
    s.depth = infinity();
    s.holdout = false;
    return s;
}
