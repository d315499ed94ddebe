// callgrind_marks.h — CALLGRIND_START_INSTRUMENTATION / CALLGRIND_STOP_INSTRUMENTATION for the
// benches' `once` modes (run under `valgrind --tool=callgrind --instr-atstart=no`): valgrind's own
// header where it is installed, else marks that do nothing (the benches then run as they are).
#pragma once

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif
