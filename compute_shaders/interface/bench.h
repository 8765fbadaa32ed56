// Benchmark probes (compute_shaders/bench/), used by hemo-bench only. Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_BENCH_H
#define HEMO_INTERFACE_BENCH_H

// bench/pair_gather.comp: the memory pattern of an SPH pair loop. Invocation i walks entries
// k = 0 .. entries-1 of a neighbour list, interleaved (entry k of particle i at k * n + i) or,
// with specialization constant 2 set, contiguous (at i * entries + k),
// and for each neighbour j loads `loads` vec4 (specialization constant 1, 0..4) from the
// buffers A..D at j, with a few flops per pair; the sum goes to OUT[i] so nothing is dead.
#define HEMO_BENCH_BINDING_LIST 0
#define HEMO_BENCH_BINDING_A 1
#define HEMO_BENCH_BINDING_B 2
#define HEMO_BENCH_BINDING_C 3
#define HEMO_BENCH_BINDING_D 4
#define HEMO_BENCH_BINDING_OUT 5
#define HEMO_BENCH_BINDING_COUNT 6
// push constants: uint n; uint entries  (8 bytes)

#endif
