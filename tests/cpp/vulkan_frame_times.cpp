// Not a test: frame times of the Vulkan renderer (lavapipe here) against the CPU reference on the
// same scenes at 800×600 (or argv[1]×argv[2]), both traversals. lavapipe uses LP_NUM_THREADS
// threads (default: every CPU), the CPU reference every hardware thread: the same count unless
// LP_NUM_THREADS says otherwise.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "bvhlab/vulkan_renderer.h"
#include "render_scenes.h"
#include "vulkan_test_env.h"

using namespace bvhlab;

namespace {

/// The faster of `runs` renders, after one that compiles the shaders.
template <class Render>
RenderTimings best_of(int runs, Render&& render) {
    render();
    RenderTimings best = render();
    for (int i = 1; i < runs; ++i) {
        RenderTimings t = render();
        if (t.total_ms < best.total_ms) best = t;
    }
    return best;
}

void time_scene(VulkanRenderer& vulkan, const char* name, const test::RenderTestScene& scene, RenderSettings s) {
    std::vector<float> image(std::size_t(s.width) * s.height * 4);
    std::printf("upload %s: %.1f ms\n", name, vulkan.upload(scene.render));
    const double pixels = double(s.width) * s.height;
    for (Traversal traversal : {Traversal::Stack, Traversal::Stackless}) {
        s.traversal = traversal;
        RenderTimings v = best_of(3, [&] { return vulkan.render(s, {image.data()}); });
        RenderTimings c = best_of(3, [&] { return render_cpu(scene.render, s, {image.data()}, 0); });
        std::printf(
            "%-16s %-9s  Vulkan %7.1f ms (overlay %.1f, trace %.1f, readback %.1f; %.2f Mrays/s primary)"
            "  CPU %7.1f ms (%.2f Mrays/s)  ratio %.2f\n",
            name, to_string(traversal).c_str(), v.total_ms, v.overlay_ms, v.trace_ms, v.readback_ms,
            pixels / v.trace_ms / 1e3, c.total_ms, pixels / c.trace_ms / 1e3, v.total_ms / c.total_ms);
    }
}

}  // namespace

int main(int argc, char** argv) {
    test::prepare_vulkan_environment();
    RenderSettings size;
    size.width = argc > 2 ? std::uint32_t(std::stoul(argv[1])) : 800;
    size.height = argc > 2 ? std::uint32_t(std::stoul(argv[2])) : 600;
    VulkanRenderer vulkan;
    const char* lp_threads = std::getenv("LP_NUM_THREADS");
    std::printf("%s (LP_NUM_THREADS=%s) vs CPU reference on %u threads, %ux%u, 1 sample per pixel\n",
                vulkan.device_name().c_str(), lp_threads ? lp_threads : "unset", std::thread::hardware_concurrency(),
                size.width, size.height);
    auto whitted = test::whitted_showcase();
    auto mesh = test::bumpy_mesh(400);  // 320 000 triangles
    for (auto [name, scene] : {std::pair{"whitted", whitted.get()}, std::pair{"mesh 320k tris", mesh.get()}}) {
        RenderSettings s = scene->settings;
        s.width = size.width;
        s.height = size.height;
        s.samples_per_axis = 1;
        time_scene(vulkan, name, *scene, s);
    }
}
