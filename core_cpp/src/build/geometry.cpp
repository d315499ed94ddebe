#include "bvhlab/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "../platform/number_text.h"
#include "bvhlab/build_config.h"
#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/simd.h"
#include "bvhlab/thread_pool.h"

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

/// What the exact searches below say where the fast check found a bad triangle and they find none.
constexpr const char* kChangedWhileRead =
    "the triangles changed while they were read (another thread writing into the array during the call?)";

/// Throws naming the first non-finite triangle (the slow, exact search behind the fast check).
[[noreturn]] void throw_bad_triangle(const GeometryView& g) {
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        if (!finite_floats(g.triangles + 9 * i, 9))
            throw std::invalid_argument("triangle " + std::to_string(i) + " has a NaN or infinite vertex coordinate");
    // the fast check saw one, this search none: the caller's arrays changed in between
    throw std::invalid_argument(kChangedWhileRead);
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
    throw std::invalid_argument(kChangedWhileRead);
}

void validate_spheres(const GeometryView& g) {
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        if (!finite_floats(g.spheres + 4 * i, 3))
            throw std::invalid_argument("sphere " + std::to_string(i) + " has a NaN or infinite centre");
        float r = g.sphere_radius(i);
        if (!(r >= kMinRadius) || !std::isfinite(r))
            throw std::invalid_argument("sphere " + std::to_string(i) + " has radius " + number_text(r) +
                                        "; a radius must be a finite number of at least 2^-60 (8.7e-19), below "
                                        "which its square underflows");
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

void check_extent(const Aabb& box, std::size_t triangle_count) {
    const Vec3 side = box.hi - box.lo;
    const float extent = std::max(side.x, std::max(side.y, side.z));
    if (triangle_count == 0 || !(extent > 0.0f) || extent >= kMinExtent) return;
    char text[320];
    std::snprintf(text, sizeof text,
                  "the scene spans only %.3g units (the largest side of its primitives' box): below 2^-32 "
                  "(%.3g) float32's triangle test loses hits (its products underflow); scale the scene up",
                  double(extent), double(kMinExtent));
    throw std::invalid_argument(text);
}

void validate(const GeometryView& g) {
    validate_counts(g);
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        if (!finite_floats(g.triangles + 9 * i, 9)) throw_bad_triangle(g);
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        for (int c = 0; c < 3; ++c)
            if (!in_coordinate_range(g.vertex(i, c))) throw_far_triangle(g);
    validate_spheres(g);
}

Aabb prim_box(const GeometryView& g, std::uint32_t ref) {
    const std::size_t i = ref_index(ref);
    return (is_sphere_ref(ref) ? sphere_ref(g, i) : triangle_ref(g, i)).box();
}

namespace {

/// The fingerprint is a sum of one term per primitive (mod 2^64): the term folds the primitive's
/// words into a value seeded by its index, one multiply a word (xor, rotate and multiply by an odd
/// constant: for fixed other inputs each step maps a word, and the running value, one to one), then
/// mixes it (the splitmix64 finaliser, Steele et al. 2014). So a change to one primitive always
/// changes its term, a swap of two changes both terms (each is seeded by its primitive's index),
/// and the terms can be added in any order: chunk by chunk on several threads, and inside the
/// pass that makes the references (the multiplies run beside its vector work).
constexpr std::uint64_t kPrime1 = 0x9E3779B185EBCA87ull, kPrime2 = 0xC2B2AE3D27D4EB4Full;

inline std::uint64_t fold(std::uint64_t h, std::uint64_t w) {
    h ^= w;
    return ((h << 29) | (h >> 35)) * kPrime2;
}
inline std::uint64_t mix(std::uint64_t x) {
    x ^= x >> 30, x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27, x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}
/// Term of primitive `index` (triangles 0..T-1, then spheres) over its kFloats floats.
template <int kFloats>
inline std::uint64_t term(std::uint64_t index, const float* p) {
    std::uint64_t h = (index + 1) * kPrime1;
    for (int k = 0; k + 2 <= kFloats; k += 2) {
        std::uint64_t w;
        std::memcpy(&w, p + k, 8);
        h = fold(h, w);
    }
    if constexpr (kFloats % 2) {
        std::uint32_t w;
        std::memcpy(&w, p + kFloats - 1, 4);
        h = fold(h, w);
    }
    return mix(h);
}
constexpr int kTriangleFloats = 9, kSphereFloats = 4;

/// The fingerprint from the sum of every primitive's term: with the counts mixed in.
std::uint64_t finish_fingerprint(std::uint64_t triangle_count, std::uint64_t sphere_count, std::uint64_t sum) {
    return mix(sum ^ mix(triangle_count * kPrime1 + sphere_count * kPrime2));
}
std::uint64_t finish_fingerprint(const GeometryView& g, std::uint64_t sum) {
    return finish_fingerprint(g.triangle_count, g.sphere_count, sum);
}

/// Triangles per chunk of the passes over the input on several threads (~0.6 MB of input).
constexpr std::size_t kChunkTriangles = 1u << 14;

/// What a chunk of make_prim_refs found: its terms' sum and the validation's two reductions.
struct ChunkChecks {
    std::uint64_t sum = 0;
    float poison = 0.0f, reach = 0.0f;
    /// Bounds of the references' boxes and of their twice-centroids (lanes 0-2).
    F4 lo = F4::splat(std::numeric_limits<float>::infinity()), hi = neg(lo), c2_lo = lo, c2_hi = hi;

    void grow(F4 ref_lo, F4 ref_hi) {
        const F4 c2 = ref_lo + ref_hi;
        lo = min(lo, ref_lo), hi = max(hi, ref_hi), c2_lo = min(c2_lo, c2), c2_hi = max(c2_hi, c2);
    }
    void merge(const ChunkChecks& o) {
        sum += o.sum, poison += o.poison, reach = std::max(reach, o.reach);
        lo = min(lo, o.lo), hi = max(hi, o.hi), c2_lo = min(c2_lo, o.c2_lo), c2_hi = max(c2_hi, o.c2_hi);
    }
};

/// References, checks and fingerprint terms of triangles [first, last), 4 lanes at a time: a
/// triangle's vertices are loaded as three overlapping 4-float rows (lane 3 of each is the next
/// vertex's x, or the next triangle's first coordinate, which is checked anyway), so all but
/// the last triangle of the input are read within it; that one goes by the scalar path.
/// Checked on the way: x·0 is 0 for finite x and NaN otherwise, so one sum tells whether any
/// coordinate was NaN or infinite, without a separate pass; the largest |coordinate| is tracked
/// the same way, for the range check.
ChunkChecks triangle_refs(const GeometryView& g, std::size_t first, std::size_t last, PrimRef* refs) {
    const F4 zero = F4::splat(0.0f);
    F4 poison4 = zero, reach4 = zero;
    ChunkChecks out;
    const std::size_t simd_last = std::min(last, g.triangle_count - 1);
    std::size_t i = first;
    for (; i < simd_last; ++i) {
        const float* v = g.triangles + 9 * i;
        const F4 a = F4::load(v), b = F4::load(v + 3), c = F4::load(v + 6);
        poison4 = poison4 + (a * zero + b * zero) + c * zero;
        reach4 = max(reach4, max(max(max(a, neg(a)), max(b, neg(b))), max(c, neg(c))));
        PrimRef& r = refs[i];
        float* row = reinterpret_cast<float*>(&r);  // lo, ref | hi, code: lane 3 lands on ref and code,
        const F4 lo = min(a, min(b, c)), hi = max(a, max(b, c));
        lo.store(row), hi.store(row + 4);  // which are written next
        r.ref = static_cast<std::uint32_t>(i), r.code = 0;
        out.grow(lo, hi);  // lane 3 is not a bound's: never read
        out.sum += term<kTriangleFloats>(i, v);
    }
    out.poison = poison4.lane(0) + poison4.lane(1) + poison4.lane(2) + poison4.lane(3);
    out.reach = std::max(std::max(reach4.lane(0), reach4.lane(1)), std::max(reach4.lane(2), reach4.lane(3)));
    for (; i < last; ++i) {
        const float* v = g.triangles + 9 * i;
        for (int k = 0; k < 9; ++k) out.poison += v[k] * 0.0f, out.reach = std::max(out.reach, std::fabs(v[k]));
        refs[i] = triangle_ref(g, i);
        out.grow(refs[i].lo4(), refs[i].hi4());
        out.sum += term<kTriangleFloats>(i, v);
    }
    return out;
}

std::uint64_t sphere_terms(const GeometryView& g) {
    std::uint64_t sum = 0;
    for (std::size_t s = 0; s < g.sphere_count; ++s)
        sum += term<kSphereFloats>(g.triangle_count + s, g.spheres + 4 * s);
    return sum;
}

/// Runs pass(first, last) over the chunks of kChunkTriangles triangles, on up to `threads`
/// threads of the shared pool; returns what each chunk's pass returned, in chunk order.
/// `cancel` (may be null) is polled on the calling thread (slot 0) before each chunk and while it
/// waits; once it asks to stop, no further chunk begins (those left keep a default result).
template <class Pass>
auto for_each_triangle_chunk(const GeometryView& g, unsigned threads, const Pass& pass,
                             Cancellation* cancel = nullptr) {
    std::vector<decltype(pass(std::size_t(0), std::size_t(0)))> out((g.triangle_count + kChunkTriangles - 1) /
                                                                    kChunkTriangles);
    ThreadPool::shared().run_until_stopped(
        out.size(), threads,
        [&](std::size_t k, unsigned) {
            const std::size_t first = k * kChunkTriangles;
            out[k] = pass(first, std::min(first + kChunkTriangles, g.triangle_count));
        },
        cancel);
    return out;
}

}  // namespace

BigVector<PrimRef> make_prim_refs(const GeometryView& g, unsigned threads, PrimRefsSummary* summary,
                                  Cancellation* cancel) {
    validate_counts(g);
    BigVector<PrimRef> refs(g.primitive_count());
    ChunkChecks all;
    for (const ChunkChecks& c : for_each_triangle_chunk(
             g, threads,
             [&](std::size_t first, std::size_t last) { return triangle_refs(g, first, last, refs.data()); }, cancel))
        all.merge(c);
    if (cancel && cancel->stop_requested()) return {};
    if (all.poison != 0.0f) throw_bad_triangle(g);  // NaN != 0 too
    if (all.reach > kMaxCoordinate) throw_far_triangle(g);
    validate_spheres(g);
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        PrimRef& r = refs[g.triangle_count + i];
        r = sphere_ref(g, i);
        all.grow(r.lo4(), r.hi4());
    }
    if (!refs.empty()) check_extent(to_aabb(all.lo, all.hi), g.triangle_count);
    if (summary) {
        summary->fingerprint = finish_fingerprint(g, all.sum + sphere_terms(g));
        if (!refs.empty()) {  // as bounds_of has them: the centroids are halved twice-centroids
            const F4 half = F4::splat(0.5f);
            summary->box = to_aabb(all.lo, all.hi), summary->centroids = to_aabb(all.c2_lo * half, all.c2_hi * half);
        }
    }
    return refs;
}

std::uint64_t geometry_fingerprint(const GeometryView& g, unsigned threads) {
    std::uint64_t sum = sphere_terms(g);
    for (std::uint64_t s : for_each_triangle_chunk(g, threads, [&](std::size_t first, std::size_t last) {
             std::uint64_t chunk = 0;
             for (std::size_t i = first; i < last; ++i) chunk += term<kTriangleFloats>(i, g.triangles + 9 * i);
             return chunk;
         }))
        sum += s;
    return finish_fingerprint(g, sum);
}

std::uint64_t packed_fingerprint(const PackedPrim* prims, std::size_t count, std::size_t triangle_count,
                                 std::size_t sphere_count) {
    std::uint64_t sum = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const PackedPrim& p = prims[k];
        if (is_sphere_ref(p.ref)) {  // centre (v0) and radius (v1.x), as the input's four floats
            const float words[kSphereFloats] = {p.v0.x, p.v0.y, p.v0.z, p.v1.x};
            sum += term<kSphereFloats>(triangle_count + ref_index(p.ref), words);
        } else {
            const float words[kTriangleFloats] = {p.v0.x, p.v0.y, p.v0.z, p.v1.x, p.v1.y,
                                                  p.v1.z, p.v2.x, p.v2.y, p.v2.z};
            sum += term<kTriangleFloats>(p.ref, words);
        }
    }
    return finish_fingerprint(triangle_count, sphere_count, sum);
}

}  // namespace bvhlab
