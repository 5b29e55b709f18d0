// io/dtm_tiff: the libtiff / libgeotiff plumbing shared by DTM reading (dtm_file.cpp) and
// writing (dtm_write.cpp), private to src/foundation/io: error capture, the GDAL_NODATA tag,
// RAII handles and the "path: problem" failure message.
#pragma once

#include <geotiff.h>
#include <xtiffio.h>

#include <memory>
#include <string>

namespace vp::io::dtm_detail {

inline constexpr ttag_t kTagGdalNoData = 42113;  // GDAL_NODATA, ASCII

// --- libtiff diagnostics ---------------------------------------------------------------
// libtiff reports errors through one process-wide handler. Ours appends to a thread_local
// buffer, so a failure's text ends up in the message of the call (on this thread) that
// caused it. The guard installs the handlers for the duration of one of our calls and puts
// back whatever was there before (OpenCV, for one, installs its own).
class TiffDiagnostics {
 public:
  TiffDiagnostics();
  ~TiffDiagnostics();
  TiffDiagnostics(const TiffDiagnostics&) = delete;
  TiffDiagnostics& operator=(const TiffDiagnostics&) = delete;

  // " (libtiff: ...)" when libtiff said something, else "".
  static std::string detail();
  // Whether libtiff reported an error since the guard was installed (on this thread).
  static bool anyError();

 private:
  TIFFErrorHandler previousError_;
  TIFFErrorHandler previousWarning_;
};

// --- GDAL_NODATA tag registration --------------------------------------------------------
// libtiff 4.5 does not know tag 42113; without a definition it cannot be written, and on
// read it would only be seen as an anonymous field. registerTags() installs (once) an
// extender, chained to the previous one (e.g. libgeotiff's), that defines it on every TIFF
// opened after registration.
void registerTags();

struct TiffCloser {
  void operator()(TIFF* tif) const { XTIFFClose(tif); }
};
using TiffPtr = std::unique_ptr<TIFF, TiffCloser>;

struct GtifCloser {
  void operator()(GTIF* gtif) const { GTIFFree(gtif); }
};
using GtifPtr = std::unique_ptr<GTIF, GtifCloser>;

// Sets *why (when given) to "path: problem"; returns false.
bool fail(std::string* why, const std::string& path, const std::string& problem);

}  // namespace vp::io::dtm_detail
