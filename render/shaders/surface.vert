#version 450
// The marching-cubes surface, straight from the extractor's vertex buffer (position, outward
// normal per vertex), drawn with the indirect arguments the extraction wrote.
#extension GL_GOOGLE_include_directive : require
#include "interface/render.h"

layout(location = 0) in vec4 position;
layout(location = 1) in vec4 normal;
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 eye;    // xyz: camera position (m)
  vec4 light;  // xyz: direction towards the light (unit)
  vec4 color;  // rgb: base colour
} pc;

layout(location = 0) out vec3 worldPos;
layout(location = 1) out vec3 worldNormal;

void main() {
  worldPos = position.xyz;
  worldNormal = normal.xyz;
  gl_Position = pc.viewProj * vec4(position.xyz, 1.0);
}
