// simulator/site_map: SceneSpec -> site.geojson (see the header).
#include "site_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace vp::sim {
namespace {

class GeoJsonWriter {
 public:
  explicit GeoJsonWriter(const geodesy::LocalFrame& frame) : frame_(frame) {}

  void polygon(const char* kind, const std::string& id, const std::string& name,
               const std::vector<Eigen::Vector2d>& ring) {
    std::string coordinates = "[[";
    for (const Eigen::Vector2d& p : ring) {
      coordinates += position(p) + ", ";
    }
    coordinates += position(ring.front()) + "]]";  // RFC 7946: the ring is closed
    feature(kind, id, name, "Polygon", coordinates);
  }

  void line(const char* kind, const std::string& id, const std::string& name,
            const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
    feature(kind, id, name, "LineString", "[" + position(from) + ", " + position(to) + "]");
  }

  std::string text() const {
    return "{\"type\": \"FeatureCollection\",\n \"name\": \"simulated site (vp_simulate)\",\n"
           " \"features\": [\n" +
           features_.str() + "\n]}\n";
  }

 private:
  std::string position(const Eigen::Vector2d& enu) const {
    const geodesy::GeodeticPoint p = frame_.toGeodetic(Eigen::Vector3d(enu.x(), enu.y(), 0.0));
    char buffer[64];  // 1e-9 deg: about 0.1 mm
    std::snprintf(buffer, sizeof buffer, "[%.9f, %.9f]", p.longitude_deg, p.latitude_deg);
    return buffer;
  }

  void feature(const char* kind, const std::string& id, const std::string& name, const char* type,
               const std::string& coordinates) {
    if (count_++ > 0) {
      features_ << ",\n";
    }
    features_ << "  {\"type\": \"Feature\", \"properties\": {\"kind\": \"" << kind
              << "\", \"id\": \"" << id << "\", \"name\": \"" << name
              << "\"}, \"geometry\": {\"type\": \"" << type
              << "\", \"coordinates\": " << coordinates << "}}";
  }

  const geodesy::LocalFrame& frame_;
  std::ostringstream features_;
  int count_ = 0;
};

// A rectangle: centre, unit axis, half-extents along it and across it (counter-clockwise).
std::vector<Eigen::Vector2d> rectangle(const Eigen::Vector2d& centre, const Eigen::Vector2d& dir,
                                       double halfAlong_m, double halfAcross_m) {
  const Eigen::Vector2d left(-dir.y(), dir.x());
  const Eigen::Vector2d a = dir * halfAlong_m;
  const Eigen::Vector2d c = left * halfAcross_m;
  return {centre - a - c, centre + a - c, centre + a + c, centre - a + c};
}

}  // namespace

std::string siteGeoJson(const SceneSpec& scene, const geodesy::LocalFrame& frame) {
  GeoJsonWriter out(frame);
  const bool intersection = scene.kind == SceneKind::Intersection;
  for (std::size_t r = 0; r < scene.roads.size(); ++r) {
    const Road& road = scene.roads[r];
    const std::string rid = "road-" + std::to_string(r + 1);
    // Over the generated extent around the view centre, along the road.
    const double mid_m = road.along(scene.viewCentre);
    const double from_m = mid_m - scene.extent_m;
    const double to_m = mid_m + scene.extent_m;
    const Eigen::Vector2d left = road.leftNormal();
    const Eigen::Vector2d base = road.centre + road.dir * ((from_m + to_m) / 2.0);
    const double half_m = (to_m - from_m) / 2.0;
    // Kerb to kerb: the right side is -leftNormal.
    const Eigen::Vector2d centre = base + left * ((road.leftHalf_m() - road.rightHalf_m()) / 2.0);
    out.polygon(
        "drivable", rid, "road " + std::to_string(r + 1),
        rectangle(centre, road.dir, half_m, (road.leftHalf_m() + road.rightHalf_m()) / 2.0));
    for (int lane = 0; lane < road.lanesForward; ++lane) {
      const Eigen::Vector2d offset = left * road.laneOffset_m(true, lane);
      out.line("lane", rid + "-forward-" + std::to_string(lane + 1),
               "road " + std::to_string(r + 1) + " forward lane " + std::to_string(lane + 1),
               road.centre + road.dir * from_m + offset, road.centre + road.dir * to_m + offset);
    }
    for (int lane = 0; lane < road.lanesBackward; ++lane) {
      const Eigen::Vector2d offset = left * road.laneOffset_m(false, lane);
      out.line("lane", rid + "-backward-" + std::to_string(lane + 1),
               "road " + std::to_string(r + 1) + " backward lane " + std::to_string(lane + 1),
               road.centre + road.dir * to_m + offset, road.centre + road.dir * from_m + offset);
    }
    if (intersection && road.stopDistance_m < 1e8) {
      // The two approaches: the forward lanes arrive from -dir, the backward ones from +dir.
      for (const double side : {-1.0, 1.0}) {
        const Eigen::Vector2d at = road.centre + road.dir * (side * road.stopDistance_m);
        const std::string approach = side < 0 ? "1" : "2";
        out.line("gate", rid + "-gate-" + approach,
                 "road " + std::to_string(r + 1) + " approach " + approach,
                 at - left * road.rightHalf_m(), at + left * road.leftHalf_m());
      }
    }
  }
  if (intersection && scene.roads.size() >= 2) {
    // The junction with its rounded kerb corners: the square the two carriageways and the corner
    // radii span (a turning vehicle may cut over the fillets).
    double half_m = scene.cornerRadius_m;
    for (const Road& road : scene.roads) {
      half_m =
          std::max(half_m, std::max(road.leftHalf_m(), road.rightHalf_m()) + scene.cornerRadius_m);
    }
    out.polygon("drivable", "junction", "junction",
                rectangle(scene.junction, scene.roads[0].dir, half_m, half_m));
  }
  for (std::size_t i = 0; i < scene.lots.size(); ++i) {
    const ParkingLot& lot = scene.lots[i];
    out.polygon("parking", "lot-" + std::to_string(i + 1), "parking lot " + std::to_string(i + 1),
                rectangle(lot.centre, lot.dir, lot.length_m / 2.0, lot.width_m / 2.0));
  }
  for (std::size_t i = 0; i < scene.paved.size(); ++i) {
    const Patch& p = scene.paved[i];
    out.polygon("drivable", "paved-" + std::to_string(i + 1), "paved area " + std::to_string(i + 1),
                rectangle(p.centre, p.dir, p.halfLength_m, p.halfWidth_m));
  }
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const Building& b = scene.buildings[i];
    const Eigen::Vector2d dir(std::cos(b.heading_rad), std::sin(b.heading_rad));
    out.polygon("exclusion", "building-" + std::to_string(i + 1),
                "building " + std::to_string(i + 1),
                rectangle(b.centre, dir, b.length_m / 2.0, b.width_m / 2.0));
  }
  return out.text();
}

}  // namespace vp::sim
