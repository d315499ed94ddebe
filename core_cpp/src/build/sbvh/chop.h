// chop.h — a reference cut by an axis-aligned plane: the boxes of its two parts (Stich, Friedrich
// and Dietrich 2009 §3.2, "chopped" references; the triangle is clipped, not only its box).
#pragma once
#include "bvhlab/geometry.h"
#include "bvhlab/prim_ref.h"

namespace bvhlab::sbvh {

/// The common part of two boxes (empty() when they do not meet).
inline Aabb intersect(const Aabb& a, const Aabb& b) { return {max(a.lo, b.lo), min(a.hi, b.hi)}; }

/// The boxes of the parts of reference `r` (its box is the part of its primitive it stands for)
/// below and above the plane x[axis] = pos: the triangle is clipped by the plane and the polygon's
/// box intersected with the reference's box (a sphere's box is cut as a box). Each part's box holds
/// that part of the primitive inside r's box, in exact arithmetic: the plane's crossings of the
/// edges are widened by their rounding error. A part may come out empty() (the primitive inside
/// r's box lies on one side only).
void chop_reference(const GeometryView& g, const PrimRef& r, int axis, float pos, Aabb& below, Aabb& above);

/// chop_reference for a triangle whose vertices `v` are loaded already, its reference's box `box`.
void chop_triangle(const Vec3 v[3], const Aabb& box, int axis, float pos, Aabb& below, Aabb& above);
/// Where edge a→b crosses x[axis] = pos (a and b strictly on either side), as a box that holds the
/// exact point (the float point widened by its rounding error).
Aabb edge_crossing(Vec3 a, Vec3 b, int axis, float pos);
/// chop_reference for a box (a sphere's reference).
void chop_box(const Aabb& box, int axis, float pos, Aabb& below, Aabb& above);

/// r with its box replaced (its reference kept).
inline PrimRef with_box(const PrimRef& r, const Aabb& b) {
    return PrimRef{{b.lo.x, b.lo.y, b.lo.z}, r.ref, {b.hi.x, b.hi.y, b.hi.z}, 0};
}

}  // namespace bvhlab::sbvh
