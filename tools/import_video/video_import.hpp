// tools/import_video: a consumer drone's video and its telemetry subtitles (DJI-style .SRT)
// into a recorded sequence (docs/recorded_sequence.md) that the app replays, with the camera
// from a catalogue of drone cameras or a calibration and a DTM (flat or given).
//
// Contract: importVideo() checks everything it can before writing (video, subtitles, camera
// size, DTM), then writes the sequence with SequenceWriter: every `every`-th frame as JPEG with
// its presentation time (video clock, from the first frame: VideoReplay), the telemetry rows of
// the subtitles on the same clock (input/subtitle_telemetry), rig.yaml and dtm.tif. A
// malformed subtitle is an error line naming the file and line; it is skipped and the import
// goes on (counted in the summary). Where the subtitles carry no attitude the rows assume a
// nadir camera: sequence.yaml's notes say so, a warning is returned, the rows are counted. A
// start-up problem (file missing, camera size mismatch, no usable telemetry) returns false
// naming the file or option.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera/camera_model.hpp"
#include "subtitle_telemetry/subtitle_telemetry.hpp"

namespace vp::importer {

struct CatalogueCamera {
  std::string name;   // the --camera value
  std::string model;  // the maker's name
  double sensorWidth_mm = 0.0;
  double focalLength_mm = 0.0;
  std::vector<std::pair<int, int>> videoModes_px;
};

// The catalogue file (tools/import_video/drone_cameras.yaml); false and *why on a bad file.
bool loadCameraCatalogue(const std::string& path, std::vector<CatalogueCamera>& out,
                         std::string* why);
// The catalogue camera in the video mode width x height: square pixels, centred principal
// point, pinhole; false naming the modes when the size is not one of them.
bool catalogueIntrinsics(const CatalogueCamera& camera, int width_px, int height_px,
                         camera::Intrinsics& out, std::string* why);
// A calibration file: OpenCV's (camera_matrix, distortion_coefficients, image_width,
// image_height) or a YAML file with this project's `camera:` section.
bool loadCalibration(const std::string& path, camera::Intrinsics& intrinsics,
                     camera::Distortion& distortion, std::string* why);

struct ImportOptions {
  std::string videoPath;
  std::string srtPath;  // empty: the video's name with .SRT or .srt
  std::string outDir;
  int every = 1;                          // keep every n-th frame, >= 1
  std::int64_t maxFrames = 0;             // frames written; 0 = all
  std::string cameraName;                 // a catalogue camera, or
  std::string calibrationPath;            // a calibration file (one of the two)
  std::string cataloguePath;              // default: the repository's drone_cameras.yaml
  std::optional<double> flatDtmHeight_m;  // a flat DTM at this ellipsoidal height, or
  std::string dtmPath;                    // a DTM file (GeoTIFF, or raster + world file)
  std::string dtmCrs = "auto";            // terrain.crs for a world-file DTM
  subtitle::SubtitleTelemetryOptions telemetry{};
  int jpegQuality = 92;
};

struct ImportSummary {
  std::int64_t framesRead = 0;
  std::int64_t framesWritten = 0;
  std::int64_t framesOutsideTelemetry = 0;  // written frames before/after the telemetry's span
  std::uint64_t indexTimestamps = 0;        // frames without a usable PTS
  std::size_t subtitleBlocks = 0;
  std::size_t subtitleSamples = 0;
  std::size_t telemetryRows = 0;
  std::size_t nadirAssumed = 0;
  std::size_t yawFromMotion = 0;
  std::vector<std::string> errors;    // skipped subtitles: "<file>:<line>: ..."
  std::vector<std::string> warnings;  // the nadir assumption, frames outside the telemetry
};

bool importVideo(const ImportOptions& options, ImportSummary& summary, std::string* why);

}  // namespace vp::importer
