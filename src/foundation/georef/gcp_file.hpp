// georef/gcp_file: the ground control point file (docs/field_data.md, "Ground control points").
//
// Contract: readGcpFile() reads a CSV file whose first line other than comments is the header
// `id,u_px,v_px,latitude_deg,longitude_deg` or the same with `,height_m`; each further line is
// one point: an id (letters, digits, '_', '-', '.'), the pixel in the *raw* camera frame
// (column u to the right, row v down, pixel centres at integers, as OpenCV), WGS84 latitude and
// longitude in degrees and, optionally, the WGS84 ellipsoidal height in metres (an empty field:
// unknown). Lines starting with '#' and blank lines are skipped; spaces around fields are
// ignored. Every problem fails with "<file>:<line>:<column>: <field>: <problem>", and an id
// used twice names both lines. Start-up only (allocates, never throws).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"

namespace vp::georef {

struct GcpRecord {
  std::string id;
  Eigen::Vector2d pixel{0.0, 0.0};  // raw frame, px
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  std::optional<double> height_m;  // WGS84 ellipsoidal; none: unknown
  int line = 0;                    // in the file
};

struct GcpFile {
  std::string path;
  std::vector<GcpRecord> points;
};

bool readGcpFile(const std::string& path, GcpFile* out, std::string* why);

// The header line the reader expects (with or without heights).
std::string gcpHeader(bool withHeight);

}  // namespace vp::georef
