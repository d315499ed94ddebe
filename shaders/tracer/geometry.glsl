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

/// 1/d, with a huge finite value for d = 0 (0·inf would give NaN on a slab plane).
float safe_inverse(float d) {
    float tiny = d < 0.0f ? -1e-30f : 1e-30f;
    return 1.0f / (abs(d) < 1e-30f ? tiny : d);
}

TraceRay make_ray(vec3 origin, vec3 dir, float tmin) {
    TraceRay r;
    r.origin = origin;
    r.dir = dir;
    r.inv_dir = vec3(safe_inverse(dir.x), safe_inverse(dir.y), safe_inverse(dir.z));
    r.tmin = tmin;
    return r;
}

/// Slab test: where the ray enters the box within (tmin, tmax), or -1 when it misses.
float box_entry(vec3 lo, vec3 hi, TraceRay r, float tmax) {
    vec3 t0 = (lo - r.origin) * r.inv_dir;
    vec3 t1 = (hi - r.origin) * r.inv_dir;
    float tnear = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), max(min(t0.z, t1.z), r.tmin));
    float tfar = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), min(max(t0.z, t1.z), tmax));
    return tnear <= tfar ? tnear : -1.0f;
}

/// Möller–Trumbore. A hit in (tmin, t_best) returns true with tuv = (t, u, v).
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
    if (!(t > r.tmin && t < t_best)) return false;
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

/// Nearest root in (tmin, t_best).
bool hit_sphere(GpuSphere s, TraceRay r, float t_best, OUT(float) t_hit) {
    vec2 roots = sphere_roots(s, r);
    if (roots.x > roots.y) return false;
    float t = roots.x > r.tmin ? roots.x : roots.y;
    if (!(t > r.tmin && t < t_best)) return false;
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
