#include "hemo/sim/inflow.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemo::sim {

double Inflow::meanSpeedAt(double t) const {
  double w = 1.0;
  if (period > 0.0f && !waveform.empty()) {
    const double n = double(waveform.size());
    const double phase = (t / period - std::floor(t / period)) * n;
    const auto k = std::min(std::size_t(phase), waveform.size() - 1);
    const double frac = phase - double(k);
    w = waveform[k] + (waveform[(k + 1) % waveform.size()] - double(waveform[k])) * frac;
  }
  const double r = ramp > 0.0f ? std::clamp(t / ramp, 0.0, 1.0) : 1.0;
  return double(meanSpeed) * w * r;
}

double Inflow::axialVelocity(double t, double r) const {
  if (profile == Profile::Plug) return meanSpeedAt(t);
  const double s = r / radius;
  return meanSpeedAt(t) * 2.0 * std::max(1.0 - s * s, 0.0);
}

void Inflow::validate() const {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("inflow: " + what);
  };
  require(std::isfinite(zoneStart) && std::isfinite(zoneEnd) && zoneEnd > zoneStart, "the zone must have a positive length");
  require(std::isfinite(radius) && radius > 0.0f, "the radius must be positive (m)");
  require(std::isfinite(centreY) && std::isfinite(centreZ), "the axis must be finite");
  require(std::isfinite(meanSpeed), "the mean speed must be finite (m/s)");
  require(std::isfinite(period) && period >= 0.0f, "the waveform period must be >= 0 (s)");
  require(std::isfinite(ramp) && ramp >= 0.0f, "the ramp must be >= 0 (s)");
  require(waveform.size() <= kMaxSamples, "at most " + std::to_string(kMaxSamples) + " waveform samples");
  require(waveform.empty() || (period > 0.0f && waveform.size() >= 2), "a waveform needs a positive period and at least 2 samples");
  for (float w : waveform) require(std::isfinite(w), "waveform samples must be finite");
  require(std::isfinite(maxMassRatio) && maxMassRatio >= 1.0f, "the mass cap must be at least 1 (x the initial mass)");
  if (open) {
    const OpenEnds& o = *open;
    require(std::isfinite(o.startX) && std::isfinite(o.endX) && o.endX > o.startX, "open ends: the tube's end must lie past its start");
    require(zoneStart == o.startX, "open ends: the inlet buffer must start at the tube's start");
    require(std::isfinite(o.outletLength) && o.outletLength > 0.0f && o.endX - o.outletLength > zoneEnd,
            "open ends: the outlet buffer must have a positive length and leave a lumen after the inlet buffer");
    require(std::isfinite(o.pendingMargin) && o.pendingMargin > 0.0f && o.pendingMargin < zoneEnd - zoneStart,
            "open ends: the refill margin must be positive and shorter than the inlet buffer");
    require(!holdPressure, "open ends: the zone cannot hold the lumen pressure (its mass supply is for closed loops)");
    for (int a = 0; a < 3; ++a) require(std::isfinite(o.parking[a]), "open ends: the parking point must be finite");
    require(!o.pressureInlet || o.pressureOutlet, "open ends: a pressure inlet needs a pressure outlet");
    require(std::isfinite(o.inletPressure) && std::isfinite(o.outletPressure), "open ends: the pressures must be finite (Pa)");
    require(!(o.pressureInlet || o.pressureOutlet) || (std::isfinite(o.slab) && o.slab > 0.0f),
            "open ends: a pressure end needs a slab of positive width");
  }
}

InflowParams makeInflowParams(const Inflow& in, float restDensity, float particleMass) {
  in.validate();
  if (!(restDensity > 0.0f) || !(particleMass > 0.0f)) throw std::invalid_argument("inflow: rest density and particle mass must be positive");
  InflowParams p{};
  p.zoneStart = in.zoneStart;
  p.zoneEnd = in.zoneEnd;
  p.centreY = in.centreY;
  p.centreZ = in.centreZ;
  p.radius = in.radius;
  p.meanSpeed = in.meanSpeed;
  p.period = in.waveform.empty() ? 0.0f : in.period;
  p.ramp = in.ramp;
  p.profile = in.profile == Inflow::Profile::Plug ? 1u : 0u;
  p.samples = static_cast<std::uint32_t>(in.waveform.size());
  p.enabled = 1u;
  p.holdPressure = in.holdPressure ? 1u : 0u;
  p.restDensity = restDensity;
  p.maxMass = in.maxMassRatio * particleMass;
  p.baseMass = particleMass;
  std::copy(in.waveform.begin(), in.waveform.end(), p.waveform);
  p.inletPlane = in.zoneEnd;
  p.outletPlane = 3.0e38f;
  p.startX = -3.0e38f;
  p.endX = 3.0e38f;
  if (in.open) {
    p.open = 1u;
    p.outletPlane = in.open->endX - in.open->outletLength;
    p.startX = in.open->startX;
    p.endX = in.open->endX;
    p.parking[0] = in.open->parking.x;
    p.parking[1] = in.open->parking.y;
    p.parking[2] = in.open->parking.z;
    p.parking[3] = in.zoneEnd - in.zoneStart;
    p.pendingMargin = in.open->pendingMargin;
    p.inletPressure = in.open->pressureInlet ? 1u : 0u;
    p.outletPressure = in.open->pressureOutlet ? 1u : 0u;
    p.pressures[0] = in.open->inletPressure;
    p.pressures[1] = in.open->outletPressure;
    p.pressures[2] = in.open->slab;
    p.pressures[3] = in.open->characteristic;
    p.box[0] = in.open->boxMin.x;
    p.box[1] = in.open->boxMin.y;
    p.box[2] = in.open->boxMax.x;
    p.box[3] = in.open->boxMax.y;
  }
  return p;
}

InflowParams disabledInflowParams() { return InflowParams{}; }

}  // namespace hemo::sim
