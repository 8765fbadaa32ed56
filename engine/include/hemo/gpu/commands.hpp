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
namespace detail {
struct BarrierScope;  // stages and accesses of one side of a barrier (commands.cpp)
}

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

  // Named barriers: global memory barriers, each between a producer and a consumer (the raw
  // stage and access masks live only in commands.cpp). A barrier makes what its producer
  // wrote visible to everything its consumer does, and orders the consumer's writes after
  // the producer's reads:
  //   compute   a dispatch's shader writes (and reads)
  //   transfer  fills and copies
  //   dispatch  everything a later dispatch may do with a buffer: read it as indirect
  //             arguments (an indirect or gated dispatch), read it as storage, uniform or
  //             texel data, and write it
  //   graphics  what a draw reads: indirect arguments, vertex attributes, shader reads
  //   host      host reads after the fence
  // A barrier always covers every consumer of its kind: there is no barrier to indirect
  // arguments alone, because a buffer a shader writes may be read by the next dispatch both
  // as arguments and as data (marching cubes' and the gate's arguments are), and a barrier
  // that covers one of two readers leaves the other unordered.
  void computeToCompute();   // compute -> dispatch
  void computeToTransfer();  // compute -> transfer
  void transferToCompute();  // transfer -> dispatch
  void transferToTransfer(); // transfer -> transfer
  // compute and transfer -> graphics (the renderer's one hand-off from the simulation)
  void computeToGraphics();
  void computeToHost();      // compute and transfer -> host

  // Transfer commands. The recorder remembers what fills and copies wrote since the last
  // barrier out of transfer, and throws std::logic_error when a later command touches those
  // bytes without one: a fill or copy over them (transferToTransfer), a copy reading them,
  // or a dispatch that binds them or reads its arguments there (transferToCompute).
  void fill(const Buffer& buffer, std::uint32_t value, VkDeviceSize offset = 0, VkDeviceSize bytes = VK_WHOLE_SIZE);
  void copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize srcOffset = 0,
            VkDeviceSize dstOffset = 0);

  // Dispatches (direct, indirect and gated, whether or not the GPU opens them) and barriers
  // recorded since begin().
  std::uint64_t dispatchCount() const { return dispatches_; }
  std::uint64_t barrierCount() const { return barriers_; }

 private:
  void bind(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push, std::uint32_t pushBytes);
  void barrier(const detail::BarrierScope& producer, const detail::BarrierScope& consumer);
  // The pending transfer writes (see fill/copy).
  struct Range {
    const Buffer* buffer;
    VkDeviceSize begin, end;
  };
  void transferWrote(const Buffer& buffer, VkDeviceSize offset, VkDeviceSize bytes, const char* what);
  void checkNotPending(VkBuffer buffer, VkDeviceSize begin, VkDeviceSize end, const std::string& user,
                       const char* barrierName) const;
  void checkDispatchReads(const ComputePipeline& pipeline, const DescriptorSet& set, VkBuffer args,
                          VkDeviceSize argsOffset) const;

  Context* context_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  bool pending_ = false;
  VkPipeline boundPipeline_ = VK_NULL_HANDLE;
  VkDescriptorSet boundSet_ = VK_NULL_HANDLE;
  std::uint64_t dispatches_ = 0;
  std::uint64_t barriers_ = 0;
  DispatchGate* gate_ = nullptr;
  std::vector<Range> pendingTransfer_;
};

// Barriers for the one-time copies of Buffer's staging path (Context::runOnce), which run
// outside a CommandRecorder: every earlier compute, transfer and draw access on the queue
// before a copy, and a copy's writes before the host reads them.
void recordBeforeStagingCopy(const Context& context, VkCommandBuffer cmd);
void recordStagingCopyToHost(VkCommandBuffer cmd);

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
