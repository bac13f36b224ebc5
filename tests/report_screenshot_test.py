#!/usr/bin/python3
"""A headless browser's screenshots of the report's index.html (ctest label `long`).

usage: /usr/bin/python3 tests/report_screenshot_test.py BUILD_DIR SOURCE_DIR

Makes a small database with the harness (sphere-2, branin, swing-velocity-single x every optimizer
`--all` runs there, 12 on the RL env, 3 seeds, budget 20) and a report of it with one landscape,
then takes 1400 x 1600 screenshots of index.html and gallery.html with Firefox ESR
(`firefox-esr --headless --screenshot`, Debian's firefox-esr, which scripts/install-deps.sh
installs) or Chromium (`chromium --headless --screenshot`). Checks: the PNG is 1400 x 1600; its top
800 px are not blank (more than 3% of the pixels not white); the winner's green of the overview
(html.heat(0)) shows on that first screen, i.e. the answer is above the fold; in the HTML the first
heading is the claims, then the overview, before the per-env detail and the provenance.

Fit: a copy of index.html with a measuring script (the report itself has no JavaScript) draws one
8 x 12 px square per table at the top left of the window, green when the table's right edge stays
inside its container's content box and the window, red when it overflows, and a last square for
the page (no horizontal scroll); the screenshot's squares must all be green, so every optimizer's
column of the overview is in view at 1,400 px. The same copy with the overview's cells forced 12em
wide must show the overview's square red: the check can fail.
Exits 77 (ctest: skipped) with one line saying so when no browser is installed.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

BUILD = SRC = ""
W, H = 1400, 1600
WINNER_GREEN = "#aadeaa"       # reports/dsb_report/html.py heat(0.0)
FITS, OVERFLOWS = (0, 255, 0), (255, 0, 0)
SQUARE = 8                     # px per table in the probe's row of squares
# draws the squares: table k at x = 8k; its right edge against its parent's content box and the
# window; then the page's scroll width against the window
PROBE = """<script>
(function () {
  var vw = document.documentElement.clientWidth;
  var bar = document.createElement("div");
  bar.style.cssText = "position:fixed;left:0;top:0;height:12px;z-index:99999;display:flex;" +
                      "background:#000;margin:0;padding:0";
  function square(ok) {
    var d = document.createElement("div");
    d.style.cssText = "flex:none;width:8px;height:12px;background:" + (ok ? "#00ff00" : "#ff0000");
    bar.appendChild(d);
  }
  var tables = document.getElementsByTagName("table");
  for (var i = 0; i < tables.length; i++) {
    var t = tables[i].getBoundingClientRect();
    var p = tables[i].parentElement, pr = p.getBoundingClientRect(), cs = getComputedStyle(p);
    var inner = pr.right - parseFloat(cs.paddingRight) - parseFloat(cs.borderRightWidth);
    square(t.right <= inner + 0.5 && t.right <= vw + 0.5 && t.left >= -0.5);
  }
  square(document.documentElement.scrollWidth <= vw);
  document.body.appendChild(bar);
})();
</script>"""


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


def probe_copy(out, name, css=""):
    """A copy of out/index.html (same folder, so its images resolve) with PROBE and `css` added."""
    with open(os.path.join(out, "index.html"), encoding="utf-8") as f:
        text = f.read()
    text = text.replace("</head>", f"<style>{css}</style></head>", 1)
    text = text.replace("</body>", PROBE + "</body>", 1)
    path = os.path.join(out, name)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def table_names(html):
    """One name per <table> of the page: the id of the heading above it, then its class."""
    names, head = [], "top"
    for m in re.finditer(r'<h[23] id="([^"]+)"|<table( class="([^"]+)")?', html):
        if m.group(1):
            head = m.group(1)
        else:
            names.append(head + (f" ({m.group(3)})" if m.group(3) else ""))
    return names


def squares(rows, n):
    """The probe's n + 1 squares from a screenshot: True where green, False where red."""
    out = []
    for k in range(n + 1):
        px = rows[6][k * SQUARE + SQUARE // 2]
        if px not in (FITS, OVERFLOWS):
            raise AssertionError(f"probe square {k} has colour {px}: the script did not run")
        out.append(px == FITS)
    return out


class TestScreenshot(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="dsb_screenshot_test_")
        db = os.path.join(cls.tmp, "db.sqlite")
        subprocess.run([os.path.join(BUILD, "bin", "harness"), "--env",
                        "sphere-2,branin,swing-velocity-single", "--all", "--seeds", "3",
                        "--budget", "20", "--quiet", "--db", db], check=True)
        land = os.path.join(cls.tmp, "land")
        subprocess.run([os.path.join(SRC, "scripts", "landscape-gallery.sh"), land, "--build", BUILD,
                        "--envs", "branin", "--res", "15"], check=True, capture_output=True)
        cls.out = os.path.join(cls.tmp, "report")
        subprocess.run([sys.executable, os.path.join(SRC, "reports", "make_report.py"), "--db", db,
                        "--out", cls.out, "--landscapes", land, "--harness",
                        os.path.join(BUILD, "bin", "harness")], check=True, capture_output=True)
        probe_copy(cls.out, "probe.html")
        probe_copy(cls.out, "probe_control.html", "table.overview td.cell { min-width: 12em; }")
        cls.exe = browser()
        cls.shots = {}
        for page in ("index.html", "gallery.html", "probe.html", "probe_control.html"):
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
        self.assertGreater(green, 300)   # three envs: three winner cells of about 70 x 35 px

    def test_every_table_fits_its_column_at_1400_px(self):
        names = table_names(self.html)
        self.assertIn("overview (overview)", names)
        fits = squares(self.pixels("probe.html"), len(names))
        bad = [n for n, ok in zip(names + ["the page (horizontal scroll)"], fits) if not ok]
        print(f"probe.html: {fits.count(True)} of {len(fits)} squares green", file=sys.stderr)
        self.assertEqual(bad, [], f"overflowing at {W} px: {bad}")
        # every optimizer of --all on the RL env has its column in the overview
        head = re.findall(r"<th>(.*?)</th>", self.html.split('<table class="overview">')[1]
                          .split("</tr>")[0])
        self.assertEqual(len(head), 13)   # env + 12 optimizers

    def test_the_fit_check_fails_on_an_overflowing_overview(self):
        names = table_names(self.html)
        fits = squares(self.pixels("probe_control.html"), len(names))
        bad = [n for n, ok in zip(names + ["the page (horizontal scroll)"], fits) if not ok]
        self.assertIn("overview (overview)", bad)
        self.assertIn("the page (horizontal scroll)", bad)

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
