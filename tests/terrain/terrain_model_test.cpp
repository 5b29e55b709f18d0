#include "terrain/terrain_model.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <new>
#include <random>
#include <vector>

#include <gtest/gtest.h>

// Counts heap allocations, to check that queries do not allocate.
namespace {
std::atomic<long> allocationCount{0};
}  // namespace

[[gnu::noinline]] void* operator new(std::size_t size) {
  ++allocationCount;
  if (void* p = std::malloc(size == 0 ? 1 : size)) {
    return p;
  }
  throw std::bad_alloc();
}
// Kept out of line: once inlined into the standard allocator, g++ flags the free() of a
// pointer that came from operator new (-Wmismatched-new-delete), which is intended here.
[[gnu::noinline]] void operator delete(void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace vp::terrain {
namespace {

constexpr double kPi = 3.14159265358979323846;
const geodesy::GeodeticPoint kOrigin{43.07, -89.40, 260.0};  // Madison, UTM 16N

// Max |g| over all hits the tests check; printed at the end as the measured accuracy.
double gMaxAbs = 0.0;

// A UTM 16N grid centred on the frame origin; height(e, n) with e, n relative to the
// origin's easting/northing.
struct UtmGridSpec {
  int cols = 201;
  int rows = 201;
  double cell_m = 5.0;
  std::function<double(double, double)> height;
};

geodesy::UtmPoint originUtm() {
  return geodesy::toUtm(kOrigin, 16);
}

TerrainGrid makeUtmGrid(const UtmGridSpec& spec) {
  const geodesy::UtmPoint o = originUtm();
  TerrainGrid grid;
  grid.cols = spec.cols;
  grid.rows = spec.rows;
  grid.crs = CrsSpec{HorizontalCrs::Utm, 16, true};
  grid.transform.x0 = o.easting_m - 0.5 * (spec.cols - 1) * spec.cell_m;
  grid.transform.dxCol = spec.cell_m;
  grid.transform.dxRow = 0.0;
  grid.transform.y0 = o.northing_m + 0.5 * (spec.rows - 1) * spec.cell_m;
  grid.transform.dyCol = 0.0;
  grid.transform.dyRow = -spec.cell_m;
  grid.heights_m.resize(static_cast<std::size_t>(spec.cols) * spec.rows);
  for (int r = 0; r < spec.rows; ++r) {
    for (int c = 0; c < spec.cols; ++c) {
      const double e = grid.transform.x0 + c * spec.cell_m - o.easting_m;
      const double n = grid.transform.y0 - r * spec.cell_m - o.northing_m;
      grid.heights_m[static_cast<std::size_t>(r) * spec.cols + c] =
          static_cast<float>(spec.height(e, n));
    }
  }
  return grid;
}

TerrainModel makeModel(TerrainGrid grid) {
  TerrainModel model;
  std::string why;
  EXPECT_TRUE(model.init(std::move(grid), geodesy::LocalFrame(kOrigin), &why)) << why;
  return model;
}

// Analytic height of a UTM-defined surface at an ENU point.
double analyticAtEnu(const geodesy::LocalFrame& frame, const Eigen::Vector3d& enu,
                     const std::function<double(double, double)>& height) {
  const geodesy::UtmPoint o = originUtm();
  const geodesy::UtmPoint u = geodesy::toUtm(frame.toGeodetic(enu), 16);
  return height(u.easting_m - o.easting_m, u.northing_m - o.northing_m);
}

// g at an ENU point: geodetic height minus the DTM's height there.
double gAt(const TerrainModel& model, const geodesy::LocalFrame& frame, const Eigen::Vector3d& p) {
  const geodesy::GeodeticPoint geo = frame.toGeodetic(p);
  const auto h = model.heightAt(geo.latitude_deg, geo.longitude_deg);
  EXPECT_TRUE(h.hasValue());
  return h ? geo.height_m - *h : 1e9;
}

void expectOnSurface(const TerrainModel& model, const Eigen::Vector3d& hit) {
  const double g = gAt(model, geodesy::LocalFrame(kOrigin), hit);
  gMaxAbs = std::max(gMaxAbs, std::abs(g));
  EXPECT_LT(std::abs(g), 1e-4) << "hit " << hit.transpose();
}

// Newton's method on f(t) = h(P(t)) - analytic(P(t)) from a guess: an independent solution
// for smooth analytic surfaces (planes).
double analyticRayT(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tGuess,
                    const std::function<double(double, double)>& height) {
  const geodesy::LocalFrame frame(kOrigin);
  const auto f = [&](double t) {
    const Eigen::Vector3d p = o + t * d;
    return frame.toGeodetic(p).height_m - analyticAtEnu(frame, p, height);
  };
  double t = tGuess;
  for (int i = 0; i < 50; ++i) {
    const double h = 1e-4;
    const double df = (f(t + h) - f(t - h)) / (2 * h);
    const double dt = f(t) / df;
    t -= dt;
    if (std::abs(dt) < 1e-10) {
      break;
    }
  }
  return t;
}

// First t where g changes sign along the ray, scanned with a fine fixed step (brute force)
// and bisected to 1e-9.
double bruteFirstCrossingT(const TerrainModel& model, const Eigen::Vector3d& o,
                           const Eigen::Vector3d& d, double tMax, double dt) {
  const geodesy::LocalFrame frame(kOrigin);
  double prev = gAt(model, frame, o);
  for (double t = dt; t <= tMax; t += dt) {
    const double g = gAt(model, frame, o + t * d);
    if (prev > 0.0 && g <= 0.0) {
      // Refine the bracket by plain bisection (independent of the model's own refinement).
      double lo = t - dt;
      double hi = t;
      while (hi - lo > 1e-9) {
        const double mid = 0.5 * (lo + hi);
        (gAt(model, frame, o + mid * d) > 0.0 ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    }
    prev = g;
  }
  return -1.0;
}

TEST(CrsSpec, ParsesAndPrints) {
  const auto wgs = crsFromString("WGS84");
  ASSERT_TRUE(wgs.has_value());
  EXPECT_EQ(wgs->kind, HorizontalCrs::Wgs84Geographic);
  EXPECT_EQ(toString(*wgs), "wgs84");
  const auto utm = crsFromString("utm:16N");
  ASSERT_TRUE(utm.has_value());
  EXPECT_EQ(utm->kind, HorizontalCrs::Utm);
  EXPECT_EQ(utm->utmZone, 16);
  EXPECT_TRUE(utm->utmNorth);
  EXPECT_EQ(toString(*utm), "utm:16N");
  const auto south = crsFromString("UTM:33s");
  ASSERT_TRUE(south.has_value());
  EXPECT_EQ(south->utmZone, 33);
  EXPECT_FALSE(south->utmNorth);
  EXPECT_EQ(toString(*south), "utm:33S");
  EXPECT_TRUE(crsFromString("utm:1n").has_value());
  EXPECT_TRUE(crsFromString("utm:60S").has_value());
  for (const char* bad : {"", "utm", "utm:", "utm:0N", "utm:61N", "utm:16", "utm:16X", "utm:N",
                          "utm:-5N", "utm:123N", "wgs 84", "utm16N", "utm:1 6N"}) {
    EXPECT_FALSE(crsFromString(bad).has_value()) << bad;
  }
}

TEST(TerrainModel, InitRejectsBadGrids) {
  const geodesy::LocalFrame frame(kOrigin);
  const TerrainGrid good = makeUtmGrid({5, 5, 5.0, [](double, double) { return 260.0; }});
  std::string why;
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.heights_m.pop_back();
    EXPECT_FALSE(model.init(g, frame, &why));
    EXPECT_NE(why.find("heights"), std::string::npos) << why;
  }
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.transform.dxCol = 0.0;
    g.transform.dyCol = 0.0;
    EXPECT_FALSE(model.init(g, frame, &why));
    EXPECT_NE(why.find("singular"), std::string::npos) << why;
  }
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.transform.dxCol = 5.0;
    g.transform.dyCol = 0.0;
    g.transform.dxRow = 10.0;
    g.transform.dyRow = 0.0;  // parallel axes
    EXPECT_FALSE(model.init(g, frame, &why));
  }
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.transform.x0 = std::nan("");
    EXPECT_FALSE(model.init(g, frame, &why));
  }
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.noData = 260.0F;  // every sample is NoData
    EXPECT_FALSE(model.init(g, frame, &why));
    EXPECT_NE(why.find("no valid"), std::string::npos) << why;
  }
  {
    TerrainModel model;
    TerrainGrid g = good;
    g.crs.utmZone = 61;
    EXPECT_FALSE(model.init(g, frame, &why));
  }
  {
    TerrainModel model;
    EXPECT_TRUE(model.init(good, frame, &why)) << why;
    EXPECT_FLOAT_EQ(model.minHeight_m(), 260.0F);
    EXPECT_FLOAT_EQ(model.maxHeight_m(), 260.0F);
  }
}

TEST(TerrainModel, DefaultModelAnswersOutside) {
  const TerrainModel model;
  EXPECT_FALSE(model.heightAt(kOrigin.latitude_deg, kOrigin.longitude_deg).hasValue());
  EXPECT_FALSE(
      model.intersectRay(Eigen::Vector3d(0, 0, 100), Eigen::Vector3d(0, 0, -1)).hasValue());
}

TEST(TerrainModel, HeightAtIsExactOnAPlane) {
  const double slope = std::tan(15.0 * kPi / 180.0);
  const auto plane = [slope](double e, double n) { return 260.0 + slope * e - 0.05 * n; };
  const TerrainModel model = makeModel(makeUtmGrid({101, 81, 5.0, plane}));
  EXPECT_NEAR(model.minHeight_m(), 260.0 - slope * 250.0 - 0.05 * 200.0, 1e-3);
  EXPECT_NEAR(model.maxHeight_m(), 260.0 + slope * 250.0 + 0.05 * 200.0, 1e-3);
  const geodesy::LocalFrame frame(kOrigin);
  const geodesy::UtmPoint o = originUtm();
  double maxErr = 0.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ue(-249.0, 249.0);
  std::uniform_real_distribution<double> un(-199.0, 199.0);
  for (int i = 0; i < 500; ++i) {
    geodesy::UtmPoint u = o;
    const double e = ue(rng);
    const double n = un(rng);
    u.easting_m += e;
    u.northing_m += n;
    const geodesy::GeodeticPoint p = geodesy::fromUtm(u);
    const auto h = model.heightAt(p.latitude_deg, p.longitude_deg);
    ASSERT_TRUE(h.hasValue());
    maxErr = std::max(maxErr, std::abs(*h - plane(e, n)));
  }
  // float32 storage of ~330 m heights: ~3e-5 m.
  EXPECT_LT(maxErr, 1e-4);
  std::cout << "[ measure  ] plane heightAt max error " << maxErr << " m\n";

  // heightAtEnu ignores z.
  const auto a = model.heightAtEnu(Eigen::Vector3d(30.0, 40.0, 0.0));
  const auto b = model.heightAtEnu(Eigen::Vector3d(30.0, 40.0, 500.0));
  ASSERT_TRUE(a.hasValue());
  ASSERT_TRUE(b.hasValue());
  EXPECT_NEAR(*a, analyticAtEnu(frame, Eigen::Vector3d(30.0, 40.0, 0.0), plane), 1e-4);
  EXPECT_NEAR(*a, *b, 0.05);  // the vertical is tilted only ~5e-5 rad at 50 m
}

TEST(TerrainModel, HeightAtStatusesAtEdgesOutsideAndNoData) {
  UtmGridSpec spec{21, 21, 10.0, [](double e, double) { return 260.0 + 0.1 * e; }};
  TerrainGrid grid = makeUtmGrid(spec);
  grid.noData = -9999.0F;
  grid.heights_m[10 * 21 + 10] = -9999.0F;                                // centre sample
  grid.heights_m[3 * 21 + 15] = std::numeric_limits<float>::quiet_NaN();  // NaN counts too
  const TerrainModel model = makeModel(grid);
  const geodesy::UtmPoint o = originUtm();
  const auto at = [&](double e, double n) {
    geodesy::UtmPoint u = o;
    u.easting_m += e;
    u.northing_m += n;
    const geodesy::GeodeticPoint p = geodesy::fromUtm(u);
    return model.heightAt(p.latitude_deg, p.longitude_deg);
  };
  // Corners and edges (exactly on the border) are inside.
  for (const auto& [e, n] : std::vector<std::pair<double, double>>{
           {-100, -100}, {100, 100}, {-100, 100}, {100, -100}, {0, 100}, {-100, 37}}) {
    const auto h = at(e, n);
    ASSERT_TRUE(h.hasValue()) << e << " " << n;
    EXPECT_NEAR(*h, 260.0 + 0.1 * e, 1e-4);
  }
  EXPECT_EQ(at(100.01, 0).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(at(0, -100.01).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(at(5000, 0).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(model.heightAt(10.0, 10.0).error(), TerrainError::OutsideDtm);  // other zone
  EXPECT_EQ(model.heightAt(-43.07, -89.40).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(model.heightAt(std::nan(""), -89.40).error(), TerrainError::OutsideDtm);
  // Every query whose four samples include the hole is NoData; one cell away is fine.
  EXPECT_EQ(at(0, 0).error(), TerrainError::NoData);
  EXPECT_EQ(at(-9.9, 9.9).error(), TerrainError::NoData);
  EXPECT_EQ(at(9.9, -9.9).error(), TerrainError::NoData);
  EXPECT_TRUE(at(10.1, 0).hasValue());
  EXPECT_TRUE(at(0, -10.1).hasValue());
  EXPECT_EQ(at(50 + 3, 70 - 3).error(), TerrainError::NoData);  // next to the NaN
  EXPECT_EQ(toString(TerrainError::NoData), std::string("DTM has no data there"));
}

TEST(TerrainModel, GroundPointLiesOnTheDtm) {
  const auto surface = [](double e, double n) {
    return 260.0 + 0.2 * e + 20.0 * std::sin(n / 80.0);
  };
  const TerrainModel model = makeModel(makeUtmGrid({201, 201, 5.0, surface}));
  const geodesy::LocalFrame frame(kOrigin);
  for (const auto& [x, y] :
       std::vector<std::pair<double, double>>{{0, 0}, {300, -200}, {-450, 450}, {123.4, 56.7}}) {
    const auto p = model.groundPointEnu(x, y);
    ASSERT_TRUE(p.hasValue());
    EXPECT_DOUBLE_EQ(p->x(), x);
    EXPECT_DOUBLE_EQ(p->y(), y);
    EXPECT_LT(std::abs(gAt(model, frame, *p)), 1e-6);
  }
  EXPECT_EQ(model.groundPointEnu(5000, 0).error(), TerrainError::OutsideDtm);
}

TEST(TerrainModel, VerticalRayOnFlatGrid) {
  const TerrainModel model =
      makeModel(makeUtmGrid({201, 201, 5.0, [](double, double) { return 250.0; }}));
  const auto hit = model.intersectRay(Eigen::Vector3d(0, 0, 100), Eigen::Vector3d(0, 0, -1));
  ASSERT_TRUE(hit.hasValue());
  EXPECT_NEAR(hit->x(), 0.0, 1e-9);
  EXPECT_NEAR(hit->y(), 0.0, 1e-9);
  EXPECT_NEAR(hit->z(), -10.0, 1e-5);  // the frame origin is at 260 m
  expectOnSurface(model, *hit);
}

TEST(TerrainModel, ObliqueRayOnFlatGridAccountsForCurvature) {
  const TerrainModel model =
      makeModel(makeUtmGrid({201, 201, 5.0, [](double, double) { return 250.0; }}));
  const geodesy::LocalFrame frame(kOrigin);
  // Hits about 440 m away, where the ground (250 m) is ~1.5 cm lower in ENU than at the
  // origin; a flat-Earth intersection (z = -10) would be off by that much.
  const Eigen::Vector3d origin(0, 0, 30);
  const Eigen::Vector3d dir(0.8, 0.6, -0.08);
  const auto hit = model.intersectRay(origin, dir);
  ASSERT_TRUE(hit.hasValue());
  expectOnSurface(model, *hit);
  EXPECT_NEAR(frame.toGeodetic(*hit).height_m, 250.0, 1e-4);
  EXPECT_LT(hit->z(), -10.01);
  const double tAnalytic = analyticRayT(origin, dir, 500.0, [](double, double) { return 250.0; });
  EXPECT_NEAR((*hit - (origin + tAnalytic * dir)).norm(), 0.0, 1e-4);
}

TEST(TerrainModel, RaysOnFifteenDegreeSlopeMatchAnalyticIntersection) {
  const double slope = std::tan(15.0 * kPi / 180.0);
  const auto plane = [slope](double e, double n) { return 260.0 + slope * e + 0.02 * n; };
  const TerrainModel model = makeModel(makeUtmGrid({201, 201, 5.0, plane}));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-300.0, 300.0);
  std::uniform_real_distribution<double> az(0.0, 2 * kPi);
  std::uniform_real_distribution<double> dip(0.15, 1.5);
  double maxDist = 0.0;
  int hits = 0;
  for (int i = 0; i < 200; ++i) {
    const double x = pos(rng);
    const double y = pos(rng);
    const Eigen::Vector3d origin(x, y, plane(x, y) - 260.0 + 60.0);
    const double a = az(rng);
    const double d = dip(rng);
    const Eigen::Vector3d dir(std::cos(d) * std::sin(a), std::cos(d) * std::cos(a), -std::sin(d));
    const auto hit = model.intersectRay(origin, 3.0 * dir);  // not unit length on purpose
    if (!hit) {
      EXPECT_EQ(hit.error(), TerrainError::OutsideDtm);  // left the grid first
      continue;
    }
    ++hits;
    expectOnSurface(model, *hit);
    const double tGuess = (*hit - origin).norm() / 3.0;
    const double t = analyticRayT(origin, 3.0 * dir, tGuess, plane);
    maxDist = std::max(maxDist, (*hit - (origin + t * 3.0 * dir)).norm());
  }
  EXPECT_GT(hits, 150);
  EXPECT_LT(maxDist, 2e-4);
  std::cout << "[ measure  ] 15 deg slope: " << hits << " hits, max distance to analytic "
            << maxDist << " m\n";
}

TEST(TerrainModel, SixtyDegreeSlope) {
  const double slope = std::tan(60.0 * kPi / 180.0);
  const auto plane = [slope](double, double n) { return 260.0 + slope * n; };
  const TerrainModel model = makeModel(makeUtmGrid({81, 81, 5.0, plane}));
  double maxDist = 0.0;
  // Looking north into the face, down the face, along it and straight down.
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> rays{
      {{0, -150, 0}, {0, 1, 0}},         // horizontal into the face
      {{0, -150, 50}, {0, 1, -0.5}},     // downward into the face
      {{0, 100, 300}, {0, -1, -3}},      // downhill, the ray steeper than the face
      {{10, 20, 300}, {0.3, -0.2, -1}},  // mostly downward
      {{0, 0, 100}, {0, 0, -1}},         // vertical
      {{-80, -50, 20}, {1, 0.5, 0}},     // horizontal, oblique to the contours
  };
  for (const auto& [origin, dir] : rays) {
    const auto hit = model.intersectRay(origin, dir);
    ASSERT_TRUE(hit.hasValue()) << origin.transpose() << " / " << dir.transpose();
    expectOnSurface(model, *hit);
    const double t = analyticRayT(origin, dir, (*hit - origin).norm() / dir.norm(), plane);
    maxDist = std::max(maxDist, (*hit - (origin + t * dir)).norm());
    const double tBrute = bruteFirstCrossingT(model, origin, dir, 1000.0 / dir.norm(), 0.01);
    EXPECT_NEAR((*hit - origin).norm() / dir.norm(), tBrute, 1e-3);
  }
  EXPECT_LT(maxDist, 2e-4);
  std::cout << "[ measure  ] 60 deg slope max distance to analytic " << maxDist << " m\n";
}

// A north-south ridge 100 m east of the origin, 30 m above a flat 260 m floor.
double ridge(double e, double) {
  const double u = (e - 100.0) / 20.0;
  return 260.0 + 30.0 * std::exp(-u * u);
}

TEST(TerrainModel, GrazingRayOverRidgeReturnsFirstCrossing) {
  const TerrainModel model = makeModel(makeUtmGrid({401, 201, 5.0, ridge}));
  const geodesy::LocalFrame frame(kOrigin);
  // Descending rays that clip the ridge near its top and, beyond it, reach the floor again.
  for (const double z0 : {29.0, 29.5, 29.8}) {
    const Eigen::Vector3d origin(0, 0, z0);
    const Eigen::Vector3d dir(1, 0.01, -0.01);
    const auto hit = model.intersectRay(origin, dir);
    ASSERT_TRUE(hit.hasValue()) << z0;
    expectOnSurface(model, *hit);
    EXPECT_LT(hit->x(), 100.0) << z0;  // the front face, not the floor ~2900 m on
    const double tBrute = bruteFirstCrossingT(model, origin, dir, 200.0, 0.005);
    EXPECT_NEAR(hit->x(), tBrute, 1e-3) << z0;
  }
  // A ray passing just over the crest continues to the floor far beyond.
  const Eigen::Vector3d origin(0, 0, 31.0);
  const Eigen::Vector3d dir(1, 0, -0.002);
  const auto over = model.intersectRay(origin, dir);
  EXPECT_FALSE(over.hasValue());  // the floor would be at ~15 km, off the grid
  EXPECT_EQ(over.error(), TerrainError::OutsideDtm);
  // A steeper ray clears the crest and lands on the floor behind it.
  const auto behind = model.intersectRay(Eigen::Vector3d(0, 0, 40.0), Eigen::Vector3d(1, 0, -0.05));
  ASSERT_TRUE(behind.hasValue());
  expectOnSurface(model, *behind);
  EXPECT_GT(behind->x(), 150.0);
}

TEST(TerrainModel, RandomRaysOverHillsFindTheFirstCrossing) {
  const auto hills = [](double e, double n) {
    return 260.0 + 15.0 * std::sin(e / 37.0) * std::cos(n / 23.0) + 0.05 * e;
  };
  const TerrainModel model = makeModel(makeUtmGrid({161, 161, 5.0, hills}));
  const geodesy::LocalFrame frame(kOrigin);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-300.0, 300.0);
  std::uniform_real_distribution<double> az(0.0, 2 * kPi);
  std::uniform_real_distribution<double> dip(0.01, 0.6);
  int hits = 0;
  for (int i = 0; i < 150; ++i) {
    const double x = pos(rng);
    const double y = pos(rng);
    const Eigen::Vector3d origin(x, y, 40.0);
    const double a = az(rng);
    const double d = dip(rng);
    const Eigen::Vector3d dir(std::cos(d) * std::sin(a), std::cos(d) * std::cos(a), -std::sin(d));
    const auto hit = model.intersectRay(origin, dir);
    if (!hit) {
      EXPECT_EQ(hit.error(), TerrainError::OutsideDtm);  // descending, left the grid first
      continue;
    }
    ++hits;
    expectOnSurface(model, *hit);
    const double t = (*hit - origin).norm();
    // No earlier crossing at a 5 cm scan.
    const double tBrute = bruteFirstCrossingT(model, origin, dir, t + 1.0, 0.05);
    EXPECT_NEAR(t, tBrute, 1e-4) << i;
  }
  EXPECT_GT(hits, 100);
  std::cout << "[ measure  ] hills: " << hits << " hits of 150 rays\n";
}

TEST(TerrainModel, RayStatuses) {
  const TerrainModel model =
      makeModel(makeUtmGrid({81, 81, 5.0, [](double e, double) { return 260.0 + 0.1 * e; }}));
  // Pointing up, or horizontal above the highest sample.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d(0.1, 0, 1)).error(),
            TerrainError::NoIntersection);
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 200), Eigen::Vector3d(1, 0, 0)).error(),
            TerrainError::NoIntersection);
  // Leaves the grid (±200 m) before descending to the ground: its ground point is off it.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d(0, 1, -0.01)).error(),
            TerrainError::OutsideDtm);
  // Level, below the highest sample but above the ground here: leaves without meeting it.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 15), Eigen::Vector3d(-1, 0, 0)).error(),
            TerrainError::NoIntersection);
  // Never comes near the grid.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(5000, 0, 50), Eigen::Vector3d(1, 0, -1)).error(),
            TerrainError::OutsideDtm);
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 500, 50), Eigen::Vector3d(1, 0, -0.1)).error(),
            TerrainError::OutsideDtm);
  // Comes from outside, enters the grid's side below the surface: the crossing is outside.
  EXPECT_EQ(
      model.intersectRay(Eigen::Vector3d(100, 400, 0), Eigen::Vector3d(0, -1, -0.001)).error(),
      TerrainError::OutsideDtm);
  // ...but from outside above the surface, it hits inside.
  const auto inside = model.intersectRay(Eigen::Vector3d(-400, 0, 50), Eigen::Vector3d(1, 0, -0.2));
  ASSERT_TRUE(inside.hasValue());
  expectOnSurface(model, *inside);
  // Origin under the ground.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, -5), Eigen::Vector3d(0, 0, -1)).error(),
            TerrainError::NoIntersection);
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, -5), Eigen::Vector3d(0, 0, 1)).error(),
            TerrainError::NoIntersection);
  // Degenerate direction.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d::Zero()).error(),
            TerrainError::NoIntersection);
}

TEST(TerrainModel, RaysAndNoDataHoles) {
  TerrainGrid grid = makeUtmGrid({81, 81, 5.0, [](double, double) { return 255.0; }});
  grid.noData = -9999.0F;
  // A hole of 5 x 5 samples centred 50 m east of the origin (col 50, row 40).
  for (int r = 38; r <= 42; ++r) {
    for (int c = 48; c <= 52; ++c) {
      grid.heights_m[static_cast<std::size_t>(r) * 81 + c] = -9999.0F;
    }
  }
  const TerrainModel model = makeModel(grid);
  // Straight down into the hole.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(50, 0, 50), Eigen::Vector3d(0, 0, -1)).error(),
            TerrainError::NoData);
  // Oblique, the crossing would be in the hole.
  EXPECT_EQ(model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d(1, 0, -1)).error(),
            TerrainError::NoData);
  // Passing over the hole (high above) and hitting beyond it.
  const auto beyond = model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d(1, 0, -0.5));
  ASSERT_TRUE(beyond.hasValue());
  expectOnSurface(model, *beyond);
  EXPECT_NEAR(beyond->x(), 110.0, 0.1);
  // Hitting before the hole.
  const auto before = model.intersectRay(Eigen::Vector3d(0, 0, 50), Eigen::Vector3d(1, 0, -2));
  ASSERT_TRUE(before.hasValue());
  EXPECT_NEAR(before->x(), 27.5, 0.01);
}

TEST(TerrainModel, GeographicGrid) {
  // 0.0001 deg steps (~8 m east, ~11 m north), heights a plane in (lon, lat).
  TerrainGrid grid;
  grid.cols = 121;
  grid.rows = 101;
  grid.crs = CrsSpec{HorizontalCrs::Wgs84Geographic, 0, true};
  grid.transform = GeoTransform{kOrigin.longitude_deg - 0.006, 1e-4, 0.0,
                                kOrigin.latitude_deg + 0.005,  0.0,  -1e-4};
  const auto plane = [](double lat, double lon) {
    return 260.0 + 2000.0 * (lat - 43.07) - 1000.0 * (lon + 89.40);
  };
  grid.heights_m.resize(121 * 101);
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      grid.heights_m[static_cast<std::size_t>(r) * grid.cols + c] =
          static_cast<float>(plane(grid.transform.y0 - r * 1e-4, grid.transform.x0 + c * 1e-4));
    }
  }
  const TerrainModel model = makeModel(grid);
  const auto h = model.heightAt(43.0712345, -89.4023456);
  ASSERT_TRUE(h.hasValue());
  EXPECT_NEAR(*h, plane(43.0712345, -89.4023456), 1e-4);
  EXPECT_EQ(model.heightAt(43.0712345, -89.3939).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(model.heightAt(43.0751, -89.40).error(), TerrainError::OutsideDtm);
  EXPECT_EQ(model.heightAt(43.07, 270.60).hasValue(), true);  // same meridian, wrapped

  const geodesy::LocalFrame frame(kOrigin);
  for (const Eigen::Vector3d& dir :
       {Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 1, -0.5), Eigen::Vector3d(-0.3, 1, -0.2)}) {
    const auto hit = model.intersectRay(Eigen::Vector3d(10, -20, 60), dir);
    ASSERT_TRUE(hit.hasValue()) << dir.transpose();
    expectOnSurface(model, *hit);
    const geodesy::GeodeticPoint g = frame.toGeodetic(*hit);
    EXPECT_NEAR(g.height_m, plane(g.latitude_deg, g.longitude_deg), 1e-4);
  }
}

TEST(TerrainModel, SouthernZoneGridAcrossTheEquator) {
  // utm:33S grid straddling the equator: points north of it come back from UTM with
  // northp = true and must be shifted by the false northing.
  const geodesy::GeodeticPoint origin{0.0, 15.0, 100.0};
  const geodesy::UtmPoint o = geodesy::toUtm(origin, 33);
  TerrainGrid grid;
  grid.cols = 41;
  grid.rows = 41;
  grid.crs = CrsSpec{HorizontalCrs::Utm, 33, false};
  const double northingSouth = o.northp ? o.northing_m + 10000000.0 : o.northing_m;
  grid.transform = GeoTransform{o.easting_m - 100.0, 5.0, 0.0, northingSouth + 100.0, 0.0, -5.0};
  grid.heights_m.resize(41 * 41);
  for (int r = 0; r < 41; ++r) {
    for (int c = 0; c < 41; ++c) {
      grid.heights_m[static_cast<std::size_t>(r) * 41 + c] = static_cast<float>(100.0 + r);
    }
  }
  TerrainModel model;
  std::string why;
  ASSERT_TRUE(model.init(grid, geodesy::LocalFrame(origin), &why)) << why;
  const auto north = model.heightAt(0.0005, 15.0);  // ~55 m north: row ~9
  const auto south = model.heightAt(-0.0005, 15.0);
  ASSERT_TRUE(north.hasValue());
  ASSERT_TRUE(south.hasValue());
  EXPECT_NEAR(*north, 100.0 + 20.0 - 55.3 / 5.0, 0.05);
  EXPECT_NEAR(*south, 100.0 + 20.0 + 55.3 / 5.0, 0.05);
}

TEST(TerrainModel, QueriesDoNotAllocate) {
  TerrainGrid grid = makeUtmGrid({81, 81, 5.0, ridge});
  grid.noData = -9999.0F;
  grid.heights_m[40 * 81 + 60] = -9999.0F;
  const TerrainModel model = makeModel(grid);
  const long before = allocationCount.load();
  double sink = 0.0;
  for (int i = 0; i < 20; ++i) {
    const auto h = model.heightAt(kOrigin.latitude_deg + 1e-5 * i, kOrigin.longitude_deg);
    sink += h ? *h : 0.0;
    sink += model.heightAtEnu(Eigen::Vector3d(i, -i, 3.0)).hasValue() ? 1.0 : 0.0;
    const auto g = model.groundPointEnu(5.0 * i, 2.0 * i);
    sink += g ? g->z() : 0.0;
    const auto hit =
        model.intersectRay(Eigen::Vector3d(0, 0, 40), Eigen::Vector3d(1, 0.05 * i, -0.1));
    sink += hit ? hit->x() : 0.0;
    sink += model.heightAt(10.0, 10.0).hasValue() ? 1.0 : 0.0;  // far away
    sink += model.intersectRay(Eigen::Vector3d(5000, 0, 50), Eigen::Vector3d(1, 0, -1)).hasValue()
                ? 1.0
                : 0.0;
  }
  EXPECT_EQ(allocationCount.load(), before);
  // The counter does see allocations.
  const auto probe = std::make_unique<std::vector<double>>(100, 1.0);
  sink += probe->back();
  EXPECT_GT(allocationCount.load(), before);
  EXPECT_TRUE(std::isfinite(sink));
}

// Prints the largest |g| seen at any hit when the binary ends (the measured accuracy).
class ReportAccuracy : public ::testing::Environment {
 public:
  void TearDown() override {
    std::cout << "[ measure  ] max |g| over all checked hits: " << gMaxAbs << " m\n";
  }
};
[[maybe_unused]] ::testing::Environment* const kReportAccuracy =
    ::testing::AddGlobalTestEnvironment(new ReportAccuracy);

}  // namespace
}  // namespace vp::terrain

namespace vp::terrain {
namespace {

// coverage(): a surface model over the same area covers the DTM; one missing its eastern part
// is found off it there, NoData holes are told apart, and samplePosition() places sample centres.
TEST(TerrainCoverage, FindsThePartOfTheDtmASurfaceModelMisses) {
  const auto flat = [](double, double) { return 260.0; };
  const TerrainModel dtm = makeModel(makeUtmGrid({41, 41, 5.0, flat}));  // +-100 m
  const TerrainModel same = makeModel(makeUtmGrid({81, 81, 2.5, flat}));
  const Coverage full = coverage(dtm, same);
  EXPECT_EQ(full.checked, 41U * 41U);
  EXPECT_EQ(full.outside + full.noData, 0U);

  // +-60 m: the DTM's ring beyond 60 m is off it, on every side.
  const TerrainModel smaller = makeModel(makeUtmGrid({25, 25, 5.0, flat}));
  const Coverage part = coverage(dtm, smaller);
  EXPECT_EQ(part.checked, 41U * 41U);
  EXPECT_EQ(part.outside, 41U * 41U - 25U * 25U);
  // The grid's corners in ENU: UTM grid north is 1.6 degrees off true north here (2.8 m at
  // 100 m).
  EXPECT_NEAR(part.outsideMin_m.x(), -100.0, 4.0);
  EXPECT_NEAR(part.outsideMax_m.y(), 100.0, 4.0);

  // NoData in the cover: counted apart, where it is.
  TerrainGrid holed = makeUtmGrid({41, 41, 5.0, flat});
  holed.noData = -9999.0F;
  holed.heights_m[20 * 41 + 30] = -9999.0F;  // 50 m east of the centre
  const Coverage holes = coverage(dtm, makeModel(holed));
  EXPECT_EQ(holes.outside, 0U);
  EXPECT_GT(holes.noData, 0U);
  // The points whose interpolation touches the hole: within a cell of it.
  EXPECT_GE(holes.noDataMin_m.x(), 44.0);
  EXPECT_LE(holes.noDataMax_m.x(), 56.0);
  EXPECT_LE(holes.noDataMin_m.x(), 50.5);
  EXPECT_GE(holes.noDataMax_m.x(), 49.5);

  const auto centre = dtm.samplePosition(20, 20);
  ASSERT_TRUE(centre.hasValue());
  EXPECT_NEAR(centre->latitude_deg, kOrigin.latitude_deg, 1e-7);
  EXPECT_NEAR(centre->longitude_deg, kOrigin.longitude_deg, 1e-7);
  EXPECT_FALSE(dtm.samplePosition(41, 0).hasValue());
}

}  // namespace
}  // namespace vp::terrain
