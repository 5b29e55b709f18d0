// traffic/track_slots: the fixed tables of per-track state the traffic analysis keeps (one slot
// per followed track, allocated at start-up).
//
// Contract: Slot has `bool used` and `std::uint32_t trackId`. findTrackSlot() returns the used
// slot of the track or nullptr; claimTrackSlot() marks the first unused slot as the track's and
// returns it, nullptr when every slot is used. A slot is left in its empty state by whoever
// releases it (claiming does not reset it: the owners' empty states differ). No allocation.
#pragma once

#include <cstdint>
#include <span>

namespace vp::traffic {

template <typename Slot>
Slot* findTrackSlot(std::span<Slot> slots, std::uint32_t trackId) {
  for (Slot& slot : slots) {
    if (slot.used && slot.trackId == trackId) {
      return &slot;
    }
  }
  return nullptr;
}

template <typename Slot>
Slot* claimTrackSlot(std::span<Slot> slots, std::uint32_t trackId) {
  for (Slot& slot : slots) {
    if (!slot.used) {
      slot.used = true;
      slot.trackId = trackId;
      return &slot;
    }
  }
  return nullptr;
}

}  // namespace vp::traffic
