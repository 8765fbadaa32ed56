// The driven inflow zone of a periodic vessel (hemo/sim/inflow.hpp has the model).
struct InflowParams {
  float zoneStart;  // m along x
  float zoneEnd;
  float centreY;    // m, the tube's axis
  float centreZ;
  float radius;     // m
  float meanSpeed;  // U (m/s)
  float period;     // s (0: constant)
  float ramp;       // s
  uint profile;     // 0 parabolic, 1 plug
  uint samples;     // waveform samples over one period
  uint enabled;
  uint holdPressure;  // the zone supplies mass, relaxing towards m rho0 / rho within [baseMass, maxMass]
  float restDensity;  // rho0 (kg/m^3)
  float maxMass;      // kg, cap of a particle's mass
  float baseMass;     // kg, the initial particle mass (the floor)
  float reserved1;
  float waveform[64];
};
