#include "hemo/gpu/pipeline_cache.hpp"

#include <sstream>

namespace hemo::gpu {

const ComputePipeline& PipelineCache::get(const PipelineDesc& desc) {
  std::ostringstream keyText;
  keyText << desc.shader << "|wg=" << desc.workgroupSize << "|push=" << desc.pushConstantBytes
          << "|bind=" << desc.bindingCount << "|uniform=" << desc.uniformSlots << "|texel=" << desc.texelSlots
          << "|stexel=" << desc.storageTexelSlots;
  for (std::uint32_t v : desc.specialization) keyText << '|' << v;
  const std::string key = keyText.str();
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = pipelines_.find(key);
  if (it == pipelines_.end()) {
    it = pipelines_.emplace(key, std::make_unique<ComputePipeline>(*context_, desc)).first;
  }
  return *it->second;
}

}  // namespace hemo::gpu
