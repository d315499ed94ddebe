// py_bvh.h — what the Python module keeps per tree, shared by the binding files.
//
// A Python Bvh may be used from several threads at once (intersect on one, refit on another,
// boxes on a third). Each operation takes the current TreeVersion, a shared_ptr to an immutable
// tree, and works on that: a refit makes a new version from it (the old one untouched, not
// copied: refitted in bvh.h) and publishes it, so a reader sees the
// old tree or the new one, never freed or half-written memory. Arrays handed to Python keep
// their version alive.
#pragma once
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "bvhlab/owned_mutex.h"
#include "bvhlab/bvh.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/ray_record.h"
#include "bvhlab/update.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab::python {

namespace nb = nanobind;
using Triangles = nb::ndarray<const float, nb::shape<-1, 3, 3>, nb::c_contig, nb::device::cpu>;
using Spheres = nb::ndarray<const float, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;

inline GeometryView view_of(const Triangles& tris, const std::optional<Spheres>& spheres) {
    GeometryView g;
    g.triangles = tris.data();
    g.triangle_count = tris.shape(0);
    if (spheres) g.spheres = spheres->data(), g.sphere_count = spheres->shape(0);
    return g;
}

using CostsPtr = std::shared_ptr<const NodeCostArray>;

/// Throws std::invalid_argument unless `bvh` holds its geometry. The TLAS of a two-level tree as a
/// tree (`tlas_tree`) has instance indices for references and no primitives: a ray query, a
/// record, a refit or a file of it would read (or need) primitives that are not there.
inline void require_geometry(const Bvh& bvh, const char* what) {
    if (bvh.prims.size() != bvh.refs.size())
        throw std::invalid_argument(std::string(what) +
                                    ": this tree holds no geometry (the TLAS of a two-level tree, whose references are "
                                    "instances); ask the InstancedBvh, or its meshes' trees");
}

/// One immutable version of a tree, with the views made of it on first use (thread-safe).
class TreeVersion {
public:
    /// `built`: the costs of the tree's nodes when they were built (update.h), carried from the
    /// version this one was made from; null for a tree as built (taken from it when first asked).
    TreeVersion(Bvh tree, std::uint64_t revision, CostsPtr built = nullptr)
        : bvh(std::move(tree)), revision(revision), built_(std::move(built)) {}

    const Bvh bvh;
    const std::uint64_t revision;  ///< 0 when built, +1 per refit or update

    const CostsPtr& built_costs() const {
        std::call_once(built_once_, [this] {
            if (!built_) built_ = std::make_shared<const NodeCostArray>(subtree_costs(bvh));
        });
        return built_;
    }

    const DepthOrder& order() const {
        std::call_once(order_once_, [this] { order_.emplace(make_depth_order(bvh)); });
        return *order_;
    }
    const WideBvh& wide() const {
        std::call_once(wide_once_, [this] { wide_.emplace(make_wide(bvh)); });
        return *wide_;
    }

    /// The binary node each line of the wide tree stands for (ray_record.h), for wide records.
    const WideNames& wide_names() const {
        std::call_once(names_once_, [this] { names_.emplace(name_wide_nodes(bvh, wide())); });
        return *names_;
    }

private:
    mutable std::once_flag order_once_, wide_once_, built_once_, names_once_;
    mutable std::optional<WideNames> names_;
    mutable CostsPtr built_;
    mutable std::optional<DepthOrder> order_;
    mutable std::optional<WideBvh> wide_;
};

using TreePtr = std::shared_ptr<const TreeVersion>;

/// The Python-side tree: the current version, replaced as a whole by refit.
class PyBvh {
public:
    explicit PyBvh(Bvh tree) : current_(std::make_shared<const TreeVersion>(std::move(tree), 0)) {}
    /// A tree whose current version is `version` (shared, immutable): fork's copy-on-write.
    explicit PyBvh(TreePtr version) : current_(std::move(version)) {}

    TreePtr current() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return current_;
    }
    /// Publishes the tree and built costs that `make(current version)` returns (a std::pair), made
    /// from the current one without copying it first (refitted, update_bvh): changes are serialised
    /// (the last call wins, as it would without threads); readers are never blocked by them. Call
    /// without the GIL.
    /// A change asked for on the thread making one (from an optimisation's or update's progress
    /// callback) raises ReentrantCall, RuntimeError in Python: it waited for itself, and Ctrl-C
    /// could not end the wait.
    template <class Make>
    void replace(Make&& make) {
        std::lock_guard<OwnedMutex> writer(writer_mutex_);
        TreePtr old = current();
        auto [tree, built] = make(*old);
        auto version = std::make_shared<const TreeVersion>(std::move(tree), old->revision + 1, std::move(built));
        std::lock_guard<std::mutex> lock(mutex_);
        current_ = std::move(version);
    }

private:
    mutable std::mutex mutex_;              ///< guards current_ (held only to copy or swap the pointer)
    OwnedMutex writer_mutex_{"this tree"};  ///< one update at a time
    TreePtr current_;
};

/// A read-only numpy array over `data` that keeps `owner` (a tree version) alive.
template <class T>
nb::ndarray<nb::numpy, const T> array_owned_by(const TreePtr& owner, const T* data,
                                               std::initializer_list<size_t> shape) {
    auto* keep = new TreePtr(owner);
    nb::capsule capsule(keep, [](void* p) noexcept { delete static_cast<TreePtr*>(p); });
    return nb::ndarray<nb::numpy, const T>(data, shape, capsule);
}

}  // namespace bvhlab::python
