"""A page rendered by a real browser (Debian's Chromium, headless), audited from inside:
script errors, images that did not load, and content wider than the window.

The page is copied with a small script put first in its <head>: it records every script
error, then, once the page has loaded and its own scripts have run, writes what it found
into the DOM, which ``chromium --dump-dom`` prints.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

WINDOW_WIDTH_PX = 1280

AUDIT = """<script>
window.__errors = [];
window.addEventListener("error", function (event) {
  window.__errors.push(String(event.message || (event.target && (event.target.src || event.target.href))));
}, true);
window.addEventListener("unhandledrejection", function (event) {
  window.__errors.push("unhandled rejection: " + String(event.reason));
});
window.addEventListener("load", function () {
  setTimeout(function () {
    var images = Array.prototype.slice.call(document.images);
    var broken = images.filter(function (img) { return !(img.complete && img.naturalWidth > 0); })
                       .map(function (img) { return (img.src || "").slice(0, 80); });
    var wide = Array.prototype.slice.call(document.querySelectorAll("table")).map(function (table) {
      var box = table.getBoundingClientRect();
      return {right: Math.round(box.right), width: Math.round(box.width),
              head: (table.rows[0] ? table.rows[0].innerText : "").slice(0, 80)};
    }).filter(function (t) { return t.right > window.innerWidth; });
    var result = {errors: window.__errors, images: images.length, broken_images: broken,
                  wide_tables: wide, page_width: document.documentElement.scrollWidth,
                  window_width: window.innerWidth, text: document.body.innerText.slice(0, 20000),
                  title: document.title,
                  marked: document.querySelectorAll('[id*="lapjoint-marker"]').length};
    var out = document.createElement("pre");
    out.id = "lapjoint-audit";
    out.textContent = JSON.stringify(result);
    document.body.appendChild(out);
  }, 1500);
});
</script>"""


def chromium() -> str | None:
    """The Chromium executable, or None when the machine has none."""
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def needs_chromium(test):
    """Skipped without Chromium; a failure then with LAPJOINT_REQUIRE_CHROMIUM=1 (tests/conftest.py)."""
    test = pytest.mark.skipif(
        chromium() is None, reason="no chromium on this machine (Debian: apt-get install chromium)"
    )(test)
    return pytest.mark.group("chromium")(test)


def audit_page(page: Path, workdir: Path) -> dict:
    """Render ``page`` at a 1280 px wide window and return what the audit script found:
    ``errors`` (script errors), ``images``, ``broken_images``, ``wide_tables`` (tables
    reaching past the window's right edge), ``page_width``, ``window_width``, ``text``,
    ``title`` (the document's title once its scripts ran) and ``marked`` (elements whose id
    holds ``lapjoint-marker``: the hostile-names test puts it in every injected element)."""
    text = page.read_text()
    audited = workdir / f"audited_{page.name}"
    audited.write_text(re.sub(r"<head([^>]*)>", lambda m: m.group(0) + AUDIT, text, count=1))
    result = subprocess.run(
        [
            chromium(),
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            f"--window-size={WINDOW_WIDTH_PX},900",
            "--virtual-time-budget=15000",
            f"--user-data-dir={workdir / 'chromium-profile'}",
            "--dump-dom",
            audited.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    match = re.search(r'<pre id="lapjoint-audit">(.*?)</pre>', result.stdout, re.S)
    if match is None:
        raise AssertionError(f"the audit script did not report for {page}:\n{result.stderr[-3000:]}")
    return json.loads(html.unescape(match.group(1)))
