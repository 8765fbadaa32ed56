// Stable LSD radix sort of (uint key, uint value) pairs (compute_shaders/sort/).
#ifndef HEMO_INTERFACE_SORT_H
#define HEMO_INTERFACE_SORT_H

// Bits of the key handled per pass, and the number of buckets per pass.
#define HEMO_RADIX_BITS 8
#define HEMO_RADIX_BUCKETS 256

// Each invocation owns one chunk of consecutive pairs and keeps a private histogram, so the
// rank of every pair is fixed by (bucket, chunk, position in chunk): stable and deterministic
// without atomics. counts/offsets are laid out bucket-major: [bucket * chunkCount + chunk].
#define HEMO_SORT_BINDING_PAIRS_IN 0
#define HEMO_SORT_BINDING_COUNTS 1
#define HEMO_SORT_BINDING_PAIRS_OUT 2
#define HEMO_SORT_BINDING_COUNT 3
// push constants: uint n; uint shift; uint chunkSize; uint chunkCount  (16 bytes)

#endif
