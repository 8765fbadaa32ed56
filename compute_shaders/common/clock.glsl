// One record of the solver's double-buffered clock (interface/sph.h): a step reads
// clocks[clockIn]; only the integrator writes, into clocks[1 - clockIn].
struct ClockRecord {
  float time;          // s
  float compensation;  // Kahan compensation of the time sum
  float lastDt;        // s
  uint steps;
};
