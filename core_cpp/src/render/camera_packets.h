// camera_packets.h — camera rays of a run of pixels traced ahead, all at once, through the flat
// scene's wide tree by the batch walk (wide_bvh.h intersect_wide_batch), which takes eight of them
// together where they run together (one origin, directions within ~5.7°: a camera's neighbouring
// pixels, or one pixel's samples; wide_packet.inl), for the CPU tracer's wide walk to take
// instead of tracing each alone (cpu_tracer.h nearest_hit). The batch's hits are intersect_wide's
// bit for bit, and a query is answered from here only where its ray is, bit for bit, the one
// traced ahead, so the image is the same whatever the tracer asks. Packets count no box tests:
// used only by a render that does not keep its cost (RenderSettings::keep_cost).
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "bvhlab/ray.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab {

class CameraPackets {
public:
    /// Camera rays a run holds (at most, but where a pixel has over kRays / kLeastPixels samples
    /// to trace: a run is at least kLeastPixels): its rays, hits and tables stay ~100 KiB a thread.
    static constexpr std::uint32_t kRays = 1024, kLeastPixels = 8;

    /// The pixels of a run for `samples` camera rays a pixel: as many as kRays holds, at least
    /// kLeastPixels (eight neighbours make a packet).
    static std::uint32_t run_pixels(std::uint32_t samples) {
        return std::max(kLeastPixels, kRays / std::max(1u, samples));
    }

    /// Starts a run of pixels [x0, x0 + pixels) of row y, none of their rays added yet.
    void begin(std::uint32_t y, std::uint32_t x0, std::uint32_t pixels) {
        y_ = y, x0_ = x0, pixels_ = pixels;
        first_.assign(pixels, 0), start_.assign(pixels + 1, 0);
        rays_.clear(), slot_.clear();
    }
    /// Pixel x0 + k's samples [first, first + count) come next, in order (k = 0, 1, ... in turn).
    void pixel(std::uint32_t k, std::uint32_t first, std::uint32_t count) {
        first_[k] = first;
        start_[k + 1] = start_[k] + count;
    }
    /// The next sample's camera query (`traced` false: the sample has no ray, e.g. outside a
    /// fisheye's circle).
    void add(const Ray& ray, bool traced) {
        slot_.push_back(traced ? std::uint32_t(rays_.size()) : kNoHit);
        if (traced) rays_.push_back(ray);
    }
    /// Traces the run's rays through `wide` (the tree of `bvh`).
    void trace(const WideBvh& wide, const Bvh& bvh) {
        hits_.resize(rays_.size());
        intersect_wide_batch(wide, bvh, rays_.data(), rays_.size(), hits_.data());
    }
    /// Where the ray of pixel (x, y)'s sample `sample` is among the rays traced (the order they
    /// were added in), or kNoHit where it is not in the run or has no ray.
    std::uint32_t slot(std::uint32_t x, std::uint32_t y, std::uint32_t sample) const {
        if (y != y_ || x < x0_ || x - x0_ >= pixels_) return kNoHit;
        const std::uint32_t k = x - x0_;
        if (sample < first_[k] || sample - first_[k] >= start_[k + 1] - start_[k]) return kNoHit;
        return slot_[start_[k] + sample - first_[k]];
    }
    /// The hit of the ray in `at` (a slot) where it is `ray`, bit for bit; else false (and where
    /// `at` is not a slot of this run: kNoHit).
    bool find(std::uint32_t at, const Ray& ray, Hit& hit) const {
        if (at >= rays_.size() || !same_bits(rays_[at], ray)) return false;
        hit = hits_[at];
        return true;
    }

private:
    static bool same_bits(const Ray& a, const Ray& b) {
        const float x[8] = {a.origin.x, a.origin.y, a.origin.z, a.dir.x, a.dir.y, a.dir.z, a.tmin, a.tmax};
        const float y[8] = {b.origin.x, b.origin.y, b.origin.z, b.dir.x, b.dir.y, b.dir.z, b.tmin, b.tmax};
        return std::memcmp(x, y, sizeof x) == 0;
    }

    std::uint32_t y_ = 0, x0_ = 0, pixels_ = 0;
    std::vector<std::uint32_t> first_, start_;  ///< each pixel's first sample; its entries start_[k] ..
    std::vector<std::uint32_t> slot_;           ///< an entry's ray in rays_, or kNoHit
    std::vector<Ray> rays_;
    std::vector<Hit> hits_;
};

}  // namespace bvhlab
