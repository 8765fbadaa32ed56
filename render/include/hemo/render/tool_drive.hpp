#pragma once
// Driving a tool by hand (hemo-view): the cursor moves the tool's tip on the plane through the
// tip that faces the camera, a key or the wheel moves it in depth, and each frame the tool's
// keyframes become a short path from its pose now to where the hand wants it
// (sim::ToolContact::setKeys between batches). The path's speed is capped: the tool's motion
// bounds the time step and pushes the blood, so a mouse flick must not become a tool at
// hundreds of m/s.
#include "hemo/render/renderer.hpp"
#include "hemo/sim/tools.hpp"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <vector>

namespace hemo::render {

// The point under a window pixel (x right, y down, from the top-left corner of a view of
// `viewSize` pixels) on the plane through `through` facing the camera (its normal is the view
// direction, eye to target).
glm::vec3 cursorOnPlane(const Camera& camera, glm::vec2 pixel, glm::vec2 viewSize, glm::vec3 through);
// The window pixel where a point appears (the inverse of cursorOnPlane on that plane).
glm::vec2 pixelOf(const Camera& camera, glm::vec2 viewSize, glm::vec3 point);

// Where the hand wants the tool.
struct HandTarget {
  glm::vec3 position{0.0f};  // m: the tip
  float jawOpening = 0.0f;   // m: a grasper's gap (ignored for other tools)
  bool cutting = false;      // a blade cuts on its way (ignored for other tools)
};

// The tool's keyframes for the next `lead` seconds of simulated time from `now`: its pose at
// `now` (as its current keys give it), then at now + lead the target, or as far towards it
// as `maxSpeed` (m/s, for the tip and for the jaws) allows; after that it holds. The
// orientation stays. Valid keys (sim::ToolSpec::validate) for lead > 0; one key (hold) for
// lead <= 0.
std::vector<sim::ToolKey> handKeys(const sim::ToolSpec& tool, double now, double lead, const HandTarget& target,
                                   float maxSpeed);

// A tool for the hand in a scene whose own tools do not include one of this kind, sized from
// the particle spacing dp and placed from the particles' box [lo, hi] inside the domain
// [domainMin, domainMax]:
//   probe   a capsule of radius 1.5 dp and shaft 12 dp, tip just above the particles;
//   blade   an edge of 6 dp (radius dp / 4), tip just above the particles, not cutting
//           until dragged;
//   grasper jaws of radius 0.75 dp and width 2 dp, along the shaft (z) from below the
//           particles to above them, side by side across y, open wider than the particles'
//           box in y: a clamp across a vessel along x.
// Named "hand <kind>".
sim::ToolSpec handTool(sim::ToolKind kind, float spacing, glm::vec3 lo, glm::vec3 hi, glm::vec3 domainMin,
                       glm::vec3 domainMax);

}  // namespace hemo::render
