#pragma once
// Pipelines created once per Context and shared by every stage that uses the same shader with
// the same workgroup size and specialization constants (pipeline creation compiles the
// shader, which costs milliseconds on lavapipe).
#include "hemo/gpu/pipeline.hpp"

#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace hemo::gpu {

class PipelineCache {
 public:
  explicit PipelineCache(Context& context) : context_(&context) {}
  const ComputePipeline& get(const PipelineDesc& desc);
  std::size_t size() const { return pipelines_.size(); }

 private:
  Context* context_;
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<ComputePipeline>> pipelines_;
};

}  // namespace hemo::gpu
