// The SPH parameter block (see interface/sph.h for units), bound read-only.
struct SphParams {
  vec4 gravity;
  float h;
  float supportRadius;
  float listRadius;
  float kernelNorm;
  float rho0;
  float taitB;
  float mu;
  float etaSq;
  float psi;
  float repulsionCutoff;
  float wallSpacing;
  float cflAcoustic;
  float cflForce;
  float dtViscous;
  float dtMax;
  float c0;
  uint clampNegativePressure;
  uint neighbourCapacity;
  float dampingRate;
  float dampingUntil;
  uint spsEnabled;
  float spsSmagorinsky;
  float spsBlinn;
  float pad0;
};
