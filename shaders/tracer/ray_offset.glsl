// ray_offset.glsl — where a secondary or shadow ray starts: off its surface by the precision of its
// own hit point, not by one scene-wide distance (which was below float32's spacing far from the
// origin, and far above a small object's size in a large scene). The method is pbrt-v4's (Pharr,
// Jakob and Humphreys, "Physically Based Rendering", 4th ed., §6.8 "Managing Rounding Error"): the
// hit point recomputed on the primitive with a conservative bound on its error per coordinate
// (§6.8.5: the triangle's barycentric point, the sphere's point reprojected onto it), then moved
// along the normal by that bound's projection onto it, rounded away from the surface (§6.8.6,
// OffsetRayOrigin); and, as pbrt's triangle test does (§6.8.4, its "deltaT"), the watertight
// test's own error in t for the new ray (which grows with the triangle's size, not with |p|)
// added to the distance, since our test has no such check. Shared code: see geometry.glsl.

/// γ(n) = nε / (1 - nε), ε = 2^-24: a bound on the relative error of n roundings (pbrt §6.8.1),
/// written as nε·1.0001 (a larger bound for n < 1,000) so that no division can round differently
/// on the GPU and the CPU.
float gamma_bound(float n) { return n * 5.96046448e-8f * 1.0001f; }

/// The smallest normal float: the rounding below stays off subnormals, which a GPU may flush to 0.
LOCAL_CONST float SMALLEST_NORMAL = 1.17549435e-38f;

/// The next float above v (pbrt's NextFloatUp; v is finite: coordinates are at most 2^40).
float next_float_up(float v) {
    if (v >= -SMALLEST_NORMAL && v < SMALLEST_NORMAL) return v < 0.0f ? 0.0f : SMALLEST_NORMAL;
    uint b = floatBitsToUint(v);
    return uintBitsToFloat(v > 0.0f ? b + 1u : b - 1u);
}

float next_float_down(float v) { return -next_float_up(-v); }

/// A bound on the error of the t that hit_triangle computes for the ray from `origin` along `dir`
/// against the triangle v0 v1 v2 (pbrt-v4 §6.8.4, its triangle test's deltaT, for our test's
/// arithmetic: the same sheared coordinates, t = (u·az + v·bz + w·cz) / det · (1/dir[kz])), here
/// doubled. A ray starting this far (times |cos| to the normal) off the triangle's plane cannot
/// meet the plane behind it at a computed t > 0.
float triangle_t_error(vec3 v0, vec3 v1, vec3 v2, vec3 origin, vec3 dir) {
    TraceRay r = make_ray(origin, dir, 0.0f);
    ShearedTriangle s = sheared_triangle(v0, v1, v2, r);
    float max_z = max(max(abs(s.a.z), abs(s.b.z)), abs(s.c.z));
    float max_x = max(max(abs(s.ax), abs(s.bx)), abs(s.cx));
    float max_y = max(max(abs(s.ay), abs(s.by)), abs(s.cy));
    float det = abs(s.u + s.v + s.w);
    if (det == 0.0f) return 0.0f;  // seen edge-on: the test never hits it
    float max_e = max(max(abs(s.u), abs(s.v)), abs(s.w));
    float dx = gamma_bound(5.0f) * (max_x + max_z);
    float dy = gamma_bound(5.0f) * (max_y + max_z);
    float de = 2.0f * (gamma_bound(2.0f) * max_x * max_y + dy * max_x + dx * max_y);
    float dz = gamma_bound(3.0f) * max_z;
    float dt = 3.0f * (gamma_bound(3.0f) * max_e * max_z + de * max_z + dz * max_e) / det;
    return 2.0f * dt * abs(r.shear.z);
}

/// The ray origin off the point p (error bound `amount` along the unit normal n, which points
/// to the side the ray leaves to): p + n·amount with each coordinate rounded away from p, so
/// that the rounding of the sum cannot bring it back (pbrt-v4 §6.8.6, OffsetRayOrigin).
vec3 offset_origin(vec3 p, vec3 n, float amount) {
    vec3 offset = n * amount;
    vec3 o = p + offset;
    o.x = offset.x > 0.0f ? next_float_up(o.x) : (offset.x < 0.0f ? next_float_down(o.x) : o.x);
    o.y = offset.y > 0.0f ? next_float_up(o.y) : (offset.y < 0.0f ? next_float_down(o.y) : o.y);
    o.z = offset.z > 0.0f ? next_float_up(o.z) : (offset.z < 0.0f ? next_float_down(o.z) : o.z);
    return o;
}
