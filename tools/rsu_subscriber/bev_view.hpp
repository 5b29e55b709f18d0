// tools/rsu_subscriber/bev_view: a north-up bird's-eye picture of the received tracks (and the
// latest occupancy grid), written as PNG.
//
// Contract: the view is a square of side 2 * range_m centred on `centre` (world ENU, m), drawn
// at `size_px` pixels; east is right, north is up. Each vehicle is its footprint rectangle
// (length x width, rotated by its ENU heading) with a line to its front and its track id;
// confirmed tracks are green, lost ones orange; a vehicle with keypoints also shows its ASM
// wireframe (the mesh's edges in plan, blue). Occupied grid cells are grey, free cells
// dark, unobserved cells black. write() returns false with a message when OpenCV cannot
// write the file (written to a temporary name first, then renamed, so a viewer never sees a
// half-written PNG). With an overlay, the site map is drawn under the vehicles (drivable
// areas dark grey, parking dark blue, exclusions dark red, zones yellow outlines, lanes cyan
// lines with an arrow at their end, gates magenta lines with their id and, when given, their
// label such as the counts), the recent events as white rings, and the overlay's text lines
// in the top-left corner.
#pragma once

#include <map>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "messages/messages.hpp"
#include "site/site.hpp"

namespace vp::rsu {

struct BevSettings {
  double centreEast_m = 0.0;
  double centreNorth_m = 0.0;
  double range_m = 60.0;
  int size_px = 800;
};

struct BevOverlay {
  const site::Site* site = nullptr;              // in the drones' world ENU frame
  std::map<std::string, std::string> gateLabel;  // gate id -> text beside it (counts)
  std::vector<Eigen::Vector2d> eventMarks_m;     // recent events, world ENU
  std::vector<std::string> lines;                // text panel, top left
};

bool writeBev(const BevSettings& settings, std::span<const messages::VehicleState> vehicles,
              const messages::OccupancyGrid* grid, const std::string& path, std::string* why,
              const BevOverlay* overlay = nullptr);

}  // namespace vp::rsu
