// vp_sim_figure: the documentation picture docs/images/sim_vs_real.jpg: a simulated frame with
// its ground truth drawn on it (rotated boxes, driving-direction arrows, projected ASM
// wireframes) next to a real drone image with its YOLO boxes (axis-aligned, no heading).
//
// usage: vp_sim_figure --sequence DIR [--frame I] [--crop-px N] --real IMAGE --labels TXT
//                      --out FILE.jpg [--quality Q]
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "geometry/rotated_box.hpp"
#include "sequence/recorded_sequence.hpp"
#include "shape/vehicle_model.hpp"

namespace {

cv::Point2f pt(const Eigen::Vector2d& p) {
  return {static_cast<float>(p.x()), static_cast<float>(p.y())};
}

void drawTruth(cv::Mat& img, const vp::sequence::SequenceReader& reader, std::int64_t frameId) {
  // Wireframes first (under the boxes): the unique edges of the ASM mesh between projected
  // keypoints; solid where both ends are visible.
  std::set<std::pair<int, int>> edges;
  for (const auto& t : vp::shape::mesh()) {
    for (int e = 0; e < 3; ++e) {
      const int a = t.v[static_cast<std::size_t>(e)];
      const int b = t.v[static_cast<std::size_t>((e + 1) % 3)];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  }
  const auto keypoints = reader.keypoints(frameId);
  for (const auto& o : reader.objects(frameId)) {
    std::array<const vp::sequence::KeypointTruth*, vp::shape::kKeypointCount> kp{};
    for (const auto& k : keypoints) {
      if (k.trackId == o.trackId) {
        kp[static_cast<std::size_t>(k.keypoint)] = &k;
      }
    }
    for (const auto& [a, b] : edges) {
      const auto* ka = kp[static_cast<std::size_t>(a)];
      const auto* kb = kp[static_cast<std::size_t>(b)];
      if (ka == nullptr || kb == nullptr) {
        continue;
      }
      const bool visible = ka->visible && kb->visible;
      cv::line(img, pt(ka->pixel), pt(kb->pixel),
               visible ? cv::Scalar(255, 255, 0) : cv::Scalar(140, 110, 40), visible ? 2 : 1,
               cv::LINE_AA);
    }
  }
  for (const auto& o : reader.objects(frameId)) {
    const auto c = vp::geometry::corners(o.imageBox);
    const cv::Scalar colour = o.parked ? cv::Scalar(0, 200, 255) : cv::Scalar(0, 255, 0);
    for (int i = 0; i < 4; ++i) {
      cv::line(img, pt(c[static_cast<std::size_t>(i)]),
               pt(c[static_cast<std::size_t>((i + 1) % 4)]), colour, 3, cv::LINE_AA);
    }
    const Eigen::Vector2d centre(o.imageBox.cx, o.imageBox.cy);
    const Eigen::Vector2d tip =
        centre + 0.5 * o.imageBox.length *
                     Eigen::Vector2d(std::cos(o.imageBox.angle), std::sin(o.imageBox.angle));
    cv::arrowedLine(img, pt(centre), pt(tip), cv::Scalar(0, 0, 255), 3, cv::LINE_AA, 0, 0.3);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string sequenceDir, realImage, labels, out;
  int frameIndex = 0;
  int crop_px = 1400;
  int quality = 88;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const std::string v = argv[i + 1];
    if (a == "--sequence") {
      sequenceDir = v;
    } else if (a == "--frame") {
      frameIndex = std::stoi(v);
    } else if (a == "--crop-px") {
      crop_px = std::stoi(v);
    } else if (a == "--real") {
      realImage = v;
    } else if (a == "--labels") {
      labels = v;
    } else if (a == "--out") {
      out = v;
    } else if (a == "--quality") {
      quality = std::stoi(v);
    } else {
      std::cerr << "vp_sim_figure: unknown argument " << a << "\n";
      return 2;
    }
  }
  if (sequenceDir.empty() || realImage.empty() || out.empty()) {
    std::cerr << "usage: vp_sim_figure --sequence DIR [--frame I] [--crop-px N] --real IMAGE "
                 "--labels TXT "
                 "--out FILE.jpg [--quality Q]\n";
    return 2;
  }
  vp::sequence::SequenceReader reader;
  std::string why;
  if (!reader.open(sequenceDir, &why)) {
    std::cerr << "vp_sim_figure: " << why << "\n";
    return 1;
  }
  cv::Mat sim;
  if (!reader.loadFrame(static_cast<std::size_t>(frameIndex), sim, &why)) {
    std::cerr << "vp_sim_figure: " << why << "\n";
    return 1;
  }
  drawTruth(sim, reader, reader.frames()[static_cast<std::size_t>(frameIndex)].frameId);
  const int side = 640;
  const int crop = std::min({crop_px, sim.cols, sim.rows});
  cv::Mat simCrop;
  cv::resize(sim(cv::Rect((sim.cols - crop) / 2, (sim.rows - crop) / 2, crop, crop)), simCrop,
             cv::Size(side, side), 0, 0, cv::INTER_AREA);

  cv::Mat real = cv::imread(realImage, cv::IMREAD_COLOR);
  if (real.empty()) {
    std::cerr << "vp_sim_figure: cannot read " << realImage << "\n";
    return 1;
  }
  cv::resize(real, real, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  std::ifstream in(labels);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    int cls = 0;
    double cx = 0, cy = 0, w = 0, h = 0;
    if (s >> cls >> cx >> cy >> w >> h) {
      cv::rectangle(real, cv::Point2d((cx - w / 2) * side, (cy - h / 2) * side),
                    cv::Point2d((cx + w / 2) * side, (cy + h / 2) * side), cv::Scalar(255, 0, 255),
                    2, cv::LINE_AA);
    }
  }
  const int caption = 56;
  cv::Mat canvas(side + caption, 2 * side + 8, CV_8UC3, cv::Scalar(255, 255, 255));
  simCrop.copyTo(canvas(cv::Rect(0, 0, side, side)));
  real.copyTo(canvas(cv::Rect(side + 8, 0, side, side)));
  const auto text = [&](const std::string& t, int x, int y) {
    cv::putText(canvas, t, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
  };
  text("Simulated (vp_simulate " + reader.info().source.substr(reader.info().source.find("seed")) +
           "), ground truth: rotated boxes, driving direction, ASM wireframes",
       6, side + 20);
  text(
      "Real: public \"Drone-View-Vehicle-Image-Set\", CATS Lab, Madison 2022, with its YOLO boxes "
      "(axis-aligned)",
      6, side + 44);
  const std::vector<int> params = {cv::IMWRITE_JPEG_QUALITY, quality};
  if (!cv::imwrite(out, canvas, params)) {
    std::cerr << "vp_sim_figure: cannot write " << out << "\n";
    return 1;
  }
  return 0;
}
