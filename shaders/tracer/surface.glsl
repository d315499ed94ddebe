// surface.glsl — a hit as shading sees it (surface_at: its point, normal and material, the
// primitive fetched once) and where rays leaving it start (ray_origin, with ray_offset.glsl's
// bounds: pbrt-v4 §6.8); an instance's points and normals moved between its spaces. Included by
// shade.glsl after RayTask and the loaders.

/// A hit as shading sees it.
struct Surface {
    vec3 p;          ///< the hit point as traced, origin + t·dir: where the surface is shaded
    vec3 base;       ///< where rays leaving it start from: p recomputed on the primitive (surface_at)
    vec3 p_error;    ///< a bound on base's error, per coordinate (pbrt-v4 §6.8.5)
    vec3 facing;     ///< the geometric normal on the side the ray came from
    bool entering;   ///< the ray hit the outside
    GpuMaterial m;
    float opaque;    ///< what is neither reflected nor transmitted
    bool triangle;   ///< a triangle, whose vertices in the world follow
    vec3 v0;
    vec3 v1;
    vec3 v2;
};

/// An object-space normal in the world: times the inverse transpose of the object-to-world
/// transform, i.e. the transpose of the world-to-object one (PBRT §3.10.3, "Normals"). No sign
/// flip for a mirroring transform: the outside stays the outside, as Blender and Cycles keep a
/// mirrored object's normals (only the vertices' winding is reversed in the world).
vec3 normal_to_world(GpuInstance inst, vec3 n) {
    return xyz(inst.row0) * n.x + xyz(inst.row1) * n.y + xyz(inst.row2) * n.z;
}

/// What each component of cross(a, b) sums in magnitude: the scale of its rounding.
vec3 cross_magnitude(vec3 a, vec3 b) {
    a = abs(a);
    b = abs(b);
    return vec3(a.y * b.z + a.z * b.y, a.z * b.x + a.x * b.z, a.x * b.y + a.y * b.x);
}

/// A point q of an instance's object space in the world, `p`: the world-to-object transform undone,
/// its 3×3 part L inverted by its adjugate (the inverse's columns are the rows' cross products over
/// the determinant), then the object's origin P added (GpuInstance), and `err`, a bound on that
/// arithmetic's error per coordinate: γ(6) of what the adjugate's products sum over |q| (each entry
/// two roundings, the sum three, the division one), plus |L⁻¹q| times the determinant's relative
/// error, γ(5)·(|r0|·|adj|)/|det| — large where the transform is skewed and stretched (a bound of
/// γ(16)·|p| alone was 262× too small at 100:1 with skew: a stretched sphere's instance shadowed
/// itself) — and γ(1)·|p| for adding P. False where it is no usable number (a determinant over- or
/// underflowed, an object scale beyond about 1e±12, or one so ill-conditioned that the bound
/// fails): p is not made.
bool world_point(GpuInstance inst, vec3 q, OUT(vec3) p, OUT(vec3) err) {
    vec3 r0 = xyz(inst.row0);
    vec3 r1 = xyz(inst.row1);
    vec3 r2 = xyz(inst.row2);
    vec3 a0 = cross(r1, r2);
    float det = dot(r0, a0);
    float det_rel = gamma_bound(5.0f) * dot(abs(r0), cross_magnitude(r1, r2)) / abs(det);
    if (!(abs(det) >= SMALLEST_NORMAL && det_rel < 0.5f)) return false;
    vec3 local = (a0 * q.x + cross(r2, r0) * q.y + cross(r0, r1) * q.z) / det;
    p = local + vec3(inst.row0.w, inst.row1.w, inst.row2.w);
    vec3 sums = cross_magnitude(r1, r2) * abs(q.x) + cross_magnitude(r2, r0) * abs(q.y) + cross_magnitude(r0, r1) * abs(q.z);
    err = gamma_bound(6.0f) * sums / abs(det) + det_rel * abs(local) + gamma_bound(1.0f) * abs(p);
    return max(max(err.x, err.y), err.z) < 1e30f;
}

/// The hit point (shaded where traced, as the flattened copy of a two-level scene is), the point
/// rays leave it from with a bound on its error, its geometric normal (unit, outwards; triangles: by
/// winding in the mesh's own space) and material, the primitive fetched once; a two-level hit's
/// normal comes from its instance's object space. The point rays leave from is recomputed on the
/// primitive (pbrt-v4 §6.8.5), since origin + t·dir carries the error of the origin and of t
/// (which grows with the distance and, for the watertight test, with the triangle's size): a
/// triangle's is v0 + b1·e1 + b2·e2 from the hit's barycentrics (any barycentrics give a point of
/// the plane; only the rounding of this sum moves it off), from its vertices in the world (an
/// instance's moved there: the same barycentrics, and the same offsets as its flattened copy's;
/// from the object space's, an instanced glass knot and its flattened copy were 124 pixels apart,
/// 14 before), a sphere's the traced point projected onto it, c + (p - c)·r / |p - c| (an
/// instanced sphere keeps origin + t·dir, bounded by the rounding of that sum and its transform).
Surface surface_at(RayTask task, Hit hit) {
    Surface s;
    vec3 traced = task.origin + task.dir * hit.t;
    bool moved = hit.instance != NO_INSTANCE;
    GpuInstance inst;
    if (moved) inst = load_instance(hit.instance);
    s.p_error = gamma_bound(16.0f) * (abs(task.origin) + abs(task.dir * hit.t));
    s.p = traced;
    s.base = traced;
    vec3 n;
    uint material;
    if ((hit.ref & REF_SPHERE_BIT) != 0u) {
        GpuSphere sphere = load_sphere(hit.ref & REF_INDEX_MASK);
        vec3 c = xyz(sphere.center_radius);
        n = (moved ? object_point(inst, traced) : traced) - c;
        float len = length(n);
        if (len > 0.0f) n = n * (sphere.center_radius.w / len);
        // γ(5)|q| for the reprojection (pbrt), γ(4)|q| more for the sphere test's own rounding of
        // |o - c|² - r², whose sign decides whether a ray leaving the surface meets it again
        if (!moved) s.base = c + n;
        if (!moved) s.p_error = gamma_bound(9.0f) * abs(n) + gamma_bound(1.0f) * abs(s.base);
        material = sphere.material.x;
        s.triangle = false;
    } else {
        GpuTriangle tri = load_triangle(hit.ref);
        n = cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
        material = tri.material;
        s.v0 = tri.v0;
        s.v1 = tri.v1;
        s.v2 = tri.v2;
        vec3 err0 = vec3(0.0f);
        vec3 err1 = vec3(0.0f);
        vec3 err2 = vec3(0.0f);
        // an instance's vertices in the world, with the error of the inverted transform; where it
        // has no usable inverse, the traced point and its bound (and no triangle's t bound)
        s.triangle = !moved || (world_point(inst, tri.v0, s.v0, err0) && world_point(inst, tri.v1, s.v1, err1) &&
                                world_point(inst, tri.v2, s.v2, err2));
        if (!s.triangle) {
            // the traced point's t as the test made it, in the instance's space (t is the same
            // number there), four times over for the ray that leaves (its own bound needs the
            // world vertices this transform has none of)
            vec3 o = object_point(inst, task.origin);
            s.p_error += vec3(4.0f * triangle_t_error(tri.v0, tri.v1, tri.v2, o, object_vector(inst, task.dir)));
        }
        if (s.triangle) {
            vec3 e1 = s.v1 - s.v0;
            vec3 e2 = s.v2 - s.v0;
            s.base = s.v0 + (e1 * hit.u + e2 * hit.v);
            s.p_error = gamma_bound(3.0f) * (abs(e1 * hit.u) + abs(e2 * hit.v)) + gamma_bound(1.0f) * abs(s.base) + err0 +
                        (err0 + err1) * hit.u + (err0 + err2) * hit.v;
        }
    }
    n = unit_vector(moved ? normal_to_world(inst, n) : n);
    s.entering = dot(n, task.dir) < 0.0f;
    s.facing = s.entering ? n : -n;
    s.m = load_material(material);
    s.opaque = max(1.0f - s.m.color_reflective.w - s.m.transparent_ior.x, 0.0f);
    return s;
}

/// Where a ray leaving the surface `f` along `dir` starts (outward: to the side of `facing`,
/// else through it): off the surface by p's error bound projected onto the normal (pbrt-v4
/// §6.8.6), plus, for a triangle, how far the watertight test's t for this very ray may be off
/// (pbrt's deltaT, §6.8.4; measured in the world for an instance too, whose test runs in its
/// object space: the bound is doubled, and a flat scene and its instanced copy start their rays
/// alike).
vec3 ray_origin(Surface f, vec3 dir, bool outward) {
    float amount = dot(abs(f.facing), f.p_error);
    if (f.triangle) amount += triangle_t_error(f.v0, f.v1, f.v2, f.base, dir) * abs(dot(dir, f.facing));
    // a finite start, however far the bound (a grazing ray near ±2^40 overflowed it: NaN origins)
    amount = min(amount, 1e30f);
    return offset_origin(f.base, outward ? f.facing : -f.facing, amount);
}
