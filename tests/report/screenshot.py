"""Screenshots of the HTML report in headless Chromium, and a check for horizontal overflow.

::

    python tests/report/screenshot.py REPORT_DIR [--out SHOTS_DIR] [--width 1400]
                                      [--height 3000] [--full]

For every page of the report (``index.html`` and, when present, ``bench.html`` and
``stress.html``) it writes ``<page>.png`` (the first ``--height`` pixels at ``--width``; with
``--full`` the whole page) and measures the page's layout in the same browser: a copy of the
page with a small inline script (deleted afterwards; the report's own script only opens its
folds for printing) writes ``document.documentElement.scrollWidth`` and every element sticking
out to the right of the window into the DOM, which ``--dump-dom`` returns. Content inside a
scrolling wrapper (``overflow-x: auto``) does not count: it scrolls inside the page instead of
widening it.

Exit status: 0 when no page overflows, 1 when one does (each culprit printed), 2 when
Chromium or the report is missing.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
PAGES = ("index.html", "bench.html", "stress.html")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars")
RESULT_ID = "layout-check-result"
# Runs after layout (on load, so images have their sizes): the page width, the window width,
# and the elements whose right edge passes the window, outside any scrolling wrapper.
CHECK_SCRIPT = """<script>
window.addEventListener('load', function () {
  var root = document.documentElement, limit = root.clientWidth, culprits = [];
  document.querySelectorAll('body *').forEach(function (el) {
    if (el.closest('.scroll') && !el.classList.contains('scroll')) { return; }
    var box = el.getBoundingClientRect();
    if (box.width > 0 && box.right > limit + 1) {
      culprits.push(el.tagName.toLowerCase() + (el.id ? '#' + el.id : '')
        + (el.className && typeof el.className === 'string' ? '.' + el.className : '')
        + ' right=' + Math.round(box.right));
    }
  });
  var scrolling = 0, where = [];
  document.querySelectorAll('.scroll').forEach(function (el) {
    if (el.scrollWidth > el.clientWidth + 1) {
      scrolling += 1;
      var section = el.closest('[id]');
      var first = el.querySelector('th');
      where.push((section ? section.id : 'page') + ' (' + (first ? first.textContent : '')
        + ') ' + el.scrollWidth + '>' + el.clientWidth);
    }
  });
  var out = document.createElement('pre');
  out.id = 'RESULT_ID';
  out.textContent = JSON.stringify({scrollWidth: root.scrollWidth, clientWidth: limit,
    height: root.scrollHeight, culprits: culprits.slice(0, 20), scrolling: scrolling,
    scrolling_in: where.slice(0, 20)});
  document.body.appendChild(out);
});
</script>""".replace("RESULT_ID", RESULT_ID)


def chromium(arguments: list[str], timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run headless Chromium with a fresh profile directory (removed afterwards)."""
    profile = tempfile.mkdtemp(prefix="report-chromium-")
    try:
        return subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *arguments],
                              capture_output=True, text=True, timeout=timeout, check=False)
    finally:
        shutil.rmtree(profile, ignore_errors=True)


def measure(page: Path, width: int) -> dict:
    """The layout numbers of ``page`` at ``width`` px (see :data:`CHECK_SCRIPT`)."""
    html = page.read_text(encoding="utf-8")
    probe = page.with_name(f".layout-check-{page.name}")  # beside it: relative links resolve
    probe.write_text(html.replace("</body>", CHECK_SCRIPT + "</body>"), encoding="utf-8")
    try:
        done = chromium([f"--window-size={width},1000", "--virtual-time-budget=10000",
                         "--dump-dom", probe.resolve().as_uri()])
    finally:
        probe.unlink(missing_ok=True)
    found = re.search(rf'<pre id="{RESULT_ID}">(.*?)</pre>', done.stdout, re.DOTALL)
    if not found:
        raise RuntimeError(f"no layout result from Chromium for {page}: {done.stderr[-500:]}")
    import html as html_module

    return json.loads(html_module.unescape(found.group(1)))


def screenshot(page: Path, target: Path, width: int, height: int) -> Path:
    chromium([f"--window-size={width},{height}", f"--screenshot={target.resolve()}",
              page.resolve().as_uri()])
    if not target.is_file():
        raise RuntimeError(f"Chromium wrote no screenshot of {page}")
    return target


def check_report(report_dir: Path, shots_dir: Path, width: int = 1400, height: int = 3000,
                 full: bool = False) -> dict[str, dict]:
    """Screenshot and measure every page of the report; ``{page: layout}``, each layout with
    ``overflow`` (page wider than the window) and ``screenshot`` (its path)."""
    shots_dir.mkdir(parents=True, exist_ok=True)
    found = {}
    for name in PAGES:
        page = report_dir / name
        if not page.is_file():
            continue
        layout = measure(page, width)
        layout["overflow"] = (layout["scrollWidth"] > layout["clientWidth"] + 1
                              or bool(layout["culprits"]))
        shot_height = min(layout["height"], 30000) if full else height
        layout["screenshot"] = str(screenshot(page, shots_dir / f"{page.stem}.png", width,
                                              shot_height))
        found[name] = layout
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", type=Path, help="report directory (holds index.html)")
    parser.add_argument("--out", type=Path, default=None,
                        help="where the screenshots go (default: REPORT/screenshots)")
    parser.add_argument("--width", type=int, default=1400, help="window width, px")
    parser.add_argument("--height", type=int, default=3000, help="screenshot height, px")
    parser.add_argument("--full", action="store_true", help="screenshot whole pages")
    args = parser.parse_args(argv)
    if not Path(CHROMIUM).exists():
        print(f"no {CHROMIUM}: install it (apt-get install -y chromium)")
        return 2
    if not (args.report / "index.html").is_file():
        print(f"no {args.report / 'index.html'}")
        return 2
    layouts = check_report(args.report, args.out or args.report / "screenshots", args.width,
                           args.height, args.full)
    for name, layout in layouts.items():
        state = "OVERFLOWS" if layout["overflow"] else "fits"
        print(f"{name}: {state} (page {layout['scrollWidth']} px in a {layout['clientWidth']} px"
              f" window; {layout['scrolling']} wide tables scroll) -> {layout['screenshot']}")
        for culprit in layout["culprits"]:
            print(f"    overflows: {culprit}")
        for place in layout["scrolling_in"]:
            print(f"    scrolls (px wide > shown): {place}")
    return 1 if any(layout["overflow"] for layout in layouts.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
