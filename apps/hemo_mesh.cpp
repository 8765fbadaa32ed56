// hemo-mesh: writes the project's own vessel surfaces as binary STL (hemo/scene/mesh_vessel.hpp,
// vesselSurface), for mesh scenes and tests: a tube along x, bent up and back over its length
// if asked, with a saccular aneurysm on the outer side of the bend's crest; or a branching
// vessel (branchSurface): a parent tube that splits into two daughters.
#include "cli.hpp"
#include "hemo/io/atomic_file.hpp"
#include "hemo/io/mesh.hpp"
#include "hemo/scene/mesh_vessel.hpp"

#include <cstdio>
#include <numbers>
#include <string>

int main(int argc, char** argv) {
  const char* usage =
      "usage: hemo-mesh --out FILE.stl --length-m L --radius-m R [--bend-height-m H] [--sac-radius-m RS --sac-offset-m C]\n"
      "                 [--straight-m S] [--around N] [--along M] [--unit-m U] [--help]\n"
      "  a tube of radius R from x = 0 to L whose axis rises to z = H at x = L/2 and falls back (z = H (1 - cos(2 pi x/L))/2),\n"
      "  with a spherical sac of radius RS centred C above the axis at x = L/2 (a saccular aneurysm on the bend's outer side);\n"
      "  with S > 0, straight runs of length S lead into the bend and out of it (all of it shifted S along x: the ends at\n"
      "  x = 0 and L + 2 S; open inlets and outlets want straight ends for their buffers);\n"
      "  N x M quads (M = 0: about square).\n"
      "hemo-mesh --out FILE.stl --length-m L --radius-m R --branch-angle-deg A --branch-radius-m RB --split-m X --spread-m Y\n"
      "          [--sac-radius-m RS --sac-offset-m C] [--cell-m H] [--unit-m U]\n"
      "  a branching vessel: a parent tube of radius R from x = 0 splits at x = X into two daughters of radius RB at +-A\n"
      "  degrees in the x-y plane, which turn parallel to x once Y off the axis and end at x = L; with a spherical sac of\n"
      "  radius RS centred C past the split on the axis (an aneurysm at the apex); marching cubes over the lumen on a grid\n"
      "  of H (default RB / 8).\n"
      "  Coordinates are written in units of U m (default 0.001: millimetres, as segmentation tools write them).\n"
      "  Prints the two open ends' centres in m (for the scene's vessel.mesh.ends).\n";
  if (hemo::cli::printUsageIfAsked(argc, argv, usage)) return 0;
  try {
    const auto args = hemo::cli::parse(argc, argv, {"--out", "--length-m", "--radius-m", "--bend-height-m", "--sac-radius-m", "--sac-offset-m",
                                                    "--straight-m", "--around", "--along", "--unit-m", "--branch-angle-deg",
                                                    "--branch-radius-m", "--split-m", "--spread-m", "--cell-m"});
    if (!args.positional.empty()) throw hemo::cli::UsageError("unexpected argument '" + args.positional[0] + "'");
    if (!args.has("--out")) throw hemo::cli::UsageError("--out FILE.stl is required");
    if (!args.has("--length-m") || !args.has("--radius-m")) throw hemo::cli::UsageError("--length-m and --radius-m are required");
    const double unit = args.number("--unit-m", 0.001, 1e-9, 1e3);
    const std::string out = args.text("--out");
    if (args.has("--sac-radius-m") != args.has("--sac-offset-m")) throw hemo::cli::UsageError("--sac-radius-m and --sac-offset-m go together");
    // Builds the surface (its parameter errors are usage errors) and writes it.
    auto write = [&](const auto& build, const char* what) {
      hemo::io::TriangleMesh mesh;
      try {
        mesh = build();
      } catch (const std::invalid_argument& e) {
        throw hemo::cli::UsageError(e.what());
      }
      for (glm::dvec3& p : mesh.vertices) p /= unit;
      hemo::io::writeStl(out, mesh, std::string(what) + ", unit " + std::to_string(unit) + " m");
      std::printf("wrote %s: %zu triangles, %zu vertices, unit %g m\n", out.c_str(), mesh.triangles.size(), mesh.vertices.size(), unit);
    };
    if (args.has("--branch-angle-deg")) {
      for (const char* key : {"--bend-height-m", "--straight-m", "--around", "--along"}) {
        if (args.has(key)) throw hemo::cli::UsageError(std::string(key) + " does not apply to a branching vessel (--branch-angle-deg)");
      }
      for (const char* key : {"--branch-radius-m", "--split-m", "--spread-m"}) {
        if (!args.has(key)) throw hemo::cli::UsageError(std::string(key) + " is required with --branch-angle-deg");
      }
      hemo::scene::BranchSurfaceSpec spec;
      spec.length = args.number("--length-m", 0.0, 1e-6, 1.0);
      spec.radius = args.number("--radius-m", 0.0, 1e-7, 0.5);
      spec.angle = args.number("--branch-angle-deg", 0.0, 1e-3, 80.0) * std::numbers::pi / 180.0;
      spec.branchRadius = args.number("--branch-radius-m", 0.0, 1e-7, 0.5);
      spec.split = args.number("--split-m", 0.0, 0.0, 1.0);
      spec.spread = args.number("--spread-m", 0.0, 0.0, 1.0);
      spec.cell = args.number("--cell-m", 0.0, 0.0, 1.0);
      spec.sacRadius = args.number("--sac-radius-m", 0.0, 0.0, 1.0);
      spec.sacOffset = args.number("--sac-offset-m", 0.0, 0.0, 1.0);
      write([&] { return hemo::scene::branchSurface(spec); }, "hemo-mesh branching vessel");
      std::printf("ends at (0, 0, 0) m, (%g, %g, 0) m and (%g, %g, 0) m\n", spec.length, spec.spread, spec.length, -spec.spread);
      return 0;
    }
    for (const char* key : {"--branch-radius-m", "--split-m", "--spread-m", "--cell-m"}) {
      if (args.has(key)) throw hemo::cli::UsageError(std::string(key) + " applies only to a branching vessel (--branch-angle-deg)");
    }
    hemo::scene::VesselSurfaceSpec spec;
    spec.length = args.number("--length-m", 0.0, 1e-6, 1.0);
    spec.radius = args.number("--radius-m", 0.0, 1e-7, 0.5);
    spec.bendHeight = args.number("--bend-height-m", 0.0, 0.0, 1.0);
    spec.sacRadius = args.number("--sac-radius-m", 0.0, 0.0, 1.0);
    spec.sacOffset = args.number("--sac-offset-m", 0.0, 0.0, 1.0);
    spec.straight = args.number("--straight-m", 0.0, 0.0, 1.0);
    spec.around = static_cast<std::uint32_t>(args.count("--around", 64, 8, 4096));
    spec.along = static_cast<std::uint32_t>(args.count("--along", 0, 0, 100000));
    write([&] { return hemo::scene::vesselSurface(spec); }, "hemo-mesh vessel surface");
    std::printf("ends at (0, 0, 0) m and (%g, 0, 0) m\n", spec.length + 2.0 * spec.straight);
    return 0;
  } catch (const hemo::cli::UsageError& e) {
    std::fprintf(stderr, "hemo-mesh: %s\n%s", e.what(), usage);
    return 1;
  } catch (const hemo::io::WriteError& e) {
    std::fprintf(stderr, "hemo-mesh: %s\n", e.what());
    return 4;
  }
}
