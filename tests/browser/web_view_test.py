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
from http.server import BaseHTTPRequestHandler, HTTPServer

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

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

CONTOURS = '{"plates": [{"z_mm": 0, "polygons": [[[0, 0], [5, 0], [5, 5], [0, 5]]]}]}'


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
        self.wait = WebDriverWait(self.browser, 20)

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

    def open_project(self, name):
        self.wait.until(lambda b: b.find_element(By.LINK_TEXT, name)).click()
        self.wait.until(lambda b: b.find_element(By.ID, "project").is_displayed())

    def make_project(self):
        self.server.pba("project", "create", "demo")
        contours = os.path.join(self.folder, "putamen.json")
        with open(contours, "w") as f:
            f.write(CONTOURS)
        self.server.pba("atlas", "create", "-p", "demo", "Putamen", contours,
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
        row = self.wait.until(lambda b: self.structure_row("Putamen"))
        self.assertEqual(row.find_elements(By.TAG_NAME, "td")[2].text, "")
        checkout = os.path.join(self.folder, "checkout.json")
        self.server.pba("atlas", "checkout", "-p", "demo", "Putamen", "-o", checkout)
        taken = time.time()
        WebDriverWait(self.browser, 2, poll_frequency=0.1).until(
            lambda b: self.structure_row("Putamen").find_elements(By.TAG_NAME, "td")[2].text == "admin")
        self.assertLess(time.time() - taken, 2.0)
        self.screenshot("lock")

    def test_a_viewer_cannot_take_a_lock_from_the_page(self):
        self.make_project()
        vera = self.server.create_user("vera")
        self.server.pba("project", "role", "demo", "vera", "viewer")
        self.sign_in(vera)
        self.open_project("demo")
        row = self.wait.until(lambda b: self.structure_row("Putamen"))
        row.find_element(By.TAG_NAME, "button").click()
        error = self.wait.until(
            lambda b: b.find_element(By.ID, "action-error").text or False)
        self.assertRegex(error, "(?i)viewer|editor|permission|role")
        listed = self.server.pba("--json", "atlas", "show", "-p", "demo", "Putamen").stdout
        self.assertNotIn("vera", listed)

    def test_a_job_result_renders(self):
        scene = os.path.join(self.folder, "block.yaml")
        with open(scene, "w") as f:
            f.write(BLOCK)
        submitted = self.server.pba("job", "submit", scene, "--wait").stdout
        job = re.search(r"Submitted job (\S+)", submitted).group(1)
        self.sign_in(self.server.admin)
        link = self.wait.until(lambda b: b.find_element(
            By.XPATH, "//table[@id='jobs']//tr[td[text()='%s']]//a[text()='view']" % job))
        link.click()
        drawn = self.wait.until(lambda b: b.execute_script("return window.pbaView || null;"))
        self.assertEqual(drawn["regions"], ["body"])
        # The largest displacement drawn is the summary's (float32 in metres).
        summary = json.loads(self.server.pba("--json", "job", "status", job).stdout)
        largest_mm = summary["summary"]["results"]["max_displacement_mm"]
        self.assertGreater(largest_mm, 1.0)  # the top pushed 1 mm down, and bulging
        self.assertAlmostEqual(drawn["largest_m"] * 1000 / largest_mm, 1.0, places=5)
        # Pixels of the canvas: the model covers a good part of it, in more
        # than the background's colour.
        colours = self.browser.execute_script("""
            const canvas = document.querySelector('#view canvas');
            const gl = canvas.getContext('webgl2') || canvas.getContext('webgl');
            const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
            const pixels = new Uint8Array(4 * w * h);
            gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
            let model = 0; const seen = new Set();
            for (let i = 0; i < pixels.length; i += 4) {
              const key = pixels[i] + ',' + pixels[i + 1] + ',' + pixels[i + 2];
              if (key !== '244,244,244') { ++model; seen.add(key); }
            }
            return {fraction: model / (w * h), distinct: seen.size};""")
        self.screenshot("job")
        self.assertGreater(colours["fraction"], 0.02)
        self.assertGreater(colours["distinct"], 20)
        names = [a.text for a in self.browser.find_elements(By.CSS_SELECTOR, "#job-files a")]
        self.assertTrue(any(n.startswith("result.h5") for n in names), names)
        self.assertTrue(any(n.startswith("surfaces.glb") for n in names), names)
        # Picking the model names its region.
        canvas = self.browser.find_element(By.CSS_SELECTOR, "#view canvas")
        canvas.click()
        self.assertEqual(self.browser.find_element(By.ID, "picked").text, "body")

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

        evil = HTTPServer(("127.0.0.2", 0), Evil)
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


if __name__ == "__main__":
    unittest.main()
