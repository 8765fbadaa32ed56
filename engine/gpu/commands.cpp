#include "hemo/gpu/commands.hpp"

#include "hemo/gpu/gate.hpp"

namespace hemo::gpu {

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
  gate_ = nullptr;
  boundPipeline_ = VK_NULL_HANDLE;
  boundSet_ = VK_NULL_HANDLE;
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
    vkCmdDispatchIndirect(cmd_, gate_->args_.handle(), gate_->claim(groups));
  } else {
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

void CommandRecorder::barrier(VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst,
                              VkAccessFlags dstAccess) {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = srcAccess;
  b.dstAccessMask = dstAccess;
  vkCmdPipelineBarrier(cmd_, src, dst, 0, 1, &b, 0, nullptr, 0, nullptr);
}

// Reads after a barrier include uniform-buffer reads: parameter blocks written by one pass
// (as storage) are read by the next as uniform buffers.
void CommandRecorder::computeToCompute() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
          VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
}

void CommandRecorder::computeToTransfer() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
          VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT,
          VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
}

void CommandRecorder::transferToCompute() {
  barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
          VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
}

void CommandRecorder::transferToTransfer() {
  barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
          VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
}

void CommandRecorder::computeToGraphics() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
          VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
          VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
          VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
}

void CommandRecorder::computeToIndirect() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
          VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT, VK_ACCESS_INDIRECT_COMMAND_READ_BIT);
}

void CommandRecorder::computeToComputeAndIndirect() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
          VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
          VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT);
}

void CommandRecorder::computeToHost() {
  barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
          VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
          VK_ACCESS_HOST_READ_BIT);
}

void CommandRecorder::fill(const Buffer& buffer, std::uint32_t value, VkDeviceSize offset, VkDeviceSize bytes) {
  if (bytes == 0) return;
  vkCmdFillBuffer(cmd_, buffer.handle(), offset, bytes, value);
}

void CommandRecorder::copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize srcOffset,
                           VkDeviceSize dstOffset) {
  if (bytes == 0) return;
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
  for (std::size_t i = 1; i < ticks.size(); ++i) {
    out.emplace_back(labels_[i], double(ticks[i] - ticks[i - 1]) * msPerTick);
  }
  return out;
}

double TimestampQueries::totalMs() const {
  double sum = 0.0;
  for (const auto& [label, ms] : stageMs()) sum += ms;
  return sum;
}

}  // namespace hemo::gpu
