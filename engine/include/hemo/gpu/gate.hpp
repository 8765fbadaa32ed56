#pragma once
// GPU-decided conditional work without a host round trip. Dispatches recorded between
// CommandRecorder::beginGate(gate) and endGate() become indirect dispatches, one slot of
// the gate's argument buffer each; the gate remembers the workgroup counts they were
// recorded with. recordArm() (one small dispatch) then writes, on the GPU, either those
// counts (gate open) or zeros (closed) into the slots, depending on a value another stage
// computed: open when values[index] > threshold, or when the value is NaN.
// A region must record the same dispatches with the same counts every time (the slots are
// reused by every step of a batch); a mismatch throws. A gate made with several variants
// holds as many regions, each with its own share of the slots (beginGate's `variant`), for a
// caller whose gated work takes one of a few shapes (the solver's full and partial sorts).
// A shader may also arm the gate at the end of the pass that computes the decision
// (common/gate.glsl), saving recordArm's dispatch.
#include "hemo/gpu/commands.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace hemo::gpu {

class DispatchGate {
 public:
  // maxSlots in all, split evenly between `variants` regions.
  DispatchGate(Context& context, const Buffer& values, std::uint32_t maxSlots, std::string name,
               std::uint32_t variants = 1);

  // Records the decision for the next gated region. Needs the writes of `values` visible to
  // compute (a computeToCompute barrier before), and ends with computeToCompute, which orders
  // the arguments before the region's indirect reads.
  void recordArm(CommandRecorder& rec, std::uint32_t index, float threshold);
  // Zeroes the counter of openings (transfer command).
  void recordReset(CommandRecorder& rec);
  // How often the gate opened since the last reset (a readback: outside the step loop).
  std::uint32_t readOpened() const;
  // Whether the gate stands open for the next region (a readback).
  bool readIsOpen() const;
  const std::string& name() const { return name_; }

  // For a shader that arms the gate itself, at the end of the pass that computes the decision
  // (common/gate.glsl: one dispatch less per region than recordArm). Such a shader binds
  // these three buffers and must be followed by CommandRecorder::computeToCompute, which
  // orders the arguments before the region's indirect reads.
  const Buffer& armedCounts() const { return armed_; }
  const Buffer& arguments() const { return args_; }
  const Buffer& openings() const { return opened_; }
  std::uint32_t slots() const { return maxSlots_; }
  // Its buffers, for a checkpoint (hemo/io/checkpoint.hpp): the arguments the last arming
  // wrote, the openings, and the counts (which the next recording of a region writes again).
  void checkpointBuffers(std::vector<Buffer*>& out) { out.insert(out.end(), {&armed_, &args_, &opened_}); }

 private:
  friend class CommandRecorder;
  // The indirect-argument offset for the next dispatch of the region being recorded.
  VkDeviceSize claim(Groups groups);
  void beginRegion(std::uint32_t variant);
  void endRegion();

  std::string name_;
  std::uint32_t maxSlots_;
  std::uint32_t variants_;
  std::uint32_t cursorEnd_ = 0;  // past the slots of the region being recorded
  const ComputePipeline* arm_;
  Buffer armed_;   // host-written table of counts (uvec4 per slot)
  Buffer args_;    // indirect arguments (uvec4 per slot; the first three are x, y, z)
  Buffer opened_;  // uint
  DescriptorSet set_;
  std::vector<std::uint32_t> table_;  // host copy of armed_
  std::uint32_t cursor_ = 0;
  bool dirty_ = false;
};

}  // namespace hemo::gpu
