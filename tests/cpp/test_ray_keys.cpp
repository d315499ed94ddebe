// test_ray_keys.cpp — RayKeys::of_rays (ray_order.h): the keys of a block of rays, eight at a time
// on AVX2 (ray_piece_avx2.cpp), equal to the key of each ray alone (RayKeys::operator()) on every
// path this CPU has: origins inside, on and outside the box, infinite and not a number, signed
// zeros in the directions, both grid sizes, a flat box, and counts that leave a tail of the
// scalar loop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "bvhlab/isa.h"
#include "ray_order.h"

namespace bvhlab {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN(), kInf = std::numeric_limits<float>::infinity();

TEST(RayKeys, OfRaysEqualsEachRaysKeyOnEveryPath) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coord(-6.0f, 22.0f), dir(-1.0f, 1.0f);
    const float odd[] = {kNaN, kInf, -kInf, 0.0f, -0.0f, 16.0f, 15.999999f, 1e30f, -1e30f, 3e38f, 1e-44f};
    std::vector<float> o, d;
    for (int i = 0; i < 4099; ++i) {
        for (int a = 0; a < 3; ++a) {
            const bool special = rng() % 7 == 0;
            o.push_back(special ? odd[rng() % std::size(odd)] : coord(rng));
            d.push_back(rng() % 9 == 0 ? (rng() % 2 ? 0.0f : -0.0f) : dir(rng));
        }
    }
    const auto n = std::uint32_t(o.size() / 3);
    const Isa before = active_isa();
    std::uint32_t compared = 0, paths = 0;  // the instruction sets this build and CPU have
    for (Isa isa : {Isa::Portable, Isa::Avx2, Isa::Avx512}) paths += isa_supported(isa);
    for (const Aabb& box : {Aabb{{0, 0, 0}, {16, 16, 16}}, Aabb{{-1, 2, 5}, {9, 3, 5}}, Aabb{}})
        for (std::size_t rays : {std::size_t(kOrderLeast), 16 * kOrderLeast}) {
            const RayKeys keys(box, rays);
            for (Isa isa : {Isa::Portable, Isa::Avx2, Isa::Avx512}) {
                if (!isa_supported(isa)) continue;
                set_isa(isa);
                for (std::uint32_t count : {n, n - 3, 7u, 8u, 0u}) {
                    std::vector<std::uint16_t> got(count + 1, 0xbeef);
                    keys.of_rays(o.data(), d.data(), count, got.data());
                    for (std::uint32_t j = 0; j < count; ++j, ++compared)
                        ASSERT_EQ(got[j], keys(&o[3 * j], &d[3 * j])) << "ray " << j << " of " << count;
                    EXPECT_EQ(got[count], 0xbeef) << "written past the rays";
                }
            }
        }
    set_isa(before);
    EXPECT_GT(compared, 6u * paths * 8000);  // six boxes and sizes a path, each ~8,200 rays
}

}  // namespace
}  // namespace bvhlab
