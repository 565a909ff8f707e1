#!/usr/bin/env python3
"""A connection flood, run by hand against a running coordinator (docs/reference/protocol.md).

Floods the coordinator from one source address the way a hostile peer could: idle TCP
connections that never send a byte, and HTTP/2 requests that are opened and never finished; while
the flood lasts it asks the health service once a second from another address, and reads the
coordinator's memory and the run store's evaluation count, so one can see that the coordinator
keeps answering and the run keeps going.

    deploy/flood.py --port P --pid PID --store results/<name>/run.sqlite [--idle 1100]
                    [--streams 4000] [--seconds 40] [--source 127.0.0.5] [--token T]

Needs the `h2` package (pip install h2) and the coordinator binary for the health check
(COORDINATOR, default target/release/coordinator). Prints one line per second and a summary.
"""

import argparse
import os
import socket
import sqlite3
import subprocess
import time

import h2.config
import h2.connection


def connect(source, port):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind((source, 0))
    s.settimeout(5)
    s.connect(("127.0.0.1", port))
    s.setblocking(False)
    return s


def closed_by_peer(s):
    try:
        return s.recv(65536) == b""
    except BlockingIOError:
        return False
    except OSError:
        return True


def open_streams(source, port, count, token, per_connection=100):
    """HTTP/2 connections each opening `per_connection` gRPC calls whose request never ends."""
    held = []
    path = "/amorph.v1.EvaluationCoordinator/Register"
    while count > 0:
        try:
            s = connect(source, port)
        except OSError:
            held.append(None)
            count -= per_connection
            continue
        c = h2.connection.H2Connection(h2.config.H2Configuration(client_side=True))
        c.initiate_connection()
        n = min(per_connection, count)
        for i in range(n):
            c.send_headers(
                2 * i + 1,
                [
                    (":method", "POST"),
                    (":scheme", "http"),
                    (":path", path),
                    (":authority", f"127.0.0.1:{port}"),
                    ("content-type", "application/grpc"),
                    ("te", "trailers"),
                ]
                + ([("authorization", f"Bearer {token}")] if token else []),
            )
        try:
            s.sendall(c.data_to_send())
        except OSError:
            pass
        held.append((s, c))
        count -= n
    return held


def answered(streams):
    """What the coordinator has done to the unfinished calls since the last look: streams it
    refused or reset, streams it answered (a status, e.g. DEADLINE_EXCEEDED once the call's time is
    up), and connections found closed (these count again at every look)."""
    import h2.events as ev

    reset = ended = closed = 0
    for held in streams:
        if held is None:
            closed += 1
            continue
        s, c = held
        try:
            while data := s.recv(65536):
                for e in c.receive_data(data):
                    reset += isinstance(e, ev.StreamReset)
                    ended += isinstance(e, ev.StreamEnded)
                    closed += isinstance(e, ev.ConnectionTerminated)
            else:
                closed += 1
        except BlockingIOError:
            pass
        except Exception:
            closed += 1
    return reset, ended, closed


def rss_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        return None


def evaluations(store):
    try:
        c = sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=1)
        return c.execute("select count(*) from evaluation").fetchone()[0]
    except sqlite3.Error:
        return None


def health(port):
    binary = os.environ.get("COORDINATOR", "target/release/coordinator")
    start = time.monotonic()
    try:
        ok = subprocess.run(
            [binary, "--health-check", f"http://127.0.0.1:{port}"],
            capture_output=True,
            timeout=10,
        ).returncode == 0
    except subprocess.TimeoutExpired:
        ok = False
    return ok, time.monotonic() - start


def main():
    a = argparse.ArgumentParser()
    a.add_argument("--port", type=int, required=True)
    a.add_argument("--pid", type=int, required=True)
    a.add_argument("--store", required=True)
    a.add_argument("--idle", type=int, default=1100)
    a.add_argument("--streams", type=int, default=4000)
    a.add_argument("--seconds", type=float, default=40)
    a.add_argument("--source", default="127.0.0.5")
    a.add_argument("--token", default=os.environ.get("AMORPH_TOKEN"), help="the run's token, if it has one")
    args = a.parse_args()

    # The run's pace without the flood, over the same kind of window, to compare with.
    e0 = evaluations(args.store)
    time.sleep(10)
    e1 = evaluations(args.store)
    print(f"before: rss {rss_kib(args.pid)} KiB, {e0} -> {e1} evaluations in 10 s")
    idle, refused = [], 0
    for _ in range(args.idle):
        try:
            idle.append(connect(args.source, args.port))
        except OSError:
            refused += 1
    streams = open_streams(args.source, args.port, args.streams, args.token)
    print(f"flood: {len(idle)} idle connections opened ({refused} refused at connect), "
          f"{args.streams} unfinished calls on {len(streams)} connections")
    start = time.monotonic()
    worst, failures, checks, peak = 0.0, 0, 0, 0
    first_evals = evaluations(args.store)
    while time.monotonic() - start < args.seconds:
        ok, took = health(args.port)
        checks += 1
        failures += not ok
        worst = max(worst, took)
        rss = rss_kib(args.pid) or 0
        peak = max(peak, rss)
        alive = sum(not closed_by_peer(s) for s in idle)
        reset, ended, closed = answered(streams)
        print(f"t={time.monotonic() - start:5.1f}s health {'ok' if ok else 'FAILED'} in {took:.3f}s, "
              f"rss {rss} KiB, idle connections still open {alive}, since last line calls reset {reset} / "
              f"answered {ended}, connections closed {closed}, "
              f"evaluations {evaluations(args.store)}", flush=True)
        time.sleep(max(0.0, 1.0 - took))
    alive = sum(not closed_by_peer(s) for s in idle)
    print(f"summary: {checks} health checks, {failures} failed, slowest {worst:.3f}s; "
          f"peak rss {peak} KiB; idle connections the coordinator kept {alive} of {len(idle)}; "
          f"evaluations {first_evals} -> {evaluations(args.store)} during the flood")
    for s in idle + [held[0] for held in streams if held]:
        s.close()


if __name__ == "__main__":
    main()
