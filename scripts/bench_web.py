#!/usr/bin/python3
"""What the web view costs a user: for each scene given (default the atlas
indentation and the atlas bolt), a pba-server with --http solves it, then
headless Chromium (Debian's, through Selenium) signs in and opens the job's
page; printed per scene as a Markdown row: elements, regions drawn, the
bytes of surfaces.glb and of everything the page fetched from the click on,
and the time from the click to the first frame of the 3D view (median of
`runs` openings, each in a fresh page).

Usage: scripts/bench_web.py [runs [SCENE.yaml ...]]   (default 5)
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
                          os.path.join(root, "examples", "atlas_bolt.yaml")]

folder = tempfile.mkdtemp(prefix="pba-bench-web-")
os.chmod(folder, 0o755)
server = web.Server(folder)
print("| scene | elements | regions drawn | surfaces.glb | fetched after the click | "
      "click to first frame (median of %d) |" % runs)
print("|---|---|---|---|---|---|")
try:
    for scene in scenes:
        out = server.pba("job", "submit", scene, "--wait").stdout
        job = re.search(r"Submitted job (\S+)", out).group(1)
        status = json.loads(server.pba("--json", "job", "status", job).stdout)
        elements = status["summary"]["modelled"]["elements"]
        glb = next(int(f["size_bytes"]) for f in status["result_files"]
                   if f["name"] == "surfaces.glb")
        times, fetched, regions = [], [], 0
        for _ in range(runs):
            browser = web.chromium()
            try:
                browser.get(server.http + "/")
                WebDriverWait(browser, 20).until(lambda b: b.find_element(By.ID, "token"))
                WebDriverWait(browser, 20).until(
                    lambda b: b.find_element(By.ID, "sign-in").is_displayed())
                browser.find_element(By.ID, "token").send_keys(server.admin)
                browser.find_element(By.CSS_SELECTOR, "#sign-in-form button").click()
                link = WebDriverWait(browser, 30).until(lambda b: b.find_element(
                    By.XPATH, "//tr[@data-job='%s']//a[text()='view']" % job))
                browser.execute_script("performance.clearResourceTimings();"
                                       "window.pbaClick = performance.now();")
                link.click()
                drawn = WebDriverWait(browser, 120, poll_frequency=0.05).until(
                    lambda b: b.execute_script("return window.pbaView || null;"))
                # The first frame was drawn when the view recorded it.
                elapsed = drawn["drawn_at_ms"] - browser.execute_script("return window.pbaClick;")
                size = browser.execute_script(
                    "return performance.getEntriesByType('resource')"
                    ".reduce((n, e) => n + (e.transferSize || 0), 0);")
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
