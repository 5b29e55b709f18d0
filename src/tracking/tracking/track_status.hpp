// tracking/track_status: the lifecycle state of a track, on its own so that the stages after
// the tracker (messages, output files) name it without depending on the tracker itself.
//
// Contract: Tentative until the track is confirmed, Confirmed while detections match it, Lost
// while it is predicted without a match (tracking/track_manager.hpp describes the lifecycle).
// toString() gives the lower-case word that files and logs write.
#pragma once

#include <cstdint>

namespace vp::tracking {

enum class TrackStatus : std::uint8_t { Tentative, Confirmed, Lost };

constexpr const char* toString(TrackStatus status) {
  switch (status) {
    case TrackStatus::Tentative:
      return "tentative";
    case TrackStatus::Confirmed:
      return "confirmed";
    case TrackStatus::Lost:
      return "lost";
  }
  return "?";
}

}  // namespace vp::tracking
