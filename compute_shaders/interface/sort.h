// Stable LSD radix sort of (uint key, uint value) pairs (compute_shaders/sort/).
#ifndef HEMO_INTERFACE_SORT_H
#define HEMO_INTERFACE_SORT_H

// Most bits of the key handled per pass, and the most buckets per pass. A sort of k-bit keys
// makes ceil(k / HEMO_RADIX_BITS) passes of ceil(k / passes) bits each (14-bit cell indices:
// two passes of 7 bits), so no pass counts buckets that cannot occur.
#define HEMO_RADIX_BITS 8
#define HEMO_RADIX_BUCKETS 256

// Each invocation owns one chunk of consecutive pairs and keeps a private histogram, so the
// rank of every pair is fixed by (bucket, chunk, position in chunk): stable and deterministic
// without atomics. counts/offsets are laid out bucket-major: [bucket * chunkCount + chunk].
// Chunk size trades parallelism against the size of the counts array that is scanned.
#define HEMO_SORT_BINDING_PAIRS_IN 0
#define HEMO_SORT_BINDING_COUNTS 1
#define HEMO_SORT_BINDING_PAIRS_OUT 2
#define HEMO_SORT_BINDING_COUNT 3
// push constants: uint n; uint shift; uint chunkSize; uint chunkCount; uint digitBits (20 bytes)

#endif
