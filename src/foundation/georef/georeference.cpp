#include "georef/georeference.hpp"

#include <cstdio>

#include "csv/csv_io.hpp"

namespace vp::georef {

namespace {

std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f m", value);
  return text;
}

}  // namespace

bool loadGroundView(const GeorefOptions& options, const camera::CameraModel& rawCamera,
                    const geodesy::LocalFrame& frame, const terrain::TerrainModel* terrain,
                    GroundView* out, std::string* why) {
  *out = GroundView{};
  if (!readGcpFile(options.gcpFile, &out->file, why)) {
    return false;
  }
  const std::string name = csv::shortened(options.gcpFile);
  for (const GcpRecord& record : out->file.points) {
    const auto ideal = rawCamera.undistortPixel(record.pixel);
    if (!ideal) {
      if (why != nullptr) {
        *why = csv::location(options.gcpFile, record.line) + ": point '" + record.id +
               "': pixel beyond the lens model's valid field";
      }
      return false;
    }
    geodesy::GeodeticPoint position{record.latitude_deg, record.longitude_deg,
                                    frame.origin().height_m};
    if (record.height_m) {
      position.height_m = *record.height_m;
    } else if (terrain != nullptr && terrain->grid().cols >= 2) {
      if (const auto h = terrain->heightAt(record.latitude_deg, record.longitude_deg)) {
        position.height_m = *h;
      }
    }
    out->points.push_back(ControlPoint{record.id, *ideal, frame.toEnu(position)});
  }
  std::string problem;
  if (!estimateGroundHomography(out->points, options.homography, &out->homography, &problem)) {
    if (why != nullptr) {
      *why = name + ": " + problem;
    }
    return false;
  }
  out->camera = recoverCamera(out->homography, rawCamera.intrinsics());
  return true;
}

bool checkResiduals(const GroundView& view, double maxResidual_m, std::string* why) {
  const GroundHomography& h = view.homography;
  if (h.residuals.empty() || h.max_m <= maxResidual_m) {
    return true;
  }
  const GcpRecord& worst = view.file.points[h.maxIndex];
  if (why != nullptr) {
    *why = csv::location(view.file.path, worst.line) + ": point '" + worst.id +
           "': ground residual " + metres(h.max_m) + " exceeds " + metres(maxResidual_m) +
           " (RMS " + metres(h.rms_m) + " over " + std::to_string(h.residuals.size()) +
           " points): a wrong coordinate or pixel? (vp_gcp check lists every residual)";
  }
  return false;
}

}  // namespace vp::georef
