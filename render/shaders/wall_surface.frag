#version 450
// The wall's surface: tissue coloured, reddening with the strain of its points' springs,
// lit on both sides (Blinn-Phong from a light above the camera, with a soft rim), and as opaque as asked (blended over what
// is behind it). The cutaway removes the half between the camera and the plane through the
// target.
layout(location = 0) in vec3 worldPos;
layout(location = 1) in vec3 worldNormal;
layout(location = 2) in float strain;
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 period;  // xyz: period on periodic axes (0 elsewhere); w: strain at the red end
  vec4 origin;  // xyz: the domain's low corner on periodic axes; w: opacity
  vec4 eye;     // xyz: the camera; w: 1 with the cutaway
  vec4 cut;
} pc;
layout(location = 0) out vec4 outColor;

void main() {
  if (pc.eye.w != 0.0 && dot(pc.cut.xyz, worldPos) > pc.cut.w) {
    discard;
  }
  // On periodic axes only the domain's box (a seam triangle is drawn twice, a period apart).
  const vec3 outside = vec3(greaterThan(pc.period.xyz, vec3(0.0))) *
                       (vec3(lessThan(worldPos, pc.origin.xyz)) + vec3(greaterThanEqual(worldPos, pc.origin.xyz + pc.period.xyz)));
  if (any(greaterThan(outside, vec3(0.0)))) {
    discard;
  }
  const vec3 v = normalize(pc.eye.xyz - worldPos);
  vec3 n = length(worldNormal) > 0.0 ? normalize(worldNormal) : v;
  if (dot(n, v) < 0.0) {
    n = -n;
  }
  const vec3 l = normalize(v + vec3(0.0, 0.0, 0.6));
  const float diffuse = max(dot(n, l), 0.0);
  const float specular = pow(max(dot(n, normalize(l + v)), 0.0), 24.0);
  const float rim = pow(1.0 - max(dot(n, v), 0.0), 3.0);
  const vec3 tissue = mix(vec3(0.86, 0.56, 0.52), vec3(0.80, 0.12, 0.10), clamp(strain / pc.period.w, 0.0, 1.0));
  const vec3 lit = tissue * (0.30 + 0.70 * diffuse) + vec3(0.25 * specular) + 0.15 * rim * vec3(1.0, 0.85, 0.8);
  outColor = vec4(lit, pc.origin.w);
}
