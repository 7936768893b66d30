"""The Campbell report in a real browser (issue 23): headless Chromium (Debian's ``chromium``,
installed by ``.ci/run``) opens ``report.html``; a probe script injected at the top of the page
records every JavaScript error and every image that did not decode, and whether the
interactive plotly diagram drew its SVG. The probe is checked against pages with a deliberate
script error and a broken image, so the test can fail."""

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.report import write_campbell_report

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
#: CI (``.ci/run`` sets GEARMODAL_CI=1) installs Chromium: there these tests must run
IN_CI = os.environ.get("GEARMODAL_CI") == "1"

PROBE = """<script>
window.__errors = [];
window.addEventListener('error', function (e) {
  var t = e.target && e.target !== window ? (e.target.tagName + ' ' + (e.target.alt || ''))
                                          : '';
  window.__errors.push(String(e.message || t || e));
}, true);
var __ce = console.error;
console.error = function () { window.__errors.push([].slice.call(arguments).join(' '));
                              __ce.apply(console, arguments); };
window.addEventListener('load', function () {
  setTimeout(function () {
    var bad = [];
    for (var i = 0; i < document.images.length; i++) {
      var im = document.images[i];
      if (!im.complete || im.naturalWidth === 0) { bad.push(im.alt); }
    }
    var plot = document.getElementById('campbell-interactive');
    var out = {errors: window.__errors, broken: bad, images: document.images.length,
               plot: !!(plot && plot.querySelector('svg.main-svg'))};
    var pre = document.createElement('pre');
    pre.id = '__probe';
    pre.textContent = JSON.stringify(out);
    document.body.appendChild(pre);
  }, 300);
});
</script>"""


def _render(page, tmp_path) -> dict:
    """Open ``page`` (HTML text) with the probe in headless Chromium; the probe's findings.
    Without Chromium the test is skipped with its reason, except in CI, where it fails."""
    if not CHROMIUM:
        if IN_CI:
            pytest.fail("chromium is not installed (.ci/run installs Debian's chromium)")
        pytest.skip("needs Chromium (Debian: apt-get install chromium); runs in CI")
    html = page.replace("<head>", "<head>" + PROBE, 1)
    path = tmp_path / "probe.html"
    path.write_text(html)
    profile = tmp_path / "profile"
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={profile}", "--virtual-time-budget=20000",
           "--dump-dom", path.as_uri()]
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120).stdout
    m = re.search(r'<pre id="__probe">(.*?)</pre>', dom, re.S)
    assert m, "the probe did not report: the page did not finish loading"
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&")
                      .replace("&lt;", "<").replace("&gt;", ">"))


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("campbell")
    stage = gm.examples.planetary_stage()
    camp = gm.campbell(stage, np.linspace(0.0, 3000.0, 5))
    write_campbell_report(camp, gm.modal(stage, 3000.0), out)
    return (out / "report.html").read_text()


@pytest.mark.slow
def test_campbell_report_renders_without_errors(report, tmp_path):
    got = _render(report, tmp_path)
    assert got["errors"] == [] and got["broken"] == []
    assert got["plot"] and got["images"] >= 10  # the diagrams and every mode drawn
    assert report.count("id='mode-") >= 10  # each linked mode has its anchor


@pytest.mark.slow
def test_the_probe_sees_a_script_error_and_a_broken_image(tmp_path):
    page = ("<!DOCTYPE html><html><head><title>x</title></head><body>"
            "<img alt='broken' src='data:image/png;base64,AAAA'>"
            "<script>no_such_function();</script></body></html>")
    got = _render(page, tmp_path)
    assert any("no_such_function" in e for e in got["errors"])
    assert got["broken"] == ["broken"] and not got["plot"]
