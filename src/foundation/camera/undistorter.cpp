#include "camera/undistorter.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace vp::camera {

namespace {

// Source coordinate for output pixels that must stay black: far enough outside the frame
// that none of the bilinear neighbours is inside it, and still representable in the
// 16-bit fixed-point map.
constexpr float kOutsideSource = -100.0F;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

bool validOutput(const Intrinsics& out, std::string* why) {
  if (out.width_px <= 0 || out.height_px <= 0) {
    return fail(why, "output size must be > 0, got " + std::to_string(out.width_px) + "x" +
                         std::to_string(out.height_px));
  }
  if (!std::isfinite(out.fx_px) || out.fx_px <= 0.0 || !std::isfinite(out.fy_px) ||
      out.fy_px <= 0.0) {
    return fail(why, "output fx_px and fy_px must be finite and > 0");
  }
  if (!std::isfinite(out.cx_px) || !std::isfinite(out.cy_px)) {
    return fail(why, "output cx_px and cy_px must be finite");
  }
  return true;
}

cv::Matx33d cameraMatrix(const Intrinsics& k) {
  return {k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0};
}

}  // namespace

bool Undistorter::init(const CameraModel& input, std::string* why) {
  return init(input, input.intrinsics(), why);
}

bool Undistorter::init(const CameraModel& input, const Intrinsics& output, std::string* why) {
  const Intrinsics& in = input.intrinsics();
  if (in.width_px <= 0 || in.height_px <= 0) {
    return fail(why, "input camera model is not initialised");
  }
  if (!validOutput(output, why)) {
    return false;
  }

  const cv::Size outSize(output.width_px, output.height_px);
  cv::Mat floatX;
  cv::Mat floatY;
  const Distortion& distortion = input.distortion();
  if (distortion.model == LensModel::BrownConrady) {
    const cv::Vec<double, 5> coefficients(distortion.k1, distortion.k2, distortion.p1,
                                          distortion.p2, distortion.k3);
    cv::initUndistortRectifyMap(cameraMatrix(in), coefficients, cv::noArray(), cameraMatrix(output),
                                outSize, CV_32FC1, floatX, floatY);
  } else {
    // No OpenCV equivalent for the spherical model (and the pinhole is just a rescale when
    // the output intrinsics differ): evaluate the forward model for each output pixel.
    floatX.create(outSize, CV_32FC1);
    floatY.create(outSize, CV_32FC1);
    for (int v = 0; v < outSize.height; ++v) {
      auto* rowX = floatX.ptr<float>(v);
      auto* rowY = floatY.ptr<float>(v);
      for (int u = 0; u < outSize.width; ++u) {
        const Eigen::Vector2d ideal((u - output.cx_px) / output.fx_px,
                                    (v - output.cy_px) / output.fy_px);
        const Eigen::Vector2d distorted = input.distortNormalized(ideal);
        rowX[u] = static_cast<float>(in.cx_px + in.fx_px * distorted.x());
        rowY[u] = static_cast<float>(in.cy_px + in.fy_px * distorted.y());
      }
    }
  }

  // Output pixels beyond the valid field have no trustworthy source: past the Brown-Conrady
  // fold-over the polynomial maps them back into the frame as a mirrored ghost. Blank them.
  const double maxIdealRadius2 = input.maxIdealRadius() * input.maxIdealRadius();
  for (int v = 0; v < outSize.height; ++v) {
    auto* rowX = floatX.ptr<float>(v);
    auto* rowY = floatY.ptr<float>(v);
    for (int u = 0; u < outSize.width; ++u) {
      const double x = (u - output.cx_px) / output.fx_px;
      const double y = (v - output.cy_px) / output.fy_px;
      if (!(x * x + y * y <= maxIdealRadius2) || !std::isfinite(rowX[u]) ||
          !std::isfinite(rowY[u])) {
        rowX[u] = kOutsideSource;
        rowY[u] = kOutsideSource;
      }
    }
  }

  cv::Mat fixedXY;
  cv::Mat fixedInterp;
  cv::convertMaps(floatX, floatY, fixedXY, fixedInterp, CV_16SC2);
  input_ = in;
  output_ = output;
  mapX_ = fixedXY;
  mapY_ = fixedInterp;
  return true;
}

bool Undistorter::apply(const cv::Mat& src, cv::Mat& dst) const {
  if (mapX_.empty() || src.empty()) {
    return false;
  }
  if (src.cols != input_.width_px || src.rows != input_.height_px) {
    return false;
  }
  if (dst.cols != output_.width_px || dst.rows != output_.height_px || dst.type() != src.type()) {
    return false;
  }
  // remap cannot work in place; overlapping buffers would read already-written output.
  if (src.datastart < dst.dataend && dst.datastart < src.dataend) {
    return false;
  }
  try {
    // dst already has the right size and type, so remap's create() keeps its buffer.
    cv::remap(src, dst, mapX_, mapY_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  } catch (const cv::Exception&) {
    return false;  // an element type remap does not support
  }
  return true;
}

}  // namespace vp::camera
