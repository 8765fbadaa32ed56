#include "hemo/gpu/commands.hpp"

#include "hemo/gpu/gate.hpp"

#include <algorithm>
#include <stdexcept>

namespace hemo::gpu {

// One side of a barrier: the pipeline stages and the accesses it covers.
struct detail::BarrierScope {
  VkPipelineStageFlags stages;
  VkAccessFlags access;
};

namespace {
using Scope = detail::BarrierScope;

// Producers: what was written before the barrier. A source stage covers the logically earlier
// stages too (an indirect dispatch's argument read comes before its shader), so the reads a
// later write must wait for are ordered with them.
constexpr VkPipelineStageFlags kComputeStages = VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
constexpr Scope kComputeWrites{kComputeStages, VK_ACCESS_SHADER_WRITE_BIT};
constexpr Scope kTransferWrites{VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT};
constexpr Scope kComputeAndTransferWrites{kComputeStages | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                          VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT};

// Consumers. A dispatch may read any buffer it binds as storage, uniform or texel data
// (SHADER_READ covers storage and texel reads, UNIFORM_READ the uniform blocks), write it,
// and read its workgroup counts from a buffer at the indirect stage (dispatchIndirect, and
// every dispatch of a gate region).
constexpr Scope kDispatch{kComputeStages, VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT |
                                              VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT};
constexpr Scope kTransfer{VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT};
constexpr Scope kDraw{VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT |
                          VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                      VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT |
                          VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT};
constexpr Scope kDispatchOrTransfer{kDispatch.stages | kTransfer.stages, kDispatch.access | kTransfer.access};
constexpr Scope kHost{VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT};

// Everything the engine does with a buffer on the queue: the producer side of the barrier
// that opens a recording (earlier submissions, Buffer's staging copies). Draws only where the
// queue draws (a barrier may name only stages its queue supports).
Scope anyAccess(const Context& context) {
  const VkPipelineStageFlags draw = context.queueDraws() ? VK_PIPELINE_STAGE_ALL_GRAPHICS_BIT : 0;
  return {kComputeStages | VK_PIPELINE_STAGE_TRANSFER_BIT | draw,
          VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT};
}

void recordBarrier(VkCommandBuffer cmd, const Scope& producer, const Scope& consumer) {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = producer.access;
  b.dstAccessMask = consumer.access;
  vkCmdPipelineBarrier(cmd, producer.stages, consumer.stages, 0, 1, &b, 0, nullptr, 0, nullptr);
}

bool overlaps(VkDeviceSize b0, VkDeviceSize e0, VkDeviceSize b1, VkDeviceSize e1) { return b0 < e1 && b1 < e0; }
}  // namespace

CommandRecorder::CommandRecorder(Context& context) : context_(&context) {
  VkDevice device = context.device();
  VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  poolInfo.queueFamilyIndex = context.queueFamily();
  check(vkCreateCommandPool(device, &poolInfo, nullptr, &pool_), "vkCreateCommandPool");
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  try {
    check(vkAllocateCommandBuffers(device, &alloc, &cmd_), "vkAllocateCommandBuffers");
    check(vkCreateFence(device, &fenceInfo, nullptr, &fence_), "vkCreateFence");
  } catch (...) {
    vkDestroyCommandPool(device, pool_, nullptr);
    throw;
  }
}

CommandRecorder::~CommandRecorder() {
  VkDevice device = context_->device();
  if (pending_) vkWaitForFences(device, 1, &fence_, VK_TRUE, UINT64_MAX);
  vkDestroyFence(device, fence_, nullptr);
  vkDestroyCommandPool(device, pool_, nullptr);
}

void CommandRecorder::begin() {
  wait();
  check(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd_, &info), "vkBeginCommandBuffer");
  dispatches_ = 0;
  barriers_ = 0;
  gate_ = nullptr;
  pendingTransfer_.clear();
  boundPipeline_ = VK_NULL_HANDLE;
  boundSet_ = VK_NULL_HANDLE;
  // Submission order alone orders no memory: what earlier submissions and staging copies
  // wrote (and read) is ordered before this recording's dispatches and transfers here.
  barrier(anyAccess(*context_), kDispatchOrTransfer);
}

void CommandRecorder::end() {
  computeToHost();
  check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
}

void CommandRecorder::submit() {
  check(vkResetFences(context_->device(), 1, &fence_), "vkResetFences");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd_;
  check(vkQueueSubmit(context_->queue(), 1, &submit, fence_), "vkQueueSubmit");
  pending_ = true;
}

void CommandRecorder::wait() {
  if (!pending_) return;
  const VkResult r = vkWaitForFences(context_->device(), 1, &fence_, VK_TRUE, UINT64_MAX);
  pending_ = false;
  check(r, "vkWaitForFences");
}

namespace {
void checkPushBytes(const ComputePipeline& pipeline, std::uint32_t pushBytes) {
  if (pushBytes != pipeline.pushConstantBytes()) {
    throw std::invalid_argument("push constants for '" + pipeline.name() + "' are " +
                                std::to_string(pushBytes) + " bytes; the pipeline expects " +
                                std::to_string(pipeline.pushConstantBytes()));
  }
}
}  // namespace

void CommandRecorder::bind(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push,
                           std::uint32_t pushBytes) {
  checkPushBytes(pipeline, pushBytes);
  // Rebind only what changed (lavapipe pays for every bind when the command buffer runs).
  if (pipeline.handle() != boundPipeline_) {
    vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
    boundPipeline_ = pipeline.handle();
    boundSet_ = VK_NULL_HANDLE;
  }
  VkDescriptorSet handle = set.handle();
  if (handle != boundSet_) {
    vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, 1, &handle, 0, nullptr);
    boundSet_ = handle;
  }
  if (pushBytes) {
    vkCmdPushConstants(cmd_, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, pushBytes, push);
  }
}

void CommandRecorder::dispatch(const ComputePipeline& pipeline, const DescriptorSet& set,
                               const void* push, std::uint32_t pushBytes, Groups groups) {
  if (groups.total() == 0) {
    checkPushBytes(pipeline, pushBytes);  // a wrong size is an error even when nothing runs
    return;
  }
  bind(pipeline, set, push, pushBytes);
  if (gate_) {
    const VkDeviceSize slot = gate_->claim(groups);
    checkDispatchReads(pipeline, set, gate_->args_.handle(), slot);
    vkCmdDispatchIndirect(cmd_, gate_->args_.handle(), slot);
  } else {
    checkDispatchReads(pipeline, set, VK_NULL_HANDLE, 0);
    vkCmdDispatch(cmd_, groups.x, groups.y, 1);
  }
  ++dispatches_;
}

void CommandRecorder::dispatchIndirect(const ComputePipeline& pipeline, const DescriptorSet& set, const void* push,
                                       std::uint32_t pushBytes, const Buffer& args, VkDeviceSize offset) {
  if (gate_) {
    throw std::logic_error("indirect dispatch of '" + pipeline.name() + "' inside the gate region of '" +
                           gate_->name() + "'");
  }
  if (offset % 4 != 0 || offset + 3 * sizeof(std::uint32_t) > args.size()) {
    throw std::invalid_argument("indirect arguments of '" + pipeline.name() + "' at byte " + std::to_string(offset) +
                                " do not fit buffer '" + args.name() + "'");
  }
  checkDispatchReads(pipeline, set, args.handle(), offset);
  bind(pipeline, set, push, pushBytes);
  vkCmdDispatchIndirect(cmd_, args.handle(), offset);
  ++dispatches_;
}

void CommandRecorder::beginGate(DispatchGate& gate, std::uint32_t variant) {
  if (gate_) throw std::logic_error("gated regions do not nest ('" + gate.name() + "' inside '" + gate_->name() + "')");
  gate.beginRegion(variant);  // (throws for a variant the gate does not have)
  gate_ = &gate;
}

void CommandRecorder::endGate() {
  if (!gate_) throw std::logic_error("endGate without beginGate");
  gate_->endRegion();
  gate_ = nullptr;
}


void recordBeforeStagingCopy(const Context& context, VkCommandBuffer cmd) {
  recordBarrier(cmd, anyAccess(context), kTransfer);
}
void recordStagingCopyToHost(VkCommandBuffer cmd) { recordBarrier(cmd, kTransferWrites, kHost); }

void CommandRecorder::barrier(const Scope& producer, const Scope& consumer) {
  recordBarrier(cmd_, producer, consumer);
  ++barriers_;
  if (producer.access & VK_ACCESS_TRANSFER_WRITE_BIT) pendingTransfer_.clear();
}

void CommandRecorder::computeToCompute() { barrier(kComputeWrites, kDispatch); }
void CommandRecorder::computeToTransfer() { barrier(kComputeWrites, kTransfer); }
void CommandRecorder::transferToCompute() { barrier(kTransferWrites, kDispatch); }
void CommandRecorder::transferToTransfer() { barrier(kTransferWrites, kTransfer); }
void CommandRecorder::computeToGraphics() { barrier(kComputeAndTransferWrites, kDraw); }
void CommandRecorder::computeToHost() { barrier(kComputeAndTransferWrites, kHost); }

void CommandRecorder::checkNotPending(VkBuffer buffer, VkDeviceSize begin, VkDeviceSize end, const std::string& user,
                                      const char* barrierName) const {
  for (const Range& r : pendingTransfer_) {
    if (r.buffer->handle() == buffer && overlaps(r.begin, r.end, begin, end)) {
      throw std::logic_error(user + " touches bytes " + std::to_string(std::max(r.begin, begin)) + " to " +
                             std::to_string(std::min(r.end, end)) + " of buffer '" + r.buffer->name() +
                             "' that a fill or copy wrote with no barrier since (" + barrierName + ")");
    }
  }
}

void CommandRecorder::checkDispatchReads(const ComputePipeline& pipeline, const DescriptorSet& set, VkBuffer args,
                                         VkDeviceSize argsOffset) const {
  if (pendingTransfer_.empty()) return;
  for (const DescriptorSet::Bound& b : set.bound()) {
    checkNotPending(b.buffer, b.begin, b.end, "dispatch of '" + pipeline.name() + "'", "transferToCompute");
  }
  if (args != VK_NULL_HANDLE) {
    checkNotPending(args, argsOffset, argsOffset + 12, "the indirect arguments of '" + pipeline.name() + "'",
                    "transferToCompute");
  }
}

void CommandRecorder::transferWrote(const Buffer& buffer, VkDeviceSize offset, VkDeviceSize bytes, const char* what) {
  const VkDeviceSize end = bytes == VK_WHOLE_SIZE ? buffer.allocatedSize() : offset + bytes;
  checkNotPending(buffer.handle(), offset, end, what, "transferToTransfer");
  pendingTransfer_.push_back({&buffer, offset, end});
}

void CommandRecorder::fill(const Buffer& buffer, std::uint32_t value, VkDeviceSize offset, VkDeviceSize bytes) {
  if (bytes == 0) return;
  transferWrote(buffer, offset, bytes, "a fill");
  vkCmdFillBuffer(cmd_, buffer.handle(), offset, bytes, value);
}

void CommandRecorder::copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize srcOffset,
                           VkDeviceSize dstOffset) {
  if (bytes == 0) return;
  checkNotPending(src.handle(), srcOffset, srcOffset + bytes, "a copy from buffer '" + src.name() + "'",
                  "transferToTransfer");
  transferWrote(dst, dstOffset, bytes, "a copy to it");
  VkBufferCopy region{srcOffset, dstOffset, bytes};
  vkCmdCopyBuffer(cmd_, src.handle(), dst.handle(), 1, &region);
}

TimestampQueries::TimestampQueries(Context& context, std::uint32_t capacity)
    : context_(&context), capacity_(capacity) {
  if (!context.timestampsSupported()) return;
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_TIMESTAMP;
  info.queryCount = capacity;
  check(vkCreateQueryPool(context.device(), &info, nullptr, &pool_), "vkCreateQueryPool");
}

TimestampQueries::~TimestampQueries() {
  if (pool_) vkDestroyQueryPool(context_->device(), pool_, nullptr);
}

void TimestampQueries::reset(CommandRecorder& rec) {
  labels_.clear();
  if (pool_) vkCmdResetQueryPool(rec.handle(), pool_, 0, capacity_);
}

void TimestampQueries::mark(CommandRecorder& rec, std::string label) {
  if (labels_.size() >= capacity_) {
    throw std::length_error("more than " + std::to_string(capacity_) + " timestamps in one recording");
  }
  if (pool_) {
    vkCmdWriteTimestamp(rec.handle(), VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_,
                        static_cast<std::uint32_t>(labels_.size()));
  }
  labels_.push_back(std::move(label));
}

std::vector<std::pair<std::string, double>> TimestampQueries::stageMs() const {
  std::vector<std::pair<std::string, double>> out;
  if (!pool_ || labels_.size() < 2) return out;
  std::vector<std::uint64_t> ticks(labels_.size());
  check(vkGetQueryPoolResults(context_->device(), pool_, 0, static_cast<std::uint32_t>(ticks.size()),
                              ticks.size() * sizeof(std::uint64_t), ticks.data(), sizeof(std::uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
        "vkGetQueryPoolResults");
  const double msPerTick = context_->timestampPeriodNs() * 1e-6;
  // Only the low timestampValidBits bits count (36 on some GPUs): a difference is taken
  // modulo 2^bits, so a counter that wrapped between two marks still gives the elapsed ticks.
  const std::uint32_t bits = context_->timestampValidBits();
  const std::uint64_t mask = bits >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << bits) - 1;
  for (std::size_t i = 1; i < ticks.size(); ++i) {
    out.emplace_back(labels_[i], double((ticks[i] - ticks[i - 1]) & mask) * msPerTick);
  }
  return out;
}

double TimestampQueries::totalMs() const {
  double sum = 0.0;
  for (const auto& [label, ms] : stageMs()) sum += ms;
  return sum;
}

}  // namespace hemo::gpu
