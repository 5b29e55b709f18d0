#!/usr/bin/python3
"""Plays systemd's part for a Type=notify service with a watchdog, where systemd cannot run
(a chroot, a container): listens on a notify socket, starts the command, and checks the
service protocol of sd_notify(3):

  1. READY=1 arrives within --ready-timeout seconds of the start;
  2. then at least --watchdogs WATCHDOG=1 messages, no two further apart than WATCHDOG_USEC
     (systemd would kill the service at that point);
  3. on SIGTERM the process sends STOPPING=1 and exits with status 0 within --stop-timeout.

Like NotifyAccess=main, only datagrams from the started process itself count (the sender's
pid comes from SCM_CREDENTIALS). The command must exec the service so that its pid is the
one started here, and must itself put NOTIFY_SOCKET / WATCHDOG_USEC / WATCHDOG_PID into the
service's environment (test_package.sh does, through env and sh -c inside the chroot).

Usage: sd_notify_harness.py --socket HOST_PATH --watchdog-usec N [options] -- COMMAND...
Exit status 0 when every check passes, 1 when one fails, 2 on a usage error.
"""

import argparse
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import time


def parse_args():
    p = argparse.ArgumentParser(
        description="Emulate systemd's notify socket and watchdog for one service start.")
    p.add_argument("--socket", required=True,
                   help="path of the datagram socket to create (as seen on this side)")
    p.add_argument("--watchdog-usec", type=int, required=True,
                   help="the WATCHDOG_USEC given to the service (gap limit between WATCHDOG=1)")
    p.add_argument("--watchdogs", type=int, default=2,
                   help="WATCHDOG=1 messages to wait for after READY=1 (default 2)")
    p.add_argument("--ready-timeout", type=float, default=60.0,
                   help="seconds from start to READY=1 (default 60, the unit's TimeoutStartSec)")
    p.add_argument("--stop-timeout", type=float, default=10.0,
                   help="seconds from SIGTERM to exit (default 10, the unit's TimeoutStopSec)")
    p.add_argument("--log", help="file for the service's stdout and stderr (default: inherit)")
    p.add_argument("command", nargs=argparse.REMAINDER, help="-- then the command to start")
    a = p.parse_args()
    if a.command and a.command[0] == "--":
        a.command = a.command[1:]
    if not a.command:
        p.error("no command given (put it after --)")
    if a.watchdog_usec <= 0 or a.watchdogs < 0:
        p.error("--watchdog-usec must be > 0 and --watchdogs >= 0")
    return a


def main():
    a = parse_args()
    t0 = time.monotonic()

    def say(text):
        print(f"harness: [{time.monotonic() - t0:7.3f} s] {text}", flush=True)

    if os.path.exists(a.socket):
        os.unlink(a.socket)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(a.socket)
    os.chmod(a.socket, 0o777)  # the service runs as an unprivileged user
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_PASSCRED, 1)

    out = open(a.log, "wb") if a.log else None
    say("starting: " + " ".join(a.command))
    proc = subprocess.Popen(a.command, stdout=out, stderr=subprocess.STDOUT if out else None,
                            start_new_session=True)
    say(f"pid {proc.pid}")

    failures = []
    ready_at = None
    watchdog_times = []
    stopping_at = None
    status_text = None
    ignored = 0
    term_sent_at = None
    exit_code = None
    limit_s = a.watchdog_usec / 1e6
    creds_size = struct.calcsize("3i")

    def receive(timeout):
        nonlocal ready_at, stopping_at, status_text, ignored
        r, _, _ = select.select([sock], [], [], max(0.0, timeout))
        if not r:
            return
        data, anc, _, _ = sock.recvmsg(4096, socket.CMSG_SPACE(creds_size))
        now = time.monotonic()
        pid = None
        for level, kind, payload in anc:
            if level == socket.SOL_SOCKET and kind == socket.SCM_CREDENTIALS:
                pid, _, _ = struct.unpack("3i", payload[:creds_size])
        if pid != proc.pid:
            ignored += 1
            say(f"ignored a datagram from pid {pid} (NotifyAccess=main)")
            return
        for line in data.decode("utf-8", "replace").split("\n"):
            if not line:
                continue
            if line == "READY=1" and ready_at is None:
                ready_at = now
                say("READY=1")
            elif line == "WATCHDOG=1":
                watchdog_times.append(now)
                if ready_at is not None:
                    say(f"WATCHDOG=1 (#{len(watchdog_times)})")
            elif line == "STOPPING=1":
                stopping_at = now
                say("STOPPING=1")
            elif line.startswith("STATUS="):
                if line != status_text:
                    say(line)
                status_text = line
            else:
                say(f"other message: {line}")

    try:
        # 1. READY=1
        while ready_at is None and proc.poll() is None and time.monotonic() - t0 < a.ready_timeout:
            receive(0.1)
        if ready_at is None:
            failures.append("no READY=1 " + (f"(exited with {proc.returncode} first)"
                            if proc.poll() is not None else f"within {a.ready_timeout} s"))
        else:
            # 2. watchdog pings after READY=1
            deadline = ready_at + limit_s * (a.watchdogs + 1) + 1.0
            while proc.poll() is None and time.monotonic() < deadline:
                after_ready = [t for t in watchdog_times if t >= ready_at]
                if len(after_ready) >= a.watchdogs:
                    break
                receive(0.05)
            after_ready = [t for t in watchdog_times if t >= ready_at]
            if len(after_ready) < a.watchdogs:
                failures.append(f"{len(after_ready)} WATCHDOG=1 after READY=1, expected "
                                f">= {a.watchdogs}" + (f" (exited with {proc.returncode})"
                                                       if proc.poll() is not None else ""))
            stamps = [ready_at] + after_ready
            gaps = [b - s for s, b in zip(stamps, stamps[1:])]
            if gaps:
                say("watchdog gaps: " + ", ".join(f"{g * 1000:.0f} ms" for g in gaps) +
                    f" (limit {limit_s * 1000:.0f} ms, expected about {limit_s * 500:.0f} ms)")
            if any(g > limit_s for g in gaps):
                failures.append(f"a watchdog gap of {max(gaps):.3f} s exceeds WATCHDOG_USEC "
                                f"({limit_s:.3f} s): systemd would have killed the service")
        # 3. SIGTERM -> STOPPING=1, exit 0
        if proc.poll() is None:
            term_sent_at = time.monotonic()
            say("sending SIGTERM")
            proc.send_signal(signal.SIGTERM)
            while proc.poll() is None and time.monotonic() - term_sent_at < a.stop_timeout:
                receive(0.05)
            if proc.poll() is None:
                failures.append(f"still running {a.stop_timeout} s after SIGTERM (killed)")
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            else:
                receive(0.2)  # a STOPPING=1 sent just before exit may still be queued
                say(f"exited with status {proc.returncode} "
                    f"{(time.monotonic() - term_sent_at) * 1000:.0f} ms after SIGTERM")
        exit_code = proc.returncode
        if term_sent_at is not None:
            if exit_code != 0:
                failures.append(f"exit status {exit_code} after SIGTERM, expected 0")
            if stopping_at is None:
                failures.append("no STOPPING=1 after SIGTERM")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        sock.close()
        os.unlink(a.socket)
        if out:
            out.close()

    if ready_at is not None:
        say(f"summary: READY after {(ready_at - t0):.2f} s, "
            f"{len([t for t in watchdog_times if t >= ready_at])} WATCHDOG=1, "
            f"STOPPING={'yes' if stopping_at else 'no'}, exit {exit_code}")
    for f in failures:
        print(f"harness: FAIL: {f}", flush=True)
    if not failures:
        print("harness: PASS", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
