#!/usr/bin/python3
"""Lanes of a site drawn from recorded traffic: the straight runs of moving tracks, grouped by
direction and lateral position, become `lane` features (LineStrings in their driving direction)
of a site file (docs/site_map.md) - a first draft of the lanes for the lanes' prior on front/back
(site.lane_direction_prior) and the traffic analysis, for an operator to check and edit in QGIS.

Input: trajectory files the app writes (vp_firmware_app --trajectory-csv; docs/tracking.md):
confirmed rows with their WGS84 position and speed. Each track's moving positions (|velocity| >=
--min-speed-mps) are resampled every metre along its path and cut where its direction turns by
more than --max-turn-deg from the run's; runs of at least --min-run-m are kept. Runs whose
directions lie within --merge-angle-deg and whose lateral distance is below --merge-offset-m form
one lane: its direction the runs' length-weighted mean, its centre line through their mean
lateral position, from the first to the last metre any run covers. A lane needs --min-tracks
distinct tracks and --min-length-m of length.

Output: a GeoJSON site file. With --site, every feature of that file is kept (with --replace-lanes
its lanes are left out) and the drawn lanes are added; without it the file holds the lanes and one
drivable area, the tracks' bounding rectangle widened by --margin-m (a site needs one). Ids
`lane-drawn-N`, names `lane drawn from N tracks`, width --width-m.

  lanes_from_tracks.py --tracks A_tracks.csv [B_tracks.csv ...] --out site.geojson
      [--site SITE.geojson [--replace-lanes]] [--max-frame N] [options]
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from typing import Dict, List, Sequence, Tuple

import numpy as np

EARTH_RADIUS_M = 6378137.0


class LocalPlane:
    """Equirectangular metres about a reference point: ample for a site of a few hundred metres."""

    def __init__(self, lat0_deg: float, lon0_deg: float):
        self.lat0, self.lon0 = lat0_deg, lon0_deg
        self.kx = EARTH_RADIUS_M * math.cos(math.radians(lat0_deg)) * math.pi / 180.0
        self.ky = EARTH_RADIUS_M * math.pi / 180.0

    def to_xy(self, lat_deg: float, lon_deg: float) -> Tuple[float, float]:
        return (lon_deg - self.lon0) * self.kx, (lat_deg - self.lat0) * self.ky

    def to_lonlat(self, x: float, y: float) -> List[float]:
        return [round(self.lon0 + x / self.kx, 9), round(self.lat0 + y / self.ky, 9)]


def read_tracks(paths: Sequence[str], min_speed_mps: float, max_frame: int | None
                ) -> Dict[Tuple[int, int], List[Tuple[float, float, float]]]:
    """(file index, track id) -> [(time_s, lat, lon)] of its confirmed, moving rows."""
    need = {"frame_id", "track_id", "velocity", "time_s", "status", "latitude_deg", "longitude_deg"}
    tracks: Dict[Tuple[int, int], List[Tuple[float, float, float]]] = {}
    for k, path in enumerate(paths):
        with open(path, newline="") as f:
            rows = csv.DictReader(line for line in f if not line.startswith("#"))
            missing = need - set(rows.fieldnames or [])
            if missing:
                raise SystemExit(f"{path}: not a trajectory file (no column {', '.join(sorted(missing))})")
            for line, r in enumerate(rows, start=2):
                try:
                    if r["status"] != "confirmed" or abs(float(r["velocity"])) < min_speed_mps:
                        continue
                    if max_frame is not None and int(r["frame_id"]) > max_frame:
                        continue
                    tracks.setdefault((k, int(r["track_id"])), []).append(
                        (float(r["time_s"]), float(r["latitude_deg"]), float(r["longitude_deg"])))
                except ValueError as e:
                    raise SystemExit(f"{path}: row {line}: {e}")
    for samples in tracks.values():
        samples.sort()
    return tracks


def resample(points: np.ndarray, step_m: float = 1.0) -> np.ndarray:
    """Points every step_m along the polyline (its first point kept)."""
    if len(points) < 2:
        return points
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] < step_m:
        return points[:1]
    t = np.arange(0.0, s[-1] + 1e-9, step_m)
    return np.stack([np.interp(t, s, points[:, 0]), np.interp(t, s, points[:, 1])], axis=1)


def straight_runs(path: np.ndarray, max_turn_deg: float, min_run_m: float, window: int = 3
                  ) -> List[np.ndarray]:
    """Cuts a path sampled every metre where its local direction leaves the run's by max_turn."""
    if len(path) < 2 * window + 2:
        return []
    runs, start = [], 0
    cos_max = math.cos(math.radians(max_turn_deg))
    ref = None
    for i in range(window, len(path) - window):
        d = path[i + window] - path[i - window]
        n = np.linalg.norm(d)
        if n < 1e-6:
            continue
        d = d / n
        if ref is None:
            ref = d
            continue
        if float(d @ ref) < cos_max:
            runs.append(path[start:i])
            start, ref = i, d
    runs.append(path[start:])
    return [r for r in runs if len(r) >= 2 and np.linalg.norm(r[-1] - r[0]) >= min_run_m]


class Lane:
    def __init__(self, run: np.ndarray, track):
        self.runs = []
        self.tracks = set()
        self.add(run, track)

    def add(self, run: np.ndarray, track) -> None:
        self.runs.append(run)
        self.tracks.add(track)
        d = np.zeros(2)
        for r in self.runs:
            d += r[-1] - r[0]  # longer runs weigh more
        self.direction = d / np.linalg.norm(d)
        self.normal = np.array([-self.direction[1], self.direction[0]])
        pts = np.concatenate(self.runs)
        self.offset = float(np.mean(pts @ self.normal))
        along = pts @ self.direction
        self.along = (float(along.min()), float(along.max()))

    def accepts(self, run: np.ndarray, cos_angle: float, max_offset_m: float, max_gap_m: float) -> bool:
        d = run[-1] - run[0]
        d = d / np.linalg.norm(d)
        if float(d @ self.direction) < cos_angle:
            return False
        if abs(float(np.mean(run @ self.normal)) - self.offset) > max_offset_m:
            return False
        a = run @ self.direction
        return a.min() <= self.along[1] + max_gap_m and a.max() >= self.along[0] - max_gap_m

    def ends(self) -> Tuple[np.ndarray, np.ndarray]:
        base = self.offset * self.normal
        return base + self.along[0] * self.direction, base + self.along[1] * self.direction


def draw_lanes(tracks, plane: LocalPlane, args) -> List[Lane]:
    runs = []
    for key, samples in tracks.items():
        xy = np.array([plane.to_xy(lat, lon) for _, lat, lon in samples], float)
        for run in straight_runs(resample(xy), args.max_turn_deg, args.min_run_m):
            runs.append((run, key))
    runs.sort(key=lambda rk: -np.linalg.norm(rk[0][-1] - rk[0][0]))
    lanes: List[Lane] = []
    cos_angle = math.cos(math.radians(args.merge_angle_deg))
    for run, key in runs:
        for lane in lanes:
            if lane.accepts(run, cos_angle, args.merge_offset_m, args.max_gap_m):
                lane.add(run, key)
                break
        else:
            lanes.append(Lane(run, key))
    return [l for l in lanes if len(l.tracks) >= args.min_tracks
            and l.along[1] - l.along[0] >= args.min_length_m]


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tracks", nargs="+", required=True, metavar="CSV",
                   help="trajectory files of the app (vp_firmware_app --trajectory-csv)")
    p.add_argument("--out", required=True, help="the site file to write (GeoJSON)")
    p.add_argument("--site", help="a site file whose features are kept and extended")
    p.add_argument("--replace-lanes", action="store_true",
                   help="with --site: leave out its lanes (and zones that name one)")
    p.add_argument("--max-frame", type=int, help="use only rows up to this frame id")
    p.add_argument("--min-speed-mps", type=float, default=2.0, help="moving rows only (default 2)")
    p.add_argument("--max-turn-deg", type=float, default=20.0,
                   help="a run ends where the track turns by more (default 20)")
    p.add_argument("--min-run-m", type=float, default=10.0, help="shortest run kept (default 10)")
    p.add_argument("--merge-angle-deg", type=float, default=12.0,
                   help="runs of one lane differ in direction by less (default 12)")
    p.add_argument("--merge-offset-m", type=float, default=1.5,
                   help="... and lie closer sideways than this (default 1.5)")
    p.add_argument("--max-gap-m", type=float, default=10.0,
                   help="... with at most this gap between them along the lane (default 10)")
    p.add_argument("--min-tracks", type=int, default=3, help="tracks a lane needs (default 3)")
    p.add_argument("--min-length-m", type=float, default=15.0, help="shortest lane (default 15)")
    p.add_argument("--width-m", type=float, default=3.5, help="the lanes' width_m (default 3.5)")
    p.add_argument("--margin-m", type=float, default=5.0,
                   help="without --site: the drivable area's margin around the tracks (default 5)")
    args = p.parse_args(argv)
    for name in ("min_speed_mps", "min_run_m", "merge_offset_m", "max_gap_m", "min_length_m", "margin_m"):
        if not getattr(args, name) >= 0:
            p.error(f"--{name.replace('_', '-')} must be >= 0")
    if not 0 < args.width_m <= 50:
        p.error("--width-m must be in (0, 50]")
    if not 0 < args.max_turn_deg < 90 or not 0 < args.merge_angle_deg < 90:
        p.error("--max-turn-deg and --merge-angle-deg must be in (0, 90)")
    if args.min_tracks < 1:
        p.error("--min-tracks must be >= 1")
    if args.replace_lanes and not args.site:
        p.error("--replace-lanes needs --site")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    tracks = read_tracks(args.tracks, args.min_speed_mps, args.max_frame)
    if not tracks:
        raise SystemExit(f"{args.tracks[0]}: no confirmed track moving at >= {args.min_speed_mps} m/s")
    lat0 = float(np.mean([s[1] for v in tracks.values() for s in v]))
    lon0 = float(np.mean([s[2] for v in tracks.values() for s in v]))
    plane = LocalPlane(lat0, lon0)
    lanes = draw_lanes(tracks, plane, args)

    features = []
    if args.site:
        try:
            with open(args.site) as f:
                site = json.load(f)
            kept = site["features"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise SystemExit(f"{args.site}: not a site file ({e})")
        dropped = set()
        if args.replace_lanes:
            dropped = {f["properties"]["id"] for f in kept if f["properties"].get("kind") == "lane"}
        features = [f for f in kept if f["properties"].get("id") not in dropped
                    and f["properties"].get("lane") not in dropped]
        collection = {k: v for k, v in site.items() if k != "features"}
    else:
        xy = np.array([plane.to_xy(lat, lon) for v in tracks.values() for _, lat, lon in v])
        (x0, y0), (x1, y1) = xy.min(0) - args.margin_m, xy.max(0) + args.margin_m
        ring = [plane.to_lonlat(x, y) for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0))]
        features = [{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [ring]},
                     "properties": {"kind": "drivable", "id": "drivable-drawn",
                                    "name": "the tracks' extent"}}]
        collection = {"type": "FeatureCollection"}
    for i, lane in enumerate(lanes, start=1):
        a, b = lane.ends()
        features.append({"type": "Feature",
                         "geometry": {"type": "LineString",
                                      "coordinates": [plane.to_lonlat(*a), plane.to_lonlat(*b)]},
                         "properties": {"kind": "lane", "id": f"lane-drawn-{i}",
                                        "name": f"lane drawn from {len(lane.tracks)} tracks",
                                        "width_m": args.width_m}})
    collection["features"] = features
    with open(args.out, "w") as f:
        json.dump(collection, f, indent=1)
        f.write("\n")
    print(f"lanes_from_tracks: {len(lanes)} lanes from {len(tracks)} moving tracks -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
