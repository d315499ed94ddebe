// fuzz_input.h — turns the fuzzer's raw bytes into a build configuration, geometry and rays.
// Layout (every field reads 0 once the bytes run out, so any input is valid):
//   byte 0: method (% 6) and axis (/ 6 % 3)   byte 1: bins - 2        byte 2: max leaf size, SAH block, threads
//   byte 3: triangles (% 48)   byte 4: spheres (% 16)   byte 5: rays (% 48)   byte 6: encoding, SBVH
//   then the floats: triangles (9 each), spheres (4), ray origins and directions (6), then the
//   offset of a refit and a depth range for boxes.
// Byte 6 bit 0 chooses how a float is read: raw IEEE bits (4 bytes: NaN, inf, subnormals, 1e38)
// or a small grid value (1 byte: coincident, axis-aligned, degenerate shapes are common). Bit 1
// makes the method sbvh (byte 0's method is then not used), bits 2-4 its budget (kBudgets),
// bits 5-6 its alpha (kAlphas), bit 7 turns its unsplitting off; inputs older than the SBVH bits
// had them 0 (the corpus reads as it did).
#pragma once
#include <cstdint>
#include <cstring>
#include <vector>

#include "bvhlab/build_config.h"
#include "bvhlab/geometry.h"

namespace bvhlab::fuzz {

class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
    std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
    float raw_float() {
        std::uint32_t bits = 0;
        for (int k = 0; k < 4; ++k) bits |= std::uint32_t(byte()) << (8 * k);
        float f;
        std::memcpy(&f, &bits, 4);
        return f;
    }
    /// One of 256 values: -8 .. 7.9375 in steps of 1/16.
    float grid_float() { return float(int(byte()) - 128) / 16.0f; }

private:
    const std::uint8_t* data_;
    std::size_t size_, pos_ = 0;
};

/// The SBVH settings byte 6 draws from (the defaults 1.5 and 3e-4 first; a budget of 1 leaves
/// no room for spatial splits, 64 is the most allowed; an alpha of 0 tries a spatial split at every node).
constexpr float kBudgets[8] = {1.5f, 1.0f, 1.1f, 1.25f, 2.0f, 3.0f, 8.0f, 64.0f};
constexpr float kAlphas[4] = {3e-4f, 0.0f, 1e-2f, 1.0f};

struct FuzzCase {
    BuildConfig config;
    std::vector<float> triangles, spheres, origins, directions;
    float refit_offset = 0;
    std::uint32_t depth_min = 0, depth_max = 0;
    std::uint32_t threads = 1;

    GeometryView view() const { return {triangles.data(), triangles.size() / 9, spheres.data(), spheres.size() / 4}; }
};

inline FuzzCase read_case(const std::uint8_t* data, std::size_t size) {
    ByteReader in(data, size);
    FuzzCase c;
    const std::uint8_t kinds = in.byte();
    c.config.method = static_cast<SplitMethod>(kinds % 6);
    c.config.axis = static_cast<AxisPolicy>(kinds / 6 % 3);
    c.config.bins = 2 + in.byte() % 255;
    const std::uint8_t leaf = in.byte();
    c.config.max_leaf_size = 1 + leaf % 8;
    c.config.sah_block = 1u << (leaf >> 3 & 7) % 7;  // 1 .. 64
    c.threads = c.config.threads = 1 + (leaf >> 7);
    const std::size_t triangles = in.byte() % 48, spheres = in.byte() % 16, rays = in.byte() % 48;
    const std::uint8_t encoding = in.byte();
    const bool raw = encoding & 1;
    if (encoding & 2) {
        c.config.method = SplitMethod::Sbvh;
        c.config.sbvh_budget = kBudgets[encoding >> 2 & 7];
        c.config.sbvh_alpha = kAlphas[encoding >> 5 & 3];
        c.config.sbvh_unsplit = !(encoding & 0x80);
    }
    auto next = [&] { return raw ? in.raw_float() : in.grid_float(); };
    c.triangles.resize(9 * triangles);
    for (float& f : c.triangles) f = next();
    c.spheres.resize(4 * spheres);
    for (float& f : c.spheres) f = next();
    c.origins.resize(3 * rays);
    c.directions.resize(3 * rays);
    for (std::size_t i = 0; i < 3 * rays; ++i) c.origins[i] = next(), c.directions[i] = next();
    c.refit_offset = next();
    c.depth_min = in.byte() % 70;
    c.depth_max = c.depth_min + in.byte() % 8;
    return c;
}

}  // namespace bvhlab::fuzz
