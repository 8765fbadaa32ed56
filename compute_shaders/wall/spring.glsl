// The spring record of interface/wall.h.
struct Spring {
  uint a;
  uint b;
  float restLength;
  float stiffness;
  float damping;
  float maxForce;
  uint broken;
  uint pad;
};

// The force of one spring, computed the same way from either end so the two ends get exactly
// opposite forces: returns f d for end a (f > 0 is tension), with the quantities of
// interface/wall.h; delta = x_b - x_a (by the minimum image on periodic axes). A spring of
// zero length has no direction and no force.
vec3 hemo_spring_force_on_a(vec3 delta, vec3 va, vec3 vb, float restLength, float stiffness, float damping,
                            out float tension) {
  const float len = length(delta);
  if (len <= 0.0) {
    tension = 0.0;
    return vec3(0.0);
  }
  const vec3 d = delta / len;
  tension = stiffness * (len - restLength) + damping * dot(vb - va, d);
  return tension * d;
}
