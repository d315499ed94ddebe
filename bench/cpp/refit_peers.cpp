// refit_peers.cpp — refit against rebuild of a 1M-triangle deforming mesh on one core, bvhlab
// beside tinybvh's BVH::Refit / Build (issue 34: refit >= 10x faster than rebuild, and at
// least tinybvh's refit speed per triangle). Not part of the CMake build: bench/refit_peers.sh
// compiles it against build/cpp's library and, when given, a local copy of tinybvh.
//
// The mesh: a 708×708 grid of two triangles per cell (1,002,528 triangles) with a travelling
// wave; each frame moves every vertex. Times are the least of 5 after one warm-up. bvhlab's
// refit also packs the leaves' geometry (its traversals read it) and takes the geometry's
// fingerprint; tinybvh's recomputes the boxes of its BVH only (its BVH8_CPU traversal would need
// a conversion after it, not timed here).
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/stats.h"

#ifdef BVHLAB_TINYBVH
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"
#endif

namespace {

constexpr int kGrid = 708;

std::vector<float> wave(float phase) {
    std::vector<float> tris;
    tris.reserve(std::size_t(kGrid) * kGrid * 18);
    auto p = [&](int i, int j) {
        const float x = float(i) / kGrid, y = float(j) / kGrid;
        return std::array<float, 3>{x, y, 0.05f * std::sin(20.0f * x + phase) * std::cos(14.0f * y)};
    };
    for (int i = 0; i < kGrid; ++i)
        for (int j = 0; j < kGrid; ++j)
            for (auto v : {p(i, j), p(i + 1, j), p(i, j + 1), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)})
                tris.insert(tris.end(), v.begin(), v.end());
    return tris;
}

double least_ms(const std::function<void()>& fn, int repeat = 5) {
    fn();  // warm-up: first touches of fresh memory
    double best = 1e30;
    for (int r = 0; r < repeat; ++r) {
        const auto t = std::chrono::steady_clock::now();
        fn();
        best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
    }
    return best;
}

}  // namespace

int main() {
    const std::vector<float> rest = wave(0.0f), moved = wave(1.0f);
    const std::size_t n = rest.size() / 9;
    using namespace bvhlab;
    BuildConfig config;
    config.threads = 1;
    const Bvh built = build_bvh({rest.data(), n, nullptr, 0}, config);
    const GeometryView frame{moved.data(), n, nullptr, 0};
    const double refit_ms = least_ms([&] { Bvh t = refitted(built, frame, 1); });
    const double build_ms = least_ms([&] { Bvh t = build_bvh(frame, config); });
    const double refit_sah = sah_cost(refitted(built, frame, 1)), build_sah = sah_cost(build_bvh(frame, config));
    std::printf(
        "{\"triangles\": %zu,\n \"bvhlab\": {\"refit_ms\": %.2f, \"build_ms\": %.2f, \"ratio\": %.2f, "
        "\"refit_sah\": %.2f, \"build_sah\": %.2f}",
        n, refit_ms, build_ms, build_ms / refit_ms, refit_sah, build_sah);
#ifdef BVHLAB_TINYBVH
    std::vector<tinybvh::bvhvec4> v_rest(3 * n), v_moved(3 * n);
    for (std::size_t i = 0; i < 3 * n; ++i) {
        v_rest[i] = tinybvh::bvhvec4(rest[3 * i], rest[3 * i + 1], rest[3 * i + 2], 0);
        v_moved[i] = tinybvh::bvhvec4(moved[3 * i], moved[3 * i + 1], moved[3 * i + 2], 0);
    }
    tinybvh::BVH tb;
    tb.threadedBuild = false;
    tb.Build(v_rest.data(), std::uint32_t(n));
    v_rest = v_moved;  // tinybvh reads the vertices it was built over through its pointer to them
    const double tb_refit = least_ms([&] { tb.Refit(); });
    tinybvh::BVH fresh;
    fresh.threadedBuild = false;
    const double tb_build = least_ms([&] { fresh.Build(v_rest.data(), std::uint32_t(n)); });
    std::printf(",\n \"tinybvh\": {\"refit_ms\": %.2f, \"build_ms\": %.2f, \"ratio\": %.2f}", tb_refit, tb_build,
                tb_build / tb_refit);
#endif
    std::printf("}\n");
}
