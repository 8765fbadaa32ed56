// Weakly compressible SPH (compute_shaders/sph/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_SPH_H
#define HEMO_INTERFACE_SPH_H

// Texel slots. The passes read their read-only per-particle inputs (the list, positions,
// velocities, pair data, state...) as uniform texel buffers (GLSL samplerBuffer /
// usamplerBuffer with texelFetch; R32G32B32A32_SFLOAT for vec4 records, R32_UINT for indices)
// and write their outputs as storage buffers. On llvmpipe a storage-buffer load walks the
// SIMD lanes one by one with a branch per lane and component, where a texel fetch is one
// unrolled gather: the pair_gather probe's four vec4 gathers per entry fell from ~60 to
// ~5.6 ns (docs/benchmarks.md, "texel gathers"). On GPUs both are ordinary cached loads.
// Where a pass writes some records of a buffer and reads others (boundary_pressure.comp's
// state, wall/spring_forces.comp's accelerations), the buffer is bound twice, storage for
// the records it writes and texel for those it reads; no record is both.

// Particle kinds, stored as a float in velocities[i].w (exact small integers).
// Specialization constant of the SPH pair passes (density, boundary pressure, SPS, forces,
// the wall's reaction): the periodic axes, bit a for axis a (common/sph_params.glsl). An id
// past the passes' own constants (1, 2).
#define HEMO_SPEC_PERIODIC_AXES 9
// The pair passes that read a neighbour list (density, boundary pressure, SPS, forces, the
// wall's reaction) are also compiled with HEMO_CELL_WALK = 1, as "<name>_cells": the variant
// the solver runs when it keeps no list (hemo::sim::NeighbourSearch::Cells) and each pass walks
// the grid's cells instead (common/cell_walk.glsl). A separate module rather than a
// specialization constant: with the walk's loops compiled into the force pass but never
// taken, lavapipe (Mesa 22.3) ran the list path of a scene with its list in pages wrongly
// (SphPhysicsTest.VesselWithItsListInPagesGivesBitIdenticalRuns: time-step partials of some
// pages were never written), so the list variants hold none of the walk's code.
#ifndef HEMO_CELL_WALK
#define HEMO_CELL_WALK 0
#endif
#define HEMO_KIND_FLUID 0
#define HEMO_KIND_BOUNDARY 1  // rigid: fixed position, counts in density, viscosity, repulsion
#define HEMO_KIND_WALL 2      // vessel wall: a boundary particle for the fluid that moves as a mass
                              // point of the spring network (compute_shaders/wall/)
// A fluid slot with no particle in it (open vessel ends, hemo/sim/inflow.hpp): it lies in
// the fluid's part of the grid at the parking point, far outside the domain, so no pair pass
// finds it within the support; it builds no list of its own, the density pass gives it no
// volume, and the integrator leaves it where it is. The outlet parks the fluid that leaves;
// the inlet's spawns (sph/open_spawn.comp) take parked slots.
#define HEMO_KIND_PARKED 3

// Layout of the params storage buffer (std430), mirrored by hemo::sim::SphParams in C++.
//   vec4  gravity            xyz: gravity + body force (m/s^2)
//   float h                  smoothing length (m)
//   float supportRadius      kernel support 2h (m)
//   float listRadius         neighbour-list radius = support * (1 + skin) (m) = cell size
//   float kernelNorm         Wendland C2 (3D): 21 / (16 pi h^3)  (1/m^3)
//   float rho0               rest density (kg/m^3)
//   float taitB              Tait stiffness B = c0^2 rho0 / 7 (Pa)
//   float mu                 dynamic viscosity (Pa s) / the lattice factor of the viscous term
//                            (SphSettings::viscousLatticeFactor)
//   float etaSq              regulariser of the viscous term, 0.01 h^2 (m^2)
//   float psi                repulsion strength Psi (m/s^2)
//   float repulsionCutoff    D (m): no repulsion beyond this normal distance
//   float wallSpacing        spacing of boundary particles (m): width of T(y)
//   float cflAcoustic        C_a in dt <= C_a h / (c0 + |v|)
//   float cflForce           C_f in dt <= C_f sqrt(h / |a|)
//   float dtViscous          viscous limit 0.125 h^2 rho0 / mu (s)
//   float dtMax              upper bound of the time step (s)
//   float c0                 speed of sound (m/s)
//   uint  clampNegativePressure
//   uint  neighbourCapacity  entries per particle in the neighbour list
//   float dampingRate        settling damping xi (1/s): v <- v / (1 + xi dt) while t < dampingUntil
//   float dampingUntil       end of the settling phase (s); 0: no damping
//   uint  spsEnabled         sub-particle-scale turbulence (Dalrymple & Rogers 2006) on/off
//   float spsSmagorinsky     (C_s dp)^2 (m^2): eddy viscosity nu_t = (C_s dp)^2 |S|
//   float spsBlinn           C_I dp^2 (m^2): isotropic part -2/3 C_I dp^2 |S|^2
//   uint  listStride         entry k of particle i's neighbour list is at
//                            (i & listPageMask) * listParticleStride + k * listStride of the
//                            buffer of i's page: interleaved on GPUs (listStride = the page's
//                            slots, listParticleStride = 1: neighbouring invocations read
//                            neighbouring words), contiguous on CPU devices (listStride = 1,
//                            listParticleStride = capacity: each lane streams its own list,
//                            where the interleaved walk missed the cache on every entry;
//                            docs/benchmarks.md, pair_gather)
//   vec4  origin             xyz: domain origin (m), where periodic axes start
//   vec4  period             xyz: period (m) on periodic axes, 0 on the others
//   vec4  invPeriod          xyz: 1 / period, 0 on non-periodic axes
//   float backgroundPressure p_bg (Pa): added to the Tait pressure, p = B((rho/rho0)^7 - 1) + p_bg;
//                            the transmural (lumen) pressure of a vessel
//   float backgroundRamp     (s): p_bg rises linearly from 0 at t = 0 to its value at this time
//   uint  listParticleStride see listStride
//   float deltaSph           delta of the continuity density's diffusion term (delta-SPH); 0 with
//                            summation density
//   vec4  gravityOnly        xyz: gravity alone (m/s^2), without the body force: the hydrostatic
//                            density difference the diffusion term leaves alone
//   uint  listPageMask       pages: the neighbour list and the interacting pairs are split into
//                            pages of 2^k slots, each its own buffer, where one buffer for all
//                            slots would pass a binding limit of the device (a storage buffer's
//                            range, a texel buffer's elements, the largest allocation); a slot's
//                            index in its page is i & listPageMask (~0: one page, all slots).
//                            The passes that walk a list (build, density, boundary pressure,
//                            SPS, forces, the wall's reaction) run once per page over its slots
//                            ([first, n) in their push constants), with that page's buffers
//                            bound, and the boundary pass over each page's own active list and
//                            indirect arguments.
//   uint  pressureSolver     0: the Tait equation of state gives the pressure (WCSPH); 1: the
//                            DFSPH solve does (see "The pressure solver" below): the density
//                            pass writes the expansion side of the Tait law (p_bg at rho0
//                            and above) and boundary particles (rho0, their fluid's mean)
//   float solveFloor         DFSPH: the least denominator |sum_j m_j gradW_ij|^2 + sum_j |m_j gradW_ij|^2
//                            the stiffness divides by (kg^2 m^-8): a quarter of a full
//                            neighbourhood's on the fill's lattice. A particle the wall's
//                            boundary particles surround (none of it fluid) has a sum that
//                            nearly cancels, and its stiffness, unbounded, threw it out at
//                            10^13 m/s (the dam break without repulsion)
//   float rheologyExponent   non-Newtonian blood: (n - 1) / a of the Carreau-Yasuda law (see "Viscosity")
//   vec4  gridOrigin         the neighbour grid (common/grid.glsl, HemoGrid), fixed for a solver:
//   vec4  gridInvCell        origin (m), cells per m, cells per axis, periodic axes and parts;
//   uvec4 gridDims           what the cell walks (common/cell_walk.glsl) find a slot's
//   uvec4 gridPeriodic       candidate ranges with, as the list build does from its push constants
//   vec4  carreau            non-Newtonian blood: (mu_inf, mu_0 - mu_inf (Pa s, over the lattice
//                            factor), lambda (s), a); all 0 for Newtonian blood (see "Viscosity")
//   float solveCompliance    DFSPH: the density solve's compliance 1 / c0^2 (s^2 m^-2; see "The
//                            pressure solver"), 0 when fluid.solver_compressible is false
//   float solvePad0..2       0

// sph/build_list.comp: the neighbour (Verlet) list, over a grid of two parts (interface/grid.h:
// the fluid's slots first, then the boundary and wall particles', each part by cell).
#define HEMO_BUILD_BINDING_POSITIONS 0  // the grid's positions at build, with the kind in w
#define HEMO_BUILD_BINDING_CELL_START 1
#define HEMO_BUILD_BINDING_PARAMS 2
#define HEMO_BUILD_BINDING_NCOUNT 3
// Entries are slots; a boundary or wall neighbour's entry carries HEMO_LIST_BOUNDARY_BIT, so
// the density pass can sort the interacting pairs by kind without loading the neighbour's
// kind (boundary particles list only fluid neighbours, whose entries are plain slots).
#define HEMO_BUILD_BINDING_NLIST 4
#define HEMO_LIST_BOUNDARY_BIT 0x80000000u
#define HEMO_BUILD_BINDING_STATUS 5
// The boundary-pressure pass's active list (HEMO_BPRESSURE_BINDING_ACTIVE_ARGS), emptied by
// invocation 0 of the build: the list is filled again after every build.
#define HEMO_BUILD_BINDING_ACTIVE_ARGS 6
#define HEMO_BUILD_BINDING_COUNT 7

// Clusters (ListLayout::Clusters, CPU devices): the fluid's slots [0, fluid) in grid order are
// cut into clusters of HEMO_CLUSTER_SIZE consecutive slots (the last may hold fewer), and each
// cluster has one list, the union of its members' neighbour lists, which the cluster passes walk
// evaluating every entry against all members: on llvmpipe a texel fetch costs per lane whatever
// the arithmetic, so a fetch that serves eight pairs costs an eighth (hemo-bench
// primitives, pair_gather with clusters). An entry is a slot (bits 0-22) with the members within the list radius of it
// as a mask (bit 23 + m for member m) and HEMO_LIST_BOUNDARY_BIT for a boundary or wall
// neighbour. A slot appears at most once in a cluster's list: a cluster whose members lie in
// more than one row of grid cells walks each row's members separately, and a row keeps only
// the slots that no earlier row's members are within the list radius of. So the passes count
// every entry for every member (beyond the support the kernel is 0) and read no mask; the
// masks serve the build's neighbour count and the tests. Boundary entries that a member may come within the
// repulsion's reach of before the next build (common/repulsion.glsl; that reach plus the skin)
// fill the list from entry capacity - 1 down, all other entries (fluid, and boundary ones
// marked as such) from entry 0 up: the force pass runs the repulsion over the back section
// only. The count packs both (front | back << 16). The build stores whole texels of four, so
// each section's last texel may hold up to three entries of padding, which no pass reads.
// In a scene without wall particles the boundary particles' slots [fluid, n) are cut into
// clusters too, numbered after the fluid's (the first is ceil(fluid / HEMO_CLUSTER_SIZE)):
// their lists hold fluid entries only (all sph/boundary_clusters.comp needs), and no member
// names itself. Wall particles keep per-particle lists, which the wall's reaction reads.
#define HEMO_CLUSTER_SIZE 4
#define HEMO_CLUSTER_SLOT_MASK 0x7fffffu
#define HEMO_CLUSTER_MEMBER_SHIFT 23u
#define HEMO_CLUSTER_MAX_SLOTS 0x800000u  // slots the entries can name

// sph/build_clusters.comp: the clusters' lists.
#define HEMO_CBUILD_BINDING_POSITIONS 0  // the grid's positions at build, with the kind in w
#define HEMO_CBUILD_BINDING_CELL_START 1
#define HEMO_CBUILD_BINDING_PARAMS 2
#define HEMO_CBUILD_BINDING_CCOUNT 3  // uint per cluster: front | back << 16
#define HEMO_CBUILD_BINDING_CLIST 4   // clusterCapacity entries per cluster
#define HEMO_CBUILD_BINDING_STATUS 5
// The boundary-pressure pass's active list (HEMO_BPRESSURE_BINDING_ACTIVE_ARGS), emptied by
// invocation 0 of the fluid's clusters (as by sph/build_list.comp).
#define HEMO_CBUILD_BINDING_ACTIVE_ARGS 6
#define HEMO_CBUILD_BINDING_COUNT 7

// sph/cluster_order.comp: the order in which the cluster pair passes walk the fluid's clusters.
// A SIMD group runs a pair loop as long as its longest lane, and neighbouring clusters' lists
// differ in length (the free surface, the walls), so in grid order a group ran 12-16% more
// texel iterations than its lanes needed (the dam break). Each window of
// HEMO_CLUSTER_ORDER_WINDOW consecutive clusters (the last may hold fewer) is sorted by its
// clusters' front texels, then back texels, then cluster number (a stable sort, so the order
// follows from the counts alone): invocation g of a pair pass walks cluster order[g], which
// lies in g's own window, so the groups stay within a small region of the grid. The results
// are the same bit for bit: each cluster's sums do not depend on which invocation makes them.
// The boundary particles' clusters (sph/boundary_clusters.comp) get the same treatment: the
// active list as the sorting mode appended it (ITEMS, its length in ACTIVE_ARGS.w) is sorted
// window by window into the list that the evaluations walk (push constant `list` 1). Its
// windows hold whichever clusters the appends put there, which varies from run to run, as the
// active list's order always did; the results do not.
#define HEMO_CLUSTER_ORDER_WINDOW 64u
#define HEMO_CORDER_BINDING_CCOUNT 0  // the build's counts (front | back << 16)
#define HEMO_CORDER_BINDING_ORDER 1   // uint per cluster: the walk order
#define HEMO_CORDER_BINDING_ITEMS 2   // list 1: the active list as appended (clusters from `base`)
#define HEMO_CORDER_BINDING_ACTIVE_ARGS 3  // list 1: uvec4 whose w is the active list's length
#define HEMO_CORDER_BINDING_COUNT 4

// sph/density_clusters.comp: sph/density.comp over the clusters' lists (summation density).
#define HEMO_CDENSITY_BINDING_POSITIONS 0
#define HEMO_CDENSITY_BINDING_VELOCITIES 1
#define HEMO_CDENSITY_BINDING_PARAMS 2
#define HEMO_CDENSITY_BINDING_STATE 3
#define HEMO_CDENSITY_BINDING_CCOUNT 4
#define HEMO_CDENSITY_BINDING_CLIST 5  // RGBA32UI texels: four entries each
#define HEMO_CDENSITY_BINDING_CLOCK 6
#define HEMO_CDENSITY_BINDING_VISCOUS_VEL 7
#define HEMO_CDENSITY_BINDING_PAIR_POSITION 8
#define HEMO_CDENSITY_BINDING_ORDER 9  // sph/cluster_order.comp's walk order
#define HEMO_CDENSITY_BINDING_COUNT 10

// sph/forces_clusters.comp: sph/forces.comp over the clusters' lists (no SPS term).
#define HEMO_CFORCES_BINDING_POSITIONS 0
#define HEMO_CFORCES_BINDING_VELOCITIES 1
#define HEMO_CFORCES_BINDING_NORMALS 2
#define HEMO_CFORCES_BINDING_PARAMS 3
#define HEMO_CFORCES_BINDING_STATE 4
#define HEMO_CFORCES_BINDING_CCOUNT 5
#define HEMO_CFORCES_BINDING_CLIST 6
#define HEMO_CFORCES_BINDING_ACCEL 7
#define HEMO_CFORCES_BINDING_DT_LIMIT 8
#define HEMO_CFORCES_BINDING_IDS 9
#define HEMO_CFORCES_BINDING_STATUS 10
#define HEMO_CFORCES_BINDING_VISCOUS_VEL 11
#define HEMO_CFORCES_BINDING_PAIR_POSITION 12
#define HEMO_CFORCES_BINDING_DT_PARTIALS 13
#define HEMO_CFORCES_BINDING_DT_COUNTS 14
#define HEMO_CFORCES_BINDING_ORDER 15  // sph/cluster_order.comp's walk order
#define HEMO_CFORCES_BINDING_COUNT 16

// sph/density.comp: summation density and Tait pressure of fluid particles from the list.
#define HEMO_DENSITY_BINDING_POSITIONS 0
#define HEMO_DENSITY_BINDING_VELOCITIES 1
#define HEMO_DENSITY_BINDING_PARAMS 2
#define HEMO_DENSITY_BINDING_STATE 3
#define HEMO_DENSITY_BINDING_NCOUNT 4
#define HEMO_DENSITY_BINDING_NLIST 5
#define HEMO_DENSITY_BINDING_CLOCK 6  // the solver's clock (ramped background pressure)
#define HEMO_DENSITY_BINDING_VISCOUS_VEL 7  // written for fluid particles (see the pair data below)
// With continuity density (specialization constant 1 of this pass and the integrator: 1 with
// symplectic Euler, 2 with RK2), a fluid particle's density is carried in normals[i].w (fluid
// particles have no normal; the grid's reorder moves it with the particle; 0 reads as rho0,
// the fill's density). With 1 the pass advances it over the last step into state.x and the
// integrator stores that back; with 2 the pass writes its rate to state.z and the integrator's
// stages advance it.
#define HEMO_DENSITY_BINDING_NORMALS 8
#define HEMO_DENSITY_BINDING_PAIR_POSITION 9  // written for fluid particles (see the pair data below)
// The interacting pairs: of a fluid particle's list (built with a skin, so up to a third of
// its entries lie beyond the support at any step), the entries within interaction range now,
// for the SPS and force passes of the same evaluation, as plain slots with the list's layout
// (hemo_list_slot): the fluid neighbours from entry 0 up, in list order, and the boundary and
// wall neighbours from entry capacity - 1 down, in list order, so the force pass runs the
// repulsion in a loop of its own over the boundary pairs only. The count packs both:
// fluid pairs | boundary pairs << 16 (hemo_pair_counts). Interaction range: the kernel's
// support, or the repulsion's reach sqrt((|D| + dp)^2 + dp^2) where that is larger
// (common/repulsion.glsl). Entries of other particles are not written.
#define HEMO_DENSITY_BINDING_PAIR_COUNT 10
#define HEMO_DENSITY_BINDING_PAIR_LIST 11
// InflowParams (common/inflow.glsl): the pressure an open end's buffer holds (inletPressure,
// outletPressure) replaces the Tait pressure of the fluid in it
#define HEMO_DENSITY_BINDING_INFLOW 12
// The open ends' profiles (common/inflow.glsl, HEMO_OPEN_BINS): a velocity-driven buffer takes
// the pressure the lumen has next to its plane
#define HEMO_DENSITY_BINDING_OPEN_PROFILE 13
#define HEMO_DENSITY_BINDING_COUNT 14

// sph/boundary_pressure.comp: pressure and density of boundary particles extrapolated from
// their fluid neighbours (Adami, Hu & Adams 2012).
#define HEMO_BPRESSURE_BINDING_POSITIONS 0
#define HEMO_BPRESSURE_BINDING_VELOCITIES 1
#define HEMO_BPRESSURE_BINDING_PARAMS 2
#define HEMO_BPRESSURE_BINDING_STATE 3
#define HEMO_BPRESSURE_BINDING_NCOUNT 4
#define HEMO_BPRESSURE_BINDING_NLIST 5
// The pair data: what the force pass gathers of a neighbour j, written each force evaluation
// by the density pass (fluid) and the boundary-pressure pass (boundary and wall particles),
// two vec4:
//   pair position    (x_j, V_j p_j)     (m, m^3 Pa)
//   viscous velocity (v_j, +-V_j)       (m/s, m^3),   V_j = m_j / rho_j
// which is all the pressure form a_i = -(1 / rho_i) sum_j V_j (p_i + p_j) gradW_ij, the viscous
// term and the SPS term need (sph/forces.comp). v_j is what the viscous term sees: a fluid
// particle's own velocity, a boundary particle's no-slip velocity. The sign of the volume
// tells the kind: positive for fluid, negative for boundary and wall particles, zero for
// detached wall particles (no SPH mass). On llvmpipe a storage-buffer gather cost by its components
// (a float a third of a vec4, a vec2 nearly a vec4; hemo-bench primitives, pair_gather); Monaghan's pressure form,
// which also needs m_j, took a third gather and 12% more time in the force pass.
#define HEMO_BPRESSURE_BINDING_VISCOUS_VEL 6
#define HEMO_BPRESSURE_BINDING_CLOCK 7
#define HEMO_BPRESSURE_BINDING_PAIR_POSITION 8
// The state buffer again, read as a texel buffer at the fluid neighbours (STATE writes only
// the boundary particles' records, so no record is both read and written in the pass).
#define HEMO_BPRESSURE_BINDING_FLUID_STATE 9
// Most boundary particles of a tank have no fluid within the list radius (the dam break:
// 1,600-2,100 of 10,296 do), and no fluid particle reads their pair data. After each list
// build one pass over the non-fluid slots (HEMO_BPRESSURE_SORT) gives those the values of a
// particle without fluid neighbours and lists the others, the active ones; every force
// evaluation then runs over the active list alone (HEMO_BPRESSURE_ACTIVE), dispatched
// indirectly with the group count the sorting pass counted.
// With boundary clusters the sorting mode appends the active clusters, in no particular order,
// to a list of its own (its set binds that one here), and sph/cluster_order.comp sorts it into
// the walk order of the list the evaluations read.
#define HEMO_BPRESSURE_BINDING_ACTIVE 10       // uint per slot: the active slots (per particle: in no particular order)
#define HEMO_BPRESSURE_BINDING_ACTIVE_ARGS 11  // uvec4 (workgroups, 1, 1, active count): indirect arguments
#define HEMO_BPRESSURE_BINDING_COUNT 12
// The pass's modes (push constant `mode`):
#define HEMO_BPRESSURE_ACTIVE 0  // the active list's slots: pressure from the fluid neighbours
#define HEMO_BPRESSURE_SORT 1    // slots [first, n): list the active ones, set the others
// slots [first, n): set the particles without fluid neighbours only, to the pressure of the
// clock record given (for output between list builds); the active list is left alone
#define HEMO_BPRESSURE_REST 2
// sph/boundary_clusters.comp: the same pass over the boundary particles' clusters (scenes
// without wall particles), with the same bindings, modes and push constants plus the
// clusters' capacity and the first boundary cluster; NCOUNT and NLIST are the clusters' counts
// and lists (RGBA32UI texels), and the active list holds clusters (relative to the first).

// sph/sps_stress.comp: from each fluid particle's strain rate, its SPS stress tau (with the
// SPS term) and its viscosity (non-Newtonian blood, see "Viscosity" below); the force pass
// and the wall's reaction read both at the pair's fluid particles.
// NCOUNT / NLIST here and in the force pass: the interacting pairs (PAIR_COUNT / PAIR_LIST of
// the density pass), not the neighbour list.
#define HEMO_SPS_BINDING_POSITIONS 0
#define HEMO_SPS_BINDING_VELOCITIES 1
#define HEMO_SPS_BINDING_PARAMS 2
#define HEMO_SPS_BINDING_STATE 3
#define HEMO_SPS_BINDING_NCOUNT 4
#define HEMO_SPS_BINDING_NLIST 5
#define HEMO_SPS_BINDING_TAU_A 6  // vec4 (xx, yy, zz, xy) of tau (Pa)
#define HEMO_SPS_BINDING_TAU_B 7  // vec4 (xz, yz, 0, 0)
#define HEMO_SPS_BINDING_VISCOSITY 8  // float per fluid slot: mu_i (Pa s, over the lattice factor)
#define HEMO_SPS_BINDING_VISCOUS_VEL 9  // the pair data's viscous velocity (v, +-V), for the viscosity
#define HEMO_SPS_BINDING_COUNT 10
// Viscosity. Newtonian blood has one mu (params.mu). Non-Newtonian blood (Carreau-Yasuda)
// has its own per fluid particle from its shear rate |S| = sqrt(2 S:S):
//   mu_i = mu_inf + (mu_0 - mu_inf) (1 + (lambda |S|)^a)^((n - 1) / a),
// S from the corrected velocity gradient G M^-1 (Bonet & Lok 1999), with
// G = sum_j V_j (u_j - u_i) (x) gradW_ij and M = sum_j V_j (x_j - x_i) (x) gradW_ij, exact for a
// linear field (on the lattice M = 0.97 I at h/dp = 1.3), and u_j a boundary particle's no-slip
// velocity (the viscous term's, extrapolated from the fluid: Adami et al. 2012): with the
// wall's own velocity there, a particle next to the wall saw half its shear rate, and a
// shear-thinning fluid was too viscous there (a Carreau-Yasuda tube flowed 7% slow). Where
// M is nearly singular (det M < 1/4: a particle with few neighbours, at a free surface or in a
// splash) G alone.
// (params.carreau = (mu_inf, mu_0 - mu_inf, lambda, a), params.rheologyExponent = (n - 1) / a,
// the viscosities over the lattice factor as params.mu). A fluid pair's viscous term then
// takes mu_i + mu_j where the Newtonian one takes 2 mu, and a pair of a fluid particle and a
// boundary or wall particle 2 mu_i (the wall has no shear rate of its own): the harmonic
// and arithmetic means differ little where the shear rate varies over a support, and the
// sum keeps the pair terms symmetric. Compiled in by specialization constant 3 of the strain
// and force passes and 2 of the wall's reaction (hemo::sim::Rheology).


// sph/forces.comp: pressure, viscosity, repulsion, gravity; per-particle time-step limit.
#define HEMO_FORCES_BINDING_POSITIONS 0
#define HEMO_FORCES_BINDING_VELOCITIES 1
#define HEMO_FORCES_BINDING_NORMALS 2
#define HEMO_FORCES_BINDING_PARAMS 3
#define HEMO_FORCES_BINDING_STATE 4
#define HEMO_FORCES_BINDING_NCOUNT 5
#define HEMO_FORCES_BINDING_NLIST 6
#define HEMO_FORCES_BINDING_ACCEL 7
#define HEMO_FORCES_BINDING_DT_LIMIT 8
#define HEMO_FORCES_BINDING_IDS 9
#define HEMO_FORCES_BINDING_STATUS 10
#define HEMO_FORCES_BINDING_TAU_A 11
#define HEMO_FORCES_BINDING_TAU_B 12
#define HEMO_FORCES_BINDING_VISCOUS_VEL 13
#define HEMO_FORCES_BINDING_PAIR_POSITION 14
// The time step's reduction's first level (common/dt_fold.glsl), shared with the wall
// stage's spring pass:
#define HEMO_FORCES_BINDING_DT_PARTIALS 15  // vec2 (min, max) per SIMD group of both passes
#define HEMO_FORCES_BINDING_DT_COUNTS 16    // uint[2]: the partials each pass wrote
#define HEMO_FORCES_BINDING_VISCOSITY 17    // HEMO_SPS_BINDING_VISCOSITY, as an R32F texel buffer
#define HEMO_FORCES_BINDING_COUNT 18

// sph/dt_reduce.comp: the time step's reduction's second level (one workgroup).
#define HEMO_DTREDUCE_BINDING_PARTIALS 0  // texel vec2 (RG32F): HEMO_FORCES_BINDING_DT_PARTIALS
#define HEMO_DTREDUCE_BINDING_COUNTS 1    // uint[3]
#define HEMO_DTREDUCE_BINDING_RESULT 2    // vec2 (min, max) of every limit; NaN if any is
// texel vec2: the tools' contact pass's partials (tool/contact.comp; from index 0), pass 2
#define HEMO_DTREDUCE_BINDING_TOOL_PARTIALS 3
// With tools (interface/tool.h): the tools buffer (uniform), the clock, the contact pass's
// force and torque partials and their count, and the batch's tool log (placeholders without)
#define HEMO_DTREDUCE_BINDING_TOOLS 4
#define HEMO_DTREDUCE_BINDING_CLOCK 5
#define HEMO_DTREDUCE_BINDING_TOOL_FORCES 6
#define HEMO_DTREDUCE_BINDING_TOOL_FORCE_COUNT 7
#define HEMO_DTREDUCE_BINDING_TOOL_LOG 8
#define HEMO_DTREDUCE_BINDING_COUNT 9

// Open vessel ends (hemo/sim/inflow.hpp): at most this many, end 0 the inlet, then the outlets.
#define HEMO_OPEN_MAX_ENDS 8u
// Their counters (uint each): fluid particles parked outside the domain (through a tear), and
// per end e: those that left its buffer into the lumen across its plane, came into its buffer
// from the lumen, were parked past its end, and were spawned into its buffer as images. Each
// buffer's deficit, the particles it holds fewer than it started with, follows from them:
// LEAVE + PARKED - ENTER - SPAWNED (sph/open_spawn.comp makes up to that many images). The
// inlet's net inflow is its LEAVE - ENTER, an outlet's net outflow its ENTER - LEAVE.
#define HEMO_OPEN_COUNTER_PARKED_OUTSIDE 0u
#define HEMO_OPEN_COUNTER_LEAVE(e) (1u + 4u * (e))
#define HEMO_OPEN_COUNTER_ENTER(e) (2u + 4u * (e))
#define HEMO_OPEN_COUNTER_PARKED(e) (3u + 4u * (e))
#define HEMO_OPEN_COUNTER_SPAWNED(e) (4u + 4u * (e))
#define HEMO_OPEN_COUNTER_COUNT (1u + 4u * HEMO_OPEN_MAX_ENDS)
// A fluid slot's pending value (HEMO_INTEGRATE_BINDING_PENDING): 0, or end e's image owed to
// its buffer (OWING), or owed after spending a credit (CREDITED; sph/integrate.comp). A
// particle's credit for end e is normals.w = e + 1.
#define HEMO_OPEN_OWING(e) (1u + (e))
#define HEMO_OPEN_CREDITED(e) (1u + HEMO_OPEN_MAX_ENDS + (e))
// The pressure ends' speed and pressure bins (common/inflow.glsl): bins per plane, words per
// bin (low, high, count), the fixed-point offsets and scales of speeds (m/s) and pressures (Pa),
// and a plane's pressure before any particle was measured.
#define HEMO_OPEN_BINS 16u
#define HEMO_OPEN_SUM_WORDS 3u
#define HEMO_OPEN_SPEED_OFFSET 64.0
#define HEMO_OPEN_FIXED_SCALE 16777216.0
#define HEMO_OPEN_PRESSURE_OFFSET 1.0e6
#define HEMO_OPEN_PRESSURE_SCALE 2048.0
#define HEMO_OPEN_NO_PRESSURE -1.0e30f
// The profile's layout (float each; the sums': HEMO_OPEN_SUM_WORDS words each): end e's speed
// bin b at e BINS + b, its plane's pressure at PRESSURE(e).
#define HEMO_OPEN_PRESSURE(e) (HEMO_OPEN_MAX_ENDS * HEMO_OPEN_BINS + (e))
#define HEMO_OPEN_PROFILE_SIZE (HEMO_OPEN_MAX_ENDS * (HEMO_OPEN_BINS + 1u))


// sph/open_spawn.comp: the buffers' refill, at the start of every step that rebuilds the
// neighbour list (inside the rebuild gate, before the grid), over the fluid's slots [0, N):
// particles that left a buffer into the lumen since the last refill get their images at the
// buffer's far end, a buffer length back along the end's axis, in parked slots, as many per
// end as the buffer's deficit (HEMO_OPEN_COUNTER_*): first those that owe their buffer one
// (HEMO_OPEN_OWING), then those that spent a credit crossing (HEMO_OPEN_CREDITED: they had
// come into the buffer from the lumen, and their image is made only where the buffer has
// since lost particles at its far end, as reverse flow takes them out). The k-th served
// crosser (the owing of every end in end order, then the credited likewise, each class in
// slot order) takes the k-th parked slot in slot order (a prefix scan of the flags, no float
// atomics). With E ends (InflowParams.endCount) the scan has 2E + 1 segments of N flags:
// owing of ends 0..E-1, credited of ends 0..E-1, the parked slots.
#define HEMO_SPAWN_BINDING_POSITIONS 0
#define HEMO_SPAWN_BINDING_VELOCITIES 1
#define HEMO_SPAWN_BINDING_NORMALS 2
#define HEMO_SPAWN_BINDING_PENDING 3   // uint per fluid slot (HEMO_INTEGRATE_BINDING_PENDING)
#define HEMO_SPAWN_BINDING_SCAN 4      // uint[(2E + 1) N + 1 + E]: the segments' flags, then 0 (scanned: (2E + 1) N + 1); then the ends' deficits
#define HEMO_SPAWN_BINDING_CROSSERS 5  // uint per fluid slot: the slot of the k-th served crosser (bits 29-31: its end)
#define HEMO_SPAWN_BINDING_INFLOW 6    // InflowParams
#define HEMO_SPAWN_BINDING_COUNTERS 7  // HEMO_OPEN_COUNTER_*
#define HEMO_SPAWN_BINDING_STATUS 8
#define HEMO_SPAWN_BINDING_COUNT 9
#define HEMO_SPAWN_END_SHIFT 29u       // (fluid slots stay below 2^29)
// push constants: uint n (fluid slots N), uint mode
#define HEMO_SPAWN_FLAGS 0    // the segments' flags, scan[(2E + 1) N] = 0, the deficits
#define HEMO_SPAWN_SCATTER 1  // (after the scan) crossers[k] = i for each served crosser i of rank k
#define HEMO_SPAWN_COPY 2     // each parked slot of rank k < served takes crosser k's image; the
                              // crossers served or not needed clear their flag, the others count a shortfall

// sph/integrate.comp: symplectic Euler or one stage of RK2 midpoint with the GPU-reduced time
// step, clock, status. Specialization constant 2, the stage:
#define HEMO_INTEGRATE_SYMPLECTIC_EULER 0
#define HEMO_INTEGRATE_RK2_HALF 1  // save (x, v), move to the midpoint with dt / 2
#define HEMO_INTEGRATE_RK2_FULL 2  // from the saved (x, v) with the midpoint's v and a
#define HEMO_INTEGRATE_BINDING_POSITIONS 0
#define HEMO_INTEGRATE_BINDING_VELOCITIES 1
#define HEMO_INTEGRATE_BINDING_ACCEL 2
#define HEMO_INTEGRATE_BINDING_PARAMS 3
#define HEMO_INTEGRATE_BINDING_DT 4
#define HEMO_INTEGRATE_BINDING_CLOCK 5
#define HEMO_INTEGRATE_BINDING_STATUS 6
#define HEMO_INTEGRATE_BINDING_LOG 7
#define HEMO_INTEGRATE_BINDING_SAVED_POS 8
#define HEMO_INTEGRATE_BINDING_SAVED_VEL 9
#define HEMO_INTEGRATE_BINDING_STEP_DT 10
#define HEMO_INTEGRATE_BINDING_POS_AT_BUILD 11
#define HEMO_INTEGRATE_BINDING_CHECK_PARTIALS 12  // vec4 per SIMD group: its part of the rebuild test (below)
#define HEMO_INTEGRATE_BINDING_INFLOW 13  // InflowParams (common/inflow.glsl): the driven inflow zone
#define HEMO_INTEGRATE_BINDING_STATE 14  // vec4 (rho, p, rate, 0): the inflow zone's mass supply reads rho; continuity density rho or its rate
#define HEMO_INTEGRATE_BINDING_NORMALS 15  // w: where a fluid particle carries its density (continuity)
// POSITIONS and VELOCITIES again as texel slots: each invocation reads its own record through
// these and then writes it through the storage bindings (a texel read costs llvmpipe a
// fraction of a storage read; no record is read after it is written in the pass).
#define HEMO_INTEGRATE_BINDING_POSITIONS_IN 16
#define HEMO_INTEGRATE_BINDING_VELOCITIES_IN 17
// Open vessel ends (InflowParams.open, specialization constant 3 = 2): the counts of fluid
// crossing the inlet and outlet planes (HEMO_OPEN_COUNTER_*, integers: sums that do not
// depend on the order) and, per fluid slot, whether the particle crossed the inlet plane since
// the last spawn pass and still owes the inlet buffer its image (sph/open_spawn.comp).
#define HEMO_INTEGRATE_BINDING_OPEN_COUNTERS 23
#define HEMO_INTEGRATE_BINDING_PENDING 24
// Pressure ends (common/inflow.glsl, HEMO_OPEN_BINS): the sums of the axial velocities next
// to each plane, and the profiles the buffers move at (float per bin, the inlet's then the
// outlet's; sph/open_profile.comp).
#define HEMO_INTEGRATE_BINDING_OPEN_SUMS 25
#define HEMO_INTEGRATE_BINDING_OPEN_PROFILE 26
// Open ends: the escape mask (hemo/sim/inflow.hpp, EscapeGrid; a bit per cell, set where blood
// is far enough outside the vessel's wall to be parked)
#define HEMO_INTEGRATE_BINDING_ESCAPE_MASK 27
#define HEMO_INTEGRATE_BINDING_COUNT 28

// sph/open_profile.comp: one workgroup; each bin's mean axial speed from the integrator's sums
// (a bin nobody crossed keeps its last speed), then the sums back to zero.
#define HEMO_OPROFILE_BINDING_SUMS 0
#define HEMO_OPROFILE_BINDING_PROFILE 1
#define HEMO_OPROFILE_BINDING_COUNT 2

// The rebuild test (docs/architecture.md, "the rebuild test"), in the integrator's full
// stages (symplectic Euler, RK2's second): each slot's x displacement d.x since the list
// build and its reach |d - (c, 0, 0)| (+ the midpoint look-ahead), c the middle of the
// x-displacement range extrapolated from the two steps before; each SIMD group reduces them
// to a partial (min d.x, max d.x, the two largest reaches), and sph/rebuild_decide.comp, one
// workgroup dispatched after the integrator, reduces the partials to the result and arms the
// neighbour-rebuild gate for the next step (common/gate.glsl): rebuild when the two largest
// reaches' half-sum exceeds half the skin (and, after a symplectic step, the tile test below
// fails too).
#define HEMO_INTEGRATE_BINDING_DRIFT_RANGE 18  // uniform vec4: the result as the step found it
#define HEMO_INTEGRATE_BINDING_CHECK_COUNT 19  // uint: the partials this dispatch wrote
#define HEMO_CHECK_RESULT_REACH 2      // the float index of the reach the gate compares (the half-sum) in the result
// The tile test (symplectic Euler only; docs/architecture.md, "the rebuild test"): space is cut
// into tiles of at least 1.5 list radii (common/tiles.glsl, the grid as it was at the build);
// each tile collects the bounding box of its particles' displacements since the build (rigid
// boundary particles: the point 0), and the list still holds every pair within the support
// while no two neighbouring tiles' boxes (a tile and itself included) are further apart than
// the skin and the two largest reaches sum to less than a tile less the support. The rebuild
// gate opens only when this test and the reach test both fail. The integrator collects the
// boxes; sph/rebuild_decide.comp compares them, decides and arms the gate. (In the
// integrator's last workgroup the comparison cost the dam break's step 0.4 ms: llvmpipe runs
// the code after the other workgroups' early return under an empty mask.)
#define HEMO_INTEGRATE_BINDING_TILE_GRID 20   // uniform TileGrid (common/tiles.glsl)
#define HEMO_INTEGRATE_BINDING_TILE_BOXES 21  // uint[HEMO_TILE_WORDS] per tile (below)
#define HEMO_INTEGRATE_BINDING_TILE_OCCUPIED 22  // uint count, uint collected, then the indices of the tiles with moving particles (count and collected start and end at 0)
// A tile's words: 0-2 the largest -d (so the smallest d) and 4-6 the largest d per axis, as
// order keys (hemo_order_key: unsigned order = float order, 0 = empty); word 3 is nonzero
// when rigid boundary particles lie in the tile (sph/tile_static.comp), whose displacement is 0.
#define HEMO_TILE_WORDS 8
// The integrator collects the boxes in a step only when the last step's half-sum of the two
// largest reaches passed this fraction of the threshold (half the skin): the tiles decide only
// where the reach test fails.
#define HEMO_TILE_COLLECT_FROM 0.75
#define HEMO_TILE_STATIC_WORD 3

// sph/rebuild_decide.comp: the rebuild test's reduction, the tile test's comparison (constant
// 1 = 1, after symplectic Euler) and the gate (one workgroup).
#define HEMO_DECIDE_BINDING_TILE_GRID 0     // uniform TileGrid
#define HEMO_DECIDE_BINDING_TILE_BOXES 1
#define HEMO_DECIDE_BINDING_TILE_OCCUPIED 2
#define HEMO_DECIDE_BINDING_CHECK_RESULT 3  // vec4: the last step's result in, this step's out (HEMO_INTEGRATE_BINDING_DRIFT_RANGE)
#define HEMO_DECIDE_BINDING_TILE_RESULT 4   // float: the largest box separation of neighbouring tiles (m), for tests
#define HEMO_DECIDE_BINDING_GATE_ARMED 5
#define HEMO_DECIDE_BINDING_GATE_ARGS 6
#define HEMO_DECIDE_BINDING_GATE_OPENED 7
#define HEMO_DECIDE_BINDING_CHECK_PARTIALS 8  // texel vec4: the integrator's partials
#define HEMO_DECIDE_BINDING_CHECK_COUNT 9     // uint: how many it wrote
// uvec4[2]: the next step's indirect arguments for the integrator that collects the tile boxes
// ([0]) and the one that does not ([1]); one of them is (0, 1, 1) (tile test only)
#define HEMO_DECIDE_BINDING_INTEGRATE_ARGS 10
#define HEMO_DECIDE_BINDING_TILE_BOXES_IN 11  // the tile boxes as uvec4 texels, two per tile (for the reads)
#define HEMO_DECIDE_BINDING_COUNT 12

// sph/tile_static.comp: marks the tiles that hold rigid boundary particles (once per upload).
#define HEMO_TILE_STATIC_BINDING_POSITIONS 0  // texel vec4
#define HEMO_TILE_STATIC_BINDING_VELOCITIES 1 // texel vec4 (w: kind)
#define HEMO_TILE_STATIC_BINDING_TILE_GRID 2  // uniform TileGrid
#define HEMO_TILE_STATIC_BINDING_TILE_BOXES 3
#define HEMO_TILE_STATIC_BINDING_COUNT 4

// Clock buffer (std430): two records of {float time; float compensation (Kahan); float lastDt;
// uint steps}, read and written alternately (see sph/integrate.comp).
// Step log: vec2 (time after the step, dt) per step of the current batch.

// The pressure solver (hemo::sim::PressureSolver::Dfsph): divergence-free SPH (Bender &
// Koschier 2015, 2017) in place of the Tait equation of state for compression. The density
// pass then writes p = max(B ((min(rho, rho0) / rho0)^7 - 1) + p_bg, 0) (common/tait.glsl,
// hemo_expansion_pressure: the background pressure p_bg, 0 unless the scene sets one, where
// the blood is at or above rho0, falling as it expands) and the boundary pass rho0 and its
// fluid neighbours' mean of it, so the force pass gives the non-pressure acceleration a_np
// (with those pressures' pair terms, which load a vessel's wall with its lumen pressure).
// After the density solve a wall takes the reaction of both solves' mirrored boundary terms
// (wall/dfsph_reaction.comp). Two solves per step, each a relaxed Jacobi iteration of two pair
// passes with the stiffness denominator
//   D_i = max(|sum_j m_j gradW_ij|^2 + sum_{j fluid} |m_j gradW_ij|^2, floor)
// (j over fluid and boundary neighbours; a boundary neighbour moves with its own velocity and
// mirrors i's stiffness, as in Akinci et al. 2012):
//  divergence (mode 1), after the density pass and before the boundary pass: the velocities
//    at the new positions lose their compressive divergence,
//      predict  d_i = max(sum_j m_j (v_i - v_j) . gradW_ij, 0),  k_i = d_i / D_i
//      correct  v_i -= sum_{j fluid} m_j (k_i + k_j) gradW_ij + sum_b m_b k_i gradW_ib
//    (velocities and the pair data's copy of them, viscousVel), to a mean d_i dt' / rho0 at
//    most the tolerance, dt' the last step's dt. This is what takes out the velocities the
//    last density solve left behind: without it the dam break and a column at rest gained
//    energy every step until they blew up.
//  density (mode 0), after the force pass: the predicted velocities v*_i = v_i + dt a_i lose
//    the compression they would cause over the step dt,
//      predict  rho*_i = rho_i + dt sum_j m_j (v*_i - v*_j) . gradW_ij,
//               e_i = max(rho*_i - rho0 - p_i C, 0),
//               k_i = kappa_i / rho_i = e_i / (dt^2 D_i + rho_i^2 C)
//      correct  a_i -= sum_{j fluid} m_j (k_i + k_j) gradW_ij + sum_b m_b k_i gradW_ib
//    to a mean e_i / rho0 at most the tolerance, p_i = sum of k_i rho_i^2 over the solve's
//    corrections so far (kappa.w) and C = solveCompliance = 1 / c0^2: the compression the Tait
//    law, linearised at rho0, gives that pressure stays (C = 0, fluid.solver_compressible
//    false: none). Far above the acoustic step (dt^2 D_i >> rho_i^2 C) this is DFSPH's
//    constant-density solve; far below it p_i -> c0^2 (rho*_i - rho0), WCSPH's pressure, with
//    the compression held in the density from step to step instead of taken out within one.
//    The integrator's symplectic Euler step with a = a_np + a_p is then the solver's v = v*,
//    x += dt v. state.y shows the density pass's pressure plus that of the step's impulses
//    over dt: the divergence solve's (sum of k_i) rho_i^2 / dt plus the density solve's sum of
//    k_i rho_i^2, so its time average is the pressure that carries the fluid's weight (a
//    single step's is not: a solve corrects the error left by earlier steps whenever
//    the mean passes the tolerance, and a short step, such as one that ends at the end time,
//    shows that correction over its short dt).
// Each prediction sums its error per workgroup in fixed point (2^-20 of rho0 per particle,
// integers: the order of the sum cannot change a bit) and one workgroup reduces the sums
// (sph/dfsph_reduce.comp): the first prediction of a solve and every reduction always run;
// each later (correction, prediction) pair is a gated region (hemo::gpu::DispatchGate) that
// the reduction before it opens or closes, so the GPU decides how many run. The first region
// of each solve always opens (HEMO_DFSPH_MIN_*_CORRECTIONS): with none, a step whose mean
// was within the tolerance had no pressure at all, and a local compression grew unchecked
// until the mean passed it (a column at rest fell freely between the corrections). The host records
// R regions per solve, R at most the cap (hemo::sim::SphSolver::setRecordedIterations): a
// solve still open after the R-th, below the cap, marks the batch (HEMO_DFSPH_DEPTH_DEEPER)
// and hemo::sim::Simulation::run runs the batch again from its start with the cap's worth
// recorded. Every solve thus ends as the cap's recording would have ended it, bit for bit,
// while a step records only the few iterations that solves usually take.
#define HEMO_DFSPH_ERROR_SCALE 1048576.0
#define HEMO_DFSPH_MODE_DENSITY 0u
#define HEMO_DFSPH_MODE_DIVERGENCE 1u
// Corrections each solve runs even where its first prediction is within the tolerance (as
// Bender & Koschier 2017's loops do; docs/physics.md, "The pressure solver").
#define HEMO_DFSPH_MIN_DENSITY_CORRECTIONS 1u
#define HEMO_DFSPH_MIN_DIVERGENCE_CORRECTIONS 1u
#define HEMO_DFSPH_BINDING_POSITIONS 0   // texel vec4 (x, m)
#define HEMO_DFSPH_BINDING_VELOCITIES 1  // predict: texel vec4 (v, kind); correct: storage (its own record)
#define HEMO_DFSPH_BINDING_ACCEL 2       // predict: texel vec4; correct: storage (its own record)
#define HEMO_DFSPH_BINDING_PARAMS 3
#define HEMO_DFSPH_BINDING_STATE 4       // predict: storage vec4 (rho, p), its own record; correct: unused
#define HEMO_DFSPH_BINDING_PAIR_COUNT 5  // the density pass's interacting pairs (HEMO_DENSITY_BINDING_PAIR_*)
#define HEMO_DFSPH_BINDING_PAIR_LIST 6
#define HEMO_DFSPH_BINDING_KAPPA 7       // vec4 (k_i, p_i, divergence sum of k_i, the density solve's own p_i): predict's own record; correct reads (texel)
#define HEMO_DFSPH_BINDING_VISCOUS_VEL 8  // correct: storage, its own record (the divergence solve's v)
#define HEMO_DFSPH_CORRECT_BINDING_COUNT 9
#define HEMO_DFSPH_BINDING_PARTIALS 9    // predict: uint per workgroup, sum of the errors in fixed point
#define HEMO_DFSPH_BINDING_DT 10         // uniform vec2: the time step's reduction (sph/dt_reduce.comp)
#define HEMO_DFSPH_BINDING_CLOCK 11      // uniform: the clock's two records
#define HEMO_DFSPH_BINDING_COUNT 12
// sph/dfsph_reduce.comp: the stats (uint words, hemo::sim::PressureSolveStats) and the gate.
#define HEMO_DFSPH_REDUCE_BINDING_PARTIALS 0
#define HEMO_DFSPH_REDUCE_BINDING_STATS 1
#define HEMO_DFSPH_REDUCE_BINDING_ARMED 2   // hemo::gpu::DispatchGate::armedCounts
#define HEMO_DFSPH_REDUCE_BINDING_ARGS 3    // ... arguments
#define HEMO_DFSPH_REDUCE_BINDING_OPENED 4  // ... openings
#define HEMO_DFSPH_REDUCE_BINDING_DEPTH 5   // uint[HEMO_DFSPH_DEPTH_COUNT], reset by the host each batch
#define HEMO_DFSPH_REDUCE_BINDING_COUNT 6
// The depth words: what the batch's solves needed of the recorded regions.
#define HEMO_DFSPH_DEPTH_MAX 0     // most corrections of one solve in the batch
#define HEMO_DFSPH_DEPTH_DEEPER 1  // solves left open after the last recorded region, below the cap
#define HEMO_DFSPH_DEPTH_COUNT 2
// The stats: HEMO_DFSPH_STAT_COUNT words per solve, the density solve's first, then the
// divergence solve's.
#define HEMO_DFSPH_STAT_ACTIVE 0        // 1 while the current step's solve iterates
#define HEMO_DFSPH_STAT_ITERATIONS 1    // corrections of the current (last) step's solve
#define HEMO_DFSPH_STAT_ERROR 2         // float bits: the last mean error measured, / rho0
#define HEMO_DFSPH_STAT_CAP_HITS 3      // solves that ended at the cap above the tolerance
#define HEMO_DFSPH_STAT_SOLVES 4        // solves since the reset
#define HEMO_DFSPH_STAT_TOTAL 5         // corrections since the reset
#define HEMO_DFSPH_STAT_MAX 6           // most corrections of one solve since the reset
#define HEMO_DFSPH_STAT_WORST_ERROR 7   // float bits: the largest final error of a solve since the reset
#define HEMO_DFSPH_STAT_COUNT 8


// Status buffer (uint[8]).
#define HEMO_STATUS_FIRST_BAD_STEP 0      // first step with a non-finite particle (init ~0u)
#define HEMO_STATUS_NONFINITE 1           // particle updates that produced NaN/Inf
#define HEMO_STATUS_NEIGHBOUR_OVERFLOW 2  // particles whose neighbours exceeded the capacity
#define HEMO_STATUS_MAX_NEIGHBOURS 3      // most neighbours any particle had
#define HEMO_STATUS_BAD_INPUT_ID 4        // lowest id entering the force pass non-finite (init ~0u)
#define HEMO_STATUS_BAD_FORCE_ID 5        // lowest id whose acceleration came out non-finite (init ~0u)
// spawns at the open inlet that found no parked slot (the reserve ran out; the run stops)
#define HEMO_STATUS_OPEN_SHORTFALL 6
#define HEMO_STATUS_COUNT 8

#endif
