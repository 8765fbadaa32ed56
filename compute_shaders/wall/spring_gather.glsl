// The springs of one wall particle, gathered through the CSR adjacency by particle id (no
// float atomics), with rupture: shared by wall/spring_forces.comp and wall/substep.comp. The
// including shader declares the texel buffers springsT (two uvec4 per Spring), springsOfT,
// firstT, slotOfIdT, positions(k) and velocities(k) (macros reading the current state), the
// storage buffers springsRW (the broken flags) and counters (interface/wall.h), and includes
// wall/spring.glsl, common/sph_params.glsl.

// Spring record k of interface/wall.h, read as its two uvec4 texels.
Spring hemo_spring(uint k) {
  const uvec4 t0 = texelFetch(springsT, int(2u * k));
  const uvec4 t1 = texelFetch(springsT, int(2u * k + 1u));
  return Spring(t0.x, t0.y, uintBitsToFloat(t0.z), uintBitsToFloat(t0.w), uintBitsToFloat(t1.x),
                uintBitsToFloat(t1.y), t1.z, t1.w);
}

// The sum of the forces (N) of the unbroken springs of the particle `id` in `slot`, at the
// current positions and velocities. A spring whose tension exceeds its maximum force breaks
// now, for good (the seed's rupture rule): both ends compute this tension from the same inputs
// in the same order, so they agree; end a alone writes the flag and counts it, and the other
// end may read the record before or after that write and skips the spring either way. Out: the
// summed stiffness and the count of the springs still intact, and the springs it has at all.
vec3 hemo_spring_gather(uint slot, uint id, out float stiffness, out uint intact, out uint total) {
  const HemoPairParams pp = hemo_pair_params();
  vec3 force = vec3(0.0);
  stiffness = 0.0;
  intact = 0u;
  const vec3 xSelf = positions(slot).xyz;
  const vec3 vSelf = velocities(slot).xyz;
  const uint begin = texelFetch(firstT, int(id)).x;
  const uint end = texelFetch(firstT, int(id + 1u)).x;
  total = end - begin;
  for (uint e = begin; e < end; ++e) {
    const uint springIndex = texelFetch(springsOfT, int(e)).x;
    const Spring s = hemo_spring(springIndex);
    if (s.broken != 0u) {
      continue;
    }
    // Only the other end is gathered; the force is computed from (a, b) in the spring's own
    // order either way, so both ends get exactly opposite forces.
    const bool selfIsA = id == s.a;
    const uint other = texelFetch(slotOfIdT, int(selfIsA ? s.b : s.a)).x;
    const vec3 xOther = positions(other).xyz;
    const vec3 vOther = velocities(other).xyz;
    float tension;
    const vec3 delta = hemo_min_image(selfIsA ? xOther - xSelf : xSelf - xOther, pp);
    const vec3 fa = hemo_spring_force_on_a(delta, selfIsA ? vSelf : vOther, selfIsA ? vOther : vSelf, s.restLength,
                                           s.stiffness, s.damping, tension);
    if (tension > s.maxForce) {
      if (selfIsA) {
        springsRW[springIndex].broken = 1u;
        atomicAdd(counters[HEMO_WALL_COUNTER_BROKEN], 1u);
      }
      continue;
    }
    force += selfIsA ? fa : -fa;
    stiffness += s.stiffness;
    ++intact;
  }
  return force;
}
