// coverage.h — whether the parts of a primitive a spatial-split tree (SBVH) keeps cover it: each
// reference of a primitive stands for the part of it inside its leaf's box (Stich, Friedrich and
// Dietrich 2009 §3.2; chop.h), so a ray hits the primitive only where some such box holds it.
#pragma once
#include <vector>

#include "bvhlab/geometry.h"

namespace bvhlab {

/// Whether the boxes `parts` together hold all of triangle `v` (its whole area) or of the box
/// `sphere_box` (a sphere's references are its box cut as a box). Worked out in double, each box
/// widened by a rounding margin; a primitive of no area (volume) is covered by any parts. Past
/// kMostPieces uncovered pieces at once (coverage.cpp), each piece's centre must lie in a part
/// not yet taken away: a point outside every part is refused, one inside proves less (accepted).
bool triangle_covered(const Vec3 v[3], const std::vector<Aabb>& parts);
bool box_covered(const Aabb& sphere_box, const std::vector<Aabb>& parts);

}  // namespace bvhlab
