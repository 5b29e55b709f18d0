// preprocess/white_balance: automatic white balance by near-white reference points in YCbCr
// (seed 001, "Automatic white balance for lens colour deviation"), estimated per frame and
// applied through per-channel lookup tables, with no heap allocation per frame.
//
// Contract: estimate() reads a regular subsample of an 8-bit BGR frame (every
// sampleStride_px-th pixel in both axes; pure black pixels, e.g. the blank corners of an
// undistorted frame, are skipped) and
//  1. converts it to YCbCr (BT.601, full range, Cb/Cr centred on 0),
//  2. splits it into regionRows x regionCols regions (the seed's 12) and computes per region
//     the chroma means Mb, Mr and mean absolute deviations Db, Dr; regions flatter than
//     minRegionDeviation in both chroma axes carry no colour information and are skipped;
//  3. averages Mb, Mr, Db, Dr over the remaining regions and takes as near-white candidates
//     the samples with |Cb - (Mb + Db sign(Mb))| < 1.5 Db and |Cr - (1.5 Mr + Dr sign(Mr))| <
//     1.5 Dr (the seed's inequalities),
//  4. keeps the brightest whitePointShare of the candidates (by luminance, in whole 1-level
//     luminance bins from the top) as reference white points, and
//  5. sets each channel's gain to Ymax / (mean of that channel over the reference points),
//     Ymax the largest sample luminance, clamped to [1 / maxGain, maxGain].
// When no region or no candidate qualifies, found is false and the gains are 1. apply() maps
// every pixel through round(v * gain) saturated to 255, in place or into another buffer.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace vp::preprocess {

// Upper bound on regionRows x regionCols (the per-region statistics live in fixed arrays).
constexpr int kMaxWhiteBalanceRegions = 64;

struct WhiteBalanceOptions {
  int regionRows = 3;  // the seed's 12 regions: 3 x 4 over a landscape frame
  int regionCols = 4;
  int sampleStride_px = 4;          // estimate on every 4th pixel in u and v, >= 1
  double whitePointShare = 0.10;    // brightest share of the candidates, (0, 1] (seed: 10 %)
  double minRegionDeviation = 0.5;  // chroma mean abs deviation, 8-bit units, >= 0
  double maxGain = 4.0;             // gains limited to [1/maxGain, maxGain], >= 1
};

// Gains in the frame's channel order (B, G, R for BGR frames).
struct WhiteBalanceGains {
  std::array<float, 3> gain{1.0F, 1.0F, 1.0F};
  bool found = false;      // false: no reference white found, gains are 1
  int candidateCount = 0;  // near-white candidates among the samples
  int referenceCount = 0;  // reference white points used for the gains
  int regionsUsed = 0;     // regions with colour variation
};

// Checks the options; false with a message naming the key otherwise.
bool validate(const WhiteBalanceOptions& options, std::string* why);

// The 8-bit table of one gain: entry v = saturate(round(v * gain)) - how every gain of the
// preprocessing is applied (white balance, exposure; the crops' exposure gain too).
std::array<std::uint8_t, 256> gainTable(float gain);

class WhiteBalancer {
 public:
  WhiteBalancer() = default;

  // Start-up: checks the options and allocates the sample buffers for frames of frameSize.
  bool init(const WhiteBalanceOptions& options, cv::Size frameSize, std::string* why = nullptr);
  bool initialised() const { return frameSize_.width > 0; }

  // Real-time: gains for one BGR frame of frameSize (CV_8UC3; other input returns
  // found = false).
  WhiteBalanceGains estimate(const cv::Mat& bgrFrame);

  // Applies gains: dst[c] = saturate(round(src[c] * gain[c])) for rows [rowBegin, rowEnd).
  // src and dst have the same size and type CV_8UC3 and may be the same image. The tables
  // are built by setGains() (256 entries per channel), so threads can share them.
  void setGains(const WhiteBalanceGains& gains);
  void applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd) const;

 private:
  WhiteBalanceOptions options_{};
  cv::Size frameSize_{};
  int samplesX_ = 0;
  int samplesY_ = 0;
  // Per sample: luminance (< 0 marks a skipped black pixel) and centred chroma.
  std::vector<float> luma_;
  std::vector<float> cb_;
  std::vector<float> cr_;
  std::vector<int> regionCol_;       // per sample column: its region's column
  std::vector<int> regionRowStart_;  // per sample row: its region row x regionCols
  std::array<std::array<std::uint8_t, 256>, 3> table_{};
};

}  // namespace vp::preprocess
