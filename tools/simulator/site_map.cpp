// simulator/site_map: SceneSpec -> site.geojson (see the header).
#include "site_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace vp::sim {
namespace {

constexpr double kQueueZoneLength_m = 40.0;  // a queue zone's length upstream of the stop line

class GeoJsonWriter {
 public:
  explicit GeoJsonWriter(const geodesy::LocalFrame& frame) : frame_(frame) {}

  void polygon(const char* kind, const std::string& id, const std::string& name,
               const std::vector<Eigen::Vector2d>& ring, const std::string& extra = "") {
    std::string coordinates = "[[";
    for (const Eigen::Vector2d& p : ring) {
      coordinates += position(p) + ", ";
    }
    coordinates += position(ring.front()) + "]]";  // RFC 7946: the ring is closed
    feature(kind, id, name, "Polygon", coordinates, extra);
  }

  void line(const char* kind, const std::string& id, const std::string& name,
            const Eigen::Vector2d& from, const Eigen::Vector2d& to, const std::string& extra = "") {
    feature(kind, id, name, "LineString", "[" + position(from) + ", " + position(to) + "]", extra);
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

  // extra: further properties, each as `, "key": value`.
  void feature(const char* kind, const std::string& id, const std::string& name, const char* type,
               const std::string& coordinates, const std::string& extra) {
    if (count_++ > 0) {
      features_ << ",\n";
    }
    features_ << "  {\"type\": \"Feature\", \"properties\": {\"kind\": \"" << kind
              << "\", \"id\": \"" << id << "\", \"name\": \"" << name << "\"" << extra
              << "}, \"geometry\": {\"type\": \"" << type << "\", \"coordinates\": " << coordinates
              << "}}";
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

// A traffic island's outline, counter-clockwise: a tip at each pointed end, two corners at a
// blunt one.
std::vector<Eigen::Vector2d> outline(const Island& island) {
  const Eigen::Vector2d left(-island.dir.y(), island.dir.x());
  const auto at = [&](double along, double across) {
    return Eigen::Vector2d(island.centre + along * island.dir + across * left);
  };
  const double l = island.halfLength_m;
  const double w = island.halfWidth_m;
  std::vector<Eigen::Vector2d> ring;
  if (island.noseLength_m > 0.0) {
    ring.push_back(at(-l, 0.0));
    ring.push_back(at(-l + island.noseLength_m, -w));
  } else {
    ring.push_back(at(-l, w));
    ring.push_back(at(-l, -w));
  }
  if (island.noseHighLength_m > 0.0) {
    ring.push_back(at(l - island.noseHighLength_m, -w));
    ring.push_back(at(l, 0.0));
  } else {
    ring.push_back(at(l, -w));
    ring.push_back(at(l, w));
  }
  if (island.noseHighLength_m > 0.0) {
    ring.push_back(at(l - island.noseHighLength_m, w));
  }
  if (island.noseLength_m > 0.0) {
    ring.push_back(at(-l + island.noseLength_m, w));
  }
  return ring;
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
    const bool stopLines = intersection && road.stopDistance_m < 1e8;
    char widthText[48];
    std::snprintf(widthText, sizeof widthText, ", \"width_m\": %.3f", road.laneWidth_m);
    const std::string width = widthText;
    // Each travel lane in its driving direction. At an intersection a lane ends at its stop line
    // (the queue zone before it names it) and its continuation starts beyond the junction.
    for (const bool forward : {true, false}) {
      const int lanes = forward ? road.lanesForward : road.lanesBackward;
      const double sign = forward ? 1.0 : -1.0;  // along the driving direction
      const double start_m = forward ? from_m : to_m;
      const double end_m = forward ? to_m : from_m;
      const std::string way = forward ? "forward" : "backward";
      for (int lane = 0; lane < lanes; ++lane) {
        const Eigen::Vector2d offset = left * road.laneOffset_m(forward, lane);
        const auto at = [&](double along_m) { return road.centre + road.dir * along_m + offset; };
        const std::string id = rid + "-" + way + "-" + std::to_string(lane + 1);
        const std::string name =
            "road " + std::to_string(r + 1) + " " + way + " lane " + std::to_string(lane + 1);
        const double stop_m = -sign * road.stopDistance_m;  // the approach's stop line
        if (!stopLines || sign * (stop_m - start_m) < 1.0) {
          out.line("lane", id, name, at(start_m), at(end_m), width);
          continue;
        }
        out.line("lane", id, name + " (approach)", at(start_m), at(stop_m), width);
        if (sign * (end_m + stop_m) > 1.0) {
          out.line("lane", id + "-exit", name + " (exit)", at(-stop_m), at(end_m), width);
        }
        // The queue: the lane's width over kQueueZoneLength_m upstream of the stop line.
        const double length_m = std::min(kQueueZoneLength_m, sign * (stop_m - start_m));
        const Eigen::Vector2d middle = at(stop_m - sign * length_m / 2.0);
        out.polygon("zone", id + "-queue", name + " queue",
                    rectangle(middle, road.dir, length_m / 2.0, road.laneWidth_m / 2.0),
                    ", \"role\": \"queue\", \"lane\": \"" + id + "\"");
      }
    }
    if (stopLines) {
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
    // The box junction: where the two carriageways' travel lanes cross (a parallelogram).
    const Road& a = scene.roads[0];
    const Road& b = scene.roads[1];
    const auto travelRight = [](const Road& road) {
      return road.medianHalf_m + road.lanesForward * road.laneWidth_m;
    };
    const auto travelLeft = [](const Road& road) {
      return road.medianHalf_m + road.lanesBackward * road.laneWidth_m;
    };
    const Eigen::Vector2d na = a.leftNormal();
    const Eigen::Vector2d nb = b.leftNormal();
    const double det = na.x() * nb.y() - na.y() * nb.x();
    if (std::abs(det) > 0.2) {
      // The point whose lateral offsets are la from road a's centre line and lb from b's.
      const auto corner = [&](double la, double lb) {
        const double ca = la + na.dot(a.centre);
        const double cb = lb + nb.dot(b.centre);
        return Eigen::Vector2d((ca * nb.y() - na.y() * cb) / det,
                               (na.x() * cb - ca * nb.x()) / det);
      };
      out.polygon("zone", "junction-box", "box junction",
                  {corner(-travelRight(a), -travelRight(b)), corner(travelLeft(a), -travelRight(b)),
                   corner(travelLeft(a), travelLeft(b)), corner(-travelRight(a), travelLeft(b))},
                  ", \"role\": \"box_junction\"");
    }
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
  for (std::size_t i = 0; i < scene.islands.size(); ++i) {
    out.polygon("exclusion", "island-" + std::to_string(i + 1),
                "traffic island " + std::to_string(i + 1), outline(scene.islands[i]));
  }
  return out.text();
}

}  // namespace vp::sim
