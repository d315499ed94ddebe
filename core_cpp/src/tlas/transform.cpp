// transform.cpp — checks, inverse and boxes of instance transforms (transform.h).
#include "bvhlab/transform.h"

#include "../platform/number_text.h"
#include "bvhlab/simd.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace bvhlab {
namespace {

double det3(const Transform& t) {
    const auto& m = t.m;
    auto d = [&](int i) { return double(m[i]); };
    return d(0) * (d(5) * d(10) - d(6) * d(9)) - d(1) * (d(4) * d(10) - d(6) * d(8)) +
           d(2) * (d(4) * d(9) - d(5) * d(8));
}

double column_length(const Transform& t, int c) {
    const double x = t.m[c], y = t.m[4 + c], z = t.m[8 + c];
    return std::sqrt(x * x + y * y + z * z);
}

/// The inverse of the linear part, row-major in a[9]: the adjugate over the determinant, in double.
void inverse_linear(const Transform& t, double det, double a[9]) {
    const auto& m = t.m;
    auto d = [&](int i) { return double(m[i]); };
    const double inv_det = 1.0 / det;
    const double adj[9] = {d(5) * d(10) - d(6) * d(9), d(2) * d(9) - d(1) * d(10), d(1) * d(6) - d(2) * d(5),
                           d(6) * d(8) - d(4) * d(10), d(0) * d(10) - d(2) * d(8), d(2) * d(4) - d(0) * d(6),
                           d(4) * d(9) - d(5) * d(8),  d(1) * d(8) - d(0) * d(9),  d(0) * d(5) - d(1) * d(4)};
    for (int k = 0; k < 9; ++k) a[k] = adj[k] * inv_det;
}

/// True when every entry of the linear part and of its inverse is at most kMaxTransformEntry in
/// magnitude (transform.h says why).
bool scales_in_range(const Transform& t, double det) {
    double a[9];
    inverse_linear(t, det, a);
    bool in = true;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            in &= (std::fabs(double(t.m[4 * r + c])) <= kMaxTransformEntry) &
                  (std::fabs(a[3 * r + c]) <= kMaxTransformEntry);
    return in;
}

bool determinant_invertible(const Transform& t, double det) {
    const double bound = column_length(t, 0) * column_length(t, 1) * column_length(t, 2);  // Hadamard: |det| <= bound
    return std::fabs(det) > 1e-6 * bound && std::isfinite(det);
}

}  // namespace

bool transform_invertible(const Transform& t) {
    for (float x : t.m)
        if (!std::isfinite(x)) return false;
    const double det = det3(t);
    return determinant_invertible(t, det) && scales_in_range(t, det);
}

void validate_transform(const Transform& t, const char* what) {
    if (transform_invertible(t)) return;
    for (float x : t.m)
        if (!std::isfinite(x))
            throw std::invalid_argument(std::string(what) + ": the transform has a NaN or infinite entry");
    const double det = det3(t);
    if (!determinant_invertible(t, det)) {
        // the determinant relative to its bound (Hadamard), which the test compares: a shear with
        // determinant 1 can have axes too nearly parallel ("determinant 1" alone read as a contradiction)
        const double bound = column_length(t, 0) * column_length(t, 1) * column_length(t, 2);
        if (!(bound > 0))
            throw std::invalid_argument(std::string(what) +
                                        ": the transform cannot be inverted (an axis of length 0: a zero scale)");
        throw std::invalid_argument(std::string(what) +
                                    ": the transform cannot be inverted (a zero-scale axis, or axes "
                                    "(nearly) parallel: |determinant| " +
                                    number_text(std::fabs(det)) + " is " + number_text(float(std::fabs(det) / bound)) +
                                    " of the product of its axes' lengths, which must be above 1e-6)");
    }
    throw std::invalid_argument(std::string(what) +
                                ": the transform scales by more than 2^76 (7.6e22) or less than 2^-76 (1.3e-23) "
                                "along some axis, beyond what float32 rays can follow into the mesh");
}

Transform inverse(const Transform& t) {
    double a[9];
    inverse_linear(t, det3(t), a);  // then -A^-1 · translation
    auto d = [&](int i) { return double(t.m[i]); };
    Transform out;
    for (int r = 0; r < 3; ++r) {
        const double tr = -(a[3 * r] * d(3) + a[3 * r + 1] * d(7) + a[3 * r + 2] * d(11));
        out.m[4 * r] = float(a[3 * r]), out.m[4 * r + 1] = float(a[3 * r + 1]), out.m[4 * r + 2] = float(a[3 * r + 2]);
        out.m[4 * r + 3] = float(tr);
    }
    return out;
}

namespace {

/// std::nextafter(x, -inf) and (x, +inf) from the bits, as libm computes them (a call of ~30
/// instructions each, six an instance: 18% of a 100,000-instance build_tlas before).
float next_down(float x) {
    if (!(x > -INFINITY)) return x;  // -inf, NaN
    if (x == 0.0f) return -0x1p-149f;
    std::uint32_t bits;
    std::memcpy(&bits, &x, 4);
    bits = x > 0.0f ? bits - 1 : bits + 1;
    std::memcpy(&x, &bits, 4);
    return x;
}
float next_up(float x) { return -next_down(-x); }

/// The union of the moved boxes before rounding: per row r of the transform, the least and
/// the greatest of centre - half and centre + half over the boxes, where (Arvo, Graphics Gems 1990)
///   centre = ((m[r][0] c.x + m[r][1] c.y) + m[r][2] c.z) + m[r][3],
///   half   = (|m[r][0]| h.x + |m[r][1]| h.y) + |m[r][2]| h.z,
/// in this order in double on every path. The boxes two at a time (SSE2) where there is SSE: 300
/// instructions for eight boxes against 870 box by box with the rows paired, 1,270 before either.
/// Min and max do not depend on the order of the boxes but for the sign of a zero, which the
/// rounding outwards (transform_boxes) makes the same.
void union_of_moved(const Transform& t, const BoxesToMove& boxes, double lo[3], double hi[3]) {
    const std::size_t n = boxes.centre[0].size();
    for (int r = 0; r < 3; ++r) {
        const double m0 = t.m[4 * r], m1 = t.m[4 * r + 1], m2 = t.m[4 * r + 2], m3 = t.m[4 * r + 3];
        const double a0 = std::fabs(m0), a1 = std::fabs(m1), a2 = std::fabs(m2);
        const double *cx = boxes.centre[0].data(), *cy = boxes.centre[1].data(), *cz = boxes.centre[2].data();
        const double *hx = boxes.half[0].data(), *hy = boxes.half[1].data(), *hz = boxes.half[2].data();
#ifdef BVHLAB_SSE
        const __m128d vm0 = _mm_set1_pd(m0), vm1 = _mm_set1_pd(m1), vm2 = _mm_set1_pd(m2), vm3 = _mm_set1_pd(m3);
        const __m128d va0 = _mm_set1_pd(a0), va1 = _mm_set1_pd(a1), va2 = _mm_set1_pd(a2);
        __m128d vlo = _mm_set1_pd(INFINITY), vhi = _mm_set1_pd(-INFINITY);
        for (std::size_t k = 0; k < n; k += 2) {
            const __m128d centre = _mm_add_pd(
                _mm_add_pd(_mm_add_pd(_mm_mul_pd(vm0, _mm_loadu_pd(cx + k)), _mm_mul_pd(vm1, _mm_loadu_pd(cy + k))),
                           _mm_mul_pd(vm2, _mm_loadu_pd(cz + k))),
                vm3);
            const __m128d half =
                _mm_add_pd(_mm_add_pd(_mm_mul_pd(va0, _mm_loadu_pd(hx + k)), _mm_mul_pd(va1, _mm_loadu_pd(hy + k))),
                           _mm_mul_pd(va2, _mm_loadu_pd(hz + k)));
            vlo = _mm_min_pd(_mm_sub_pd(centre, half), vlo), vhi = _mm_max_pd(_mm_add_pd(centre, half), vhi);
        }
        vlo = _mm_min_pd(vlo, _mm_unpackhi_pd(vlo, vlo)), vhi = _mm_max_pd(vhi, _mm_unpackhi_pd(vhi, vhi));
        lo[r] = _mm_cvtsd_f64(vlo), hi[r] = _mm_cvtsd_f64(vhi);
#else
        lo[r] = INFINITY, hi[r] = -INFINITY;
        for (std::size_t k = 0; k < n; ++k) {
            const double centre = m0 * cx[k] + m1 * cy[k] + m2 * cz[k] + m3;
            const double half = a0 * hx[k] + a1 * hy[k] + a2 * hz[k];
            lo[r] = std::min(lo[r], centre - half), hi[r] = std::max(hi[r], centre + half);
        }
#endif
    }
}

}  // namespace

BoxesToMove::BoxesToMove(const Aabb* boxes, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k) {
        const Aabb& box = boxes[k];
        if (box.empty()) continue;
        for (int a = 0; a < 3; ++a) {
            centre[a].push_back(0.5 * (double(box.lo[a]) + box.hi[a]));
            half[a].push_back(0.5 * (double(box.hi[a]) - box.lo[a]));
        }
    }
    if (centre[0].size() % 2)
        for (int a = 0; a < 3; ++a) centre[a].push_back(centre[a].back()), half[a].push_back(half[a].back());
}

Aabb transform_boxes(const Transform& t, const BoxesToMove& boxes) {
    double lo[3], hi[3];
    union_of_moved(t, boxes, lo, hi);
    Aabb out;
    if (lo[0] > hi[0]) return out;  // nothing but empty boxes (or a NaN in the transform, which min and max pass over)
    for (int r = 0; r < 3; ++r) {
        // Rounded outwards: a vertex moved into the world in float, or a ray moved into the object,
        // lands within a few ulps of its exact place. (A zero's sign changes nothing here: with
        // pad 0, lo and hi are both zero, and next_down and next_up give the same for ±0.)
        const double pad = 0x1p-20 * std::max({std::fabs(lo[r]), std::fabs(hi[r]), hi[r] - lo[r]});
        out.lo[r] = next_down(float(lo[r] - pad));
        out.hi[r] = next_up(float(hi[r] + pad));
    }
    return out;
}

Aabb transform_boxes(const Transform& t, const Aabb* boxes, std::size_t count) {
    return transform_boxes(t, BoxesToMove(boxes, count));
}

Aabb transform_box(const Transform& t, const Aabb& box) { return transform_boxes(t, &box, 1); }

}  // namespace bvhlab
