// A C++ driver for profiling builds and traversal without Python around them:
//   build_bench TRIANGLES.f32 METHOD [repeat] [max_leaf_size]
// TRIANGLES.f32 is raw float32 T×3×3 (numpy: tris.tofile(path)). Prints the minimum build time.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/stats.h"

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
    std::printf("%s: %zu triangles, min %.1f ms (%.2f Mprims/s), nodes %llu, height %u, SAH %.2f\n", argv[2],
                g.triangle_count, best, g.triangle_count / best / 1e3, (unsigned long long)s.nodes, s.height, s.sah_cost);
}
