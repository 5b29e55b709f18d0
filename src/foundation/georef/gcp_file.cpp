#include "georef/gcp_file.hpp"

#include <cctype>
#include <map>

#include "csv/csv_io.hpp"

namespace vp::georef {

namespace {

const std::vector<std::string> kColumns = {"id", "u_px", "v_px", "latitude_deg", "longitude_deg"};
const std::vector<std::string> kColumnsWithHeight = {"id",           "u_px",          "v_px",
                                                     "latitude_deg", "longitude_deg", "height_m"};

// The line without blanks around its fields.
std::string withoutBlanks(std::string_view line) {
  std::string out;
  out.reserve(line.size());
  for (const char c : line) {
    if (c != ' ' && c != '\t') {
      out.push_back(c);
    }
  }
  return out;
}

bool validId(std::string_view id) {
  if (id.empty()) {
    return false;
  }
  for (const char c : id) {
    if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '_' && c != '-' && c != '.') {
      return false;
    }
  }
  return true;
}

}  // namespace

std::string gcpHeader(bool withHeight) {
  return csv::joinColumns(withHeight ? kColumnsWithHeight : kColumns);
}

bool readGcpFile(const std::string& path, GcpFile* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    const std::string text = csv::readWholeFile(path);
    const std::vector<std::string>* names = nullptr;
    std::map<std::string, int> lineOfId;
    csv::forEachLine(text, [&](int line, std::string_view raw) {
      const std::string row = withoutBlanks(raw);
      if (row.empty() || row.front() == '#') {
        return;
      }
      if (names == nullptr) {
        if (row == gcpHeader(false)) {
          names = &kColumns;
        } else if (row == gcpHeader(true)) {
          names = &kColumnsWithHeight;
        } else {
          throw csv::ReadError{csv::location(path, line) + ": header: expected '" +
                               gcpHeader(false) + "' or '" + gcpHeader(true) + "', got " +
                               csv::quote(row)};
        }
        return;
      }
      const csv::RowParser parser(path, line, row, *names);
      GcpRecord record;
      record.line = line;
      record.id = std::string(parser.field(0));
      if (!validId(record.id)) {
        parser.fail(0, "expected letters, digits, '_', '-' or '.', got " + csv::quote(record.id));
      }
      record.pixel = {parser.real<double>(1), parser.real<double>(2)};
      record.latitude_deg = parser.real<double>(3);
      record.longitude_deg = parser.real<double>(4);
      if (record.latitude_deg < -90.0 || record.latitude_deg > 90.0) {
        parser.fail(3, "must be in [-90, 90] degrees");
      }
      if (record.longitude_deg < -180.0 || record.longitude_deg > 180.0) {
        parser.fail(4, "must be in [-180, 180] degrees");
      }
      if (names->size() == 6 && !parser.field(5).empty()) {
        record.height_m = parser.real<double>(5);
      }
      if (const auto [at, inserted] = lineOfId.emplace(record.id, line); !inserted) {
        parser.fail(0, "id " + csv::quote(record.id) + " already used on line " +
                           std::to_string(at->second));
      }
      out->points.push_back(std::move(record));
    });
    if (names == nullptr) {
      throw csv::ReadError{csv::shortened(path) + ": no header line (expected '" +
                           gcpHeader(false) + "' or '" + gcpHeader(true) + "')"};
    }
  });
}

}  // namespace vp::georef
