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


// bench/param_read.comp: invocation i of n runs `reads` iterations, each reading one vec4 at
// an index that depends only on the iteration (the same address for the whole dispatch) from
// a storage buffer, a uniform buffer or push constants (specialization constant 1 picks),
// with two fused multiply-adds per read; the result goes to OUT[i].
#define HEMO_BENCH_PARAM_BINDING_STORAGE 0
#define HEMO_BENCH_PARAM_BINDING_UNIFORM 1
#define HEMO_BENCH_PARAM_BINDING_OUT 2
#define HEMO_BENCH_PARAM_BINDING_COUNT 3
#define HEMO_BENCH_PARAM_VEC4S 8
// push constants: vec4 p[HEMO_BENCH_PARAM_VEC4S - 1]; uint n; uint reads  (120 bytes)

// bench/store_scatter.comp: invocation i of n writes `entries` uints, entry k at k * n + i
// (interleaved) or at i * entries + k (contiguous, specialization constant 1), through a
// storage buffer (OUT) or a storage texel buffer of R32_UINT texels (IMAGE; specialization
// constant 2 set), each store under a data-dependent mask like a list build's.
#define HEMO_BENCH_STORE_BINDING_OUT 0
#define HEMO_BENCH_STORE_BINDING_IMAGE 1
#define HEMO_BENCH_STORE_BINDING_COUNT 2
// push constants: uint n; uint entries  (8 bytes)

// bench/dispatch_probe.comp: invocation i of n reads IN[i] and writes nothing to memory
// others see, so dispatches of it need no barrier between them.
#define HEMO_BENCH_PROBE_BINDING_IN 0
#define HEMO_BENCH_PROBE_BINDING_COUNT 1
// push constants: uint n  (4 bytes)

#endif
