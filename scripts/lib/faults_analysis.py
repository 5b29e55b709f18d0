#!/usr/bin/env python3
"""Helpers of scripts/faults.sh (not run by hand): the parts of the fault cases that are easier
in Python than in bash. Each subcommand prints what faults.sh reads back (key=value lines) and
explains a failed check on stderr.

  slow_reader FIFO COPY RATE_BPS     reads FIFO at about RATE_BPS bytes/s into COPY until EOF
  write_stalls STRACE_LOG NAME       durations of the write(2) calls on files whose path
                                     contains NAME (strace -f -T -y output)
  watchdog_gaps SOCKET LOG -- CMD    plays systemd's notify socket for CMD (READY=1,
                                     WATCHDOG=1 times), runs it to its end
  churn TRAJECTORY_CSV SUB_CSV...    what each subscriber received first, against the app's
                                     trajectory file (the tracks the app published per frame)
  telemetry SEQUENCE DETECTIONS_CSV MAX_AGE_S LOOKAHEAD_S
                                     the frames a pose should be stale for, from the recording,
                                     against the lift status in the detections file
"""

import csv
import os
import re
import socket
import statistics
import subprocess
import sys
import time


def slow_reader(fifo, copy, rate_bps):
    """A slow disk: takes at most rate_bps bytes per second from the FIFO (in 10 ms steps)."""
    rate = float(rate_bps)
    step_s = 0.01
    chunk = max(1, int(rate * step_s))
    with open(fifo, "rb", buffering=0) as src, open(copy, "wb") as dst:
        next_t = time.monotonic()
        while True:
            data = src.read(chunk)
            if not data:
                break
            dst.write(data)
            next_t += len(data) / rate
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
    return 0


def percentile(values, q):
    ordered = sorted(values)
    if not ordered:
        return float("nan")
    index = min(len(ordered) - 1, max(0, int(round(q / 100.0 * (len(ordered) - 1)))))
    return ordered[index]


def write_stalls(log, name):
    """strace -f -T -y lines: 'PID write(FD<path>, ..., N) = N <0.000123>', also split into
    '<unfinished ...>' and '<... write resumed>' when threads interleave."""
    pending = {}
    durations = []
    sizes = []
    whole = re.compile(r"^(\d+)\s+write\((\d+)<([^>]*)>,.*\)\s+=\s+(-?\d+).*<([0-9.]+)>$")
    start = re.compile(r"^(\d+)\s+write\((\d+)<([^>]*)>,.*<unfinished \.\.\.>$")
    resumed = re.compile(r"^(\d+)\s+<\.\.\. write resumed>.*=\s+(-?\d+).*<([0-9.]+)>$")
    with open(log, encoding="utf-8", errors="replace") as f:
        for line in f:
            line = line.rstrip("\n")
            m = whole.match(line)
            if m:
                if name in m.group(3):
                    durations.append(float(m.group(5)))
                    sizes.append(int(m.group(4)))
                continue
            m = start.match(line)
            if m:
                pending[m.group(1)] = name in m.group(3)
                continue
            m = resumed.match(line)
            if m and pending.pop(m.group(1), False):
                durations.append(float(m.group(3)))
                sizes.append(int(m.group(2)))
    ms = [d * 1000.0 for d in durations]
    print(f"writes={len(ms)}")
    if ms:
        print(f"bytes_median={int(statistics.median(sizes))}")
        print(f"write_median_ms={statistics.median(ms):.3f}")
        print(f"write_p99_ms={percentile(ms, 99):.3f}")
        print(f"write_max_ms={max(ms):.3f}")
        print(f"write_total_s={sum(ms) / 1000.0:.3f}")
    return 0


def watchdog_gaps(sock_path, log, command):
    """systemd's side of sd_notify(3) for one run of command: READY=1 and WATCHDOG=1 times."""
    if os.path.exists(sock_path):
        os.unlink(sock_path)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(sock_path)
    sock.settimeout(0.05)
    t0 = time.monotonic()
    ready = None
    kicks = []
    with open(log, "wb") as out:
        proc = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT)
        while True:
            try:
                data = sock.recv(4096)
            except socket.timeout:
                if proc.poll() is not None:
                    break
                continue
            now = time.monotonic() - t0
            for line in data.decode("utf-8", "replace").split("\n"):
                if line == "READY=1" and ready is None:
                    ready = now
                elif line == "WATCHDOG=1":
                    kicks.append(now)
    end = time.monotonic() - t0
    sock.close()
    os.unlink(sock_path)
    stamps = ([ready] if ready is not None else []) + [k for k in kicks if ready is None or k >= ready]
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    print(f"exit={proc.returncode}")
    print(f"ready_s={ready if ready is not None else -1:.3f}")
    print(f"kicks={len(kicks)}")
    print(f"max_gap_s={max(gaps) if gaps else 0.0:.3f}")
    print(f"run_s={end:.3f}")
    return 0


def read_trajectory(path):
    """{frame_id: {track_id: (x, y)}} of the tracks the app published, x/y as written (3 dp)."""
    frames = {}
    with open(path, newline="") as f:
        rows = (line for line in f if not line.startswith("#"))
        for row in csv.DictReader(rows):
            frame = int(row["frame_id"])
            frames.setdefault(frame, {})[int(row["track_id"])] = (row["coordinate_world_x"],
                                                                    row["coordinate_world_y"])
    return frames


def churn(trajectory, subscribers):
    """For each subscriber file: states received, and whether the first states it received are
    each live vehicle's newest state: the first measurement time's tracks must be every track the
    app published in that frame (found by track id and position), one state each."""
    frames = read_trajectory(trajectory)
    by_key = {}
    for frame, tracks in frames.items():
        for track, xy in tracks.items():
            by_key.setdefault((track, xy), set()).add(frame)
    ok = 0
    straddled = 0
    failures = []
    received = []
    first_sizes = []
    for path in subscribers:
        groups = {}
        order = []
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                if row.get("event") != "state":
                    continue
                t = int(row["measurement_time_ns"])
                if t not in groups:
                    groups[t] = []
                    order.append(t)
                xy = (f"{float(row['east_m']):.3f}", f"{float(row['north_m']):.3f}")
                groups[t].append((int(row["track_id"]), xy))
        states = sum(len(g) for g in groups.values())
        received.append(states)
        name = os.path.basename(path)
        if not order:
            failures.append(f"{name}: no state received")
            continue

        def frame_of(group):
            votes = {}
            for key in group:
                for frame in by_key.get(key, ()):
                    votes[frame] = votes.get(frame, 0) + 1
            return max(votes, key=votes.get) if votes else None

        first = groups[order[0]]
        frame = frame_of(first)
        if frame is None:
            failures.append(f"{name}: first states match no frame of the trajectory file")
            continue
        expected = set(frames[frame])
        got = [track for track, _ in first]
        first_sizes.append(len(got))
        if len(got) != len(set(got)):
            failures.append(f"{name}: a track twice in the first states (frame {frame})")
        elif set(got) == expected:
            ok += 1
        elif len(order) > 1 and frame_of(groups[order[1]]) == frame + 1 and \
                expected <= set(got) | {track for track, _ in groups[order[1]]}:
            # Matched while the app was writing frame F+1: part of the tracks came as F+1 already.
            straddled += 1
        else:
            failures.append(f"{name}: first states (frame {frame}) hold tracks {sorted(got)}, "
                            f"the app published {sorted(expected)}")
    print(f"subscribers={len(subscribers)}")
    print(f"newest_ok={ok}")
    print(f"straddled={straddled}")
    print(f"states_min={min(received) if received else 0}")
    print(f"states_total={sum(received)}")
    print(f"first_tracks_median={statistics.median(first_sizes) if first_sizes else 0}")
    for failure in failures:
        print(f"churn: {failure}", file=sys.stderr)
    return 1 if failures else 0


def telemetry(sequence, detections, max_age_s, lookahead_s):
    """Expected pose status per frame (the pose buffer's rule: nearest sample among those pushed
    by frame time + lookahead further than max_age -> stale; before the first -> no pose) against
    the lift status of the frame's detections."""
    max_age = int(round(float(max_age_s) * 1e9))
    lookahead = int(round(float(lookahead_s) * 1e9))
    with open(os.path.join(sequence, "telemetry.csv"), newline="") as f:
        samples = [int(r["timestamp_ns"]) for r in csv.DictReader(f)]
    with open(os.path.join(sequence, "frames.csv"), newline="") as f:
        frames = [(int(r["frame_id"]), int(r["timestamp_ns"])) for r in csv.DictReader(f)]
    expected = {}
    for frame, t in frames:
        seen = [s for s in samples if s <= t + lookahead]
        if not seen:
            expected[frame] = "no_pose"
            continue
        age = min(abs(t - s) for s in seen)
        expected[frame] = "stale_pose" if age > max_age else "ok"
    got = {}
    with open(detections, newline="") as f:
        rows = (line for line in f if not line.startswith("#"))
        for row in csv.DictReader(rows):
            got.setdefault(int(row["frame_id"]), []).append((row["lift_status"], row["east_m"]))
    failures = []
    image_only = 0
    for frame, statuses in got.items():
        want = expected.get(frame)
        for status, east in statuses:
            if want == "ok" and status != "ok":
                failures.append(f"frame {frame}: lift status {status}, the pose should be ok")
            if want in ("stale_pose", "no_pose"):
                if status != want:
                    failures.append(f"frame {frame}: lift status {status}, expected {want}")
                elif east not in ("", "nan"):
                    failures.append(f"frame {frame}: image-only detection with a position {east}")
                else:
                    image_only += 1
    stale = [f for f, s in expected.items() if s == "stale_pose"]
    print(f"expected_stale={len(stale)}")
    print(f"expected_no_pose={sum(1 for s in expected.values() if s == 'no_pose')}")
    print(f"stale_frames={','.join(str(f) for f in stale)}")
    print(f"image_only={image_only}")
    for failure in failures[:10]:
        print(f"telemetry: {failure}", file=sys.stderr)
    return 1 if failures else 0


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    command, args = argv[1], argv[2:]
    if command == "slow_reader" and len(args) == 3:
        return slow_reader(*args)
    if command == "write_stalls" and len(args) == 2:
        return write_stalls(*args)
    if command == "watchdog_gaps" and len(args) >= 4 and args[2] == "--":
        return watchdog_gaps(args[0], args[1], args[3:])
    if command == "churn" and len(args) >= 2:
        return churn(args[0], args[1:])
    if command == "telemetry" and len(args) == 4:
        return telemetry(*args)
    print(f"faults_analysis.py: bad arguments: {' '.join(argv[1:])}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
