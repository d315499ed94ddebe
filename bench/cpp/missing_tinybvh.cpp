// Built unless CMake is given -DBVHLAB_TINYBVH_DIR (a local copy of github.com/jbikker/tinybvh).
#include <stdexcept>

#include "bench_data.h"

std::unique_ptr<bench::Peer> bench::make_tinybvh_peer(const std::string&, unsigned) {
    throw std::invalid_argument("bvh_bench was built without tinybvh (cmake -DBVHLAB_TINYBVH_DIR=...)");
}
