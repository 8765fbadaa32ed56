#pragma once
// Static, small-displacement response of a wall's spring network to lumen pressure: the
// rupture pressure of any built vessel, not only of the shapes with a closed-form estimate
// (hoopRupturePressure for a tube, sacRupturePressure for a sac). The springs are linearised
// about the built (rest) state: a displacement u moves spring s's tension by
// k_s d_s . (u_b - u_a) (d_s its unit direction from a to b), so the wall's equilibrium under
// loads f is K u = f with K = sum_s k_s d_s d_s^T assembled over each spring's two ends.
// Anchored points do not move. The pressure acts on the lumen's surface through the inner
// layer's points: each carries P times its share of the lumen's area, along the lumen's
// outward normal. Since the response is linear, the first spring reaches its maximum force at
// P* = min_s f_max,s / t_s over the springs whose tension t_s (per pascal) is positive.
#include "hemo/scene/aneurysm.hpp"
#include "hemo/sim/wall.hpp"

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::scene {

struct StaticResponse {
  std::vector<double> tension;        // N per Pa of lumen pressure, per spring
  double rupturePressure = 0.0;       // Pa: min f_max / tension over stretched springs
  std::uint32_t firstSpring = 0;      // the spring that reaches its maximum force first
  std::uint32_t iterations = 0;       // conjugate-gradient iterations
  double residual = 0.0;              // |K u - f| / |f| at the end
};

// Solves K u = loads (N per Pa, per wall point; positions xyz in m, the first
// network.points.size() entries are the wall) by conjugate gradients; `period` (m, 0: none)
// is the periodic length along x for spring directions. The network's rigid motions carry
// no load (the lumen's pressure loads are self-balanced) and are removed by a tiny diagonal
// shift. Throws std::invalid_argument if the solve does not converge or no spring stretches.
StaticResponse staticResponse(const sim::SpringNetwork& network, const std::vector<glm::vec4>& positions, double period,
                              const std::vector<glm::dvec3>& loads);

// The lumen pressure loads (N per Pa) of a surface of revolution built from `spec` (a tube or
// a fusiform aneurysm): on each inner-layer wall point, its share of the lumen's surface along
// the lumen's outward normal (the point's built inward normal `inward`, reversed). A ring's
// share is the lumen's area between the midpoints to the neighbouring rings, divided evenly
// among its points. Throws std::invalid_argument for a sac or a bifurcation.
std::vector<glm::dvec3> lumenLoads(const AneurysmSpec& spec, const std::vector<glm::vec4>& positions,
                                   const std::vector<glm::vec4>& inward, std::uint32_t wall);

}  // namespace hemo::scene
