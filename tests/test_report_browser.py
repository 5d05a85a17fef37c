"""The HTML report as a person sees it (issue 18 item 6): every page of reports/validation opened in
headless Chromium, every figure loaded, no external URL; screenshots of the index and a case page.

Marked ``browser``: CI runs it after scripts/install-engines.sh has installed Chromium (Debian's
chromium-headless-shell).  ``pytest -m browser`` runs it here.
"""
from __future__ import annotations

import html.parser
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPORT = Path(__file__).resolve().parents[1] / "reports" / "validation"
BROWSERS = ("chromium-headless-shell", "chromium", "chromium-browser")
PROBE = ("<script>window.addEventListener('load', () => {const im = [...document.images];"
         "const bad = im.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.getAttribute('src'));"
         "document.title = 'PROBE ' + JSON.stringify({images: im.length, broken: bad});});</script>")

pytestmark = pytest.mark.browser


def browser() -> str:
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("no headless Chromium: install it with scripts/install-engines.sh (Debian: chromium-headless-shell)")


def chromium(*args, timeout=120) -> subprocess.CompletedProcess:
    return subprocess.run([browser(), "--no-sandbox", "--disable-gpu", "--hide-scrollbars", *args],
                          capture_output=True, text=True, timeout=timeout)


class Refs(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.urls, self.images = [], 0

    def handle_starttag(self, tag, attrs):
        self.images += tag == "img"
        self.urls += [v for k, v in attrs if k in ("src", "href") and v]


def probe(text: str, folder: Path, tmp_path: Path) -> dict:
    """Open ``text`` in Chromium as if it were a page of ``folder`` (a copy with a <base> and a script
    that counts the images and lists those that did not load); returns {images, broken}."""
    head = f'<base href="{folder.as_uri()}/">{PROBE}'
    probed = re.sub(r"<head>", lambda m: "<head>" + head, text, count=1)
    if probed == text:
        probed = f"<head>{head}</head>" + text
    copy = tmp_path / "probe.html"
    copy.write_text(probed)
    out = chromium("--virtual-time-budget=10000", "--dump-dom", copy.as_uri())
    found = re.search(r"<title>PROBE (.*?)</title>", out.stdout)
    assert found, f"Chromium did not finish loading the page: {out.stderr[-500:]}"
    return json.loads(found.group(1).replace("&quot;", '"'))


def test_the_probe_sees_a_missing_figure(tmp_path):
    """Negative control: a page naming a figure that is not there fails the probe."""
    (tmp_path / "here.png").write_bytes((REPORT / "cs-photoelastic" / "force_pdfs.png").read_bytes())
    got = probe('<html><head></head><body><img src="here.png"><img src="gone.png"></body></html>', tmp_path, tmp_path)
    assert got == {"images": 2, "broken": ["gone.png"]}


def pages():
    return sorted(REPORT.rglob("*.html"))


def test_the_report_has_its_pages():
    names = {p.relative_to(REPORT).as_posix() for p in pages()}
    assert "index.html" in names and len(names) >= 10, names


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(REPORT).as_posix())
def test_every_page_loads_every_figure_in_chromium_and_names_no_external_url(page, tmp_path):
    text = page.read_text()
    refs = Refs()
    refs.feed(text)
    external = [u for u in refs.urls if re.match(r"^(https?:)?//", u)]
    assert not external, f"{page}: external URLs {external}"
    got = probe(text, page.parent, tmp_path)
    assert got["broken"] == [], f"{page}: figures that did not load: {got['broken']}"
    assert got["images"] == refs.images


@pytest.mark.parametrize("page", ["index.html", "cs-photoelastic/index.html"])
def test_screenshot_shows_the_page(page, tmp_path):
    import matplotlib.image as mpimg

    shot = tmp_path / "shot.png"
    out = chromium(f"--screenshot={shot}", "--window-size=1280,1600", (REPORT / page).as_uri())
    assert shot.exists(), out.stderr[-500:]
    img = mpimg.imread(shot)
    assert img.shape[:2] == (1600, 1280)
    grey = img[..., :3].mean(axis=2)
    dark = grey < 0.5  # text and figure lines on the white page
    assert 0.005 < dark.mean() < 0.5, dark.mean()  # a page with content, not blank nor black
    rows = np.flatnonzero(dark.any(axis=1))
    assert rows.size and rows[0] < 200, "the page's heading is not at the top"
