// tools/rsu_subscriber/bev_view: OpenCV drawing of the bird's-eye view.
#include "bev_view.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace vp::rsu {

namespace {

template <typename ToPixel>
void drawSite(cv::Mat& image, const site::Site& site, const BevOverlay& overlay,
              const ToPixel& toPixel) {
  const auto points = [&](const site::Feature& f) {
    std::vector<cv::Point> out;
    for (const Eigen::Vector2d& v : site.vertices(f)) {
      out.emplace_back(toPixel(v.x(), v.y()));
    }
    return out;
  };
  // Areas first (filled), then lines on top.
  for (const site::Feature& f : site.features()) {
    const std::vector<cv::Point> ring = points(f);
    if (f.kind == site::FeatureKind::Drivable) {
      cv::fillPoly(image, std::vector<std::vector<cv::Point>>{ring}, cv::Scalar(55, 55, 55));
    } else if (f.kind == site::FeatureKind::Parking) {
      cv::fillPoly(image, std::vector<std::vector<cv::Point>>{ring}, cv::Scalar(80, 45, 30));
    } else if (f.kind == site::FeatureKind::Exclusion) {
      cv::fillPoly(image, std::vector<std::vector<cv::Point>>{ring}, cv::Scalar(30, 30, 90));
    }
  }
  for (const site::Feature& f : site.features()) {
    const std::vector<cv::Point> line = points(f);
    if (line.size() < 2) {
      continue;
    }
    if (f.kind == site::FeatureKind::Zone) {
      cv::polylines(image, line, true, cv::Scalar(0, 220, 220), 1, cv::LINE_AA);
      cv::putText(image, f.id, line.front() + cv::Point(3, 12), cv::FONT_HERSHEY_SIMPLEX, 0.35,
                  cv::Scalar(0, 220, 220), 1);
    } else if (f.kind == site::FeatureKind::Lane) {
      cv::polylines(image, line, false, cv::Scalar(200, 200, 0), 1, cv::LINE_AA);
      // A head of about 10 px on the last segment, whatever its length.
      const cv::Point2d last = line.back() - line[line.size() - 2];
      const double length_px = std::max(1.0, std::hypot(last.x, last.y));
      cv::arrowedLine(image, line[line.size() - 2], line.back(), cv::Scalar(200, 200, 0), 1,
                      cv::LINE_AA, 0, std::min(0.5, 10.0 / length_px));
    } else if (f.kind == site::FeatureKind::Gate) {
      cv::polylines(image, line, false, cv::Scalar(255, 0, 255), 2, cv::LINE_AA);
      std::string text = f.id;
      if (const auto label = overlay.gateLabel.find(f.id); label != overlay.gateLabel.end()) {
        text += " " + label->second;
      }
      cv::putText(image, text, line.back() + cv::Point(4, -4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  cv::Scalar(255, 120, 255), 1);
    }
  }
}

}  // namespace

bool writeBev(const BevSettings& settings, std::span<const messages::VehicleState> vehicles,
              const messages::OccupancyGrid* grid, const std::string& path, std::string* why,
              const BevOverlay* overlay) {
  const int size = settings.size_px;
  const double scale = size / (2.0 * settings.range_m);  // px per metre
  const auto toPixel = [&](double east, double north) {
    return cv::Point2d((east - settings.centreEast_m) * scale + size / 2.0,
                       size / 2.0 - (north - settings.centreNorth_m) * scale);
  };
  cv::Mat image(size, size, CV_8UC3, cv::Scalar(0, 0, 0));
  if (grid != nullptr && !grid->cells.empty()) {
    const double res = static_cast<double>(grid->resolution_m);
    for (std::uint32_t row = 0; row < grid->rows; ++row) {
      for (std::uint32_t col = 0; col < grid->cols; ++col) {
        const messages::Occupancy cell = grid->at(row, col);
        if (cell == messages::Occupancy::Unobserved) {
          continue;
        }
        const cv::Point2d a =
            toPixel(grid->originEast_m + col * res, grid->originNorth_m + row * res);
        const cv::Point2d b =
            toPixel(grid->originEast_m + (col + 1) * res, grid->originNorth_m + (row + 1) * res);
        const cv::Scalar colour = cell == messages::Occupancy::Occupied ? cv::Scalar(110, 110, 110)
                                                                        : cv::Scalar(40, 40, 40);
        cv::rectangle(image, cv::Rect(cv::Point(a), cv::Point(b)), colour, cv::FILLED);
      }
    }
  }
  // 10 m grid lines for scale.
  for (double m = -std::floor(settings.range_m / 10) * 10; m <= settings.range_m; m += 10) {
    const cv::Point2d h0 =
        toPixel(settings.centreEast_m - settings.range_m, settings.centreNorth_m + m);
    const cv::Point2d h1 =
        toPixel(settings.centreEast_m + settings.range_m, settings.centreNorth_m + m);
    const cv::Point2d v0 =
        toPixel(settings.centreEast_m + m, settings.centreNorth_m - settings.range_m);
    const cv::Point2d v1 =
        toPixel(settings.centreEast_m + m, settings.centreNorth_m + settings.range_m);
    cv::line(image, h0, h1, cv::Scalar(60, 30, 30), 1);
    cv::line(image, v0, v1, cv::Scalar(60, 30, 30), 1);
  }
  if (overlay != nullptr && overlay->site != nullptr) {
    drawSite(image, *overlay->site, *overlay, toPixel);
  }
  for (const messages::VehicleState& v : vehicles) {
    const double c = std::cos(v.headingEnu_rad);
    const double s = std::sin(v.headingEnu_rad);
    const double hl = 0.5 * static_cast<double>(v.length_m);
    const double hw = 0.5 * static_cast<double>(v.width_m);
    const double corners[4][2] = {{hl, hw}, {hl, -hw}, {-hl, -hw}, {-hl, hw}};
    cv::Point polygon[4];
    for (int k = 0; k < 4; ++k) {
      polygon[k] = cv::Point(toPixel(v.enu_m[0] + c * corners[k][0] - s * corners[k][1],
                                     v.enu_m[1] + s * corners[k][0] + c * corners[k][1]));
    }
    const cv::Scalar colour =
        v.status == messages::TrackStatus::Lost ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 220, 0);
    cv::polylines(image, std::vector<cv::Point>(polygon, polygon + 4), true, colour, 2);
    if (v.keypointCount == shape::kKeypointCount) {
      // The ASM wireframe seen from above: the mesh's edges between the keypoints' plan
      // positions (each inner edge twice; cheap at this size).
      const auto plan = [&](std::uint16_t k) {
        return toPixel(v.keypointsEnu_m[k][0], v.keypointsEnu_m[k][1]);
      };
      for (const shape::Triangle& t : shape::mesh()) {
        for (int e = 0; e < 3; ++e) {
          cv::line(image, plan(t.v[static_cast<std::size_t>(e)]),
                   plan(t.v[static_cast<std::size_t>((e + 1) % 3)]), cv::Scalar(200, 120, 60), 1,
                   cv::LINE_AA);
        }
      }
    }
    const cv::Point2d centre = toPixel(v.enu_m[0], v.enu_m[1]);
    cv::line(image, centre, toPixel(v.enu_m[0] + c * hl, v.enu_m[1] + s * hl), colour, 2);
    cv::putText(image, std::to_string(v.trackId), centre + cv::Point2d(6, -6),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 255), 1);
  }
  if (overlay != nullptr) {
    for (const Eigen::Vector2d& mark : overlay->eventMarks_m) {
      cv::circle(image, cv::Point(toPixel(mark.x(), mark.y())), 7, cv::Scalar(255, 255, 255), 1,
                 cv::LINE_AA);
    }
    int y = 16;
    for (const std::string& line : overlay->lines) {
      cv::putText(image, line, cv::Point(8, y), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  cv::Scalar(255, 255, 255), 1);
      y += 15;
    }
  }
  const std::string temporary = path + ".tmp.png";
  try {
    if (!cv::imwrite(temporary, image)) {
      *why = path + ": OpenCV could not write the PNG";
      return false;
    }
  } catch (const cv::Exception& e) {
    *why = path + ": " + e.what();
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    *why = path + ": " + ec.message();
    return false;
  }
  return true;
}

}  // namespace vp::rsu
