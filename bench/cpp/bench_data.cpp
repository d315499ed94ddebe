#include "bench_data.h"

#include <fstream>
#include <stdexcept>
#include <string>

namespace bench {
namespace {

std::vector<float> load_floats(const std::string& path) {
    std::ifstream f(path, std::ios::binary | std::ios::ate);
    if (!f) throw std::invalid_argument("cannot open " + path);
    std::vector<float> v(std::size_t(f.tellg()) / sizeof(float));
    f.seekg(0);
    f.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(float)));
    return v;
}

}  // namespace

/// A file of whole rows of `width` floats, or an error saying what it holds: a file of shadow rays
/// (7 floats a ray) read as rays of 6 was traced as other rays, without a word (bench/ab_batch.py
/// passed them without --shadow).
std::vector<float> load_rows(const std::string& path, std::size_t width, const char* what) {
    std::vector<float> v = load_floats(path);
    if (v.size() % width)
        throw std::invalid_argument(path + " holds " + std::to_string(v.size()) + " floats, not whole " + what +
                                    " of " + std::to_string(width) +
                                    (width == 6 ? " (shadow rays: --shadow FILE)" : ""));
    return v;
}

Mesh load_mesh(const std::string& path) { return {load_rows(path, 9, "triangles")}; }
void split_rays(const Rays& rays, std::vector<float>& origins, std::vector<float>& directions) {
    origins.resize(3 * rays.count()), directions.resize(3 * rays.count());
    for (std::size_t i = 0; i < rays.count(); ++i)
        for (int a = 0; a < 3; ++a)
            origins[3 * i + a] = rays.od[6 * i + a], directions[3 * i + a] = rays.od[6 * i + 3 + a];
}

Rays load_rays(const std::string& path) { return {load_rows(path, 6, "rays"), {}}; }

Rays load_shadow_rays(const std::string& path) {
    const std::vector<float> all = load_rows(path, 7, "shadow rays");
    Rays rays;
    for (std::size_t i = 0; i + 7 <= all.size(); i += 7) {
        rays.od.insert(rays.od.end(), all.begin() + std::ptrdiff_t(i), all.begin() + std::ptrdiff_t(i + 6));
        rays.tmax.push_back(all[i + 6]);
    }
    return rays;
}

std::unique_ptr<Peer> make_peer(const std::string& spec, unsigned threads) {
    const auto colon = spec.find(':');
    const std::string system = spec.substr(0, colon),
                      options = colon == std::string::npos ? "" : spec.substr(colon + 1);
    if (system == "bvhlab") return make_bvhlab_peer(options, threads);
    if (system == "embree") return make_embree_peer(options, threads);
    if (system == "tinybvh") return make_tinybvh_peer(options, threads);
    throw std::invalid_argument("unknown system in '" + spec + "' (bvhlab, embree, tinybvh)");
}

}  // namespace bench
