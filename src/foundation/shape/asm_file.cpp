// shape/asm_file: ActiveShapeModel::save() and load(), the ASM's YAML file (docs/asm.md): apart
// from the model's mathematics (vehicle_model.cpp) because it is a file format, checked field by
// field with messages that name the file and the field.
#include <array>
#include <cmath>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "shape/vehicle_model.hpp"

namespace vp::shape {
namespace {

constexpr int kFormatVersion = 1;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

// Reads the fields of one ASM file; every error names the file and the field.
class FieldReader {
 public:
  FieldReader(const std::string& path, std::string* why) : path_(path), why_(why) {}

  bool error(const std::string& field, const std::string& message) const {
    return fail(why_, path_ + ": field '" + field + "': " + message);
  }

  bool number(const YAML::Node& node, const std::string& field, double* out) const {
    if (!node || !node.IsScalar()) {
      return error(field, node ? "expected a number" : "missing");
    }
    try {
      *out = node.as<double>();
    } catch (const YAML::Exception&) {
      return error(field, "expected a number, got '" + node.Scalar() + "'");
    }
    if (!std::isfinite(*out)) {
      return error(field, "not a finite number");
    }
    return true;
  }

  bool integer(const YAML::Node& node, const std::string& field, int* out) const {
    if (!node || !node.IsScalar()) {
      return error(field, node ? "expected an integer" : "missing");
    }
    try {
      *out = node.as<int>();
    } catch (const YAML::Exception&) {
      return error(field, "expected an integer, got '" + node.Scalar() + "'");
    }
    return true;
  }

  bool sequence(const YAML::Node& node, const std::string& field, std::size_t size) const {
    if (!node) {
      return error(field, "missing");
    }
    if (!node.IsSequence()) {
      return error(field, "expected a sequence");
    }
    if (node.size() != size) {
      return error(field, "expected " + std::to_string(size) + " entries, got " +
                              std::to_string(node.size()));
    }
    return true;
  }

  bool numbers(const YAML::Node& node, const std::string& field, std::span<double> out) const {
    if (!sequence(node, field, out.size())) {
      return false;
    }
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!number(node[i], field + "[" + std::to_string(i) + "]", &out[i])) {
        return false;
      }
    }
    return true;
  }

  bool keypoints(const YAML::Node& node, const std::string& field, KeypointModel* out) const {
    if (!sequence(node, field, kKeypointCount)) {
      return false;
    }
    for (int k = 0; k < kKeypointCount; ++k) {
      std::array<double, 3> xyz{};
      if (!numbers(node[static_cast<std::size_t>(k)], field + "[" + std::to_string(k) + "]", xyz)) {
        return false;
      }
      out->col(k) = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
    }
    return true;
  }

 private:
  const std::string& path_;
  std::string* why_;
};

void emitKeypoints(YAML::Emitter& out, const KeypointModel& model) {
  out << YAML::BeginSeq;
  for (int k = 0; k < kKeypointCount; ++k) {
    out << YAML::Flow << YAML::BeginSeq << model(0, k) << model(1, k) << model(2, k)
        << YAML::EndSeq;
  }
  out << YAML::EndSeq;
}

}  // namespace

bool ActiveShapeModel::save(const std::string& path, std::string* why) const {
  if (componentCount_ == 0) {
    return fail(why, path + ": cannot save an empty ASM (init() or load() first)");
  }
  const int n = componentCount_;
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // 17 significant digits: doubles survive the round trip
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kFormatVersion;
  out << YAML::Key << "keypoint_names" << YAML::Value << YAML::BeginSeq;
  for (const char* name : keypointNames()) {
    out << name;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "component_count" << YAML::Value << n;
  out << YAML::Key << "explained_variance_share" << YAML::Value << explainedVarianceShare_;
  out << YAML::Key << "mean" << YAML::Value;
  emitKeypoints(out, mean_);
  out << YAML::Key << "sigma" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int s = 0; s < n; ++s) {
    out << sigmas_[static_cast<std::size_t>(s)];
  }
  out << YAML::EndSeq;
  out << YAML::Key << "eigenvectors" << YAML::Value << YAML::BeginSeq;
  for (int s = 0; s < n; ++s) {
    emitKeypoints(out, eigenvectors_[static_cast<std::size_t>(s)]);
  }
  out << YAML::EndSeq;
  out << YAML::Key << "type_priors" << YAML::Value << YAML::BeginMap;
  for (int t = 0; t < kCarTypeCount; ++t) {
    const TypePrior& prior = typePriors_[static_cast<std::size_t>(t)];
    if (prior.sampleCount == 0) {
      continue;
    }
    out << YAML::Key << toString(static_cast<VehicleType>(t)) << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "sample_count" << YAML::Value << prior.sampleCount;
    out << YAML::Key << "mean" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int s = 0; s < n; ++s) {
      out << prior.mean[static_cast<std::size_t>(s)];
    }
    out << YAML::EndSeq;
    out << YAML::Key << "covariance" << YAML::Value << YAML::BeginSeq;
    for (int s = 0; s < n; ++s) {
      out << YAML::Flow << YAML::BeginSeq;
      for (int u = 0; u < n; ++u) {
        out << prior.covariance(s, u);
      }
      out << YAML::EndSeq;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (heldOutError_.modelCount > 0) {
    out << YAML::Key << "held_out_error" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "model_count" << YAML::Value << heldOutError_.modelCount;
    out << YAML::Key << "rms_m" << YAML::Value << heldOutError_.rms_m;
    out << YAML::Key << "max_m" << YAML::Value << heldOutError_.max_m;
    out << YAML::Key << "planimetric_rms_m" << YAML::Value << heldOutError_.planimetricRms_m;
    out << YAML::Key << "height_rms_m" << YAML::Value << heldOutError_.heightRms_m;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good()) {
    return fail(why, path + ": YAML emitter error: " + out.GetLastError());
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << out.c_str() << '\n';
  file.close();
  if (!file) {
    return fail(why, path + ": cannot write the file");
  }
  return true;
}

bool ActiveShapeModel::load(const std::string& path, std::string* why) {
  YAML::Node root;
  {
    std::ifstream probe(path);
    if (!probe) {
      return fail(why, path + ": cannot open the ASM file");
    }
  }
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    return fail(why, path + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) {
    return fail(why, path + ": expected a YAML mapping at the top level");
  }
  const FieldReader read(path, why);
  int version = 0;
  if (!read.integer(root["format_version"], "format_version", &version)) {
    return false;
  }
  if (version != kFormatVersion) {
    return read.error("format_version", "unsupported version " + std::to_string(version) +
                                            " (this build reads " + std::to_string(kFormatVersion) +
                                            ")");
  }
  const YAML::Node names = root["keypoint_names"];
  if (!read.sequence(names, "keypoint_names", kKeypointCount)) {
    return false;
  }
  for (std::size_t k = 0; k < keypointNames().size(); ++k) {
    const std::string name = names[k].IsScalar() ? names[k].Scalar() : std::string("?");
    if (name != keypointNames()[k]) {
      return read.error("keypoint_names", "entry " + std::to_string(k) + " is '" + name +
                                              "', expected '" + keypointNames()[k] +
                                              "' (the file was made for another topology)");
    }
  }
  int n = 0;
  if (!read.integer(root["component_count"], "component_count", &n)) {
    return false;
  }
  if (n < 1 || n > kMaxShapeComponents) {
    return read.error("component_count", "must be 1.." + std::to_string(kMaxShapeComponents) +
                                             ", got " + std::to_string(n));
  }
  const auto count = static_cast<std::size_t>(n);
  double share = 0.0;
  if (!read.number(root["explained_variance_share"], "explained_variance_share", &share)) {
    return false;
  }
  if (share < 0.0 || share > 1.0) {
    return read.error("explained_variance_share", "must be in [0, 1]");
  }
  KeypointModel mean;
  if (!read.keypoints(root["mean"], "mean", &mean)) {
    return false;
  }
  std::array<double, kMaxShapeComponents> sigmas{};
  if (!read.numbers(root["sigma"], "sigma", std::span<double>(sigmas.data(), count))) {
    return false;
  }
  std::array<KeypointModel, kMaxShapeComponents> vectors{};
  const YAML::Node eigen = root["eigenvectors"];
  if (!read.sequence(eigen, "eigenvectors", count)) {
    return false;
  }
  for (std::size_t s = 0; s < count; ++s) {
    if (!read.keypoints(eigen[s], "eigenvectors[" + std::to_string(s) + "]", &vectors[s])) {
      return false;
    }
  }
  // Built aside so that a failed load leaves this model as it was.
  ActiveShapeModel next;
  std::string problem;
  if (!next.setModel(mean, std::span<const double>(sigmas.data(), count),
                     std::span<const KeypointModel>(vectors.data(), count), share, &problem)) {
    return read.error("eigenvectors/sigma", problem);
  }
  const YAML::Node priors = root["type_priors"];
  if (priors && !priors.IsMap()) {
    return read.error("type_priors", "expected a mapping from car type to prior");
  }
  if (priors) {
    for (const auto& entry : priors) {
      const std::string key = entry.first.Scalar();
      const std::string field = "type_priors." + key;
      const std::optional<VehicleType> type = vehicleTypeFromString(key);
      if (!type || static_cast<int>(*type) >= kCarTypeCount) {
        return read.error(field, "not a car type (estate, compact, sports, sedan, suv, van)");
      }
      TypePrior prior;
      if (!read.integer(entry.second["sample_count"], field + ".sample_count",
                        &prior.sampleCount)) {
        return false;
      }
      if (prior.sampleCount < 0) {
        return read.error(field + ".sample_count", "must be >= 0");
      }
      if (!read.numbers(entry.second["mean"], field + ".mean",
                        std::span<double>(prior.mean.data(), count))) {
        return false;
      }
      const YAML::Node covariance = entry.second["covariance"];
      if (!read.sequence(covariance, field + ".covariance", count)) {
        return false;
      }
      for (std::size_t s = 0; s < count; ++s) {
        std::array<double, kMaxShapeComponents> row{};
        if (!read.numbers(covariance[s], field + ".covariance[" + std::to_string(s) + "]",
                          std::span<double>(row.data(), count))) {
          return false;
        }
        for (std::size_t u = 0; u < count; ++u) {
          prior.covariance(static_cast<Eigen::Index>(s), static_cast<Eigen::Index>(u)) = row[u];
        }
      }
      next.typePriors_[static_cast<std::size_t>(*type)] = prior;
    }
  }
  const YAML::Node error = root["held_out_error"];
  if (error) {
    ReconstructionError e;
    if (!read.integer(error["model_count"], "held_out_error.model_count", &e.modelCount) ||
        !read.number(error["rms_m"], "held_out_error.rms_m", &e.rms_m) ||
        !read.number(error["max_m"], "held_out_error.max_m", &e.max_m) ||
        !read.number(error["planimetric_rms_m"], "held_out_error.planimetric_rms_m",
                     &e.planimetricRms_m) ||
        !read.number(error["height_rms_m"], "held_out_error.height_rms_m", &e.heightRms_m)) {
      return false;
    }
    next.heldOutError_ = e;
  }
  *this = next;
  return true;
}

}  // namespace vp::shape
