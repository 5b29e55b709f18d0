// io/dtm_tiff: libtiff error capture and the GDAL_NODATA tag extender (dtm_tiff.hpp).
#include "io/dtm_tiff.hpp"

#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <string>

namespace vp::io::dtm_detail {
namespace {

thread_local std::string tiffErrors;

void appendMessage(const char* module, const char* fmt, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof(text), fmt, ap);
  if (!tiffErrors.empty()) {
    tiffErrors += "; ";
  }
  if (module != nullptr && module[0] != '\0') {
    tiffErrors += module;
    tiffErrors += ": ";
  }
  tiffErrors += text;
}

void errorHandler(const char* module, const char* fmt, va_list ap) {
  appendMessage(module, fmt, ap);
}

// Warnings (unknown private tags and the like) are not failures; keep the log quiet.
void warningHandler(const char*, const char*, va_list) {}

TIFFExtendProc previousExtender = nullptr;

void tagExtender(TIFF* tif) {
  if (previousExtender != nullptr) {
    previousExtender(tif);
  }
  if (TIFFFindField(tif, kTagGdalNoData, TIFF_ANY) == nullptr) {
    static const TIFFFieldInfo kGdalNoData[] = {{kTagGdalNoData, -1, -1, TIFF_ASCII, FIELD_CUSTOM,
                                                 1, 0, const_cast<char*>("GDALNoDataValue")}};
    TIFFMergeFieldInfo(tif, kGdalNoData, 1);
  }
}

}  // namespace

TiffDiagnostics::TiffDiagnostics()
    : previousError_(TIFFSetErrorHandler(errorHandler)),
      previousWarning_(TIFFSetWarningHandler(warningHandler)) {
  tiffErrors.clear();
}

TiffDiagnostics::~TiffDiagnostics() {
  TIFFSetErrorHandler(previousError_);
  TIFFSetWarningHandler(previousWarning_);
}

std::string TiffDiagnostics::detail() {
  return tiffErrors.empty() ? "" : " (libtiff: " + tiffErrors + ")";
}

bool TiffDiagnostics::anyError() {
  return !tiffErrors.empty();
}

void registerTags() {
  static std::once_flag once;
  std::call_once(once, [] { previousExtender = TIFFSetTagExtender(tagExtender); });
}

bool fail(std::string* why, const std::string& path, const std::string& problem) {
  if (why != nullptr) {
    *why = path + ": " + problem;
  }
  return false;
}

}  // namespace vp::io::dtm_detail
