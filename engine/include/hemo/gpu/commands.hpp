#pragma once
// Command recording with named barriers and GPU timestamps. One recorder holds one primary
// command buffer; many dispatches (many simulation steps) go into it before one submit.
#include "hemo/gpu/pipeline.hpp"

#include <string>
#include <utility>
#include <vector>

namespace hemo::gpu {

class TimestampQueries;
class DispatchGate;

class CommandRecorder {
 public:
  explicit CommandRecorder(Context& context);
  ~CommandRecorder();
  CommandRecorder(const CommandRecorder&) = delete;
  CommandRecorder& operator=(const CommandRecorder&) = delete;

  Context& context() const { return *context_; }
  VkCommandBuffer handle() const { return cmd_; }

  // Starts recording (waits for the previous submission of this recorder first).
  void begin();
  // Ends recording. Adds a final barrier that makes every compute and transfer write
  // visible to the host, so readbacks after wait() see the results.
  void end();
  void submit();
  void wait();
  void submitAndWait() {
    submit();
    wait();
  }

  void dispatch(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push,
                std::uint32_t pushBytes, Groups groups);
  template <class Push>
  void dispatch(const ComputePipeline& pipeline, const DescriptorSet& set, const Push& push, Groups groups) {
    dispatch(pipeline, set, &push, sizeof(Push), groups);
  }

  // Workgroup counts read from `args` at `offset` (three uint32: x, y, z) when the command
  // runs: work whose size only the GPU knows. Not allowed inside a gate region.
  void dispatchIndirect(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push,
                        std::uint32_t pushBytes, const Buffer& args, VkDeviceSize offset);
  template <class Push>
  void dispatchIndirect(const ComputePipeline& pipeline, const DescriptorSet& set, const Push& push,
                        const Buffer& args, VkDeviceSize offset) {
    dispatchIndirect(pipeline, set, &push, sizeof(Push), args, offset);
  }
  void dispatchIndirect(const ComputePipeline& pipeline, const DescriptorSet& set, const Buffer& args,
                        VkDeviceSize offset) {
    dispatchIndirect(pipeline, set, nullptr, 0, args, offset);
  }

  // Dispatches between beginGate and endGate run only when the gate is open (see gate.hpp);
  // `variant` picks one of the gate's regions.
  void beginGate(DispatchGate& gate, std::uint32_t variant = 0);
  void endGate();

  // Named barriers (global memory barriers; the only raw masks live in commands.cpp).
  void computeToCompute();   // shader writes -> shader reads/writes
  void computeToTransfer();  // shader writes -> copy/fill
  void transferToCompute();  // copy/fill -> shader reads/writes
  void transferToTransfer();
  void computeToIndirect();  // shader writes -> indirect dispatch/draw arguments
  // Compute writes read both as indirect arguments and by later compute shaders.
  void computeToComputeAndIndirect();
  // Compute/transfer writes -> what a draw reads: indirect arguments, vertex attributes,
  // storage buffers in vertex shaders (the renderer's one hand-off from the simulation).
  void computeToGraphics();
  void computeToHost();      // shader/copy writes -> host reads after a fence

  void fill(const Buffer& buffer, std::uint32_t value, VkDeviceSize offset = 0, VkDeviceSize bytes = VK_WHOLE_SIZE);
  void copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize srcOffset = 0,
            VkDeviceSize dstOffset = 0);

  std::uint64_t dispatchCount() const { return dispatches_; }

 private:
  void bind(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push, std::uint32_t pushBytes);
  void barrier(VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst, VkAccessFlags dstAccess);

  Context* context_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  bool pending_ = false;
  VkPipeline boundPipeline_ = VK_NULL_HANDLE;
  VkDescriptorSet boundSet_ = VK_NULL_HANDLE;
  std::uint64_t dispatches_ = 0;
  DispatchGate* gate_ = nullptr;
};

// GPU timestamps around named stages. reset() before use in each recording; stage times are
// read after the submission completed.
class TimestampQueries {
 public:
  TimestampQueries(Context& context, std::uint32_t capacity);
  ~TimestampQueries();
  TimestampQueries(const TimestampQueries&) = delete;
  TimestampQueries& operator=(const TimestampQueries&) = delete;

  bool supported() const { return pool_ != VK_NULL_HANDLE; }
  void reset(CommandRecorder& rec);
  // Marks the end of the stage `label` (and the start of the next). The first mark of a
  // recording should be "start".
  void mark(CommandRecorder& rec, std::string label);
  // (label, milliseconds since the previous mark) for every mark after the first.
  std::vector<std::pair<std::string, double>> stageMs() const;
  // Milliseconds from the first to the last mark.
  double totalMs() const;

 private:
  Context* context_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  std::uint32_t capacity_;
  std::vector<std::string> labels_;
};

}  // namespace hemo::gpu
