#include "bvhlab/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "bvhlab/build_config.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/simd.h"

namespace bvhlab {
namespace {

bool finite_floats(const float* p, int n) {
    for (int i = 0; i < n; ++i)
        if (!std::isfinite(p[i])) return false;
    return true;
}

PrimRef triangle_ref(const GeometryView& g, std::size_t i) {
    Aabb box;
    for (int c = 0; c < 3; ++c) box.grow(g.vertex(i, c));
    return {{box.lo.x, box.lo.y, box.lo.z}, static_cast<std::uint32_t>(i), {box.hi.x, box.hi.y, box.hi.z}, 0};
}

PrimRef sphere_ref(const GeometryView& g, std::size_t i) {
    Vec3 c = g.sphere_center(i);
    float r = g.sphere_radius(i);
    return {{c.x - r, c.y - r, c.z - r},
            gpu::REF_SPHERE_BIT | static_cast<std::uint32_t>(i),
            {c.x + r, c.y + r, c.z + r},
            0};
}

/// Throws naming the first non-finite triangle (the slow, exact search behind the fast check).
[[noreturn]] void throw_bad_triangle(const GeometryView& g) {
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        if (!finite_floats(g.triangles + 9 * i, 9))
            throw std::invalid_argument("triangle " + std::to_string(i) + " has a NaN or infinite vertex coordinate");
    throw std::logic_error("throw_bad_triangle: no bad triangle");
}

std::string range_text() {
    char text[96];
    std::snprintf(text, sizeof text, "the supported range [-%.5g, %.5g] (2^40)", kMaxCoordinate, kMaxCoordinate);
    return text;
}

/// Throws naming the first triangle with a coordinate outside ±kMaxCoordinate (coordinate_range.h).
[[noreturn]] void throw_far_triangle(const GeometryView& g) {
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        for (int c = 0; c < 3; ++c)
            if (!in_coordinate_range(g.vertex(i, c)))
                throw std::invalid_argument("triangle " + std::to_string(i) + " has a vertex coordinate outside " +
                                            range_text() +
                                            ", where float32 ray tests would overflow; move or scale "
                                            "the scene nearer the origin");
    throw std::logic_error("throw_far_triangle: no such triangle");
}

void validate_spheres(const GeometryView& g) {
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        if (!finite_floats(g.spheres + 4 * i, 3))
            throw std::invalid_argument("sphere " + std::to_string(i) + " has a NaN or infinite centre");
        float r = g.sphere_radius(i);
        if (!(r >= kMinRadius) || !std::isfinite(r)) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "sphere %zu has radius %g; a radius must be a finite number of at "
                          "least 2^-60 (8.7e-19), below which its square underflows",
                          i, double(r));
            throw std::invalid_argument(text);
        }
        Aabb box = sphere_ref(g, i).box();
        if (!in_coordinate_range(box.lo) || !in_coordinate_range(box.hi))
            throw std::invalid_argument("sphere " + std::to_string(i) + " (centre ± radius) reaches outside " +
                                        range_text() + ", where float32 ray tests would overflow");
    }
}

void validate_counts(const GeometryView& g) {
    // a reference's index holds 2^31 - 1; the SAH's counts rounded up to whole blocks (sah.h)
    // must stay below 2^31, which the sweeps convert to floats as signed integers
    constexpr std::size_t kMaxPrimitives = gpu::REF_INDEX_MASK - 2 * (kMaxSahBlock - 1);
    if (g.primitive_count() > kMaxPrimitives)
        throw std::invalid_argument("too many primitives: at most " + std::to_string(kMaxPrimitives));
    if ((g.triangle_count && !g.triangles) || (g.sphere_count && !g.spheres))
        throw std::invalid_argument("primitive count given without data");
}

}  // namespace

void validate(const GeometryView& g) {
    validate_counts(g);
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        if (!finite_floats(g.triangles + 9 * i, 9)) throw_bad_triangle(g);
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        for (int c = 0; c < 3; ++c)
            if (!in_coordinate_range(g.vertex(i, c))) throw_far_triangle(g);
    validate_spheres(g);
}

BigVector<PrimRef> make_prim_refs(const GeometryView& g) {
    validate_counts(g);
    BigVector<PrimRef> refs(g.primitive_count());
    // Checked on the way: x·0 is 0 for finite x and NaN otherwise, so one sum tells whether any
    // coordinate was NaN or infinite, without a separate pass over the input.
    // The largest |coordinate| is tracked the same way, for the range check.
    // Four lanes at a time: a triangle's vertices are loaded as three overlapping 4-float rows
    // (lane 3 of each is the next vertex's x, or the next triangle's first coordinate, which is
    // checked anyway), so all but the last triangle read within the input; the last one is done
    // by the scalar path.
    const F4 zero = F4::splat(0.0f);
    F4 poison4 = zero, reach4 = zero;
    const std::size_t simd_count = g.triangle_count ? g.triangle_count - 1 : 0;
    for (std::size_t i = 0; i < simd_count; ++i) {
        const float* v = g.triangles + 9 * i;
        const F4 a = F4::load(v), b = F4::load(v + 3), c = F4::load(v + 6);
        poison4 = poison4 + (a * zero + b * zero) + c * zero;
        reach4 = max(reach4, max(max(max(a, neg(a)), max(b, neg(b))), max(c, neg(c))));
        PrimRef& r = refs[i];
        float* row = reinterpret_cast<float*>(&r);  // lo, ref | hi, code: lane 3 lands on ref and code,
        min(a, min(b, c)).store(row);               // which are written next
        max(a, max(b, c)).store(row + 4);
        r.ref = static_cast<std::uint32_t>(i), r.code = 0;
    }
    float poison = poison4.lane(0) + poison4.lane(1) + poison4.lane(2) + poison4.lane(3);
    float reach = std::max(std::max(reach4.lane(0), reach4.lane(1)), std::max(reach4.lane(2), reach4.lane(3)));
    for (std::size_t i = simd_count; i < g.triangle_count; ++i) {
        const float* v = g.triangles + 9 * i;
        for (int k = 0; k < 9; ++k) poison += v[k] * 0.0f, reach = std::max(reach, std::fabs(v[k]));
        refs[i] = triangle_ref(g, i);
    }
    if (poison != 0.0f) throw_bad_triangle(g);  // NaN != 0 too
    if (reach > kMaxCoordinate) throw_far_triangle(g);
    validate_spheres(g);
    for (std::size_t i = 0; i < g.sphere_count; ++i) refs[g.triangle_count + i] = sphere_ref(g, i);
    return refs;
}

namespace {

/// Eight independent multiply-rotate lanes over 8-byte words (the structure of xxHash64, Collet
/// 2014, with twice its lanes: each lane's multiply chain waits 8 cycles a word, and four lanes
/// kept the loop at 4 bytes a cycle), folded and avalanched at the end.
class Fingerprint {
public:
    void add(const void* data, std::size_t n) {
        const auto* bytes = static_cast<const unsigned char*>(data);
        std::size_t i = 0;
        for (; i + 64 <= n; i += 64)
            for (int k = 0; k < 8; ++k) lane_[k] = round(lane_[k], word(bytes + i + 8 * k));
        for (; i + 8 <= n; i += 8) lane_[0] = round(lane_[0], word(bytes + i));
        if (i < n) lane_[1] = round(lane_[1], std::uint64_t(word4(bytes + i)));
        total_ += n;
    }
    std::uint64_t finish() const {
        std::uint64_t h = total_ * kPrime1;
        for (std::uint64_t lane : lane_) h = (h ^ round(0, lane)) * kPrime1 + kPrime2;
        h ^= h >> 33, h *= kPrime2, h ^= h >> 29, h *= kPrime3;
        return h ^ (h >> 32);
    }

private:
    static constexpr std::uint64_t kPrime1 = 0x9E3779B185EBCA87ull, kPrime2 = 0xC2B2AE3D27D4EB4Full,
                                   kPrime3 = 0x165667B19E3779F9ull;
    static std::uint64_t round(std::uint64_t acc, std::uint64_t w) {
        acc += w * kPrime2;
        acc = (acc << 31) | (acc >> 33);
        return acc * kPrime1;
    }
    static std::uint64_t word(const unsigned char* p) {
        std::uint64_t w;
        std::memcpy(&w, p, 8);
        return w;
    }
    static std::uint32_t word4(const unsigned char* p) {
        std::uint32_t w;
        std::memcpy(&w, p, 4);
        return w;
    }

    std::uint64_t lane_[8] = {kPrime1 + kPrime2, kPrime2,           0,           0 - kPrime1,
                              kPrime3,           kPrime3 + kPrime1, kPrime1 * 3, 0 - kPrime2};
    std::uint64_t total_ = 0;
};

}  // namespace

std::uint64_t geometry_fingerprint(const GeometryView& g) {
    Fingerprint f;
    const std::uint64_t counts[2] = {g.triangle_count, g.sphere_count};
    f.add(counts, sizeof(counts));
    if (g.triangle_count) f.add(g.triangles, 9 * sizeof(float) * g.triangle_count);
    if (g.sphere_count) f.add(g.spheres, 4 * sizeof(float) * g.sphere_count);
    return f.finish();
}

}  // namespace bvhlab
