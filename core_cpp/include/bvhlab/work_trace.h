// work_trace.h — callgrind marks for measuring how a parallel build shares its work (test-only:
// compiled in with -DBVHLAB_WORK_TRACE=ON, bench/build_threads.py). Each mark ends the current
// thread's segment of instructions and names it: under `valgrind --tool=callgrind
// --separate-threads=yes` every mark dumps that thread's counts since its last mark (its own
// file, the name in its `desc:` line), from which the script rebuilds each pool run's tasks and
// the serial parts between them. Without the option the marks compile to nothing.
#pragma once

#ifdef BVHLAB_WORK_TRACE
#include <cstdio>

#include <valgrind/callgrind.h>

/// Ends this thread's segment, named by the printf-style format and arguments.
#define BVHLAB_WORK_MARK(...)                                           \
    do {                                                                \
        char bvhlab_mark_[96];                                          \
        std::snprintf(bvhlab_mark_, sizeof(bvhlab_mark_), __VA_ARGS__); \
        CALLGRIND_DUMP_STATS_AT(bvhlab_mark_);                          \
    } while (0)
#else
#define BVHLAB_WORK_MARK(...) ((void)0)
#endif
