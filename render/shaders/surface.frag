#version 450
// Blinn-Phong with a headlight-like key light; lit on both sides (a cut-open surface shows
// its inside).
layout(location = 0) in vec3 worldPos;
layout(location = 1) in vec3 worldNormal;
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 eye;
  vec4 light;
  vec4 color;
} pc;
layout(location = 0) out vec4 outColor;

void main() {
  const vec3 v = normalize(pc.eye.xyz - worldPos);
  vec3 n = length(worldNormal) > 0.0 ? normalize(worldNormal) : v;
  if (dot(n, v) < 0.0) {
    n = -n;
  }
  const vec3 l = normalize(pc.light.xyz);
  const float diffuse = max(dot(n, l), 0.0);
  const float specular = pow(max(dot(n, normalize(l + v)), 0.0), 48.0);
  outColor = vec4(pc.color.rgb * (0.25 + 0.75 * diffuse) + vec3(0.35 * specular), 1.0);
}
