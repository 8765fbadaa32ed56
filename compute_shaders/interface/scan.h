// Prefix scan and min/max reduction (compute_shaders/scan/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_SCAN_H
#define HEMO_INTERFACE_SCAN_H

// Elements each invocation scans sequentially; a workgroup covers workgroupSize * this.
#define HEMO_SCAN_ITEMS 16

// scan/scan_block.comp: in-place exclusive scan of each block, block totals to `sums`.
// scan/scan_add.comp:   adds the (scanned) block offset sums[block] to every element.
#define HEMO_SCAN_BINDING_DATA 0
#define HEMO_SCAN_BINDING_SUMS 1
#define HEMO_SCAN_BINDING_LENGTH 2  // uint[]: a length the GPU computed (indirect scans)
#define HEMO_SCAN_BINDING_COUNT 3
// push constants (16 bytes): uint n (elements at this level; with a GPU length, the most);
// uint lengthIndex (0xffffffff: n is the length; else the level-0 length is
// length[lengthIndex] + lengthPlus); uint lengthPlus; uint level (0: the data; k: block sums
// of level k - 1, whose length is the level-0 length divided by the block size k times,
// rounded up).
#define HEMO_SCAN_NO_LENGTH 0xffffffffu

// scan/reduce_minmax.comp: (min, max) of floats in one dispatch (per-workgroup partials, the
// last workgroup to finish reduces them; the counter must start at 0 and is left at 0).
#define HEMO_REDUCE_ITEMS 8
#define HEMO_REDUCE_BINDING_VALUES 0
#define HEMO_REDUCE_BINDING_PARTIALS 1  // vec2 per workgroup
#define HEMO_REDUCE_BINDING_COUNTER 2   // uint: workgroups finished
#define HEMO_REDUCE_BINDING_RESULT 3    // vec2
#define HEMO_REDUCE_BINDING_COUNT 4
// push constants: uint n  (4 bytes)

#endif
