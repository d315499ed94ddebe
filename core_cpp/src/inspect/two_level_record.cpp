// two_level_record.cpp — one ray's two-level walk, recorded by the walk itself
// (traverse_two_level.cpp) into a TwoLevelRecord.
#include "bvhlab/two_level_record.h"

#include <stdexcept>
#include <string>
#include <utility>

#include "bvhlab/coordinate_range.h"

namespace bvhlab {
namespace {

class Recorder final : public TwoLevelRecorder {
public:
    Recorder(const TwoLevel& scene, const std::vector<const WideNames*>& names, const HiddenPrims& hidden,
             TwoLevelRecord& r)
        : scene_(scene), names_(names), hidden_(hidden), r_(r) {}

    void box(std::uint32_t node, bool entered) override {
        r_.tlas.box_nodes.push_back(node), r_.tlas.box_hit.push_back(entered);
    }

    Hit instance(std::uint32_t leaf, std::uint32_t index, const BlasView& blas, const Ray& ray, Traversal mode,
                 std::uint32_t* visited) override {
        TraversalRecord& t = r_.tlas;
        t.prim_slots.push_back(index), t.prim_leaf.push_back(leaf), t.prim_closer.push_back(0);
        t.prim_box_test.push_back(std::uint32_t(t.box_nodes.size()));
        TraversalRecord b;
        Hit h;
        if (mode == Traversal::Wide) {
            h = detail::intersect_wide_recorded(*blas.bvh, *blas.wide, names(index), ray, b);
        } else {
            h = detail::intersect_recorded(*blas.bvh, ray, mode, b, hidden_, scene_.tlas->instances[index].blas);
            b.nodes_visited = std::uint32_t(b.box_nodes.size());
        }
        *visited = b.nodes_visited;
        b.hit = h;
        if (h.ref == kNoHit) b.hit_leaf = kNoHit;
        r_.blas.push_back(std::move(b));
        return h;
    }

    void instance_done(bool closer, float t_scale) override {
        r_.blas.back().hit.t *= t_scale;  // the world ray's units (inf stays inf)
        r_.tlas.prim_closer.back() = closer;
        if (closer) r_.hit_tlas_leaf = r_.tlas.prim_leaf.back(), r_.hit_leaf = r_.blas.back().hit_leaf;
    }

private:
    const WideNames& names(std::uint32_t instance) const {
        const std::uint32_t b = scene_.tlas->instances[instance].blas;
        if (b >= names_.size() || !names_[b])
            throw std::invalid_argument("a wide two-level record needs the names of mesh " + std::to_string(b) +
                                        "'s wide tree");
        return *names_[b];
    }

    const TwoLevel& scene_;
    const std::vector<const WideNames*>& names_;
    const HiddenPrims& hidden_;
    TwoLevelRecord& r_;
};

}  // namespace

TwoLevelRecord record_two_level(const TwoLevel& scene, Ray ray, Traversal mode,
                                const std::vector<const WideNames*>& wide_names, const HiddenPrims& hidden) {
    check_two_level(scene, mode);
    if (hidden && mode == Traversal::Wide)
        throw std::invalid_argument("record_two_level: the wide walk does not pass hidden primitives by");
    const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z}, dir[3] = {ray.dir.x, ray.dir.y, ray.dir.z};
    check_rays(RayBatch{origin, dir, 1, ray.tmin, ray.tmax});  // the checks and scaling of the batch
    const float t_scale = scale_ray(ray);
    TwoLevelRecord record;
    Recorder recorder(scene, wide_names, hidden, record);
    record.hit = detail::intersect_two_level_recorded(scene, ray, mode, recorder, &record.nodes_visited);
    record.tlas.nodes_visited = std::uint32_t(record.tlas.box_nodes.size());
    record.hit.hit.t *= t_scale;
    for (TraversalRecord& b : record.blas) b.hit.t *= t_scale;
    if (record.hit.hit.ref == kNoHit) record.hit_leaf = record.hit_tlas_leaf = kNoHit;
    else record.tlas.hit = record.hit.hit, record.tlas.hit_leaf = record.hit_tlas_leaf;
    return record;
}

}  // namespace bvhlab
