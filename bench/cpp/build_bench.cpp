// A C++ driver for profiling builds and traversal without Python around them:
//   build_bench TRIANGLES.f32 METHOD [repeat] [max_leaf_size]
// TRIANGLES.f32 is raw float32 T×3×3 (numpy: tris.tofile(path)). Prints the minimum build time.
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <random>

#include "bvhlab/bvh.h"
#include "bvhlab/stats.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s TRIANGLES.f32 METHOD [repeat] [max_leaf_size]\n", argv[0]);
        return 2;
    }
    std::ifstream f(argv[1], std::ios::binary | std::ios::ate);
    std::vector<float> tris(std::size_t(f.tellg()) / sizeof(float));
    f.seekg(0);
    f.read(reinterpret_cast<char*>(tris.data()), std::streamsize(tris.size() * sizeof(float)));
    bvhlab::GeometryView g{tris.data(), tris.size() / 9};
    bvhlab::BuildConfig cfg;
    cfg.method = bvhlab::parse_split_method(argv[2]);
    cfg.threads = 1;
    if (argc > 4) cfg.max_leaf_size = std::stoul(argv[4]);
    int repeat = argc > 3 ? std::stoi(argv[3]) : 5;
    double best = 1e30;
    bvhlab::BvhStats s;
    for (int i = 0; i < repeat; ++i) {
        bvhlab::Bvh bvh = bvhlab::build_bvh(g, cfg);
        best = std::min(best, bvh.build_ms);
        s = bvhlab::compute_stats(bvh);
    }
    if (std::getenv("TRACE")) {
        // random rays: origins uniform in the bounds, directions uniform on the sphere
        bvhlab::Bvh bvh = bvhlab::build_bvh(g, cfg);
        bvhlab::Aabb box = bvhlab::node_box(bvh.nodes[0]);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(0, 1);
        std::normal_distribution<float> nd(0, 1);
        const std::size_t n = 200000;
        std::vector<bvhlab::Ray> rays(n);
        for (auto& r : rays) {
            bvhlab::Vec3 e = box.extent();
            r.origin = box.lo + bvhlab::Vec3{u(rng) * e.x, u(rng) * e.y, u(rng) * e.z};
            r.dir = bvhlab::normalize(bvhlab::Vec3{nd(rng), nd(rng), nd(rng)});
        }
        bvhlab::WideBvh wide = bvhlab::make_wide(bvh);
        for (auto mode : {bvhlab::Traversal::Stack, bvhlab::Traversal::Stackless, bvhlab::Traversal::Wide}) {
            double best_t = 1e30;
            std::size_t hits = 0;
            for (int k = 0; k < 5; ++k) {
                auto t0 = std::chrono::steady_clock::now();
                hits = 0;
                for (const auto& r : rays)
                    hits += (mode == bvhlab::Traversal::Wide ? bvhlab::intersect_wide(wide, bvh, r)
                                                              : bvhlab::intersect(bvh, r, mode)).ref != bvhlab::kNoHit;
                best_t = std::min(best_t, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            }
            const char* names[] = {"stack", "stackless", "wide"};
            std::printf("%s random rays: %.2f Mrays/s (%zu hits)\n", names[int(mode)],
                        n / best_t / 1e6, hits);
        }
    }
    std::printf("%s: %zu triangles, min %.1f ms (%.2f Mprims/s), nodes %llu, height %u, SAH %.2f\n", argv[2],
                g.triangle_count, best, g.triangle_count / best / 1e3, (unsigned long long)s.nodes, s.height, s.sah_cost);
}
