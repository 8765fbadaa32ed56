#include "hemo/sim/inflow.hpp"

#include <glm/geometric.hpp>

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
    require(!o.outlets.empty() && o.endCount() <= OpenEnds::kMaxEnds,
            "open ends: one inlet and 1 to " + std::to_string(OpenEnds::kMaxEnds - 1) + " outlets, got " + std::to_string(o.outlets.size()) + " outlets");
    for (std::size_t k = 0; k < o.endCount(); ++k) {
      const OpenEnd* e = &o.end(k);
      const std::string which = k == 0 ? "open ends: the inlet's " : "open ends: outlet " + std::to_string(k) + "'s ";
      for (int a = 0; a < 3; ++a) require(std::isfinite(e->origin[a]) && std::isfinite(e->axis[a]), which + "frame must be finite");
      require(std::abs(glm::length(glm::dvec3(e->axis)) - 1.0) < 1e-5, which + "axis must be a unit vector");
      require(std::isfinite(e->radius) && e->radius > 0.0f, which + "radius must be positive (m)");
      require(std::isfinite(e->length) && e->length > 0.0f, which + "buffer must have a positive length (m)");
      require(std::isfinite(e->reach) && e->reach >= e->radius, which + "reach must be at least its radius (m)");
      require(std::isfinite(e->pressurePa), which + "pressure must be finite (Pa)");
      require(e->pressure || e->pressurePa == 0.0f, which + "pressure applies only to a pressure end");
      for (std::size_t j = 0; j < k; ++j) {
        const OpenEnd& f = o.end(j);
        require(glm::length(glm::dvec3(e->origin - f.origin)) > double(e->length) + f.length,
                "open ends: the buffers must leave a lumen between them");
      }
      if (k > 0) {
        require(!o.inlet.pressure || e->pressure, "open ends: a pressure inlet needs pressure outlets");
        require(o.outlets.size() == 1 || e->pressure, "open ends: several outlets must be pressure outlets (a flow split would need its ratios)");
      }
    }
    require(std::isfinite(o.pendingMargin) && o.pendingMargin > 0.0f && o.pendingMargin < o.inlet.length,
            "open ends: the refill margin must be positive and shorter than the inlet buffer");
    require(!holdPressure, "open ends: the zone cannot hold the lumen pressure (its mass supply is for closed loops)");
    for (int a = 0; a < 3; ++a) require(std::isfinite(o.parking[a]), "open ends: the parking point must be finite");
    bool anyPressure = false;
    for (std::size_t k = 0; k < o.endCount(); ++k) anyPressure = anyPressure || o.end(k).pressure;
    require(!anyPressure || (std::isfinite(o.slab) && o.slab > 0.0f), "open ends: a pressure end needs a slab of positive width");
    require(std::isfinite(o.parkBeyond) && o.parkBeyond >= 0.0f, "open ends: the escape distance must be zero or positive (m)");
    require(!(o.parkBeyond > 0.0f) || (o.escape.cell > 0.0f && o.escape.words() > 0), "open ends: an escape distance needs its grid");
  }
}

EscapeGrid EscapeGrid::over(glm::vec3 lo, glm::vec3 hi, float spacing) {
  EscapeGrid g;
  g.origin = lo;
  g.cell = 2.0f * spacing;
  for (int a = 0; a < 3; ++a) g.dims[a] = std::max(1u, std::uint32_t(std::ceil((hi[a] - lo[a]) / g.cell)));
  return g;
}

glm::vec3 EscapeGrid::centre(std::size_t k) const {
  const auto x = std::uint32_t(k % dims.x), y = std::uint32_t(k / dims.x % dims.y), z = std::uint32_t(k / (std::size_t(dims.x) * dims.y));
  return origin + cell * (glm::vec3(float(x), float(y), float(z)) + 0.5f);
}

glm::dvec2 OpenEnd::local(glm::dvec3 p) const {
  const glm::dvec3 d = p - glm::dvec3(origin), a(axis);
  const double s = glm::dot(d, a);
  const glm::dvec3 across = d - s * a;
  return {s, glm::dot(across, across)};
}

bool OpenEnd::inBuffer(glm::dvec3 p) const {
  const glm::dvec2 l = local(p);
  return l.x >= 0.0 && l.x < double(length) && l.y < double(reach) * reach;
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
  if (in.open) {
    const OpenEnds& o = *in.open;
    p.open = 1u;
    p.endCount = std::uint32_t(o.endCount());
    for (std::size_t k = 0; k < o.endCount(); ++k) {
      const OpenEnd* e = &o.end(k);
      InflowParams::End& g = p.ends[k];
      const glm::vec3 shift = e->shift();
      for (int a = 0; a < 3; ++a) g.origin[a] = e->origin[a], g.axis[a] = e->axis[a], g.shift[a] = shift[a];
      g.origin[3] = e->length;
      g.axis[3] = e->radius;
      g.shift[3] = e->reach;
      g.drive[0] = (o.inlet.radius / e->radius) * (o.inlet.radius / e->radius);
      g.drive[1] = e->pressurePa;
      g.drive[2] = e->pressure ? 1.0f : 0.0f;
    }
    for (int a = 0; a < 3; ++a) {
      p.parking[a] = o.parking[a];
      p.boxMin[a] = o.boxMin[a];
      p.boxMax[a] = o.boxMax[a];
    }
    p.pendingMargin = o.pendingMargin;
    p.slab[0] = o.slab;
    p.slab[1] = o.characteristic;
    if (o.parkBeyond > 0.0f) {
      for (int a = 0; a < 3; ++a) p.escapeOrigin[a] = o.escape.origin[a], p.escapeDims[a] = o.escape.dims[a];
      p.escapeOrigin[3] = 1.0f / o.escape.cell;
      p.escapeDims[3] = 1u;
    }
  }
  return p;
}

InflowParams disabledInflowParams() { return InflowParams{}; }

}  // namespace hemo::sim
