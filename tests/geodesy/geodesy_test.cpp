#include "geodesy/geodesy.hpp"

#include <cmath>
#include <optional>
#include <vector>

#include <gtest/gtest.h>
#include <GeographicLib/LocalCartesian.hpp>

namespace vp::geodesy {
namespace {

const GeodeticPoint kMadison{43.0731, -89.4012, 260.0};

TEST(LocalFrame, OriginMapsToZero) {
  const LocalFrame frame(kMadison);
  const Eigen::Vector3d enu = frame.toEnu(kMadison);
  EXPECT_NEAR(enu.norm(), 0.0, 1e-9);
}

TEST(LocalFrame, AxesPointEastNorthUp) {
  const LocalFrame frame(kMadison);
  // 0.001 deg of latitude is about 111 m north; of longitude about 81 m east at 43 deg.
  const Eigen::Vector3d north =
      frame.toEnu({kMadison.latitude_deg + 0.001, kMadison.longitude_deg, kMadison.height_m});
  EXPECT_NEAR(north.x(), 0.0, 1e-6);
  EXPECT_NEAR(north.y(), 111.1, 0.5);
  const Eigen::Vector3d east =
      frame.toEnu({kMadison.latitude_deg, kMadison.longitude_deg + 0.001, kMadison.height_m});
  EXPECT_NEAR(east.x(), 81.4, 0.5);
  EXPECT_GT(east.x(), 0.0);
  const Eigen::Vector3d up = frame.toEnu({kMadison.latitude_deg, kMadison.longitude_deg, 300.0});
  EXPECT_NEAR(up.z(), 40.0, 1e-6);
}

TEST(LocalFrame, RoundTripIsExact) {
  const LocalFrame frame(kMadison);
  for (double x = -2000.0; x <= 2000.0; x += 400.0) {
    for (double y = -2000.0; y <= 2000.0; y += 400.0) {
      const Eigen::Vector3d enu(x, y, 35.0);
      const Eigen::Vector3d back = frame.toEnu(frame.toGeodetic(enu));
      EXPECT_LT((back - enu).norm(), 1e-8) << x << ", " << y;
    }
  }
}

TEST(LocalFrame, LocalToWorldRotationMatchesGeographicLib) {
  const LocalFrame frame(kMadison);
  const GeographicLib::LocalCartesian reference(kMadison.latitude_deg, kMadison.longitude_deg,
                                                kMadison.height_m);
  const GeodeticPoint far{43.09, -89.37, 400.0};
  Eigen::Matrix3d m;
  const Eigen::Vector3d enu = frame.toEnu(far, &m);
  std::vector<double> expected(9);
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  reference.Forward(far.latitude_deg, far.longitude_deg, far.height_m, x, y, z, expected);
  EXPECT_NEAR(enu.x(), x, 1e-9);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(m(r, c), expected[static_cast<std::size_t>(3 * r + c)], 1e-12);
    }
  }
  EXPECT_NEAR((m * m.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  Eigen::Matrix3d atOrigin;
  frame.toEnu(kMadison, &atOrigin);
  EXPECT_NEAR((atOrigin - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
}

TEST(Utm, MadisonIsInZone16NorthAndRoundTrips) {
  const UtmPoint utm = toUtm(kMadison);
  EXPECT_EQ(utm.zone, 16);
  EXPECT_TRUE(utm.northp);
  // Madison's capitol area lies near 306 km E, 4771 km N in UTM 16N.
  EXPECT_NEAR(utm.easting_m, 305800.0, 1500.0);
  EXPECT_NEAR(utm.northing_m, 4771500.0, 1500.0);
  const GeodeticPoint back = fromUtm(utm);
  EXPECT_NEAR(back.latitude_deg, kMadison.latitude_deg, 1e-10);
  EXPECT_NEAR(back.longitude_deg, kMadison.longitude_deg, 1e-10);
  EXPECT_DOUBLE_EQ(back.height_m, kMadison.height_m);
}

TEST(Utm, ForcedZoneIsHonouredAndRoundTrips) {
  const UtmPoint utm = toUtm(kMadison, 15);
  EXPECT_EQ(utm.zone, 15);
  const GeodeticPoint back = fromUtm(utm);
  EXPECT_NEAR(back.latitude_deg, kMadison.latitude_deg, 1e-10);
  EXPECT_NEAR(back.longitude_deg, kMadison.longitude_deg, 1e-10);
}

TEST(Utm, SouthernHemisphere) {
  const UtmPoint utm = toUtm({-33.8688, 151.2093, 10.0});  // Sydney
  EXPECT_EQ(utm.zone, 56);
  EXPECT_FALSE(utm.northp);
}

// Published reference points. Their coordinates are given on GRS80 (the Australian ones) or
// WGS84; the two ellipsoids differ by 0.1 mm in the semi-minor axis, far below these tolerances.
double dms(double deg, double min, double sec) {
  const double sign = deg < 0.0 ? -1.0 : 1.0;
  return sign * (std::abs(deg) + min / 60.0 + sec / 3600.0);
}

struct ReferencePoint {
  const char* name;
  GeodeticPoint point;
  int zone;
  bool north;
  double easting_m;
  double northing_m;
  double tolerance_m;  // half a unit of the last published digit
};

TEST(Utm, MatchesPublishedReferencePoints) {
  const ReferencePoint points[] = {
      // GDA94 Technical Manual, worked examples of the grid conversion (MGA = UTM on GRS80),
      // published to the millimetre.
      {"Buninyong",
       {dms(-37, 39, 10.15610), dms(143, 55, 35.38390), 0.0},
       54,
       false,
       758173.797,
       5828674.340,
       0.0005},
      {"Flinders Peak",
       {dms(-37, 57, 3.72030), dms(144, 25, 29.52440), 0.0},
       55,
       false,
       273741.297,
       5796489.777,
       0.0005},
      // GeographicLib's GeoConvert manual page: 33.3 N 44.4 E is 38n 444140.54 3684706.36.
      {"GeoConvert example", {33.3, 44.4, 0.0}, 38, true, 444140.54, 3684706.36, 0.005},
  };
  for (const ReferencePoint& r : points) {
    for (const std::optional<UtmPoint>& utm :
         {std::optional<UtmPoint>(toUtm(r.point)), tryUtm(r.point)}) {
      ASSERT_TRUE(utm.has_value()) << r.name;
      EXPECT_EQ(utm->zone, r.zone) << r.name;
      EXPECT_EQ(utm->northp, r.north) << r.name;
      EXPECT_NEAR(utm->easting_m, r.easting_m, r.tolerance_m) << r.name;
      EXPECT_NEAR(utm->northing_m, r.northing_m, r.tolerance_m) << r.name;
    }
    // And back: the published grid coordinates give the published geodetic point within their
    // rounding (1 m is less than 1.5e-5 deg of latitude or longitude below 45 deg).
    const GeodeticPoint back = fromUtm({r.zone, r.north, r.easting_m, r.northing_m, 0.0});
    const double tolerance_deg = 1.5e-5 * r.tolerance_m;
    EXPECT_NEAR(back.latitude_deg, r.point.latitude_deg, tolerance_deg) << r.name;
    EXPECT_NEAR(back.longitude_deg, r.point.longitude_deg, tolerance_deg) << r.name;
  }
}

TEST(Utm, FalseNorthingOnlySouthOfTheEquator) {
  const std::optional<UtmPoint> north = tryUtm({1e-7, 9.0, 0.0});  // zone 32's central meridian
  const std::optional<UtmPoint> south = tryUtm({-1e-7, 9.0, 0.0});
  ASSERT_TRUE(north && south);
  EXPECT_EQ(north->zone, 32);
  EXPECT_TRUE(north->northp);
  EXPECT_FALSE(south->northp);
  EXPECT_NEAR(north->easting_m, 500000.0, 1e-6);
  EXPECT_NEAR(north->northing_m, 0.0111, 0.001);  // 1e-7 deg = 11 mm
  EXPECT_NEAR(south->northing_m, 10000000.0 - 0.0111, 0.001);
}

TEST(Utm, ZoneOfTheLongitudeWithTheNorwayAndSvalbardExceptions) {
  EXPECT_EQ(tryUtm({50.0, 5.3, 0.0})->zone, 31);  // 0..6 deg E
  EXPECT_EQ(tryUtm({60.4, 5.3, 0.0})->zone, 32);  // Bergen: zone 32 reaches 3 deg E there
  EXPECT_EQ(tryUtm({60.4, 2.9, 0.0})->zone, 31);
  EXPECT_EQ(tryUtm({78.2, 15.6, 0.0})->zone, 33);  // Longyearbyen: 9..21 deg E is zone 33
  EXPECT_EQ(tryUtm({78.2, 8.9, 0.0})->zone, 31);
  EXPECT_EQ(tryUtm({0.0, -180.0, 0.0})->zone, 1);
  EXPECT_EQ(tryUtm({0.0, 179.999, 0.0})->zone, 60);
}

TEST(Utm, TryUtmIsEmptyOutsideTheBandAndForInvalidPoints) {
  EXPECT_FALSE(tryUtm({84.0, 10.0, 0.0}).has_value());  // UPS north
  EXPECT_FALSE(tryUtm({-80.5, 10.0, 0.0}).has_value());
  EXPECT_TRUE(tryUtm({83.99, 10.0, 0.0}).has_value());
  EXPECT_TRUE(tryUtm({-80.0, 10.0, 0.0}).has_value());
  EXPECT_FALSE(tryUtm({std::nan(""), 10.0, 0.0}).has_value());
  EXPECT_FALSE(tryUtm({95.0, 10.0, 0.0}).has_value());
  EXPECT_FALSE(tryUtm({45.0, 10.0, INFINITY}).has_value());
}

TEST(Utm, RoundTripsAcrossAZone) {
  for (double lat = -79.5; lat < 84.0; lat += 7.3) {
    for (double dlon = -2.9; dlon <= 2.9; dlon += 0.58) {
      const GeodeticPoint p{lat, -75.0 + dlon, 12.5};  // zone 18, central meridian 75 W
      const std::optional<UtmPoint> utm = tryUtm(p);
      ASSERT_TRUE(utm.has_value());
      const GeodeticPoint back = fromUtm(*utm);
      // 1e-10 deg is about 10 micrometres.
      EXPECT_NEAR(back.latitude_deg, p.latitude_deg, 1e-10) << lat << " " << dlon;
      EXPECT_NEAR(back.longitude_deg, p.longitude_deg, 1e-10) << lat << " " << dlon;
      EXPECT_DOUBLE_EQ(back.height_m, p.height_m);
    }
  }
}

TEST(Azimuth, CardinalDirections) {
  const GeodeticPoint north{kMadison.latitude_deg + 0.01, kMadison.longitude_deg, 0.0};
  const GeodeticPoint east{kMadison.latitude_deg, kMadison.longitude_deg + 0.01, 0.0};
  const GeodeticPoint south{kMadison.latitude_deg - 0.01, kMadison.longitude_deg, 0.0};
  const GeodeticPoint west{kMadison.latitude_deg, kMadison.longitude_deg - 0.01, 0.0};
  EXPECT_NEAR(azimuth_deg(kMadison, north), 0.0, 1e-9);
  EXPECT_NEAR(azimuth_deg(kMadison, east), 90.0, 0.01);
  EXPECT_NEAR(azimuth_deg(kMadison, south), 180.0, 1e-9);
  EXPECT_NEAR(azimuth_deg(kMadison, west), 270.0, 0.01);
}

TEST(Validity, RejectsNonFiniteAndOutOfRange) {
  EXPECT_TRUE(isValid(kMadison));
  EXPECT_FALSE(isValid({std::nan(""), 0.0, 0.0}));
  EXPECT_FALSE(isValid({0.0, 0.0, INFINITY}));
  EXPECT_FALSE(isValid({91.0, 0.0, 0.0}));
  EXPECT_FALSE(isValid({0.0, -181.0, 0.0}));
}

}  // namespace
}  // namespace vp::geodesy
