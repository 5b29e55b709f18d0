// Tests of input/subtitle_telemetry: the two subtitle families (bracketed key/value with and
// without gimbal angles; legacy GPS(...) with BAROMETER or H), the problems that skip one
// subtitle (named by file and line) while the rest is read, and the conversion to telemetry
// rows (heights, earth gimbal, the nadir assumption with yaw from the motion).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "geodesy/geodesy.hpp"
#include "subtitle_telemetry/subtitle_telemetry.hpp"

namespace vp::subtitle {
namespace {

// Mini 3 Pro / Mavic 3 style, with the HTML wrapper and gimbal angles in one bracket.
constexpr const char* kBracketed =
    "1\n"
    "00:00:00,000 --> 00:00:00,033\n"
    "<font size=\"28\">FrameCnt: 1, DiffTime: 33ms\n"
    "2023-05-12 14:32:10.123\n"
    "[iso: 100] [shutter: 1/1000.0] [fnum: 1.7] [ev: 0] [color_md: default] [focal_len: 24.00] "
    "[latitude: 43.073100] [longitude: -89.401200] [rel_alt: 80.100 abs_alt: 340.236] "
    "[gb_yaw: 12.5 gb_pitch: -89.9 gb_roll: 0.0] [ct: 5500] </font>\n"
    "\n"
    "2\r\n"
    "00:00:00,033 --> 00:00:00,066\r\n"
    "<font size=\"28\">FrameCnt: 2, DiffTime: 33ms\r\n"
    "2023-05-12 14:32:10.156\r\n"
    "[latitude : 43.073101] [longitude : -89.401201] [rel_alt: 80.200 abs_alt: 340.336] "
    "[gb_yaw: 12.6] [gb_pitch: -89.8] [gb_roll: 0.1] </font>\r\n";

// Phantom 4 style: GPS(lon,lat,alt), HOME(...) and BAROMETER; and the Mavic Pro "H" form.
constexpr const char* kLegacy =
    "1\n"
    "00:00:01,000 --> 00:00:02,000\n"
    "HOME(-89.4012,43.0731) 2017.07.29 15:18:50\n"
    "GPS(-89.4012,43.0731,270) BAROMETER:80.5\n"
    "ISO:100 Shutter:60 EV: Fnum:2.2 \n"
    "\n"
    "2\n"
    "00:00:02,000 --> 00:00:03,000\n"
    "F/2.8, SS 320.56, ISO 100, EV 0, GPS (-89.4013, 43.0732, 271), D 24.58m, H 81.00m, "
    "HS 0.00m/s, VS 0.00m/s\n";

TEST(SubtitleParser, BracketedSubtitlesGivePositionAltitudesGimbalAndFrameCount) {
  const SubtitleFile f = parseSubtitles(kBracketed, "DJI_0001.SRT");
  EXPECT_TRUE(f.problems.empty()) << f.problems.front();
  ASSERT_EQ(f.samples.size(), 2U);
  EXPECT_EQ(f.blocks, 2U);
  EXPECT_EQ(f.bracketed, 2U);
  const SubtitleSample& a = f.samples[0];
  EXPECT_EQ(a.number, 1);
  EXPECT_EQ(a.line, 1U);
  EXPECT_EQ(a.start_ns, 0);
  EXPECT_EQ(a.end_ns, 33'000'000);
  EXPECT_EQ(a.frameCount, 1);
  EXPECT_EQ(a.format, SubtitleFormat::Bracketed);
  EXPECT_DOUBLE_EQ(a.latitude_deg, 43.0731);
  EXPECT_DOUBLE_EQ(a.longitude_deg, -89.4012);
  EXPECT_DOUBLE_EQ(*a.relativeAltitude_m, 80.1);
  EXPECT_DOUBLE_EQ(*a.absoluteAltitude_m, 340.236);
  ASSERT_TRUE(a.gimbal.has_value());
  EXPECT_DOUBLE_EQ(a.gimbal->yaw_deg, 12.5);
  EXPECT_DOUBLE_EQ(a.gimbal->pitch_deg, -89.9);
  EXPECT_DOUBLE_EQ(a.gimbal->roll_deg, 0.0);
  // CRLF line ends, spaces before the colon and one bracket per gimbal angle.
  const SubtitleSample& b = f.samples[1];
  EXPECT_EQ(b.line, 7U);
  EXPECT_EQ(b.start_ns, 33'000'000);
  EXPECT_DOUBLE_EQ(b.latitude_deg, 43.073101);
  EXPECT_DOUBLE_EQ(b.gimbal->roll_deg, 0.1);
}

TEST(SubtitleParser, LegacySubtitlesReadGpsLongitudeFirstAndTheHeightAboveHome) {
  const SubtitleFile f = parseSubtitles(kLegacy, "DJI_0002.SRT");
  EXPECT_TRUE(f.problems.empty()) << f.problems.front();
  ASSERT_EQ(f.samples.size(), 2U);
  EXPECT_EQ(f.legacy, 2U);
  const SubtitleSample& a = f.samples[0];
  EXPECT_EQ(a.format, SubtitleFormat::Legacy);
  EXPECT_EQ(a.start_ns, 1'000'000'000);
  EXPECT_DOUBLE_EQ(a.latitude_deg, 43.0731);
  EXPECT_DOUBLE_EQ(a.longitude_deg, -89.4012);
  EXPECT_DOUBLE_EQ(*a.absoluteAltitude_m, 270.0);
  EXPECT_DOUBLE_EQ(*a.relativeAltitude_m, 80.5);
  EXPECT_FALSE(a.gimbal.has_value());
  const SubtitleSample& b = f.samples[1];
  EXPECT_DOUBLE_EQ(b.latitude_deg, 43.0732);
  EXPECT_DOUBLE_EQ(b.longitude_deg, -89.4013);
  EXPECT_DOUBLE_EQ(*b.relativeAltitude_m, 81.0);
  EXPECT_DOUBLE_EQ(*b.absoluteAltitude_m, 271.0);
}

TEST(SubtitleParser, MalformedSubtitlesAreNamedByLineAndSkippedTheRestIsRead) {
  const std::string text =
      "1\n00:00:00,000 --> 00:00:00,100\n[latitude: 43.0731] [longitude: -89.4012] "
      "[rel_alt: 80 abs_alt: 300]\n\n"
      // line 5: not a number
      "x2\n00:00:00,100 --> 00:00:00,200\n[latitude: 43.0731] [longitude: -89.4012]\n\n"
      // line 9, 10: a broken time range
      "3\n00:00:00,200 -> 00:00:00,300\n[latitude: 43.0731] [longitude: -89.4012]\n\n"
      // line 13..16: latitude is not a number (named on its line, 16)
      "4\n00:00:00,300 --> 00:00:00,400\nFrameCnt: 4\n[latitude: 43.07a] [longitude: -89.4]\n\n"
      // line 18: no position at all
      "5\n00:00:00,400 --> 00:00:00,500\n[iso: 100]\n\n"
      // line 22: no GPS fix
      "6\n00:00:00,500 --> 00:00:00,600\n[latitude: 0.000000] [longitude: 0.000000] "
      "[rel_alt: 0 abs_alt: 0]\n\n"
      // line 26: gimbal in part
      "7\n00:00:00,600 --> 00:00:00,700\n[latitude: 43.0731] [longitude: -89.4012] "
      "[gb_yaw: 3]\n\n"
      // line 30, 31: going back in time
      "8\n00:00:00,000 --> 00:00:00,050\n[latitude: 43.0731] [longitude: -89.4012]\n\n"
      "9\n00:00:00,800 --> 00:00:00,900\n[latitude: 43.0732] [longitude: -89.4013] "
      "[rel_alt: 81 abs_alt: 301]\n";
  const SubtitleFile f = parseSubtitles(text, "bad.SRT");
  EXPECT_EQ(f.blocks, 9U);
  ASSERT_EQ(f.samples.size(), 2U);
  EXPECT_EQ(f.samples[0].number, 1);
  EXPECT_EQ(f.samples[1].number, 9);
  ASSERT_EQ(f.problems.size(), 7U);
  EXPECT_EQ(f.problems[0], "bad.SRT:5: expected a subtitle number, got 'x2'; subtitle skipped");
  EXPECT_EQ(f.problems[1],
            "bad.SRT:10: expected a time range 'HH:MM:SS,mmm --> HH:MM:SS,mmm', got "
            "'00:00:00,200 -> 00:00:00,300'; subtitle 3 skipped");
  EXPECT_EQ(f.problems[2], "bad.SRT:16: latitude: not a number '43.07a'; subtitle 4 skipped");
  EXPECT_EQ(f.problems[3],
            "bad.SRT:18: no position (expected [latitude: ...] [longitude: ...] or "
            "GPS(lon,lat,alt)); subtitle 5 skipped");
  EXPECT_EQ(f.problems[4], "bad.SRT:22: no GPS fix (latitude and longitude 0); subtitle 6 skipped");
  EXPECT_EQ(f.problems[5],
            "bad.SRT:26: gimbal angles given in part (gb_yaw, gb_pitch, gb_roll go together); "
            "subtitle 7 skipped");
  EXPECT_EQ(f.problems[6],
            "bad.SRT:31: starts at 0.000 s, not after the previous subtitle (0.000 s); subtitle 8 "
            "skipped");
}

TEST(SubtitleParser, EmptyAndGarbageInputGiveNoSamplesAndNeverThrow) {
  EXPECT_TRUE(parseSubtitles("", "e.SRT").samples.empty());
  EXPECT_EQ(parseSubtitles("\n\n\n", "e.SRT").blocks, 0U);
  const SubtitleFile f = parseSubtitles(
      "\xEF\xBB\xBF"
      "1\n",
      "e.SRT");
  ASSERT_EQ(f.problems.size(), 1U);
  EXPECT_EQ(f.problems[0], "e.SRT:1: no time range after the subtitle number; subtitle 1 skipped");
  const SubtitleFile g =
      parseSubtitles("1\n00:00:00,000 --> 00:00:01,000\nGPS(1e999,2,3)\n", "g.SRT");
  EXPECT_TRUE(g.samples.empty());
  EXPECT_EQ(g.problems.size(), 1U);
}

TEST(SubtitleTelemetry, HeightsFromAbsoluteOrRelativeAltitudeAndTheEarthGimbal) {
  const SubtitleFile f = parseSubtitles(kBracketed, "a.SRT");
  SubtitleTelemetryOptions abs;
  abs.geoidSeparation_m = -33.5;
  const SubtitleTelemetry t = toTelemetry(f, abs, "a.SRT");
  ASSERT_EQ(t.records.size(), 2U);
  EXPECT_EQ(t.nadirAssumed, 0U);
  EXPECT_EQ(t.records[1].timestamp_ns, 33'000'000);
  EXPECT_DOUBLE_EQ(t.records[0].position.height_m, 340.236 - 33.5);
  EXPECT_EQ(t.records[0].gimbal.reference, geodesy::GimbalReference::Earth);
  EXPECT_DOUBLE_EQ(t.records[0].gimbal.angles.yaw_deg, 12.5);
  EXPECT_DOUBLE_EQ(t.records[0].gimbal.angles.pitch_deg, -89.9);
  EXPECT_NEAR(t.records[0].bodyToNed.norm(), 1.0, 1e-12);

  SubtitleTelemetryOptions rel;
  rel.altitude = AltitudeSource::Relative;
  rel.homeHeight_m = 230.0;
  const SubtitleTelemetry r = toTelemetry(f, rel, "a.SRT");
  ASSERT_EQ(r.records.size(), 2U);
  EXPECT_DOUBLE_EQ(r.records[0].position.height_m, 310.1);

  // A subtitle without the chosen altitude is a problem naming its line; the others stay.
  const SubtitleFile m = parseSubtitles(
      "1\n00:00:00,000 --> 00:00:00,100\n[latitude: 43.0731] [longitude: -89.4012] "
      "[rel_alt: 80]\n\n2\n00:00:00,100 --> 00:00:00,200\n[latitude: 43.0731] "
      "[longitude: -89.4012] [rel_alt: 80 abs_alt: 300]\n",
      "m.SRT");
  const SubtitleTelemetry mt = toTelemetry(m, abs, "m.SRT");
  ASSERT_EQ(mt.records.size(), 1U);
  ASSERT_EQ(mt.problems.size(), 1U);
  EXPECT_EQ(mt.problems[0],
            "m.SRT:1: no absolute altitude (abs_alt, or GPS(...)'s third value); sample skipped");
}

TEST(SubtitleTelemetry, WithoutAttitudeTheCameraLooksDownWithYawAlongTheMotion) {
  // Hovering for 2 s, then flying east at 5 m/s for 2 s, 10 subtitles a second.
  const geodesy::LocalFrame frame(geodesy::GeodeticPoint{43.0731, -89.4012, 300.0});
  std::string text;
  for (int i = 0; i < 40; ++i) {
    const double east_m = i < 20 ? 0.0 : 0.5 * (i - 19);
    const geodesy::GeodeticPoint p = frame.toGeodetic(Eigen::Vector3d(east_m, 0.0, 0.0));
    char block[256];
    std::snprintf(block, sizeof(block),
                  "%d\n00:00:%02d,%03d --> 00:00:%02d,%03d\nGPS(%.7f,%.7f,300) BAROMETER:80\n\n",
                  i + 1, i / 10, (i % 10) * 100, (i + 1) / 10, ((i + 1) % 10) * 100,
                  p.longitude_deg, p.latitude_deg);
    text += block;
  }
  const SubtitleFile f = parseSubtitles(text, "p4.SRT");
  ASSERT_EQ(f.samples.size(), 40U) << (f.problems.empty() ? "" : f.problems.front());
  const SubtitleTelemetry t = toTelemetry(f, SubtitleTelemetryOptions{}, "p4.SRT");
  ASSERT_EQ(t.records.size(), 40U);
  EXPECT_EQ(t.nadirAssumed, 40U);
  EXPECT_GT(t.yawFromMotion, 15U);
  EXPECT_LT(t.yawFromMotion, 40U);
  // Hovering before the first motion: yaw 0; flying east: yaw 90 deg; pitch -90 throughout.
  EXPECT_DOUBLE_EQ(t.records[5].gimbal.angles.yaw_deg, 0.0);
  EXPECT_NEAR(t.records[30].gimbal.angles.yaw_deg, 90.0, 0.5);
  for (const sequence::TelemetryRecord& r : t.records) {
    EXPECT_DOUBLE_EQ(r.gimbal.angles.pitch_deg, -90.0);
    EXPECT_EQ(r.gimbal.reference, geodesy::GimbalReference::Earth);
  }
}

}  // namespace
}  // namespace vp::subtitle
