#version 450
// A disc shaded as a small sphere under a light fixed to the camera.
layout(location = 0) in vec2 corner;
layout(location = 1) in vec3 color;
layout(location = 0) out vec4 outColor;

void main() {
  const float r2 = dot(corner, corner);
  if (r2 > 1.0) {
    discard;
  }
  const vec3 n = vec3(corner, sqrt(1.0 - r2));
  const float diffuse = max(dot(n, normalize(vec3(-0.35, 0.45, 0.82))), 0.0);
  outColor = vec4(color * (0.35 + 0.65 * diffuse), 1.0);
}
