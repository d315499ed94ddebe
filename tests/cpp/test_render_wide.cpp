// The CPU tracer's wide traversal (render_settings.h Traversal::Wide): each query answered by the
// CPU queries' 8-wide walk gives the image of the stack walk bit for bit (colour and depth), with
// spheres, transparent surfaces (a shadow ray whose nearest crossing is glass left to the stack
// walk), the overlay's lines, several samples and threads, with the cost kept and without it (the
// camera rays then traced ahead, eight at a time where they run together); its cost is 8 box tests
// a wide node that intersect_wide visits for the pixel's primary ray; what it cannot do is refused
// or said.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <vector>

#include "bvhlab/isa.h"
#include "bvhlab/pixel_ray.h"
#include "bvhlab/wide_bvh.h"
#include "instanced_render.h"

using namespace bvhlab;
using namespace bvhlab::test;

namespace {

struct Images {
    std::vector<float> color, depth, cost;
    RenderTimings timings;
};

/// The images of a whole render (the cost where the settings keep it).
Images render(const RenderScene& scene, RenderSettings settings, Traversal traversal, std::uint32_t threads,
              const WideTrees& wide = {}) {
    settings.traversal = traversal;
    const std::size_t n = std::size_t(settings.width) * settings.height;
    Images out{std::vector<float>(4 * n), std::vector<float>(n), std::vector<float>(n), {}};
    std::unique_ptr<RenderJob> job = start_cpu(scene, settings, threads, wide);
    job->run(job->samples_per_pixel());
    job->resolve({out.color.data(), out.depth.data(), settings.keep_cost ? out.cost.data() : nullptr, nullptr});
    out.timings = job->timings();
    return out;
}

/// `settings` without the cost: the wide walk's camera rays traced ahead (cpu_tracer.h
/// trace_camera_rays).
RenderSettings without_cost(RenderSettings settings) {
    settings.keep_cost = false;
    return settings;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

std::size_t hit_pixels(const Images& im) {
    std::size_t hits = 0;
    for (float d : im.depth) hits += d < kNoDepth ? 1 : 0;
    return hits;
}

/// The instruction sets this build and CPU run (isa.h), each set in turn by the loop's body; the
/// one in use before is set back at the end.
struct EachIsa {
    std::vector<Isa> isas;
    Isa before = active_isa();
    EachIsa() {
        for (Isa isa : {Isa::Portable, Isa::Avx2, Isa::Avx512})
            if (isa_supported(isa)) isas.push_back(isa);
    }
    ~EachIsa() { set_isa(before); }
};

/// Stack and wide on 1 and 3 threads, wide with the cost kept and without it (the camera rays
/// traced ahead, in packets where they run together: the AVX2 path; the portable one walks each
/// alone, as with the cost), on every instruction set: the same colour and depth bits; the scene
/// in view (at least `in_view` of the pixels hit something). Without the cost on AVX2, `ahead` of
/// the camera rays were answered from the runs traced ahead (every one where the scene's every
/// surface is seen by camera rays, each traced ahead as the trace makes it); else none.
void expect_wide_is_stack(const RenderScene& scene, const RenderSettings& settings, double in_view = 0.1,
                          double ahead = 1.0) {
    const Images stack = render(scene, settings, Traversal::Stack, 1);
    EXPECT_GT(double(hit_pixels(stack)) / double(stack.depth.size()), in_view);
    const double camera_rays = double(stack.depth.size()) * settings.samples_per_axis * settings.samples_per_axis;
    const EachIsa each;
    for (Isa isa : each.isas) {
        set_isa(isa);
        for (std::uint32_t threads : {1u, 3u}) {
            const Images wide = render(scene, settings, Traversal::Wide, threads);
            EXPECT_TRUE(same_bits(stack.color, wide.color)) << threads << " threads, " << isa_name(isa);
            EXPECT_TRUE(same_bits(stack.depth, wide.depth)) << threads << " threads, " << isa_name(isa);
            EXPECT_EQ(wide.timings.camera_rays_ahead, 0u);
            const Images packets = render(scene, without_cost(settings), Traversal::Wide, threads);
            EXPECT_TRUE(same_bits(stack.color, packets.color)) << threads << " threads, ahead, " << isa_name(isa);
            EXPECT_TRUE(same_bits(stack.depth, packets.depth)) << threads << " threads, ahead, " << isa_name(isa);
            const double answered = double(packets.timings.camera_rays_ahead);
            if (isa >= Isa::Avx2) EXPECT_GE(answered, ahead * camera_rays) << threads << " threads";
            else EXPECT_EQ(answered, 0.0) << isa_name(isa);
            EXPECT_LE(answered, camera_rays);
        }
    }
}

}  // namespace

TEST(RenderWide, SpheresAndTrianglesGiveTheStackWalksImage) {
    const ScenePtr s = five_spheres();
    expect_wide_is_stack(s->render, s->settings);
    EXPECT_NE(render(s->render, s->settings, Traversal::Wide, 1).timings.device.find("wide walk"), std::string::npos);
}

/// A scene with a transparent material: the wide walk answered shadow rays whose nearest crossing
/// was opaque (transmission 0) and left those whose nearest was glass to the stack walk, the image
/// still the stack walk's (expect_wide_is_stack); the stack walk counts neither.
void expect_both_kinds_of_blocked_shadow_rays(const RenderTimings& wide, const RenderTimings& stack) {
    EXPECT_GT(wide.shadow_rays_opaque, 0u) << wide.device;
    EXPECT_GT(wide.shadow_rays_glass, 0u) << wide.device;
    EXPECT_EQ(stack.shadow_rays_opaque + stack.shadow_rays_glass, 0u);
    EXPECT_NE(wide.device.find("shadows through glass or hidden surfaces: stack walk"), std::string::npos)
        << wide.device;
}

TEST(RenderWide, TransparentSurfacesReflectionsAndSamplesGiveTheStackWalksImage) {
    const ScenePtr s = whitted_showcase();  // glass, mirrors, 2×2 samples
    expect_wide_is_stack(s->render, s->settings);
    const Images wide = render(s->render, s->settings, Traversal::Wide, 1);
    const Images wide3 = render(s->render, s->settings, Traversal::Wide, 3);
    expect_both_kinds_of_blocked_shadow_rays(wide.timings, render(s->render, s->settings, Traversal::Stack, 1).timings);
    // every pixel's rays are the same whichever thread traces them, and however the trace is cut
    // into budgets of steps (a query left to the stack walk goes on there: asked and counted once)
    EXPECT_EQ(wide3.timings.shadow_rays_opaque, wide.timings.shadow_rays_opaque);
    EXPECT_EQ(wide3.timings.shadow_rays_glass, wide.timings.shadow_rays_glass);
    RenderSettings cut = s->settings;
    cut.steps_per_dispatch = gpu::MIN_STEPS_PER_DISPATCH;
    const Images small = render(s->render, cut, Traversal::Wide, 2);
    EXPECT_GT(small.timings.dispatches, 2 * wide.timings.dispatches);  // the traces were cut
    EXPECT_EQ(small.timings.shadow_rays_opaque, wide.timings.shadow_rays_opaque);
    EXPECT_EQ(small.timings.shadow_rays_glass, wide.timings.shadow_rays_glass);
    EXPECT_TRUE(same_bits(small.color, wide.color));
    // the camera rays traced ahead with the traces cut into budgets: the same image, every camera
    // ray answered from them (on the AVX2 path: the packets')
    const Images ahead = render(s->render, without_cost(cut), Traversal::Wide, 2);
    EXPECT_TRUE(same_bits(ahead.color, wide.color));
    if (active_isa() >= Isa::Avx2)
        EXPECT_EQ(ahead.timings.camera_rays_ahead, std::uint64_t(s->settings.width) * s->settings.height * 4);
}

TEST(RenderWide, CameraRaysAheadInSamplePassesAndAfterACancelGiveTheWholeRendersImage) {
    // a job run in passes of samples (a viewport's refinement), and one cancelled mid-way and run
    // again: each pass's camera rays traced ahead from each pixel's own samples so far
    const ScenePtr s = bumpy_mesh(60);
    RenderSettings settings = s->settings;
    settings.samples_per_axis = 3;  // 9 samples: passes of 1, 2 and 6 more
    settings.traversal = Traversal::Wide;
    const Images whole = render(s->render, settings, Traversal::Wide, 2);
    const std::size_t n = std::size_t(settings.width) * settings.height;
    std::vector<float> color(4 * n);
    for (std::uint32_t threads : {1u, 3u}) {
        std::unique_ptr<RenderJob> job = start_cpu(s->render, without_cost(settings), threads);
        for (std::uint32_t samples : {1u, 3u, 9u}) job->run(samples);
        job->resolve({color.data(), nullptr, nullptr, nullptr});
        EXPECT_TRUE(same_bits(color, whole.color)) << threads << " threads, in passes";
        if (active_isa() >= Isa::Avx2) EXPECT_EQ(job->timings().camera_rays_ahead, 9 * n);
        // cancelled at the calling thread's third look (some rows and pixels done, some not: each
        // pixel's own samples so far), then run again
        std::unique_ptr<RenderJob> cut = start_cpu(s->render, without_cost(settings), threads);
        int looks = 0;
        Cancellation cancel([&] { return ++looks >= 3; }, std::chrono::milliseconds(0));
        EXPECT_THROW(cut->run(9, &cancel), Cancelled);
        EXPECT_EQ(looks, 3);
        cut->run(9);
        cut->resolve({color.data(), nullptr, nullptr, nullptr});
        EXPECT_TRUE(same_bits(color, whole.color)) << threads << " threads, after a cancel";
    }
}

TEST(RenderWide, CameraRaysAheadUnderEveryProjectionAndALensGiveTheStackWalksImage) {
    const ScenePtr s = bumpy_mesh(60);
    RenderSettings settings = s->settings;
    settings.samples_per_axis = 2;
    Camera& c = settings.camera;
    const Camera pinhole = c;
    c.aperture_radius = 0.05f, c.focus_distance = 8.0f;  // rays from points of a lens: fewer packets
    expect_wide_is_stack(s->render, settings);
    c = pinhole, c.projection = Projection::Orthographic, c.ortho_scale = 6.0f;  // parallel rays
    expect_wide_is_stack(s->render, settings);
    c = pinhole, c.projection = Projection::Equirectangular;
    expect_wide_is_stack(s->render, settings, 0.01);
    // the fisheye's frame corners lie outside its circle: samples without a camera ray, none traced
    c = pinhole, c.projection = Projection::FisheyeEquidistant, c.fisheye_fov_degrees = 150;
    expect_wide_is_stack(s->render, settings, 0.01, 0.6);
    const Images fisheye = render(s->render, without_cost(settings), Traversal::Wide, 1);
    EXPECT_LT(double(fisheye.timings.camera_rays_ahead), 0.9 * 4 * double(fisheye.depth.size()));
}

TEST(RenderWide, ARenderWithoutTheCostRefusesItAndTheHeatmap) {
    const ScenePtr s = five_spheres();
    RenderSettings settings = without_cost(s->settings);
    settings.traversal = Traversal::Wide;
    std::unique_ptr<RenderJob> job = start_cpu(s->render, settings, 1);
    job->run(1);
    const std::size_t n = std::size_t(settings.width) * settings.height;
    std::vector<float> color(4 * n), cost(n), heat(4 * n);
    job->resolve({color.data(), nullptr, nullptr, nullptr});  // the colour alone is there
    for (const RenderImages& out : {RenderImages{color.data(), nullptr, cost.data(), nullptr},
                                    RenderImages{nullptr, nullptr, nullptr, heat.data()}})
        try {
            job->resolve(out);
            ADD_FAILURE() << "no error";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("keep_cost"), std::string::npos) << e.what();
        }
    settings.mode = RenderMode::Heatmap;  // whose image the cost is
    try {
        start_cpu(s->render, settings);
        ADD_FAILURE() << "no error";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("keep_cost"), std::string::npos) << e.what();
    }
}

TEST(RenderWide, AnOpaqueSceneCountsNoShadowRaysByTheirNearestCrossing) {
    const ScenePtr s = five_spheres();  // every material opaque: the any-hit walk answers
    const RenderTimings wide = render(s->render, s->settings, Traversal::Wide, 2).timings;
    EXPECT_EQ(wide.shadow_rays_opaque + wide.shadow_rays_glass, 0u);
}

TEST(RenderWide, AMeshOfFiftyThousandTrianglesGivesTheStackWalksImage) {
    const ScenePtr s = bumpy_mesh();
    RenderSettings settings = s->settings;
    settings.samples_per_axis = 2;
    expect_wide_is_stack(s->render, settings);
    // the wide copy given (as the Python module passes its cached one) or made by the job: the same
    const WideBvh wide = make_wide(s->bvh);
    EXPECT_TRUE(same_bits(render(s->render, settings, Traversal::Wide, 2, {&wide, nullptr}).color,
                          render(s->render, settings, Traversal::Wide, 2).color));
}

TEST(RenderWide, TheOverlaysLinesAndTheClippingPlanesBoundThePrimaryRays) {
    const ScenePtr s = overlay_sphere();  // the lines in front of the sphere cut its primary rays short
    expect_wide_is_stack(s->render, s->settings, 0.05);
    RenderSettings clipped = s->settings;
    clipped.overlay = false;
    clipped.camera.clip_start = 6.2f;  // behind the near side of the sphere, in front of its far side
    clipped.camera.clip_end = 7.5f;
    expect_wide_is_stack(s->render, clipped, 0.02);  // a ring of the sphere left
    RenderSettings unclipped = clipped;
    unclipped.camera.clip_start = 0, unclipped.camera.clip_end = INFINITY;
    // the planes cut: fewer pixels hit than without them
    EXPECT_LT(hit_pixels(render(s->render, clipped, Traversal::Wide, 1)),
              hit_pixels(render(s->render, unclipped, Traversal::Wide, 1)));
}

TEST(RenderWide, CostIsEightBoxTestsAWideNodeOfThePrimaryRay) {
    const ScenePtr s = bumpy_mesh(60);
    RenderSettings settings = s->settings;
    const WideBvh wide = make_wide(s->bvh);
    for (RenderMode mode : {RenderMode::Shade, RenderMode::Heatmap}) {
        settings.mode = mode;
        const Images im = render(s->render, settings, Traversal::Wide, 2, {&wide, nullptr});
        std::size_t checked = 0, visiting = 0;
        for (std::uint32_t y = 0; y < settings.height; ++y)
            for (std::uint32_t x = 0; x < settings.width; ++x) {
                std::uint32_t visited = 0;
                intersect_wide(wide, s->bvh, pixel_ray(s->render, settings, x, y, 0), &visited);
                const float cost = im.cost[std::size_t(y) * settings.width + x];
                ASSERT_EQ(cost, float(8 * visited)) << "pixel " << x << ", " << y;
                ++checked, visiting += visited > 1;
            }
        EXPECT_EQ(checked, std::size_t(settings.width) * settings.height);
        EXPECT_GT(visiting, checked / 4);  // most rays go past the root
    }
}

TEST(RenderWide, AnEmptySceneIsSky) {
    auto s = std::make_unique<RenderTestScene>();
    s->material({1, 1, 1});
    s->build();
    small_image(s->settings, 16, 8);
    const Images wide = render(s->render, s->settings, Traversal::Wide, 2);
    EXPECT_EQ(hit_pixels(wide), 0u);
    EXPECT_TRUE(same_bits(wide.color, render(s->render, s->settings, Traversal::Stack, 2).color));
}

TEST(RenderWide, TraversalCountersAreRefused) {
    const ScenePtr s = five_spheres();
    RenderSettings settings = s->settings;
    settings.traversal = Traversal::Wide;
    settings.traversal_counters = true;
    try {
        start_cpu(s->render, settings);
        FAIL() << "no error";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'stack' or 'stackless'"), std::string::npos) << e.what();
    }
}

namespace {

/// The two-level queries' view of `s` (tlas.h), each mesh's wide copy in `wides`.
TwoLevel wide_view(const InstancedRender& s, std::vector<WideBvh>& wides) {
    wides.clear();
    for (const Bvh& t : s.trees) wides.push_back(make_wide(t));
    TwoLevel view{&s.tlas, {}};
    for (std::size_t k = 0; k < s.trees.size(); ++k) view.blases.push_back({&s.trees[k], &wides[k]});
    return view;
}

/// Instances (rotated, scaled unevenly, mirrored) of a triangle mesh between two meshes of spheres
/// and triangles (the later meshes' primitives numbered after the earlier ones' in the render
/// scene), every material opaque where `opaque`, else the first glass-like.
InstancedPtr spheres_and_meshes(bool opaque) {
    auto p = std::make_unique<InstancedRender>();
    InstancedRender& s = *p;
    s.add_mesh(random_scene(150, 20, 7), 1);
    s.add_mesh(octasphere(3, {0, 0, 0}, 2.0f), 0);
    s.add_mesh(random_scene(200, 40, 5), 1);
    if (opaque) s.materials[4] = 0.0f;  // the first material's transparency
    const float pi = 3.14159265f;
    s.blas_of = {1, 2, 2, 1, 2, 0};
    s.transforms = {
        Transform{},
        make_transform({0, 0, 1}, pi / 5, {1, 1, 1}, {8, 0, 0}),
        make_transform({1, 2, 3}, 1.1f, {2.0f, 0.5f, 1.3f}, {0, 10, 2}),  // non-uniform scale
        make_transform({1, 0, 0}, 0.3f, {-1, 1, 1}, {8, 10, 0}),          // mirrored
        make_transform({1, 1, 0}, 0.7f, {1.5f, 0.6f, 1.0f}, {16, 6, -1}),
        make_transform({0, 1, 1}, 2.0f, {0.8f, 0.8f, 0.8f}, {4, 5, 1}),
    };
    s.finish();
    return p;
}

}  // namespace

TEST(RenderWide, TwoLevelScenesGiveTheStackWalksImage) {
    for (bool opaque : {true, false}) {
        const InstancedPtr p = spheres_and_meshes(opaque);
        ASSERT_TRUE(p->two_level.two_level());
        std::vector<WideBvh> wides;
        const TwoLevel view = wide_view(*p, wides);
        RenderSettings settings = p->settings;
        settings.samples_per_axis = 2;
        const Images stack = render(p->two_level, settings, Traversal::Stack, 2);
        EXPECT_GT(double(hit_pixels(stack)) / double(stack.depth.size()), 0.1);
        for (std::uint32_t threads : {1u, 3u}) {
            const Images wide = render(p->two_level, settings, Traversal::Wide, threads, {nullptr, &view});
            EXPECT_TRUE(same_bits(stack.color, wide.color)) << "opaque " << opaque << ", " << threads << " threads";
            EXPECT_TRUE(same_bits(stack.depth, wide.depth)) << "opaque " << opaque;
            if (opaque) EXPECT_NE(wide.timings.device.find(", wide walk)"), std::string::npos) << wide.timings.device;
            else expect_both_kinds_of_blocked_shadow_rays(wide.timings, stack.timings);
            // no camera rays ahead in a two-level scene (no packets through instances): the same image
            const Images uncosted =
                render(p->two_level, without_cost(settings), Traversal::Wide, threads, {nullptr, &view});
            EXPECT_TRUE(same_bits(stack.color, uncosted.color));
            EXPECT_EQ(uncosted.timings.camera_rays_ahead, 0u);
        }
    }
    const InstancedPtr many = many_instances();  // 100 instances of one mesh
    std::vector<WideBvh> wides;
    const TwoLevel view = wide_view(*many, wides);
    EXPECT_TRUE(same_bits(render(many->two_level, many->settings, Traversal::Stack, 2).color,
                          render(many->two_level, many->settings, Traversal::Wide, 2, {nullptr, &view}).color));
}

TEST(RenderWide, ATwoLevelSceneWithoutItsTlasIsWalkedByTheStackWalkAndSaysSo) {
    const InstancedPtr p = mixed_instances();
    const Images stack = render(p->two_level, p->settings, Traversal::Stack, 2);
    const Images wide = render(p->two_level, p->settings, Traversal::Wide, 2);
    EXPECT_TRUE(same_bits(stack.color, wide.color));
    EXPECT_NE(wide.timings.device.find("without its TLAS: stack walk"), std::string::npos) << wide.timings.device;
}

TEST(RenderWide, AnotherScenesOrAMovedTlasOrAMeshWithoutItsWideCopyIsRefused) {
    const InstancedPtr p = mixed_instances(), other = many_instances();
    RenderSettings settings = p->settings;
    settings.traversal = Traversal::Wide;
    std::vector<WideBvh> wides;
    const TwoLevel others = wide_view(*other, wides);
    EXPECT_THROW(start_cpu(p->two_level, settings, 1, {nullptr, &others}), std::invalid_argument);
    std::vector<WideBvh> own;
    TwoLevel view = wide_view(*p, own);
    // the scene's meshes, one instance moved: a TLAS of the same counts, not the scene's
    std::vector<const Bvh*> blases;
    for (const Bvh& t : p->trees) blases.push_back(&t);
    std::vector<Transform> moved = p->transforms;
    moved[2].m[3] += 1.0f;
    const Tlas later = build_tlas(blases, p->blas_of, moved);
    TwoLevel moved_view = view;
    moved_view.tlas = &later;
    EXPECT_THROW(start_cpu(p->two_level, settings, 1, {nullptr, &moved_view}), std::invalid_argument);
    EXPECT_NO_THROW(start_cpu(p->two_level, settings, 1, {nullptr, &view}));
    view.blases[1].wide = nullptr;
    EXPECT_THROW(start_cpu(p->two_level, settings, 1, {nullptr, &view}), std::invalid_argument);
}
