// tests/georef: the ground homography from control points (exact on exact points, residuals,
// degenerate sets refused by name, the recovered camera), the GCP file and the loaded view, and
// the plane lifter built on it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "georef/gcp_file.hpp"
#include "georef/georeference.hpp"
#include "georef/ground_homography.hpp"
#include "lifting/plane_lifter.hpp"
#include "plane_dtm.hpp"

namespace vp::georef {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A camera 80 m above a sloping plane, tilted 20 degrees from nadir, yawed 30 degrees.
struct SyntheticView {
  camera::Intrinsics k{1280, 960, 1000.0, 1002.0, 641.5, 478.0};
  Eigen::Vector3d centre{10.0, -20.0, 82.0};
  Eigen::Matrix3d cameraToEnu;
  GroundPlane plane{2.0, 0.02, -0.01};

  SyntheticView() {
    Eigen::Matrix3d nadir;  // columns: camera x, y, z in ENU (x east, y south, z down)
    nadir << 1, 0, 0, 0, -1, 0, 0, 0, -1;
    cameraToEnu = Eigen::AngleAxisd(30.0 * kPi / 180.0, Eigen::Vector3d::UnitZ()) * nadir *
                  Eigen::AngleAxisd(20.0 * kPi / 180.0, Eigen::Vector3d::UnitX());
  }
  Eigen::Vector2d project(const Eigen::Vector3d& world) const {
    const Eigen::Vector3d c = cameraToEnu.transpose() * (world - centre);
    return {k.fx_px * c.x() / c.z() + k.cx_px, k.fy_px * c.y() / c.z() + k.cy_px};
  }
  // The ground point a pixel sees.
  Eigen::Vector3d ground(const Eigen::Vector2d& pixel) const {
    const Eigen::Vector3d ray = cameraToEnu * Eigen::Vector3d((pixel.x() - k.cx_px) / k.fx_px,
                                                              (pixel.y() - k.cy_px) / k.fy_px, 1.0);
    // centre + t ray on z = a + b x + c y
    const double t = (plane.a + plane.b * centre.x() + plane.c * centre.y() - centre.z()) /
                     (ray.z() - plane.b * ray.x() - plane.c * ray.y());
    return centre + t * ray;
  }
  std::vector<ControlPoint> points(const std::vector<Eigen::Vector2d>& pixels) const {
    std::vector<ControlPoint> out;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      out.push_back({"P" + std::to_string(i + 1), pixels[i], ground(pixels[i])});
    }
    return out;
  }
};

const std::vector<Eigen::Vector2d> kSixPixels = {{100, 120}, {1150, 90},  {640, 480},
                                                 {80, 880},  {1200, 900}, {400, 700}};

TEST(GroundHomography, ExactOnNoiseFreePointsWithTheirPlaneAndCamera) {
  const SyntheticView view;
  const std::vector<ControlPoint> points = view.points(kSixPixels);
  GroundHomography h;
  std::string why;
  ASSERT_TRUE(estimateGroundHomography(points, {}, &h, &why)) << why;
  ASSERT_EQ(h.residuals.size(), points.size());
  for (const PointResidual& r : h.residuals) {
    EXPECT_LT(r.ground_m, 1e-6) << r.id;
    EXPECT_LT(r.image_px, 1e-6) << r.id;
  }
  EXPECT_LT(h.rms_m, 1e-6);
  // Pixels that are not control points map to their ground point too.
  for (const Eigen::Vector2d& pixel :
       {Eigen::Vector2d(5, 5), Eigen::Vector2d(1270, 500), Eigen::Vector2d(700, 950)}) {
    const auto en = mapToGround(h.imageToGround, pixel);
    ASSERT_TRUE(en.has_value());
    EXPECT_LT((*en - view.ground(pixel).head<2>()).norm(), 1e-6);
  }
  EXPECT_NEAR(h.plane.a, 2.0, 1e-9);
  EXPECT_NEAR(h.plane.b, 0.02, 1e-9);
  EXPECT_NEAR(h.plane.c, -0.01, 1e-9);
  const auto camera = recoverCamera(h, view.k);
  ASSERT_TRUE(camera.has_value());
  EXPECT_LT((camera->centreEnu - view.centre).norm(), 1e-5);
  EXPECT_LT((camera->cameraToEnu - view.cameraToEnu).norm(), 1e-7);
  EXPECT_NEAR(camera->heightAboveGround_m,
              view.centre.z() - view.plane.heightAt(view.centre.x(), view.centre.y()), 1e-5);
}

TEST(GroundHomography, ResidualsShowTheWrongPointAndNoiseStaysSmall) {
  const SyntheticView view;
  std::vector<Eigen::Vector2d> pixels = kSixPixels;
  pixels.push_back({900, 300});
  pixels.push_back({300, 350});
  std::vector<ControlPoint> points = view.points(pixels);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (ControlPoint& p : points) {
    p.pixel += Eigen::Vector2d(noise(rng), noise(rng));
  }
  GroundHomography h;
  std::string why;
  ASSERT_TRUE(estimateGroundHomography(points, {}, &h, &why)) << why;
  // 0.5 px at about 0.09 m/px: a few centimetres.
  EXPECT_LT(h.rms_m, 0.1);
  EXPECT_LE(h.rms_m, h.initialRms_m + 1e-12);  // the refinement never makes it worse
  // A position typed 4 m off is the largest residual, by far.
  points[3].groundEnu.x() += 4.0;
  ASSERT_TRUE(estimateGroundHomography(points, {}, &h, &why)) << why;
  EXPECT_EQ(h.residuals[h.maxIndex].id, "P4");
  for (std::size_t i = 0; i < h.residuals.size(); ++i) {
    if (i != h.maxIndex) {
      EXPECT_LT(h.residuals[i].ground_m, h.max_m) << h.residuals[i].id;
    }
  }
  EXPECT_GT(h.max_m, 1.0);
}

TEST(GroundHomography, DegenerateSetsAreRefusedNamingThePoints) {
  const SyntheticView view;
  std::string why;
  GroundHomography h;
  // Fewer than 4.
  std::vector<ControlPoint> three = view.points({{100, 100}, {900, 120}, {500, 800}});
  EXPECT_FALSE(estimateGroundHomography(three, {}, &h, &why));
  EXPECT_NE(why.find("3 ground control point(s) ('P1', 'P2', 'P3'): at least 4"), std::string::npos)
      << why;
  // The same id twice.
  std::vector<ControlPoint> points = view.points(kSixPixels);
  points[4].id = "P2";
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("'P2' appears twice"), std::string::npos) << why;
  // The same pixel twice (a row pasted twice with another id).
  points = view.points(kSixPixels);
  points[5].pixel = points[1].pixel + Eigen::Vector2d(0.3, 0.0);
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("'P2' and 'P6' are at the same pixel"), std::string::npos) << why;
  // The same ground position twice.
  points = view.points(kSixPixels);
  points[5].groundEnu = points[0].groundEnu;
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("'P1' and 'P6' are at the same ground position"), std::string::npos) << why;
  // Four of five on one line in the image (a road's edge): named, the fifth is not.
  points = view.points({{100, 100}, {400, 300}, {700, 500}, {1000, 700}, {900, 150}});
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("'P1', 'P2', 'P3', 'P4' lie on one line in the image (with one point off"),
            std::string::npos)
      << why;
  // All on one line: nothing to fit.
  points = view.points({{100, 100}, {400, 300}, {700, 500}, {1000, 700}});
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("'P1', 'P2', 'P3', 'P4' lie on one line in the image:"), std::string::npos)
      << why;
  // Pixels fine, ground positions typed on a line.
  points = view.points(kSixPixels);
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i].groundEnu = Eigen::Vector3d(3.0 * static_cast<double>(i), 1.0, 0.0);
  }
  EXPECT_FALSE(estimateGroundHomography(points, {}, &h, &why));
  EXPECT_NE(why.find("lie on one line on the ground"), std::string::npos) << why;
}

std::string writeFile(const std::string& name, const std::string& text) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("vp_georef_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(GcpFile, ReadsPointsWithCommentsBlanksAndOptionalHeights) {
  const std::string path = writeFile("good.csv",
                                     "# surveyed 2024-05-02\n"
                                     "id, u_px, v_px, latitude_deg, longitude_deg, height_m\n"
                                     "\n"
                                     "corner_A, 101.5, 220.25, 43.07310, -89.40120, 231.5\n"
                                     "corner_B,1800,240,43.07320,-89.40100,\n");
  GcpFile file;
  std::string why;
  ASSERT_TRUE(readGcpFile(path, &file, &why)) << why;
  ASSERT_EQ(file.points.size(), 2U);
  EXPECT_EQ(file.points[0].id, "corner_A");
  EXPECT_EQ(file.points[0].line, 4);
  EXPECT_DOUBLE_EQ(file.points[0].pixel.y(), 220.25);
  ASSERT_TRUE(file.points[0].height_m.has_value());
  EXPECT_DOUBLE_EQ(*file.points[0].height_m, 231.5);
  EXPECT_FALSE(file.points[1].height_m.has_value());
  EXPECT_DOUBLE_EQ(file.points[1].longitude_deg, -89.401);
}

TEST(GcpFile, ProblemsNameTheFileLineAndField) {
  GcpFile file;
  std::string why;
  EXPECT_FALSE(readGcpFile(writeFile("header.csv", "id,u,v,lat,lon\n"), &file, &why));
  EXPECT_NE(why.find("header.csv:1: header: expected 'id,u_px,v_px,latitude_deg,longitude_deg'"),
            std::string::npos)
      << why;
  EXPECT_FALSE(
      readGcpFile(writeFile("lat.csv", "id,u_px,v_px,latitude_deg,longitude_deg\nA,1,2,93.5,10\n"),
                  &file, &why));
  EXPECT_NE(why.find("lat.csv:2:"), std::string::npos) << why;
  EXPECT_NE(why.find("latitude_deg: must be in [-90, 90]"), std::string::npos) << why;
  EXPECT_FALSE(
      readGcpFile(writeFile("twice.csv",
                            "id,u_px,v_px,latitude_deg,longitude_deg\nA,1,2,3,4\nB,5,6,7,8\n"
                            "A,9,9,9,9\n"),
                  &file, &why));
  EXPECT_NE(why.find("twice.csv:4:1: id: id 'A' already used on line 2"), std::string::npos) << why;
  EXPECT_FALSE(
      readGcpFile(writeFile("number.csv", "id,u_px,v_px,latitude_deg,longitude_deg\nA,1,x2,3,4\n"),
                  &file, &why));
  EXPECT_NE(why.find("number.csv:2:5: v_px: not a number"), std::string::npos) << why;
  EXPECT_FALSE(readGcpFile("/nonexistent/gcp.csv", &file, &why));
  EXPECT_NE(why.find("/nonexistent/gcp.csv"), std::string::npos) << why;
}

// The synthetic view seen through a distorting lens, written as a GCP file at a real place.
struct FileFixture {
  SyntheticView view;
  geodesy::LocalFrame frame{geodesy::GeodeticPoint{43.0731, -89.4012, 250.0}};
  camera::CameraModel lens;
  std::vector<Eigen::Vector3d> groundEnu;
  std::string text;  // of the last file written

  FileFixture() {
    camera::Distortion d;
    d.model = camera::LensModel::BrownConrady;
    d.k1 = -0.12;
    d.k2 = 0.05;
    d.p1 = 2e-4;
    EXPECT_TRUE(lens.init(view.k, d));
  }
  // Rows for the given pixels (ideal), written as the lens records them; heights optional.
  std::string write(const std::string& name, const std::vector<Eigen::Vector2d>& ideal,
                    bool heights) {
    text = gcpHeader(true) + "\n";
    groundEnu.clear();
    for (std::size_t i = 0; i < ideal.size(); ++i) {
      const Eigen::Vector3d g = view.ground(ideal[i]);
      groundEnu.push_back(g);
      const geodesy::GeodeticPoint p = frame.toGeodetic(g);
      const Eigen::Vector2d raw = lens.distortPixel(ideal[i]);
      char row[256];
      std::snprintf(row, sizeof row, "G%zu,%.6f,%.6f,%.10f,%.10f,", i + 1, raw.x(), raw.y(),
                    p.latitude_deg, p.longitude_deg);
      text += row;
      if (heights) {
        text += std::to_string(p.height_m);
      }
      text += "\n";
    }
    return writeFile(name, text);
  }
};

TEST(GroundView, LensDistortionIsRemovedBeforeTheFit) {
  FileFixture f;
  GeorefOptions options;
  options.gcpFile = f.write("lens.csv", kSixPixels, true);
  GroundView view;
  std::string why;
  ASSERT_TRUE(loadGroundView(options, f.lens, f.frame, nullptr, &view, &why)) << why;
  EXPECT_LT(view.homography.max_m, 1e-4);  // rows carry 1e-6 px and 1e-10 deg
  EXPECT_TRUE(checkResiduals(view, 0.01, &why));
  ASSERT_TRUE(view.camera.has_value());
  EXPECT_LT((view.camera->centreEnu - f.view.centre).norm(), 0.01);
  // Through the plane lifter on the raw lens: a raw pixel lands on its ground point.
  lifting::PlaneLifter lifter;
  ASSERT_TRUE(lifter.init(view.homography, view.camera, f.lens, f.frame, &why)) << why;
  const Eigen::Vector2d ideal(900, 650);
  const auto ground = lifter.pixelToGround(f.lens.distortPixel(ideal));
  ASSERT_TRUE(ground.hasValue());
  EXPECT_LT((*ground - f.view.ground(ideal)).norm(), 1e-3);
  const auto back = lifter.groundToPixel(f.view.ground(ideal));
  ASSERT_TRUE(back.hasValue());
  EXPECT_LT((*back - f.lens.distortPixel(ideal)).norm(), 1e-3);
}

TEST(GroundView, MissingHeightsComeFromTheDtmAndALargeResidualIsRefusedByName) {
  FileFixture f;
  // A flat DTM 2 m above the origin: the points' plane is that height, whatever the view says.
  terrain::TerrainModel terrain;
  std::string why;
  ASSERT_TRUE(terrain.init(test::planeDtm(f.frame.origin(), 252.0, 0.0, 0.0, 300.0), f.frame, &why))
      << why;
  GeorefOptions options;
  options.gcpFile = f.write("noheight.csv", kSixPixels, false);
  GroundView view;
  ASSERT_TRUE(loadGroundView(options, f.lens, f.frame, &terrain, &view, &why)) << why;
  EXPECT_NEAR(view.homography.plane.heightAt(0.0, 0.0), 2.0, 0.01);
  EXPECT_NEAR(view.homography.plane.b, 0.0, 1e-4);
  // Without a DTM: the origin's height.
  ASSERT_TRUE(loadGroundView(options, f.lens, f.frame, nullptr, &view, &why)) << why;
  EXPECT_NEAR(view.homography.plane.heightAt(0.0, 0.0), 0.0, 0.01);
  // One point's pixel clicked 40 px off: named with its line.
  std::string text = f.text;
  const std::size_t row = text.find("G3,");
  const std::size_t comma = text.find(',', row + 3);
  const double u = std::stod(text.substr(row + 3, comma - row - 3));
  text.replace(row + 3, comma - row - 3, std::to_string(u + 40.0));
  options.gcpFile = writeFile("clicked.csv", text);
  ASSERT_TRUE(loadGroundView(options, f.lens, f.frame, nullptr, &view, &why)) << why;
  EXPECT_FALSE(checkResiduals(view, 1.0, &why));
  EXPECT_NE(why.find("clicked.csv:4: point 'G3': ground residual"), std::string::npos) << why;
  // Degenerate sets are refused naming the file.
  options.gcpFile = f.write("few.csv", {{100, 100}, {900, 120}, {500, 800}}, true);
  EXPECT_FALSE(loadGroundView(options, f.lens, f.frame, nullptr, &view, &why));
  EXPECT_NE(why.find("few.csv: 3 ground control point(s) ('G1', 'G2', 'G3')"), std::string::npos)
      << why;
}

TEST(PlaneLifter, BoxesAboveTheGroundAreLiftedToTheGroundBelow) {
  const SyntheticView view;
  const std::vector<ControlPoint> points = view.points(kSixPixels);
  GroundHomography h;
  std::string why;
  ASSERT_TRUE(estimateGroundHomography(points, {}, &h, &why)) << why;
  camera::CameraModel pinhole;
  ASSERT_TRUE(pinhole.init(view.k, camera::Distortion{}));
  const geodesy::LocalFrame frame(geodesy::GeodeticPoint{43.0731, -89.4012, 250.0});
  lifting::PlaneLifter lifter;
  ASSERT_TRUE(lifter.init(h, recoverCamera(h, view.k), pinhole, frame, &why)) << why;
  // A car-sized box around the image of points 0.75 m above the ground near the image corner.
  const Eigen::Vector3d centre = view.ground({1100, 850});
  const double heading = 0.6;
  const Eigen::Vector3d forward(std::cos(heading), std::sin(heading), 0.0);
  const Eigen::Vector3d left(-forward.y(), forward.x(), 0.0);
  const Eigen::Vector3d up(0, 0, 0.75);
  const Eigen::Vector2d c = view.project(centre + up);
  const Eigen::Vector2d f = view.project(centre + 2.25 * forward + up);
  const Eigen::Vector2d l = view.project(centre + 0.9 * left + up);
  const double angle = std::atan2(f.y() - c.y(), f.x() - c.x());
  const geometry::RotatedBox box{c.x(), c.y(), 2.0 * (f - c).norm(), 2.0 * (l - c).norm(), angle};
  const auto raised = lifter.boxToGround(box, 0.75);
  ASSERT_TRUE(raised.hasValue());
  EXPECT_LT((raised->centreEnu.head<2>() - centre.head<2>()).norm(), 1e-3);
  EXPECT_NEAR(raised->centreEnu.z(), view.plane.heightAt(centre.x(), centre.y()), 1e-3);
  EXPECT_NEAR(std::remainder(raised->headingEnu_rad - heading, 2.0 * kPi), 0.0, 0.01);
  EXPECT_NEAR(raised->length_m, 4.5, 0.05);
  // The same box taken as lying on the ground lands beyond the vehicle (parallax).
  const auto flat = lifter.boxToGround(box, 0.0);
  ASSERT_TRUE(flat.hasValue());
  EXPECT_GT((flat->centreEnu.head<2>() - centre.head<2>()).norm(), 0.2);
  // The GSD at the image centre: about height / focal length.
  const double gsd = lifter.groundSampleDistance_m({640, 480});
  EXPECT_GT(gsd, 80.0 / 1001.0 * 0.95);
  EXPECT_LT(gsd, 80.0 / 1001.0 * 1.2);
  // Beyond the horizon: no ground.
  georef::GroundHomography sky = h;
  sky.imageToGround.row(2) = Eigen::RowVector3d(0.0, 1.0, -500.0);  // horizon at v = 500
  lifting::PlaneLifter skyLifter;
  ASSERT_TRUE(skyLifter.init(sky, std::nullopt, pinhole, frame, &why));
  EXPECT_FALSE(skyLifter.pixelToGround({640, 100}).hasValue());
  EXPECT_EQ(skyLifter.pixelToGround({640, 100}).error(), lifting::LiftError::NoIntersection);
}

}  // namespace
}  // namespace vp::georef
