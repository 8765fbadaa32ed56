// Vessel wall: mass-spring model (compute_shaders/wall/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_WALL_H
#define HEMO_INTERFACE_WALL_H

// Wall particles have kind HEMO_KIND_WALL (interface/sph.h).

// Spring record (std430, 32 bytes), mirrored by hemo::sim::GpuSpring:
//   uint  a, b          particle ids of the ends, a < b
//   float restLength    m
//   float stiffness     N/m
//   float damping       N s/m (along the spring)
//   float maxForce      N: a tension above this breaks the spring for good
//   uint  broken        0 or 1
//   uint  pad
// The force on end a is +f d, on end b -f d, with d = (x_b - x_a) / |x_b - x_a| and
// f = stiffness (|x_b - x_a| - restLength) + damping (v_b - v_a) . d (positive: tension).

// Per particle id: vec4 (mass in kg, anchored 0/1, 0, 0).

// wall/spring_forces.comp: one invocation per particle slot; wall particles gather the forces
// of their unbroken springs through the CSR adjacency (springsOf[first[id] .. first[id + 1]))
// plus the exact reaction of every force the fluid felt from them (pressure, viscosity,
// repulsion: the pair terms of sph/forces.comp, negated), and get their acceleration (gravity
// included; zero when anchored) and time-step limit.
#define HEMO_SPRINGF_BINDING_POSITIONS 0
#define HEMO_SPRINGF_BINDING_VELOCITIES 1
#define HEMO_SPRINGF_BINDING_IDS 2
#define HEMO_SPRINGF_BINDING_SLOT_OF_ID 3
#define HEMO_SPRINGF_BINDING_SPRINGS 4
#define HEMO_SPRINGF_BINDING_FIRST 5
#define HEMO_SPRINGF_BINDING_SPRINGS_OF 6
#define HEMO_SPRINGF_BINDING_WALL_INFO 7
#define HEMO_SPRINGF_BINDING_ACCEL 8
#define HEMO_SPRINGF_BINDING_DT_LIMIT 9
#define HEMO_SPRINGF_BINDING_PARAMS 10    // SphParams
#define HEMO_SPRINGF_BINDING_STATE 11     // (rho, p) per slot
#define HEMO_SPRINGF_BINDING_NCOUNT 12    // neighbour list (a wall particle's: its fluid neighbours)
#define HEMO_SPRINGF_BINDING_NLIST 13
#define HEMO_SPRINGF_BINDING_NORMALS 14
// The pair data of interface/sph.h: viscous velocity (v, +-V) and pair position (x, V p). A
// wall particle's own viscous velocity is the no-slip velocity the fluid's viscous term used;
// a fluid neighbour's two vec4 are all the reaction's pair terms need (the repulsion also
// reads the neighbour's mass and normalisation, only where it acts).
#define HEMO_SPRINGF_BINDING_WALL_VEL 15
#define HEMO_SPRINGF_BINDING_COUNTERS 16
#define HEMO_SPRINGF_BINDING_FRAMES 17    // uvec2 per id: the normal's two frame points
#define HEMO_SPRINGF_BINDING_PAIR_POSITION 18
// The acceleration buffer again, read as a texel buffer at the fluid neighbours (ACCEL writes
// only wall particles' records, so no record is both read and written in the pass).
#define HEMO_SPRINGF_BINDING_FLUID_ACCEL 19
// The springs as a storage buffer: the pass sets broken flags (rupture: end a of a spring
// whose tension exceeds its maximum force; the two ends compute the same tension).
#define HEMO_SPRINGF_BINDING_SPRINGS_RW 20
// The time step's reduction, begun by the fluid's force pass (interface/sph.h, HEMO_FORCES_BINDING_DT_*):
#define HEMO_SPRINGF_BINDING_DT_PARTIALS 21
#define HEMO_SPRINGF_BINDING_DT_COUNTS 22
// vec4 per slot, written for wall slots: (F_fluid / m + g, 0), what the fluid (and, under
// DFSPH, the solve's reaction, wall/dfsph_reaction.comp) and gravity give the particle for the
// whole step; the wall's substeps (wall/substep.comp) add the springs to it.
#define HEMO_SPRINGF_BINDING_HELD 23
// vec4 per slot, written for wall slots when the pass computes wall shear (push wallShear):
// (the wall shear stress the fluid exerts, Pa: the tangential viscous force on the particle
// over the lumen area it carries, wall info z; 1 where fluid wets the particle else 0).
#define HEMO_SPRINGF_BINDING_WSS 24
// float per fluid slot (R32F texel): the fluid's viscosity, with non-Newtonian blood
// (interface/sph.h, "Viscosity"; HEMO_SPS_BINDING_VISCOSITY).
#define HEMO_SPRINGF_BINDING_VISCOSITY 25
#define HEMO_SPRINGF_BINDING_COUNT 26

// wall/dfsph_reaction.comp (DFSPH scenes only): after the density solve, each wall particle
// adds the reaction of the pressure the solve gave its fluid neighbours through the mirrored
// boundary term, F_w = sum_f m_f m_w (p_f / rho_f^2) gradW_fw, to its acceleration; push:
// uint n, uint first, uint idCount (the slots [first, n)).
#define HEMO_WALLP_BINDING_POSITIONS 0   // texel vec4 (x, SPH mass)
#define HEMO_WALLP_BINDING_VELOCITIES 1  // texel vec4 (v, kind)
#define HEMO_WALLP_BINDING_IDS 2         // texel uint
#define HEMO_WALLP_BINDING_WALL_INFO 3   // texel vec4 by id (mass, anchored)
#define HEMO_WALLP_BINDING_STATE 4       // texel vec4 (rho, p)
#define HEMO_WALLP_BINDING_KAPPA 5       // texel vec4: y, the solve's pressure (interface/sph.h, HEMO_DFSPH_BINDING_KAPPA)
#define HEMO_WALLP_BINDING_NCOUNT 6      // the wall particle's fluid neighbours (as HEMO_SPRINGF_BINDING_NCOUNT)
#define HEMO_WALLP_BINDING_NLIST 7
#define HEMO_WALLP_BINDING_PARAMS 8
#define HEMO_WALLP_BINDING_ACCEL 9       // storage: its own (wall) record
#define HEMO_WALLP_BINDING_HELD 10       // storage: its own record of HEMO_SPRINGF_BINDING_HELD
#define HEMO_WALLP_BINDING_COUNT 11

// wall/substep.comp: the wall's substeps. A scene whose springs would limit the step (their
// dt <= C sqrt(m / sum k)) lets the wall take N substeps of dt / N per fluid step instead
// (hemo::sim::SpringNetwork::substeps): the fluid's force on it held for the step, the springs
// re-evaluated, rupture included, at every substep; symplectic Euler, as the fluid. Mode
// ADVANCE: v += a dt / N, x += v dt / N for the free wall slots; mode FORCE: a = springs / m +
// held (rupture and detachment as wall/spring_forces.comp). The step records ADVANCE, then
// (FORCE, ADVANCE) N - 1 times, after the fluid's dt is known and before the integrator,
// which then leaves wall particles where the substeps put them. Push: uint n, uint first,
// uint idCount, uint substeps, uint mode, uint clockIn, float endTime.
#define HEMO_SUBSTEP_MODE_ADVANCE 0u
#define HEMO_SUBSTEP_MODE_STEP 1u
#define HEMO_SUBSTEP_BINDING_POSITIONS 0     // storage: the substep's output, its own record
#define HEMO_SUBSTEP_BINDING_VELOCITIES 1    // storage: the substep's output, its own record
#define HEMO_SUBSTEP_BINDING_POSITIONS_IN 2  // texel vec4: the substep's input (the other pair, or
#define HEMO_SUBSTEP_BINDING_VELOCITIES_IN 3 //   the same buffers for a substep in place)
#define HEMO_SUBSTEP_BINDING_IDS 4           // texel uint
#define HEMO_SUBSTEP_BINDING_SLOT_OF_ID 5    // texel uint
#define HEMO_SUBSTEP_BINDING_SPRINGS 6       // texel uvec4, two per Spring
#define HEMO_SUBSTEP_BINDING_FIRST 7         // texel uint
#define HEMO_SUBSTEP_BINDING_SPRINGS_OF 8    // texel uint
#define HEMO_SUBSTEP_BINDING_WALL_INFO 9     // texel vec4 by id (mass, anchored)
#define HEMO_SUBSTEP_BINDING_ACCEL 10        // storage: its own record (STEP writes it)
#define HEMO_SUBSTEP_BINDING_HELD 11         // texel vec4 (HEMO_SPRINGF_BINDING_HELD)
#define HEMO_SUBSTEP_BINDING_SPRINGS_RW 12   // storage: broken flags
#define HEMO_SUBSTEP_BINDING_COUNTERS 13
#define HEMO_SUBSTEP_BINDING_PARAMS 14       // uniform SphParams
#define HEMO_SUBSTEP_BINDING_DT 15           // uniform vec2: the time step's reduction
#define HEMO_SUBSTEP_BINDING_CLOCK 16        // uniform: the clock's two records
#define HEMO_SUBSTEP_BINDING_KINDS 17        // texel vec4: the live velocities (w: the slot's kind)
#define HEMO_SUBSTEP_BINDING_COUNT 18

// wall/point_shade.comp: per particle slot, vec2(largest strain of its unbroken springs,
// fraction of its springs broken) for the renderer; push: uint n, uint idCount.
#define HEMO_SHADE_BINDING_POSITIONS 0
#define HEMO_SHADE_BINDING_VELOCITIES 1
#define HEMO_SHADE_BINDING_IDS 2
#define HEMO_SHADE_BINDING_SLOT_OF_ID 3
#define HEMO_SHADE_BINDING_SPRINGS 4
#define HEMO_SHADE_BINDING_FIRST 5
#define HEMO_SHADE_BINDING_SPRINGS_OF 6
#define HEMO_SHADE_BINDING_PARAMS 7
#define HEMO_SHADE_BINDING_SHADE 8
#define HEMO_SHADE_BINDING_WSS 9          // HEMO_SPRINGF_BINDING_WSS (push mode 1)
#define HEMO_SHADE_BINDING_SHEAR_SUMS 10  // HEMO_SHEARACC_BINDING_SUMS (push modes 2, 3)
#define HEMO_SHADE_BINDING_STATE 11       // the fluid's state (rho, p, ...) per slot (push mode 4)
#define HEMO_SHADE_BINDING_COUNT 12

// The wall shear maps' accumulation (wall/shear_accumulate.comp), after each step, per point
// id: the step's wall shear stress (HEMO_SPRINGF_BINDING_WSS at the point's slot) times the
// step's dt added to (sum tau dt (Pa s), sum |tau| dt (Pa s)), and, by invocation 0, dt to the
// record after the last id's (x: the time summed, s).
#define HEMO_SHEARACC_BINDING_IDS_SLOT 0   // texel uint per id: its slot (slot of id)
#define HEMO_SHEARACC_BINDING_WSS 1        // texel vec4 per slot
#define HEMO_SHEARACC_BINDING_CLOCK 2      // uniform ClockRecord[2]
#define HEMO_SHEARACC_BINDING_SUMS 3       // storage vec4 per id, and one more
#define HEMO_SHEARACC_BINDING_COUNT 4

// A wall particle's normal follows the deformed wall: n = normalize((x_A - x) x (x_B - x)) for
// its frame points A and B (ids; HEMO_NO_FRAME keeps the normal it has).
#define HEMO_NO_FRAME 0xffffffffu

// Counters (uint[4]).
#define HEMO_WALL_COUNTER_BROKEN 0    // springs broken so far
#define HEMO_WALL_COUNTER_DETACHED 1  // wall particles whose springs are all broken (SPH mass set to
                                      // zero: no longer part of the fluid's boundary)

#endif
