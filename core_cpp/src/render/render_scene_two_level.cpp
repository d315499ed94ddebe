// The render scene of a two-level tree (issue 34): the TLAS and every mesh's BLAS copied into one
// forest of nodes, pairs and leaf primitives (each tree's indices moved to its place there, so the
// tracer's walk steps through a BLAS exactly as through a flat tree), every mesh's triangles and
// spheres one after another, and the instances in the TLAS's leaf order.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "bvhlab/pair_nodes.h"
#include "bvhlab/render.h"
#include "render_scene_parts.h"

namespace bvhlab {
namespace {

using namespace render_parts;

/// Where a tree's arrays start in the forest's.
struct TreePlace {
    std::uint32_t node = 0, pair = 0, prim = 0;
};

std::uint32_t checked_offset(std::size_t n, const char* what) {
    if (n >= gpu::PAIR_LEAF_BIT)
        throw std::invalid_argument(std::string("the two-level scene has too many ") + what + " for the tracer (2^31)");
    return std::uint32_t(n);
}

BvhNode moved_node(BvhNode n, const TreePlace& at) {
    if (is_leaf(n)) n.index += at.prim;
    else n.index += at.node, n.info = gpu::NODE_INTERNAL_BIT | ((n.info & ~gpu::NODE_INTERNAL_BIT) + at.node);
    return n;
}

std::uint32_t moved_child(std::uint32_t word, const TreePlace& at) {
    return (word & gpu::PAIR_LEAF_BIT) ? gpu::PAIR_LEAF_BIT | ((word & ~gpu::PAIR_LEAF_BIT) + at.prim) : word + at.pair;
}

/// Appends a tree to the forest at its end; returns where it went. Leaf primitives' references
/// move by the mesh's first triangle and sphere in the scene's arrays.
TreePlace append_tree(RenderScene& s, const Bvh& bvh, std::uint32_t first_triangle, std::uint32_t first_sphere) {
    const TreePlace at{
        checked_offset(s.forest_nodes.size() + bvh.nodes.size(), "nodes") - bvh.node_count(),
        checked_offset(s.pairs.size(), "nodes"),
        checked_offset(s.forest_prims.size() + bvh.prims.size(), "primitives") - std::uint32_t(bvh.prims.size())};
    for (const BvhNode& n : bvh.nodes) s.forest_nodes.push_back(moved_node(n, at));
    for (gpu::BvhPair p : make_pair_nodes(bvh)) {
        p.child_a = moved_child(p.child_a, at);
        p.child_b = moved_child(p.child_b, at);
        s.pairs.push_back(p);
    }
    for (gpu::GpuTriangle p : bvh.prims) {
        const bool sphere = (p.ref & gpu::REF_SPHERE_BIT) != 0;
        p.ref = sphere ? gpu::REF_SPHERE_BIT | ((p.ref & gpu::REF_INDEX_MASK) + first_sphere) : p.ref + first_triangle;
        s.forest_prims.push_back(p);
    }
    return at;
}

/// The mesh's triangles and spheres (with their materials) appended to the scene's arrays.
void append_geometry(RenderScene& s, const RenderMesh& mesh, std::size_t n_materials) {
    const GeometryView& g = mesh.geometry;
    for (std::size_t i = 0; i < g.triangle_count; ++i)
        s.triangles.push_back(pack_triangle(g, i, material_index(mesh.triangle_material, i, n_materials, "triangle")));
    for (std::size_t i = 0; i < g.sphere_count; ++i) {
        const std::uint32_t m = material_index(mesh.sphere_material, i, n_materials, "sphere");
        s.spheres.push_back({v4(g.sphere_center(i), g.sphere_radius(i)), {m, 0, 0, 0}});
    }
    checked_offset(s.triangles.size(), "triangles"), checked_offset(s.spheres.size(), "spheres");
}

std::uint32_t tree_height(const Bvh& bvh) {
    return bvh.depths.empty() ? 0u : std::uint32_t(*std::max_element(bvh.depths.begin(), bvh.depths.end())) + 1;
}

gpu::GpuInstance gpu_instance(const Instance& inst, const TreePlace& at, const Bvh& blas, std::uint32_t index) {
    const auto m = object_map(inst.object_to_world, inst.world_to_object).m;  // as the CPU walks (transform.h)
    return {{m[0], m[1], m[2], m[3]},
            {m[4], m[5], m[6], m[7]},
            {m[8], m[9], m[10], m[11]},
            {at.node, at.node + blas.node_count(), at.pair, index}};
}

void check_meshes(const Tlas& tlas, const std::vector<RenderMesh>& meshes) {
    for (const Instance& inst : tlas.instances)
        if (inst.blas >= meshes.size())
            throw std::invalid_argument("the TLAS refers to mesh " + std::to_string(inst.blas) +
                                        ", but the scene has " + std::to_string(meshes.size()));
    for (const RenderMesh& m : meshes) {
        if (!m.bvh) throw std::invalid_argument("a mesh of the two-level scene has no tree");
        check_tree_matches(*m.bvh, m.geometry);
    }
    for (const BvhNode& n : tlas.tree.nodes)
        if (is_leaf(n) && leaf_count(n) != 1)
            throw std::invalid_argument("the renderers take a TLAS with one instance per leaf (default_tlas_config)");
}

}  // namespace

RenderScene make_render_scene(const Tlas& tlas, const std::vector<RenderMesh>& meshes, const MaterialView& mv) {
    check_meshes(tlas, meshes);
    if (tlas.instances.size() == 1 && tlas.instances[0].identity) {  // one mesh where it was modelled: flat
        const RenderMesh& m = meshes[tlas.instances[0].blas];
        return make_render_scene(*m.bvh, m.geometry,
                                 {mv.materials, mv.material_count, m.triangle_material, m.sphere_material});
    }
    static const Bvh kNoTree;
    if (tlas.tree.empty()) return make_render_scene(kNoTree, GeometryView{}, mv);  // nothing to hit
    RenderScene s;
    s.materials = gpu_materials(mv);
    s.holdout = any_holdout(s.materials);
    s.hidden = any_hidden(s.materials);
    const std::size_t n_materials = mv.material_count ? mv.material_count : 1;
    std::vector<std::uint32_t> first_triangle, first_sphere;
    for (const RenderMesh& m : meshes) {
        first_triangle.push_back(std::uint32_t(s.triangles.size()));
        first_sphere.push_back(std::uint32_t(s.spheres.size()));
        append_geometry(s, m, n_materials);
    }
    s.first_triangle = first_triangle;
    s.first_sphere = first_sphere;
    s.instance_slots.assign(tlas.instances.size(), gpu::NO_INSTANCE);
    append_tree(s, tlas.tree, 0, 0);  // first, at 0; its leaves' slots are those of `instances` (it packs no prims)
    std::vector<TreePlace> places;
    std::uint32_t blas_height = 1;
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        places.push_back(append_tree(s, *meshes[k].bvh, first_triangle[k], first_sphere[k]));
        blas_height = std::max(blas_height, tree_height(*meshes[k].bvh));
    }
    std::uint64_t walk_steps = 2ull * tlas.tree.node_count() + tlas.tree.refs.size() + 2;
    for (std::uint32_t index : tlas.tree.refs) {
        const Instance& inst = tlas.instances[index];
        const Bvh& blas = *meshes[inst.blas].bvh;
        s.instance_slots[index] = std::uint32_t(s.instances.size());
        s.instances.push_back(gpu_instance(inst, places[inst.blas], blas, index));
        walk_steps += 2 + 2ull * blas.node_count() + blas.refs.size() + 2;  // enter, the BLAS's walk, return
    }
    // The overlay pass of an instanced scene draws the TLAS's boxes (its depths are TLAS depths);
    // set_overlay_boxes gives it BLAS boxes moved into the world instead (the Python side makes them).
    fill_boxes(s, tlas.tree);
    s.bounds = node_box(tlas.tree.nodes[0]);
    s.node_count = tlas.tree.node_count();
    s.ref_count = std::uint32_t(tlas.tree.refs.size());
    s.stack_entries = std::max(tree_height(tlas.tree) + blas_height, 3u) - 2;
    s.walk_steps = walk_steps;
    return s;
}

}  // namespace bvhlab
