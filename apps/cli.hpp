#pragma once
// Minimal command-line parsing shared by the hemo apps: positional arguments and
// "--name value" options, with errors that name the argument; and the programs' shared report
// of validation messages.
#include "hemo/gpu/context.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <utility>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemo::cli {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;  // "--json" -> "file.json"

  bool has(const std::string& name) const { return options.count(name) != 0; }
  std::string text(const std::string& name, const std::string& fallback = "") const {
    auto it = options.find(name);
    return it == options.end() ? fallback : it->second;
  }
  std::uint64_t count(const std::string& name, std::uint64_t fallback, std::uint64_t min, std::uint64_t max) const {
    auto it = options.find(name);
    if (it == options.end()) return fallback;
    const std::string& v = it->second;
    std::size_t used = 0;
    unsigned long long x = 0;
    try {
      if (v.empty() || v[0] == '-') throw std::invalid_argument(v);
      x = std::stoull(v, &used);
    } catch (const std::exception&) {
      throw UsageError(name + " expects a whole number, got '" + v + "'");
    }
    if (used != v.size()) throw UsageError(name + " expects a whole number, got '" + v + "'");
    if (x < min || x > max) {
      throw UsageError(name + " must be between " + std::to_string(min) + " and " + std::to_string(max) +
                       ", got " + v);
    }
    return x;
  }
  // A finite number in [min, max], or `fallback` when the option is absent.
  double number(const std::string& name, double fallback, double min, double max) const {
    auto it = options.find(name);
    if (it == options.end()) return fallback;
    const std::optional<double> x = finite(it->second);
    if (!x) throw UsageError(name + " expects a number, got '" + it->second + "'");
    if (*x < min || *x > max) {
      throw UsageError(name + " must be between " + std::to_string(min) + " and " + std::to_string(max) + ", got " +
                       it->second);
    }
    return *x;
  }
  // A non-negative, finite number of seconds, or `fallback` when the option is absent.
  double seconds(const std::string& name, double fallback) const {
    auto it = options.find(name);
    if (it == options.end()) return fallback;
    const std::optional<double> t = finite(it->second);
    if (!t || *t < 0) throw UsageError(name + " expects a non-negative time in seconds, got '" + it->second + "'");
    return *t;
  }
  // The whole text as a finite number, if it is one.
  static std::optional<double> finite(const std::string& v) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(v, &used);
    } catch (const std::exception&) {
      return std::nullopt;
    }
    if (used == 0 || used != v.size() || !std::isfinite(x)) return std::nullopt;
    return x;
  }
  // An image size "WxH" (16 <= W, H <= 8192), or `fallback` when the option is absent.
  std::pair<std::uint32_t, std::uint32_t> size(const std::string& name,
                                               std::pair<std::uint32_t, std::uint32_t> fallback) const {
    auto it = options.find(name);
    if (it == options.end()) return fallback;
    unsigned w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(it->second.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192) {
      throw UsageError(name + " expects WxH with 16 <= W, H <= 8192, got '" + it->second + "'");
    }
    return {w, h};
  }
};

// When the command line asks for help ("--help" or "-h" where an option may stand, not as
// the value of another option), prints `usage` to stdout and returns true: the app then
// exits 0.
// With the validation layer on (HEMO_VALIDATION), prints what it reported, under `app`'s
// name; true when it reported anything (the program then exits with 3).
inline bool validationProblems(hemo::gpu::Context& ctx, const char* app) {
  if (!ctx.validationEnabled() || ctx.validationMessageCount() == 0) return false;
  for (const auto& m : ctx.takeValidationMessages()) std::cerr << m << "\n";
  std::cerr << app << ": the Vulkan validation layer reported problems\n";
  return true;
}

inline bool printUsageIfAsked(int argc, char** argv, const char* usage) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--help" || s == "-h") {
      std::fputs(usage, stdout);
      return true;
    }
    if (s.rfind("--", 0) == 0) ++i;  // skip the option's value
  }
  return false;
}

// The host's processor as /proc/cpuinfo names it ("unknown" elsewhere). Recorded with every
// timing: on a CPU device (lavapipe) the host decides the speed, and the same work has taken
// twice the time on one host as on another.
inline std::string hostCpu() {
  std::ifstream info("/proc/cpuinfo");
  std::map<std::string, std::string> fields;
  std::string line;
  // The first processor's block: "key<tabs>: value" lines up to the first empty one.
  while (std::getline(info, line) && !line.empty()) {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos || colon == 0) continue;
    const std::size_t keyEnd = line.find_last_not_of(" \t", colon - 1);
    if (keyEnd == std::string::npos) continue;
    const std::size_t start = line.find_first_not_of(" \t", colon + 1);
    fields[line.substr(0, keyEnd + 1)] = start == std::string::npos ? "" : line.substr(start);
  }
  std::string name = fields["model name"];
  if (name.empty()) return "unknown";
  // Virtual machines often give only a family name ("AMD EPYC"); the family and model
  // numbers say which generation it is.
  if (!fields["cpu family"].empty() && !fields["model"].empty()) {
    name += " (family " + fields["cpu family"] + ", model " + fields["model"] + ")";
  }
  return name;
}

// Parses argv; every option takes exactly one value and must be in `known`.
inline Args parse(int argc, char** argv, const std::set<std::string>& known) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    std::string s = argv[i];
    if (s.rfind("--", 0) == 0) {
      if (!known.count(s)) throw UsageError("unknown option " + s);
      if (i + 1 >= argc) throw UsageError(s + " needs a value");
      if (a.options.count(s)) throw UsageError(s + " given twice");
      a.options[s] = argv[++i];
    } else {
      a.positional.push_back(s);
    }
  }
  return a;
}

}  // namespace hemo::cli
