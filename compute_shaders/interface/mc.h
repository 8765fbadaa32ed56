// The blood surface: particle field and marching cubes (compute_shaders/mc/). Shared by GLSL
// and C++ (mirrored by hemo::surface::McGrid / McArgs with static_asserts).
#ifndef HEMO_INTERFACE_MC_H
#define HEMO_INTERFACE_MC_H

// The field lives at the points of a uniform grid, x fastest (rows padded to multiples of 4
// values), as fixed-point integers:
// value = int / HEMO_MC_FIXED_SCALE. Integers make the particle splat deterministic (integer
// addition does not depend on order) without float atomics.
#define HEMO_MC_FIXED_SCALE 1048576.0
// Voxels along x handled by one classify/generate invocation (a "run").
#define HEMO_MC_RUN 4

// McGrid, std430, 64 bytes:
//   vec4  origin    xyz: position of point (0,0,0) (m); w: voxel size (m)
//   uvec4 points    xyz: points per axis (>= 2 for any voxel); w: row stride, the ints per
//                   x-row (points.x rounded up to a multiple of 4; the padding stays 0):
//                   point (x, y, z) is field[x + stride (y + points.y z)]
//   uvec4 runs      x: runs per x-row = ceil((points.x - 1) / HEMO_MC_RUN); y, z: voxels
//                   along y and z; w: run count (written by mc/prepare.comp)
//   vec4  level     x: iso level (inside: field > iso); y: z-planes a particle's support
//                   spans (written by mc/bounds.comp for the splat); zw: 0
// McArgs, std430, 64 bytes (indirect arguments and totals, all uint):
//   [0..3]   classify/compact dispatch (x, y, z, 0) over runs
//   [4..7]   generate dispatch (x, y, z, 0) over active runs
//   [8..11]  draw (vertexCount, instanceCount, firstVertex, firstInstance)
//   [12..15] triangles (all the field holds), active runs, triangles written (<= capacity),
//            runs
#define HEMO_MC_ARGS_CLASSIFY 0
#define HEMO_MC_ARGS_GENERATE 4
#define HEMO_MC_ARGS_DRAW 8
#define HEMO_MC_ARGS_TRIANGLES 12
#define HEMO_MC_ARGS_ACTIVE_RUNS 13
#define HEMO_MC_ARGS_WRITTEN 14
#define HEMO_MC_ARGS_RUNS 15

// mc/bounds.comp (one workgroup): the fluid's bounding box -> grid origin, voxel, points.
#define HEMO_MC_BOUNDS_BINDING_POSITIONS 0
#define HEMO_MC_BOUNDS_BINDING_VELOCITIES 1  // w: particle kind; only fluid counts
#define HEMO_MC_BOUNDS_BINDING_GRID 2
#define HEMO_MC_BOUNDS_BINDING_SPLAT_ARGS 3     // uvec4: the splat's dispatch
#define HEMO_MC_BOUNDS_BINDING_SPLAT_GRID 4     // McGrid the splat writes on (= the grid, or coarser)
#define HEMO_MC_BOUNDS_BINDING_UPSAMPLE_ARGS 5  // uvec4: mc/upsample.comp's dispatch (0 when direct)
#define HEMO_MC_BOUNDS_BINDING_COUNT 6
// push: uint n; uint resolution (voxels along the longest side); float margin (m); float iso;
//       uint splatWorkgroup; float splatVoxel (m, 0: splat on the extraction grid);
//       uint upsampleWorkgroup; pad; vec4 clipLo, clipHi (m: the region the grid may cover)

// mc/upsample.comp: the extraction grid's values by trilinear interpolation of the splat grid
// (rounded to fixed point).
#define HEMO_MC_UPSAMPLE_BINDING_GRID 0
#define HEMO_MC_UPSAMPLE_BINDING_SPLAT_GRID 1
#define HEMO_MC_UPSAMPLE_BINDING_SPLAT_FIELD 2
#define HEMO_MC_UPSAMPLE_BINDING_FIELD 3
#define HEMO_MC_UPSAMPLE_BINDING_COUNT 4

// mc/splat.comp: each fluid particle adds round(scale V_j W(|x - x_j|, h)) to the points
// within its support (integer atomics).
#define HEMO_MC_SPLAT_BINDING_POSITIONS 0
#define HEMO_MC_SPLAT_BINDING_VELOCITIES 1
#define HEMO_MC_SPLAT_BINDING_STATE 2  // vec4 (rho, p, ...) per particle
#define HEMO_MC_SPLAT_BINDING_GRID 3
#define HEMO_MC_SPLAT_BINDING_FIELD 4
#define HEMO_MC_SPLAT_BINDING_COUNT 5
// push: uint n; float h; float kernelNorm; float rho0 (used where rho is not yet known)

// mc/prepare.comp (one invocation): runs of the grid and the classify dispatch.
#define HEMO_MC_PREPARE_BINDING_GRID 0
#define HEMO_MC_PREPARE_BINDING_ARGS 1
#define HEMO_MC_PREPARE_BINDING_COUNT 2
// push: uint classifyWorkgroup; uint maxRuns

// mc/classify.comp: per run, the cases of its voxels and their triangle count.
#define HEMO_MC_CLASSIFY_BINDING_GRID 0
#define HEMO_MC_CLASSIFY_BINDING_FIELD 1
#define HEMO_MC_CLASSIFY_BINDING_RUN_TRIANGLES 2  // uint per run (then scanned: offsets)
#define HEMO_MC_CLASSIFY_BINDING_RUN_ACTIVE 3     // uint per run, 0/1 (then scanned)
#define HEMO_MC_CLASSIFY_BINDING_RUN_CASES 4      // uint per run: four 8-bit cases, x ascending
#define HEMO_MC_CLASSIFY_BINDING_ARGS 5
#define HEMO_MC_CLASSIFY_BINDING_TABLE 6
#define HEMO_MC_CLASSIFY_BINDING_COUNT 7

// mc/compact.comp: active run indices in order; invocation 0 writes the generate and draw
// arguments and the totals.
#define HEMO_MC_COMPACT_BINDING_RUN_TRIANGLES 0
#define HEMO_MC_COMPACT_BINDING_RUN_ACTIVE 1
#define HEMO_MC_COMPACT_BINDING_ACTIVE_RUNS 2
#define HEMO_MC_COMPACT_BINDING_ARGS 3
#define HEMO_MC_COMPACT_BINDING_COUNT 4
// push: uint maxTriangles; uint generateWorkgroup

// mc/generate.comp: the triangles of each active run, at its scanned offset.
#define HEMO_MC_GENERATE_BINDING_GRID 0
#define HEMO_MC_GENERATE_BINDING_FIELD 1
#define HEMO_MC_GENERATE_BINDING_TABLE 2
#define HEMO_MC_GENERATE_BINDING_RUN_TRIANGLES 3
#define HEMO_MC_GENERATE_BINDING_RUN_CASES 4
#define HEMO_MC_GENERATE_BINDING_ACTIVE_RUNS 5
#define HEMO_MC_GENERATE_BINDING_ARGS 6
#define HEMO_MC_GENERATE_BINDING_VERTICES 7  // per vertex: vec4 position (w 1), vec4 normal (w 0)
#define HEMO_MC_GENERATE_BINDING_COUNT 8
// push: uint maxTriangles

#endif
