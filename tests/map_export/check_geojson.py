#!/usr/bin/python3
"""Checks that a file is GeoJSON that GIS programs open (RFC 7946), for vp_map_export's tests.

    check_geojson.py MAP.geojson [--expect-features N]

1. Strict JSON (Python's json module, UTF-8; NaN and Infinity refused).
2. RFC 7946 structure: a FeatureCollection of Features, each with a properties object whose
   values are scalars, and a Point, LineString or Polygon geometry; positions [longitude,
   latitude] within range; a LineString has two or more distinct positions; a Polygon's rings
   have four or more positions and are closed; the outer ring is counter-clockwise.
3. When GDAL's library is installed (libgdal, QGIS's reader of GeoJSON), the file is opened with
   its GeoJSON driver (through ctypes: no Python binding needed) and must give back every feature.
Exit status 0 when everything holds; otherwise 1 and the problems on stderr.
"""

import argparse
import ctypes
import ctypes.util
import json
import sys


def refuse_constant(name):
    raise ValueError(f"{name} is not JSON")


def check_position(p, where, problems):
    if (not isinstance(p, list) or len(p) not in (2, 3)
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)):
        problems.append(f"{where}: not a position [lon, lat]: {p!r}")
        return False
    if not (-180 <= p[0] <= 180 and -90 <= p[1] <= 90):
        problems.append(f"{where}: [{p[0]}, {p[1]}] is not WGS84 longitude/latitude")
        return False
    return True


def signed_area(ring):
    return sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(ring, ring[1:])) / 2


def check_geometry(g, where, problems):
    if not isinstance(g, dict) or "type" not in g or "coordinates" not in g:
        problems.append(f"{where}: geometry without type or coordinates")
        return
    kind, c = g["type"], g["coordinates"]
    if kind == "Point":
        check_position(c, where, problems)
    elif kind == "LineString":
        if not isinstance(c, list) or len(c) < 2:
            problems.append(f"{where}: a LineString needs two or more positions")
            return
        if all(check_position(p, where, problems) for p in c) and len(
                {tuple(p) for p in c}) < 2:
            problems.append(f"{where}: a LineString with one distinct position")
    elif kind == "Polygon":
        if not isinstance(c, list) or not c:
            problems.append(f"{where}: a Polygon without rings")
            return
        for i, ring in enumerate(c):
            if not isinstance(ring, list) or len(ring) < 4:
                problems.append(f"{where}: ring {i} has fewer than 4 positions")
                continue
            if not all(check_position(p, where, problems) for p in ring):
                continue
            if ring[0] != ring[-1]:
                problems.append(f"{where}: ring {i} is not closed")
            elif i == 0 and signed_area(ring) <= 0:
                problems.append(f"{where}: the outer ring is not counter-clockwise")
    else:
        problems.append(f"{where}: unexpected geometry type {kind!r}")


def check_structure(doc, problems):
    if not isinstance(doc, dict) or doc.get("type") != "FeatureCollection":
        problems.append("not a FeatureCollection")
        return 0
    if "crs" in doc:
        problems.append("a crs member (RFC 7946 has none: WGS84 only)")
    features = doc.get("features")
    if not isinstance(features, list):
        problems.append("features is not an array")
        return 0
    for i, f in enumerate(features):
        where = f"feature {i}"
        if not isinstance(f, dict) or f.get("type") != "Feature":
            problems.append(f"{where}: not a Feature")
            continue
        props = f.get("properties")
        if not isinstance(props, dict):
            problems.append(f"{where}: properties is not an object")
        elif any(isinstance(v, (dict, list)) for v in props.values()):
            problems.append(f"{where}: a property that is not a scalar (GIS tables hold scalars)")
        check_geometry(f.get("geometry"), where, problems)
    return len(features)


def ogr_feature_count(path):
    """Features GDAL's GeoJSON driver reads from the file, or None when GDAL is not installed."""
    name = ctypes.util.find_library("gdal")
    candidates = [name] if name else []
    candidates += ["libgdal.so.32", "libgdal.so"]
    gdal = None
    for candidate in candidates:
        try:
            gdal = ctypes.CDLL(candidate)
            break
        except OSError:
            continue
    if gdal is None:
        return None
    gdal.GDALAllRegister()
    gdal.GDALOpenEx.restype = ctypes.c_void_p
    gdal.GDALOpenEx.argtypes = [ctypes.c_char_p, ctypes.c_uint, ctypes.c_void_p, ctypes.c_void_p,
                                ctypes.c_void_p]
    gdal.GDALDatasetGetLayerCount.argtypes = [ctypes.c_void_p]
    gdal.GDALDatasetGetLayer.restype = ctypes.c_void_p
    gdal.GDALDatasetGetLayer.argtypes = [ctypes.c_void_p, ctypes.c_int]
    gdal.OGR_L_GetFeatureCount.restype = ctypes.c_longlong
    gdal.OGR_L_GetFeatureCount.argtypes = [ctypes.c_void_p, ctypes.c_int]
    gdal.GDALClose.argtypes = [ctypes.c_void_p]
    gdal_of_vector = 0x04
    drivers = (ctypes.c_char_p * 2)(b"GeoJSON", None)
    dataset = gdal.GDALOpenEx(path.encode(), gdal_of_vector, drivers, None, None)
    if not dataset:
        return -1
    count = 0
    for i in range(gdal.GDALDatasetGetLayerCount(dataset)):
        count += gdal.OGR_L_GetFeatureCount(gdal.GDALDatasetGetLayer(dataset, i), 1)
    gdal.GDALClose(dataset)
    return count


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("path")
    parser.add_argument("--expect-features", type=int)
    args = parser.parse_args()
    problems = []
    try:
        with open(args.path, "rb") as f:
            doc = json.loads(f.read().decode("utf-8"), parse_constant=refuse_constant)
    except (ValueError, UnicodeDecodeError) as error:
        print(f"{args.path}: not strict JSON: {error}", file=sys.stderr)
        return 1
    count = check_structure(doc, problems)
    if args.expect_features is not None and count != args.expect_features:
        problems.append(f"{count} features, expected {args.expect_features}")
    ogr = ogr_feature_count(args.path)
    if ogr is None:
        print(f"{args.path}: GDAL not installed: the GeoJSON driver check is skipped")
    elif ogr != count:
        problems.append(f"GDAL's GeoJSON driver reads {ogr} features of {count}"
                        if ogr >= 0 else "GDAL's GeoJSON driver cannot open the file")
    else:
        print(f"{args.path}: GDAL's GeoJSON driver reads all {ogr} features")
    for p in problems:
        print(f"{args.path}: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
