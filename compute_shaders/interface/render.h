// The renderer's graphics shaders (render/shaders/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_RENDER_H
#define HEMO_INTERFACE_RENDER_H

// render/particles.vert: storage buffers of the particle store, read by the vertex shader.
#define HEMO_RENDER_BINDING_POSITIONS 0
#define HEMO_RENDER_BINDING_VELOCITIES 1
#define HEMO_RENDER_BINDING_WALL_SHADE 2  // vec2 per slot (wall/point_shade.comp); read only
                                          // when push show.w (the strain scale) is non-zero
#define HEMO_RENDER_BINDING_COUNT 3
// push (128 bytes): mat4 viewProj; vec4 right (w radius m); vec4 up (w speed scale m/s);
//                   uvec4 show (fluid, wall, boundary, float bits of the strain scale);
//                   vec4 cut (wall and boundary particles with dot(cut.xyz, x) > cut.w are
//                   hidden)

// render/surface.vert + .frag: vertex attributes from the marching-cubes vertex buffer
// (stride 32: vec4 position at 0, vec4 normal at 16).
#define HEMO_RENDER_SURFACE_STRIDE 32
// push (112 bytes): mat4 viewProj; vec4 eye; vec4 light; vec4 color

// render/springs.vert + .frag: the wall's springs as lines (two vertices per spring).
#define HEMO_RENDER_SPRINGS_BINDING_POSITIONS 0
#define HEMO_RENDER_SPRINGS_BINDING_SLOT_OF_ID 1
#define HEMO_RENDER_SPRINGS_BINDING_SPRINGS 2  // Spring records (interface/wall.h)
#define HEMO_RENDER_SPRINGS_BINDING_COUNT 3

// The wall's surface (render/shaders/wall_surface.vert): two sets of the same three-buffer
// layout. Set 0 is the springs' (positions, slot of id, springs); set 1:
#define HEMO_RENDER_WALL_BINDING_TRIANGLES 0  // uint[6] per triangle: ids a, b, c, then the
                                              // springs along (a, b), (b, c), (c, a)
                                              // (hemo/sim/wall_surface.hpp)
#define HEMO_RENDER_WALL_BINDING_NORMALS 1    // vec4 per slot: the wall's normal (xyz)
#define HEMO_RENDER_WALL_BINDING_SHADE 2      // vec2 per slot: (strain, broken fraction)
// push (96 bytes): mat4 viewProj; vec4 period (xyz m, w strain scale); uvec4 flags (x: draw
//                  broken springs)

#endif
