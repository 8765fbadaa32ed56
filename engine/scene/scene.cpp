#include "hemo/scene/scene.hpp"

#include "hemo/scene/aneurysm.hpp"
#include "hemo/scene/bifurcation.hpp"
#include "hemo/scene/build.hpp"
#include "hemo/scene/mesh_vessel.hpp"
#include "hemo/io/mesh.hpp"
#include "hemo/scene/tube.hpp"
#include "interface/tool.h"

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

namespace hemo::scene {

using Json = nlohmann::json;

namespace {

enum class Kind { Number, Integer, Bool, String, Vec3, NumberList, Choice, ChoiceList, Objects, Section };

struct Field {
  std::string key;
  Kind kind;
  std::string unit;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool minExclusive = false;
  Json def;  // null: required
  std::string description;
  std::vector<std::string> choices = {};
  std::vector<Field> items = {};  // Objects: fields of each element; Section: fields
};

constexpr double kInf = std::numeric_limits<double>::infinity();

// The whole scene format, in one place.
const std::vector<Field>& schema() {
  static const std::vector<Field> fields = {
      {"scene", Kind::String, "", 0, 0, false, nullptr, "Scene name, reported in outputs."},
      {"description", Kind::String, "", 0, 0, false, "", "Free text."},
      {"particles", Kind::Section, "", 0, 0, false, nullptr, "Particle resolution.", {},
       {
           {"spacing_m", Kind::Number, "m", 0, 10, true, nullptr, "Initial particle spacing dp (fluid and boundary lattice)."},
           {"smoothing_ratio", Kind::Number, "1", 0.5, 3, false, 1.3, "Smoothing length h / dp; the kernel support is 2h."},
           {"neighbour_capacity", Kind::Integer, "1", 8, 1024, false, 128, "Neighbour-list entries per particle; exceeding it stops the run."},
           {"list_layout", Kind::Choice, "", 0, 0, false, "auto", "How the neighbour list lies in memory: interleaved (entry k of consecutive particles side by side: a GPU's loads coalesce; the default on GPUs), contiguous (each particle's entries together, read four per texel: fewer, wider loads; the default on CPU devices), clusters (CPU devices: one list per four consecutive fluid particles; WCSPH with summation density, Newtonian blood and no SPS term only, else contiguous), or auto. Results differ only in the order of the sums; for benchmarks and devices where the default is not the fastest.", {"auto", "interleaved", "contiguous", "clusters"}},
           {"neighbour_search", Kind::Choice, "", 0, 0, false, "auto", "How the passes find a particle's neighbours: a neighbour list (fastest where it fits; 8 x neighbour_capacity bytes per particle), cells (no list: each pass walks the grid cells around the particle, for scenes the list would not fit; the same results bit for bit), or auto (the list where the device's memory holds it, else cells).", {"auto", "list", "cells"}},
           {"list_skin", Kind::Number, "1", 0, 1, false, 0.1, "Neighbour-list radius = 2h (1 + skin). A larger skin rebuilds the list less often but makes it longer: 0.1 suits the dam break, 0.25 (with a capacity of 176) the vessel scenes, whose shear flows spread the displacements (docs/benchmarks.md)."},
       }},
      {"fluid", Kind::Section, "", 0, 0, false, nullptr, "The fluid (blood defaults are density 1060, viscosity 3.5e-3).", {},
       {
           {"density_kg_m3", Kind::Number, "kg/m^3", 1, 1e5, false, 1000.0, "Rest density rho0."},
           {"viscosity_pa_s", Kind::Number, "Pa s", 0, 100, false, 1e-3, "Dynamic viscosity mu (laminar term) of Newtonian blood."},
           {"rheology", Kind::Section, "", 0, 0, false, Json::object(), "How the viscosity depends on the shear rate (docs/physics.md, \"Non-Newtonian blood\"). The defaults are Cho & Kensey's (1991) fit to whole blood.", {},
            {
                {"model", Kind::Choice, "", 0, 0, false, "newtonian", "newtonian (viscosity_pa_s everywhere) or carreau_yasuda: each particle's viscosity mu_inf + (mu_0 - mu_inf) (1 + (lambda g)^a)^((n - 1) / a) at its shear rate g (shear-thinning blood; viscosity_pa_s does not apply).", {"newtonian", "carreau_yasuda"}},
                {"zero_shear_viscosity_pa_s", Kind::Number, "Pa s", 0, 100, true, 0.056, "mu_0: the viscosity at rest (the largest; it sets the viscous time-step limit)."},
                {"infinite_shear_viscosity_pa_s", Kind::Number, "Pa s", 0, 100, false, 0.00345, "mu_inf: the viscosity at high shear rates (at most mu_0)."},
                {"relaxation_time_s", Kind::Number, "s", 0, 1e3, true, 3.313, "lambda: the inverse of the shear rate where thinning sets in."},
                {"power_index", Kind::Number, "1", 0, 1, true, 0.3568, "n: the power-law index (below 1: shear thinning)."},
                {"yasuda_exponent", Kind::Number, "1", 0, 10, true, 2.0, "a: how sharp the transition is (2: the Carreau law)."},
            }},
           {"speed_of_sound_m_s", Kind::Number, "m/s", 0, 1e5, false, 0.0, "Speed of sound c0; 0 derives 10 x expected_max_speed_m_s."},
           {"expected_max_speed_m_s", Kind::Number, "m/s", 0, 1e4, true, nullptr, "Largest flow speed expected; sets c0 unless given."},
           {"clamp_negative_pressure", Kind::Bool, "", 0, 0, false, true, "Clamp Tait pressure at 0 (free surfaces)."},
           {"turbulence", Kind::Choice, "", 0, 0, false, "none", "Sub-particle-scale turbulence model (Dalrymple & Rogers 2006), or none.", {"none", "sps"}},
           {"density", Kind::Choice, "", 0, 0, false, "summation", "How the density is found: summed over the neighbours (the seed's method), or carried by each particle and advanced by the continuity equation with delta-SPH density diffusion (holds a free surface at rest; not with a vessel inflow).", {"summation", "continuity"}},
           {"solver", Kind::Choice, "", 0, 0, false, "wcsph", "How the pressure is found: wcsph (weakly compressible: the Tait equation of state, the step limited by the speed of sound) or dfsph (the density and divergence solves of divergence-free SPH, Bender & Koschier 2017, holding the Tait law's compressibility unless solver_compressible is false: iterates each step to solver_tolerance, the step limited by the flow's speed; summation density, symplectic Euler and the neighbour list; the wall takes the reaction of the solved pressure, and the background (lumen) pressure loads it as under wcsph).", {"wcsph", "dfsph"}},
           {"solver_tolerance", Kind::Number, "1", 0, 0.1, true, 1e-3, "dfsph: the mean residual over the fluid that ends a step's iterations: the density solve's (rho* - rho0 - p / c0^2)+ / rho0 (without the p / c0^2 when solver_compressible is false), the divergence solve's compressive divergence times the step over rho0."},
           {"solver_compressible", Kind::Bool, "", 0, 0, false, true, "dfsph: the density solve leaves the compression that the Tait law, linearised at rho0, gives its pressure (p / c0^2, c0 from speed_of_sound_m_s), so the blood is as compressible as under wcsph and a step below the acoustic one gives wcsph's pressure; false: the solve takes out all compression each step (incompressible), which at steps far below the acoustic one makes the fluid churn (docs/physics.md)."},
           {"solver_max_iterations", Kind::Integer, "1", 1, 1000, false, 50, "dfsph: the cap on each solve's corrections per step; a solve that reaches it above the tolerance is counted and reported. A step records about one and a half times what the last batch's solves took (a batch whose solve needs more runs again, recorded to the cap, so results do not depend on it); each recorded iteration the GPU skips still costs empty dispatches (docs/physics.md)."},
           {"delta_sph", Kind::Number, "-", 0, 1, false, 0.1, "delta of the continuity density's diffusion term (Molteni & Colagrossi 2009, with the hydrostatic correction of Fourtakas et al. 2019)."},
           {"smagorinsky_constant", Kind::Number, "1", 0, 1, false, 0.12, "C_s of the SPS eddy viscosity nu_t = (C_s dp)^2 |S|."},
           {"blinn_constant", Kind::Number, "1", 0, 1, false, 0.0066, "C_I of the SPS isotropic term -2/3 C_I dp^2 |S|^2."},
           {"background_pressure_Pa", Kind::Number, "Pa", 0, 1e8, false, 0.0, "Lumen (background) pressure p_bg added to the Tait pressure of every particle: what pressurises a vessel. Uniform, so it pushes only where the fluid meets a wall or ends."},
           {"background_pressure_ramp_s", Kind::Number, "s", 0, 1e6, false, 0.0, "p_bg rises linearly from 0 over this time (0: from the start)."},
           {"blocks", Kind::Objects, "", 0, kInf, false, Json::array(), "Boxes filled with fluid particles on the dp lattice (a vessel fills itself).", {},
            {
                {"min_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Lower corner."},
                {"max_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Upper corner."},
                {"velocity_m_s", Kind::Vec3, "m/s", -1e4, 1e4, false, Json::array({0.0, 0.0, 0.0}), "Initial velocity."},
                {"lattice", Kind::Choice, "", 0, 0, false, "cubic", "Particle arrangement: the simple cubic dp lattice, or body-centred cubic cells of edge 2^(1/3) dp fitted to the box (the same particles per volume; a stable packing under pressure, for fluid that starts at rest).", {"cubic", "bcc"}},
            }},
       }},
      {"boundary", Kind::Section, "", 0, 0, false, Json::object(), "Rigid boundaries.", {},
       {
           {"tanks", Kind::Objects, "", 0, kInf, false, Json::array(), "Rigid boxes made of boundary particles outside each face.", {},
            {
                {"min_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Inner lower corner."},
                {"max_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Inner upper corner."},
                {"layers", Kind::Integer, "1", 1, 8, false, 3, "Layers of boundary particles (enough to fill the kernel support: >= 2h/dp)."},
                {"open_top", Kind::Bool, "", 0, 0, false, true, "No wall on the +z face."},
            }},
           {"repulsion_scale", Kind::Number, "1", 0, 10, false, 0.01, "Psi = scale c0^2 / (2h): strength of the repulsive boundary force."},
           {"repulsion_cutoff_ratio", Kind::Number, "1", 0, 6, true, 0.5, "D = ratio x dp: no repulsion beyond this normal distance (at most 2h/dp). Below the rest spacing (1) so it guards against penetration without carrying the fluid at rest."},
       }},
      {"vessel", Kind::Section, "", 0, 0, false, Json::object(), "A vessel wall of wall particles joined by springs, filled with fluid; its axis runs along +x. Omit it for scenes without walls (no spring stage runs).", {},
       {
           {"shape", Kind::Choice, "", 0, 0, false, "none", "Straight tube, tube with a spherical sac on its +z side halfway along, tube bulging all round halfway along, a bifurcation (two branches that split off and merge again halfway along the tube: a loop, periodic or with open ends; a vessel that branches into separate outlets is a mesh), a surface mesh of the lumen (vessel.mesh), or none.", {"none", "tube", "saccular_aneurysm", "fusiform_aneurysm", "bifurcation", "mesh"}},
           {"mesh", Kind::Section, "", 0, 0, false, Json::object(), "shape \"mesh\": the lumen's surface, as segmented from CT or MR angiography (docs/meshes.md). Its wall layers lie at (l + 1/2) dp outside the surface; start_m, length_m and radius_m come from the mesh and its inlet.", {},
            {
                {"file", Kind::String, "", 0, 0, false, "", "STL (binary or ASCII) or OBJ file of the lumen's surface, relative to the scene file: one connected surface of triangles wound counter-clockwise seen from outside, open only at its ends."},
                {"unit_m", Kind::Number, "m", 0, 1e3, true, 1.0, "Metres per unit of the file's coordinates: 0.001 for millimetres (what segmentation tools export)."},
                {"ends", Kind::Objects, "", 0, kInf, false, Json::array(), "Every open boundary loop of the surface, named; a loop no entry names is an error (a hole). Either the ends lie on the two planes of a periodic x axis, matching across the seam (the blood leaving the outlet comes back through the inlet), or the vessel has open ends (vessel.outlet): one inlet and 1 to 7 outlets (a branching vessel) anywhere, each in the frame of its loop (the cap's centre, inward normal and equivalent radius), straight for its buffer's length.", {},
                 {
                     {"role", Kind::Choice, "", 0, 0, false, nullptr, "What the end is: the inlet (on a periodic vessel, on the domain's min x plane when vessel.inflow drives the flow: the zone starts there) or an outlet.", {"inlet", "outlet"}},
                     {"at_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "A point at the end's centre (within its radius): which loop the entry names."},
                     {"pressure_Pa", Kind::Number, "Pa", -1e6, 1e6, false, 0.0, "An outlet's own pressure over fluid.background_pressure_Pa, in place of vessel.outlet.pressure_Pa (a pressure outlet of a vessel with open ends): branches whose downstream beds differ."},
                 }},
                {"regions", Kind::Objects, "", 0, kInf, false, Json::array(), "Parts of the wall with other tissue, such as an aneurysm's thinner, weaker dome: a spring whose midpoint lies within a region's sphere takes its stiffness and strength scales (the first region that holds it).", {},
                 {
                     {"centre_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Centre of the region's sphere."},
                     {"radius_m", Kind::Number, "m", 0, 1e3, true, nullptr, "Radius of the region's sphere."},
                     {"stiffness_scale", Kind::Number, "1", 0, 1e6, true, 1.0, "The springs' stiffness there / the wall's."},
                     {"strength_scale", Kind::Number, "1", 0, 1e6, true, 1.0, "The springs' maximum force there / the wall's."},
                 }},
            }},
           {"start_m", Kind::Vec3, "m", -1e6, 1e6, false, Json::array({0.0, 0.0, 0.0}), "Start of the axis. With a periodic x axis the tube spans the domain: start x = domain min x."},
           {"length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "Length along +x (with a periodic x axis: the domain's period)."},
           {"radius_m", Kind::Number, "m", 0, 1e3, false, 0.0, "Inner radius; the wall's layers lie at radius + (l + 1/2) dp."},
           {"layers", Kind::Integer, "1", 1, 4, false, 2, "Wall layers."},
           {"point_mass_kg", Kind::Number, "kg", 0, 1e6, false, 0.0, "Mass of each wall point (for the springs)."},
           {"stiffness_N_m", Kind::Number, "N/m", 0, 1e12, false, 0.0, "Stiffness of every tube spring (or give youngs_modulus_Pa and wall_thickness_m)."},
           {"youngs_modulus_Pa", Kind::Number, "Pa", 0, 1e12, false, 0.0, "Instead of stiffness_N_m: the wall's Young's modulus E; the springs get the hoop stiffness of a thin tube of this modulus and wall_thickness_m (docs/physics.md)."},
           {"poisson_ratio", Kind::Number, "1", 0, 0.5, false, 0.45, "Poisson's ratio nu of the wall (with youngs_modulus_Pa; must be below 0.5)."},
           {"wall_thickness_m", Kind::Number, "m", 0, 1, false, 0.0, "Wall thickness t for the tissue mapping (youngs_modulus_Pa, failure_stress_Pa)."},
           {"failure_stress_Pa", Kind::Number, "Pa", 0, 1e12, false, 0.0, "Instead of max_force_N: the tissue's failure stress sigma_f; springs break so that the tube ruptures at P* = sigma_f t / R."},
           {"damping_N_s_m", Kind::Number, "N s/m", 0, 1e12, false, 0.0, "Damping of every spring, along the spring."},
           {"max_force_N", Kind::Number, "N", 0, 1e30, false, 1e30, "A spring whose tension exceeds this breaks, for good."},
           {"anchor_ends", Kind::Bool, "", 0, 0, false, true, "Fix the first and last rings of a non-periodic tube."},
           {"sac_radius_m", Kind::Number, "m", 0, 1e3, false, 0.0, "saccular_aneurysm: inner radius of the sac."},
           {"neck_width_m", Kind::Number, "m", 0, 1e3, false, 0.0, "saccular_aneurysm: width of the opening between tube and sac."},
           {"bulge_radius_m", Kind::Number, "m", 0, 1e3, false, 0.0, "fusiform_aneurysm: inner radius at the bulge's middle (r(x) = R + (Rb - R) cos^2(pi (x - xc) / Lb))."},
           {"bulge_length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "fusiform_aneurysm: axial length Lb of the bulge, centred halfway along the tube."},
           {"branch_angle_deg", Kind::Number, "deg", 0, 80, true, 30.0, "bifurcation: angle of each branch to the parent's axis, in the x-y plane (the branches leave at +-angle and come back at -+angle)."},
           {"branch_length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "bifurcation: length of each leg (split to bend, bend to merge); the loop spans 2 L cos(angle) along x, centred on the tube, and its bends lie L sin(angle) off the axis."},
           {"sac_stiffness_scale", Kind::Number, "1", 0, 1e6, true, 1.0, "Aneurysms: the sac's or bulge's springs' stiffness / the tube's."},
           {"sac_strength_scale", Kind::Number, "1", 0, 1e6, true, 1.0, "Aneurysms: the sac's or bulge's springs' maximum force / the tube's."},
           {"time_step_factor", Kind::Number, "1", 0, 1, true, 0.1, "The wall's time-step limit: dt <= factor sqrt(m / sum k) at every wall point. Symplectic Euler is stable up to 1 (a spring network's highest frequency is at most sqrt(2 sum k / m)); RK2 midpoint amplifies an undamped spring by about 1 + (omega dt)^4 / 8 per step and relies on the springs' damping, so keep it small there."},
           {"substeps", Kind::Integer, "1", 1, 256, false, 1, "The wall's substeps per fluid step: with N > 1 the wall takes N substeps of dt / N (its springs and rupture evaluated at each, the fluid's force held over the step), so its springs limit the step to N time_step_factor sqrt(m / sum k) instead of time_step_factor sqrt(m / sum k). Pick N about the fluid's own step over the springs' limit (hemo-run prints both). Symplectic Euler only."},
           {"inflow", Kind::Section, "", 0, 0, false, Json::object(), "Driven inflow (periodic vessels): fluid in a zone at the start of the tube moves at a prescribed axial velocity, and what leaves the far end comes back through the periodic seam (recycled; the particle count never changes). A pump: it sets the flow rate whatever the pressure.", {},
            {
                {"profile", Kind::Choice, "", 0, 0, false, "none", "Velocity profile over the cross-section: parabolic (Poiseuille, peak 2x the mean), plug (uniform), or none (no inflow). Open ends with driven_by pressure: the profile the inlet's speed is measured against is the lumen's own, and this only switches the inlet on (give parabolic).", {"none", "parabolic", "plug"}},
                {"driven_by", Kind::Choice, "", 0, 0, false, "velocity", "velocity: the zone moves at the profile and mean speed; pressure (open ends with a pressure outlet only): the inlet buffer holds pressure_Pa and moves at the lumen's own axial velocity next to it, radius by radius, so the pressure difference drives the flow.", {"velocity", "pressure"}},
                {"pressure_Pa", Kind::Number, "Pa", -1e6, 1e6, false, 0.0, "driven_by pressure: the inlet buffer's pressure over fluid.background_pressure_Pa, rising over ramp_s (times w(t) with a waveform)."},
                {"mean_speed_m_s", Kind::Number, "m/s", -1e3, 1e3, false, 0.0, "Mean speed U over the cross-section (negative: flow along -x)."},
                {"zone_length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "Length of the driven zone from the tube's start (a mesh vessel's open inlet: from its end, along its axis); at least the kernel support 2h, at most half the tube."},
                {"pulse_period_s", Kind::Number, "s", 0, 1e6, false, 0.0, "Period of the waveform (0: constant speed)."},
                {"waveform", Kind::NumberList, "1", -100, 100, false, Json::array(), "Pulsatile flow: u(t) = U w(t) (a pressure inlet: its pressure_Pa times w(t)), w sampled at equal steps over one period (2 to 64 samples, linear in between, periodic). Empty: w = 1."},
                {"ramp_s", Kind::Number, "s", 0, 1e6, false, 0.0, "u rises linearly from 0 over this time (0: at once)."},
                {"hold_lumen_pressure", Kind::Bool, "", 0, 0, false, false, "The zone is also the blood supply: each step a zone particle's mass becomes m rho0 / rho (between its initial mass and max_mass_ratio times it), so the zone holds the lumen at fluid.background_pressure_Pa while the wall stretches and blood leaves through a rupture."},
                {"max_mass_ratio", Kind::Number, "1", 1, 1e3, false, 4.0, "Cap of a particle's mass over its initial mass under hold_lumen_pressure."},
            }},
           {"outlet", Kind::Section, "", 0, 0, false, Json::object(), "Open ends (tubes, aneurysms and the bifurcation loop along x, and mesh vessels with one inlet and one or more outlets; with vessel.inflow, on a domain whose x axis is not periodic): the inflow zone is the inlet buffer, fed by an image of each particle that leaves it into the lumen; each outlet's buffer moves with the inflow's velocity profile and flow rate (one outlet) or holds a pressure, each along its end's axis, and fluid past any end leaves the simulation (its slot parked for the buffers to reuse). The lumen's mass balance is counted exactly (hemo-run's summary, open_*).", {},
            {
                {"condition", Kind::Choice, "", 0, 0, false, "none", "none: the vessel is periodic and recycles its outflow (vessel.inflow); flow: open ends, the outlet buffer drawing the inlet's flow rate; pressure: open ends, each outlet buffer holding pressure_Pa and moving at the lumen's own axial velocity next to it, radius by radius (zero gradient); a vessel with several outlets needs it.", {"none", "flow", "pressure"}},
                {"pressure_Pa", Kind::Number, "Pa", -1e6, 1e6, false, 0.0, "condition pressure: the outlet buffers' pressure over fluid.background_pressure_Pa (every outlet's)."},
                {"buffer_length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "Length of each outlet's buffer at the vessel's end, along its axis (0: the inflow zone's length); at least the kernel support 2h."},
                {"park_escaped_beyond_m", Kind::Number, "m", 0, 1, false, 0.0, "Blood farther than this outside the vessel's wall (beyond its outer layer) is removed, its slot freed for the buffers, and counted as escaped, so a bleeding vessel does not run out of free slots while its blood crosses the domain (0: only blood that leaves the domain). Give more than the wall moves, or blood in a swelling sac would be taken; the domain is divided into cells of two spacings, and a cell takes the blood in it when all of it lies that far out."},
                {"reserve_particles", Kind::Integer, "1", 0, 1e8, false, 0, "Free fluid slots for the buffers' images beyond those the outlet frees (0: automatic, twice the inlet buffer's particles and half the vessel's fluid: a sac that swells draws blood in through both ends). A run that runs out stops and says so."},
            }},
       }},
      {"forces", Kind::Section, "", 0, 0, false, Json::object(), "Body forces.", {},
       {
           {"gravity_m_s2", Kind::Vec3, "m/s^2", -1e4, 1e4, false, Json::array({0.0, 0.0, -9.81}), "Gravity."},
           {"body_force_m_s2", Kind::Vec3, "m/s^2", -1e4, 1e4, false, Json::array({0.0, 0.0, 0.0}), "Extra uniform acceleration (drives channel flows)."},
       }},
      {"time", Kind::Section, "", 0, 0, false, Json::object(), "Time stepping.", {},
       {
           {"integrator", Kind::Choice, "", 0, 0, false, "symplectic_euler", "Time integration: symplectic Euler (one force evaluation per step) or the Runge-Kutta midpoint rule (two, the reference).", {"symplectic_euler", "rk2_midpoint"}},
           {"cfl_acoustic", Kind::Number, "1", 0, 1, true, 0.3, "C_a in dt <= C_a h / (c0 + |v|)."},
           {"cfl_force", Kind::Number, "1", 0, 1, true, 0.25, "C_f in dt <= C_f sqrt(h / |a|)."},
           {"max_dt_s", Kind::Number, "s", 0, 1, true, 1e-3, "Upper bound of the time step."},
           {"end_time_s", Kind::Number, "s", 0, 1e6, false, 1.0, "Simulated time of a run (hemo-run --until overrides)."},
           {"min_dt_s", Kind::Number, "s", 0, 1, false, 0.0, "The run stops with an error when the time step falls below this: the flow blew up (a particle's speed or acceleration ran away) and the run would never reach its end. 0: 1e-4 times the scene's own step, the smallest of C_a h / (c0 + expected_max_speed) (DFSPH: C_a h / expected_max_speed), max_dt_s, the viscous limit and the wall's spring limit times its substeps."},
           {"steps_per_batch", Kind::Integer, "1", 1, 4096, false, 64, "Steps recorded into one command buffer per submit."},
           {"settle_damping_1_s", Kind::Number, "1/s", 0, 1e6, false, 0.0, "Velocity damping xi of a settling phase: v <- v / (1 + xi dt)."},
           {"settle_until_s", Kind::Number, "s", 0, 1e6, false, 0.0, "The settling phase lasts while t < this (0: none)."},
       }},
      {"tools", Kind::Objects, "", 0, kInf, false, Json::array(), "Surgical tools (at most 8): rigid bodies moved along keyframed paths that push the blood and the vessel wall out of their way and feel the force back (docs/physics.md, \"Tools\"). hemo-run writes each tool's force per step to DIR/tools.csv.", {},
       {
           {"name", Kind::String, "", 0, 0, false, nullptr, "The tool's name, reported in outputs."},
           {"kind", Kind::Choice, "", 0, 0, false, "probe", "A probe: a capsule, the segment from the tip along the tool's +z axis grown by radius_m (a sphere when length_m is 0). A blade: a probe whose segment, of length_m > 0, is an edge that cuts every spring it sweeps through while its keyframes say so (path[].cutting). A grasper: two jaws (capsules, or rounded plates with jaw_width_m) along the tool's +z axis on either side of it along its +x axis, the gap between their surfaces keyed (path[].jaw_opening_m): closing them squeezes what lies between (a clamp) and grips the wall points they squeeze (grip).", {"probe", "blade", "grasper"}},
           {"radius_m", Kind::Number, "m", 0, 1e3, true, nullptr, "Radius of the probe's capsule."},
           {"length_m", Kind::Number, "m", 0, 1e3, false, 0.0, "Length of its shaft from the tip along the tool's +z axis (0: a sphere)."},
           {"contact_distance_m", Kind::Number, "m", 0, 1e3, false, 0.0, "D: particles closer than this to the tool's surface (or inside it) are pushed out along its normal (0: the particle spacing dp)."},
           {"jaw_width_m", Kind::Number, "m", 0, 1e3, false, 0.0, "A grasper's jaws are rounded plates this wide (along the tool's y axis), each the points within radius_m of a rectangle length_m by jaw_width_m; 0: capsules. Flat jaws squeeze what they hold instead of pushing it aside."},
           {"grip", Kind::Bool, "", 0, 0, false, true, "A grasper grips the free wall points that lie within contact_distance_m of both its jaws: each is held where the jaws took it, in the jaws' plane, by a critically damped spring of grip_stiffness_N_m, so it follows the jaws until they open again. false: the jaws squeeze but do not hold. Only for graspers."},
           {"grip_stiffness_N_m", Kind::Number, "N/m", 0, 1e12, false, 0.0, "The grip's spring (0: the vessel's spring stiffness, vessel.stiffness_N_m or the one fitted to youngs_modulus_Pa). A gripped point's step is at most vessel.time_step_factor sqrt(m / k)."},
           {"contact_scale", Kind::Number, "1", 0, 1e3, true, 0.01, "Psi = scale c0^2 / (2h) of the push Psi (1 - q) / sqrt(q), q = max(x / 2h, 1e-3), x the distance to the surface: the boundary repulsion's law, on the tool's exact surface."},
           {"path", Kind::Objects, "", 1, kInf, false, nullptr, "Keyframes, in time order (at most 41): the tool holds the first pose before the first and the last after the last; in between the tip moves linearly and the orientation turns by normalised linear interpolation (under 90 degrees from key to key).", {},
            {
                {"time_s", Kind::Number, "s", 0, 1e6, false, nullptr, "Time of the keyframe."},
                {"position_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Where the tip is; inside the domain."},
                {"orientation_wxyz", Kind::NumberList, "1", -1e6, 1e6, false, Json::array({1.0, 0.0, 0.0, 0.0}), "The tool's rotation as a quaternion (w, x, y, z), normalised on loading: the default keeps its shaft along +z."},
                {"cutting", Kind::Bool, "", 0, 0, false, false, "A blade cuts from this keyframe to the next (after the last: for good)."},
                {"jaw_opening_m", Kind::Number, "m", 0, 1e3, false, 0.0, "A grasper's gap between its jaws at this keyframe (linear in between)."},
            }},
       }},
      {"surface", Kind::Section, "", 0, 0, false, Json::object(), "The blood surface (GPU marching cubes over the particles' volume-fraction field), built only when something asks for it (hemo-run --surface-every, the renderer).", {},
       {
           {"grid_resolution", Kind::Integer, "1", 4, 512, false, 128, "Voxels along the longest side of the grid around the fluid's bounding box (grown by 2h)."},
           {"iso_level", Kind::Number, "1", 0, 1, true, 0.5, "The surface is where the volume fraction sum_j (m_j / rho_j) W(|x - x_j|, h) equals this (1 inside the fluid, 0 away from it)."},
           {"max_triangles", Kind::Integer, "1", 0, 4.0e7, false, 0, "Capacity of the triangle buffer (0: 12 grid_resolution^2). Triangles beyond it are counted and reported, not drawn."},
           {"splat_voxel_h", Kind::Number, "h", 0, 4, false, 0.5, "The particles are splatted on a grid of this voxel (in smoothing lengths; never finer than the surface grid) and the surface grid's values interpolated from it: the field is smooth on the scale of h, and the splat's cost falls with the cube of this. 0: splat on the surface grid itself (exact, slow on fine grids)."},
       }},
      {"domain", Kind::Section, "", 0, 0, false, nullptr, "Region covered by the neighbour grid; particles that leave it are counted as escaped.", {},
       {
           {"min_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Lower corner."},
           {"max_m", Kind::Vec3, "m", -1e6, 1e6, false, nullptr, "Upper corner."},
           {"periodic", Kind::ChoiceList, "", 0, 0, false, Json::array(), "Axes on which [min_m, max_m) is one period: particles leaving one side enter at the other, and tanks have no walls across these axes (they must span the domain there). The period must be a whole number of spacings and at least 2.5 neighbour-list radii.", {"x", "y", "z"}},
       }},
  };
  return fields;
}

std::string kindName(Kind k) {
  switch (k) {
    case Kind::Number: return "number";
    case Kind::Integer: return "integer";
    case Kind::Bool: return "boolean";
    case Kind::String: return "string";
    case Kind::Vec3: return "array of 3 numbers";
    case Kind::NumberList: return "array of numbers";
    case Kind::Choice: return "string";
    case Kind::ChoiceList: return "array of strings";
    case Kind::Objects: return "array of objects";
    case Kind::Section: return "object";
  }
  return "?";
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string fmtPoint(glm::dvec3 p) {
  std::ostringstream s;
  s << "(" << p.x << ", " << p.y << ", " << p.z << ") m";
  return s.str();
}

class Checker {
 public:
  explicit Checker(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw SceneError(source_ + ": " + (path.empty() ? "" : path + ": ") + problem);
  }

  void checkNumber(const std::string& path, const Json& v, const Field& f) const {
    if (!v.is_number()) fail(path, "expected a " + kindName(f.kind) + (f.unit.empty() ? "" : " (" + f.unit + ")") + ", got " + v.dump());
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(path, "must be finite, got " + v.dump());
    if (f.kind == Kind::Integer && (!v.is_number_integer() || x != std::floor(x))) fail(path, "expected a whole number, got " + v.dump());
    // the engine computes in single precision: a value that would become 0 or lose its
    // precision there (below the smallest normal float) is refused, not silently zeroed
    if (x != 0.0 && std::abs(x) < double(std::numeric_limits<float>::min())) {
      fail(path, "is too small for single precision (non-zero values need |x| >= " +
                     fmt(double(std::numeric_limits<float>::min())) + "), got " + v.dump());
    }
    const bool belowMin = f.minExclusive ? x <= f.min : x < f.min;
    if (belowMin || x > f.max) {
      fail(path, "must be in " + std::string(f.minExclusive ? "(" : "[") + fmt(f.min) + ", " + fmt(f.max) + "]" +
                     (f.unit.empty() || f.unit == "1" ? "" : " " + f.unit) + ", got " + v.dump());
    }
  }

  Json object(const std::string& path, const Json& in, const std::vector<Field>& fields) const {
    if (!in.is_object()) fail(path, "expected an object, got " + in.dump());
    for (auto it = in.begin(); it != in.end(); ++it) {
      bool known = false;
      for (const auto& f : fields) known = known || f.key == it.key();
      if (!known) {
        std::string names;
        for (const auto& f : fields) names += (names.empty() ? "" : ", ") + f.key;
        fail(join(path, it.key()), "unknown key (expected one of: " + names + ")");
      }
    }
    Json out = Json::object();
    for (const auto& f : fields) {
      const std::string p = join(path, f.key);
      if (!in.contains(f.key)) {
        if (f.def.is_null()) fail(p, "is required");
        out[f.key] = f.kind == Kind::Section ? object(p, f.def, f.items) : f.def;
        continue;
      }
      out[f.key] = value(p, in.at(f.key), f);
    }
    return out;
  }

 private:
  static std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

  Json value(const std::string& p, const Json& v, const Field& f) const {
    switch (f.kind) {
      case Kind::Number:
      case Kind::Integer:
        checkNumber(p, v, f);
        return v;
      case Kind::Bool:
        if (!v.is_boolean()) fail(p, "expected true or false, got " + v.dump());
        return v;
      case Kind::String:
        if (!v.is_string()) fail(p, "expected a string, got " + v.dump());
        return v;
      case Kind::Choice: {
        if (!v.is_string()) fail(p, "expected a string, got " + v.dump());
        std::string all;
        for (const auto& c : f.choices) {
          if (c == v.get<std::string>()) return v;
          all += (all.empty() ? "" : ", ") + ("\"" + c + "\"");
        }
        fail(p, "unknown value " + v.dump() + " (expected one of: " + all + ")");
      }
      case Kind::ChoiceList: {
        if (!v.is_array()) fail(p, "expected an array of strings, got " + v.dump());
        for (std::size_t k = 0; k < v.size(); ++k) {
          value(p + "[" + std::to_string(k) + "]", v[k], Field{"", Kind::Choice, "", 0, 0, false, nullptr, "", f.choices});
          for (std::size_t m = 0; m < k; ++m) {
            if (v[m] == v[k]) fail(p, "lists " + v[k].dump() + " twice");
          }
        }
        return v;
      }
      case Kind::Vec3: {
        if (!v.is_array() || v.size() != 3) fail(p, "expected an array of 3 numbers (" + f.unit + "), got " + v.dump());
        for (std::size_t k = 0; k < 3; ++k) checkNumber(p + "[" + std::to_string(k) + "]", v[k], Field{"", Kind::Number, f.unit, f.min, f.max});
        return v;
      }
      case Kind::NumberList: {
        if (!v.is_array()) fail(p, "expected an array of numbers" + (f.unit.empty() || f.unit == "1" ? std::string() : " (" + f.unit + ")") + ", got " + v.dump());
        for (std::size_t k = 0; k < v.size(); ++k) checkNumber(p + "[" + std::to_string(k) + "]", v[k], Field{"", Kind::Number, f.unit, f.min, f.max});
        return v;
      }
      case Kind::Objects: {
        if (!v.is_array()) fail(p, "expected an array of objects, got " + v.dump());
        if (double(v.size()) < f.min) fail(p, "needs at least " + fmt(f.min) + " entr" + (f.min == 1 ? "y" : "ies"));
        Json out = Json::array();
        for (std::size_t k = 0; k < v.size(); ++k) out.push_back(object(p + "[" + std::to_string(k) + "]", v[k], f.items));
        return out;
      }
      case Kind::Section:
        return object(p, v, f.items);
    }
    return v;
  }

  std::string source_;
};

glm::vec3 vec3(const Json& v) { return {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()}; }

Box box(const Checker& c, const std::string& path, const Json& obj) {
  Box b{vec3(obj["min_m"]), vec3(obj["max_m"])};
  for (int a = 0; a < 3; ++a) {
    if (!(b.min[a] < b.max[a])) {
      c.fail(path, "min_m must be below max_m on every axis (axis " + std::string(1, "xyz"[a]) + ": " + fmt(b.min[a]) +
                       " >= " + fmt(b.max[a]) + ")");
    }
  }
  return b;
}

bool inside(const Box& inner, const Box& outer, float slack) {
  for (int a = 0; a < 3; ++a) {
    if (inner.min[a] < outer.min[a] - slack || inner.max[a] > outer.max[a] + slack) return false;
  }
  return true;
}

// `v`: the checked section (defaults filled in); `raw`: what the file gave.
// `open`: vessel.outlet gives the vessel open ends (parseOutlet).
void parseInflow(const Checker& c, const Json& in, const Json& raw, const Scene& s, Vessel& w, bool open) {
  const std::string profile = in["profile"].get<std::string>();
  if (profile == "none") {
    for (auto it = raw.begin(); it != raw.end(); ++it) {
      if (it.key() != "profile") c.fail("vessel.inflow." + it.key(), "is set but vessel.inflow.profile is \"none\" (choose \"parabolic\" or \"plug\")");
    }
    return;
  }
  if (s.sph.densityMethod == sim::DensityMethod::Continuity) {
    c.fail("vessel.inflow", "cannot be used with fluid.density \"continuity\" (the inflow zone's mass supply acts on the summed density)");
  }
  if (!s.sph.periodic[0] && !open) {
    c.fail("vessel.inflow", "needs a periodic x axis (domain.periodic [\"x\"]): the outflow is recycled to the inlet through the periodic seam (or give the vessel open ends: vessel.outlet.condition \"flow\")");
  }
  sim::Inflow f;
  f.profile = profile == "plug" ? sim::Inflow::Profile::Plug : sim::Inflow::Profile::Parabolic;
  f.meanSpeed = in["mean_speed_m_s"].get<float>();
  const float zone = in["zone_length_m"].get<float>();
  if (!(zone >= s.sph.supportRadius() * (1.0f - 1e-5f))) {
    c.fail("vessel.inflow.zone_length_m", "must be at least the kernel support 2h = " + fmt(s.sph.supportRadius()) + " m (so no fluid reaches through the zone), got " + fmt(zone));
  }
  if (zone > 0.5f * w.length) c.fail("vessel.inflow.zone_length_m", "must be at most half the tube's length (" + fmt(0.5 * w.length) + " m)");
  f.zoneStart = w.start.x;
  f.zoneEnd = w.start.x + zone;
  f.centreY = w.start.y;
  f.centreZ = w.start.z;
  f.radius = w.radius;
  f.period = in["pulse_period_s"].get<float>();
  f.ramp = in["ramp_s"].get<float>();
  for (const auto& x : in["waveform"]) f.waveform.push_back(x.get<float>());
  f.holdPressure = in["hold_lumen_pressure"].get<bool>();
  f.maxMassRatio = in["max_mass_ratio"].get<float>();
  if (!f.waveform.empty()) {
    if (f.waveform.size() < 2 || f.waveform.size() > sim::Inflow::kMaxSamples) {
      c.fail("vessel.inflow.waveform", "needs 2 to " + std::to_string(sim::Inflow::kMaxSamples) + " samples, got " + std::to_string(f.waveform.size()));
    }
    if (!(f.period > 0.0f)) c.fail("vessel.inflow.pulse_period_s", "must be positive when vessel.inflow.waveform is given");
  } else if (f.period > 0.0f) {
    c.fail("vessel.inflow.waveform", "is required when vessel.inflow.pulse_period_s is set (the samples of one period)");
  }
  const bool byPressure = in["driven_by"].get<std::string>() == "pressure";
  if (byPressure && !open) c.fail("vessel.inflow.driven_by", "\"pressure\" needs open ends with a pressure outlet (vessel.outlet.condition \"pressure\")");
  if (!byPressure && raw.contains("pressure_Pa")) c.fail("vessel.inflow.pressure_Pa", "only applies with vessel.inflow.driven_by \"pressure\"");
  if (byPressure && raw.contains("mean_speed_m_s")) c.fail("vessel.inflow.mean_speed_m_s", "does not apply to a pressure inlet (its speed is the lumen's)");
  // (a pressure inlet moves at the lumen's measured speed; its pressure_Pa follows the mean
  // speed's waveform and ramp, w(t) ramp(t): common/inflow_speed.glsl)
  if (byPressure) f.meanSpeed = 1.0f;
  if (f.meanSpeed == 0.0f) c.fail("vessel.inflow.mean_speed_m_s", "must be non-zero when an inflow profile is chosen");
  if (!(s.sph.backgroundPressure > 0.0f) && !open) {
    c.fail("fluid.background_pressure_Pa", "must be positive with a vessel.inflow: the lumen pressure is what pushes the fluid into the zone behind the pump (without it the zone runs empty); a few times rho U^2 is enough");
  }
  w.inflow = f;
}

// An open end of a mesh vessel must run straight for its buffer and a support beyond: the
// buffer moves along the end's axis, and its images come a buffer length back along it. Every
// vertex of the surface within the end's region, from `reach` behind the end to a support
// past its plane, must lie on the end's tube (0.75 to 1.25 of its radius from the axis), not
// past the end, and no other part of the vessel may come within its reach.
void checkStraightEnd(const Checker& c, const VesselMesh& mesh, const sim::OpenEnd& e, const std::string& field, const std::string& role,
                      float support) {
  for (const glm::dvec3& v : mesh.surface().vertices) {
    const glm::dvec2 l = e.local(v);
    const double r = std::sqrt(l.y), R = e.radius;
    if (l.x < -double(e.reach) || l.x > double(e.length) + support || r > double(e.reach) + support) continue;
    if (l.x < -1e-3 * R || r < 0.75 * R || r > 1.25 * R) {
      c.fail(field, "the mesh's " + role + " at " + fmtPoint(glm::dvec3(e.origin)) + " must run straight for its buffer (" +
                        fmt(e.length) + " m) and a kernel support beyond, but its surface at " + fmtPoint(v) + " lies " + fmt(r) +
                        " m from the end's axis and " + fmt(l.x) + " m along it (the end's radius is " + fmt(R) +
                        " m): shorten the buffer, or extend the vessel straight at that end");
    }
  }
}

// vessel.outlet (after parseInflow): open ends. `out`: the checked section.
void parseOutlet(const Checker& c, const Json& out, const Json& inflowSection, Scene& s, Vessel& w) {
  const std::string condition = out["condition"].get<std::string>();
  if (condition == "none") {
    for (const char* key : {"buffer_length_m", "reserve_particles", "pressure_Pa", "park_escaped_beyond_m"}) {
      if (out.contains(key) && out[key] != Json(0) && out[key] != Json(0.0)) {
        c.fail(std::string("vessel.outlet.") + key, "is set but vessel.outlet.condition is \"none\" (choose \"flow\")");
      }
    }
    return;
  }
  if (!w.inflow) c.fail("vessel.outlet", "open ends need a vessel.inflow (the inlet): give vessel.inflow.profile");
  if (s.sph.periodic[0]) c.fail("domain.periodic", "a vessel with open ends (vessel.outlet) must not be periodic along x");
  const bool meshed = w.shape == Vessel::Shape::Mesh;
  if (w.inflow->holdPressure) {
    c.fail("vessel.inflow.hold_lumen_pressure", "cannot be used with open ends (the zone's mass supply is for a closed, recycled loop)");
  }
  if (!(w.inflow->meanSpeed > 0.0f)) c.fail("vessel.inflow.mean_speed_m_s", "must be positive with open ends (the inlet is at the tube's start)");
  const bool pressureInlet = inflowSection["driven_by"].get<std::string>() == "pressure";
  if (pressureInlet && condition != "pressure") {
    c.fail("vessel.outlet.condition", "must be \"pressure\" with a pressure inlet (vessel.inflow.driven_by \"pressure\")");
  }
  if (condition != "pressure" && out["pressure_Pa"].get<double>() != 0.0) {
    c.fail("vessel.outlet.pressure_Pa", "only applies with vessel.outlet.condition \"pressure\"");
  }
  if (s.sph.densityMethod != sim::DensityMethod::Summation) c.fail("fluid.density", "open ends need summation density");
  if (s.sph.pressureSolver != sim::PressureSolver::Wcsph) c.fail("fluid.pressure_solver", "open ends need the wcsph pressure solver");
  if (s.sph.neighbourSearch == sim::NeighbourSearch::Cells) c.fail("particles.neighbour_search", "open ends need the neighbour list (\"list\" or \"auto\")");
  if (s.sph.listLayout == sim::ListLayout::Clusters) c.fail("particles.list_layout", "open ends do not walk clusters");
  const float slack = 1e-4f * s.sph.spacing;
  if (!meshed && (std::abs(w.start.x - s.domain.min.x) > slack || std::abs(w.start.x + w.length - s.domain.max.x) > slack)) {
    c.fail("vessel.length_m", "a vessel with open ends must span the domain along x (start_m x = domain min x, length_m = " +
                                  fmt(double(s.domain.max.x) - s.domain.min.x) + " m): fluid leaves at the domain's ends");
  }
  const float h2 = s.sph.supportRadius();
  const float zone = w.inflow->zoneEnd - w.inflow->zoneStart;
  if (!(zone >= h2 + s.sph.spacing * (1.0f - 1e-4f))) {
    c.fail("vessel.inflow.zone_length_m", "must be at least the kernel support and a spacing (" + fmt(h2 + s.sph.spacing) +
                                              " m) with open ends: the buffer's far end waits for its refill");
  }
  float buffer = out["buffer_length_m"].get<float>();
  if (buffer == 0.0f) buffer = zone;
  if (!(buffer >= h2 * (1.0f - 1e-5f))) {
    c.fail("vessel.outlet.buffer_length_m", "must be at least the kernel support 2h = " + fmt(h2) + " m, got " + fmt(buffer));
  }
  if (!(w.length - zone - buffer >= 2.0f * h2)) {
    c.fail("vessel.outlet.buffer_length_m", "the inlet and outlet buffers (" + fmt(zone) + " and " + fmt(buffer) +
                                                " m) leave less than two kernel supports of lumen in the " + fmt(w.length) +
                                                (meshed ? " m between the mesh's ends" : " m tube"));
  }
  sim::OpenEnds o;
  if (w.shape == Vessel::Shape::Mesh) {
    o.inlet = w.meshInlet;
    o.outlets = w.meshOutlets;
  } else {
    o.inlet.origin = w.start;
    o.inlet.axis = glm::vec3(1.0f, 0.0f, 0.0f);
    o.inlet.radius = w.radius;
    sim::OpenEnd& tail = o.outlets.emplace_back();
    tail.origin = w.start + glm::vec3(w.length, 0.0f, 0.0f);
    tail.axis = glm::vec3(-1.0f, 0.0f, 0.0f);
    tail.radius = w.radius;
  }
  if (o.outlets.size() > 1 && condition != "pressure") {
    c.fail("vessel.outlet.condition", "must be \"pressure\" on a vessel with " + std::to_string(o.outlets.size()) +
                                          " outlets (a flow outlet draws the inlet's flow; a split would need its ratios)");
  }
  // (each end's region: the lumen and its wall)
  o.inlet.reach = o.inlet.radius + float(w.layers + 1) * s.sph.spacing;
  o.inlet.length = zone;
  o.inlet.pressure = pressureInlet;
  o.inlet.pressurePa = pressureInlet ? inflowSection["pressure_Pa"].get<float>() : 0.0f;
  for (std::size_t k = 0; k < o.outlets.size(); ++k) {
    sim::OpenEnd& end = o.outlets[k];
    end.reach = end.radius + float(w.layers + 1) * s.sph.spacing;
    end.length = buffer;
    end.pressure = condition == "pressure";
    end.pressurePa = end.pressure ? out["pressure_Pa"].get<float>() : 0.0f;
    // (a mesh outlet's own pressure)
    const auto own = meshed ? w.meshEndPressures.find(w.meshOutletEntries[k]) : w.meshEndPressures.end();
    if (own != w.meshEndPressures.end()) {
      if (!end.pressure) {
        c.fail("vessel.mesh.ends[" + std::to_string(own->first) + "].pressure_Pa", "applies only with vessel.outlet.condition \"pressure\"");
      }
      end.pressurePa = own->second;
    }
  }
  if (meshed) {
    checkStraightEnd(c, *w.mesh, o.inlet, "vessel.inflow.zone_length_m", "inlet", h2);
    for (std::size_t k = 0; k < o.outlets.size(); ++k) {
      checkStraightEnd(c, *w.mesh, o.outlets[k], "vessel.outlet.buffer_length_m",
                       o.outlets.size() == 1 ? std::string("outlet") : "outlet " + std::to_string(k + 1), h2);
    }
  }
  // The gap the refill leaves at the buffer's far end stays beyond the support of the buffer
  // particles within the support of the inlet plane (two supports upstream of it), or at least
  // half a spacing (hemo/sim/inflow.hpp).
  o.pendingMargin = std::max(zone - 2.0f * h2, 0.5f * s.sph.spacing);
  // One metre past the domain's end, at its lowest corner: beyond every support, in the grid's
  // corner cell (interface/sph.h, HEMO_KIND_PARKED).
  o.parking = glm::vec3(s.domain.max.x + 1.0f, s.domain.min.y, s.domain.min.z);
  o.boxMin = s.domain.min;
  o.boxMax = s.domain.max;
  o.slab = h2;  // the lumen's slab next to each plane whose speeds a pressure end takes
  o.characteristic = 1.0f / (s.sph.restDensity * s.sph.soundSpeed);
  o.parkBeyond = out["park_escaped_beyond_m"].get<float>();
  if (o.parkBeyond > 0.0f) o.escape = sim::EscapeGrid::over(s.domain.min, s.domain.max, s.sph.spacing);
  w.inflow->open = o;
  w.reserveParticles = out["reserve_particles"].get<std::uint32_t>();
  s.sph.parkedSlots = true;
}

// shape "mesh": reads and checks the surface, names its ends, and sets the vessel's start,
// length and radius from them (before the inflow, which reads them).
void parseMesh(const Checker& c, const Json& v, const Json& raw, const Scene& s, const std::filesystem::path& baseDir, Vessel& w) {
  for (const char* key : {"start_m", "length_m", "radius_m", "anchor_ends", "sac_radius_m", "neck_width_m", "sac_stiffness_scale", "sac_strength_scale",
                          "bulge_radius_m", "bulge_length_m", "branch_angle_deg", "branch_length_m"}) {
    if (raw.contains(key)) c.fail(std::string("vessel.") + key, "does not apply to a mesh vessel (the mesh gives the geometry)");
  }
  const Json& m = v["mesh"];
  const std::string file = m["file"].get<std::string>();
  if (file.empty()) c.fail("vessel.mesh.file", "is required for vessel.shape \"mesh\"");
  std::filesystem::path path(file);
  if (path.is_relative() && !baseDir.empty()) path = baseDir / path;
  io::TriangleMesh mesh;
  try {
    mesh = io::readMesh(path);
  } catch (const io::MeshError& e) {
    c.fail("vessel.mesh.file", e.what());
  }
  const double unit = m["unit_m"].get<double>();
  for (glm::dvec3& p : mesh.vertices) p *= unit;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const glm::dvec3& p : mesh.vertices) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const double across = glm::length(hi - lo);
  // The largest vessels (the aorta) are centimetres across; a mesh metres across was read in
  // the wrong unit.
  if (!(across <= 0.5)) {
    c.fail("vessel.mesh.unit_m", "makes the mesh " + fmt(across) + " m across (with unit_m = " + fmt(unit) +
                                     "): no blood vessel is that large; if the file is in millimetres, set unit_m to 0.001");
  }
  std::shared_ptr<const VesselMesh> vm;
  try {
    vm = std::make_shared<const VesselMesh>(std::move(mesh));
  } catch (const std::invalid_argument& e) {
    c.fail("vessel.mesh.file", path.string() + ": " + e.what());
  }
  const auto& loops = vm->ends();
  const Json& ends = m["ends"];
  std::vector<int> claimed(loops.size(), -1);
  for (std::size_t k = 0; k < ends.size(); ++k) {
    const std::string p = "vessel.mesh.ends[" + std::to_string(k) + "]";
    const glm::dvec3 at(vec3(ends[k]["at_m"]));
    int best = -1;
    double bestDistance = std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < loops.size(); ++e) {
      const double d = glm::length(at - loops[e].centroid);
      if (d <= std::max(loops[e].radius, 2.0 * double(s.sph.spacing)) && d < bestDistance) best = int(e), bestDistance = d;
    }
    if (best < 0) {
      std::string where;
      for (const MeshEnd& e : loops) where += (where.empty() ? "" : ", ") + fmtPoint(e.centroid);
      c.fail(p + ".at_m", "no open end of the mesh has its centre within its radius of " + fmtPoint(at) +
                              (loops.empty() ? std::string(" (the mesh is closed)") : " (its open ends are at " + where + ")"));
    }
    if (claimed[std::size_t(best)] >= 0) {
      c.fail(p + ".at_m", "names the same end as vessel.mesh.ends[" + std::to_string(claimed[std::size_t(best)]) + "]");
    }
    claimed[std::size_t(best)] = int(k);
  }
  w.endRoles.assign(loops.size(), "");
  for (std::size_t e = 0; e < loops.size(); ++e) {
    if (claimed[e] < 0) {
      c.fail("vessel.mesh.ends", "the mesh has an open boundary loop (a hole) at " + fmtPoint(loops[e].centroid) + ", about " +
                                     fmt(2.0 * loops[e].radius) + " m across, that no entry names: close it in the mesh, or name it an inlet or outlet");
    }
    w.endRoles[e] = ends[std::size_t(claimed[e])]["role"].get<std::string>();
  }
  const bool open = raw.contains("outlet") && raw["outlet"].is_object() && raw["outlet"].value("condition", "none") != "none";
  // An outlet's own pressure (vessel.mesh.ends[k].pressure_Pa; parseOutlet takes it).
  const Json* rawEnds = raw.contains("mesh") && raw["mesh"].contains("ends") ? &raw["mesh"]["ends"] : nullptr;
  for (std::size_t k = 0; k < ends.size(); ++k) {
    const bool given = rawEnds && k < rawEnds->size() && (*rawEnds)[k].contains("pressure_Pa");
    if (!given) continue;
    const std::string p = "vessel.mesh.ends[" + std::to_string(k) + "].pressure_Pa";
    if (ends[k]["role"].get<std::string>() != "outlet") c.fail(p, "applies to an outlet, not to the inlet (its pressure is vessel.inflow.pressure_Pa)");
    if (!open) c.fail(p, "applies to a pressure outlet of a vessel with open ends (vessel.outlet.condition \"pressure\")");
    w.meshEndPressures[k] = ends[k]["pressure_Pa"].get<float>();
  }
  if (!loops.empty() && !s.sph.periodic[0] && !open) {
    c.fail("domain.periodic", "a mesh vessel with open ends needs either a periodic x axis with its ends on the two planes, or open "
                              "inlets and outlets (vessel.outlet.condition \"flow\" or \"pressure\")");
  }
  const MeshEnd* inlet = nullptr;
  for (std::size_t e = 0; e < loops.size(); ++e) {
    if (w.endRoles[e] == "inlet" && (!inlet || loops[e].centroid.x < inlet->centroid.x)) inlet = &loops[e];
  }
  const glm::dvec3 centre = inlet ? inlet->centroid : 0.5 * (lo + hi);
  w.start = glm::vec3(s.sph.periodic[0] ? double(s.domain.min.x) : lo.x, centre.y, centre.z);
  w.length = s.sph.periodic[0] ? s.domain.max.x - s.domain.min.x : float(hi.x - lo.x);
  w.radius = float(inlet ? inlet->radius : 2.0 * vm->volume() / vm->area());
  if (open) {
    // Open ends (vessel.outlet): one inlet and one or more outlets (a branching vessel), each
    // in its own frame.
    std::size_t inlets = 0, outlets = 0;
    for (const std::string& role : w.endRoles) (role == "inlet" ? inlets : outlets) += 1;
    if (inlets != 1 || outlets < 1 || outlets + 1 > sim::OpenEnds::kMaxEnds) {
      c.fail("vessel.mesh.ends", "open ends (vessel.outlet) on a mesh vessel take one inlet and 1 to " +
                                     std::to_string(sim::OpenEnds::kMaxEnds - 1) + " outlets, got " + std::to_string(inlets) +
                                     " inlets and " + std::to_string(outlets) + " outlets");
    }
    auto frame = [](const MeshEnd& e) {
      sim::OpenEnd f;
      f.origin = glm::vec3(e.centroid);
      f.axis = glm::vec3(-e.normal);
      f.radius = float(e.radius);
      return f;
    };
    w.meshInlet = frame(*inlet);
    w.start = w.meshInlet.origin;
    // (the length: the nearest outlet's distance, which bounds the buffers)
    w.length = 3.0e38f;
    // (the outlets in the order of the scene's entries)
    for (std::size_t k = 0; k < ends.size(); ++k) {
      for (std::size_t e = 0; e < loops.size(); ++e) {
        if (claimed[e] != int(k) || w.endRoles[e] != "outlet") continue;
        w.meshOutlets.push_back(frame(loops[e]));
        w.meshOutletEntries.push_back(k);
        w.length = std::min(w.length, float(glm::length(loops[e].centroid - inlet->centroid)));
      }
    }
  }
  if (raw.contains("inflow") && raw["inflow"].value("profile", "none") != "none") {
    if (!inlet) c.fail("vessel.mesh.ends", "vessel.inflow needs an end with role \"inlet\"");
    if (!open && std::abs(inlet->centroid.x - double(s.domain.min.x)) > 1e-3 * s.sph.spacing) {
      c.fail("vessel.mesh.ends", "the inlet must be the end on the plane x = domain min x (" + fmt(s.domain.min.x) +
                                     " m), where the inflow zone starts (for flow along -x give a negative vessel.inflow.mean_speed_m_s)");
    }
  }
  // The wall's outer layer reaches layers dp out; one more spacing of room around it.
  const double room = double(w.layers + 1) * s.sph.spacing;
  const Box need{glm::vec3(s.sph.periodic[0] ? glm::dvec3(s.domain.min.x, lo.y - room, lo.z - room) : lo - room),
                 glm::vec3(s.sph.periodic[0] ? glm::dvec3(s.domain.max.x, hi.y + room, hi.z + room) : hi + room)};
  const float slack = 1e-4f * s.sph.spacing;
  if (!inside(need, s.domain, slack)) {
    c.fail("vessel.mesh", "the mesh with its wall (x " + fmt(need.min.x) + ".." + fmt(need.max.x) + ", y " + fmt(need.min.y) + ".." +
                              fmt(need.max.y) + ", z " + fmt(need.min.z) + ".." + fmt(need.max.z) + " m) reaches outside the domain");
  }
  for (std::size_t k = 0; k < m["regions"].size(); ++k) {
    const Json& r = m["regions"][k];
    MeshRegion region;
    region.centre = vec3(r["centre_m"]);
    region.radius = r["radius_m"].get<float>();
    region.stiffnessScale = r["stiffness_scale"].get<float>();
    region.strengthScale = r["strength_scale"].get<float>();
    // A region must hold some of the wall: its sphere reaches the surface's box.
    const glm::dvec3 nearest = glm::clamp(glm::dvec3(region.centre), lo, hi);
    if (!(glm::length(nearest - glm::dvec3(region.centre)) < double(region.radius) + room)) {
      c.fail("vessel.mesh.regions[" + std::to_string(k) + "].centre_m", "the region's sphere does not reach the mesh's wall");
    }
    w.meshRegions.push_back(region);
  }
  w.mesh = std::move(vm);
}

void parseVessel(const Checker& c, const Json& v, const Json& raw, Scene& s, const std::filesystem::path& baseDir) {
  const std::string shape = v["shape"].get<std::string>();
  auto given = [&](const char* key) { return raw.contains(key); };
  if (shape == "none") {
    for (auto it = raw.begin(); it != raw.end(); ++it) {
      if (it.key() != "shape") c.fail("vessel." + it.key(), "is set but vessel.shape is not (\"tube\", \"saccular_aneurysm\", \"fusiform_aneurysm\", \"bifurcation\" or \"mesh\")");
    }
    return;
  }
  Vessel w;
  w.shape = shape == "mesh"                ? Vessel::Shape::Mesh
            : shape == "tube"              ? Vessel::Shape::Tube
            : shape == "saccular_aneurysm" ? Vessel::Shape::SaccularAneurysm
            : shape == "fusiform_aneurysm" ? Vessel::Shape::FusiformAneurysm
                                           : Vessel::Shape::Bifurcation;
  w.start = vec3(v["start_m"]);
  w.length = v["length_m"].get<float>();
  w.radius = v["radius_m"].get<float>();
  w.layers = v["layers"].get<std::uint32_t>();
  w.pointMass = v["point_mass_kg"].get<float>();
  w.stiffness = v["stiffness_N_m"].get<float>();
  w.damping = v["damping_N_s_m"].get<float>();
  w.maxForce = v["max_force_N"].get<float>();
  w.anchorEnds = v["anchor_ends"].get<bool>();
  w.sacRadius = v["sac_radius_m"].get<float>();
  w.neckWidth = v["neck_width_m"].get<float>();
  w.sacStiffnessScale = v["sac_stiffness_scale"].get<float>();
  w.sacStrengthScale = v["sac_strength_scale"].get<float>();
  w.bulgeRadius = v["bulge_radius_m"].get<float>();
  w.bulgeLength = v["bulge_length_m"].get<float>();
  w.branchAngle = float(v["branch_angle_deg"].get<double>() * std::numbers::pi / 180.0);
  w.branchLength = v["branch_length_m"].get<float>();
  w.timeStepFactor = v["time_step_factor"].get<float>();
  w.substeps = v["substeps"].get<std::uint32_t>();
  const bool meshed = w.shape == Vessel::Shape::Mesh;
  if (meshed) {
    parseMesh(c, v, raw, s, baseDir, w);
  } else if (given("mesh")) {
    c.fail("vessel.mesh", "only applies to vessel.shape \"mesh\"");
  }
  for (const char* key : {"length_m", "radius_m", "point_mass_kg"}) {
    if (meshed && std::string(key) != "point_mass_kg") continue;
    if (!given(key) || !(v[key].get<double>() > 0.0)) c.fail(std::string("vessel.") + key, "is required (and positive) for a " + shape);
  }
  w.youngsModulus = v["youngs_modulus_Pa"].get<float>();
  w.poissonRatio = v["poisson_ratio"].get<float>();
  w.wallThickness = v["wall_thickness_m"].get<float>();
  w.failureStress = v["failure_stress_Pa"].get<float>();
  if (given("youngs_modulus_Pa") == given("stiffness_N_m")) {
    c.fail("vessel.stiffness_N_m", "give either stiffness_N_m or youngs_modulus_Pa (with wall_thickness_m), not " +
                                       std::string(given("stiffness_N_m") ? "both" : "neither"));
  }
  if (given("stiffness_N_m") && !(w.stiffness > 0.0f)) c.fail("vessel.stiffness_N_m", "must be positive");
  if (given("max_force_N") && given("failure_stress_Pa")) c.fail("vessel.failure_stress_Pa", "give either max_force_N or failure_stress_Pa, not both");
  const bool tissue = given("youngs_modulus_Pa") || given("failure_stress_Pa");
  if (tissue && !(w.wallThickness > 0.0f)) c.fail("vessel.wall_thickness_m", "is required (and positive) with youngs_modulus_Pa or failure_stress_Pa");
  if (!tissue && (given("wall_thickness_m") || given("poisson_ratio"))) {
    c.fail(given("wall_thickness_m") ? "vessel.wall_thickness_m" : "vessel.poisson_ratio", "only applies with youngs_modulus_Pa or failure_stress_Pa");
  }
  for (const char* key : {"youngs_modulus_Pa", "failure_stress_Pa"}) {
    if (given(key) && !(v[key].get<double>() > 0.0)) c.fail(std::string("vessel.") + key, "must be positive");
  }
  if (!(w.poissonRatio < 0.5f)) c.fail("vessel.poisson_ratio", "must be below 0.5 (an incompressible membrane has no finite hoop stiffness here)");
  if (w.shape != Vessel::Shape::Bifurcation) {
    for (const char* key : {"branch_angle_deg", "branch_length_m"}) {
      if (given(key)) c.fail(std::string("vessel.") + key, "only applies to a bifurcation (vessel.shape \"bifurcation\")");
    }
  }
  if (meshed) {
    // (parseMesh rejected the analytic shapes' keys)
  } else if (w.shape == Vessel::Shape::Tube || w.shape == Vessel::Shape::Bifurcation) {
    for (const char* key : {"sac_radius_m", "neck_width_m", "sac_stiffness_scale", "sac_strength_scale", "bulge_radius_m", "bulge_length_m"}) {
      if (given(key)) c.fail(std::string("vessel.") + key, "only applies to an aneurysm (vessel.shape \"saccular_aneurysm\" or \"fusiform_aneurysm\")");
    }
  } else {
    const std::array<const char*, 2> sac{"sac_radius_m", "neck_width_m"}, bulge{"bulge_radius_m", "bulge_length_m"};
    const bool saccular = w.shape == Vessel::Shape::SaccularAneurysm;
    for (const char* key : saccular ? bulge : sac) {
      if (given(key)) c.fail(std::string("vessel.") + key, "does not apply to a " + shape);
    }
    for (const char* key : saccular ? sac : bulge) {
      if (!given(key) || !(v[key].get<double>() > 0.0)) c.fail(std::string("vessel.") + key, "is required (and positive) for a " + shape);
    }
  }
  parseInflow(c, v["inflow"], raw.contains("inflow") ? raw["inflow"] : Json::object(), s, w,
              v["outlet"]["condition"].get<std::string>() != "none");
  parseOutlet(c, v["outlet"], v["inflow"], s, w);
  if (w.radius < 2.0f * s.sph.spacing) c.fail("vessel.radius_m", "must be at least two particle spacings (" + fmt(2.0 * s.sph.spacing) + " m)");
  w.periodic = s.sph.periodic[0];
  if (s.sph.periodic[1] || s.sph.periodic[2]) c.fail("domain.periodic", "a vessel allows only x to be periodic (its axis)");
  const float slack = 1e-4f * s.sph.spacing;
  if (w.periodic) {
    if (!meshed && (std::abs(w.start.x - s.domain.min.x) > slack || std::abs(w.start.x + w.length - s.domain.max.x) > slack)) {
      c.fail("vessel.length_m", "a periodic vessel must span the domain along x (start_m x = domain min x, length_m = " +
                                    fmt(double(s.domain.max.x) - s.domain.min.x) + " m)");
    }
  }
  // The wall's outer layer reaches radius + layers dp; one more spacing of room around it.
  const float room = float(w.layers + 1) * s.sph.spacing;
  float halfWidth = w.radius + room, top = w.radius + room;
  if (w.shape == Vessel::Shape::FusiformAneurysm) {
    if (!(w.bulgeRadius > w.radius)) c.fail("vessel.bulge_radius_m", "must exceed vessel.radius_m");
    top = halfWidth = w.bulgeRadius + room;
  }
  if (w.shape == Vessel::Shape::SaccularAneurysm) {
    const double hw = 0.5 * w.neckWidth;
    if (hw >= w.radius || hw >= w.sacRadius) c.fail("vessel.neck_width_m", "must be narrower than the tube's and the sac's diameters");
    top = float(sacCentreOffset(w.radius, w.sacRadius, w.neckWidth)) + w.sacRadius + room;
    halfWidth = std::max(halfWidth, w.sacRadius + room);
  }
  if (w.shape == Vessel::Shape::Bifurcation) {
    if (!given("branch_length_m") || !(w.branchLength > 0.0f)) c.fail("vessel.branch_length_m", "is required (and positive) for a bifurcation");
    const bool open = w.inflow && w.inflow->open;
    if (!w.periodic && !open) {
      c.fail("domain.periodic", "a bifurcation needs a periodic x axis (the merged flow returns through the seam) or open ends (vessel.outlet)");
    }
    try {
      const BifurcationGeometry g = bifurcationGeometry(vesselSpec(w, s.sph));
      halfWidth = float(g.joints[1].y - w.start.y) + w.radius + room;
      if (w.inflow && float(g.joints[0].x) - w.radius < w.inflow->zoneEnd) {
        c.fail("vessel.inflow.zone_length_m", "the inflow zone (to x = " + fmt(w.inflow->zoneEnd) + " m) must end a radius before the split at x = " +
                                                  fmt(g.joints[0].x) + " m (lengthen the tube or shorten the branches)");
      }
      // (open ends: the outlet's buffer likewise, a radius past the merge)
      if (open) {
        const sim::OpenEnd& outlet = w.inflow->open->outlets[0];
        const float plane = outlet.origin.x - outlet.length;
        if (plane - w.radius < float(g.joints[2].x)) {
          c.fail("vessel.outlet.buffer_length_m", "the outlet buffer (from x = " + fmt(plane) + " m) must start a radius after the merge at x = " +
                                                      fmt(g.joints[2].x) + " m (lengthen the tube or shorten the branches)");
        }
      }
    } catch (const std::invalid_argument& e) {
      c.fail("vessel", e.what());
    }
  }
  const Box need{glm::vec3(w.start.x, w.start.y - halfWidth, w.start.z - w.radius - room),
                 glm::vec3(w.start.x + w.length, w.start.y + halfWidth, w.start.z + top)};
  if (!meshed && !inside(need, s.domain, slack)) {  // (parseMesh checked the mesh's box)
    c.fail("vessel", "the vessel with its wall (x " + fmt(need.min.x) + ".." + fmt(need.max.x) + ", y " + fmt(need.min.y) + ".." +
                         fmt(need.max.y) + ", z " + fmt(need.min.z) + ".." + fmt(need.max.z) + " m) reaches outside the domain");
  }
  if (tissue) {  // springs fitted to the built layout
    try {
      const double E = given("youngs_modulus_Pa") ? w.youngsModulus : 1.0, sigma = given("failure_stress_Pa") ? w.failureStress : 1.0;
      TissueSprings fit;
      if (meshed) {
        AneurysmSpec unit = vesselSpec(w, s.sph);
        unit.tube.stiffness = unit.tube.maxForce = 1.0f;
        fit = springsFromMeshTissue(*w.mesh, buildMeshVessel(unit), E, w.poissonRatio, w.wallThickness, sigma);
      } else {
        fit = springsFromTissue(vesselSpec(w, s.sph).tube, E, w.poissonRatio, w.wallThickness, sigma);
      }
      if (given("youngs_modulus_Pa")) w.stiffness = fit.stiffness;
      if (given("failure_stress_Pa")) w.maxForce = fit.maxForce;
    } catch (const std::invalid_argument& e) {
      c.fail("vessel", e.what());
    }
  }
  s.vessel = w;
}

void parseTools(const Checker& c, const Json& tools, const Json& raw, Scene& s) {
  if (tools.size() > HEMO_TOOL_MAX_TOOLS) {
    c.fail("tools", "at most " + std::to_string(HEMO_TOOL_MAX_TOOLS) + " tools, got " + std::to_string(tools.size()));
  }
  const float slack = 1e-6f * s.sph.spacing;
  for (std::size_t k = 0; k < tools.size(); ++k) {
    const std::string p = "tools[" + std::to_string(k) + "]";
    const Json& t = tools[k];
    sim::ToolSpec tool;
    tool.name = t["name"].get<std::string>();
    if (tool.name.empty()) c.fail(p + ".name", "must not be empty");
    for (const sim::ToolSpec& other : s.tools) {
      if (other.name == tool.name) c.fail(p + ".name", "\"" + tool.name + "\" names another tool too");
    }
    const std::string kind = t["kind"].get<std::string>();
    tool.kind = kind == "blade" ? sim::ToolKind::Blade : kind == "grasper" ? sim::ToolKind::Grasper : sim::ToolKind::Probe;
    if (tool.kind == sim::ToolKind::Blade && !(t["length_m"].get<double>() > 0.0)) {
      c.fail(p + ".length_m", "a blade needs an edge: length_m must be positive");
    }
    tool.radius = t["radius_m"].get<float>();
    tool.length = t["length_m"].get<float>();
    tool.contactDistance = t["contact_distance_m"].get<float>();
    if (tool.contactDistance == 0.0f) tool.contactDistance = s.sph.spacing;
    tool.contactScale = t["contact_scale"].get<float>();
    tool.jawWidth = t["jaw_width_m"].get<float>();
    if (tool.jawWidth > 0.0f && tool.kind != sim::ToolKind::Grasper) c.fail(p + ".jaw_width_m", "only a grasper has jaws");
    const bool grip = t["grip"].get<bool>();
    const float gripStiffness = t["grip_stiffness_N_m"].get<float>();
    const bool gripGiven = k < raw.size() && raw[k].is_object() && raw[k].contains("grip");
    if (tool.kind != sim::ToolKind::Grasper && ((gripGiven && grip) || gripStiffness != 0.0f)) {
      c.fail(p + (gripStiffness != 0.0f ? ".grip_stiffness_N_m" : ".grip"), "only a grasper grips (tools[].kind \"grasper\")");
    }
    if (tool.kind == sim::ToolKind::Grasper && grip) {  // (without a vessel there is nothing to grip)
      tool.gripStiffness = gripStiffness > 0.0f ? gripStiffness : s.vessel ? s.vessel->stiffness : 0.0f;
    }
    if (tool.contactDistance > s.sph.supportRadius()) {
      c.fail(p + ".contact_distance_m", "must not exceed the kernel support 2h = " + fmt(s.sph.supportRadius()) + " m");
    }
    const Json& path = t["path"];
    if (path.size() > HEMO_TOOL_MAX_KEYS) {
      c.fail(p + ".path", "at most " + std::to_string(HEMO_TOOL_MAX_KEYS) + " keyframes, got " + std::to_string(path.size()));
    }
    for (std::size_t m = 0; m < path.size(); ++m) {
      const std::string kp = p + ".path[" + std::to_string(m) + "]";
      const Json& key = path[m];
      sim::ToolKey tk;
      tk.time = key["time_s"].get<double>();
      tk.position = vec3(key["position_m"]);
      tk.cutting = key["cutting"].get<bool>();
      if (tk.cutting && tool.kind != sim::ToolKind::Blade) c.fail(kp + ".cutting", "only a blade cuts (tools[].kind \"blade\")");
      tk.jawOpening = key["jaw_opening_m"].get<float>();
      if (key.contains("jaw_opening_m") && tk.jawOpening != 0.0f && tool.kind != sim::ToolKind::Grasper) {
        c.fail(kp + ".jaw_opening_m", "only a grasper has jaws (tools[].kind \"grasper\")");
      }
      const Json& q = key["orientation_wxyz"];
      if (q.size() != 4) c.fail(kp + ".orientation_wxyz", "expected 4 numbers (w, x, y, z), got " + q.dump());
      const glm::dquat dq(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>());
      const double norm = std::sqrt(dq.w * dq.w + dq.x * dq.x + dq.y * dq.y + dq.z * dq.z);
      if (!(norm > 1e-6)) c.fail(kp + ".orientation_wxyz", "must not be zero (a rotation as a quaternion w, x, y, z)");
      tk.orientation = glm::quat(float(dq.w / norm), float(dq.x / norm), float(dq.y / norm), float(dq.z / norm));
      if (m > 0 && !(tk.time > tool.keys.back().time)) {
        c.fail(kp + ".time_s", "keyframes must be in time order: " + fmt(tk.time) + " s is not after the previous keyframe's " +
                                   fmt(tool.keys.back().time) + " s");
      }
      if (!inside(Box{tk.position, tk.position}, s.domain, slack)) {
        c.fail(kp + ".position_m", "the tool's tip lies outside the domain");
      }
      if (m > 0) {
        const sim::ToolKey& prev = tool.keys.back();
        const double speed = double(glm::length(tk.position - prev.position)) / (tk.time - prev.time);
        if (speed > double(s.sph.soundSpeed)) {
          c.fail(kp + ".position_m", "the tool's tip moves at " + fmt(speed) + " m/s from the previous keyframe, faster than the speed of sound c0 = " +
                                         fmt(s.sph.soundSpeed) + " m/s");
        }
      }
      tool.keys.push_back(tk);
    }
    // On a periodic axis the contact takes the minimum image of a particle's offset from the
    // tip: the tool's reach along that axis (at its keys' orientations and halfway between
    // them) must stay under half the period.
    glm::vec3 reach(0.0f);
    for (std::size_t m = 0; m < tool.keys.size(); ++m) {
      std::vector<glm::quat> turns{tool.keys[m].orientation};
      if (m > 0) turns.push_back(glm::normalize(tool.keys[m - 1].orientation + tool.keys[m].orientation));
      float opening = tool.keys[m].jawOpening;
      if (m > 0) opening = std::max(opening, tool.keys[m - 1].jawOpening);
      for (const glm::quat& q : turns) {
        const glm::vec3 axis = q * glm::vec3(0.0f, 0.0f, 1.0f), side = q * glm::vec3(1.0f, 0.0f, 0.0f);
        const glm::vec3 lateral = glm::cross(axis, side);
        const glm::vec3 jaws = tool.kind == sim::ToolKind::Grasper
                                   ? (0.5f * opening + tool.radius) * glm::abs(side) + 0.5f * tool.jawWidth * glm::abs(lateral)
                                   : glm::vec3(0.0f);
        reach = glm::max(reach, tool.radius + tool.contactDistance + tool.length * glm::abs(axis) + jaws);
      }
    }
    for (int a = 0; a < 3; ++a) {
      const float period = s.domain.max[a] - s.domain.min[a];
      if (s.sph.periodic[a] && !(reach[a] < 0.5f * period)) {
        c.fail(p + ".radius_m", "the tool reaches " + fmt(reach[a]) + " m from its tip along " + std::string(1, "xyz"[a]) +
                                    ", more than half the period there (" + fmt(0.5 * period) + " m)");
      }
    }
    try {
      tool.validate();
    } catch (const std::invalid_argument& e) {
      c.fail(p, e.what());
    }
    s.tools.push_back(tool);
  }
}

}  // namespace

void checkPeriodicAxes(const Scene& s, const std::string& source, int onlyAxis) {
  const Checker c(source);
  const float slack = 1e-6f * s.sph.spacing;
  for (int a = 0; a < 3; ++a) {
    if (!s.sph.periodic[a] || (onlyAxis >= 0 && a != onlyAxis)) continue;
    const std::string axis(1, "xyz"[a]);
    const double period = double(s.domain.max[a]) - s.domain.min[a];
    const double spacings = period / s.sph.spacing;
    if (std::abs(spacings - std::round(spacings)) > 1e-3) {
      c.fail("domain.periodic", "the period along " + axis + " (" + fmt(period) + " m) must be a whole number of spacings dp = " +
                                    fmt(s.sph.spacing) + " m (it is " + fmt(spacings) + ")");
    }
    const double listRadius = s.sph.listRadius();
    // The neighbour grid's cells are half a list radius and a particle scans two cells either
    // side, so a period needs 5 distinct cells (sph.cpp, gridFor).
    if (period < 2.5 * listRadius * (1.0 - 1e-6)) {
      c.fail("domain.periodic", "the period along " + axis + " (" + fmt(period) + " m) must be at least 2.5 neighbour-list radii (" +
                                    fmt(2.5 * listRadius) + " m)");
    }
    for (std::size_t k = 0; k < s.tanks.size(); ++k) {
      const Box& b = s.tanks[k].box;
      if (std::abs(b.min[a] - s.domain.min[a]) > slack || std::abs(b.max[a] - s.domain.max[a]) > slack) {
        c.fail("boundary.tanks[" + std::to_string(k) + "]", "must span the domain along the periodic axis " + axis +
                                                              " (min_m and max_m equal to the domain's there)");
      }
    }
  }
}

Scene parseScene(const std::string& text, const std::string& source, const std::filesystem::path& baseDir) {
  Json raw;
  try {
    raw = Json::parse(text);
  } catch (const Json::exception& e) {  // syntax errors, and numbers that overflow a double
    throw SceneError(source + ": not valid JSON: " + e.what());
  }
  const Checker c(source);
  const Json j = c.object("", raw, schema());

  Scene s;
  s.name = j["scene"].get<std::string>();
  if (s.name.empty()) c.fail("scene", "must not be empty");
  s.description = j["description"].get<std::string>();

  const Json& part = j["particles"];
  s.sph.spacing = part["spacing_m"].get<float>();
  s.sph.smoothingRatio = part["smoothing_ratio"].get<float>();
  s.sph.neighbourCapacity = part["neighbour_capacity"].get<std::uint32_t>();
  s.sph.listSkin = part["list_skin"].get<float>();
  {
    const std::string layout = part["list_layout"].get<std::string>();
    s.sph.listLayout = layout == "interleaved"  ? sim::ListLayout::Interleaved
                       : layout == "contiguous" ? sim::ListLayout::Contiguous
                       : layout == "clusters"   ? sim::ListLayout::Clusters
                                                : sim::ListLayout::Auto;
  }
  {
    const std::string search = part["neighbour_search"].get<std::string>();
    s.sph.neighbourSearch = search == "list"    ? sim::NeighbourSearch::List
                            : search == "cells" ? sim::NeighbourSearch::Cells
                                                : sim::NeighbourSearch::Auto;
  }

  const Json& fluid = j["fluid"];
  s.sph.restDensity = fluid["density_kg_m3"].get<float>();
  s.sph.viscosity = fluid["viscosity_pa_s"].get<float>();
  {
    const Json& r = fluid["rheology"];
    const Json& given = raw.contains("fluid") && raw["fluid"].contains("rheology") ? raw["fluid"]["rheology"] : Json::object();
    if (r["model"].get<std::string>() == "carreau_yasuda") {
      s.sph.rheology = sim::Rheology::CarreauYasuda;
      if (raw["fluid"].contains("viscosity_pa_s")) {
        c.fail("fluid.viscosity_pa_s", "does not apply with fluid.rheology.model \"carreau_yasuda\" (the law gives each particle its viscosity)");
      }
      s.sph.carreau = {r["zero_shear_viscosity_pa_s"].get<float>(), r["infinite_shear_viscosity_pa_s"].get<float>(),
                       r["relaxation_time_s"].get<float>(), r["power_index"].get<float>(), r["yasuda_exponent"].get<float>()};
      if (s.sph.carreau.muInf > s.sph.carreau.mu0) {
        c.fail("fluid.rheology.infinite_shear_viscosity_pa_s", "must not exceed zero_shear_viscosity_pa_s (" + fmt(s.sph.carreau.mu0) + " Pa s)");
      }
    } else {
      for (auto it = given.begin(); it != given.end(); ++it) {
        if (it.key() != "model") c.fail("fluid.rheology." + it.key(), "only applies with fluid.rheology.model \"carreau_yasuda\"");
      }
    }
  }
  s.expectedMaxSpeed = fluid["expected_max_speed_m_s"].get<float>();
  const float c0 = fluid["speed_of_sound_m_s"].get<float>();
  s.sph.soundSpeed = c0 > 0.0f ? c0 : 10.0f * s.expectedMaxSpeed;
  s.sph.clampNegativePressure = fluid["clamp_negative_pressure"].get<bool>();
  s.sph.sps = fluid["turbulence"].get<std::string>() == "sps";
  s.sph.densityMethod = fluid["density"].get<std::string>() == "continuity" ? sim::DensityMethod::Continuity
                                                                            : sim::DensityMethod::Summation;
  s.sph.deltaSph = fluid["delta_sph"].get<float>();
  s.sph.pressureSolver = fluid["solver"].get<std::string>() == "dfsph" ? sim::PressureSolver::Dfsph : sim::PressureSolver::Wcsph;
  s.sph.solverTolerance = fluid["solver_tolerance"].get<float>();
  s.sph.solverMaxIterations = fluid["solver_max_iterations"].get<std::uint32_t>();
  s.sph.solverCompressible = fluid["solver_compressible"].get<bool>();
  s.sph.smagorinsky = fluid["smagorinsky_constant"].get<float>();
  s.sph.blinn = fluid["blinn_constant"].get<float>();
  s.sph.backgroundPressure = fluid["background_pressure_Pa"].get<float>();
  s.sph.backgroundPressureRamp = fluid["background_pressure_ramp_s"].get<float>();
  for (std::size_t k = 0; k < fluid["blocks"].size(); ++k) {
    const std::string p = "fluid.blocks[" + std::to_string(k) + "]";
    const Json& b = fluid["blocks"][k];
    s.blocks.push_back({box(c, p, b), vec3(b["velocity_m_s"]),
                        b["lattice"].get<std::string>() == "bcc" ? FluidBlock::Lattice::BodyCentred : FluidBlock::Lattice::Cubic});
  }

  const Json& boundary = j["boundary"];
  for (std::size_t k = 0; k < boundary["tanks"].size(); ++k) {
    const std::string p = "boundary.tanks[" + std::to_string(k) + "]";
    const Json& t = boundary["tanks"][k];
    s.tanks.push_back({box(c, p, t), t["layers"].get<std::uint32_t>(), t["open_top"].get<bool>()});
  }
  s.sph.repulsionScale = boundary["repulsion_scale"].get<float>();
  s.sph.repulsionCutoffRatio = boundary["repulsion_cutoff_ratio"].get<float>();
  if (s.sph.repulsionCutoffRatio > 2.0f * s.sph.smoothingRatio) {
    c.fail("boundary.repulsion_cutoff_ratio", "D must not exceed the kernel support 2h/dp = " + fmt(2.0 * s.sph.smoothingRatio));
  }

  s.sph.gravity = vec3(j["forces"]["gravity_m_s2"]);
  s.sph.bodyForce = vec3(j["forces"]["body_force_m_s2"]);

  const Json& time = j["time"];
  s.sph.integrator = time["integrator"].get<std::string>() == "rk2_midpoint" ? sim::Integrator::Rk2Midpoint
                                                                            : sim::Integrator::SymplecticEuler;
  s.sph.cflAcoustic = time["cfl_acoustic"].get<float>();
  s.sph.cflForce = time["cfl_force"].get<float>();
  s.sph.maxTimeStep = time["max_dt_s"].get<float>();
  s.endTime = time["end_time_s"].get<double>();
  s.minTimeStep = time["min_dt_s"].get<double>();
  s.stepsPerBatch = time["steps_per_batch"].get<std::uint32_t>();
  s.sph.dampingRate = time["settle_damping_1_s"].get<float>();
  s.sph.dampingUntil = time["settle_until_s"].get<float>();

  s.surface.resolution = j["surface"]["grid_resolution"].get<std::uint32_t>();
  s.surface.iso = j["surface"]["iso_level"].get<float>();
  s.surface.maxTriangles = j["surface"]["max_triangles"].get<std::uint32_t>();
  s.surface.splatVoxelOverH = j["surface"]["splat_voxel_h"].get<float>();

  s.domain = box(c, "domain", j["domain"]);
  const float slack = 1e-6f * s.sph.spacing;
  for (const auto& axisName : j["domain"]["periodic"]) {
    const int a = axisName.get<std::string>()[0] - 'x';
    s.sph.periodic[a] = true;
    for (auto& t : s.tanks) t.periodic[a] = true;
  }
  checkPeriodicAxes(s, source);
  parseVessel(c, j["vessel"], raw.contains("vessel") ? raw["vessel"] : Json::object(), s, baseDir);
  if (s.blocks.empty() && !s.vessel) c.fail("fluid.blocks", "needs at least 1 entry (or a vessel to fill)");
  for (std::size_t k = 0; k < s.blocks.size(); ++k) {
    if (!inside(s.blocks[k].box, s.domain, slack)) {
      c.fail("fluid.blocks[" + std::to_string(k) + "]", "lies (partly) outside the domain");
    }
  }
  for (std::size_t k = 0; k < s.tanks.size(); ++k) {
    const float reach = float(s.tanks[k].layers) * s.sph.spacing;
    const glm::vec3 grow = glm::mix(glm::vec3(reach), glm::vec3(0.0f), s.tanks[k].periodic);
    const Box outer{s.tanks[k].box.min - grow, s.tanks[k].box.max + grow};
    Box need = outer;
    if (s.tanks[k].openTop) need.max.z = s.tanks[k].box.max.z;
    if (!inside(need, s.domain, slack)) {
      c.fail("boundary.tanks[" + std::to_string(k) + "]",
             "its " + std::to_string(s.tanks[k].layers) + " layers of boundary particles reach outside the domain");
    }
  }
  parseTools(c, j["tools"], raw.contains("tools") ? raw["tools"] : Json::array(), s);
  if (s.vessel && s.vessel->substeps > 1 && s.sph.integrator != sim::Integrator::SymplecticEuler) {
    c.fail("vessel.substeps", "above 1 needs time.integrator \"symplectic_euler\" (the wall's substeps are symplectic Euler)");
  }
  if (s.sph.pressureSolver == sim::PressureSolver::Dfsph) {
    const char* why = s.sph.densityMethod != sim::DensityMethod::Summation ? "needs fluid.density \"summation\""
                      : s.sph.integrator != sim::Integrator::SymplecticEuler ? "steps with time.integrator \"symplectic_euler\""
                      : s.sph.neighbourSearch == sim::NeighbourSearch::Cells ? "needs particles.neighbour_search \"list\" or \"auto\""
                      : s.sph.listLayout == sim::ListLayout::Clusters ? "does not walk clusters (particles.list_layout)"
                                                                       : nullptr;
    if (why) c.fail("fluid.solver", std::string("\"dfsph\" ") + why);
  }
  try {
    s.sph.validate();
  } catch (const std::invalid_argument& e) {
    throw SceneError(source + ": " + e.what());
  }
  return s;
}

Scene loadScene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path.string() + ": cannot open the scene file");
  std::ostringstream text;
  text << in.rdbuf();
  return parseScene(text.str(), path.string(), path.parent_path());
}

namespace {
void collect(const std::vector<Field>& fields, const std::string& prefix, std::vector<FieldDoc>& out) {
  for (const auto& f : fields) {
    const std::string path = prefix.empty() ? f.key : prefix + "." + f.key;
    FieldDoc d;
    d.path = path;
    d.type = f.kind == Kind::Choice || f.kind == Kind::ChoiceList ? std::string(f.kind == Kind::ChoiceList ? "array of " : "one of ") + [&] {
      std::string s;
      for (const auto& ch : f.choices) s += (s.empty() ? "" : ", ") + ("\"" + ch + "\"");
      return s;
    }() : kindName(f.kind);
    d.unit = f.unit == "1" ? "-" : f.unit;
    if (f.kind == Kind::Number || f.kind == Kind::Integer || f.kind == Kind::Vec3 || f.kind == Kind::NumberList) {
      d.range = std::string(f.minExclusive ? "(" : "[") + fmt(f.min) + ", " + fmt(f.max) + "]";
    } else if (f.kind == Kind::Objects) {
      d.range = ">= " + fmt(f.min) + " entries";
    }
    d.defaultValue = f.def.is_null() ? "required" : f.def.dump();
    if (f.kind == Kind::Section || f.kind == Kind::Objects) d.defaultValue = f.def.is_null() ? "required" : "optional";
    d.description = f.description;
    out.push_back(d);
    if (f.kind == Kind::Section) collect(f.items, path, out);
    if (f.kind == Kind::Objects) collect(f.items, path + "[]", out);
  }
}
}  // namespace

std::vector<FieldDoc> sceneSchema() {
  std::vector<FieldDoc> out;
  collect(schema(), "", out);
  return out;
}

std::string schemaMarkdown() {
  std::ostringstream s;
  s << "| key | type | unit | range | default | description |\n|---|---|---|---|---|---|\n";
  for (const auto& d : sceneSchema()) {
    s << "| `" << d.path << "` | " << d.type << " | " << d.unit << " | " << d.range << " | " << d.defaultValue << " | "
      << d.description << " |\n";
  }
  return s.str();
}

}  // namespace hemo::scene
