#include "morton.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "bvhlab/thread_pool.h"

namespace bvhlab {
namespace {

/// Spreads the low 10 bits of v so that two zero bits follow each (PBRT's LeftShift3).
std::uint32_t spread_bits(std::uint32_t v) {
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

std::uint32_t quantize(float x, float lo, float scale) { return truncate_clamped((x - lo) * scale, 1023.0f); }

struct Key {
    std::uint32_t code, index;
};

constexpr int kDigitBits = 10;
constexpr std::uint32_t kDigits = 1u << kDigitBits;   // values of one digit
constexpr std::size_t kChunk = std::size_t(1) << 16;  // keys per task of the passes over all of them
/// A bucket of at most this many keys is sorted by insertion, one of at most kCompareMax by
/// comparisons, rather than by the counting sort, which clears and sums two histograms of kDigits
/// counts (Sponza, one thread: 15.4 M instructions a build in the buckets' sorts with the counting
/// sort above 48 keys, 12.6 M with comparisons up to 256; comparisons up to 1,024 made uniform1m's
/// LBVH build 25% slower, on mispredicted branches).
constexpr std::size_t kInsertionMax = 48;
constexpr std::size_t kCompareMax = 256;

std::uint32_t digit(std::uint32_t code, int d) { return (code >> (kDigitBits * d)) & (kDigits - 1); }

/// Stable sort of keys[0, n) on digits 0 and 1 of their codes (they share digit 2), with `scratch`
/// (n keys) to spare: insertion or comparisons where n is small, else one pass that counts both
/// digits and one that scatters by each (a counting sort). The result is in keys.
void sort_low_digits(Key* keys, Key* scratch, std::size_t n) {
    if (n <= kInsertionMax) {
        for (std::size_t i = 1; i < n; ++i) {
            const Key k = keys[i];
            std::size_t j = i;
            for (; j > 0 && keys[j - 1].code > k.code; --j) keys[j] = keys[j - 1];
            keys[j] = k;
        }
        return;
    }
    if (n <= kCompareMax) {  // (code, index) as one 64-bit number: unique, so any sort is stable
        std::uint64_t* wide = reinterpret_cast<std::uint64_t*>(scratch);
        for (std::size_t i = 0; i < n; ++i) wide[i] = std::uint64_t(keys[i].code) << 32 | keys[i].index;
        std::sort(wide, wide + n);
        for (std::size_t i = 0; i < n; ++i) keys[i] = {std::uint32_t(wide[i] >> 32), std::uint32_t(wide[i])};
        return;
    }
    std::array<std::array<std::uint32_t, kDigits>, 2> start{};  // both digits counted in one pass
    for (std::size_t i = 0; i < n; ++i) ++start[0][digit(keys[i].code, 0)], ++start[1][digit(keys[i].code, 1)];
    Key *from = keys, *to = scratch;
    for (int d = 0; d < 2; ++d) {
        std::uint32_t sum = 0;
        bool one_value = false;
        for (std::uint32_t& c : start[d]) one_value |= c == n, sum += c, c = sum - c;  // exclusive prefix sum
        if (one_value) continue;  // every key has this digit: the pass would move none
        for (std::size_t i = 0; i < n; ++i) to[start[d][digit(from[i].code, d)]++] = from[i];
        std::swap(from, to);
    }
    if (from != keys) std::copy(from, from + n, keys);
}

}  // namespace

// The sort moves 8-byte (code, index) keys, not the 32-byte references (Embree's Morton builder
// sorts such pairs too), and runs on the pool: one pass makes the codes and counts the top digit
// (bits 20-29) per chunk; a second scatters the keys by it, stably (each chunk from its own
// offsets); each of its 1024 buckets, which no longer need the others, is then sorted on the two
// lower digits by one task, in memory it has to itself; the references are gathered last. Stable
// throughout: codes in order, ties in input order, whatever the threads (the single-threaded
// least-significant-digit sort it replaced gave the same order, at 4.4 ms on Sponza on one or two
// threads).
void sort_by_morton_code(BigVector<PrimRef>& refs, const Aabb& centroid_bounds, unsigned threads,
                         Cancellation* cancel) {
    Vec3 extent = centroid_bounds.extent();
    float scale[3];
    for (int a = 0; a < 3; ++a) {  // a subnormal extent would make the scale inf, and 0·inf = NaN
        const float s = 1024.0f / extent[a];
        scale[a] = extent[a] > 0 && std::isfinite(s) ? s : 0.0f;
    }
    const std::size_t n = refs.size(), chunks = (n + kChunk - 1) / kChunk;
    const auto run = [&](std::size_t count, const std::function<void(std::size_t)>& task) {
        return ThreadPool::shared().run_until_stopped(
            count, threads, [&](std::size_t k, unsigned) { task(k); }, cancel);
    };
    BigVector<Key> keys(n), by_top(n);
    std::vector<std::array<std::uint32_t, kDigits>> count(chunks);
    const float lo[3] = {centroid_bounds.lo[0], centroid_bounds.lo[1], centroid_bounds.lo[2]};
    if (!run(chunks, [&, in = refs.data(), out = keys.data()](std::size_t c) {
            std::uint32_t* const mine = count[c].data();  // locals: the stores below may not alias them
            std::fill(mine, mine + kDigits, 0u);
            const float lo0 = lo[0], lo1 = lo[1], lo2 = lo[2], s0 = scale[0], s1 = scale[1], s2 = scale[2];
            for (std::size_t i = c * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
                const PrimRef& r = in[i];
                const std::uint32_t code = spread_bits(quantize(r.centroid(0), lo0, s0)) << 2 |
                                           spread_bits(quantize(r.centroid(1), lo1, s1)) << 1 |
                                           spread_bits(quantize(r.centroid(2), lo2, s2));
                out[i] = {code, static_cast<std::uint32_t>(i)};
                ++mine[digit(code, 2)];
            }
        }))
        return;
    // Where each bucket begins, and where each chunk writes into it: the chunks in order.
    std::vector<std::size_t> bucket(kDigits + 1, 0);
    for (std::uint32_t v = 0; v < kDigits; ++v) {
        std::size_t at = bucket[v];
        for (auto& c : count) {
            const std::uint32_t here = c[v];
            c[v] = std::uint32_t(at), at += here;
        }
        bucket[v + 1] = at;
    }
    if (!run(chunks, [&](std::size_t c) {
            std::array<std::uint32_t, kDigits>& at = count[c];
            for (std::size_t i = c * kChunk, end = std::min(n, i + kChunk); i < end; ++i)
                by_top[at[digit(keys[i].code, 2)]++] = keys[i];
        }))
        return;
    // The largest buckets first (the pool hands out tasks in order).
    std::vector<std::uint32_t> order(kDigits);
    for (std::uint32_t v = 0; v < kDigits; ++v) order[v] = v;
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        return bucket[a + 1] - bucket[a] > bucket[b + 1] - bucket[b];
    });
    const std::size_t used = std::size_t(
        std::find_if(order.begin(), order.end(), [&](std::uint32_t v) { return bucket[v + 1] == bucket[v]; }) -
        order.begin());
    if (!run(used, [&](std::size_t k) {
            const std::uint32_t v = order[k];
            sort_low_digits(by_top.data() + bucket[v], keys.data() + bucket[v], bucket[v + 1] - bucket[v]);
        }))
        return;
    // The gather reads the references at random: fetch the one kAhead keys later meanwhile.
    constexpr std::size_t kAhead = 16;
    BigVector<PrimRef> sorted(n);
    if (!run(chunks, [&](std::size_t c) {
            for (std::size_t j = c * kChunk, end = std::min(n, j + kChunk); j < end; ++j) {
                if (j + kAhead < end) __builtin_prefetch(&refs[by_top[j + kAhead].index]);
                sorted[j] = refs[by_top[j].index];
                sorted[j].code = by_top[j].code;
            }
        }))
        return;
    refs.swap(sorted);
}

}  // namespace bvhlab
