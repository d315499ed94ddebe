// deferred_parts.h — the ranges the top of a build left to the pool, built from one queue.
#pragma once
#include <functional>

#include "subtree_builder.h"

namespace bvhlab {

/// Builds the deferred ranges of `top` into top.parts on up to `threads` threads, from one queue
/// ordered by size, largest first. A range larger than `part_size` is split by one task down to
/// ranges of at most part_size, which join the queue at once (into its own `parts`); the others
/// are built whole. So the top can stop at ranges large enough for chunked passes to pay while
/// the threads share parts small enough to end together, with no wait between the two. The
/// calling thread runs `poll` while it waits for work. A task that throws stops the others, and
/// the exception comes out here; a stop asked of shared.cancel ends every thread's work early.
void build_deferred(BuildShared& shared, Subtree& top, std::uint32_t part_size, unsigned threads,
                    const std::function<void()>& poll);

}  // namespace bvhlab
