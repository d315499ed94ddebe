// geometry.glsl — rays and the ray-box, ray-triangle and ray-sphere tests: the one definition of
// each, for the tracer (trace.comp, the CPU reference) and the CPU traversal (ray.h, through
// core_cpp/include/bvhlab/shared_geometry.h; the wide traversal does the same arithmetic lane by
// lane, core_cpp/src/query/wide_traverse.inl).
// Shared code: GLSL that also compiles as C++ (glsl_compat.h), so the compute shader and the CPU
// run the same arithmetic. Keep to that subset: no swizzles (use xyz()), no struct constructors,
// float literals with an f suffix, INOUT/OUT for reference parameters, INLINE before each function
// (C++ includes this file in a header).

/// A ray with what the tests need precomputed (make_ray).
struct TraceRay {
    vec3 origin;
    vec3 dir;
    vec3 inv_dir;  ///< 1/dir, ±inf for a zero component (box tests)
    float tmin;
    uint kx;       ///< the watertight test's axes: kz is the largest |dir| component, kx and ky
    uint ky;       ///< the other two, swapped when dir[kz] < 0 so that the winding is kept
    uint kz;
    vec3 shear;    ///< dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz] (as products with 1 / dir[kz])
    vec3 lo_on_plane;  ///< box_entry's distance to a box's lo plane that the origin lies on
                       ///< (on_plane_distance): 0, or for a ray parallel to it -inf where that plane
                       ///< is the near one (inv_dir > 0), +inf where it is the far one
    vec3 hi_on_plane;  ///< the same for the hi plane (0, or -lo_on_plane)
};

/// `v` (not 0) at length 1 whatever its size: normalize squares the components, so a triangle's
/// cross product (its edges' lengths multiplied) past ~1.8e19 overflowed to inf, below ~1e-19
/// underflowed to 0, and the normal came out 0 (a floor of 16e9 units unlit, a mirror of it
/// reflecting nothing, where its instance at that scale was lit; a thin lens's ray towards a focus
/// distance past ~1e19 had no direction: an audit). Such a vector is first divided by its largest
/// component; others are normalised as before, bit for bit.
INLINE vec3 unit_vector(vec3 v) {
    float m = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if (m > 1.15292150e18f || (m < 8.67361738e-19f && m > 0.0f)) v = v / m;  // 2^60, 2^-60
    return normalize(v);
}

/// 1/d, with a signed infinity for d = ±0 (said explicitly rather than left to the division).
INLINE float inverse_or_infinity(float d) {
    float inf = uintBitsToFloat(0x7f800000u);
    if (d == 0.0f) return (floatBitsToUint(d) >> 31) != 0u ? -inf : inf;
    return 1.0f / d;
}

/// The distance to a slab plane that the origin lies on, for an axis of inverse direction `inv`:
/// 0, as offset·inv is, where the ray crosses the plane (it enters or leaves the slab at its
/// origin); `parallel` where the ray is parallel to the plane (an infinite inverse: 0·inv is NaN),
/// -inf for a near plane and +inf for a far one, so that the plane bounds nothing. (Given to
/// every ray on a plane, that ±inf let a ray leaving a box through the far plane it starts on pass
/// as inside the slab for ever: the tracer entered boxes that the ray misses and hit_box does not
/// enter, and counted more box tests than Bvh.trace_pixel records — a camera at x = 0 over a floor
/// whose boxes end at x = 0, 168 of 432 pixels of the bundled whitted scene.)
INLINE float on_plane_distance(float inv, float parallel) {
    return abs(inv) == uintBitsToFloat(0x7f800000u) ? parallel : 0.0f;
}

/// The axis of the largest |component| (ties go to the later axis, z before y before x).
INLINE uint largest_axis_of(vec3 d) {
    float x = abs(d.x);
    float y = abs(d.y);
    float z = abs(d.z);
    if (x > y && x > z) return 0u;
    return y > z ? 1u : 2u;
}

/// v's components in the ray's axis order (kx, ky, kz).
INLINE vec3 in_ray_axes(vec3 v, TraceRay r) { return vec3(v[r.kx], v[r.ky], v[r.kz]); }

/// The ray origin + t·dir, t in (tmin, ...), with the per-ray constants of the box test (inverse
/// direction) and of the watertight triangle test (Woop, Benthin and Wald 2013, §3: the axis
/// permutation and the shear that maps the ray onto the +z axis).
INLINE TraceRay make_ray(vec3 origin, vec3 dir, float tmin) {
    TraceRay r;
    r.origin = origin;
    r.dir = dir;
    r.inv_dir = vec3(inverse_or_infinity(dir.x), inverse_or_infinity(dir.y), inverse_or_infinity(dir.z));
    r.tmin = tmin;
    float inf = uintBitsToFloat(0x7f800000u);
    vec3 lo_parallel = vec3(r.inv_dir.x < 0.0f ? inf : -inf, r.inv_dir.y < 0.0f ? inf : -inf, r.inv_dir.z < 0.0f ? inf : -inf);
    r.lo_on_plane = vec3(on_plane_distance(r.inv_dir.x, lo_parallel.x), on_plane_distance(r.inv_dir.y, lo_parallel.y),
                         on_plane_distance(r.inv_dir.z, lo_parallel.z));
    r.hi_on_plane = vec3(on_plane_distance(r.inv_dir.x, -lo_parallel.x), on_plane_distance(r.inv_dir.y, -lo_parallel.y),
                         on_plane_distance(r.inv_dir.z, -lo_parallel.z));
    r.kz = largest_axis_of(dir);
    uint next = r.kz == 2u ? 0u : r.kz + 1u;
    uint last = next == 2u ? 0u : next + 1u;
    bool flip = dir[r.kz] < 0.0f;  // selects, not a branch: its sign is random for random rays
    r.kx = flip ? last : next;
    r.ky = flip ? next : last;
    float inv_z = r.inv_dir[r.kz];  // the box test's 1 / dir[kz]: no division here (the paper has three)
    r.shear = vec3(dir[r.kx] * inv_z, dir[r.ky] * inv_z, inv_z);
    return r;
}

/// Distance along the ray to a slab plane `offset` = plane - origin away on an axis whose inverse
/// direction is `inv`. A ray starting on the plane gets `on_plane` (on_plane_distance) instead of
/// 0·inv (NaN when the ray is parallel to the plane, and Vulkan need not even produce that NaN).
INLINE float plane_distance(float offset, float inv, float on_plane) {
    return offset == 0.0f ? on_plane : offset * inv;
}

/// Slab test (Kay and Kajiya 1986), closed on every face and conservative (Ize 2013: the far end
/// times BOX_FAR_SCALE): where the ray enters the box within (tmin, tmax], or -1 when it misses. A
/// ray parallel to an axis (infinite inverse) is inside the slab's planes with no constraint,
/// outside them with none of the slab, and on one of them counts as inside — so a ray along a box
/// face is not lost while the closed triangle test on that face would hit (the CPU query side does
/// the same: hit_box in core_cpp/include/bvhlab/ray.h).
/// Written as the distances to the lo and hi planes, sorted by min/max, with the on-plane values
/// chosen once per ray (make_ray), rather than as the near and far planes chosen per box by the
/// sign of inv_dir: the same floats (lo - origin ≤ hi - origin, so for inv_dir > 0 the lo plane's
/// distance is the min, for inv_dir < 0 the max; a plane the origin lies on is 0 either way, and
/// for a ray parallel to it -inf as a near plane, +inf as a far one; only two distances that
/// underflow to zeros of opposite signs could come out as the other zero, which compares equal)
/// and two fewer selects per axis and box (the CPU reference on the Sponza atrium: 12% fewer
/// instructions, 5% less time).
INLINE float box_entry(vec3 lo, vec3 hi, TraceRay r, float tmax) {
    float lo_x = plane_distance(lo.x - r.origin.x, r.inv_dir.x, r.lo_on_plane.x);
    float lo_y = plane_distance(lo.y - r.origin.y, r.inv_dir.y, r.lo_on_plane.y);
    float lo_z = plane_distance(lo.z - r.origin.z, r.inv_dir.z, r.lo_on_plane.z);
    float hi_x = plane_distance(hi.x - r.origin.x, r.inv_dir.x, r.hi_on_plane.x);
    float hi_y = plane_distance(hi.y - r.origin.y, r.inv_dir.y, r.hi_on_plane.y);
    float hi_z = plane_distance(hi.z - r.origin.z, r.inv_dir.z, r.hi_on_plane.z);
    float tnear = max(max(min(lo_x, hi_x), min(lo_y, hi_y)), max(min(lo_z, hi_z), r.tmin));
    float tfar = min(min(max(lo_x, hi_x), max(lo_y, hi_y)), min(max(lo_z, hi_z), tmax)) * BOX_FAR_SCALE;
    return tnear <= tfar ? tnear : -1.0f;
}

/// Watertight ray–triangle intersection (Woop, Benthin and Wald, "Watertight Ray/Triangle
/// Intersection", JCGT 2013). The vertices, relative to the origin, are sheared so that the ray
/// runs along +z; u, v, w are the 2D edge functions of the opposite edges (the scaled barycentrics
/// of p0, p1, p2), and the ray hits when they share a sign (both faces count), closed on the edges.
/// A shared edge gives the same edge function (negated) in both triangles, from the same vertex
/// numbers, so a ray never passes between two triangles of a mesh — with Möller–Trumbore each
/// triangle rounds its own edge vectors, and rays slip through cracks (test_traverse.cpp: 7% of
/// rays aimed at a closed mesh's vertices and edges). We chose it over Möller–Trumbore for that, in
/// the same storage (three vertices instead of a vertex and two edges); measured on the wide CPU
/// traversal (bvh_bench, 1 thread, against 1764b04): 1-7% more instructions per ray on Sponza and
/// a 1M mesh with random rays, 25% more on cheap primary rays (the per-ray axis and shear), 5-37%
/// more time. Its t is a sum of vertex distances and loses more than Möller–Trumbore's where a
/// large triangle is hit near the origin (7 of 200k random rays in Sponza differ from Embree's t by
/// over 1e-4, relative, all still hits; the float64 distance is Embree's). As the paper does in
/// double precision, an edge function that comes out 0 is made again exactly (exact_edge): the
/// two products can round to one float where they differ, and two such zeros passed the sign test
/// for a ray far from a tiny triangle (a helper's audit: 1,070 of 200,000 random rays 100-500
/// units from a triangle 1.8e-5 across "hit" it, at points 600 units from it). A ray through a
/// shared edge or vertex exactly still hits both triangles, and the tie rule (closer_hit) picks one.
/// The triangle as that test sees it: the vertices relative to the ray's origin in its axes (a, b,
/// c; z their distance along the ray's kz axis), x and y sheared so that the ray runs along +z,
/// and the edge functions u, v, w. One definition for the test and for the bound on its t error
/// (ray_offset.glsl).
struct ShearedTriangle {
    vec3 a;
    vec3 b;
    vec3 c;
    float ax, ay, bx, by, cx, cy;
    float u, v, w;
};

/// a·b − fl(a·b), the rounding error of a product, exactly (no overflow or underflow inside), by
/// Dekker's product: Veltkamp's split of each factor into halves of 12 bits, whose products are
/// exact (Dekker 1971). Products, sums and differences alone, none contracted (PRECISE): a GPU may
/// split an fma into a multiply and an add (SPIR-V gives Fma no NoContraction), which made it 0.
INLINE float product_error(float a, float b, float p) {
    PRECISE float ca = 4097.0f * a;
    PRECISE float ah = ca - (ca - a);
    PRECISE float al = a - ah;
    PRECISE float cb = 4097.0f * b;
    PRECISE float bh = cb - (cb - b);
    PRECISE float bl = b - bh;
    PRECISE float e = ((ah * bh - p) + (ah * bl + al * bh)) + al * bl;
    return e;
}

/// a·b − c·d exactly, rounded once to float, where the float a·b − c·d is 0 (its two products
/// rounded to one float): the difference of the products' rounding errors (Woop et al. redo such an
/// edge function in double, whose products of floats are exact too). A shared edge's is the other
/// triangle's exactly negated (the same products, their errors by symmetric sums).
INLINE float exact_edge(float a, float b, float c, float d) {
    PRECISE float p = a * b;
    PRECISE float q = c * d;
    PRECISE float exact = product_error(a, b, p) - product_error(c, d, q);
    return exact;
}

INLINE ShearedTriangle sheared_triangle(vec3 p0, vec3 p1, vec3 p2, TraceRay r) {
    ShearedTriangle s;
    s.a = in_ray_axes(p0 - r.origin, r);
    s.b = in_ray_axes(p1 - r.origin, r);
    s.c = in_ray_axes(p2 - r.origin, r);
    s.ax = s.a.x - r.shear.x * s.a.z;
    s.ay = s.a.y - r.shear.y * s.a.z;
    s.bx = s.b.x - r.shear.x * s.b.z;
    s.by = s.b.y - r.shear.y * s.b.z;
    s.cx = s.c.x - r.shear.x * s.c.z;
    s.cy = s.c.y - r.shear.y * s.c.z;
    // uncontracted (PRECISE) as the C++ paths compute them: a 0 is the same 0 there, and a shared
    // edge's value the other triangle's negated
    PRECISE float u = s.cx * s.by - s.cy * s.bx;
    PRECISE float v = s.ax * s.cy - s.ay * s.cx;
    PRECISE float w = s.bx * s.ay - s.by * s.ax;
    s.u = u;
    s.v = v;
    s.w = w;
    // a zero made again exactly, all three too: a sliver whose third vertex is half an ulp off its
    // long edge rounds all three to 0 where they are not (the review: refused, with its neighbours'
    // shared edges now exact, a ray inside it fell through). A triangle stored as one point stays 0.
    if (s.u == 0.0f) s.u = exact_edge(s.cx, s.by, s.cy, s.bx);
    if (s.v == 0.0f) s.v = exact_edge(s.ax, s.cy, s.ay, s.cx);
    if (s.w == 0.0f) s.w = exact_edge(s.bx, s.ay, s.by, s.ax);
    return s;
}

/// t = ((u·a + v·b) + w·c) / det · (1/dir[kz]) with a, b, c the vertices' unsheared kz distances:
/// dividing before the scaling keeps it in range (coordinate_range.h). A hit in (tmin, t_best]
/// returns true with tuv = (t, barycentric of p1, of p2); t_best is inclusive so that the caller
/// can apply the tie rule.
INLINE bool hit_triangle(vec3 p0, vec3 p1, vec3 p2, TraceRay r, float t_best, OUT(vec3) tuv) {
    ShearedTriangle s = sheared_triangle(p0, p1, p2, r);
    float u = s.u;
    float v = s.v;
    float w = s.w;
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    float det = u + v + w;
    if (det == 0.0f) return false;  // seen edge-on, or a zero-area triangle (stored as one point)
    float t = (u * s.a.z + v * s.b.z + w * s.c.z) / det * r.shear.z;
    if (!(t > r.tmin && t <= t_best)) return false;
    tuv = vec3(t, v / det, w / det);
    return true;
}

/// The two roots of |o + t·d - c|² = radius², as (near, far); near > far when the ray misses.
/// Haines, Günther, Akenine-Möller, "Precision Improvements for Ray/Sphere Intersection" (Ray
/// Tracing Gems, 2019, ch. 7): the discriminant b² - a·c cancels catastrophically when the
/// sphere is small and far (float32 then resolves the ray's distance from the centre only to
/// about sqrt(ε)·|o - c|, and rays 20 radii beside a 1 mm sphere 100 m away hit it); it is
/// computed instead as radius² - |l|², l = f - (f·d / d·d)·d the part of f = o - c
/// perpendicular to the ray (their eq. 7.5, times d·d). The roots then come without cancellation
/// either: q = -(b + sign(b)·sqrt(a·Δ)), t = c/q and q/a (their eq. 7.7).
INLINE vec2 sphere_roots(vec3 centre, float radius, TraceRay r) {
    vec3 f = r.origin - centre;
    float a = dot(r.dir, r.dir);
    float b = dot(f, r.dir);
    vec3 l = f - r.dir * (b / a);
    float disc = radius * radius - dot(l, l);
    if (!(disc >= 0.0f)) return vec2(1.0f, -1.0f);
    float root = sqrt(a * disc);
    float q = b >= 0.0f ? -(b + root) : root - b;
    float c = dot(f, f) - radius * radius;
    float t0 = q != 0.0f ? c / q : 0.0f;  // q = 0: a tangent ray starting on the sphere (both 0)
    float t1 = q / a;
    return vec2(min(t0, t1), max(t0, t1));
}

/// Nearest root in (tmin, t_best] (inclusive, as hit_triangle).
INLINE bool hit_sphere(vec3 centre, float radius, TraceRay r, float t_best, OUT(float) t_hit) {
    vec2 roots = sphere_roots(centre, radius, r);
    if (roots.x > roots.y) return false;
    float t = roots.x > r.tmin ? roots.x : roots.y;
    if (!(t > r.tmin && t <= t_best)) return false;
    t_hit = t;
    return true;
}

/// How often the segment (tmin, tmax) crosses the sphere's surface: 0, 1 or 2.
INLINE uint sphere_crossings(vec3 centre, float radius, TraceRay r, float tmax) {
    vec2 roots = sphere_roots(centre, radius, r);
    if (roots.x > roots.y) return 0u;
    uint n = 0u;
    if (roots.x > r.tmin && roots.x < tmax) n += 1u;
    if (roots.y > r.tmin && roots.y < tmax) n += 1u;
    return n;
}
