"""The dashboard in a real browser (headless Chromium driven by Playwright): it loads, its plot
shows one point per row of the run's history.csv, its figures move as the run evaluates, and it
reads the same from the run's store once the run is over. Screenshots go to $DASHBOARD_SHOTS
(default target/dashboard/).

Needs the workspace's debug binaries (AMORPH_BIN_DIR, default target/debug) and Chromium
(CHROMIUM, default the `chromium` on PATH); deploy/check-dashboard.sh provides both."""

import csv
import os
import re
import shutil
import subprocess
import threading
import time
from pathlib import Path

import pytest
from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("AMORPH_BIN_DIR", ROOT / "target" / "debug"))
SHOTS = Path(os.environ.get("DASHBOARD_SHOTS", ROOT / "target" / "dashboard"))
CONFIG = ROOT / "tests" / "fixtures" / "configs" / "small_beam.toml"


class Coordinator:
    """A coordinator process; `url` is its dashboard's address, read from what it prints."""

    def __init__(self, args, cwd):
        self.process = subprocess.Popen(
            [str(BIN / "coordinator"), *args], cwd=cwd, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True)
        self.lines = []
        self.url = None
        heard = threading.Event()

        def listen():
            for line in self.process.stderr:
                self.lines.append(line)
                found = re.search(r"dashboard(?: of .*)? on (http://\S+/)", line)
                if found and self.url is None:
                    self.url = found.group(1)
                    heard.set()
            heard.set()

        threading.Thread(target=listen, daemon=True).start()
        assert heard.wait(120), "the coordinator never said where its dashboard is"
        assert self.url, "coordinator exited: " + "".join(self.lines)

    def stop(self):
        if self.process.poll() is None:
            self.process.terminate()
        self.process.wait(60)


def history_points(page):
    """The vertices the history plot draws, from its polylines."""
    return page.eval_on_selector_all(
        "#history-plot polyline",
        "ls => ls.reduce((n, l) => n + l.getAttribute('points').trim().split(/\\s+/).length, 0)")


def shown_evaluations(page):
    return int(page.get_attribute("#progress-text", "data-evaluations") or 0)


def history_rows(run_dir):
    with open(run_dir / "history.csv") as f:
        rows = list(csv.DictReader(f))
    # The plot draws the task's figure; a row whose island had no evaluated design has none.
    return [r for r in rows if r["best_rms_percent"] != ""]


@pytest.fixture(scope="module")
def browser():
    chromium = os.environ.get("CHROMIUM") or shutil.which("chromium")
    assert chromium, "no Chromium: set CHROMIUM or install Debian's chromium"
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        yield b
        b.close()


def test_live_then_from_the_store(browser, tmp_path):
    SHOTS.mkdir(parents=True, exist_ok=True)
    results = tmp_path / "results"
    run = Coordinator(
        ["--config", str(CONFIG), "--set", f'results_dir="{results}"',
         "--set", "budget.evaluations=1500", "--set", "cluster.local_workers=1",
         "--dashboard", "127.0.0.1:0"], cwd=tmp_path)
    page = browser.new_page(viewport={"width": 1280, "height": 1100})
    try:
        started = time.monotonic()
        page.goto(run.url)
        # The static page's title, then the run's name once the first status has arrived.
        page.wait_for_function("document.title === 'small · Amorph'", timeout=30_000)
        page.wait_for_function(
            "document.querySelector('#run-mode').textContent === 'live'", timeout=30_000)
        # The first epoch's points, then more: the page follows the run without a reload.
        page.wait_for_function(
            "Number(document.querySelector('#history-plot').dataset.points || 0) > 0",
            timeout=60_000)
        first_points, first_evaluations = history_points(page), shown_evaluations(page)
        page.wait_for_function(
            f"Number(document.querySelector('#progress-text').dataset.evaluations) > {first_evaluations}"
            f" && Number(document.querySelector('#history-plot').dataset.points) > {first_points}",
            timeout=60_000)
        assert history_points(page) > first_points
        assert page.text_content("#best-headline").startswith("RMS")
        workers = page.text_content("#workers tbody")
        assert "local-0" in workers, workers
        page.screenshot(path=str(SHOTS / "dashboard-live.png"), full_page=True)
        print(f"live page followed the run for {time.monotonic() - started:.1f} s")
    finally:
        run.process.wait(600)
        page.close()
    assert run.process.returncode == 0, "".join(run.lines)

    run_dir = results / "small"
    served = Coordinator(
        ["dashboard", str(run_dir / "run.sqlite"), "--listen", "127.0.0.1:0"], cwd=tmp_path)
    page = browser.new_page(viewport={"width": 1280, "height": 1100})
    try:
        loading = time.monotonic()
        page.goto(served.url)
        page.wait_for_function(
            "Number(document.querySelector('#history-plot').dataset.points || 0) > 0",
            timeout=30_000)
        print(f"stored run's page drawn {time.monotonic() - loading:.2f} s after navigation")
        assert page.text_content("#run-mode") == "from the store"
        assert history_points(page) == len(history_rows(run_dir))
        # The best design's picture is drawn and loaded.
        page.wait_for_function(
            "document.querySelector('#best-picture').complete"
            " && document.querySelector('#best-picture').naturalWidth > 0", timeout=30_000)
        # A beam's profile against its target: two lines of equal length.
        lines = page.eval_on_selector_all(
            "#detail-plot polyline", "ls => ls.map(l => l.getAttribute('points').trim().split(/\\s+/).length)")
        assert len(lines) == 2 and lines[0] == lines[1] > 2, lines
        page.click("#x-wall")
        assert history_points(page) == len(history_rows(run_dir))
        page.click("#x-evaluations")
        page.screenshot(path=str(SHOTS / "dashboard.png"), full_page=True)
    finally:
        page.close()
        served.stop()
