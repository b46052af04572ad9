#!/usr/bin/python3
"""What the web view costs a user. First the built-in atlas as a project:
its 44 structures imported, then headless Chromium (Debian's, through
Selenium) signs in and opens the project, whose 3D view the server meshes
on the first opening and takes from its cache after; printed as a Markdown
row: structures drawn, the bytes of the surfaces and of everything fetched
from the click on, and the time from the click to the first frame, on the
first opening and the median of the `runs` after it. Then, for each scene
given (default the atlas indentation and the atlas bolt), the server
solves it and the browser opens the job's page; printed per scene:
elements, regions drawn, the bytes of surfaces.glb and of everything the
page fetched from the click on, and the time from the click to the first
frame of the 3D view (median of `runs` openings, each in a fresh page).

Usage: scripts/bench_web.py [runs [SCENE.yaml ...]]   (default 5; the scenes: the atlas
  indentation and bolt examples and tests/bench/scenes/atlas_fine_push.yaml, 400,000
  tetrahedra)
  PBA_BENCH_ATLAS=0: not the built-in atlas's project
  PBA_BUILD_DIR: the build (default build/release)
  PBA_SHOTS: a folder for a screenshot of each scene's page (web_view_<scene>.png)
"""
import json
import os
import re
import shutil
import statistics
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("PBA_BIN_DIR", os.path.join(os.environ.get(
    "PBA_BUILD_DIR", os.path.join(root, "build", "release")), "bin"))
sys.path.insert(0, os.path.join(root, "tests", "browser"))
import web_view_test as web  # noqa: E402  (the tests' server and browser)
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 5
scenes = sys.argv[2:] or [os.path.join(root, "examples", "atlas_indentation.yaml"),
                          os.path.join(root, "examples", "atlas_bolt.yaml"),
                          os.path.join(root, "tests", "bench", "scenes", "atlas_fine_push.yaml")]

folder = tempfile.mkdtemp(prefix="pba-bench-web-")
os.chmod(folder, 0o755)
server = web.Server(folder)


def signed_in_browser():
    browser = web.chromium()
    browser.get(server.http + "/")
    WebDriverWait(browser, 20).until(lambda b: b.find_element(By.ID, "token"))
    WebDriverWait(browser, 20).until(lambda b: b.find_element(By.ID, "sign-in").is_displayed())
    browser.find_element(By.ID, "token").send_keys(server.admin)
    browser.find_element(By.CSS_SELECTOR, "#sign-in-form button").click()
    return browser


def fetched_bytes(browser):
    return browser.execute_script("return performance.getEntriesByType('resource')"
                                  ".reduce((n, e) => n + (e.transferSize || 0), 0);")


def open_atlas(project):
    """Opens `project`'s page in a fresh browser: seconds from the click to
    the 3D view's first frame, bytes fetched, what was drawn."""
    browser = signed_in_browser()
    try:
        link = WebDriverWait(browser, 30).until(lambda b: b.find_element(By.LINK_TEXT, project))
        browser.execute_script("performance.clearResourceTimings();"
                               "window.pbaClick = performance.now();")
        link.click()
        drawn = WebDriverWait(browser, 300, poll_frequency=0.05).until(lambda b: b.execute_script(
            "const a = window.pbaAtlas; return a && (a.ready || a.error) ? a : null;"))
        if not drawn.get("ready"):
            raise RuntimeError("the atlas view failed: %s" % drawn.get("error"))
        elapsed = drawn["drawn_at_ms"] - browser.execute_script("return window.pbaClick;")
        if os.environ.get("PBA_SHOTS"):
            browser.save_screenshot(os.path.join(os.environ["PBA_SHOTS"], "web_view_atlas.png"))
        return elapsed / 1000, fetched_bytes(browser), drawn
    finally:
        browser.quit()


try:
    if os.environ.get("PBA_BENCH_ATLAS", "1") != "0":
        server.pba("project", "create", "brain")
        server.pba("atlas", "import", "-p", "brain", "--synthetic")
        cold, cold_bytes, drawn = open_atlas("brain")
        warm = [open_atlas("brain") for _ in range(runs)]
        print("| atlas | structures drawn | surfaces | fetched after the click | "
              "click to first frame, first opening (meshed) | after (cached; median of %d) |" % runs)
        print("|---|---|---|---|---|---|")
        print("| built-in, as a project | %d | %.2f MB | %.2f MB | %.2f s | %.2f s |" % (
            len(drawn["regions"]), drawn["bytes"] / 1e6, cold_bytes / 1e6, cold,
            statistics.median(t for t, _, _ in warm)))
        print()
        sys.stdout.flush()

    print("| scene | elements | regions drawn | surfaces.glb | fetched after the click | "
          "click to first frame (median of %d) |" % runs)
    print("|---|---|---|---|---|---|")
    for scene in scenes:
        out = server.pba("job", "submit", scene, "--wait").stdout
        job = re.search(r"Submitted job (\S+)", out).group(1)
        status = json.loads(server.pba("--json", "job", "status", job).stdout)
        elements = status["summary"]["modelled"]["elements"]
        glb = next(int(f["size_bytes"]) for f in status["result_files"]
                   if f["name"] == "surfaces.glb")
        times, fetched, regions = [], [], 0
        for _ in range(runs):
            browser = signed_in_browser()
            try:
                link = WebDriverWait(browser, 30).until(lambda b: b.find_element(
                    By.XPATH, "//tr[@data-job='%s']//a[text()='view']" % job))
                browser.execute_script("performance.clearResourceTimings();"
                                       "window.pbaClick = performance.now();")
                link.click()
                drawn = WebDriverWait(browser, 120, poll_frequency=0.05).until(
                    lambda b: b.execute_script("return window.pbaView || null;"))
                # The first frame was drawn when the view recorded it.
                elapsed = drawn["drawn_at_ms"] - browser.execute_script("return window.pbaClick;")
                size = fetched_bytes(browser)
                times.append(elapsed / 1000)
                fetched.append(size)
                regions = len(drawn["regions"])
                if os.environ.get("PBA_SHOTS"):
                    name = os.path.splitext(os.path.basename(scene))[0]
                    browser.save_screenshot(
                        os.path.join(os.environ["PBA_SHOTS"], "web_view_%s.png" % name))
            finally:
                browser.quit()
        print("| %s | %s | %d | %.2f MB | %.2f MB | %.2f s |" % (
            os.path.basename(scene), f"{int(elements):,}", regions, glb / 1e6,
            statistics.median(fetched) / 1e6, statistics.median(times)))
        sys.stdout.flush()
finally:
    server.stop()
    shutil.rmtree(folder, ignore_errors=True)
