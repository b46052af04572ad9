#!/usr/bin/python3
"""The web view in a real browser: Debian's headless Chromium, driven by
Selenium through chromedriver, against a real pba-server on loopback with
the real client making the changes others make.

Each test starts its own server (pba-server --http 127.0.0.1:0) in a
temporary folder; screenshots go to $PBA_ARTIFACT_DIR (default: the
folder the test runs in) as test artifacts.

Run one: web_view_test.py WebViewTest.test_a_job_result_renders
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import h5py

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.common.exceptions import NoSuchElementException, StaleElementReferenceException
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

BIN = os.environ.get("PBA_BIN_DIR", os.path.join(os.path.dirname(__file__), "../../build/release/bin"))
ARTIFACTS = os.environ.get("PBA_ARTIFACT_DIR", os.getcwd())

BLOCK = """name: block
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 5}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {z_mm: -1}}
"""


def contours(half_width_mm):
    return ('{"plates": [{"z_mm": 0, "polygons": [[[0, 0], [%g, 0], [%g, %g], [0, %g]]]}]}'
            % ((half_width_mm,) * 4))


# A viscoelastic cube held for 3 s: history.csv with the top's force.
HOLD = """name: hold
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element: TET4_ANP, element_size_mm: 5}
material:
  neo_hookean: {shear_modulus_pa: 2200, bulk_modulus_pa: 2.2e6}
  viscoelastic: {prony: {g: [0.5], tau_s: [2]}}
boundary_conditions:
  - {set: bottom, symmetry: {}}
  - {set: x_min, symmetry: {}}
  - {set: y_min, symmetry: {}}
  - {set: top, displacement: {z_mm: -1}}
analysis:
  type: QUASI_STATIC
  time:
    end_time_s: 3
    curve: [{time_s: 0, amplitude: 0}, {time_s: 1, amplitude: 1}, {time_s: 3, amplitude: 1}]
outputs: {reaction_sets: [top]}
"""


class Server:
    """A pba-server with the web view, in its own folder."""

    def __init__(self, folder):
        self.folder = folder
        self.data = os.path.join(folder, "data")
        self.log = open(os.path.join(folder, "server.log"), "w")
        self.process = subprocess.Popen(
            [os.path.join(BIN, "pba-server"), "--data", self.data, "--listen", "127.0.0.1:0",
             "--http", "127.0.0.1:0"],
            stdout=subprocess.PIPE, stderr=self.log, text=True)
        deadline = time.time() + 30
        self.address = self.http = None
        while time.time() < deadline and self.address is None:
            line = self.process.stdout.readline()
            match = re.search(r"web view on (http://\S+)/", line)
            if match:
                self.http = match.group(1)
            match = re.search(r"listening on (\S+)", line)
            if match:
                self.address = match.group(1)
        if self.address is None or self.http is None:
            raise RuntimeError("pba-server did not start; see " + self.log.name)
        with open(os.path.join(self.data, "admin.token")) as f:
            self.admin = f.read().strip()

    def pba(self, *args, token=None, check=True):
        env = dict(os.environ, PBA_TOKEN=token or self.admin, HOME=self.folder)
        result = subprocess.run([os.path.join(BIN, "pba"), "--server", self.address, *args],
                                env=env, capture_output=True, text=True, timeout=300)
        if check and result.returncode != 0:
            raise AssertionError("pba %s: %s%s" % (" ".join(args), result.stdout, result.stderr))
        return result

    def create_user(self, name):
        result = subprocess.run([os.path.join(BIN, "pba-server"), "admin", "create-user", name,
                                 "--data", self.data], capture_output=True, text=True, timeout=60)
        return re.search(r"[0-9a-f]{64}", result.stdout + result.stderr).group(0)

    def stop(self):
        self.process.terminate()
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
        self.process.stdout.close()
        self.log.close()


def chromium():
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                 "--window-size=1400,1000", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)


class WebViewTest(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix="pba-browser-")
        os.chmod(self.folder, 0o755)
        self.server = Server(self.folder)
        self.browser = chromium()
        # Scripts reading the canvas back wait for its frame: in software
        # WebGL on a loaded machine (ctest -j2) that takes a while.
        self.browser.set_script_timeout(90)
        # The page redraws its tables at events: an element found may be
        # replaced before it is read, and is then looked for again.
        self.wait = WebDriverWait(self.browser, 20, ignored_exceptions=(
            NoSuchElementException, StaleElementReferenceException))

    def tearDown(self):
        result = self._outcome.result
        if any(test is self for test, _ in result.errors + result.failures):
            for entry in self.browser.get_log("browser"):
                print("console:", entry, file=sys.stderr)
            with open(self.server.log.name) as f:
                print("server log:\n" + f.read()[-4000:], file=sys.stderr)
        self.browser.quit()
        self.server.stop()
        shutil.rmtree(self.folder, ignore_errors=True)

    def screenshot(self, name):
        path = os.path.join(ARTIFACTS, "web_view_" + name + ".png")
        self.browser.save_screenshot(path)
        return path

    def sign_in(self, token):
        self.browser.get(self.server.http + "/")
        field = self.wait.until(lambda b: b.find_element(By.ID, "token"))
        self.wait.until(lambda b: b.find_element(By.ID, "sign-in").is_displayed())
        field.send_keys(token)
        self.browser.find_element(By.CSS_SELECTOR, "#sign-in-form button").click()
        self.wait.until(lambda b: b.find_element(By.ID, "home").is_displayed())

    def structure_row(self, name):
        return self.browser.find_element(By.CSS_SELECTOR, 'tr[data-structure="%s"]' % name)

    def cell_text(self, row_selector, column):
        """The text of a table cell, read at once (None without the row)."""
        return self.browser.execute_script(
            "const r = document.querySelector(arguments[0]);"
            "return r ? r.cells[arguments[1]].textContent : null;", row_selector, column)

    def within(self, seconds, predicate):
        return WebDriverWait(self.browser, seconds, poll_frequency=0.1, ignored_exceptions=(
            NoSuchElementException, StaleElementReferenceException)).until(predicate)

    def open_project(self, name):
        self.wait.until(lambda b: b.find_element(By.LINK_TEXT, name).click() or True)
        self.wait.until(lambda b: b.find_element(By.ID, "project").is_displayed())

    def model_pixels(self, view="#view"):
        """The share of the 3D view's pixels the model covers, and how many
        colours they have; with `red`, the share that is the overlay's red."""
        return self.browser.execute_script("""
            const canvas = document.querySelector(arguments[0] + ' canvas');
            const gl = canvas.getContext('webgl2') || canvas.getContext('webgl');
            const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
            const pixels = new Uint8Array(4 * w * h);
            gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
            let model = 0, red = 0, blue = 0, checksum = 0; const seen = new Set();
            for (let i = 0; i < pixels.length; i += 4) {
              const r = pixels[i], g = pixels[i + 1], b = pixels[i + 2];
              const key = r + ',' + g + ',' + b;
              if (key !== '244,244,244') { ++model; seen.add(key); }
              checksum = (checksum * 31 + r * 65536 + g * 256 + b) % 1000000007;
              if (r > 150 && g < 90 && b < 100) ++red;
              if (b > 140 && r < 150 && b > r + 40) ++blue;
            }
            return {fraction: model / (w * h), distinct: seen.size, red: red / (w * h),
                    blue: blue / (w * h), checksum};""", view)

    def solve(self, yaml):
        """Submits the scene `yaml` with the CLI and waits for it; its job id."""
        scene = os.path.join(self.folder, "scene.yaml")
        with open(scene, "w") as f:
            f.write(yaml)
        submitted = self.server.pba("job", "submit", scene, "--wait").stdout
        return re.search(r"Submitted job (\S+)", submitted).group(1)

    def open_job(self, job):
        # The jobs table is redrawn every 2 s: found and clicked at once.
        self.wait.until(lambda b: b.find_element(
            By.XPATH, "//tr[@data-job='%s']//a[text()='view']" % job).click() or True)

    def atlas_drawn(self, seconds=120):
        """Waits for the project's 3D view; what it drew."""
        return WebDriverWait(self.browser, seconds, poll_frequency=0.2).until(
            lambda b: b.execute_script(
                "const a = window.pbaAtlas; return a && (a.ready || a.error) ? a : null;"))

    def make_project(self):
        self.server.pba("project", "create", "demo")
        path = os.path.join(self.folder, "putamen.json")
        with open(path, "w") as f:
            f.write(contours(5))
        self.server.pba("atlas", "create", "-p", "demo", "Putamen", path,
                        "--colour", "233,189,125")

    def test_no_token_sees_nothing(self):
        self.make_project()
        self.browser.get(self.server.http + "/")
        self.wait.until(lambda b: b.find_element(By.ID, "sign-in").is_displayed())
        self.assertFalse(self.browser.find_element(By.ID, "home").is_displayed())
        self.assertNotIn("demo", self.browser.page_source)
        # The page's own script cannot reach the API without a session.
        status = self.browser.execute_async_script(
            "const done = arguments[0];"
            "fetch('/api/v1/AtlasService/ListProjects', {method: 'POST', body: '{}'})"
            ".then(r => done(r.status));")
        self.assertEqual(status, 401)

    def test_a_lock_taken_with_the_cli_shows_within_two_seconds(self):
        self.make_project()
        self.sign_in(self.server.admin)
        self.open_project("demo")
        putamen = 'tr[data-structure="Putamen"]'
        self.wait.until(lambda b: self.cell_text(putamen, 2) is not None)
        self.assertEqual(self.cell_text(putamen, 2), "")
        checkout = os.path.join(self.folder, "checkout.json")
        self.server.pba("atlas", "checkout", "-p", "demo", "Putamen", "-o", checkout)
        taken = time.time()
        self.within(2, lambda b: self.cell_text(putamen, 2) == "admin")
        self.assertLess(time.time() - taken, 2.0)
        self.screenshot("lock")

    def test_a_viewer_cannot_take_a_lock_from_the_page(self):
        self.make_project()
        vera = self.server.create_user("vera")
        self.server.pba("project", "role", "demo", "vera", "viewer")
        self.sign_in(vera)
        self.open_project("demo")
        self.wait.until(lambda b: self.structure_row("Putamen").find_element(
            By.TAG_NAME, "button").click() or True)
        error = self.wait.until(
            lambda b: b.find_element(By.ID, "action-error").text or False)
        self.assertRegex(error, "(?i)viewer|editor|permission|role")
        listed = self.server.pba("--json", "atlas", "show", "-p", "demo", "Putamen").stdout
        self.assertNotIn("vera", listed)

    def test_a_job_result_renders(self):
        job = self.solve(BLOCK)
        self.sign_in(self.server.admin)
        self.open_job(job)
        drawn = self.wait.until(lambda b: b.execute_script("return window.pbaView || null;"))
        self.assertEqual(drawn["regions"], ["body"])
        # The largest displacement drawn is the summary's (float32 in metres).
        summary = json.loads(self.server.pba("--json", "job", "status", job).stdout)
        largest_mm = summary["summary"]["results"]["max_displacement_mm"]
        self.assertGreater(largest_mm, 1.0)  # the top pushed 1 mm down, and bulging
        self.assertAlmostEqual(drawn["largest_m"] * 1000 / largest_mm, 1.0, places=5)
        # Pixels of the canvas: the model covers a good part of it, in more
        # than the background's colour.
        colours = self.model_pixels()
        self.screenshot("job")
        self.assertGreater(colours["fraction"], 0.02)
        self.assertGreater(colours["distinct"], 20)
        names = [a.text for a in self.browser.find_elements(By.CSS_SELECTOR, "#job-files a")]
        self.assertTrue(any(n.startswith("result.h5") for n in names), names)
        self.assertTrue(any(n.startswith("surfaces.glb") for n in names), names)
        # A region hidden, then the model cut in half by the section plane.
        self.browser.execute_script("document.querySelector('#job details').open = true;")
        body = self.browser.find_element(By.CSS_SELECTOR, '#regions input[data-region="body"]')
        body.click()
        self.assertEqual(self.browser.execute_script("return window.pbaView.visible;"), [])
        self.assertLess(self.model_pixels()["fraction"], 0.001)
        body.click()
        self.browser.find_element(By.ID, "cut").click()
        cut = self.model_pixels()["fraction"]
        self.assertGreater(cut, 0.01)
        self.assertLess(cut, 0.9 * colours["fraction"])
        self.browser.find_element(By.ID, "cut").click()
        # Picking the model names its region.
        canvas = self.browser.find_element(By.CSS_SELECTOR, "#view canvas")
        canvas.click()
        self.assertEqual(self.browser.find_element(By.ID, "picked").text, "body")
        # Coloured by pressure, then strain: the legend's range lies within
        # the elements' own values in result.h5 (a vertex shows the mean of
        # its elements'), and the pixels change.
        fetched = os.path.join(self.folder, "fetched")
        self.server.pba("job", "fetch", job, "-o", fetched)
        with h5py.File(os.path.join(fetched, "result.h5"), "r") as f:
            stress = f["/fields/stress"][()]
        pressures = [-(s[0] + s[1] + s[2]) / 3 for s in stress]
        options = [o.get_attribute("value")
                   for o in self.browser.find_elements(By.CSS_SELECTOR, "#colour-by option")]
        self.assertEqual(options, ["_displacement", "_PRESSURE", "_STRAIN"])
        shown = self.model_pixels()
        Select(self.browser.find_element(By.ID, "colour-by")).select_by_value("_PRESSURE")
        legend = self.browser.find_element(By.ID, "legend").text
        low, high = (float(v) for v in re.search(
            r"pressure, ([-0-9.e+]+) to ([-0-9.e+]+) Pa", legend).groups())
        tolerance = 1e-2 * max(abs(p) for p in pressures)
        self.assertGreaterEqual(low, min(pressures) - tolerance)
        self.assertLessEqual(high, max(pressures) + tolerance)
        self.assertLess(low, high)
        self.assertNotEqual(self.model_pixels()["checksum"], shown["checksum"])
        Select(self.browser.find_element(By.ID, "colour-by")).select_by_value("_STRAIN")
        self.assertIn("largest principal strain", self.browser.find_element(By.ID, "legend").text)

    def test_a_forged_cross_site_request_is_refused(self):
        self.make_project()
        self.sign_in(self.server.admin)

        class Evil(BaseHTTPRequestHandler):
            target = self.server.http

            def do_GET(self):
                page = ("<html><body><script>"
                        "fetch('%s/api/v1/AtlasService/AcquireLock', {method: 'POST',"
                        " credentials: 'include', headers: {'Content-Type': 'text/plain'},"
                        " body: JSON.stringify({project: 'demo', structure: 'Putamen'})})"
                        ".then(r => document.title = 'status ' + r.status)"
                        ".catch(e => document.title = 'blocked');"
                        "</script></body></html>" % self.target).encode()
                self.send_response(200)
                self.send_header("Content-Type", "text/html")
                self.end_headers()
                self.wfile.write(page)

            def log_message(self, *args):
                pass

        # (Threads: Chromium may hold an idle connection open beside the
        # one it loads the page on.)
        evil = ThreadingHTTPServer(("127.0.0.2", 0), Evil)
        threading.Thread(target=evil.serve_forever, daemon=True).start()
        try:
            self.browser.get("http://127.0.0.2:%d/" % evil.server_port)
            title = self.wait.until(lambda b: b.title or False)
            self.assertIn(title, ("blocked", "status 401", "status 403"))
        finally:
            evil.shutdown()
            evil.server_close()
        shown = self.server.pba("--json", "atlas", "show", "-p", "demo", "Putamen").stdout
        self.assertNotIn('"holder"', shown)

    def test_a_commit_by_another_user_updates_the_history(self):
        self.make_project()
        alice = self.server.create_user("alice")
        self.server.pba("project", "role", "demo", "alice", "editor")
        self.sign_in(self.server.admin)
        self.open_project("demo")
        self.wait.until(lambda b: b.find_element(By.LINK_TEXT, "Putamen").click() or True)
        self.wait.until(lambda b: b.find_element(By.CSS_SELECTOR, '#revisions tr[data-revision="1"]'))
        # Alice widens it from the CLI; the open page shows revision 2.
        path = os.path.join(self.folder, "alice.json")
        self.server.pba("atlas", "checkout", "-p", "demo", "Putamen", "-o", path, token=alice)
        with open(path, "w") as f:
            f.write(contours(6))
        self.server.pba("atlas", "commit", path, "-m", "wider by 1 mm", token=alice)
        second = '#revisions tr[data-revision="2"]'
        self.within(2, lambda b: self.cell_text(second, 1) is not None)
        self.assertEqual([self.cell_text(second, c) for c in (1, 2, 3)],
                         ["alice", "commit", "wider by 1 mm"])
        self.wait.until(lambda b: b.find_element(By.CSS_SELECTOR, second + " button").click() or True)
        diff = self.wait.until(lambda b: b.find_element(
            By.CSS_SELECTOR, '#revisions tr[data-revision="2"] .diff').text or False)
        # 5 x 5 mm to 6 x 6 mm on one plate: the server's own figures.
        figures = json.loads(self.server.pba("--json", "atlas", "diff", "-p", "demo", "Putamen",
                                             "--from", "1", "--to", "2").stdout)
        shape = figures.get("shape") or figures.get("contours")
        shown = float(re.search(r"Hausdorff ([0-9.e+-]+) mm", diff).group(1))
        self.assertGreater(shown, 0)
        self.assertAlmostEqual(shown, shape["hausdorff_mm"], delta=1e-3 * shape["hausdorff_mm"])

    def test_the_page_recolours_and_tags_through_the_etag(self):
        self.make_project()
        self.server.pba("atlas", "snapshot", "create", "-p", "demo")
        self.sign_in(self.server.admin)
        self.open_project("demo")
        self.wait.until(lambda b: self.structure_row("Putamen").find_element(
            By.XPATH, ".//button[text()='Colour']").click() or True)
        alert = self.wait.until(lambda b: b.switch_to.alert)
        alert.send_keys("10,200,30")
        alert.accept()
        self.wait.until(lambda b: "10,200,30" in self.structure_row("Putamen").text)
        shown = json.loads(self.server.pba("--json", "atlas", "show", "-p", "demo", "Putamen").stdout)
        self.assertEqual(shown["metadata"]["colour"], {"r": 10, "g": 200, "b": 30})
        self.wait.until(lambda b: b.find_element(
            By.CSS_SELECTOR, "#snapshots tbody tr button").click() or True)
        alert = self.wait.until(lambda b: b.switch_to.alert)
        alert.send_keys("reviewed")
        alert.accept()
        self.wait.until(lambda b: "reviewed" in b.find_element(By.ID, "snapshots").text)
        listed = self.server.pba("atlas", "snapshot", "show", "-p", "demo", "reviewed")
        self.assertEqual(listed.returncode, 0)

    def test_a_jobs_force_curve_has_the_points_of_its_history(self):
        job = self.solve(HOLD)
        fetched = os.path.join(self.folder, "fetched")
        self.server.pba("job", "fetch", job, "-o", fetched)
        with open(os.path.join(fetched, "history.csv")) as f:
            lines = f.read().strip().split("\n")
        names = [n.strip('"') for n in lines[0].split(",")]
        rows = [[float(v) for v in line.split(",")] for line in lines[1:]]
        top = names.index(next(n for n in names if n.endswith(" x [N]")))
        expected = [(r[0], (r[top] ** 2 + r[top + 1] ** 2 + r[top + 2] ** 2) ** 0.5) for r in rows]
        self.sign_in(self.server.admin)
        self.open_job(job)
        curves = self.wait.until(lambda b: b.execute_script("return window.pbaChart || null;"))
        self.assertEqual(curves["file"], "history.csv")
        self.assertEqual(len(curves["series"]), 1)
        (name, values), = curves["series"].items()
        self.assertEqual(len(values), len(expected))
        for (t, force), x, y in zip(expected, curves["x"], values):
            self.assertAlmostEqual(x, t, places=12)
            self.assertAlmostEqual(y, force, delta=1e-9 * max(1.0, abs(force)))
        self.assertTrue(self.browser.find_element(By.ID, "curve").is_displayed())
        self.screenshot("curve")
        # Stepping through time: each step drawn is result.h5's.
        self.wait.until(lambda b: b.execute_script("return window.pbaView || null;"))
        slider = self.browser.find_element(By.ID, "step")
        self.assertTrue(slider.is_displayed())
        with h5py.File(os.path.join(fetched, "result.h5"), "r") as f:
            times = f["/steps/time"][()]
            nodes = f["/mesh/nodes"].shape[0]
            steps = f["/steps/displacement"][()]
        self.assertEqual(int(slider.get_attribute("max")) + 1, len(times))
        self.assertGreater(len(times), 3)
        for k in (0, len(times) // 2, len(times) - 1):
            self.browser.execute_script(
                "const s = document.getElementById('step'); s.value = arguments[0];"
                "s.dispatchEvent(new Event('input'));", k)
            step = self.wait.until(lambda b: b.execute_script(
                "const s = window.pbaView.step; return s && s.index === arguments[0] ? s : null;", k))
            self.assertAlmostEqual(step["time"], times[k], places=12)
            block = steps[k * nodes:(k + 1) * nodes]
            largest_mm = max((x * x + y * y + z * z) ** 0.5 for x, y, z in block)
            self.assertGreater(largest_mm, 0)
            self.assertAlmostEqual(step["largest_m"] * 1000 / largest_mm, 1.0, places=5)

    def test_the_built_in_atlas_draws_every_structure_and_a_pick_names_it(self):
        self.server.pba("project", "create", "brain")
        self.server.pba("atlas", "import", "-p", "brain", "--synthetic")
        listed = json.loads(self.server.pba("--json", "atlas", "list", "-p", "brain",
                                            "--all").stdout)
        names = sorted(s["name"] for s in listed["structures"])
        self.assertEqual(len(names), 44)
        self.sign_in(self.server.admin)
        self.open_project("brain")
        atlas = self.atlas_drawn()
        self.assertNotIn("error", atlas)
        self.assertEqual(sorted(atlas["regions"]), names)
        self.assertLess(atlas["bytes"], 10e6)
        # Every structure is in the scene with triangles of its own colour.
        meshes = self.browser.execute_script("""
            return [...document.querySelectorAll('#atlas-regions input')].map(
                (box) => box.dataset.region);""")
        self.assertEqual(sorted(meshes), names)
        colours = self.model_pixels("#atlas-view")
        self.screenshot("atlas")
        self.assertGreater(colours["fraction"], 0.05)
        self.assertGreater(colours["distinct"], 20)
        # The structures' colours are the store's: a colour set with the
        # CLI redraws the structure in it.
        self.browser.execute_script("document.querySelector('#atlas details').open = true;")
        # Picking the middle of the view names a structure, with its facts.
        self.browser.find_element(By.CSS_SELECTOR, "#atlas-view canvas").click()
        name = self.wait.until(lambda b: b.find_element(By.CSS_SELECTOR, "#atlas-picked .picked-name").text or False)
        self.assertIn(name, names)
        try:
            facts = self.wait.until(lambda b: "revision 1 by admin" in b.find_element(
                By.ID, "atlas-picked").text and b.find_element(By.ID, "atlas-picked").text)
        except Exception:
            print("picked:", self.browser.find_element(By.ID, "atlas-picked").text,
                  "error:", self.browser.find_element(By.ID, "atlas-error").text, file=sys.stderr)
            raise
        self.assertIn("not locked", facts)
        # Its material, set from the page through the etag.
        field = self.browser.find_element(By.ID, "atlas-material")
        field.clear()
        field.send_keys('{"neo_hookean": {"shear_modulus_pa": 1200}}')
        self.browser.find_element(By.XPATH, "//div[@id='atlas-picked']//button").click()
        self.wait.until(lambda b: b.execute_script("return window.pbaAtlas.saved;") == name)
        shown = json.loads(self.server.pba("--json", "atlas", "show", "-p", "brain", name).stdout)
        self.assertEqual(json.loads(shown["metadata"]["material_json"]),
                         {"neo_hookean": {"shear_modulus_pa": 1200}})
        # A material that is not JSON is refused with the server's reason.
        field = self.wait.until(lambda b: b.find_element(By.ID, "atlas-material"))
        field.clear()
        field.send_keys("{shear: 1200")
        self.browser.find_element(By.XPATH, "//div[@id='atlas-picked']//button").click()
        error = self.wait.until(lambda b: b.find_element(By.ID, "atlas-error").text or False)
        self.assertIn("material_json", error)

    def test_two_revisions_of_a_structure_are_overlaid(self):
        self.server.pba("project", "create", "demo")
        path = os.path.join(self.folder, "caudate.json")
        with open(path, "w") as f:
            f.write(prism(12))
        self.server.pba("atlas", "create", "-p", "demo", "Caudate", path, "--colour", "200,200,60")
        self.server.pba("atlas", "checkout", "-p", "demo", "Caudate", "-o", path)
        with open(path, "w") as f:
            f.write(prism(16))
        self.server.pba("atlas", "commit", path, "-m", "wider")
        self.sign_in(self.server.admin)
        self.open_project("demo")
        self.atlas_drawn()
        self.wait.until(lambda b: b.find_element(By.LINK_TEXT, "Caudate").click() or True)
        self.wait.until(lambda b: b.find_element(
            By.XPATH, "//tr[@data-revision='2']//button[text()='overlay on 1']").click() or True)
        overlay = self.wait.until(lambda b: b.execute_script(
            "const a = window.pbaAtlas; return a && a.ready && a.overlay ? a : null;"))
        self.assertEqual((overlay["from"], overlay["to"], overlay["overlay"]), (1, 2, ["Caudate"]))
        pixels = self.model_pixels("#atlas-view")
        self.screenshot("overlay")
        # Revision 1 solid blue inside revision 2's red lines, which reach
        # past it on every side.
        self.assertGreater(pixels["blue"], 0.01)
        self.assertGreater(pixels["red"], 0.002)
        self.browser.find_element(By.ID, "atlas-back").click()
        back = self.atlas_drawn()
        self.assertEqual(back["regions"], ["Caudate"])
        self.assertNotIn("overlay", back)
        self.assertEqual(self.browser.execute_script(
            "return window.pbaAtlas.colourOf('Caudate');"), [200, 200, 60])
        # Someone recolours it with the CLI: the open view follows.
        self.server.pba("atlas", "set", "-p", "demo", "Caudate", "--colour", "20,160,90")
        self.within(5, lambda b: b.execute_script(
            "return window.pbaAtlas.colourOf('Caudate');") == [20, 160, 90])
        # Someone commits a new shape: the open view draws it.
        self.server.pba("atlas", "checkout", "-p", "demo", "Caudate", "-o", path)
        with open(path, "w") as f:
            f.write(prism(8))
        self.server.pba("atlas", "commit", path, "-m", "narrower")
        redrawn = WebDriverWait(self.browser, 60, poll_frequency=0.2).until(
            lambda b: b.execute_script(
                "const a = window.pbaAtlas; return a && a.ready && a.drawn_at_ms > arguments[0]"
                " ? a : null;", back["drawn_at_ms"]))
        self.assertNotEqual(redrawn["bytes"], back["bytes"])


def prism(width_mm):
    """Plate contours of a width_mm square on five plates 5 mm apart."""
    plates = ['{"z_mm": %d, "polygons": [[[0, 0], [%g, 0], [%g, %g], [0, %g]]]}'
              % (z, width_mm, width_mm, width_mm, width_mm) for z in range(0, 21, 5)]
    return '{"plates": [' + ", ".join(plates) + "]}"


if __name__ == "__main__":
    unittest.main()
