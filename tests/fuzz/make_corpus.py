#!/usr/bin/python3
"""Writes the seed corpus of the fuzz targets, tests/fuzz/corpus/<target>/ (docs/fuzzing.md).

    tests/fuzz/make_corpus.py          # rewrites the seeds (deterministic, byte-identical)

Seeds are small valid inputs of each parser, built from the repository's fixtures and
documentation examples; the campaign (scripts/fuzz.sh) mutates them. Findings fixed later are
added beside them by hand as finding-<target>-<what> (never rewritten by this script). The
ONNX seed is a tiny QDQ model made here with the onnx package (Debian's python3-onnx); the
fixture model tests/fixtures/models/classifier.onnx and config/default.yaml (15 kB) are
referenced in place (tests/fuzz/CMakeLists.txt, scripts/fuzz.sh).
"""

import os
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")
FIXTURES = os.path.join(ROOT, "tests", "fixtures")


def read(*parts):
    with open(os.path.join(*parts), "rb") as f:
        return f.read()


def write(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    with open(os.path.join(CORPUS, target, name), "wb") as f:
        f.write(data)


# ---- config_yaml ------------------------------------------------------------------------------

MINIMAL_CONFIG = b"""origin: {latitude_deg: 43.0731, longitude_deg: -89.4012, height_m: 260.0}
camera: {width_px: 32, height_px: 24, fx_px: 40.0, fy_px: 40.0}
terrain: {dtm_path: dtm.tif, crs: utm:16N, max_samples: 4096}
"""

LOOP_CONFIG = MINIMAL_CONFIG + b"""mount:
  roll_deg: 0.5
  pitch_deg: -90
  lever_arm_m: [0.1, 0.0, -0.05]
pose: {capacity: 64}
tracking: {}
source: {kind: replay, sequence_dir: seq}
telemetry: {source: recording}
app: {queue_depth: 2}
dds:
  enabled: false
  domain_id: 7
perception:
  detector_model: none.onnx
  crop_model: none
  backend: int8
  threads: 2
  white_balance_regions: [2, 3]
"""


def config_seeds():
    write("config_yaml", "minimal.yaml", MINIMAL_CONFIG)
    write("config_yaml", "loop_sections.yaml", LOOP_CONFIG)
    write("config_yaml", "rig_of_sequence_min.yaml",
          read(FIXTURES, "sequence_min", "rig.yaml"))


# ---- sequence_files ---------------------------------------------------------------------------

def sequence_seeds():
    seq = os.path.join(FIXTURES, "sequence_min")
    rig = read(seq, "rig.yaml").replace(b"../dtm/sloped_utm16n.tif", b"dtm.tif")
    parts = [read(seq, "sequence.yaml"), rig, read(seq, "frames.csv"),
             read(seq, "telemetry.csv")]
    write("sequence_files", "sequence_min", b"\0".join(parts))
    truth = [read(seq, "ground_truth", "objects.csv"), read(seq, "ground_truth", "keypoints.csv")]
    write("sequence_files", "sequence_min_ground_truth", b"\0".join(parts + truth))


# ---- dtm_file ---------------------------------------------------------------------------------

def dtm_input(tiff, world=b"", configure_crs=False):
    return bytes([1 if configure_crs else 0]) + struct.pack("<H", len(world)) + world + tiff


def plain_float_tiff(cols, rows, compression=1):
    """A minimal little-endian float32 TIFF, one strip, no GeoTIFF tags."""
    pixels = b"".join(struct.pack("<f", 250.0 + 0.5 * c - 0.25 * r)
                      for r in range(rows) for c in range(cols))
    entries = [  # (tag, type, count, value); types: 3 SHORT, 4 LONG
        (256, 4, 1, cols), (257, 4, 1, rows), (258, 3, 1, 32), (259, 3, 1, compression),
        (262, 3, 1, 1), (273, 4, 1, 0), (277, 3, 1, 1), (278, 4, 1, rows),
        (279, 4, 1, len(pixels)), (284, 3, 1, 1), (339, 3, 1, 3)]
    ifd_offset = 8
    ifd_size = 2 + 12 * len(entries) + 4
    data_offset = ifd_offset + ifd_size
    out = b"II*\0" + struct.pack("<I", ifd_offset) + struct.pack("<H", len(entries))
    for tag, typ, count, value in entries:
        if tag == 273:
            value = data_offset
        field = struct.pack("<H", value) + b"\0\0" if typ == 3 else struct.pack("<I", value)
        out += struct.pack("<HHI", tag, typ, count) + field
    return out + struct.pack("<I", 0) + pixels


def dtm_seeds():
    geotiff = read(FIXTURES, "dtm", "sloped_utm16n.tif")
    write("dtm_file", "geotiff_utm16n", dtm_input(geotiff))
    write("dtm_file", "geotiff_utm16n_configured_crs", dtm_input(geotiff, configure_crs=True))
    world = b"5.0\n0.0\n0.0\n-5.0\n304410.0\n4771831.0\n"
    write("dtm_file", "plain_with_world_file", dtm_input(plain_float_tiff(6, 5), world, True))
    write("dtm_file", "plain_world_file_no_crs", dtm_input(plain_float_tiff(4, 4), world))


# ---- mavlink_stream ---------------------------------------------------------------------------

CRC_EXTRA = {30: 39, 31: 246, 33: 104, 285: 137}


def crc_x25(data, crc=0xFFFF):
    for byte in data:
        tmp = byte ^ (crc & 0xFF)
        tmp = (tmp ^ (tmp << 4)) & 0xFF
        crc = ((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)) & 0xFFFF
    return crc


def mavlink_frame(msgid, payload, seq=0, sysid=1, compid=1, signed=False):
    payload = payload.rstrip(b"\0") or b"\0"  # MAVLink 2 trailing-zero truncation
    header = bytes([len(payload), 0x01 if signed else 0, 0, seq, sysid, compid,
                    msgid & 0xFF, (msgid >> 8) & 0xFF, (msgid >> 16) & 0xFF])
    crc = crc_x25(header + payload)
    crc = crc_x25(bytes([CRC_EXTRA[msgid]]), crc)
    frame = b"\xfd" + header + payload + struct.pack("<H", crc)
    if signed:
        frame += bytes(range(13))
    return frame


def mavlink_seeds():
    position = struct.pack("<IiiiihhhH", 1000, 430731000, -894012000, 260000, 100000, 50, -20, 0,
                           9000)
    quaternion = struct.pack("<I4f3f4f", 1010, 0.7071068, 0.0, 0.0, 0.7071068, 0, 0, 0, 0, 0, 0, 0)
    attitude = struct.pack("<I6f", 1020, 0.01, -0.02, 1.57, 0, 0, 0)
    gimbal = struct.pack("<I4f3fIHBBffB", 1030, 0.7071068, 0.0, -0.7071068, 0.0, 0, 0, 0, 0, 64,
                         1, 1, float("nan"), 0.0, 1)
    stream = (mavlink_frame(33, position, 0) + mavlink_frame(31, quaternion, 1) +
              mavlink_frame(30, attitude, 2) + mavlink_frame(285, gimbal, 3, compid=154))
    write("mavlink_stream", "serial_four_messages", b"\0" + stream)
    noisy = b"\x55\xfe\x01" + stream[:20] + stream + mavlink_frame(33, position, 4, signed=True)
    write("mavlink_stream", "serial_noise_cut_frame_signed", b"\0" + noisy)
    # Datagrams of 40 bytes: frames straddle datagram ends (counted as truncated).
    write("mavlink_stream", "datagrams_40", bytes([40]) + stream)


# ---- onnx_model -------------------------------------------------------------------------------

def onnx_seed():
    import numpy as np
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    def scalar(name, value, dtype):
        return numpy_helper.from_array(np.array(value, dtype=dtype), name)

    inits = [scalar("s_in", 1.0 / 128, np.float32), scalar("z", 0, np.int8),
             scalar("s_a", 0.05, np.float32), scalar("s_b", 0.04, np.float32),
             scalar("s_c", 0.1, np.float32)]
    rng = np.random.RandomState(3)
    w1 = rng.randint(-100, 100, size=(4, 3, 3, 3)).astype(np.int8)
    w2 = rng.randint(-100, 100, size=(2, 4, 1, 1)).astype(np.int8)
    inits += [numpy_helper.from_array(w1, "w1_q"),
              numpy_helper.from_array(np.full(4, 0.01, np.float32), "w1_s"),
              numpy_helper.from_array(np.zeros(4, np.int8), "w1_z"),
              numpy_helper.from_array(np.linspace(-0.1, 0.1, 4).astype(np.float32), "b1"),
              numpy_helper.from_array(w2, "w2_q"),
              numpy_helper.from_array(np.full(2, 0.02, np.float32), "w2_s"),
              numpy_helper.from_array(np.zeros(2, np.int8), "w2_z"),
              numpy_helper.from_array(np.zeros(2, np.float32), "b2")]
    n = helper.make_node
    nodes = [
        n("QuantizeLinear", ["image", "s_in", "z"], ["image_q"], name="q_in"),
        n("DequantizeLinear", ["image_q", "s_in", "z"], ["image_dq"], name="dq_in"),
        n("DequantizeLinear", ["w1_q", "w1_s", "w1_z"], ["w1"], name="dq_w1", axis=0),
        n("Conv", ["image_dq", "w1", "b1"], ["c1"], name="conv1", kernel_shape=[3, 3],
          pads=[1, 1, 1, 1]),
        n("Relu", ["c1"], ["r1"], name="relu1"),
        n("QuantizeLinear", ["r1", "s_a", "z"], ["r1_q"], name="q_r1"),
        n("DequantizeLinear", ["r1_q", "s_a", "z"], ["r1_dq"], name="dq_r1"),
        n("MaxPool", ["r1_dq"], ["p1"], name="pool1", kernel_shape=[2, 2], strides=[2, 2]),
        n("QuantizeLinear", ["p1", "s_a", "z"], ["p1_q"], name="q_p1"),
        n("DequantizeLinear", ["p1_q", "s_a", "z"], ["p1_dq"], name="dq_p1"),
        n("DequantizeLinear", ["w2_q", "w2_s", "w2_z"], ["w2"], name="dq_w2", axis=0),
        n("Conv", ["p1_dq", "w2", "b2"], ["c2"], name="conv2", kernel_shape=[1, 1]),
        n("QuantizeLinear", ["c2", "s_b", "z"], ["c2_q"], name="q_c2"),
        n("DequantizeLinear", ["c2_q", "s_b", "z"], ["heads"], name="dq_c2"),
        n("Sigmoid", ["heads"], ["sg"], name="sigmoid"),
        n("QuantizeLinear", ["sg", "s_c", "z"], ["sg_q"], name="q_sg"),
        n("DequantizeLinear", ["sg_q", "s_c", "z"], ["scores"], name="dq_sg"),
    ]
    graph = helper.make_graph(
        nodes, "fuzz_seed",
        [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 3, 8, 8])],
        [helper.make_tensor_value_info("heads", TensorProto.FLOAT, [1, 2, 4, 4]),
         helper.make_tensor_value_info("scores", TensorProto.FLOAT, [1, 2, 4, 4])],
        initializer=inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)],
                              producer_name="vp fuzz seed")
    model.ir_version = 7
    for key, value in (("vp.input.channel_order", "rgb"), ("vp.input.mean", "0,0,0"),
                       ("vp.input.scale", "0.00392157,0.00392157,0.00392157")):
        entry = model.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.checker.check_model(model)
    write("onnx_model", "tiny_qdq.onnx", model.SerializeToString())


# ---- detections_file / trajectory_file -------------------------------------------------------

def doc_block(doc, starts):
    """The ```text block of docs/<doc> whose first line starts with `starts`."""
    text = read(ROOT, "docs", doc).decode()
    for block in text.split("```text\n")[1:]:
        body = block.split("```")[0]
        if body.startswith(starts):
            return body.encode()
    raise SystemExit(f"docs/{doc}: no example starting with {starts!r}")


def output_file_seeds():
    dets = doc_block("detections_file.md", "# format_version")
    write("detections_file", "frames_doc_example.csv", dets)
    header, *rows = dets.decode().split("\n")[3:]
    image = ["image" + header[len("frame_id"):]]
    for i, row in enumerate(r for r in rows if r):
        image.append(f"IMG_{i:04d}" + row[row.index(","):])
    write("detections_file", "images_no_metadata.csv", ("\n".join(image) + "\n").encode())
    # format 1 (no at_frame_edge, vehicle_probability: fields 9 and 10), which the reader still reads
    old = [",".join(f[:9] + f[11:]) for f in (line.split(",") for line in image)]
    write("detections_file", "images_format1.csv",
          ("# format_version: 1\n" + "\n".join(old) + "\n").encode())
    traj = doc_block("tracking.md", "frame_id,class_id")
    write("trajectory_file", "doc_example.csv", traj)
    lines = traj.decode().split("\n")
    cut = [",".join(line.split(",")[:38]) for line in lines if line]  # no gamma columns
    write("trajectory_file", "no_gamma_columns.csv", ("\n".join(cut) + "\n").encode())


# ---- site_file -------------------------------------------------------------------------------

def doc_json(doc):
    """The first ```json block of docs/<doc>."""
    text = read(ROOT, "docs", doc).decode()
    return text.split("```json\n")[1].split("```")[0].encode()


# A crossroads of two roads with a zone at the junction, lanes and gates on each approach, in
# the form vp_simulate writes (one feature per line), around the fuzz harness's world frame.
def crossroads():
    lon0, lat0 = 11.5750, 48.1371
    d_lon, d_lat = 0.0001349, 0.0000899  # about 10 m each way

    def pos(e, n):
        return f"[{lon0 + e * d_lon / 10:.8f}, {lat0 + n * d_lat / 10:.8f}]"

    def rect(e0, n0, e1, n1):
        return "[[" + ", ".join(pos(e, n) for e, n in
                                ((e0, n0), (e1, n0), (e1, n1), (e0, n1), (e0, n0))) + "]]"

    def feature(kind, fid, name, geometry, coordinates):
        return ('  {"type": "Feature", "properties": {"kind": "%s", "id": "%s", "name": "%s"}, '
                '"geometry": {"type": "%s", "coordinates": %s}}' % (kind, fid, name, geometry,
                                                                  coordinates))

    features = [
        feature("drivable", "road-ew", "east-west road", "Polygon", rect(-60, -7, 60, 7)),
        feature("drivable", "road-ns", "north-south road", "Polygon", rect(-7, -60, 7, 60)),
        feature("parking", "lot-ne", "corner lot", "Polygon", rect(15, 15, 45, 40)),
        feature("exclusion", "roof-sw", "shop roof", "Polygon", rect(-45, -40, -15, -15)),
        feature("zone", "box-1", "box junction", "Polygon", rect(-7, -7, 7, 7)),
        feature("lane", "ew-east", "eastbound", "LineString", f"[{pos(-60, -3.5)}, {pos(60, -3.5)}]"),
        feature("lane", "ew-west", "westbound", "LineString", f"[{pos(60, 3.5)}, {pos(-60, 3.5)}]"),
        feature("lane", "ns-north", "northbound", "LineString",
                f"[{pos(3.5, -60)}, {pos(3.5, 0)}, {pos(3.5, 60)}]"),
        feature("gate", "gate-w", "west approach", "LineString", f"[{pos(-9, -7)}, {pos(-9, 7)}]"),
        feature("gate", "gate-e", "east approach", "LineString", f"[{pos(9, -7)}, {pos(9, 7)}]"),
        feature("gate", "gate-s", "south approach", "LineString", f"[{pos(-7, -9)}, {pos(7, -9)}]"),
    ]
    return ('{"type": "FeatureCollection",\n "features": [\n' + ",\n".join(features) +
            "\n ]}\n").encode()


def site_seeds():
    doc = doc_json("site_map.md")
    write("site_file", "doc_example.geojson", doc)
    write("site_file", "crossroads.geojson", crossroads())
    write("site_file", "crs84_member_3d_positions.geojson", doc.replace(
        b'"features": [',
        b'"crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},\n'
        b' "features": [', 1).replace(b"[11.5740, 48.1370]", b"[11.5740, 48.1370, 521.5]"))
    # Refused files, one problem each (the loader's messages, docs/site_map.md).
    refused = {
        "bad-not-json.geojson": doc[: len(doc) // 2],
        "bad-topology.geojson": b'{"type": "Topology", "objects": {}}\n',
        "bad-projected-crs.geojson": doc.replace(
            b'"features": [',
            b'"crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},'
            b'\n "features": [', 1),
        "bad-open-ring.geojson": doc.replace(b", [11.5740, 48.1370]]]", b"]]", 1),
        "bad-self-intersecting.geojson": doc.replace(
            b"[11.5760, 48.1372], [11.5740, 48.1372]", b"[11.5740, 48.1372], [11.5760, 48.1372]", 1),
        "bad-unknown-property.geojson": doc.replace(
            b'"name": "Main St"', b'"name": "Main St", "lanes": 2', 1),
        "bad-duplicate-id.geojson": doc.replace(b'"id": "roof-1"', b'"id": "road-1"', 1),
        "bad-no-drivable.geojson": doc.replace(b'"kind": "drivable"', b'"kind": "zone"', 1),
        "bad-one-position-gate.geojson": doc.replace(b"[[11.5742, 48.1370], [11.5742, 48.1372]]",
                                                     b"[[11.5742, 48.1370]]", 1),
        "bad-hole.geojson": doc.replace(b"[11.5745, 48.1374]]]}}",
                                        b"[11.5745, 48.1374]], [[11.5746, 48.1375], "
                                        b"[11.5747, 48.1375], [11.5747, 48.1375], "
                                        b"[11.5746, 48.1375]]]}}", 1),
        "bad-projected-positions.geojson": doc.replace(b"[11.5740, 48.13705]",
                                                       b"[691234.5, 5334567.8]", 1),
    }
    for name, data in refused.items():
        if data == doc:
            raise SystemExit(f"site seed {name}: the replacement did not apply")
        write("site_file", name, data)


def main():
    config_seeds()
    sequence_seeds()
    dtm_seeds()
    mavlink_seeds()
    output_file_seeds()
    site_seeds()
    onnx_seed()
    return 0


if __name__ == "__main__":
    sys.exit(main())
