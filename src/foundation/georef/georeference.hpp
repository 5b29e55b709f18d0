// georef/georeference: a fixed camera view placed in the world from a ground control point file
// (the `georef:` section of the configuration).
//
// Contract: loadGroundView() reads the GCP file (georef/gcp_file), removes the lens distortion
// from each point's pixel with the camera model of the raw frames (the homography is between
// ideal pinhole pixels of the calibrated intrinsics and the ground), places each point in the
// world ENU frame (a point without a height takes the DTM's height there when a terrain model is
// given and covers it, else the origin's height), estimates the homography
// (georef/ground_homography) and recovers the camera from it. checkResiduals() then refuses a
// fit whose largest ground residual exceeds the limit, naming the point and its line (a mistyped
// coordinate or a mis-clicked pixel). Messages start with the file's name. Start-up only.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "camera/camera_model.hpp"
#include "geodesy/geodesy.hpp"
#include "georef/gcp_file.hpp"
#include "georef/ground_homography.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::georef {

// The `georef:` section (docs/configuration.md).
struct GeorefOptions {
  std::string gcpFile;         // empty: no ground control (lifting uses the pose and the DTM)
  double maxResidual_m = 1.0;  // (0, 100]: largest accepted ground residual of a point
  HomographyOptions homography{};
};

struct GroundView {
  GcpFile file;                      // as read
  std::vector<ControlPoint> points;  // ideal pixels and ENU points, in the file's order
  GroundHomography homography{};
  std::optional<RecoveredCamera> camera;  // the camera the view implies (none: not decomposable)
};

bool loadGroundView(const GeorefOptions& options, const camera::CameraModel& rawCamera,
                    const geodesy::LocalFrame& frame, const terrain::TerrainModel* terrain,
                    GroundView* out, std::string* why);

bool checkResiduals(const GroundView& view, double maxResidual_m, std::string* why);

}  // namespace vp::georef
