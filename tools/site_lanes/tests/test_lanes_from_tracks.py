"""lanes_from_tracks.py on synthetic trajectory files: straight tracks in two opposite lanes give
two lanes on their centre lines in their driving directions; slow and tentative rows, turning
tracks and a lane with too few tracks give none; a given site file's features are kept; bad input
stops with a message naming the file."""
import csv
import io
import json
import math
import os
import sys
import tempfile
import unittest
import unittest.mock
from contextlib import redirect_stdout

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
import lanes_from_tracks as lft  # noqa: E402

LAT0, LON0 = 43.0821, -89.4059
PLANE = lft.LocalPlane(LAT0, LON0)
COLUMNS = ["frame_id", "track_id", "velocity", "time_s", "status", "latitude_deg", "longitude_deg"]


def write_tracks(path, tracks):
    """tracks: [(track_id, [(x, y, speed, status), ...])] sampled at 10 Hz."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for tid, samples in tracks:
            for i, (x, y, v, status) in enumerate(samples):
                lon, lat = PLANE.to_lonlat(x, y)
                w.writerow([i, tid, v, 1700000000 + 0.1 * i, status, lat, lon])


def straight(tid, y, direction, speed=10.0, length=60.0, jitter=0.0):
    n = int(length / (speed * 0.1))
    xs = [(-30.0 + speed * 0.1 * i) * direction for i in range(n)]
    return tid, [(x, y + jitter * math.sin(0.7 * i), speed, "confirmed") for i, x in enumerate(xs)]


def lanes_of(path):
    with open(path) as f:
        site = json.load(f)
    return site, [f_ for f_ in site["features"] if f_["properties"]["kind"] == "lane"]


def xy(lonlat):
    lon, lat = lonlat
    return PLANE.to_xy(lat, lon)


class LanesFromTracks(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.tracks = os.path.join(self.dir.name, "a_tracks.csv")
        self.out = os.path.join(self.dir.name, "site.geojson")

    def tearDown(self):
        self.dir.cleanup()

    def run_tool(self, *args):
        with redirect_stdout(io.StringIO()):
            return lft.main(["--tracks", self.tracks, "--out", self.out, *args])

    def test_two_opposite_lanes_on_their_centre_lines(self):
        tracks = [straight(i, 0.0, +1, jitter=0.3) for i in range(4)]       # eastbound, y = 0
        tracks += [straight(10 + i, 3.5, -1, jitter=0.3) for i in range(3)]  # westbound, y = 3.5
        tracks += [straight(20, 9.0, +1)]                                   # one track: no lane
        # slow rows and tentative rows are not movement
        tracks += [(30 + i, [(x, 12.0, 0.5, "confirmed") for x in range(-30, 30)]) for i in range(3)]
        tracks += [(40 + i, [(x, 15.0, 9.0, "tentative") for x in range(-30, 30)]) for i in range(3)]
        write_tracks(self.tracks, tracks)
        self.run_tool()
        site, lanes = lanes_of(self.out)
        self.assertEqual(len(lanes), 2)
        kinds = sorted(f["properties"]["kind"] for f in site["features"])
        self.assertEqual(kinds, ["drivable", "lane", "lane"])  # a site needs a drivable area
        by_y = sorted(lanes, key=lambda f: xy(f["geometry"]["coordinates"][0])[1])
        for lane, y, direction in ((by_y[0], 0.0, +1), (by_y[1], 3.5, -1)):
            (x0, y0), (x1, y1) = (xy(c) for c in lane["geometry"]["coordinates"])
            self.assertAlmostEqual(y0, y, delta=0.2)
            self.assertAlmostEqual(y1, y, delta=0.2)
            self.assertGreater((x1 - x0) * direction, 45.0)  # drawn in its driving direction
            self.assertEqual(lane["properties"]["width_m"], 3.5)
        self.assertRegex(by_y[0]["properties"]["name"], "from 4 tracks")

    def test_a_turn_splits_a_track_into_runs(self):
        # Four tracks east along y = 0, then north along x = 30: two lanes, one each way.
        def turning(tid):
            pts = [(x, 0.0, 8.0, "confirmed") for x in range(-30, 31)]
            pts += [(30.0, y, 8.0, "confirmed") for y in range(1, 40)]
            return tid, pts
        write_tracks(self.tracks, [turning(i) for i in range(4)])
        self.run_tool()
        _, lanes = lanes_of(self.out)
        directions = sorted(round(math.degrees(math.atan2(
            xy(f["geometry"]["coordinates"][1])[1] - xy(f["geometry"]["coordinates"][0])[1],
            xy(f["geometry"]["coordinates"][1])[0] - xy(f["geometry"]["coordinates"][0])[0])))
            for f in lanes)
        self.assertEqual(len(lanes), 2)
        self.assertAlmostEqual(directions[0], 0, delta=2)
        self.assertAlmostEqual(directions[1], 90, delta=2)

    def test_a_site_files_features_are_kept_and_its_lanes_replaced(self):
        write_tracks(self.tracks, [straight(i, 0.0, +1) for i in range(3)])
        site_in = os.path.join(self.dir.name, "in.geojson")
        ring = [PLANE.to_lonlat(x, y) for x, y in ((-50, -20), (50, -20), (50, 20), (-50, 20), (-50, -20))]
        old_lane = [PLANE.to_lonlat(-40, 8), PLANE.to_lonlat(40, 8)]
        with open(site_in, "w") as f:
            json.dump({"type": "FeatureCollection", "features": [
                {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [ring]},
                 "properties": {"kind": "drivable", "id": "road", "name": "road"}},
                {"type": "Feature", "geometry": {"type": "LineString", "coordinates": old_lane},
                 "properties": {"kind": "lane", "id": "old", "name": "old"}},
                {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [ring]},
                 "properties": {"kind": "zone", "id": "q", "name": "q", "role": "queue", "lane": "old"}}]}, f)
        self.run_tool("--site", site_in)
        site, lanes = lanes_of(self.out)
        self.assertEqual(sorted(f["properties"]["id"] for f in site["features"]),
                         ["lane-drawn-1", "old", "q", "road"])
        self.run_tool("--site", site_in, "--replace-lanes")
        site, lanes = lanes_of(self.out)
        self.assertEqual(sorted(f["properties"]["id"] for f in site["features"]), ["lane-drawn-1", "road"])

    def test_bad_input_names_the_file(self):
        with open(self.tracks, "w") as f:
            f.write("frame_id,track_id\n1,2\n")
        with self.assertRaises(SystemExit) as e:
            self.run_tool()
        self.assertIn("a_tracks.csv", str(e.exception))
        self.assertIn("not a trajectory file", str(e.exception))
        write_tracks(self.tracks, [(1, [(0.0, 0.0, 0.2, "confirmed")])])
        with self.assertRaises(SystemExit) as e:
            self.run_tool()
        self.assertIn("no confirmed track moving", str(e.exception))
        with self.assertRaises(SystemExit):
            with redirect_stdout(io.StringIO()), unittest.mock.patch("sys.stderr", io.StringIO()):
                lft.main(["--tracks", self.tracks, "--out", self.out, "--replace-lanes"])


if __name__ == "__main__":
    unittest.main()
