// geometry.glsl — rays and the ray-box, ray-triangle and ray-sphere tests of the tracer.
// Shared code: GLSL that also compiles as C++ (glsl_compat.h), so the compute shader and the CPU
// reference run the same arithmetic. Keep to that subset: no swizzles (use xyz()), no struct
// constructors, float literals with an f suffix, INOUT/OUT for reference parameters.

struct TraceRay {
    vec3 origin;
    vec3 dir;
    vec3 inv_dir;
    float tmin;
};

/// 1/d, with a signed infinity for d = ±0 (said explicitly rather than left to the division).
float inverse_or_infinity(float d) {
    float inf = uintBitsToFloat(0x7f800000u);
    if (d == 0.0f) return (floatBitsToUint(d) >> 31) != 0u ? -inf : inf;
    return 1.0f / d;
}

TraceRay make_ray(vec3 origin, vec3 dir, float tmin) {
    TraceRay r;
    r.origin = origin;
    r.dir = dir;
    r.inv_dir = vec3(inverse_or_infinity(dir.x), inverse_or_infinity(dir.y), inverse_or_infinity(dir.z));
    r.tmin = tmin;
    return r;
}

/// Distance along the ray to a slab plane `offset` = plane - origin away on an axis whose inverse
/// direction is `inv`. A ray starting on the plane gets `on_plane` instead of 0·inv (NaN when the
/// ray is parallel to the plane, and Vulkan need not even produce that NaN).
float plane_distance(float offset, float inv, float on_plane) {
    return offset == 0.0f ? on_plane : offset * inv;
}

/// Slab test (Kay and Kajiya 1986), closed on every face: where the ray enters the box within
/// (tmin, tmax], or -1 when it misses. A ray parallel to an axis (infinite inverse) is inside the
/// slab's planes with no constraint, outside them with none of the slab, and on one of them
/// counts as inside — so a ray along a box face is not lost while the closed triangle test on that
/// face would hit (the CPU query side does the same: hit_box in core_cpp/include/bvhlab/ray.h).
float box_entry(vec3 lo, vec3 hi, TraceRay r, float tmax) {
    float inf = uintBitsToFloat(0x7f800000u);
    bool nx = r.inv_dir.x < 0.0f;
    bool ny = r.inv_dir.y < 0.0f;
    bool nz = r.inv_dir.z < 0.0f;
    float near_x = plane_distance((nx ? hi.x : lo.x) - r.origin.x, r.inv_dir.x, -inf);
    float near_y = plane_distance((ny ? hi.y : lo.y) - r.origin.y, r.inv_dir.y, -inf);
    float near_z = plane_distance((nz ? hi.z : lo.z) - r.origin.z, r.inv_dir.z, -inf);
    float far_x = plane_distance((nx ? lo.x : hi.x) - r.origin.x, r.inv_dir.x, inf);
    float far_y = plane_distance((ny ? lo.y : hi.y) - r.origin.y, r.inv_dir.y, inf);
    float far_z = plane_distance((nz ? lo.z : hi.z) - r.origin.z, r.inv_dir.z, inf);
    float tnear = max(max(near_x, near_y), max(near_z, r.tmin));
    float tfar = min(min(far_x, far_y), min(far_z, tmax));
    return tnear <= tfar ? tnear : -1.0f;
}

/// Möller–Trumbore. A hit in (tmin, t_best] returns true with tuv = (t, u, v); t_best is
/// inclusive so that the caller can apply the tie rule (closer() in traverse.glsl).
bool hit_triangle(GpuTriangle tri, TraceRay r, float t_best, OUT(vec3) tuv) {
    vec3 e1 = xyz(tri.e1);
    vec3 e2 = xyz(tri.e2);
    vec3 p = cross(r.dir, e2);
    float det = dot(e1, p);
    if (det == 0.0f) return false;  // parallel, or a zero-area triangle (stored with zero edges)
    float inv_det = 1.0f / det;
    vec3 s = r.origin - xyz(tri.v0);
    float u = dot(s, p) * inv_det;
    if (!(u >= 0.0f && u <= 1.0f)) return false;
    vec3 q = cross(s, e1);
    float v = dot(r.dir, q) * inv_det;
    if (!(v >= 0.0f && u + v <= 1.0f)) return false;
    float t = dot(e2, q) * inv_det;
    if (!(t > r.tmin && t <= t_best)) return false;
    tuv = vec3(t, u, v);
    return true;
}

/// The two roots of |o + t·d - c|² = r², as (near, far); near > far when the ray misses.
vec2 sphere_roots(GpuSphere s, TraceRay r) {
    vec3 oc = r.origin - xyz(s.center_radius);
    float radius = s.center_radius.w;
    float a = dot(r.dir, r.dir);
    float b = dot(oc, r.dir);
    float c = dot(oc, oc) - radius * radius;
    float disc = b * b - a * c;
    if (!(disc >= 0.0f)) return vec2(1.0f, -1.0f);
    float sq = sqrt(disc);
    return vec2((-b - sq) / a, (-b + sq) / a);
}

/// Nearest root in (tmin, t_best] (inclusive, as hit_triangle).
bool hit_sphere(GpuSphere s, TraceRay r, float t_best, OUT(float) t_hit) {
    vec2 roots = sphere_roots(s, r);
    if (roots.x > roots.y) return false;
    float t = roots.x > r.tmin ? roots.x : roots.y;
    if (!(t > r.tmin && t <= t_best)) return false;
    t_hit = t;
    return true;
}

/// How often the segment (tmin, tmax) crosses the sphere's surface: 0, 1 or 2.
uint sphere_crossings(GpuSphere s, TraceRay r, float tmax) {
    vec2 roots = sphere_roots(s, r);
    if (roots.x > roots.y) return 0u;
    uint n = 0u;
    if (roots.x > r.tmin && roots.x < tmax) n += 1u;
    if (roots.y > r.tmin && roots.y < tmax) n += 1u;
    return n;
}
