// transform.h — the affine object-to-world transform of an instance (a 3×4 matrix), its inverse,
// and what the two-level tree does with it: points, directions and boxes moved between spaces.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

#include "bvhlab/aabb.h"
#include "bvhlab/vec3.h"

namespace bvhlab {

/// A 3×4 row-major affine matrix: world = M · (object, 1). m[4 r + c] is row r, column c; column 3
/// is the translation (the layout of Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR and of Blender's
/// matrix_world without its last row).
struct Transform {
    std::array<float, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    Vec3 point(Vec3 p) const {
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
    Vec3 vector(Vec3 d) const {
        return {m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                m[8] * d.x + m[9] * d.y + m[10] * d.z};
    }
    bool is_identity() const { return m == Transform{}.m; }
};

/// The largest |entry| of an instance's linear part A and of its inverse: 2^76. The two-level walk
/// moves a world ray's direction d, scaled so that its largest component lies in [0.5, 1)
/// (coordinate_range.h, scale_ray), into object space, where it must stay within [kMinDirection,
/// kMaxDirection] = [2^-80, 2^80] to be scaled again: with every entry at most 2^76, A^-1 d has
/// components below 3·2^76 < 2^80, and |A^-1 d| ≥ |d| / σmax(A) ≥ 0.5 / (3·2^76) (σmax at most
/// the Frobenius norm), so its largest component is above 2^-80. An instance scaled by 1e-25
/// passed the determinant's test and then every ray missed it without a word.
inline constexpr double kMaxTransformEntry = 0x1p76;

/// Throws std::invalid_argument, naming `what`, for a transform with a NaN or infinite entry, one
/// that cannot be inverted (a zero-scale axis, or axes so nearly parallel that the inverse would
/// be noise: |det| below 1e-6 of the product of its columns' lengths, Hadamard's bound), or one
/// whose linear part or inverse has an entry beyond kMaxTransformEntry. An accepted transform of
/// nearly parallel axes still moves rays into the mesh with float32's rounding times its
/// condition: hits near a triangle's outer edge may be lost (design.md, "Two-level trees").
void validate_transform(const Transform& t, const char* what);

/// What validate_transform accepts, without a message.
bool transform_invertible(const Transform& t);

/// The inverse of a transform that validate_transform accepts (computed in double, rounded once).
Transform inverse(const Transform& t);

/// How the two-level walks move a world ray into an instance's object space: the linear part
/// L = A^-1 of the world-to-object transform in columns 0-2 and, in column 3, the object's origin
/// in the world, P (the object-to-world translation): a world point p goes to L·(p - P). Its
/// world-to-object form L·p + (-L·P) sums two numbers that cancel where an instance is small and
/// far from the world's origin (scale 1e-3 at x = 1000: both near 1e6, the ray origin off by
/// float32's spacing there, 0.06; 1,807 of 2,000 rays' t off by more than 1e-3, the flattened
/// scene's world vertices 1,729): p - P is exact where they are close (Sterbenz), and L scales it.
/// The shaders' GpuInstance rows hold the same 12 numbers (surface.glsl object_point).
struct ObjectMap {
    std::array<float, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    Vec3 point(Vec3 p) const {
        const Vec3 d{p.x - m[3], p.y - m[7], p.z - m[11]};
        return vector(d);
    }
    Vec3 vector(Vec3 d) const {
        return {m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                m[8] * d.x + m[9] * d.y + m[10] * d.z};
    }
};

/// An ObjectMap by columns, as the two-level walks read it (tlas.h LeafInstance): L's columns at
/// c[0, 3), c[3, 6), c[6, 9) and P at c[9, 12), so that a ray is moved four lanes at once, a column
/// times one component at a time (object_ray.h move_ray: ObjectMap's operations in its order, lane
/// by lane, so the same bits), where by rows each output is a sum across lanes.
struct ObjectColumns {
    std::array<float, 12> c{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};

    ObjectColumns() = default;
    explicit ObjectColumns(const ObjectMap& map) {
        for (int col = 0; col < 4; ++col)
            for (int row = 0; row < 3; ++row) c[3 * col + row] = map.m[4 * row + col];
    }
};

/// The ObjectMap of an instance placed by `object_to_world`, whose inverse is `world_to_object`.
inline ObjectMap object_map(const Transform& object_to_world, const Transform& world_to_object) {
    ObjectMap out;
    out.m = world_to_object.m;
    out.m[3] = object_to_world.m[3], out.m[7] = object_to_world.m[7], out.m[11] = object_to_world.m[11];
    return out;
}

/// A box holding `t` applied to every point of the `count` boxes (Arvo's moved centre and
/// |M|-weighted half extent, in double, rounded outwards by a relative 2^-20 once, so that float
/// rounding of a moved vertex stays inside). Empty boxes add nothing; none at all: an empty box.
Aabb transform_boxes(const Transform& t, const Aabb* boxes, std::size_t count);
Aabb transform_box(const Transform& t, const Aabb& box);  ///< transform_boxes of one box

/// Boxes made ready to be moved by many transforms (a BLAS's top boxes, by each of its instances:
/// build_tlas): the centre and half extent of each non-empty box in double, by axis, in a count
/// rounded up to even (the last box repeated, which changes no union).
struct BoxesToMove {
    std::vector<double> centre[3], half[3];
    BoxesToMove(const Aabb* boxes, std::size_t count);
};
/// transform_boxes(t, boxes, count) of the boxes that `boxes` was made from: the same box, bit for bit.
Aabb transform_boxes(const Transform& t, const BoxesToMove& boxes);

}  // namespace bvhlab
