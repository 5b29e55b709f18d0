// fuzz/site_file: the site file loader (src/foundation/site: GeoJSON through yaml-cpp, the
// validator, the conversion to the world frame) and the queries of what it accepts, on arbitrary
// file contents.
// Contract checked: parseSite() returns true, or false with a message naming the file and an
// untouched (empty) site; it throws nothing. A site it accepts holds a drivable or parking
// area, features with a known kind, a non-empty id used once, their vertices stored one after
// the other (an area's ring at least 3 vertices, a line at least 2), every vertex finite and
// inside its feature's bounding box, and converting each vertex back to WGS84 gives a valid
// longitude/latitude. Its queries answer without failing: contains() is false for lines and
// for points outside the bounding box, classify() is OffRoad far from every area, and the same
// point always gets the same answer.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

#include <Eigen/Core>

#include "fuzz_support.hpp"
#include "geodesy/geodesy.hpp"
#include "site/site.hpp"

namespace {

constexpr const char* kTarget = "site_file";
constexpr const char* kSource = "site.geojson";

// The world frame of the seeds (the documentation's example lies around it); any other frame
// works the same, the positions are only further from the origin.
const vp::geodesy::LocalFrame& worldFrame() {
  static const vp::geodesy::LocalFrame frame(vp::geodesy::GeodeticPoint{48.1371, 11.5750, 520.0});
  return frame;
}

bool insideBox(const vp::site::Feature& f, const Eigen::Vector2d& p) {
  return p.x() >= f.min_m.x() && p.y() >= f.min_m.y() && p.x() <= f.max_m.x() &&
         p.y() <= f.max_m.y();
}

void checkAccepted(const vp::site::Site& site) {
  using vp::fuzz::expect;
  using vp::site::FeatureKind;
  expect(!site.empty(), kTarget, "an accepted site has no feature");
  expect(site.count(FeatureKind::Drivable) + site.count(FeatureKind::Parking) > 0, kTarget,
         "an accepted site has no drivable or parking area");
  expect(site.sourceName() == kSource, kTarget, "the site does not keep its file's name");
  std::set<std::string> ids;
  std::uint32_t nextVertex = 0;
  std::size_t lastIndex = 0;
  bool first = true;
  for (const vp::site::Feature& f : site.features()) {
    const std::string name = "feature " + std::to_string(f.index);
    expect(vp::site::featureKindFromString(vp::site::toString(f.kind)) == f.kind, kTarget,
           name + ": kind out of range");
    expect(!f.id.empty() && ids.insert(f.id).second, kTarget, name + ": empty or repeated id");
    expect(first || f.index > lastIndex, kTarget, name + ": features out of file order");
    first = false;
    lastIndex = f.index;
    expect(f.first == nextVertex, kTarget, name + ": vertices not stored one after the other");
    nextVertex = f.first + f.count;
    expect(f.count >= (vp::site::isArea(f.kind) ? 3U : 2U), kTarget,
           name + ": too few vertices for its kind");
    for (const Eigen::Vector2d& v : site.vertices(f)) {
      expect(v.allFinite(), kTarget, name + ": a vertex is not finite");
      expect(insideBox(f, v), kTarget, name + ": a vertex lies outside its bounding box");
      const vp::geodesy::GeodeticPoint back =
          worldFrame().toGeodetic(Eigen::Vector3d(v.x(), v.y(), 0.0));
      expect(std::isfinite(back.latitude_deg) && std::isfinite(back.longitude_deg) &&
                 std::abs(back.latitude_deg) <= 90.0 && std::abs(back.longitude_deg) <= 180.0,
             kTarget, name + ": a vertex does not convert back to a WGS84 position");
    }
    // Queries: at each vertex, at the box's centre and just outside the box.
    const Eigen::Vector2d centre = 0.5 * (f.min_m + f.max_m);
    const Eigen::Vector2d outside = f.max_m + Eigen::Vector2d(1.0, 1.0);
    if (!vp::site::isArea(f.kind)) {
      expect(!site.contains(f, centre), kTarget, name + ": a line contains a point");
    }
    expect(!site.contains(f, outside), kTarget, name + ": contains a point outside its box");
    for (const Eigen::Vector2d& p : {centre, site.vertices(f).front()}) {
      expect(site.classify(p) == site.classify(p), kTarget, name + ": classify() is unstable");
      expect(site.contains(f, p) == site.contains(f, p), kTarget,
             name + ": contains() is unstable");
    }
  }
  // Far beyond every feature (the boxes' union, plus a kilometre): off road.
  Eigen::Vector2d far(-1e300, -1e300);
  for (const vp::site::Feature& f : site.features()) {
    far = far.cwiseMax(f.max_m);
  }
  far += Eigen::Vector2d(1000.0, 1000.0);
  expect(site.classify(far) == vp::site::Placement::OffRoad, kTarget,
         "a point beyond every area is not off road");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(vp::fuzz::asText(data, size));
  vp::site::Site site;
  std::string why;
  if (!vp::site::parseSite(text, kSource, worldFrame(), &site, &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.starts_with(std::string(kSource) + ": "), kTarget,
                     "parseSite() failed without naming the file: '" + why + "'");
    vp::fuzz::expect(site.empty(), kTarget, "a refused file changed the site");
    return 0;
  }
  vp::fuzz::note(kTarget, "accepted " + std::to_string(site.features().size()) + " features");
  checkAccepted(site);
  return 0;
}
