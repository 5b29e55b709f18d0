#include "geodesy/geodesy.hpp"

#include <cmath>
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
