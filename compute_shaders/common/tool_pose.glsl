// A tool's pose at a time (interface/tool.h): the including shader declares the tools buffer
// as the uniform array `toolData` (HEMO_TOOL_DATA_VEC4S vec4: HEMO_TOOL_MAX_TOOLS records of
// HEMO_TOOL_RECORD_VEC4S vec4, then the keyframes, HEMO_TOOL_KEY_VEC4S vec4 each).
//   layout(std140, binding = ...) uniform Tools { vec4 toolData[HEMO_TOOL_DATA_VEC4S]; };
// A uniform block: every lane of a dispatch reads the same keys, which devices read once per
// SIMD group (from a storage buffer llvmpipe loads them lane by lane).

struct HemoToolPose {
  vec3 position;     // m: the tip
  vec4 orientation;  // unit quaternion (x, y, z, w)
  vec3 axis;         // the shaft's direction: orientation applied to (0, 0, 1)
  vec3 side;         // the jaws' direction: orientation applied to (1, 0, 0)
  float opening;     // m: a grasper's jaw opening
  float speed;       // m/s: a bound on the speed of the tool's surface between the two keys
  vec3 velocity;     // m/s: of the tip
  vec3 spin;         // rad/s: the angular velocity (the material point at arm r moves at velocity + spin x r)
  bool cutting;      // a blade: the last key at or before t says it cuts
};

vec4 hemo_tool_shape(uint tool) { return toolData[HEMO_TOOL_RECORD_VEC4S * tool]; }
vec4 hemo_tool_contact(uint tool) { return toolData[HEMO_TOOL_RECORD_VEC4S * tool + 1u]; }
vec4 hemo_tool_grip(uint tool) { return toolData[HEMO_TOOL_RECORD_VEC4S * tool + 2u]; }
vec4 hemo_tool_key(uint key, uint part) {
  return toolData[HEMO_TOOL_RECORD_VEC4S * HEMO_TOOL_MAX_TOOLS + HEMO_TOOL_KEY_VEC4S * key + part];
}

vec3 hemo_quat_rotate(vec4 q, vec3 v) {
  const vec3 t = 2.0 * cross(q.xyz, v);
  return v + q.w * t + cross(q.xyz, t);
}

HemoToolPose hemo_tool_pose(uint tool, float t) {
  const vec4 shape = hemo_tool_shape(tool);
  const vec4 contact = hemo_tool_contact(tool);
  const uint first = uint(contact.y);
  const uint count = uint(contact.z);
  // the last key at or before t (the first when t precedes them all): binary search
  uint lo = 0u, hi = count;  // keys [lo, hi) hold the answer's successor
  while (hi - lo > 1u) {
    const uint mid = (lo + hi) / 2u;
    if (hemo_tool_key(first + mid, 0u).x <= t) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const uint a = lo;
  const uint b = min(a + 1u, count - 1u);
  const vec4 ka = hemo_tool_key(first + a, 0u), kb = hemo_tool_key(first + b, 0u);
  const vec4 qa = hemo_tool_key(first + a, 1u);
  vec4 qb = hemo_tool_key(first + b, 1u);
  if (dot(qa, qb) < 0.0) {
    qb = -qb;
  }
  const float span = kb.x - ka.x;
  const bool moving = b != a && t >= ka.x && t < kb.x && span > 0.0;
  const float s = moving ? clamp((t - ka.x) / span, 0.0, 1.0) : 0.0;
  HemoToolPose p;
  p.position = mix(ka.yzw, kb.yzw, s);
  const vec4 m = mix(qa, qb, s);
  p.orientation = normalize(m);
  p.velocity = vec3(0.0);
  p.spin = vec3(0.0);
  if (moving) {
    p.velocity = (kb.yzw - ka.yzw) / span;
    // q = m / |m|: dq/dt = (dm - q (q . dm)) / |m|, dm = (qb - qa) / span; spin = 2 (dq/dt q*)
    const vec4 dm = (qb - qa) / span;
    const vec4 q = p.orientation;
    const vec4 dq = (dm - q * dot(q, dm)) / length(m);
    p.spin = 2.0 * (q.w * dq.xyz - dq.w * q.xyz + cross(q.xyz, dq.xyz));
  }
  p.axis = hemo_quat_rotate(p.orientation, vec3(0.0, 0.0, 1.0));
  p.side = hemo_quat_rotate(p.orientation, vec3(1.0, 0.0, 0.0));
  const float oa = hemo_tool_key(first + a, 2u).x, ob = hemo_tool_key(first + b, 2u).x;
  p.opening = mix(oa, ob, s);
  // the angle between the keys' orientations; normalised linear interpolation turns at most
  // 1.25 times its mean rate for the key-to-key turns of under 90 degrees the scene allows
  const float turn = 2.0 * acos(clamp(abs(dot(qa, qb)), 0.0, 1.0));
  // (a grasper's jaws reach half the opening, a radius and half their width beyond the axis,
  // and open or close at half the opening's rate each)
  const float reach = shape.y + shape.z +
                      (uint(shape.x) == HEMO_TOOL_KIND_GRASPER ? 0.5 * max(oa, ob) + shape.y + contact.w : 0.0);
  p.speed = moving ? (length(kb.yzw - ka.yzw) + 1.25 * turn * reach + 0.5 * abs(ob - oa)) / span : 0.0;
  p.cutting = uint(shape.x) == HEMO_TOOL_KIND_BLADE && t >= ka.x && hemo_tool_key(first + a, 2u).y != 0.0;
  return p;
}
