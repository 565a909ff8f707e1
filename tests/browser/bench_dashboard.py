"""Benchmarks of the dashboard (results in docs/explanation/results.md#the-dashboard):

  python tests/browser/bench_dashboard.py load STORE        # page load on a finished run's store
  python tests/browser/bench_dashboard.py overhead [ROUNDS [WATCHERS]]  # what watching costs

`load`: a fresh `coordinator dashboard STORE` each time (so the server reads the whole store),
the time from navigation until the history plot and the best design's picture are drawn, five
times, and the size of /api/status.

`overhead`: the quickstart at 6x20x6 alone with a fixed budget (6,000 evaluations, no early
stop: about 40 s on two cores, so the page's fixed cost per second weighs more than in a longer
run at a finer resolution), in ROUNDS rounds (default 3) of three runs: plain, watched over HTTP
(--dashboard, polled as the page polls it, from a thread of this script: the coordinator's
cost), and watched by the page in headless Chromium on the same machine (the coordinator's cost
plus the browser's, on the run's own two cores). Prints each run's wall time as the coordinator
reports it, the ratio to the round's plain run, their medians and the load average.

Needs release binaries (AMORPH_BIN_DIR, default target/release) and Chromium (CHROMIUM)."""

import json
import os
import re
import statistics
import subprocess
import threading
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from playwright.sync_api import sync_playwright

sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("AMORPH_BIN_DIR", str(Path(__file__).resolve().parents[2] / "target" / "release"))
from test_dashboard import Coordinator  # noqa: E402

DRAWN = ("Number(document.querySelector('#history-plot').dataset.points || 0) > 0"
         " && document.querySelector('#best-picture').complete"
         " && document.querySelector('#best-picture').naturalWidth > 0")


def launch(p):
    return p.chromium.launch(executable_path=os.environ.get("CHROMIUM", "/usr/bin/chromium"),
                             args=["--no-sandbox"])


def load(store):
    with sync_playwright() as p:
        browser = launch(p)
        times = []
        for _ in range(5):
            served = Coordinator(["dashboard", store, "--listen", "127.0.0.1:0"], cwd=".")
            page = browser.new_page(viewport={"width": 1280, "height": 1100})
            start = time.perf_counter()
            page.goto(served.url)
            page.wait_for_function(DRAWN, timeout=60_000)
            times.append(time.perf_counter() - start)
            points = page.get_attribute("#history-plot", "data-points")
            size = len(urllib.request.urlopen(served.url + "api/status").read())
            page.close()
            served.stop()
        browser.close()
    print(f"store {store}: {points} history points, /api/status {size / 1e3:.0f} kB")
    print("load times (s):", " ".join(f"{t:.3f}" for t in times),
          f"median {statistics.median(times):.3f}")


def poll(url, stop):
    """What the page asks of the coordinator, without a browser: the status every 2 s, and the
    best design's picture whenever the best changes."""
    drawn = None
    while not stop.wait(2.0):
        try:
            status = json.loads(urllib.request.urlopen(url + "api/status").read())
            best = status["best"] and status["best"]["task_id"]
            if best is not None and best != drawn:
                urllib.request.urlopen(f"{url}api/design.png?task={best}").read()
                drawn = best
        except OSError:
            return


def run_once(watcher, results, browser):
    """The run's own wall time (as it prints it) with `watcher`: None, "http" or "chromium"."""
    args = ["--set", f'results_dir="{results}"', "--set", "budget.evaluations=6000",
            "--set", "budget.target_rms_percent=0.0", "--set", "resolution.levels=[[6, 20, 6]]",
            "--set", "resolution.latest_switch=[]", "--fresh"]
    if watcher is None:
        out = subprocess.run([str(Path(os.environ["AMORPH_BIN_DIR"]) / "coordinator"), *args],
                             cwd=results, check=True, capture_output=True, text=True).stdout
    else:
        run = Coordinator([*args, "--dashboard", "127.0.0.1:0"], cwd=results)
        stop = threading.Event()
        if watcher == "http":
            poller = threading.Thread(target=poll, args=(run.url, stop))
            poller.start()
        else:
            page = browser.new_page()
            page.goto(run.url)
        out = run.process.stdout.read()
        run.process.wait()
        stop.set()
        if watcher == "http":
            poller.join()
        else:
            page.close()
    return float(re.search(r"evaluations in ([0-9.]+) s", out).group(1))


def overhead(rounds, watchers):
    print("load average before:", os.getloadavg())
    ratios = {w: [] for w in watchers}
    with tempfile.TemporaryDirectory() as results, sync_playwright() as p:
        browser = launch(p)
        for i in range(rounds):
            plain = run_once(None, results, browser)
            line = f"round {i + 1}: plain {plain:.2f} s"
            for watcher in watchers:
                watched = run_once(watcher, results, browser)
                ratios[watcher].append(watched / plain)
                line += f", {watcher} {watched:.2f} s ({watched / plain:.4f})"
            print(line, flush=True)
        browser.close()
    for watcher, r in ratios.items():
        print(f"median ratio, watched by {watcher}: {statistics.median(r):.4f}")
    print("load average after:", os.getloadavg())


if __name__ == "__main__":
    if sys.argv[1] == "load":
        load(sys.argv[2])
    else:
        overhead(int(sys.argv[2]) if len(sys.argv) > 2 else 3,
                 sys.argv[3].split(",") if len(sys.argv) > 3 else ["http", "chromium"])
