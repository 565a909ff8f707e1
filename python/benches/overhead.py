"""What a Python call costs over the Rust call it makes, and how evaluate_many scales.

1. `Scene.evaluate` from Python against the same evaluation timed inside Rust
   (`cargo bench -p amorph-python --bench evaluate_call`, which prints seconds per call), on a
   6x20x6 circular-arc beam, alternating the two in rounds so that the machine's load falls on
   both alike.
2. `Scene.evaluate_many` of 64 genomes on 1, 2, ... threads.

Run from the repository's root, with the package installed (pip install ./python):

    python python/benches/overhead.py --rounds 5
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import amorph

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RESOLUTION = "6x20x6"


def genome(scene):
    """The benchmark's design: a spanning random genome, the same every time."""
    rng = np.random.default_rng(1)
    while True:
        g = amorph.unit_genome(scene, rng.uniform(size=30 * 6))
        a = g.to_array()
        a[:, 3] = np.abs(a[:, 3])
        g = amorph.Genome(a)
        if scene.evaluate(g, RESOLUTION).ok:
            return g


def python_seconds(scene, g, calls):
    scene.evaluate(g, RESOLUTION)
    start = time.perf_counter()
    for _ in range(calls):
        scene.evaluate(g, RESOLUTION)
    return (time.perf_counter() - start) / calls


def rust_seconds(path, calls):
    out = subprocess.run(
        ["cargo", "bench", "-q", "-p", "amorph-python", "--bench", "evaluate_call", "--",
         path, RESOLUTION, str(calls)],
        cwd=REPO, check=True, capture_output=True, text=True,
    ).stdout
    return float(out.split()[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=300)
    args = parser.parse_args()
    scene = amorph.Scene.from_file(os.path.join(REPO, "configs", "quickstart.toml"))
    g = genome(scene)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "genome.json")
        g.save(path)
        rust_seconds(path, 10)  # builds the bench once, outside the timing
        print(f"load average {os.getloadavg()[0]:.2f}")
        ratios = []
        for r in range(args.rounds):
            rust = rust_seconds(path, args.calls)
            py = python_seconds(scene, g, args.calls)
            ratios.append(py / rust)
            print(f"round {r + 1}: rust {rust * 1e3:.3f} ms, python {py * 1e3:.3f} ms, ratio {py / rust:.4f}")
        print(f"python / rust: median {np.median(ratios):.4f}, range {min(ratios):.4f} to {max(ratios):.4f}")
    rng = np.random.default_rng(2)
    many = [amorph.unit_genome(scene, rng.uniform(size=30 * 6)) for _ in range(64)]
    base = None
    for threads in range(1, (os.cpu_count() or 1) + 1):
        start = time.perf_counter()
        scene.evaluate_many(many, RESOLUTION, threads=threads)
        seconds = time.perf_counter() - start
        base = base or seconds
        print(f"evaluate_many, 64 genomes, {threads} threads: {seconds:.3f} s, speed-up {base / seconds:.2f}")
    print(f"load average {os.getloadavg()[0]:.2f}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
