// build_tlas.cpp — the top-level tree over instances (tlas.h): checks, world boxes, and the binned
// SAH build of every tree run over the instances' boxes (build_bvh_over_boxes).
#include <stdexcept>
#include <string>

#include "bvhlab/coordinate_range.h"
#include "bvhlab/tlas.h"

namespace bvhlab {

BuildConfig default_tlas_config() {
    BuildConfig config;
    config.max_leaf_size = 1;
    config.sah_block = 1;
    return config;
}

namespace {

/// Up to kFrontier boxes of a BLAS's top nodes that together hold all of it (the root, then the
/// largest-area inner node replaced by its children, and again): their union moved into the
/// world is a much tighter world box than the moved root box where an instance is rotated (a
/// box turned 45° about one axis grows by √2 on two).
constexpr std::size_t kFrontier = 8;

std::vector<Aabb> top_boxes(const Bvh& tree) {
    std::vector<std::uint32_t> nodes;
    if (!tree.empty()) nodes.push_back(0);
    while (nodes.size() < kFrontier) {
        std::size_t widest = nodes.size();
        for (std::size_t k = 0; k < nodes.size(); ++k)
            if (!is_leaf(tree.nodes[nodes[k]]) &&
                (widest == nodes.size() ||
                 node_box(tree.nodes[nodes[k]]).half_area() > node_box(tree.nodes[nodes[widest]]).half_area()))
                widest = k;
        if (widest == nodes.size()) break;  // all leaves
        const std::uint32_t i = nodes[widest];
        nodes[widest] = i + 1, nodes.push_back(tree.nodes[i].index);
    }
    std::vector<Aabb> boxes;
    for (std::uint32_t i : nodes) boxes.push_back(node_box(tree.nodes[i]));
    return boxes;
}

Instance make_instance(const std::vector<BoxesToMove>& tops, std::uint32_t blas, const Transform& t,
                       std::size_t index) {
    auto what = [&] { return "instance " + std::to_string(index); };
    if (blas >= tops.size())
        throw std::invalid_argument(what() + " refers to mesh " + std::to_string(blas) + ", but the scene has " +
                                    std::to_string(tops.size()) + " mesh" + (tops.size() == 1 ? "" : "es"));
    if (!transform_invertible(t)) validate_transform(t, what().c_str());  // throws, saying why
    Instance inst;
    inst.blas = blas;
    inst.object_to_world = t;
    inst.world_to_object = inverse(t);
    inst.identity = t.is_identity();
    inst.world_box = transform_boxes(t, tops[blas]);
    if (!inst.world_box.empty() && !(in_coordinate_range(inst.world_box.lo) && in_coordinate_range(inst.world_box.hi)))
        throw std::invalid_argument(what() + " would place mesh " + std::to_string(blas) +
                                    " outside the supported coordinate range [-2^40, 2^40] (±1.0995e12)");
    return inst;
}

/// Tlas::leaf_instances of a TLAS whose tree is built (its refs instance indices).
BigVector<LeafInstance> make_leaf_instances(const Bvh& tree, const BigVector<Instance>& instances) {
    const std::size_t count = tree.refs.size();
    // each position's leaf, the last of a leaf's with the top bit set
    constexpr std::uint32_t kLast = 1u << 31;
    std::vector<std::uint32_t> leaf_of(count);
    for (std::uint32_t n = 0; n < tree.node_count(); ++n) {
        const BvhNode& node = tree.nodes[n];
        if (!is_leaf(node)) continue;
        const std::uint32_t end = node.index + leaf_count(node);
        for (std::uint32_t k = node.index; k < end; ++k) leaf_of[k] = n;
        leaf_of[end - 1] |= kLast;
    }
    // Each position's instance, read a few positions ahead of its use (the instances, 12.8 MB at
    // 100,000, read in the refs' order, miss the caches), each entry written whole and in order
    // (LeafInstance is WrittenBeforeRead: the array is not cleared first).
    constexpr std::size_t kAhead = 24;
    BigVector<LeafInstance> out(count);
    for (std::size_t k = 0; k < count; ++k) {
        if (k + kAhead < count) {
            const auto* ahead = reinterpret_cast<const char*>(&instances[tree.refs[k + kAhead]]);
            __builtin_prefetch(ahead), __builtin_prefetch(ahead + sizeof(Instance) - 1);
        }
        const std::uint32_t i = tree.refs[k];
        const Instance& inst = instances[i];
        out[k] = {ObjectColumns(object_map(inst.object_to_world, inst.world_to_object)),
                  inst.blas,
                  i,
                  leaf_of[k] & ~kLast,
                  inst.identity,
                  (leaf_of[k] & kLast) != 0};
    }
    return out;
}

}  // namespace

void check_placement(const Bvh& blas, std::uint32_t mesh, const std::uint32_t* index, const Transform* transforms,
                     std::size_t count) {
    const std::vector<Aabb> boxes = top_boxes(blas);
    std::vector<BoxesToMove> tops(mesh, BoxesToMove(nullptr, 0));  // mesh's at its index, as build_tlas has them
    tops.emplace_back(boxes.data(), boxes.size());
    for (std::size_t i = 0; i < count; ++i) make_instance(tops, mesh, transforms[i], index[i]);
}

Tlas build_tlas(const std::vector<const Bvh*>& blases, const std::vector<std::uint32_t>& blas_of,
                const std::vector<Transform>& transforms, const BuildConfig& config) {
    if (blas_of.size() != transforms.size())
        throw std::invalid_argument("one transform per instance: got " + std::to_string(blas_of.size()) +
                                    " instances and " + std::to_string(transforms.size()) + " transforms");
    for (const Bvh* b : blases)
        if (!b) throw std::invalid_argument("a mesh of the scene has no tree");
    std::vector<BoxesToMove> tops;  // each BLAS's, made ready once for all its instances
    for (const Bvh* b : blases) {
        const std::vector<Aabb> boxes = top_boxes(*b);
        tops.emplace_back(boxes.data(), boxes.size());
    }
    Tlas tlas;
    tlas.instances.reserve(blas_of.size());
    for (std::size_t i = 0; i < blas_of.size(); ++i)
        tlas.instances.push_back(make_instance(tops, blas_of[i], transforms[i], i));
    // Instances of empty meshes are not in the tree: box i of the build is instance placed[i].
    BigVector<Aabb> boxes;
    BigVector<std::uint32_t> placed;
    boxes.reserve(tlas.instances.size()), placed.reserve(tlas.instances.size());
    for (std::size_t i = 0; i < tlas.instances.size(); ++i) {
        if (tlas.instances[i].world_box.empty()) continue;
        boxes.push_back(tlas.instances[i].world_box);
        placed.push_back(static_cast<std::uint32_t>(i));
    }
    tlas.tree = build_bvh_over_boxes(boxes.data(), boxes.size(), config);
    for (std::uint32_t& ref : tlas.tree.refs) ref = placed[ref];
    tlas.wide = make_wide_tlas(tlas.tree);
    tlas.leaf_instances = make_leaf_instances(tlas.tree, tlas.instances);
    return tlas;
}

}  // namespace bvhlab
