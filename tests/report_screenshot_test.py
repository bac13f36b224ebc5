#!/usr/bin/python3
"""A headless browser's screenshot of the report's index.html (ctest label `long`).

usage: /usr/bin/python3 tests/report_screenshot_test.py BUILD_DIR SOURCE_DIR

Makes a small database with the harness (sphere-2, branin x random, cmaes, gd, 3 seeds, budget 20)
and a report of it with one landscape, then takes 1200 x 1600 screenshots of index.html and
gallery.html with Firefox ESR (`firefox-esr --headless --screenshot`, Debian's firefox-esr, which
scripts/install-deps.sh installs) or Chromium (`chromium --headless --screenshot`). Checks: the PNG
is 1200 x 1600; its top 800 px are not blank (more than 3% of the pixels not white); the winner's
green of the overview (html.heat(0)) shows on that first screen, i.e. the answer is above the fold;
and in the HTML the first heading is the claims, then the overview, before the per-env detail and
the provenance. Exits 77 (ctest: skipped) with one line saying so when no browser is installed.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

BUILD = SRC = ""
W, H = 1200, 1600
WINNER_GREEN = "#aadeaa"       # reports/dsb_report/html.py heat(0.0)


def browser():
    for exe in ("firefox-esr", "firefox", "chromium", "chromium-browser"):
        path = shutil.which(exe)
        if path:
            return path
    return None


def screenshot(exe, page, png, home):
    """One headless screenshot of the file `page` into `png`, W x H."""
    url = "file://" + os.path.abspath(page)
    if "firefox" in os.path.basename(exe):
        cmd = [exe, "--headless", "--no-remote", "--profile", os.path.join(home, "profile"),
               "--screenshot", png, f"--window-size={W},{H}", url]
        os.makedirs(os.path.join(home, "profile"), exist_ok=True)
    else:
        cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               f"--screenshot={png}", f"--window-size={W},{H}", url]
    env = dict(os.environ, HOME=home, MOZ_HEADLESS="1")
    subprocess.run(cmd, check=True, capture_output=True, timeout=180, env=env)


class TestScreenshot(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="dsb_screenshot_test_")
        db = os.path.join(cls.tmp, "db.sqlite")
        subprocess.run([os.path.join(BUILD, "bin", "harness"), "--env", "sphere-2,branin",
                        "--optimizer", "random,cmaes,gd", "--seeds", "3", "--budget", "20",
                        "--quiet", "--db", db], check=True)
        land = os.path.join(cls.tmp, "land")
        subprocess.run([os.path.join(SRC, "scripts", "landscape-gallery.sh"), land, "--build", BUILD,
                        "--envs", "branin", "--res", "15"], check=True, capture_output=True)
        cls.out = os.path.join(cls.tmp, "report")
        subprocess.run([sys.executable, os.path.join(SRC, "reports", "make_report.py"), "--db", db,
                        "--out", cls.out, "--landscapes", land], check=True, capture_output=True)
        cls.exe = browser()
        cls.shots = {}
        for page in ("index.html", "gallery.html"):
            png = os.path.join(cls.tmp, page.replace(".html", ".png"))
            screenshot(cls.exe, os.path.join(cls.out, page), png, cls.tmp)
            cls.shots[page] = png
        with open(os.path.join(cls.out, "index.html"), encoding="utf-8") as f:
            cls.html = f.read()

    @classmethod
    def tearDownClass(cls):
        if not os.environ.get("DSB_REPORT_KEEP"):
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def pixels(self, page):
        w, h, rows = png_rgba(self.shots[page])
        self.assertEqual((w, h), (W, H), f"{page}: screenshot size")
        return rows

    def test_index_first_screen_is_not_blank_and_shows_the_overview(self):
        rows = self.pixels("index.html")
        top = rows[:800]
        ink = sum(1 for r in top for p in r if min(p) < 245)
        frac = ink / (W * 800)
        print(f"index.html: {100 * frac:.1f}% of the top 800 px not white", file=sys.stderr)
        self.assertGreater(frac, 0.03)
        green = count_color(rows, WINNER_GREEN, tol=2)
        print(f"index.html: {green} px of the winner's green on the first {H} px", file=sys.stderr)
        self.assertGreater(green, 300)   # two envs: two winner cells of about 70 x 35 px

    def test_gallery_is_not_blank(self):
        rows = self.pixels("gallery.html")
        ink = sum(1 for r in rows[:800] for p in r if min(p) < 245)
        self.assertGreater(ink / (W * 800), 0.03)

    def test_html_order(self):
        heads = re.findall(r'<h2 id="([^"]+)">', self.html)
        self.assertEqual(heads[:3], ["claims", "overview", "failures"])
        for later in ("envs", "provenance"):
            self.assertLess(heads.index("overview"), heads.index(later))
        self.assertEqual(heads[-2:], ["provenance", "files"])
        self.assertEqual(re.search(r"<h1>(.*?)</h1>", self.html).group(1),
                         "diffsim-bench comparison report")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    BUILD, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if browser() is None:
        print("report_screenshot: SKIPPED: no headless browser (firefox-esr or chromium; "
              "scripts/install-deps.sh installs firefox-esr)")
        sys.exit(77)
    sys.path.insert(0, os.path.join(SRC, "reports"))
    from test_make_report import count_color, png_rgba   # noqa: E402  (stdlib PNG decoding)
    sys.exit(0 if unittest.main(argv=sys.argv[:1], exit=False).result.wasSuccessful() else 1)
