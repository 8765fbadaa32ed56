#pragma once
// The SPIR-V of every compute shader, compiled at build time and embedded in the library.
#include <cstdint>
#include <span>
#include <string_view>

namespace hemo::shaders {
// Words of the shader compiled from compute_shaders/<name>.comp, e.g. spirv("scan/scan_block").
// Throws std::invalid_argument for an unknown name.
std::span<const std::uint32_t> spirv(std::string_view name);
}  // namespace hemo::shaders
