// transforms.h — instance transforms for the two-level tests (test_tlas*, test_render_tlas).
#pragma once
#include <cmath>

#include "bvhlab/transform.h"

namespace bvhlab::test {

/// rotation about a unit axis by `angle`, then scale (applied first), then translation
inline Transform make_transform(Vec3 axis, float angle, Vec3 scale, Vec3 move) {
    axis = normalize(axis);
    const float c = std::cos(angle), s = std::sin(angle), k = 1 - c;
    const float r[9] = {
        c + axis.x * axis.x * k,          axis.x * axis.y * k - axis.z * s, axis.x * axis.z * k + axis.y * s,
        axis.y * axis.x * k + axis.z * s, c + axis.y * axis.y * k,          axis.y * axis.z * k - axis.x * s,
        axis.z * axis.x * k - axis.y * s, axis.z * axis.y * k + axis.x * s, c + axis.z * axis.z * k};
    Transform t;
    for (int row = 0; row < 3; ++row) {
        t.m[4 * row] = r[3 * row] * scale.x, t.m[4 * row + 1] = r[3 * row + 1] * scale.y;
        t.m[4 * row + 2] = r[3 * row + 2] * scale.z, t.m[4 * row + 3] = move[row];
    }
    return t;
}

}  // namespace bvhlab::test
