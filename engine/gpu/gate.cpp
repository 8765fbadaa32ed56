#include "hemo/gpu/gate.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/gate.h"

#include <stdexcept>

namespace hemo::gpu {

namespace {
constexpr std::uint32_t kWorkgroup = 64;

struct ArmPush {
  std::uint32_t slots;
  std::uint32_t index;
  float threshold;
};
static_assert(sizeof(ArmPush) == 12);
}  // namespace

DispatchGate::DispatchGate(Context& context, const Buffer& values, std::uint32_t maxSlots, std::string name,
                           std::uint32_t variants)
    : name_(std::move(name)),
      maxSlots_(std::max(maxSlots, 1u)),
      variants_(variants),
      armed_(context, VkDeviceSize(maxSlots_) * 16, MemoryUse::Device, name_ + " armed counts"),
      args_(context, VkDeviceSize(maxSlots_) * 16, MemoryUse::Device, name_ + " indirect args"),
      opened_(context, 4, MemoryUse::Device, name_ + " openings"),
      table_(std::size_t(maxSlots_) * 4, 0u) {
  if (variants_ == 0 || variants_ > maxSlots_) {
    throw std::invalid_argument("dispatch gate '" + name_ + "': " + std::to_string(variants_) +
                                " variants for " + std::to_string(maxSlots_) + " slots");
  }
  arm_ = &context.pipelines().get({"gate/arm", HEMO_GATE_BINDING_COUNT, sizeof(ArmPush), kWorkgroup, {}});
  set_ = arm_->makeSet({{HEMO_GATE_BINDING_VALUES, &values},
                        {HEMO_GATE_BINDING_ARMED, &armed_},
                        {HEMO_GATE_BINDING_ARGS, &args_},
                        {HEMO_GATE_BINDING_OPENED, &opened_}});
  armed_.upload(table_);
}

void DispatchGate::recordArm(CommandRecorder& rec, std::uint32_t index, float threshold) {
  rec.dispatch(*arm_, set_, ArmPush{maxSlots_, index, threshold}, arm_->groupsFor(maxSlots_));
  rec.computeToCompute();
}

void DispatchGate::recordReset(CommandRecorder& rec) {
  rec.fill(opened_, 0);
  rec.transferToCompute();
}

std::uint32_t DispatchGate::readOpened() const { return opened_.readback<std::uint32_t>(1)[0]; }

bool DispatchGate::readIsOpen() const {
  // Any slot: the regions this host has recorded may be of another variant than slot 0's (a
  // simulation resumed from a checkpoint records only the variants it still takes).
  const auto args = args_.readback<std::uint32_t>(std::size_t(maxSlots_) * 4);
  for (std::uint32_t s = 0; s < maxSlots_; ++s) {
    if (args[std::size_t(s) * 4] != 0u) return true;
  }
  return false;
}

void DispatchGate::beginRegion(std::uint32_t variant) {
  if (variant >= variants_) {
    throw std::out_of_range("dispatch gate '" + name_ + "': variant " + std::to_string(variant) + " of " +
                            std::to_string(variants_));
  }
  const std::uint32_t share = maxSlots_ / variants_;
  cursor_ = variant * share;
  cursorEnd_ = cursor_ + share;
}

VkDeviceSize DispatchGate::claim(Groups groups) {
  if (cursor_ >= cursorEnd_) {
    throw std::length_error("dispatch gate '" + name_ + "': more than " + std::to_string(maxSlots_ / variants_) +
                            " dispatches in one gated region");
  }
  std::uint32_t* slot = &table_[std::size_t(cursor_) * 4];
  if (slot[0] == 0) {  // first use of the slot
    slot[0] = groups.x;
    slot[1] = groups.y;
    slot[2] = 1;
    dirty_ = true;
  } else if (slot[0] != groups.x || slot[1] != groups.y) {
    throw std::logic_error("dispatch gate '" + name_ + "': dispatch " + std::to_string(cursor_) +
                           " of the region changed its workgroup counts between recordings");
  }
  return VkDeviceSize(cursor_++) * 16;
}

void DispatchGate::endRegion() {
  if (dirty_) {
    armed_.upload(table_);  // set-up only: the first recording of a region
    dirty_ = false;
  }
}

}  // namespace hemo::gpu
