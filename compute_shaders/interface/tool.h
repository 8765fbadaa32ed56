// Surgical tools (compute_shaders/tool/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_TOOL_H
#define HEMO_INTERFACE_TOOL_H

// A tool is a rigid body that the scene (keyframes) or the user moves. Its shape in its own
// frame: a capsule, the segment from the origin (the tip) to length * (0, 0, 1) grown by
// radius (length 0: a sphere). Its pose at time t: position and orientation (a unit
// quaternion) interpolated between the two keyframes around t (linear, and normalised linear
// for the quaternion), held before the first and after the last.
#define HEMO_TOOL_MAX_TOOLS 8
#define HEMO_TOOL_MAX_KEYS 41  // per tool
#define HEMO_TOOL_KIND_PROBE 0
#define HEMO_TOOL_KIND_BLADE 1  // a capsule whose segment (the edge) cuts while its keys say so
// Two jaws, rounded plates: the points within radius of the rectangles from the tip
// +- (opening / 2 + radius) along the tool's x axis, spanned by its z axis (length) and its y
// axis (the jaw's width): the gap between their faces is the keyed jaw opening.
#define HEMO_TOOL_KIND_GRASPER 2

// The tools buffer, read as a uniform block of HEMO_TOOL_DATA_VEC4S vec4 (16 KiB, the least
// maxUniformBufferRange Vulkan allows): every invocation evaluates the poses it needs from it
// (a few uniform reads), so no pass of its own computes them.
//   [3k], [3k + 1], [3k + 2] for tool k < HEMO_TOOL_MAX_TOOLS:
//           vec4 shape (kind, radius m, length m, contact distance D m)
//           vec4 contact (Psi m/s^2, first key, key count, a grasper's jaw half-width m)
//           (first key and count as floats)
//           vec4 grip (a grasper's grip stiffness k_g N/m (0: it does not grip), the wall's
//           time-step factor C, 0, 0)
//   [3 HEMO_TOOL_MAX_TOOLS + 3j], [... + 1], [... + 2] for key j:
//           vec4 (t s, position xyz m), vec4 orientation (x, y, z, w),
//           vec4 (jaw opening m, cutting 0/1, 0, 0): a blade cuts from a key with cutting 1 to
//           the next key
#define HEMO_TOOL_RECORD_VEC4S 3
#define HEMO_TOOL_KEY_VEC4S 3
#define HEMO_TOOL_DATA_VEC4S 1024
// The contact force (docs/physics.md, "Tools"): a particle whose distance x to the tool's
// surface is below D (inside the tool: x <= 0) is pushed along the surface normal with the
// acceleration Psi (1 - q) / sqrt(q), q = max(x / 2h, 1e-3): the normal part of the boundary
// repulsion, on an exact surface (so no tangential weight). The tool takes the opposite force.
//
// Grasping: a free wall point within D of both jaws of a grasper that grips (k_g > 0) is held
// by it. Its grip record (by wall id) then keeps where, in the jaws' plane, it was first
// squeezed: (a, b), its coordinates along the tool's axis and across the jaws (along
// axis x side), and the tool. While it stays squeezed, a critically damped spring pulls it
// to that anchor within the jaws' plane, a = P (w^2 (anchor - x) + 2 w (v_anchor - v)),
// w^2 = k_g / m, P the projection onto the plane, v_anchor the velocity of the tool's
// material point at x; across the plane only the jaws' push acts. Out of the squeeze, the
// record is cleared (the jaws let go). The tool takes the opposite force, and the gripped
// point's own limit C sqrt(m / k_g) bounds the time step. Record: vec4 (a m, b m, 0, tool + 1;
// 0: not gripped).

// tool/contact.comp: one invocation per slot of the moving ones (fluid and wall particles;
// anchored wall points are left out). Adds the tools' accelerations to accel (and, with the
// wall's substeps, to its held record), writes the force condition's time-step limit
// C_f sqrt(h / |a|) of the particles it touched into the time step's reduction (pass 2,
// common/dt_fold.glsl), and invocation 0 the tools' own limit (a tool surface moves at most
// D / 4 per step). Each SIMD group stores its sums of the force and torque the tools take,
// per tool k: vec4 (F, 0) and vec4 (torque about the tool's position, 0) at
// partials[(k * stride + group * gl_NumSubgroups + subgroup) * 2 + {0, 1}], and invocation 0
// the number of partials per tool in partialCount. No barrier inside the workgroup (on CPU
// devices a barrier costs more than the pass's arithmetic). sph/dt_reduce.comp, the
// single-workgroup pass after it, sums the partials in a fixed order into the step's log.
#define HEMO_TOOLC_BINDING_POSITIONS 0   // texel vec4 (x, SPH mass)
#define HEMO_TOOLC_BINDING_VELOCITIES 1  // texel vec4 (v, kind)
#define HEMO_TOOLC_BINDING_IDS 2         // texel uint
#define HEMO_TOOLC_BINDING_WALL_INFO 3   // texel vec4 by id (mass, anchored): interface/wall.h
#define HEMO_TOOLC_BINDING_PARAMS 4      // SphParams (uniform)
#define HEMO_TOOLC_BINDING_TOOLS 5       // the tools buffer (uniform)
#define HEMO_TOOLC_BINDING_CLOCK 6       // the solver's clock records (common/clock.glsl)
#define HEMO_TOOLC_BINDING_ACCEL 7       // vec4 per slot, read and written
#define HEMO_TOOLC_BINDING_HELD 8        // vec4 per slot (the wall's held force; written with substeps only)
#define HEMO_TOOLC_BINDING_PARTIALS 9
#define HEMO_TOOLC_BINDING_PARTIAL_COUNT 10  // uint
#define HEMO_TOOLC_BINDING_DT_PARTIALS 11
#define HEMO_TOOLC_BINDING_DT_COUNTS 12
#define HEMO_TOOLC_BINDING_GRIPS 13       // vec4 per wall point id (the grip record), read and written
#define HEMO_TOOLC_BINDING_COUNT 14

// tool/cut.comp (scenes with a blade and a vessel): one invocation per spring; an unbroken
// spring whose segment (its ends' positions, minimum image) crosses the surface a cutting
// blade's edge swept since the last step (the two triangles between the edge at t - lastDt and
// at t) breaks for good, counted with the wall's broken springs. Before the wall's spring pass,
// so a cut spring pulls no more in that force evaluation.
#define HEMO_TOOLCUT_BINDING_POSITIONS 0   // texel vec4
#define HEMO_TOOLCUT_BINDING_SLOT_OF_ID 1  // texel uint
#define HEMO_TOOLCUT_BINDING_SPRINGS 2     // the wall's Spring records (interface/wall.h), broken flags written
#define HEMO_TOOLCUT_BINDING_COUNTERS 3    // the wall's counters (interface/wall.h)
#define HEMO_TOOLCUT_BINDING_PARAMS 4      // SphParams (uniform): the periods
#define HEMO_TOOLCUT_BINDING_TOOLS 5       // the tools buffer (uniform)
#define HEMO_TOOLCUT_BINDING_CLOCK 6
#define HEMO_TOOLCUT_BINDING_COUNT 7

// A log record (std430, 64 bytes), mirrored by hemo::sim::ToolSample:
//   vec4 force     (F on the tool, N; w: the time t of the force evaluation, s)
//   vec4 torque    (about the tool's position, N m; w: 0)
//   vec4 position  (m; w: the tool's surface speed bound, m/s)
//   vec4 orientation (x, y, z, w)
#define HEMO_TOOL_LOG_VEC4S 4

#endif
