// Uniform-grid neighbour search (compute_shaders/grid/).
#ifndef HEMO_INTERFACE_GRID_H
#define HEMO_INTERFACE_GRID_H

// Cells are linearised x-fastest: cell = x + dims.x * (y + dims.y * z), so the three
// x-adjacent cells of a neighbour query are one contiguous range of the sorted particles.
// cellStart has cellCount + 1 entries; empty cells carry the running offset, so the
// particles of cells [a, b] are the slots [cellStart[a], cellStart[b + 1]).

// A grid of two parts (HemoGrid periodic.w = 2, hemo::sim::GridSpec::parts) sorts by the key
// cell + part * cellCount, part 0 for fluid particles (velocities.w = HEMO_GRID_FLUID_KIND)
// and 1 for the others; cellStart then has 2 cellCount + 1 entries.
#define HEMO_GRID_FLUID_KIND 0  // = HEMO_KIND_FLUID of interface/sph.h
// Parked fluid slots (HEMO_KIND_PARKED of interface/sph.h) stay in part 0 and are not counted
// as outside the grid, where they lie on purpose.
#define HEMO_GRID_PARKED_KIND 3

// The build is a counting sort by key, stable (ties keep their slot order), so the same input
// always gives the same order (engine/include/hemo/sim/neighbour_grid.hpp):
//   hash.comp ...... key and rank (an atomic count per key) of every particle; its data
//                    copied to the scratch arrays
//   cell_scan.comp . exclusive scan of the counts, block by block, and of the block totals
//   scatter.comp ... cellStart; each particle's (key, slot) into its key's range
//   reorder.comp ... each particle's place within its range by slot order, and its data moved
// The ranks come from integer atomics in whatever order the invocations run; the reorder's
// ordering by slot within each cell makes the result independent of it.

// grid/hash.comp
#define HEMO_HASH_BINDING_POSITIONS 0
#define HEMO_HASH_BINDING_PAIRS 1  // uvec2 per slot: (key, rank among the key's particles)
#define HEMO_HASH_BINDING_COUNTERS 2
#define HEMO_HASH_BINDING_VELOCITIES 3
#define HEMO_HASH_BINDING_KEY_COUNTS 4  // uint per key (+ 1): zero before, counts after
// The particle data the reorder gathers from, copied here (live -> scratch) by the same pass:
// as transfers they ran on every step, even the steps whose rebuild gate is closed.
#define HEMO_HASH_BINDING_NORMALS 5
#define HEMO_HASH_BINDING_IDS 6
#define HEMO_HASH_BINDING_POS_OUT 7
#define HEMO_HASH_BINDING_VEL_OUT 8
#define HEMO_HASH_BINDING_NORMAL_OUT 9
#define HEMO_HASH_BINDING_ID_OUT 10
#define HEMO_HASH_BINDING_COUNT 11
// counters[HEMO_COUNTER_OUTSIDE]: particles outside the grid (clamped into border cells);
// counters[HEMO_COUNTER_NONFINITE]: particles with a NaN/Inf coordinate (put in cell 0).
#define HEMO_COUNTER_OUTSIDE 0
#define HEMO_COUNTER_NONFINITE 1
#define HEMO_COUNTER_COUNT 4

// grid/cell_scan.comp: exclusive scan of the key counts within blocks of workgroupSize * HEMO_SCAN_ITEMS keys, and of the block totals (by
// the last workgroup to finish; the counter starts and ends at 0).
// The per-key buffers (counts, offsets in block, cellStart) hold whole uvec4 texels: their
// entries are padded to a multiple of 4.
#define HEMO_CELL_SCAN_BINDING_KEY_COUNTS 0
#define HEMO_CELL_SCAN_BINDING_LOCAL 1    // uint per key: offset within its block
#define HEMO_CELL_SCAN_BINDING_BLOCKS 2   // uint per block: total, then offset
#define HEMO_CELL_SCAN_BINDING_FINISHED 3 // uint
#define HEMO_CELL_SCAN_BINDING_COUNT 4

// grid/scatter.comp: cellStart = local + block offset; (key, slot) of every particle to its
// key's start + rank; the counts back to zero.
#define HEMO_SCATTER_BINDING_PAIRS 0
#define HEMO_SCATTER_BINDING_LOCAL 1
#define HEMO_SCATTER_BINDING_BLOCKS 2
#define HEMO_SCATTER_BINDING_CELL_START 3
#define HEMO_SCATTER_BINDING_ORDER 4  // uvec2 per slot: (key, source slot), in key order
#define HEMO_SCATTER_BINDING_KEY_COUNTS 5  // set back to zero for the next build
#define HEMO_SCATTER_BINDING_CELL_START_IN 6  // cellStart as uvec4 texels (the entries a partial build keeps)
#define HEMO_SCATTER_BINDING_COUNT 7

// grid/reorder.comp: moves particle data (from the scratch arrays) into sorted order in the
// live arrays, records the positions at this build, and updates id -> slot.
#define HEMO_REORDER_BINDING_ORDER 0
#define HEMO_REORDER_BINDING_POS_IN 1
#define HEMO_REORDER_BINDING_VEL_IN 2
#define HEMO_REORDER_BINDING_ID_IN 3
#define HEMO_REORDER_BINDING_POS_OUT 4
#define HEMO_REORDER_BINDING_VEL_OUT 5
#define HEMO_REORDER_BINDING_ID_OUT 6
#define HEMO_REORDER_BINDING_SLOT_OF_ID 7
#define HEMO_REORDER_BINDING_NORMAL_IN 8
#define HEMO_REORDER_BINDING_NORMAL_OUT 9
#define HEMO_REORDER_BINDING_POS_AT_BUILD 10
#define HEMO_REORDER_BINDING_CELL_START 11
#define HEMO_REORDER_BINDING_COUNT 12

// grid/neighbour_list.comp: every particle's neighbours closer than the radius, as slots of
// the sorted order, ascending; count may exceed the capacity (then the list is truncated).
#define HEMO_NLIST_BINDING_POSITIONS 0
#define HEMO_NLIST_BINDING_CELL_START 1
#define HEMO_NLIST_BINDING_COUNTS 2
#define HEMO_NLIST_BINDING_LIST 3
#define HEMO_NLIST_BINDING_COUNT 4

#endif
