// The resolve step both renderers share (src/render/pixel_sums.h): sums per pixel to images, in
// blocks of pixels on the shared pool. Checked pixel by pixel against the formulas written here,
// on a frame of several blocks with a ragged last one, on 1, 2 and 5 threads (each the same bits),
// in both modes and with every subset of images that changes what is computed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "bvhlab/palette.h"
#include "pixel_sums.h"  // private to the renderers (core_cpp/src/render)

using namespace bvhlab;

namespace {

constexpr std::uint32_t kWidth = 301, kHeight = 211;  // 63,511 pixels: three blocks and a ragged fourth
constexpr std::size_t kPixels = std::size_t(kWidth) * kHeight;

PixelSums random_sums(std::uint32_t seed) {
    PixelSums s(kPixels, true);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> n(0, 4), count(0, 1000);
    std::uniform_real_distribution<float> value(0.0f, 3.0f);
    for (std::size_t i = 0; i < kPixels; ++i) {
        s.samples[i] = n(rng);  // a fifth without samples
        s.color[i] = gpu::vec4(value(rng), value(rng), value(rng), float(count(rng)));
        s.depth[i] = i % 7 == 0 ? std::numeric_limits<float>::infinity() : value(rng);
        s.counts[i] = {count(rng), count(rng), count(rng), count(rng), count(rng)};
    }
    return s;
}

gpu::FrameParams frame(std::uint32_t mode) {
    gpu::FrameParams f{};
    f.width = kWidth, f.height = kHeight, f.mode = mode, f.heatmap_scale = 300.0f;
    return f;
}

struct Images {
    std::vector<float> color = std::vector<float>(4 * kPixels, -1.0f), heat = color;
    std::vector<float> depth = std::vector<float>(kPixels, -1.0f), cost = depth;
    std::vector<float> counters = std::vector<float>(gpu::COUNTER_COUNT * kPixels, -1.0f);
    RenderImages all() { return {color.data(), depth.data(), cost.data(), heat.data(), counters.data()}; }
};

void expect_rgba(const float* got, float r, float g, float b, float a, std::size_t i) {
    ASSERT_EQ(got[0], r) << "pixel " << i;
    ASSERT_EQ(got[1], g) << "pixel " << i;
    ASSERT_EQ(got[2], b) << "pixel " << i;
    ASSERT_EQ(got[3], a) << "pixel " << i;
}

/// Every image of `im` as the formulas say for `sums` in `mode`.
void expect_resolved(const PixelSums& sums, std::uint32_t mode, const Images& im) {
    gpu::Palette palette;
    for (std::size_t i = 0; i < kPixels; ++i) {
        const std::uint32_t n = sums.samples[i];
        const gpu::vec4 s = sums.color[i];
        const float cost = n ? s.w / float(n) : 0.0f;
        ASSERT_EQ(im.cost[i], cost) << "pixel " << i;
        ASSERT_EQ(im.depth[i], std::isinf(sums.depth[i]) ? kNoDepth : sums.depth[i]) << "pixel " << i;
        const gpu::vec3 h = palette.heat_color(cost / 300.0f);
        if (n == 0) expect_rgba(&im.heat[4 * i], 0, 0, 0, 0, i), expect_rgba(&im.color[4 * i], 0, 0, 0, 0, i);
        else expect_rgba(&im.heat[4 * i], h.x, h.y, h.z, 1, i);
        if (n != 0 && mode == gpu::MODE_HEATMAP) expect_rgba(&im.color[4 * i], h.x, h.y, h.z, 1, i);
        if (n != 0 && mode == gpu::MODE_SHADE) expect_rgba(&im.color[4 * i], s.x / n, s.y / n, s.z / n, 1, i);
        const gpu::TraversalCounts& c = sums.counts[i];
        const std::uint32_t values[] = {c.box_tests, c.box_hits, c.prim_tests, c.prim_hits, c.instance_hits};
        for (std::uint32_t k = 0; k < gpu::COUNTER_COUNT; ++k)
            ASSERT_EQ(im.counters[gpu::COUNTER_COUNT * i + k], n ? float(double(values[k]) / n) : 0.0f)
                << "pixel " << i;
    }
}

}  // namespace

TEST(Resolve, EveryPixelOfEveryImageOnAnyThreadCount) {
    const PixelSums sums = random_sums(7);
    for (std::uint32_t mode : {gpu::MODE_SHADE, gpu::MODE_HEATMAP}) {
        std::vector<float> first;
        for (unsigned threads : {1u, 2u, 5u}) {
            Images im;
            resolve(sums.view(), frame(mode), im.all(), threads);
            expect_resolved(sums, mode, im);
            if (first.empty()) first = im.color;
            EXPECT_EQ(0, std::memcmp(first.data(), im.color.data(), first.size() * sizeof(float)));
        }
    }
}

TEST(Resolve, ColourAloneIsTheSameWithoutTheOtherImages) {
    // Heat colours are made only where an image shows them: the colour alone (shade mode, none
    // made; heatmap mode, made for it) equals the colour resolved beside every image.
    const PixelSums sums = random_sums(8);
    for (std::uint32_t mode : {gpu::MODE_SHADE, gpu::MODE_HEATMAP}) {
        Images all, alone;
        resolve(sums.view(), frame(mode), all.all());
        resolve(sums.view(), frame(mode), {alone.color.data()});
        EXPECT_EQ(all.color, alone.color);
        EXPECT_EQ(alone.heat, std::vector<float>(4 * kPixels, -1.0f));  // untouched
        Images heat_only;
        resolve(sums.view(), frame(gpu::MODE_SHADE), {nullptr, nullptr, nullptr, heat_only.heat.data()});
        EXPECT_EQ(all.heat, heat_only.heat);
    }
}

TEST(Resolve, RefusesWhatTheSumsDoNotHold) {
    PixelSums sums(kPixels, false);
    Images im;
    EXPECT_THROW(resolve(sums.view(), frame(gpu::MODE_SHADE), im.all()), std::invalid_argument);  // no counters
    PixelSums::View no_depth = sums.view();
    no_depth.depth = nullptr;  // as the Vulkan renderer's where no depth image was asked for
    EXPECT_THROW(resolve(no_depth, frame(gpu::MODE_SHADE), {im.color.data(), im.depth.data()}), std::logic_error);
    PixelSums small(kPixels - 1, true);
    EXPECT_THROW(resolve(small.view(), frame(gpu::MODE_SHADE), {im.color.data()}), std::logic_error);
}

TEST(Resolve, TransparentFilmAlphaIsTheCoveredShare) {
    // Film ▸ Transparent (or a holdout: make_frame_params counts the covered samples for both): a
    // shaded pixel's alpha is covered / samples (its colour as summed: the samples that showed
    // nothing, or a holdout, added none); the heatmap and the other images stay as they were.
    PixelSums sums = random_sums(9);
    sums.covered.assign(kPixels, 0u);
    std::mt19937 rng(10);
    for (std::size_t i = 0; i < kPixels; ++i) sums.covered[i] = sums.samples[i] ? rng() % (sums.samples[i] + 1) : 0u;
    gpu::FrameParams film = frame(gpu::MODE_SHADE);
    film.film_transparent = film.count_covered = 1;
    Images im, opaque;
    resolve(sums.view(), film, im.all(), 2);
    resolve(sums.view(), frame(gpu::MODE_SHADE), opaque.all(), 2);
    int partial = 0;
    for (std::size_t i = 0; i < kPixels; ++i) {
        const std::uint32_t n = sums.samples[i];
        const float alpha = n ? float(sums.covered[i]) / float(n) : 0.0f;
        const float* o = &opaque.color[4 * i];
        expect_rgba(&im.color[4 * i], o[0], o[1], o[2], alpha, i);
        partial += alpha > 0.0f && alpha < 1.0f;
    }
    EXPECT_GT(partial, 1000);
    EXPECT_EQ(im.depth, opaque.depth);
    EXPECT_EQ(im.heat, opaque.heat);
    film.mode = gpu::MODE_HEATMAP;  // heat colours are opaque
    Images heat, heat_opaque;
    resolve(sums.view(), film, heat.all());
    resolve(sums.view(), frame(gpu::MODE_HEATMAP), heat_opaque.all());
    EXPECT_EQ(heat.color, heat_opaque.color);
    film.mode = gpu::MODE_SHADE;
    PixelSums::View none = sums.view();
    none.covered = nullptr;  // a render that was not asked for them
    EXPECT_THROW(resolve(none, film, {im.color.data()}), std::logic_error);
    resolve(none, film, {nullptr, im.depth.data()});  // no colour: nothing needs them
}
