// Built when Embree 3's headers are not found (Debian: apt-get install libembree-dev).
#include <stdexcept>

#include "bench_data.h"
#include "tlas_bench.h"

std::unique_ptr<bench::Peer> bench::make_embree_peer(const std::string&, unsigned) {
    throw std::invalid_argument("bvh_bench was built without Embree 3 (apt-get install libembree-dev)");
}

std::unique_ptr<bench::InstancedPeer> bench::make_embree_two_level() {
    throw std::invalid_argument("tlas_bench was built without Embree 3 (apt-get install libembree-dev)");
}
