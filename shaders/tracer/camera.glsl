// camera.glsl — the primary rays of the Whitted tracer (shade.glsl) as Blender frames them:
// the view plane (gpu_types.h FrameParams), perspective, orthographic and panoramic projections
// after Cycles, the n×n sample grid, depth of field through a thin lens, and the depth and clip
// distance of a primary ray. Included by shade.glsl after RayTask; compiled as GLSL and as C++
// (cpu_tracer.h), like every file of the tracer.

/// Equirectangular or fisheye: rays from one point in every direction, clipped by distance.
bool panoramic_camera() { return frame.projection >= PROJECTION_EQUIRECTANGULAR; }

/// Screen coordinates (gpu_types.h FrameParams::screen) of sample `sample_index` of pixel p: the
/// centres of an n×n grid over the pixel, image row 0 at the top.
vec2 sample_screen(uvec2 p, uint sample_index) {
    uint n = frame.samples_per_axis;
    float qx = float(p.x) + (float(sample_index % n) + 0.5f) / float(n);
    float qy = float(p.y) + (float(sample_index / n) + 0.5f) / float(n);
    return vec2(frame.screen.x + qx * frame.screen.z, frame.screen.y + qy * frame.screen.w);
}

/// Equirectangular (Cycles' equirectangular_range_to_direction, intern/cycles/kernel/camera/
/// projection.h): longitude across, latitude up. Cycles' panorama camera space (x forward, y left,
/// z up: blender_camera_matrix, intern/cycles/blender/camera.cpp) is turned into world space.
vec3 equirectangular_dir(vec2 uv) {
    float phi = frame.panorama.x * uv.x + frame.panorama.y;
    float theta = frame.panorama.z * uv.y + frame.panorama.w;
    float across = sin(theta);
    return frame.camera_forward * (across * cos(phi)) - frame.camera_right * (across * sin(phi)) +
           frame.camera_up * cos(theta);
}

/// Fisheye equidistant (Cycles' fisheye_to_direction, projection.h): the angle from the view axis
/// grows with the distance from the frame's centre, reaching half the field of view at the edge
/// of the ellipse that fills the frame; zero (no ray) outside it.
vec3 fisheye_dir(vec2 uv) {
    float u = (uv.x - 0.5f) * 2.0f;
    float v = (uv.y - 0.5f) * 2.0f;
    float r = sqrt(u * u + v * v);
    if (r > 1.0f) return vec3(0.0f);
    float theta = r * frame.panorama.x * 0.5f;
    float across = r > 0.0f ? sin(theta) / r : 0.0f;
    return frame.camera_forward * cos(theta) + frame.camera_right * (u * across) + frame.camera_up * (v * across);
}

/// lowbias32 (C. Wellons, "Hash Prospector", 2018): a well-mixed 32-bit integer hash.
uint hash_uint(uint x) {
    x = (x ^ (x >> 16u)) * 0x7feb352du;
    x = (x ^ (x >> 15u)) * 0x846ca68bu;
    return x ^ (x >> 16u);
}

/// A point of the unit disc for sample `sample_index` of pixel p: the additive recurrence R2
/// (M. Roberts, "The Unreasonable Effectiveness of Quasirandom Sequences", 2018) over the samples
/// from a start hashed from the pixel, so that a pixel's lens points spread evenly and neighbours
/// differ; mapped onto the disc by Shirley and Chiu's concentric map (JGT 1997).
vec2 lens_disc(uvec2 p, uint sample_index) {
    uint h = hash_uint(p.x ^ hash_uint(p.y + 0x9e3779b9u));
    float sx = fract(float(h >> 8u) * 5.9604645e-8f + float(sample_index) * 0.75487766f);
    float sy = fract(float(hash_uint(h) >> 8u) * 5.9604645e-8f + float(sample_index) * 0.56984029f);
    float a = 2.0f * sx - 1.0f;
    float b = 2.0f * sy - 1.0f;
    if (a == 0.0f && b == 0.0f) return vec2(0.0f);
    bool wide = abs(a) > abs(b);
    float r = wide ? a : b;
    float phi = wide ? 0.78539816f * (b / a) : 1.57079633f - 0.78539816f * (a / b);
    return vec2(r * cos(phi), r * sin(phi));
}

/// Depth of field through a thin lens (Cycles' camera_sample_perspective, _orthographic and
/// _panorama with aperturesize > 0, kernel/camera/camera.h): the ray leaves a point of the lens
/// disc (radius aperture_radius, across the view axis; panoramic: across the pinhole ray) towards
/// the point the pinhole ray reaches at the focus distance (along the view axis; panoramic: along
/// the ray). `dir` has a view-axis component of 1 (perspective, orthographic) or is unit.
void thin_lens(INOUT(vec3) origin, INOUT(vec3) dir, uvec2 p, uint sample_index) {
    vec2 lens = lens_disc(p, sample_index) * frame.aperture_radius;
    vec3 across = frame.camera_right;
    vec3 focus = origin + dir * frame.focus_distance;
    if (panoramic_camera()) {
        vec3 u = frame.camera_forward - dir * dot(dir, frame.camera_forward);
        if (dot(u, u) > 1e-12f) across = normalize(u);  // along the view axis Cycles' U is undefined
    }
    vec3 other = panoramic_camera() ? cross(dir, across) : frame.camera_up;
    origin = origin + across * lens.x + other * lens.y;
    dir = focus - origin;
}

/// The primary ray of sample `sample_index` of pixel p (Cycles' camera_sample_perspective,
/// _orthographic and _panorama, kernel/camera/camera.h), with a unit direction; a zero direction
/// where the projection has no ray (outside the fisheye's ellipse).
RayTask camera_ray(uvec2 p, uint sample_index) {
    vec2 s = sample_screen(p, sample_index);
    vec3 origin = frame.camera_position;
    vec3 dir = frame.camera_forward;
    uint projection = frame.projection;
    if (projection == PROJECTION_PERSPECTIVE) dir = frame.camera_forward + frame.camera_right * s.x + frame.camera_up * s.y;
    if (projection == PROJECTION_ORTHOGRAPHIC) origin = origin + frame.camera_right * s.x + frame.camera_up * s.y;
    if (projection == PROJECTION_EQUIRECTANGULAR) dir = equirectangular_dir(s);
    if (projection == PROJECTION_FISHEYE_EQUIDISTANT) dir = fisheye_dir(s);
    bool ray = dot(dir, dir) > 0.0f;
    if (ray && frame.aperture_radius > 0.0f) thin_lens(origin, dir, p, sample_index);
    return ray_task(origin, ray ? unit_vector(dir) : dir, vec3(1.0f), 0u, RAY_CAMERA);
}

/// Whether `task` is a ray: camera_ray's direction is zero where the projection has none.
bool has_ray(RayTask task) {
    return dot(task.dir, task.dir) > 0.0f;
}

/// The size of a pixel across the primary ray of unit direction `dir` at distance t along it
/// (at most: the largest of a pixel's two sides, and a perspective pixel's size on the axis):
/// how far apart the rays of neighbouring pixels are there.
float pixel_footprint(vec3 dir, float t) {
    float step = max(abs(frame.screen.z), abs(frame.screen.w));
    uint projection = frame.projection;
    if (projection == PROJECTION_ORTHOGRAPHIC) return step;
    if (projection == PROJECTION_PERSPECTIVE) return t * step * abs(dot(dir, frame.camera_forward));
    if (projection == PROJECTION_EQUIRECTANGULAR)
        return t * max(abs(frame.panorama.x * frame.screen.z), abs(frame.panorama.z * frame.screen.w));
    return t * frame.panorama.x * step;  // fisheye: the angle from the axis grows by the field of view across
}

/// Blender's Depth of the point at `t` along a primary ray (Cycles' camera_z_depth,
/// kernel/camera/camera.h): its distance along the view axis from the camera (perspective,
/// orthographic), or from the camera (panoramic).
float camera_depth(RayTask task, float t) {
    vec3 v = (task.origin - frame.camera_position) + task.dir * t;
    return panoramic_camera() ? length(v) : dot(v, frame.camera_forward);
}

/// How far a primary ray goes per unit of the depth it clips at: 1 / its view-axis component
/// (perspective, orthographic), 1 (panoramic: clipped by distance, as Cycles clips).
float clip_scale(vec3 dir) {
    return panoramic_camera() ? 1.0f : 1.0f / dot(dir, frame.camera_forward);
}
